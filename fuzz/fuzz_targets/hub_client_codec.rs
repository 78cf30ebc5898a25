//! The hub's reading of a TCP client's bytes, `mcp_host::hub`'s `ClientCodec` (through
//! `hub::fuzzing`, feature `fuzzing`): the bytes any client of a hub sends, driven as
//! the hub's `FramedRead` drives it, with the hub's `drop_partial` (a partial frame
//! gone stale) at fuzzer-chosen points; and the hub's checks of every frame it yields
//! (`admit`: AT command, whole request, the answer to a request not sent).
//!
//! Input: byte 0 picks the mode (bit 0: odd is API mode 1) and the hub's
//! `max_frame_len` (the rest: the default, `MAX_REQUEST_DATA`, or 2 to 33); byte 1 says
//! how many of the next bytes are chunk sizes (0-7); the rest is the stream. A chunk
//! size's low 7 bits are the read's length (all zero: a byte at a time); its high bit
//! gives up the partial frame once the read is decoded. In API mode 2 a Modem Status
//! frame is read after the stream.
//!
//! Checks: no panic, never `Err`; all input taken whenever `decode` returns `None`; the
//! frames and errors are exactly those of `xbee_api::Decoder::with_max_len` fed the same
//! reads (with `finish` then `poll` where the partial frame is given up), no frame
//! longer than `max_frame_len`; skipped bytes are never said as 0, are said before the
//! item found after them (the sum said so far is the decoder's count when it yielded
//! that item) and all are said in the end, `after_error` exactly when the last item
//! said was a dropped candidate; the codec's counters match the items; in API mode 2
//! the frame after any stream is found. Every frame's `admit`: a request answered when
//! not sent is a whole one, answered by its answer type under its own frame id, and the
//! answer encodes in both modes and decodes back to itself.
#![no_main]

use bytes::BytesMut;
use libfuzzer_sys::fuzz_target;
use mcp_fuzz::events::{Event, event_bound};
use mcp_host::codec::{CodecItem, MAX_FRAME_DATA, MAX_REQUEST_DATA};
use mcp_host::hub::fuzzing::{ClientCodec, ClientItem, admit};
use xbee_api::{ApiMode, DecodeError, Decoder};

const MODEM_STATUS: [u8; 6] = [0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F];

/// The reference: a decoder's events, each with the decoder's skipped bytes when it
/// yielded it.
struct Reference {
    decoder: Decoder,
    events: Vec<(Event, u64)>,
}

impl Reference {
    fn push(&mut self, event: Option<Event>) -> bool {
        let Some(event) = event else { return false };
        let skipped = u64::from(self.decoder.stats().bytes_skipped);
        self.events.push((event, skipped));
        true
    }

    fn decode(&mut self, mut input: &[u8]) {
        loop {
            let (consumed, event) = self.decoder.decode(input);
            let event = event.map(Event::from_decoder);
            input = &input[consumed..];
            if !self.push(event) {
                assert!(input.is_empty());
                return;
            }
        }
    }

    fn drop_partial(&mut self) {
        let event = self.decoder.finish().map(Event::from_decoder);
        if self.push(event) {
            loop {
                let event = self.decoder.poll().map(Event::from_decoder);
                if !self.push(event) {
                    break;
                }
            }
        }
    }

    fn finish(&mut self) {
        loop {
            let event = self.decoder.finish().map(Event::from_decoder);
            if !self.push(event) {
                break;
            }
        }
    }

    fn skipped(&self) -> u64 {
        u64::from(self.decoder.stats().bytes_skipped)
    }
}

/// The client codec's run: its items in order, and the checks made as they come.
struct Run {
    codec: ClientCodec,
    /// Codec items so far, with the skipped bytes said before each.
    items: Vec<(Event, u64, bool)>,
    /// Items are being said by `drop_partial`.
    dropping: bool,
    /// Skipped bytes said so far.
    skipped: u64,
    /// The last codec item said was an error.
    last_error: bool,
    bound: usize,
    max_frame_len: usize,
}

