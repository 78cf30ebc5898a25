//! `mcp-gs decode`: decode a captured byte stream or a recording.

use std::fmt;
use std::fs::File;
use std::io::{self, BufReader, IsTerminal, Read, Write};
use std::path::PathBuf;

use clap::Args;
use xbee_api::{ApiMode, DecodeError, Decoder, Frame};

use mcp_host::record::{self, Direction, RecordError, RecordReader};
use mcp_host::render;

use crate::hex_input::{BadText, HexReader};
use crate::{ApiModeArg, Failure, Format};

/// Arguments of `decode`.
#[derive(Debug, Args)]
pub(crate) struct DecodeArgs {
    /// The capture: a file of raw bytes as read from the radio, a hex dump (`--hex`), or
    /// a recording made by `monitor --record` or `hub --record`; `-` or nothing for
    /// standard input, which is decoded as it comes (a pipe from a serial port, hex typed
    /// a line at a time).
    #[arg(default_value = "-")]
    input: PathBuf,
    /// API mode of a raw capture (recordings are stored unescaped).
    #[arg(long, value_name = "1|2", default_value = "1")]
    api_mode: ApiModeArg,
    /// The input is hex text: pairs of hex digits, with whitespace, `:`, `,` and `0x`
    /// prefixes between bytes ignored and `#` starting a comment to the end of the line.
    #[arg(long)]
    hex: bool,
    /// Output format. A recording's frames in text start with the UTC time of day they
    /// were recorded at (HH:MM:SS.mmm), and a line `-- YYYY-MM-DD (UTC) --` gives the
    /// date first and at each new day; in JSON each carries `time`, seconds since 1970.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
    /// Print only counts: frames, MCP packets by category, and errors.
    #[arg(long)]
    summary: bool,
}

/// Counts for `--summary`, in arrays indexed by byte so counting costs no lookup.
#[derive(Debug)]
struct Summary {
    frames: u64,
    /// Frames by frame type byte.
    frame_types: [u64; 256],
    /// Valid MCP packets by category byte.
    categories: [u64; 256],
    /// MCP payloads that failed to parse.
    invalid_packets: u64,
    invalid_frames: u64,
}

impl Default for Summary {
    fn default() -> Self {
        Self {
            frames: 0,
            frame_types: [0; 256],
            categories: [0; 256],
            invalid_packets: 0,
            invalid_frames: 0,
        }
    }
}

/// What `decode` says when it reads a terminal: that it waits for input, which input,
/// and how to end it.
fn terminal_note(hex: bool) -> String {
    if hex {
        format!("mcp-gs: decoding hex typed on the terminal, a line at a time ({END_OF_INPUT})")
    } else {
        format!(
            "mcp-gs: decoding raw bytes from the terminal: give a capture FILE, or --hex to \
             type frames in hex ({END_OF_INPUT})"
        )
    }
}

/// How input typed on the terminal is ended: Ctrl-D on Unix; on the Windows console,
/// where Ctrl-D is a character (which `--hex` refuses), Ctrl-Z at the start of a line.
const END_OF_INPUT: &str = if cfg!(windows) {
    "end with Ctrl-Z, then Enter"
} else {
    "end with Ctrl-D"
};

/// Runs `decode`.
pub(crate) fn run(args: DecodeArgs) -> Result<(), Failure> {
    // Input that comes as it is made (a pipe, a terminal) is shown as it comes.
    let live = args.input.as_os_str() == "-" && !stdin_is_a_file();
    let input: Box<dyn Read> =
        if args.input.as_os_str() == "-" {
            let stdin = io::stdin();
            if stdin.is_terminal() {
                // Nobody is left waiting on a silent terminal without knowing why.
                err!("{}", terminal_note(args.hex));
            }
            Box::new(stdin.lock())
        } else {
            Box::new(File::open(&args.input).map_err(|e| {
                Failure::input(format!("cannot open {}: {e}", args.input.display()))
            })?)
        };
    let stdout = io::stdout().lock();
    let mut out = Output {
        inner: io::BufWriter::with_capacity(1 << 16, stdout),
        failed: false,
    };
    let result = decode_input(input, &args, &mut out, live);
    match result.and_then(|()| out.flush()) {
        Ok(()) => Ok(()),
        Err(e) if out.failed => crate::output_failure(&e).map_or(Ok(()), Err),
        Err(e) => Err(Failure::input(e.to_string())),
    }
}

