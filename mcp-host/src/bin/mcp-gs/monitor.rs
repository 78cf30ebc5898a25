//! `mcp-gs monitor`: print live packets, optionally recording them.

use std::collections::VecDeque;
use std::path::PathBuf;
use std::sync::atomic::Ordering;
use std::time::SystemTime;

use clap::Args;
use futures::StreamExt;
use mcp_host::record::Direction;
use mcp_host::render;
use mcp_host::{Diagnoser, Event, LinkEvent};

use crate::hints::hint;
use crate::link_args::{ApiModeChoice, LinkArgs};
use crate::output::Output;
use crate::radio_query::check_mode;
use crate::recording::{self, Recording, RecordingFile};
use crate::{Failure, Format};

/// Arguments of `monitor`.
#[derive(Debug, Args)]
#[command(mut_arg("timeout", |arg| arg.help(
    "Seconds to wait for the link to connect (tcp:) [default: 12]; on tcp-listen: \
or with --wait, monitor waits for its link, and once connected reconnects, as \
long as it runs"
)))]
pub(crate) struct MonitorArgs {
    #[command(flatten)]
    link: LinkArgs,
    /// Output format: text lines start with the UTC time of day (HH:MM:SS.mmm), and a
    /// line `-- YYYY-MM-DD (UTC) --` gives the date first and at each new day; every
    /// JSON object carries `time`, seconds since 1970 (with microseconds).
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
    /// Also record every received frame to FILE (see `decode` and `replay`). An
    /// existing FILE is kept unless `--force` is given.
    #[arg(long, value_name = "FILE")]
    record: Option<PathBuf>,
    /// Overwrite the `--record` file if it exists.
    #[arg(long, requires = "record")]
    force: bool,
    /// Wait for a link that is not there yet (a radio not plugged in, a simulator or
    /// hub not started) instead of failing at once; once up, it is reconnected as
    /// always.
    #[arg(long)]
    wait: bool,
    /// Stop after this many received items, 1 or more: packets, other frames and frames
    /// that failed to decode. Link events (connected, disconnected, reconnected,
    /// closed) are printed but not counted. Default: run until Ctrl-C (a link that
    /// goes away is reconnected, as often as it takes: a radio unplugged, a simulator or
    /// hub restarted) or until the link ends for good.
    #[arg(long, value_name = "N", value_parser = parse_count)]
    count: Option<u64>,
}

/// `--count`: a whole number, 1 or more.
fn parse_count(s: &str) -> Result<u64, String> {
    s.parse::<u64>()
        .ok()
        .filter(|n| *n >= 1)
        .ok_or_else(|| format!("expected a number of received items, 1 or more, got `{s}`"))
}

