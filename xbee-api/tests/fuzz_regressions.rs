//! Inputs from fuzzing the streaming decoder, and the split-invariance check the fuzz
//! targets run: the events out of a stream are the same whether it is fed whole, in
//! chunks of any sizes (empty reads included) or a byte at a time, and a decoder takes
//! new input after `finish` as a new one would.

use xbee_api::{ApiMode, DecodeError, Decoder, DecoderStats, EncodeFrame, RawFrame};

#[derive(Debug, Clone, PartialEq, Eq)]
enum Event {
    Frame(Vec<u8>),
    Error(DecodeError),
}

fn owned(event: Result<RawFrame<'_>, DecodeError>) -> Event {
    match event {
        Ok(frame) => Event::Frame(frame.data().to_vec()),
        Err(error) => Event::Error(error),
    }
}

fn decode_all<const N: usize>(decoder: &mut Decoder<N>, mut input: &[u8], out: &mut Vec<Event>) {
    loop {
        let (consumed, event) = decoder.decode(input);
        input = &input[consumed..];
        match event {
            Some(event) => out.push(owned(event)),
            None => {
                assert!(input.is_empty(), "decode returned None with input left");
                return;
            }
        }
    }
}

fn finish_all<const N: usize>(decoder: &mut Decoder<N>, out: &mut Vec<Event>) {
    while let Some(event) = decoder.finish() {
        out.push(owned(event));
    }
    assert!(decoder.is_idle());
}

/// Decodes `stream` every way; asserts they agree; returns the events and counters.
fn check_split_invariance<const N: usize>(
    mode: ApiMode,
    stream: &[u8],
) -> (Vec<Event>, DecoderStats) {
    let mut whole = Decoder::<N>::new(mode);
    let mut expected = Vec::new();
    decode_all(&mut whole, stream, &mut expected);
    finish_all(&mut whole, &mut expected);
    let stats = *whole.stats();

    let mut bytewise = Decoder::<N>::new(mode);
    let mut events = Vec::new();
    for &byte in stream {
        if let Some(event) = bytewise.push(byte) {
            events.push(owned(event));
            while let Some(event) = bytewise.poll() {
                events.push(owned(event));
            }
        }
    }
    finish_all(&mut bytewise, &mut events);
    assert_eq!(events, expected, "byte at a time, {mode}");
    assert_eq!(*bytewise.stats(), stats, "byte at a time, {mode}");

    for sizes in [&[1usize][..], &[2], &[3], &[0, 1], &[7, 0, 2], &[5, 64, 1]] {
        let mut chunked = Decoder::<N>::new(mode);
        let mut events = Vec::new();
        let mut rest = stream;
        for &size in sizes.iter().cycle() {
            if rest.is_empty() {
                break;
            }
            let (chunk, tail) = rest.split_at(size.min(rest.len()));
            decode_all(&mut chunked, chunk, &mut events);
            rest = tail;
        }
        finish_all(&mut chunked, &mut events);
        assert_eq!(events, expected, "chunks {sizes:?}, {mode}");
        assert_eq!(*chunked.stats(), stats, "chunks {sizes:?}, {mode}");
    }

    let mut again = Vec::new();
    decode_all(&mut whole, stream, &mut again);
    finish_all(&mut whole, &mut again);
    assert_eq!(again, expected, "decoder reused after finish, {mode}");
    (expected, stats)
}

fn encode(data: &[u8], mode: ApiMode) -> Vec<u8> {
    let raw = RawFrame::new(data).unwrap();
    let mut wire = vec![0; raw.encoded_len(mode)];
    raw.encode(mode, &mut wire).unwrap();
    wire
}

/// A Receive Packet carrying the MCP time command: its frame data needs escaping in
/// mode 2 (0x13 and 0x7D in the address).
const GOOD: &[u8] = &[
    0x90, 0x00, 0x13, 0xA2, 0x00, 0x40, 0x52, 0x2B, 0xAA, 0x7D, 0x84, 0x41, b'c', 0x06, 0x00, 0xF1,
    0x53, 0x65,
];

fn frames(events: &[Event]) -> usize {
    events
        .iter()
        .filter(|e| matches!(e, Event::Frame(d) if d == GOOD))
        .count()
}

fn both_modes(build: impl Fn(&[u8]) -> Vec<u8>) -> [(ApiMode, Vec<u8>); 2] {
    [ApiMode::Unescaped, ApiMode::Escaped].map(|mode| (mode, build(&encode(GOOD, mode))))
}