/// Decodes `input` as `args` say, into `out`: a recording, told by its first bytes,
/// else a raw capture or hex text.
fn decode_input(
    input: impl Read,
    args: &DecodeArgs,
    out: &mut impl Write,
    live: bool,
) -> io::Result<()> {
    let mut input = BufReader::with_capacity(1 << 16, input);
    let name = (args.input.as_os_str() != "-").then(|| args.input.display().to_string());
    let source = Source {
        name: name.as_deref(),
        hex: args.hex,
    };
    let mut printer = Printer {
        format: args.format,
        summary: args.summary.then(Summary::default),
        out,
        dates: render::text::DateLines::new(),
    };
    // Read until they tell, not a read's worth: a pipe may give a recording's first
    // bytes a few at a time.
    let head = read_head(&mut input).map_err(|e| {
        io::Error::new(
            e.kind(),
            format!("cannot read {}: {e}", args.input.display()),
        )
    })?;
    if args.hex && record::is_recording(head.data()) {
        return Err(io::Error::new(
            io::ErrorKind::InvalidData,
            format!(
                "{} is a recording (made by --record), not hex text: decode it \
                 without --hex",
                args.input.display()
            ),
        ));
    }
    let mode = args.api_mode.0;
    let mut skipped = SkippedLines::default();
    if args.hex {
        // Decoded a line at a time, as the text comes. A hex dump of a recording is a
        // recording: its head is read again, as the bytes the text gives.
        // The raw head holds no skipped lines: they come from hex text only.
        let mut bytes = HexReader::new(head.bytes.chain(input));
        let head = loop {
            // Text that is not text at all, in the first line.
            let head =
                read_head(&mut bytes).map_err(|e| io::Error::new(e.kind(), source.says(&e)))?;
            // Lines skipped before the first byte (a title line over a dump) are said
            // at once, and the head is looked for after them.
            match head.skipped.as_ref().and_then(BadText::of) {
                Some(bad) if head.data().is_empty() => {
                    skipped.add(bad);
                    printer.bad_text(bad)?;
                    printer.out.flush()?;
                }
                _ => break head,
            }
        };
        decode_bytes(head, bytes, mode, &mut printer, source, live, &mut skipped)?;
    } else {
        decode_bytes(head, input, mode, &mut printer, source, live, &mut skipped)?;
    }
    printer.finish()
}

/// Decodes `head` (from [`read_head`]) and the `rest` after it: a recording if the
/// head is one's, else a stream in `mode`. `skipped` holds the lines of hex text
/// skipped before it.
fn decode_bytes(
    head: Head,
    rest: impl Read,
    mode: ApiMode,
    printer: &mut Printer<'_, impl Write>,
    source: Source<'_>,
    live: bool,
    skipped: &mut SkippedLines,
) -> io::Result<()> {
    let recording = record::is_recording(head.data());
    let bytes = head.chain(rest);
    if recording {
        decode_recording(bytes, printer, source, live, skipped)
    } else {
        decode_stream(bytes, mode, printer, source, skipped)
    }
}

/// The input as messages name it.
#[derive(Debug, Clone, Copy)]
struct Source<'a> {
    /// The file's path; none for standard input.
    name: Option<&'a str>,
    /// The input is hex text.
    hex: bool,
}

impl Source<'_> {
    /// `message` about the input, after the file's name if it is a file: `FILE: ...`.
    fn says(&self, message: impl fmt::Display) -> String {
        match self.name {
            Some(name) => format!("{name}: {message}"),
            None => message.to_string(),
        }
    }
}

/// Lines of hex text skipped as not hex: how many, and the first, for the message at
/// the end.
#[derive(Debug, Default)]
struct SkippedLines {
    count: u64,
    first: Option<BadText>,
}

impl SkippedLines {
    /// Counts `bad`, a line skipped.
    fn add(&mut self, bad: &BadText) {
        self.count += 1;
        self.first.get_or_insert_with(|| bad.clone());
    }