/// Runs `monitor`.
pub(crate) async fn run(mut args: MonitorArgs) -> Result<(), Failure> {
    // A burst (what waited in the socket while monitor was stopped or starved a while)
    // is held for it, for its recording, rather than dropped.
    args.link.event_capacity = Some(crate::link_args::EVENTS_HELD);
    // A recording is never lost to a mistyped link: refuse to overwrite it before the
    // link is opened, and create the file only once the link is up.
    let record = args
        .record
        .as_deref()
        .map(|path| RecordingFile::check(path, args.force))
        .transpose()?;
    let (mut stream, sender) = args.link.open_with(true, args.wait).await?;
    let mut ctrl_c = std::pin::pin!(crate::interrupt::ctrl_c());
    // With --wait the link may not be there yet: the file is made once it is.
    let waiting = args.wait && sender.link_state() != mcp_host::LinkState::Connected;
    let mut recorder = match &record {
        Some(file) if !waiting => Some(file.create()?),
        _ => None,
    };
    crate::hints::announce_radio_side(stream.info());
    if let (
        ApiModeChoice::Fixed(mode),
        mcp_host::Link::Serial { .. } | mcp_host::Link::Tcp { .. },
    ) = (args.link.api_mode, &args.link.link)
    {
        let sender = sender.clone();
        let timeout = std::time::Duration::from_secs(3);
        tokio::spawn(async move { check_mode(&sender, mode, timeout).await });
    }
    // Written by a thread of its own: a reader slower than the link (a pipe, a
    // terminal paused) holds up neither Ctrl-C nor the look at the counters, nor the
    // link's frames, which are taken (and recorded) as they come: the lines of those
    // that come while a line has waited OUTPUT_WAIT are dropped, and counted.
    let output = Output::stdout().map_err(|e| {
        Failure::new(
            Failure::OTHER,
            format!("cannot start writing standard output: {e}"),
        )
    })?;
    let mut pending = Waiting::default();
    let mut interrupted = false;
    let mut output_failed = false;
    let mut seen = 0u64;
    let mut diagnoser = match args.link.api_mode {
        // From the link's first byte on: what came before this line counts too.
        ApiModeChoice::Fixed(mode) => Some(Diagnoser::new(mode, mcp_host::Stats::default())),
        ApiModeChoice::Auto => None,
    };
    let mut hinted = false;
    // Once the hint is given, frames that fail to decode are counted, not each shown.
    let mut quiet: Option<Quiet> = None;
    // Connections a TCP peer ended before anything came: it may be turning us away.
    let mut ended_silent = 0u32;
    let mut dates = render::text::DateLines::new();
    let mut lost = Lost::default();
    let mut unshown = Unshown::default();
    // Lines handed to the output's thread, to tell those it did not write at the end.
    let mut handed = 0u64;
    // Bytes that are no frames at all come as no event: the counters are looked at now
    // and then for them (and for events lost).
    let mut look = tokio::time::interval(std::time::Duration::from_secs(1));
    let ended = loop {
        let event = tokio::select! {
            event = stream.next() => event,
            room = output.room(), if !pending.is_empty() => match (room, pending.pop_front()) {
                (Some(room), Some(line)) => {
                    room.send(line);
                    handed += 1;
                    continue;
                }
                // Standard output failed: the thread's error ends the monitor.
                _ => {
                    output_failed = true;
                    None
                }
            },
            _ = &mut ctrl_c => {
                interrupted = true;
                None
            }
            failure = recording::write_failed(&mut recorder) => break Err(failure),
            _ = look.tick() => {
                let behind = lost.tell(&stream.stats(), recorder.is_some(), false);
                pending.extend(behind.map(|frames| {
                    gap_line(Gap::Behind, frames, SystemTime::now(), args.format)
                }));
                unshown.tell(recorder.is_some());
                let found = diagnoser.as_mut().and_then(|d| d.look(stream.stats()));
                let line = match (&mut quiet, found) {
                    // Still wrong: said with the counts as they are now.
                    (Some(shown), Some(found)) => {
                        shown.hint = hint(found, &args.link.link);
                        shown.tell_if_due(false)
                    }
                    (Some(shown), None) => shown.tell_if_due(false),
                    // The hint once a connection; failures counted again without it.
                    (None, Some(found)) if !(hinted && args.format == Format::Json) => {
                        let said = std::mem::replace(&mut hinted, true);
                        quiet = Quiet::after(hint(found, &args.link.link), args.format, !said);
                        None
                    }
                    _ => None,
                };
                pending.extend(line);
                continue;
            }
        };
        let Some(event) = event else { break Ok(()) };
        if let (None, Some(file), Event::Link(LinkEvent::Connected { .. })) =
            (&recorder, &record, &event)
        {
            match file.create() {
                Ok(created) => recorder = Some(created),
                Err(failure) => break Err(failure),
            }
        }
        // The next connection may be to another radio (or to this one set right): read
        // afresh from here (frames of it this monitor has not read yet may be counted
        // already, and are left out).
        if let Event::Link(LinkEvent::Disconnected { .. }) = &event {
            pending.extend(quiet.take().and_then(|mut shown| shown.tell_if_due(true)));
            hinted = false;
            if let ApiModeChoice::Fixed(mode) = args.link.api_mode {
                diagnoser = Some(Diagnoser::new(mode, stream.stats()));
            }
        }
        // A packet's time is when it was received (as its JSON object says); another
        // event's, now.
        let time = match &event {
            Event::Packet(rx) => rx.origin.received_at,
            Event::InvalidPacket(rx) => rx.origin.received_at,
            _ => SystemTime::now(),
        };
        if let (Some(recorder), Some(frame)) = (&mut recorder, frame_data(&event)) {
            if let Err(failure) = recorder.write(time, Direction::Received, frame) {
                break Err(failure);
            }
        }
        if let (Some(shown), Event::DecodeError(_)) = (&mut quiet, &event) {
            // Counted, until frames pass again.
            pending.extend(shown.count());
            seen += 1;
            if args.count.is_some_and(|n| seen >= n) {
                break Ok(());
            }
            continue;
        }
        // Frames pass again (the radio set right): failures are shown again, each, and
        // the signs looked for afresh.
        if let (Some(shown), Event::Packet(_) | Event::InvalidPacket(_) | Event::Frame(_)) =
            (&mut quiet, &event)
        {
            if shown.passed() {
                pending.extend(shown.tell_if_due(true));
                quiet = None;
                if let ApiModeChoice::Fixed(mode) = args.link.api_mode {
                    diagnoser = Some(Diagnoser::new(mode, stream.stats()));
                }
            }
        }
        // A reader that takes nothing: the line is dropped and counted, a link event's
        // (a few a minute at most, which say what the lines around them mean) but kept.
        // A burst a reader takes in time (what waited while monitor was stopped, written
        // to a file) is shown whole. Once lines are dropped, they are until the oldest
        // line waiting has waited less than half as long, and half as many wait (a reader
        // a little slow would otherwise get a line, then a gap, in turn). Where lines
        // were dropped, a line says how many, before the next one kept.
        let waited = pending.oldest_waited(std::time::Instant::now());
        if waited >= OUTPUT_WAIT || pending.len() >= PENDING_LINES {
            unshown.dropping = true;
        } else if waited < OUTPUT_WAIT / 2 && pending.len() < PENDING_LINES / 2 {
            unshown.dropping = false;
        }
        if unshown.dropping && !matches!(event, Event::Link(_)) {
            unshown.count += 1;
            unshown.run += 1;
            unshown.last = time;
        } else {
            pending.extend(unshown.gap(args.format));
            pending.push_back(line(&event, time, args.format, &mut dates));
        }
        // Text output counts failures again without the hint once it was given; JSON
        // output shows each, and the hint once a connection.
        let looking = quiet.is_none() && !(hinted && args.format == Format::Json);
        if let (Some(diagnoser), true, Event::DecodeError(_)) = (&mut diagnoser, looking, &event) {
            // A frame with no byte to escape passes in either mode (a modem status,
            // say): the hint counts on most frames failing, not on all of them.
            if let Some(found) = diagnoser.look(stream.stats()) {
                let said = std::mem::replace(&mut hinted, true);
                quiet = Quiet::after(hint(found, &args.link.link), args.format, !said);
            }
        }
        if let Event::Link(LinkEvent::Closed { reason, .. }) = &event {
            break Err(Failure::link(format!("link closed: {reason}")));
        }
        if let (Event::Link(LinkEvent::Disconnected { .. }), mcp_host::Link::Tcp { .. }) =
            (&event, &args.link.link)
        {
            if crate::hints::nothing_came(&stream.stats()) {
                ended_silent += 1;
                // Once, when it is not a one-off.
                if ended_silent == TURNED_AWAY {
                    err!("mcp-gs: {}", crate::hints::turned_away_hint());
                }
            }
        }
        // What the radio sent counts; what happened to our own link does not.
        if !matches!(event, Event::Link(_)) {
            seen += 1;
        }
        if args.count.is_some_and(|n| seen >= n) {
            break Ok(());
        }
    };
    if output_failed {
        let failed = written(output.finish([]).await);
        return end_recording(recorder, failed).await;
    }
    // What was not shown is counted, however the monitor ends.
    pending.extend(quiet.as_mut().and_then(|shown| shown.tell_if_due(true)));
    pending.extend(unshown.gap(args.format));
    handed += pending.len() as u64;
    let written_so_far = output.written();
    let finished = output.finish(pending.into_lines());
    tokio::pin!(finished);
    // After Ctrl-C (before, or while the last lines are written), a reader that takes
    // nothing more does not keep the monitor: what it did not take in time is lost.
    let drain_after_ctrl_c = async |finished| {
        tokio::time::timeout(DRAIN_AFTER_CTRL_C, finished)
            .await
            .unwrap_or(Ok(()))
    };
    let finished = match interrupted {
        true => drain_after_ctrl_c(&mut finished).await,
        false => tokio::select! {
            finished = &mut finished => finished,
            _ = &mut ctrl_c => drain_after_ctrl_c(&mut finished).await,
        },
    };
    // Too late for standard output: said on standard error alone.
    lost.tell(&stream.stats(), recorder.is_some(), true);
    unshown.tell(recorder.is_some());
    // Lines a reader that took nothing more after Ctrl-C left unwritten (not a reader
    // gone, whose end is no news).
    let unwritten = handed.saturating_sub(written_so_far.load(Ordering::Relaxed));
    if finished.is_ok() && unwritten > 0 {
        err!(
            "mcp-gs: warning: {} not written: standard output took nothing more after Ctrl-C",
            crate::counted(unwritten, "line")
        );
    }
    // The frames still queued for the file, and what it could not take. A failure of
    // the monitor itself (a recording that could not be written) is said before one of
    // its output, and not hidden by a reader gone.
    let ended = end_recording(recorder, ended).await;
    ended.and_then(|()| written(finished))
}