impl Run {
    fn codec_item(&mut self, item: CodecItem) {
        let event = match item {
            CodecItem::Frame(frame) => {
                let data = frame.data();
                assert!(
                    !data.is_empty() && data.len() <= self.max_frame_len,
                    "frame of {} bytes from a hub taking {}",
                    data.len(),
                    self.max_frame_len
                );
                check_admit(data);
                Event::Frame(data.to_vec())
            }
            CodecItem::Error(error) => Event::Error(error),
        };
        self.last_error = matches!(event, Event::Error(_));
        self.items.push((event, self.skipped, self.dropping));
        assert!(self.items.len() <= self.bound, "codec stuck in a loop");
    }

    fn skipped(&mut self, bytes: u64, after_error: bool, expected_after_error: bool) {
        assert!(bytes > 0, "0 bytes said as skipped");
        assert_eq!(
            after_error, expected_after_error,
            "skipped bytes said after_error={after_error}"
        );
        self.skipped += bytes;
    }

    /// `decode` (or `decode_eof`) until `None`.
    fn drain(&mut self, buf: &mut BytesMut, eof: bool) {
        // Two items (a skip and the item after it) per event at most.
        for _ in 0..2 * self.bound + 4 {
            let item = match eof {
                false => self.codec.decode(buf),
                true => self.codec.decode_eof(buf),
            };
            match item {
                Ok(Some(ClientItem::Codec(item))) => self.codec_item(item),
                Ok(Some(ClientItem::Skipped { bytes, after_error })) => {
                    let expected = self.last_error;
                    self.skipped(bytes, after_error, expected);
                }
                Ok(None) => {
                    assert!(
                        buf.is_empty(),
                        "decode returned None with {} bytes left",
                        buf.len()
                    );
                    return;
                }
                Err(error) => panic!("ClientCodec returned Err: {error}"),
            }
        }
        panic!("ClientCodec never returned None");
    }

    fn drop_partial(&mut self) {
        let before_error = self.last_error;
        let items = self.codec.drop_partial();
        self.dropping = true;
        let mut codec_items = 0;
        let mut skips = 0;
        for item in items {
            match item {
                ClientItem::Codec(item) => {
                    assert_eq!(skips, 0, "drop_partial said skipped bytes before an item");
                    codec_items += 1;
                    self.codec_item(item);
                }
                ClientItem::Skipped { bytes, after_error } => {
                    skips += 1;
                    self.skipped(bytes, after_error, before_error || codec_items > 0);
                }
            }
        }
        self.dropping = false;
        assert!(skips <= 1, "drop_partial said skipped bytes twice");
        // The bytes it held are all scanned: the bytes that come next are new.
        self.last_error = false;
    }
}

/// The hub's checks of a client's frame.
fn check_admit(data: &[u8]) {
    let admit = admit(data);
    if let Some(command) = admit.at_command {
        assert!(matches!(data[0], 0x08 | 0x09 | 0x88 | 0x97 | 0x17));
        assert!(data.windows(2).any(|w| w == command));
    }
    let Some((answer, m1, m2)) = admit.not_sent_answer else {
        return;
    };
    assert!(admit.is_whole_request, "an answer to a request cut short");
    assert_eq!(
        Some(answer[0]),
        admit.answer_type,
        "a request not sent answered by another type"
    );
    assert_eq!(answer[1], data[1], "answered under another frame id");
    if matches!(answer[0], 0x88 | 0x8B | 0x97) {
        assert!(
            xbee_api::Frame::parse_bytes(&answer).is_ok(),
            "the answer to a request not sent is no frame: {answer:02x?}"
        );
    }
    for (mode, wire) in [(ApiMode::Unescaped, m1), (ApiMode::Escaped, m2)] {
        let wire = wire.expect("the answer encodes");
        let mut decoder: Decoder = Decoder::new(mode);
        let (n, event) = decoder.decode(&wire);
        assert_eq!(n, wire.len());
        let frame = event.expect("an event").expect("a frame");
        assert_eq!(frame.data(), &answer[..], "the answer encoded decodes back");
    }
}