    /// The message at the end when lines were skipped: bad input, though the rest of it
    /// (`bytes` of hex, if any) was decoded.
    fn message(&self, bytes: u64) -> Option<String> {
        let first = self.first.as_ref()?;
        let rest = if bytes == 0 {
            "no line was hex"
        } else {
            "the other lines were decoded"
        };
        Some(if self.count == 1 {
            format!(
                "{first} ({}); {rest}: correct that line to decode it too",
                first.skipped_note()
            )
        } else {
            format!(
                "{} lines that are not hex were skipped (the first, {first}); {rest}: \
                 correct them to decode them too",
                self.count
            )
        })
    }
}

/// Whether standard input is a regular file (`decode < capture`), read at once, rather
/// than a pipe or a terminal whose bytes come as they are made.
fn stdin_is_a_file() -> bool {
    #[cfg(unix)]
    {
        use std::os::fd::AsFd;
        io::stdin()
            .as_fd()
            .try_clone_to_owned()
            .and_then(|fd| File::from(fd).metadata())
            .is_ok_and(|meta| meta.is_file())
    }
    #[cfg(windows)]
    {
        use std::os::windows::io::AsHandle;
        io::stdin()
            .as_handle()
            .try_clone_to_owned()
            .and_then(|handle| File::from(handle).metadata())
            .is_ok_and(|meta| meta.is_file())
    }
    #[cfg(not(any(unix, windows)))]
    {
        false
    }
}

/// Standard output, remembering whether writing it failed: an error from the output is
/// the output's failure (exit 1, or none for a closed pipe), an error from the input is
/// bad input (exit 2).
struct Output<W> {
    inner: W,
    failed: bool,
}

impl<W: Write> Write for Output<W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let result = self.inner.write(buf);
        self.failed |= result.is_err();
        result
    }

    fn flush(&mut self) -> io::Result<()> {
        let result = self.inner.flush();
        self.failed |= result.is_err();
        result
    }
}

struct Printer<'w, W: Write> {
    format: Format,
    summary: Option<Summary>,
    out: &'w mut W,
    /// A recording's dates in text output, its lines carrying the time of day.
    dates: render::text::DateLines,
}

impl<W: Write> Printer<'_, W> {
    fn frame(
        &mut self,
        data: &[u8],
        direction: Option<(Direction, std::time::SystemTime)>,
    ) -> io::Result<()> {
        if let Some(summary) = &mut self.summary {
            summary.frame(data);
            return Ok(());
        }
        let parsed = Frame::parse_bytes(data);
        if let (Format::Text, Err(_), Some((direction, time))) = (self.format, &parsed, direction) {
            // A recorded frame that cannot be read keeps its place in time.
            if let Some(date) = self.dates.before(time) {
                writeln!(self.out, "{date}")?;
            }
            let direction = render::text::direction(direction);
            write!(self.out, "{} {direction} ", render::text::time(time))?;
        }
        match (self.format, parsed) {
            (Format::Json, Ok(frame)) => {
                let mut value = render::json::frame(&frame);
                if let Some((direction, time)) = direction {
                    render::json::add_record_fields(&mut value, direction, time);
                }
                writeln!(self.out, "{value}")
            }
            (Format::Text, Ok(frame)) => {
                let line = render::text::frame(&frame);
                if let Some((direction, time)) = direction {
                    if let Some(date) = self.dates.before(time) {
                        writeln!(self.out, "{date}")?;
                    }
                    write!(self.out, "{} ", render::text::time(time))?;
                    // Packets say `rx`/`tx` themselves (`explicit rx`/`explicit tx`);
                    // other frames get it here.
                    let direction = render::text::direction(direction);
                    let said = line.strip_prefix("explicit ").unwrap_or(&line);
                    if !said.starts_with(direction) {
                        write!(self.out, "{direction} ")?;
                    }
                }
                writeln!(self.out, "{line}")
            }
            (Format::Json, Err(e)) => {
                let mut value = serde_json::json!({"error": "frame", "message": e.to_string(), "data": render::json::hex(data)});
                if let Some((direction, time)) = direction {
                    render::json::add_record_fields(&mut value, direction, time);
                }
                writeln!(self.out, "{value}")
            }
            (Format::Text, Err(e)) => writeln!(self.out, "error: {e}: {}", render::json::hex(data)),
        }
    }

    fn error(&mut self, error: &DecodeError, offset: u64) -> io::Result<()> {
        if self.summary.is_some() {
            return Ok(()); // counted by the decoder's statistics
        }
        match self.format {
            Format::Json => writeln!(
                self.out,
                "{}",
                render::json::decode_error(error, Some(offset))
            ),
            Format::Text => writeln!(
                self.out,
                "{}",
                render::text::decode_error(error, Some(offset))
            ),
        }
    }

    /// Says a line of hex text skipped as not hex, as a dropped frame is said: with
    /// where it was in the input.
    fn bad_text(&mut self, bad: &BadText) -> io::Result<()> {
        if self.summary.is_some() {
            return Ok(()); // counted for the summary
        }
        let message = format!("{} ({})", bad.problem, bad.skipped_note());
        match self.format {
            Format::Json => {
                let value =
                    serde_json::json!({"error": "hex", "line": bad.line, "message": message});
                writeln!(self.out, "{value}")
            }
            Format::Text => writeln!(
                self.out,
                "error, found at input line {}: {message}",
                bad.line
            ),
        }
    }

    fn finish(&mut self) -> io::Result<()> {
        Ok(())
    }
}