/// Ends the recording, if there is one, after the monitor ended with `ended`: the
/// frames queued written (or said missing), and its failure the monitor's if it had
/// none, else said as a warning.
async fn end_recording(
    recorder: Option<Recording>,
    ended: Result<(), Failure>,
) -> Result<(), Failure> {
    let Some(recording) = recorder else {
        return ended;
    };
    match (ended, recording.end().await.said()) {
        (Err(failure), Err(also)) => {
            err!("mcp-gs: warning: {}", also.message);
            Err(failure)
        }
        (ended, recorded) => ended.and(recorded),
    }
}

/// The line `monitor` prints for `event`, received at `time`.
fn line(
    event: &Event,
    time: SystemTime,
    format: Format,
    dates: &mut render::text::DateLines,
) -> String {
    match format {
        Format::Json => render::json::event(event).to_string(),
        Format::Text => {
            // What comes next, which may take a while: nothing is printed meanwhile.
            let next = match event {
                Event::Link(LinkEvent::Disconnected { .. }) => "; reconnecting (Ctrl-C stops)",
                _ => "",
            };
            let line = format!(
                "{} {}{next}",
                render::text::time(time),
                render::text::event(event)
            );
            match dates.before(time) {
                Some(date) => format!("{date}\n{line}"),
                None => line,
            }
        }
    }
}