fuzz_target!(|input: &[u8]| {
    let [first, n, rest @ ..] = input else {
        return;
    };
    let mode = if first & 1 == 1 {
        ApiMode::Unescaped
    } else {
        ApiMode::Escaped
    };
    let sel = first >> 1;
    let max_frame_len = match sel % 4 {
        0 => MAX_FRAME_DATA,
        1 => MAX_REQUEST_DATA,
        _ => 2 + usize::from(sel >> 2),
    };
    let (sizes, stream) = rest.split_at(usize::from(n % 8).min(rest.len()));
    let mut stream = stream.to_vec();
    let tail = match mode {
        ApiMode::Escaped => MODEM_STATUS.len(),
        ApiMode::Unescaped => 0,
    };
    let garbage = stream.len();
    if tail > 0 {
        stream.extend_from_slice(&MODEM_STATUS);
    }
    let bound = event_bound(stream.len());

    // Reads: (bytes, drop the partial frame after).
    let mut reads: Vec<(&[u8], bool)> = Vec::new();
    let (mut body, appended) = stream.split_at(garbage);
    let all_zero = sizes.iter().all(|&s| s & 0x7F == 0);
    let mut i = 0;
    while !body.is_empty() {
        let (size, drop) = match sizes {
            [] => (body.len(), false),
            _ => {
                let s = sizes[i % sizes.len()];
                let size = if all_zero { 1 } else { usize::from(s & 0x7F) };
                (size, s & 0x80 != 0)
            }
        };
        i += 1;
        let (chunk, after) = body.split_at(size.min(body.len()));
        body = after;
        reads.push((chunk, drop));
    }
    if !appended.is_empty() {
        reads.push((appended, false));
    }

    let mut reference = Reference {
        decoder: Decoder::with_max_len(mode, max_frame_len),
        events: Vec::new(),
    };
    let mut run = Run {
        codec: ClientCodec::new(mode, max_frame_len),
        items: Vec::new(),
        dropping: false,
        skipped: 0,
        last_error: false,
        bound,
        max_frame_len,
    };
    let mut buf = BytesMut::new();
    for &(chunk, drop) in &reads {
        reference.decode(chunk);
        buf.extend_from_slice(chunk);
        run.drain(&mut buf, false);
        if drop {
            reference.drop_partial();
            run.drop_partial();
            assert!(!run.codec.partial() || mode == ApiMode::Unescaped);
            assert_eq!(
                run.skipped,
                reference.skipped(),
                "skipped after drop_partial"
            );
        }
    }
    if tail > 0 {
        assert_eq!(
            run.items.last().map(|(e, _, _)| e),
            Some(&Event::Frame(MODEM_STATUS[3..5].to_vec())),
            "mode 2: a frame after the stream not found"
        );
        assert!(!run.codec.partial(), "mode 2: partial after a whole frame");
    }
    reference.finish();
    run.drain(&mut buf, true);
    assert!(!run.codec.partial(), "partial frame after the end");

    let got: Vec<&Event> = run.items.iter().map(|(e, _, _)| e).collect();
    let want: Vec<&Event> = reference.events.iter().map(|(e, _)| e).collect();
    assert_eq!(got, want, "ClientCodec differs from the decoder");
    // Skipped bytes said before each item: the decoder's count when it yielded it
    // (those of drop_partial are said after its items, at most the count).
    for ((_, said, dropping), (_, count)) in run.items.iter().zip(&reference.events) {
        match dropping {
            false => assert_eq!(said, count, "skipped bytes said before an item"),
            true => assert!(said <= count, "more skipped bytes said than skipped"),
        }
    }
    assert_eq!(
        run.skipped,
        reference.skipped(),
        "skipped bytes said in all"
    );

    let stats = run.codec.stats();
    let count = |f: fn(&Event) -> bool| got.iter().filter(|e| f(e)).count() as u64;
    assert_eq!(stats.frames, count(|e| matches!(e, Event::Frame(_))));
    assert_eq!(
        stats.bad_checksum + stats.oversize + stats.empty + stats.truncated + stats.bad_escape,
        count(|e| matches!(e, Event::Error(_)))
    );
    assert_eq!(
        stats.oversize,
        count(|e| matches!(e, Event::Error(DecodeError::Oversize { .. })))
    );
    assert_eq!(stats.bytes_skipped, run.skipped);
});