impl Summary {
    /// Counts one frame and the MCP packet it carries.
    fn frame(&mut self, data: &[u8]) {
        self.frames += 1;
        if let Some(&frame_type) = data.first() {
            self.frame_types[usize::from(frame_type)] += 1;
        }
        match Frame::parse_bytes(data) {
            Ok(Frame::ReceivePacket(rx)) => self.count_mcp(rx.data),
            Ok(Frame::TransmitRequest(tx)) => self.count_mcp(tx.data),
            // MCP with AO=1: the radio hands it over with its endpoints and cluster.
            Ok(Frame::ExplicitRxIndicator(rx)) => self.count_mcp(rx.data),
            Ok(Frame::ExplicitAddressingCommand(tx)) => self.count_mcp(tx.data),
            Ok(_) => {}
            Err(_) => self.invalid_frames += 1,
        }
    }

    fn count_mcp(&mut self, payload: &[u8]) {
        match mcp_core::parse(payload) {
            Ok(packet) => self.categories[usize::from(u8::from(packet.category()))] += 1,
            Err(_) => self.invalid_packets += 1,
        }
    }

    /// Frame types seen, with their counts, in ascending order.
    fn frame_types(&self) -> impl Iterator<Item = (u8, u64)> + '_ {
        (0..=255u8)
            .map(|t| (t, self.frame_types[usize::from(t)]))
            .filter(|&(_, n)| n > 0)
    }

    /// MCP packet counts by category name, `invalid` last, in name order.
    fn categories(&self) -> std::collections::BTreeMap<String, u64> {
        let mut map: std::collections::BTreeMap<String, u64> = (0..=255u8)
            .filter(|&c| self.categories[usize::from(c)] > 0)
            .map(|c| {
                (
                    mcp_core::Category::from(c).to_string(),
                    self.categories[usize::from(c)],
                )
            })
            .collect();
        if self.invalid_packets > 0 {
            map.insert("invalid".into(), self.invalid_packets);
        }
        map
    }
}

/// A decoder's counters added up as 64-bit counts.
#[derive(Default)]
struct Totals {
    stats: mcp_host::Stats,
    /// The decoder's counters when last taken.
    seen: xbee_api::DecoderStats,
}

impl Totals {
    /// Adds what `decoder` counted since the last call.
    fn take<const N: usize>(&mut self, decoder: &Decoder<N>) {
        let now = *decoder.stats();
        self.stats += mcp_host::Stats::decoder_since(&now, &self.seen);
        self.seen = now;
    }
}

