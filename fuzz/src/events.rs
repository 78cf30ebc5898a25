//! Decoder events as owned values, collected by each way of feeding the decoder.

use xbee_api::{DecodeError, Decoder, DecoderMode, DecoderStats};

/// One decoder event, owned so that runs can be compared.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Event {
    /// A frame: its frame data (type byte first).
    Frame(Vec<u8>),
    /// A dropped candidate frame.
    Error(DecodeError),
}

impl Event {
    /// A decoder's event, owned.
    pub fn from_decoder(event: xbee_api::DecodeEvent<'_>) -> Self {
        match event {
            Ok(frame) => Event::Frame(frame.data().to_vec()),
            Err(error) => Event::Error(error),
        }
    }
}

/// The most events a run over `input_len` bytes may yield before the decoder is
/// considered stuck in a loop: every byte can start at most one candidate, and a
/// candidate ends in at most one event.
pub fn event_bound(input_len: usize) -> usize {
    2 * input_len + 4
}

fn push_bounded(out: &mut Vec<Event>, event: Event, bound: usize) {
    out.push(event);
    assert!(
        out.len() <= bound,
        "decoder yielded more than {bound} events: stuck in a loop"
    );
}

/// Feeds `input` with `decode` until all of it is taken and nothing is pending.
pub fn decode_all<const N: usize, M: DecoderMode>(
    decoder: &mut Decoder<N, M>,
    mut input: &[u8],
    out: &mut Vec<Event>,
    bound: usize,
) {
    loop {
        let before = input.len();
        let (consumed, event) = decoder.decode(input);
        assert!(
            consumed <= before,
            "decode took {consumed} of {before} bytes"
        );
        input = &input[consumed..];
        match event {
            Some(event) => push_bounded(out, Event::from_decoder(event), bound),
            None => {
                assert!(input.is_empty(), "decode returned None with input left");
                return;
            }
        }
    }
}

/// Feeds `input` a byte at a time with `push`, draining with `poll` after each event.
pub fn push_all<const N: usize, M: DecoderMode>(
    decoder: &mut Decoder<N, M>,
    input: &[u8],
    out: &mut Vec<Event>,
    bound: usize,
) {
    for &byte in input {
        let Some(event) = decoder.push(byte) else {
            continue;
        };
        push_bounded(out, Event::from_decoder(event), bound);
        while let Some(event) = decoder.poll() {
            push_bounded(out, Event::from_decoder(event), bound);
        }
    }
    assert!(decoder.poll().is_none(), "poll yielded after draining");
}

/// Feeds all of `input` through [`Decoder::decode_each`], collecting events, at most
/// `bound` in all.
pub fn decode_each_all<const N: usize, M: DecoderMode>(
    decoder: &mut Decoder<N, M>,
    input: &[u8],
    out: &mut Vec<Event>,
    bound: usize,
) {
    decoder.decode_each(input, |event| {
        push_bounded(out, Event::from_decoder(event), bound)
    });
}

/// Ends the input: calls `finish` until it returns `None`, then checks the decoder is
/// idle.
pub fn finish_all<const N: usize, M: DecoderMode>(
    decoder: &mut Decoder<N, M>,
    out: &mut Vec<Event>,
    bound: usize,
) {
    while let Some(event) = decoder.finish() {
        push_bounded(out, Event::from_decoder(event), bound);
    }
    assert!(decoder.is_idle(), "decoder not idle after finish");
    assert!(
        decoder.finish().is_none(),
        "finish yielded after returning None"
    );
}

/// Checks the counters against the events: one count per event of each kind.
pub fn check_stats(stats: &DecoderStats, events: &[Event]) {
    let mut expected = DecoderStats {
        frames_ok: 0,
        bad_checksum: 0,
        oversize: 0,
        empty: 0,
        truncated: 0,
        bad_escape: 0,
        bytes_skipped: stats.bytes_skipped,
    };
    for event in events {
        let counter = match event {
            Event::Frame(_) => &mut expected.frames_ok,
            Event::Error(DecodeError::BadChecksum { .. }) => &mut expected.bad_checksum,
            Event::Error(DecodeError::Oversize { .. }) => &mut expected.oversize,
            Event::Error(DecodeError::EmptyFrame) => &mut expected.empty,
            Event::Error(DecodeError::Truncated { .. }) => &mut expected.truncated,
            Event::Error(DecodeError::BadEscape { .. }) => &mut expected.bad_escape,
            Event::Error(error) => panic!("a decode error with no counter: {error:?}"),
        };
        *counter += 1;
    }
    assert_eq!(*stats, expected, "counters disagree with the events");
}