/// Why received frames were not shown: standard output was not read as fast as they
/// came ([`Unshown`]), or the monitor fell behind the link ([`Lost`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Gap {
    Output,
    Behind,
}

/// The line that says `frames` received frames were not shown, the last at `time`, for
/// a reader of standard output (a program reading JSON, a pager) to see the gap:
/// `{"gap":"output","frames":N,"time":...}` where their lines would have been (they
/// were dropped for a reader that did not keep up), or `"behind"` for frames the
/// monitor fell behind the link on (missing from the recording too), said when it sees
/// they are lost, at most once a second, not where they would have been: lines of
/// frames that came before them may follow it, and `time` is when it was seen.
fn gap_line(gap: Gap, frames: u64, time: SystemTime, format: Format) -> String {
    match format {
        Format::Json => serde_json::json!({
            "gap": match gap {
                Gap::Output => "output",
                Gap::Behind => "behind",
            },
            "frames": frames,
            "time": render::json::seconds(time),
        })
        .to_string(),
        Format::Text => {
            let why = match gap {
                Gap::Output => "standard output was not read as fast as they came",
                Gap::Behind => "monitor fell behind the link",
            };
            format!(
                "{} -- {} not shown here: {why} --",
                render::text::time(time),
                crate::counted(frames, "received frame")
            )
        }
    }
}