/// Decodes a raw capture, or the bytes of hex text, in `mode`. A line of hex text that
/// is not hex is said where it was and skipped: the decoder reads on as if it was not
/// there, and the input is bad input at the end.
fn decode_stream(
    mut input: impl Read,
    mode: ApiMode,
    printer: &mut Printer<'_, impl Write>,
    source: Source<'_>,
    skipped: &mut SkippedLines,
) -> io::Result<()> {
    let mut decoder: Decoder = Decoder::new(mode);
    let mut chunk = vec![0u8; 1 << 16];
    let mut offset = 0u64;
    // The decoder's counters are 32-bit and wrap; they are added up here a read at a
    // time (64 KiB, far fewer than 2^32 of anything), so a capture of any size is
    // counted whole.
    let mut totals = Totals::default();
    // The first bytes, decoded again in the other API mode before it is suggested.
    let mut sample = Vec::new();
    loop {
        let n = match input.read(&mut chunk) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
            Err(e) => match BadText::of(&e) {
                Some(bad) if bad.goes_on() => {
                    skipped.add(bad);
                    printer.bad_text(bad)?;
                    printer.out.flush()?;
                    continue;
                }
                Some(bad) => return Err(io::Error::new(e.kind(), source.says(bad))),
                None => return Err(e),
            },
        };
        let room = MODE_SAMPLE.saturating_sub(sample.len()).min(n);
        sample.extend_from_slice(&chunk[..room]);
        if let Some(summary) = &mut printer.summary {
            // Errors are counted by the decoder; no offsets are needed.
            decoder.decode_each(&chunk[..n], |event| {
                if let Ok(frame) = event {
                    summary.frame(frame.data());
                }
            });
            offset += n as u64;
            totals.take(&decoder);
            continue;
        }
        let mut rest = &chunk[..n];
        loop {
            let (consumed, event) = decoder.decode(rest);
            rest = &rest[consumed..];
            offset += consumed as u64;
            match event {
                Some(Ok(frame)) => printer.frame(frame.data(), None)?,
                Some(Err(error)) => printer.error(&error, offset)?,
                None => break,
            }
        }
        totals.take(&decoder);
        // A read that did not fill the buffer had all there was for now (a pipe, a
        // terminal): what it decoded is shown at once, not when more comes.
        if n < chunk.len() {
            printer.out.flush()?;
        }
    }
    while let Some(event) = decoder.finish() {
        match event {
            Ok(frame) => printer.frame(frame.data(), None)?,
            Err(error) => printer.error(&error, offset)?,
        }
    }
    totals.take(&decoder);
    let stats = &totals.stats;
    if let Some(summary) = &printer.summary {
        let bad_lines = source.hex.then_some(skipped.count);
        print_summary(
            printer.out,
            summary,
            printer.format,
            offset,
            stats,
            bad_lines,
            None,
        )?;
    }
    // Decoded again in the other mode once at most, when frames failed.
    let other_finds_more = stats.decode_errors() > 0 && other_mode_finds_more(&sample, mode);
    let hint = mode_hint(mode, stats).filter(|_| other_finds_more);
    // Lines skipped make the input bad input, said first.
    let skipped = skipped.message(offset).map(|message| source.says(message));
    if offset > 0 && stats.frames == 0 {
        let errors = stats.decode_errors();
        let other = u8::from(mode.other());
        let advice = if errors == 1 && stats.truncated == 1 && !other_finds_more {
            // One candidate, cut off (by the end of the input, or in mode 2 by a start
            // delimiter), which the other mode does not find whole either (it does a
            // mode 2 frame whose length holds an escape, read in mode 1).
            "its one candidate frame is cut off (a capture that stops part way through a \
             frame?)"
                .to_owned()
        } else if errors == 1 && stats.bad_checksum == 1 && !other_finds_more {
            // One whole candidate, its checksum wrong: a byte of it mistyped (hex
            // typed in, a frame copied from a manual) more likely than another mode.
            "its one candidate frame failed its checksum (a byte of it mistyped?)".to_owned()
        } else if errors > 0 && other_finds_more {
            format!("if it is in API mode {other}, decode it with --api-mode {other}")
        } else if errors > 0 {
            format!(
                "API mode {other} finds none either in its first 64 KiB (a capture at \
                 another baud rate, or noise?)"
            )
        } else {
            "not a capture of an XBee in API mode (a recording starts with MCPREC; hex text \
             needs --hex)"
                .to_owned()
        };
        let none = format!(
            "no XBee frame in {offset} bytes ({} dropped): {advice}",
            crate::counted(errors, "candidate frame")
        );
        let message = match skipped {
            Some(skipped) => format!("{skipped}\nmcp-gs: {none}"),
            None => none,
        };
        // Input that holds no frame at all is an input error, for scripts to tell.
        return Err(io::Error::new(io::ErrorKind::InvalidData, message));
    }
    if let Some(hint) = hint {
        err!("mcp-gs: {hint}");
    }
    match skipped {
        Some(message) => Err(io::Error::new(io::ErrorKind::InvalidData, message)),
        None => Ok(()),
    }
}

