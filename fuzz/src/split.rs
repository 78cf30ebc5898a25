//! Split invariance of the XBee streaming decoder: the events out of a stream are the
//! same whether it is fed whole, in chunks of any sizes, or a byte at a time, and are
//! those of the plain reference decoder over the whole input; the decoder takes new
//! input after `finish` as if new; every frame it yields encodes and decodes to itself,
//! and so does a node discovery answer in it; an `Inbox` over the same stream hands
//! over the payloads among its events.

use xbee_api::{
    ApiMode, Decoder, DecoderMode, EncodeFrame, Frame, Mode1, Mode2, NodeInfo, RawFrame,
};

use crate::events::{
    Event, check_stats, decode_all, decode_each_all, event_bound, finish_all, push_all,
};
use crate::reference;

/// Chunk sizes from fuzzer bytes, cycled over the stream; an empty or all-zero list
/// means one byte at a time (a zero entry is an empty `decode` call).
fn chunks<'a>(stream: &'a [u8], sizes: &'a [u8]) -> impl Iterator<Item = &'a [u8]> + 'a {
    let all_zero = sizes.iter().all(|&s| s == 0);
    let mut rest = stream;
    let mut i = 0usize;
    core::iter::from_fn(move || {
        if rest.is_empty() {
            return None;
        }
        let size = if all_zero {
            1
        } else {
            usize::from(sizes[i % sizes.len()])
        };
        i += 1;
        let (chunk, tail) = rest.split_at(size.min(rest.len()));
        rest = tail;
        Some(chunk)
    })
}

/// Runs every check on one stream with a decoder of capacity `N` given `mode`, and
/// again with one whose type fixes it ([`Decoder::fixed`]), which must decode exactly
/// as the first: the same events and counters.
pub fn check_stream<const N: usize>(mode: ApiMode, sizes: &[u8], stream: &[u8]) {
    let given = check_stream_with(|| Decoder::<N>::new(mode), mode, sizes, stream);
    let fixed = match mode {
        ApiMode::Unescaped => check_stream_with(Decoder::<N, Mode1>::fixed, mode, sizes, stream),
        ApiMode::Escaped => check_stream_with(Decoder::<N, Mode2>::fixed, mode, sizes, stream),
    };
    assert_eq!(
        fixed, given,
        "decoder of a fixed mode differs from one given the mode"
    );
}

/// Runs every check on one stream with a decoder of capacity `M`, and again with one of
/// the larger capacity `N` limited to `M`'s ([`Decoder::with_max_len`]), which must decode
/// exactly as the small one: the same events and counters.
pub fn check_stream_limited<const N: usize, const M: usize>(
    mode: ApiMode,
    sizes: &[u8],
    stream: &[u8],
) {
    let small = check_stream_with(|| Decoder::<M>::new(mode), mode, sizes, stream);
    let max_len = Decoder::<M>::new(mode).capacity();
    let limited = check_stream_with(
        || Decoder::<N>::with_max_len(mode, max_len),
        mode,
        sizes,
        stream,
    );
    assert_eq!(
        limited, small,
        "decoder of capacity {N} limited to {max_len} differs from one of capacity {M}"
    );
}