/// How long a line may wait for standard output (beyond those its thread holds)
/// before the lines of the frames that come are dropped (and counted, [`Unshown`]): a
/// reader that takes nothing (a paused pager) holds up neither the link nor the
/// recording, and once it reads again gets the lines that waited (this long's worth at
/// most), then a gap line, then the lines of frames that come then.
const OUTPUT_WAIT: std::time::Duration = std::time::Duration::from_secs(2);

/// Lines waiting for standard output past which a frame's line is dropped however long
/// they waited: the memory they take (some 20 MB of JSON lines), as many as the link's
/// events held for monitor ([`EVENTS_HELD`](crate::link_args::EVENTS_HELD)).
const PENDING_LINES: usize = crate::link_args::EVENTS_HELD;

/// The lines waiting for standard output, beyond those its thread holds, each with
/// when it came.
#[derive(Debug, Default)]
struct Waiting(VecDeque<(std::time::Instant, String)>);

impl Waiting {
    fn len(&self) -> usize {
        self.0.len()
    }

    fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    fn push_back(&mut self, line: String) {
        self.0.push_back((std::time::Instant::now(), line));
    }

    fn extend(&mut self, lines: impl IntoIterator<Item = String>) {
        for line in lines {
            self.push_back(line);
        }
    }

    fn pop_front(&mut self) -> Option<String> {
        self.0.pop_front().map(|(_, line)| line)
    }

    /// How long the oldest line has waited, at `now`: zero if none waits.
    fn oldest_waited(&self, now: std::time::Instant) -> std::time::Duration {
        self.0
            .front()
            .map_or(std::time::Duration::ZERO, |(since, _)| {
                now.saturating_duration_since(*since)
            })
    }

    fn into_lines(self) -> impl Iterator<Item = String> {
        self.0.into_iter().map(|(_, line)| line)
    }
}

/// Frames whose lines were dropped because standard output was not read as fast as
/// they came: said as it happens, at most once a look, and at the end.
#[derive(Debug)]
struct Unshown {
    count: u64,
    /// The count last said.
    told: u64,
    /// Frames not shown since the last line kept: the next line kept is preceded by a
    /// [`gap_line`] of them.
    run: u64,
    /// When the last frame not shown came.
    last: SystemTime,
    /// Whether lines are being dropped: from when a line has waited [`OUTPUT_WAIT`] (or
    /// [`PENDING_LINES`] wait) until the oldest waiting has waited less than half that
    /// (and half as many wait).
    dropping: bool,
}

impl Default for Unshown {
    fn default() -> Self {
        Unshown {
            count: 0,
            told: 0,
            run: 0,
            last: SystemTime::UNIX_EPOCH,
            dropping: false,
        }
    }
}

impl Unshown {
    /// The [`gap_line`] of the frames not shown since the last line kept, if any: it
    /// goes before the next.
    fn gap(&mut self, format: Format) -> Option<String> {
        let run = std::mem::take(&mut self.run);
        (run > 0).then(|| gap_line(Gap::Output, run, self.last, format))
    }

    /// Says the frames not shown since it last said any.
    fn tell(&mut self, recording: bool) {
        if self.count > self.told {
            let kept = if recording {
                " (the recording has them)"
            } else {
                ""
            };
            err!(
                "mcp-gs: warning: {} not shown: standard output is not read as fast as they \
                 come (a pager paused?){kept}",
                crate::counted(self.count - self.told, "received frame")
            );
            self.told = self.count;
        }
    }
}

/// How long the lines not yet written may take after Ctrl-C.
const DRAIN_AFTER_CTRL_C: std::time::Duration = std::time::Duration::from_secs(1);

/// How `monitor` ends after standard output was written: done if it could be, or if its
/// reader closed it (piped into `head`); with a failure for anything else.
fn written(result: std::io::Result<()>) -> Result<(), Failure> {
    match result {
        Ok(()) => Ok(()),
        Err(e) => crate::output_failure(&e).map_or(Ok(()), Err),
    }
}

/// Events the link dropped because monitor fell behind it (a burst from a TCP peer or a
/// bridge faster than monitor records and renders them, on a busy machine; not its
/// output, whose lines are dropped instead, [`Unshown`]): said as they happen, at most
/// once a look, and in all at the end, not lost in silence.
#[derive(Debug, Default)]
struct Lost {
    /// The count last said.
    told: u64,
}