/// How many bytes of the input [`other_mode_finds_more`] decodes again.
const MODE_SAMPLE: usize = 1 << 16;

/// Whether the other API mode than `mode` finds more frames in `sample` (the first
/// bytes of the input): a noisy capture in the right mode fails frames too, and is not
/// told to try the other. Both modes take frame data of the same length here (a
/// default decoder takes 4 bytes more in mode 2): frames too long for mode 1 alone
/// are long frames, not a sign of the other mode.
fn other_mode_finds_more(sample: &[u8], mode: ApiMode) -> bool {
    let max_len = Decoder::<{ xbee_api::DEFAULT_CAPACITY }>::new(ApiMode::Unescaped).capacity();
    let frames = |mode: ApiMode| {
        let mut decoder: Decoder = Decoder::with_max_len(mode, max_len);
        decoder.decode_each(sample, |_| {});
        while decoder.finish().is_some() {}
        decoder.stats().frames_ok
    };
    frames(mode.other()) > frames(mode)
}

/// A hint when many frames failed in a way that reading the stream in the other API
/// mode explains: checksums (mode 2 escapes read as data, or the reverse), escapes, and
/// lengths (a mode 1 stream read in mode 2 loses bytes to what look like escapes), one
/// frame in ten or more.
fn mode_hint(mode: ApiMode, stats: &mcp_host::Stats) -> Option<String> {
    let failed = stats.bad_checksum + stats.bad_escape + stats.truncated + stats.oversize;
    if failed < 8 || failed.saturating_mul(10) < stats.frames {
        return None;
    }
    let other = u8::from(mode.other());
    Some(format!(
        "hint: {failed} frames failed their checksum, escapes or length and {} passed: if \
         the stream is in API mode {other}, decode it with --api-mode {other}",
        stats.frames
    ))
}

/// Decodes a recording; `live` flushes the output after every record, for a recording
/// read from a pipe as it is made. `skipped` holds the lines of hex text skipped before
/// it: they make the input bad input, said at the end.
fn decode_recording(
    input: impl Read,
    printer: &mut Printer<'_, impl Write>,
    source: Source<'_>,
    live: bool,
    skipped: &mut SkippedLines,
) -> io::Result<()> {
    // The summary counts every byte, a record cut off at the end included.
    let mut input = Counted { inner: input, n: 0 };
    let mut reader = RecordReader::new(&mut input).map_err(|e| {
        let e = io::Error::from(e);
        io::Error::new(e.kind(), source.says(&e))
    })?;
    // A recording cut off (a power lost mid-flight) or damaged part way: what came
    // before it is still decoded and counted, then the error is said, with the file and
    // how many frames came before it. (A line of a hex dump that is not hex ends it too:
    // records cannot be found again after bytes left out.)
    let mut decoded = 0u64;
    let mut damaged = 0u64;
    let result = loop {
        match reader.next_record() {
            Ok(Some(record)) => {
                printer.frame(&record.frame, Some((record.direction, record.time)))?;
                decoded += 1;
                if live && printer.summary.is_none() {
                    printer.out.flush()?;
                }
            }
            Ok(None) => {
                let skipped = skipped.message(input.n).map(|message| source.says(message));
                break skipped.map_or(Ok(()), |message| {
                    Err(io::Error::new(io::ErrorKind::InvalidData, message))
                });
            }
            Err(e) => {
                match &e {
                    RecordError::Io(e) => {
                        if let Some(bad) = BadText::of(e) {
                            skipped.add(bad);
                        }
                    }
                    // A damaged or cut-off record, not a failed read: in JSON, said in
                    // the stream too, where it ends (as a line of hex that is not).
                    _ => {
                        damaged = 1;
                        if printer.format == Format::Json && printer.summary.is_none() {
                            let value = serde_json::json!({
                                "error": "recording",
                                "offset": e.offset(),
                                "message": e.to_string(),
                            });
                            writeln!(printer.out, "{value}")?;
                        }
                    }
                }
                let message = format!("{e}; {}", decoded_before(decoded));
                let kind = io::Error::from(e).kind();
                break Err(io::Error::new(kind, source.says(message)));
            }
        }
    };
    if let Some(summary) = &printer.summary {
        let bad_lines = source.hex.then_some(skipped.count);
        print_summary(
            printer.out,
            summary,
            printer.format,
            input.n,
            &mcp_host::Stats::default(),
            bad_lines,
            Some(damaged),
        )?;
    }
    result
}