#[test]
fn delimiters_in_garbage_before_a_frame() {
    for (mode, stream) in
        both_modes(|good| [&[0x00, 0x7E, 0x00, 0x7E, 0x00, 0x05, 0x90][..], good].concat())
    {
        let (events, _) = check_split_invariance::<512>(mode, &stream);
        assert_eq!(frames(&events), 1, "{mode}: {events:?}");
    }
}

#[test]
fn candidate_swallowing_a_frame_is_rescanned() {
    // Mode 1: the candidate `7E 00 20` spans the first frame and fails its checksum;
    // the rescan from the byte after its delimiter finds the frame behind it.
    let good = encode(GOOD, ApiMode::Unescaped);
    let stream = [&[0x7E, 0x00, 0x20][..], &good, &[0; 20], &good].concat();
    let (events, stats) = check_split_invariance::<512>(ApiMode::Unescaped, &stream);
    assert_eq!(frames(&events), 2, "{events:?}");
    assert!(stats.bad_checksum >= 1, "{stats:?}");
    // Also with a buffer barely larger than the frame, forcing compaction.
    let (events, _) = check_split_invariance::<32>(ApiMode::Unescaped, &stream);
    assert_eq!(frames(&events), 2, "{events:?}");
}

#[test]
fn cut_off_frame_then_frame() {
    for (mode, stream) in both_modes(|good| [&good[..9], good].concat()) {
        let (events, stats) = check_split_invariance::<512>(mode, &stream);
        assert_eq!(frames(&events), 1, "{mode}: {events:?}");
        assert_eq!(stats.frames_ok, 1, "{mode}");
    }
}

#[test]
fn empty_and_oversize_lengths_then_frame() {
    for (mode, stream) in
        both_modes(|good| [&[0x7E, 0x00, 0x00, 0x7E, 0xFF, 0xFF][..], good].concat())
    {
        let (events, stats) = check_split_invariance::<512>(mode, &stream);
        assert_eq!(frames(&events), 1, "{mode}: {events:?}");
        assert_eq!((stats.empty, stats.oversize), (1, 1), "{mode}");
        // With 16 bytes the frame itself is oversize: no frame, nothing lost in panics.
        let (events, stats) = check_split_invariance::<16>(mode, &stream);
        assert_eq!(frames(&events), 0, "{mode}: {events:?}");
        assert!(stats.oversize >= 2, "{mode}: {stats:?}");
    }
}

#[test]
fn escapes_cut_by_a_delimiter_or_the_end() {
    let good = encode(GOOD, ApiMode::Escaped);
    // 0x7D then a raw 0x7E: bad escape, then the frame; 0x7D at the very end: truncated.
    let stream = [&[0x7E, 0x00, 0x7D][..], &good, &[0x7E, 0x00, 0x03, 0x7D]].concat();
    let (events, stats) = check_split_invariance::<512>(ApiMode::Escaped, &stream);
    assert_eq!(frames(&events), 1, "{events:?}");
    assert_eq!(stats.bad_escape, 1, "{stats:?}");
    assert_eq!(stats.truncated, 1, "{stats:?}");
    // An escape of a byte that never needs one.
    let stream = [&[0x7E, 0x00, 0x7D, 0x00][..], &good].concat();
    let (events, stats) = check_split_invariance::<512>(ApiMode::Escaped, &stream);
    assert_eq!(frames(&events), 1, "{events:?}");
    assert_eq!(stats.bad_escape, 1, "{stats:?}");
}

#[test]
fn xbee_python_streams_every_way() {
    for (mode, file) in [
        (ApiMode::Unescaped, "ap1.bin"),
        (ApiMode::Escaped, "ap2.bin"),
    ] {
        let path = format!("{}/../testdata/{file}", env!("CARGO_MANIFEST_DIR"));
        let stream = std::fs::read(path).unwrap();
        let (events, stats) = check_split_invariance::<512>(mode, &stream);
        assert!(
            events.iter().all(|e| matches!(e, Event::Frame(_))),
            "{mode}"
        );
        assert_eq!(stats.errors(), 0, "{mode}");
        // Cut in the middle: one truncated frame, the rest intact.
        let (events, stats) = check_split_invariance::<512>(mode, &stream[..stream.len() / 2]);
        assert_eq!(stats.truncated, 1, "{mode}: {events:?}");
    }
}