/// Runs every check on one stream with decoders made by `new` (each a fresh decoder in
/// `mode`); the events and counters of the whole stream.
pub fn check_stream_with<const N: usize, M: DecoderMode>(
    new: impl Fn() -> Decoder<N, M>,
    mode: ApiMode,
    sizes: &[u8],
    stream: &[u8],
) -> (Vec<Event>, xbee_api::DecoderStats) {
    let bound = event_bound(stream.len());

    // Whole slice.
    let mut whole = new();
    let mut expected = Vec::new();
    decode_all(&mut whole, stream, &mut expected, bound);
    finish_all(&mut whole, &mut expected, bound);
    check_stats(whole.stats(), &expected);
    let stats = *whole.stats();

    // The plain whole-input decoder.
    let (reference, skipped) = match mode {
        ApiMode::Unescaped => reference::mode1(stream, whole.capacity()),
        ApiMode::Escaped => reference::mode2(stream, whole.capacity()),
    };
    assert_eq!(
        expected, reference,
        "decoder differs from the reference decoder"
    );
    assert_eq!(u64::from(stats.bytes_skipped), skipped, "bytes skipped");

    // Byte at a time.
    let mut bytewise = new();
    let mut events = Vec::new();
    push_all(&mut bytewise, stream, &mut events, bound);
    finish_all(&mut bytewise, &mut events, bound);
    assert_eq!(
        events, expected,
        "push byte at a time differs from whole decode"
    );
    assert_eq!(
        *bytewise.stats(),
        stats,
        "push counters differ from whole decode"
    );

    // Fuzzer-chosen chunks.
    let mut chunked = new();
    let mut events = Vec::new();
    for chunk in chunks(stream, sizes) {
        decode_all(&mut chunked, chunk, &mut events, bound);
    }
    finish_all(&mut chunked, &mut events, bound);
    assert_eq!(events, expected, "chunked decode differs from whole decode");
    assert_eq!(
        *chunked.stats(),
        stats,
        "chunked counters differ from whole decode"
    );

    // The same chunks through the callback API.
    let mut each = new();
    let mut events = Vec::new();
    for chunk in chunks(stream, sizes) {
        decode_each_all(&mut each, chunk, &mut events, bound);
    }
    finish_all(&mut each, &mut events, bound);
    assert_eq!(events, expected, "decode_each differs from whole decode");
    assert_eq!(
        *each.stats(),
        stats,
        "decode_each counters differ from whole decode"
    );

    // An inbox, its queue emptied on a schedule of the chunk sizes, hands over the
    // payloads among those events.
    crate::inbox::check_inbox(new(), sizes, stream, &expected);

    // After `finish` the decoder reads a new stream as a new decoder would.
    let mut again = Vec::new();
    decode_all(&mut whole, stream, &mut again, bound);
    finish_all(&mut whole, &mut again, bound);
    assert_eq!(
        again, expected,
        "decoder reused after finish differs from a new one"
    );

    let capacity = whole.capacity();
    for event in &expected {
        if let Event::Frame(data) = event {
            assert!(!data.is_empty() && data.len() <= capacity);
            check_frame::<N>(mode, data);
        }
    }

    // Mode 2: a valid frame after any garbage is always found.
    if mode == ApiMode::Escaped {
        let frame = expected
            .iter()
            .find_map(|e| match e {
                Event::Frame(data) => Some(data.as_slice()),
                Event::Error(_) => None,
            })
            .unwrap_or(&[0x8A, 0x06]);
        let mut tail = stream.to_vec();
        let n = encode_raw(mode, frame, &mut tail);
        let mut events = Vec::new();
        let mut decoder = new();
        decode_all(&mut decoder, &tail, &mut events, event_bound(tail.len()));
        assert_eq!(
            events.last(),
            Some(&Event::Frame(frame.to_vec())),
            "mode 2: a valid frame of {n} bytes after the stream was not found"
        );
        assert!(
            decoder.is_idle(),
            "mode 2: decoder not idle after a whole frame"
        );
    }
    (expected, stats)
}

/// Appends `data` encoded as a frame in `mode` to `out`; returns the encoded length.
fn encode_raw(mode: ApiMode, data: &[u8], out: &mut Vec<u8>) -> usize {
    let raw = RawFrame::new(data).expect("frame data is not empty");
    let start = out.len();
    out.resize(start + raw.encoded_len(mode), 0);
    let n = raw
        .encode(mode, &mut out[start..])
        .expect("buffer of encoded_len");
    assert_eq!(
        n,
        raw.encoded_len(mode),
        "encode wrote other than encoded_len"
    );
    n
}

/// A decoded frame encodes back to a frame that decodes alone to the same data; its
/// typed form, when it has one, emits the same frame data (fixed-size frame types
/// ignore trailing bytes, so theirs is a prefix).
fn check_frame<const N: usize>(mode: ApiMode, data: &[u8]) {
    let mut wire = Vec::new();
    encode_raw(mode, data, &mut wire);
    let mut decoder = Decoder::<N>::new(mode);
    let mut events = Vec::new();
    decode_all(&mut decoder, &wire, &mut events, event_bound(wire.len()));
    finish_all(&mut decoder, &mut events, event_bound(wire.len()));
    assert_eq!(events, [Event::Frame(data.to_vec())], "frame re-encoded");

    if let Ok(frame) = Frame::parse_bytes(data) {
        check_typed(&frame, data);
    }
}

/// A typed frame emits its frame data again, and parses from it to itself.
pub fn check_typed(frame: &Frame<'_>, data: &[u8]) {
    let mut emitted = vec![0u8; frame.frame_data_len()];
    let n = frame
        .emit_frame_data(&mut emitted)
        .expect("buffer of frame_data_len");
    assert_eq!(n, emitted.len());
    match frame {
        Frame::TransmitStatus(_) | Frame::ModemStatus(_) => {
            assert!(
                data.starts_with(&emitted),
                "typed frame emitted other bytes"
            )
        }
        _ => assert_eq!(emitted, data, "typed frame emitted other bytes"),
    }
    assert_eq!(Frame::parse_bytes(&emitted).as_ref(), Ok(frame));
    // A node discovery answer reads back to its bytes.
    let answer = match frame {
        Frame::AtCommandResponse(at) if at.command == *b"ND" => Some(at.data),
        Frame::RemoteAtResponse(at) if at.command == *b"ND" => Some(at.data),
        _ => None,
    };
    if let Some(Ok(node)) = answer.map(NodeInfo::parse) {
        let mut bytes = vec![0u8; node.len()];
        assert_eq!(node.emit(&mut bytes), Ok(bytes.len()));
        assert_eq!(
            Some(&bytes[..]),
            answer,
            "node discovery answer emitted other bytes"
        );
    }
}