/// What a damaged recording's message says of the `n` frames decoded before the damage.
fn decoded_before(n: u64) -> String {
    match n {
        0 => "no frame came before it".to_owned(),
        1 => "the 1 frame before it was decoded".to_owned(),
        n => format!("the {n} frames before it were decoded"),
    }
}

/// A reader counting the bytes read through it.
struct Counted<R> {
    inner: R,
    n: u64,
}

impl<R: Read> Read for Counted<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let got = self.inner.read(buf)?;
        self.n += got as u64;
        Ok(got)
    }
}

/// Prints the counts of `--summary`; `bad_hex_lines`, the lines of hex text skipped as
/// not hex, are among the errors of hex input, and `damaged_records` (1 at most: the
/// rest is not read) among those of a recording.
fn print_summary(
    out: &mut impl Write,
    summary: &Summary,
    format: Format,
    bytes: u64,
    stats: &mcp_host::Stats,
    bad_hex_lines: Option<u64>,
    damaged_records: Option<u64>,
) -> io::Result<()> {
    let mut errors = serde_json::json!({
        "checksum": stats.bad_checksum,
        "oversize": stats.oversize,
        "empty_frame": stats.empty,
        "truncated": stats.truncated,
        "bad_escape": stats.bad_escape,
        "bytes_skipped": stats.bytes_skipped,
        "invalid_frame": summary.invalid_frames,
    });
    if let (Some(n), Some(errors)) = (bad_hex_lines, errors.as_object_mut()) {
        errors.insert("bad_hex_line".into(), n.into());
    }
    if let (Some(n), Some(errors)) = (damaged_records, errors.as_object_mut()) {
        errors.insert("damaged_record".into(), n.into());
    }
    match format {
        Format::Json => {
            let types: serde_json::Map<String, serde_json::Value> = summary
                .frame_types()
                .map(|(t, n)| (format!("0x{t:02x}"), n.into()))
                .collect();
            let value = serde_json::json!({
                "bytes": bytes,
                "frames": summary.frames,
                "frame_types": types,
                "mcp": summary.categories(),
                "errors": errors,
            });
            writeln!(out, "{value}")
        }
        Format::Text => {
            writeln!(out, "bytes: {bytes}")?;
            writeln!(out, "frames: {}", summary.frames)?;
            for (t, n) in summary.frame_types() {
                // The hex as the JSON summary keys it, the name as frames print in JSON.
                match mcp_host::render::json::frame_type_name(t) {
                    Some(name) => writeln!(out, "  type 0x{t:02x} ({name}): {n}")?,
                    None => writeln!(out, "  type 0x{t:02x}: {n}")?,
                }
            }
            writeln!(out, "mcp packets:")?;
            for (c, n) in summary.categories() {
                writeln!(out, "  {c}: {n}")?;
            }
            writeln!(out, "errors:")?;
            for (k, v) in errors.as_object().into_iter().flatten() {
                writeln!(out, "  {k}: {v}")?;
            }
            Ok(())
        }
    }
}