impl Lost {
    /// Says the events lost since it last said any (`end`: in all, if any were), and
    /// returns how many there are, if any.
    fn tell(&mut self, stats: &mcp_host::Stats, recording: bool, end: bool) -> Option<u64> {
        let lost = stats.events_dropped;
        let also = if recording {
            ", and are missing from the recording"
        } else {
            ""
        };
        let new = lost.checked_sub(self.told).filter(|&new| new > 0);
        if let Some(new) = new {
            err!(
                "mcp-gs: warning: {} lost: monitor fell behind the link (the machine busy, \
                 or monitor stopped a while?) and they were not shown{also}",
                crate::counted(new, "received frame")
            );
            self.told = lost;
        }
        if end && lost > 0 && recording {
            err!(
                "mcp-gs: warning: {} in all are missing from the recording: monitor fell \
                 behind the link",
                crate::counted(lost, "received frame")
            );
        }
        new
    }
}

/// How often [`Quiet`] says how many frames it did not show.
const QUIET_EVERY: std::time::Duration = std::time::Duration::from_secs(5);

/// Text output once the radio's settings are known to differ from the link's: every
/// frame from the radio may fail to decode, many a second, and a line for each would
/// push the one line that says what to do off the screen. They are counted instead,
/// and the count is said every [`QUIET_EVERY`], with the hint again. JSON output shows
/// every one, for the programs that read it.
struct Quiet {
    hint: String,
    /// Frames not shown since the last count was said.
    hidden: u64,
    /// When the count was last said (or the hint first given).
    told: std::time::Instant,
    /// Good frames in a row since the last that failed.
    good: u64,
}

/// Good frames in a row after which [`Quiet`] ends: the radio was set right (a line
/// that corrupts a frame now and then does not fail so many in a row).
const QUIET_UNTIL_GOOD: u64 = 64;

impl Quiet {
    /// Gives `hint` on standard error if `say`; a `Quiet` for text output.
    fn after(hint: String, format: Format, say: bool) -> Option<Quiet> {
        if say {
            err!("mcp-gs: {hint}");
        }
        (format == Format::Text).then(|| Quiet {
            hint,
            hidden: 0,
            told: std::time::Instant::now(),
            good: 0,
        })
    }

    /// Counts a frame that failed to decode, not shown: the line that says how many
    /// were not, if it is due.
    fn count(&mut self) -> Option<String> {
        self.hidden += 1;
        self.good = 0;
        self.tell_if_due(false)
    }

    /// Counts a good frame; whether [`QUIET_UNTIL_GOOD`] came in a row (the count of
    /// those not shown is then to be said).
    fn passed(&mut self) -> bool {
        self.good += 1;
        self.good >= QUIET_UNTIL_GOOD
    }

    /// The line that says how many frames were not shown, if any, when [`QUIET_EVERY`]
    /// has passed since it last did (or at once with `now`, at the end).
    fn tell_if_due(&mut self, now: bool) -> Option<String> {
        if self.hidden == 0 || !(now || self.told.elapsed() >= QUIET_EVERY) {
            return None;
        }
        let line = format!(
            "{} error: {} failed to decode, not shown ({})",
            render::text::time(SystemTime::now()),
            crate::counted(self.hidden, "more frame"),
            self.hint
        );
        self.hidden = 0;
        self.told = std::time::Instant::now();
        Some(line)
    }
}

/// Connections a TCP peer ends before anything came from it after which `monitor` says
/// what may be wrong.
const TURNED_AWAY: u32 = 3;

/// The frame data of an event, for the recording: received packets as the frame they
/// came in (a Receive Packet or an Explicit Rx Indicator), other frames as they are.
fn frame_data(event: &Event) -> Option<&[u8]> {
    match event {
        Event::Packet(rx) => Some(&rx.frame),
        Event::InvalidPacket(rx) => Some(&rx.frame),
        Event::Frame(frame) => Some(frame.data()),
        _ => None,
    }
}