/// The first bytes of `input`, enough to tell a recording: as many as a recording's
/// magic number has, or fewer if they stop matching it (or at the input's end), so that a
/// frame typed on a terminal is decoded as soon as its line ends, however short. A line
/// of hex text skipped on the way ends it there (a recording's dump does not begin
/// with one), to be said at once, before the bytes.
fn read_head(input: &mut impl Read) -> io::Result<Head> {
    let mut head = Vec::with_capacity(record::MAGIC.len());
    let mut skipped = None;
    while head.len() < record::MAGIC.len() && record::MAGIC.starts_with(&head) {
        let mut byte = [0];
        match input.read(&mut byte) {
            Ok(0) => break,
            Ok(_) => head.push(byte[0]),
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) if BadText::of(&e).is_some_and(BadText::goes_on) => {
                skipped = Some(e);
                break;
            }
            Err(e) => return Err(e),
        }
    }
    Ok(Head {
        skipped,
        bytes: io::Cursor::new(head),
    })
}

/// The first bytes of the input, read ahead to tell a recording, and read again: the
/// error of a line of hex text skipped after them first, then the bytes.
struct Head {
    skipped: Option<io::Error>,
    bytes: io::Cursor<Vec<u8>>,
}

impl Head {
    /// The bytes.
    fn data(&self) -> &[u8] {
        self.bytes.get_ref()
    }
}

impl Read for Head {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        match self.skipped.take() {
            Some(e) => Err(e),
            None => self.bytes.read(buf),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mcp_host::record::RecordWriter;

    /// A reader that gives one byte a read, as a slow pipe may.
    struct ByteAtATime<'a>(&'a [u8]);

    impl Read for ByteAtATime<'_> {
        fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
            match (self.0.split_first(), buf.first_mut()) {
                (Some((&byte, rest)), Some(slot)) => {
                    *slot = byte;
                    self.0 = rest;
                    Ok(1)
                }
                _ => Ok(0),
            }
        }
    }

    fn args(hex: bool) -> DecodeArgs {
        DecodeArgs {
            input: "-".into(),
            api_mode: ApiModeArg(ApiMode::Unescaped),
            hex,
            format: Format::Text,
            summary: true,
        }
    }

    /// The summary of `input` decoded as `args` say.
    fn summary(input: &[u8], args: &DecodeArgs) -> io::Result<String> {
        let mut out = Vec::new();
        decode_input(ByteAtATime(input), args, &mut out, false)?;
        Ok(String::from_utf8(out).unwrap())
    }

    #[test]
    fn a_recording_that_comes_a_byte_at_a_time_is_a_recording() {
        let mut recording = RecordWriter::new(Vec::new()).unwrap();
        let now = std::time::SystemTime::now();
        recording
            .write(now, Direction::Received, &[0x8A, 0x06])
            .unwrap();
        let recording = recording.into_inner();
        let out = summary(&recording, &args(false)).unwrap();
        assert!(
            out.contains("frames: 1\n  type 0x8a (modem_status): 1\n"),
            "{out}"
        );
        // As hex text too, and raw bytes given as hex are refused.
        let hex: String = recording.iter().map(|b| format!("{b:02x} ")).collect();
        let out = summary(hex.as_bytes(), &args(true)).unwrap();
        assert!(
            out.contains("frames: 1\n  type 0x8a (modem_status): 1\n"),
            "{out}"
        );
        let e = summary(&recording, &args(true)).unwrap_err();
        assert!(e.to_string().contains("is a recording"), "{e}");
        // A raw capture is read as one.
        let out = summary(&[0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F], &args(false)).unwrap();
        assert!(
            out.contains("frames: 1\n  type 0x8a (modem_status): 1\n"),
            "{out}"
        );
    }

    #[test]
    fn a_recording_cut_off_counts_the_bytes_of_its_last_record_too() {
        let mut recording = RecordWriter::new(Vec::new()).unwrap();
        let now = std::time::SystemTime::now();
        for _ in 0..2 {
            recording
                .write(now, Direction::Received, &[0x8A, 0x06])
                .unwrap();
        }
        let mut recording = recording.into_inner();
        recording.pop();
        let mut out = Vec::new();
        let e = decode_input(ByteAtATime(&recording), &args(false), &mut out, false).unwrap_err();
        assert!(e.to_string().contains("cut off"), "{e}");
        let out = String::from_utf8(out).unwrap();
        assert!(
            out.starts_with(&format!("bytes: {}\nframes: 1\n", recording.len())),
            "{out}"
        );
    }
}
