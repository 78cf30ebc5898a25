//! Property tests: valid frames among garbage, corrupt and cut-off frames, fed in any
//! read sizes, all come out in order and nothing else does; encode then decode is the
//! identity for every frame type.

mod common;

use common::{
    decode_bytes, decode_bytes_with, decode_each_slices, decode_each_slices_with, decode_slices,
    decode_slices_with, frames,
};
use proptest::prelude::*;
use xbee_api::wire::{checksum, needs_escape};
use xbee_api::{
    ApiMode, Decoder, DecoderMode, EncodeFrame, Frame, Mode1, Mode2, RawFrame, max_encoded_len,
};

const N: usize = 512;

/// Frame types with the least frame data length of each; 0x23 stands for unknown types.
const TYPES: [(u8, usize); 12] = [
    (0x10, 14),
    (0x90, 12),
    (0x8B, 7),
    (0x08, 4),
    (0x09, 4),
    (0x88, 5),
    (0x8A, 2),
    (0x11, 20),
    (0x91, 18),
    (0x17, 15),
    (0x97, 15),
    (0x23, 1),
];

/// Frame data of a random frame of a random type, at least as long as its fixed fields
/// (exactly as long for the fixed-size Transmit Status and Modem Status).
fn frame_data() -> impl Strategy<Value = Vec<u8>> {
    (
        0..TYPES.len(),
        proptest::collection::vec(any::<u8>(), 0..120),
    )
        .prop_map(|(t, mut extra)| {
            let (frame_type, min) = TYPES[t];
            if matches!(frame_type, 0x8B | 0x8A) {
                extra.clear();
            }
            let mut data = vec![frame_type];
            data.extend((1..min).map(|i| extra.get(i).copied().unwrap_or(i as u8)));
            data.extend_from_slice(&extra);
            data
        })
}

/// Frame data of a random Node Identification Indicator (0x95): random fields around
/// node information that reads (an identifier without 0x00, then its 0x00, and 0, 1, 4
/// or 5 bytes of optional fields).
fn node_identification_data() -> impl Strategy<Value = Vec<u8>> {
    (
        proptest::collection::vec(any::<u8>(), 21),
        proptest::collection::vec(1..=255u8, 0..20),
        proptest::collection::vec(any::<u8>(), 8),
        prop_oneof![Just(0usize), Just(1), Just(4), Just(5)],
        any::<[u8; 5]>(),
    )
        .prop_map(|(head, identifier, tail, extra, optional)| {
            let mut data = vec![0x95];
            data.extend(&head);
            data.extend(&identifier);
            data.push(0);
            data.extend(&tail);
            data.extend(&optional[..extra]);
            data
        })
}

/// Wire bytes of frame data with a given checksum byte.
fn wire(data: &[u8], check: u8, mode: ApiMode) -> Vec<u8> {
    let mut body = (data.len() as u16).to_be_bytes().to_vec();
    body.extend_from_slice(data);
    body.push(check);
    let mut out = vec![0x7E];
    for b in body {
        if mode == ApiMode::Escaped && needs_escape(b) {
            out.extend([0x7D, b ^ 0x20]);
        } else {
            out.push(b);
        }
    }
    out
}

#[derive(Debug, Clone)]
enum Item {
    Valid(Vec<u8>),
    /// Garbage without 0x7E.
    Garbage(Vec<u8>),
    /// A frame with its checksum off by a non-zero amount.
    BadChecksum(Vec<u8>, u8),
    /// A frame whose data holds an invalid escape (mode 2; a bad checksum in mode 1).
    BadEscape(Vec<u8>, usize),
    /// A frame cut after the given fraction of its bytes.
    Cut(Vec<u8>, f64),
}

fn item() -> impl Strategy<Value = Item> {
    prop_oneof![
        4 => frame_data().prop_map(Item::Valid),
        2 => proptest::collection::vec(any::<u8>().prop_filter("no 0x7E", |b| *b != 0x7E), 1..40)
            .prop_map(Item::Garbage),
        1 => (frame_data(), 1..=255u8).prop_map(|(d, off)| Item::BadChecksum(d, off)),
        1 => (frame_data(), any::<usize>()).prop_map(|(d, at)| Item::BadEscape(d, at)),
        1 => (frame_data(), 0.0..1.0f64).prop_map(|(d, f)| Item::Cut(d, f)),
    ]
}

/// The stream, the valid frames in order, and the byte ranges of the valid frames.
type Built = (Vec<u8>, Vec<Vec<u8>>, Vec<(usize, usize)>);

fn build(items: &[Item], mode: ApiMode) -> Built {
    let mut stream = Vec::new();
    let mut valid = Vec::new();
    let mut ranges = Vec::new();
    for item in items {
        match item {
            Item::Valid(data) => {
                let start = stream.len();
                stream.extend(wire(data, checksum(data), mode));
                ranges.push((start, stream.len()));
                valid.push(data.clone());
            }
            Item::Garbage(bytes) => stream.extend_from_slice(bytes),
            Item::BadChecksum(data, off) => {
                stream.extend(wire(data, checksum(data).wrapping_add(*off), mode))
            }
            Item::BadEscape(data, at) => {
                let mut w = wire(data, checksum(data), mode);
                let at = 3 + at % (w.len() - 3);
                w.splice(at..at, [0x7D, 0x01]);
                stream.extend(w);
            }
            Item::Cut(data, fraction) => {
                let w = wire(data, checksum(data), mode);
                let keep = 1 + ((w.len() - 1) as f64 * fraction) as usize;
                stream.extend_from_slice(&w[..keep.min(w.len() - 1)]);
            }
        }
    }
    (stream, valid, ranges)
}

/// Whether a candidate frame starting at `p` (a 0x7E that does not start a valid frame)
/// would by chance decode as a frame: such streams are not what the property is about.
fn bogus_frame_at(stream: &[u8], p: usize, mode: ApiMode) -> bool {
    let mut bytes = Vec::new();
    let mut i = p + 1;
    while i < stream.len() {
        let b = stream[i];
        match mode {
            ApiMode::Unescaped => bytes.push(b),
            ApiMode::Escaped => {
                if b == 0x7E {
                    break;
                }
                if b == 0x7D {
                    match stream.get(i + 1) {
                        Some(&n) if needs_escape(n ^ 0x20) => {
                            bytes.push(n ^ 0x20);
                            i += 1;
                        }
                        _ => break,
                    }
                } else {
                    bytes.push(b);
                }
            }
        }
        i += 1;
        if bytes.len() >= 2 {
            let len = usize::from(u16::from_be_bytes([bytes[0], bytes[1]]));
            if len == 0 || len > N - 4 {
                return false;
            }
            if bytes.len() == len + 3 {
                return checksum(&bytes[2..2 + len]) == bytes[2 + len];
            }
        }
    }
    false
}

fn plausible(stream: &[u8], ranges: &[(usize, usize)], mode: ApiMode) -> bool {
    (0..stream.len())
        .filter(|&p| stream[p] == 0x7E)
        .filter(|&p| !ranges.iter().any(|&(s, e)| p >= s && p < e))
        .all(|p| !bogus_frame_at(stream, p, mode))
}

fn mode() -> impl Strategy<Value = ApiMode> {
    prop_oneof![Just(ApiMode::Unescaped), Just(ApiMode::Escaped)]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn every_valid_frame_comes_out_in_order(
        mode in mode(),
        items in proptest::collection::vec(item(), 0..24),
        reads in proptest::collection::vec(1..80usize, 1..16),
    ) {
        let (stream, valid, ranges) = build(&items, mode);
        prop_assume!(plausible(&stream, &ranges, mode));
        let (events, stats) = decode_slices::<N>(mode, &stream, &reads);
        prop_assert_eq!(&frames(&events), &valid);
        prop_assert_eq!(stats.frames_ok as usize, valid.len());
        let (events, _) = decode_bytes::<N>(mode, &stream);
        prop_assert_eq!(&frames(&events), &valid);
    }

    #[test]
    fn encode_then_decode_is_identity(
        mode in mode(),
        data in prop_oneof![4 => frame_data(), 1 => node_identification_data()],
    ) {
        let frame = Frame::parse_bytes(&data).unwrap();
        prop_assert_eq!(frame.frame_type(), data[0]);
        let mut wire_bytes = vec![0u8; frame.encoded_len(mode)];
        let n = frame.encode(mode, &mut wire_bytes).unwrap();
        prop_assert_eq!(n, wire_bytes.len());
        let bound = max_encoded_len(data.len(), mode);
        prop_assert!(n <= bound && (mode == ApiMode::Escaped || n == bound));
        prop_assert_eq!(&wire_bytes, &wire(&data, checksum(&data), mode));
        prop_assert!(frame.encode(mode, &mut vec![0u8; n - 1]).is_err());
        // A byte at a time, the same bytes.
        let mut bytes = Vec::new();
        prop_assert_eq!(frame.write_to(mode, |b| bytes.push(b)), Ok(n));
        prop_assert_eq!(&bytes, &wire_bytes);
        let (events, stats) = decode_slices::<N>(mode, &wire_bytes, &[n]);
        prop_assert_eq!(stats.errors(), 0);
        let decoded = frames(&events);
        prop_assert_eq!(decoded.len(), 1);
        let again = Frame::parse(RawFrame::new(&decoded[0]).unwrap()).unwrap();
        prop_assert_eq!(again, frame);
    }

    #[test]
    fn arbitrary_bytes_never_panic(
        mode in mode(),
        stream in proptest::collection::vec(any::<u8>(), 0..600),
        reads in proptest::collection::vec(1..64usize, 1..8),
    ) {
        let (events, stats) = decode_slices::<64>(mode, &stream, &reads);
        prop_assert_eq!(frames(&events).len(), stats.frames_ok as usize);
        for data in frames(&events) {
            let _ = Frame::parse_bytes(&data);
        }
        let (bytes_events, bytes_stats) = decode_bytes::<64>(mode, &stream);
        let (each_events, each_stats) = decode_each_slices::<64>(mode, &stream, &reads);
        prop_assert_eq!(&events, &bytes_events);
        prop_assert_eq!(&each_events, &bytes_events);
        prop_assert_eq!(stats, bytes_stats);
        prop_assert_eq!(each_stats, bytes_stats);
    }
}

/// Frame data like [`frame_data`], with bytes drawn often from those the mode 2 decoder
/// looks at (0x7C..=0x7F, XON, XOFF), so that escapes fall at every place of a word.
fn escape_rich_data() -> impl Strategy<Value = Vec<u8>> {
    let byte = prop_oneof![
        2 => any::<u8>(),
        1 => proptest::sample::select(vec![0x7Cu8, 0x7D, 0x7E, 0x7F, 0x11, 0x13, 0x5D, 0x5E]),
    ];
    (0..TYPES.len(), proptest::collection::vec(byte, 0..300)).prop_map(|(t, mut extra)| {
        let (frame_type, min) = TYPES[t];
        if matches!(frame_type, 0x8B | 0x8A) {
            extra.truncate(min - 1);
        }
        let mut data = vec![frame_type];
        data.extend((1..min).map(|i| extra.get(i).copied().unwrap_or(i as u8)));
        data.extend_from_slice(&extra);
        data
    })
}

/// Items like [`item`], mostly valid frames of escape-rich data.
fn rich_item() -> impl Strategy<Value = Item> {
    prop_oneof![
        6 => escape_rich_data().prop_map(Item::Valid),
        1 => proptest::collection::vec(any::<u8>().prop_filter("no 0x7E", |b| *b != 0x7E), 1..40)
            .prop_map(Item::Garbage),
        1 => (escape_rich_data(), 1..=255u8).prop_map(|(d, off)| Item::BadChecksum(d, off)),
        1 => (escape_rich_data(), any::<usize>()).prop_map(|(d, at)| Item::BadEscape(d, at)),
        1 => (escape_rich_data(), 0.0..1.0f64).prop_map(|(d, f)| Item::Cut(d, f)),
    ]
}

/// Read sizes from a byte to the whole stream, so that frames often lie whole in the
/// input given to `decode` and its whole-frame paths take them.
fn reads_up_to_whole() -> impl Strategy<Value = Vec<usize>> {
    proptest::collection::vec(prop_oneof![1..80usize, 80..2000usize, Just(1 << 20)], 1..8)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    /// The slice path, with frames whole in its input, yields exactly the events and
    /// counters of the byte-at-a-time path, and every valid frame in order.
    #[test]
    fn whole_frames_in_the_input_decode_as_byte_at_a_time(
        mode in mode(),
        items in proptest::collection::vec(rich_item(), 0..24),
        reads in reads_up_to_whole(),
    ) {
        let (stream, valid, ranges) = build(&items, mode);
        prop_assume!(plausible(&stream, &ranges, mode));
        let (events, stats) = decode_slices::<N>(mode, &stream, &reads);
        prop_assert_eq!(&frames(&events), &valid);
        let (whole, whole_stats) = decode_slices::<N>(mode, &stream, &[1 << 20]);
        let (bytes, bytes_stats) = decode_bytes::<N>(mode, &stream);
        prop_assert_eq!(&events, &bytes);
        prop_assert_eq!(&whole, &bytes);
        prop_assert_eq!(stats, bytes_stats);
        prop_assert_eq!(whole_stats, bytes_stats);
        let (each, each_stats) = decode_each_slices::<N>(mode, &stream, &reads);
        let (each_whole, each_whole_stats) = decode_each_slices::<N>(mode, &stream, &[1 << 20]);
        prop_assert_eq!(&each, &bytes);
        prop_assert_eq!(&each_whole, &bytes);
        prop_assert_eq!(each_stats, bytes_stats);
        prop_assert_eq!(each_whole_stats, bytes_stats);
    }

    /// Frames as long as the buffer (no room past the data in mode 2) and garbage around
    /// them: the slice path, fed whole, matches the byte-at-a-time path.
    #[test]
    fn whole_frames_near_capacity_decode_as_byte_at_a_time(
        mode in mode(),
        frames_data in proptest::collection::vec(
            proptest::collection::vec(
                prop_oneof![3 => any::<u8>(), 1 => Just(0x7Du8), 1 => Just(0x7Eu8)],
                56..=64,
            ),
            1..6,
        ),
        garbage in proptest::collection::vec(any::<u8>(), 0..6),
    ) {
        let mut stream = Vec::new();
        for data in &frames_data {
            stream.extend(wire(data, checksum(data), mode));
            stream.extend_from_slice(&garbage);
        }
        let (whole, whole_stats) = decode_slices::<64>(mode, &stream, &[1 << 20]);
        let (bytes, bytes_stats) = decode_bytes::<64>(mode, &stream);
        let (each, each_stats) = decode_each_slices::<64>(mode, &stream, &[1 << 20]);
        prop_assert_eq!(&whole, &bytes);
        prop_assert_eq!(whole_stats, bytes_stats);
        prop_assert_eq!(&each, &bytes);
        prop_assert_eq!(each_stats, bytes_stats);
    }
}

/// Read sizes as a UART FIFO or a DMA buffer hands them over: one size throughout (1 to
/// 64 bytes), or a mix of them.
fn fifo_reads() -> impl Strategy<Value = Vec<usize>> {
    prop_oneof![
        (1..=64usize).prop_map(|n| vec![n]),
        proptest::collection::vec(1..=64usize, 1..8),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    /// Small chunks, so that frames are split across calls at every place: `decode_each`
    /// and `decode` yield exactly the events and counters of the byte-at-a-time path.
    #[test]
    fn fifo_chunks_decode_as_byte_at_a_time(
        mode in mode(),
        items in proptest::collection::vec(rich_item(), 0..24),
        reads in fifo_reads(),
    ) {
        let (stream, valid, ranges) = build(&items, mode);
        prop_assume!(plausible(&stream, &ranges, mode));
        let (bytes, bytes_stats) = decode_bytes::<N>(mode, &stream);
        let (each, each_stats) = decode_each_slices::<N>(mode, &stream, &reads);
        let (events, stats) = decode_slices::<N>(mode, &stream, &reads);
        prop_assert_eq!(&frames(&bytes), &valid);
        prop_assert_eq!(&each, &bytes);
        prop_assert_eq!(each_stats, bytes_stats);
        prop_assert_eq!(&events, &bytes);
        prop_assert_eq!(stats, bytes_stats);
    }

    /// Frames up to the buffer's capacity among garbage, in small chunks: no room past
    /// the frame data for whole steps near the end of the buffer.
    #[test]
    fn fifo_chunks_near_capacity_decode_as_byte_at_a_time(
        mode in mode(),
        frames_data in proptest::collection::vec(
            proptest::collection::vec(
                prop_oneof![3 => any::<u8>(), 1 => Just(0x7Du8), 1 => Just(0x7Eu8)],
                1..=64,
            ),
            1..6,
        ),
        garbage in proptest::collection::vec(any::<u8>(), 0..6),
        reads in fifo_reads(),
    ) {
        let mut stream = Vec::new();
        for data in &frames_data {
            stream.extend(wire(data, checksum(data), mode));
            stream.extend_from_slice(&garbage);
        }
        let (bytes, bytes_stats) = decode_bytes::<64>(mode, &stream);
        let (each, each_stats) = decode_each_slices::<64>(mode, &stream, &reads);
        let (events, stats) = decode_slices::<64>(mode, &stream, &reads);
        prop_assert_eq!(&each, &bytes);
        prop_assert_eq!(each_stats, bytes_stats);
        prop_assert_eq!(&events, &bytes);
        prop_assert_eq!(stats, bytes_stats);
    }
}

/// Frame data around a limit of 12 to 16 bytes: plain, or a frame type byte, a whole
/// frame on the wire (valid or not) and padding, so that a frame over the limit holds
/// another.
fn data_near_limit(mode: ApiMode) -> impl Strategy<Value = Vec<u8>> {
    let byte = prop_oneof![3 => any::<u8>(), 1 => Just(0x7Du8), 1 => Just(0x7Eu8)];
    let plain = proptest::collection::vec(byte.clone(), 1..=24);
    let nested = (
        proptest::collection::vec(byte.clone(), 1..=8),
        any::<bool>(),
        proptest::collection::vec(byte, 0..=8),
    )
        .prop_map(move |(inner, good, pad)| {
            let check = checksum(&inner).wrapping_add(u8::from(!good));
            let mut data = vec![0x23];
            data.extend(wire(&inner, check, mode));
            data.extend(pad);
            data
        });
    prop_oneof![plain, nested]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    /// A decoder limited to fewer bytes than its buffer holds decodes exactly as a
    /// decoder whose buffer is that small: frames over the limit are errors at their
    /// length field and, in mode 1, are scanned again, so frames inside them come out.
    #[test]
    fn a_length_limit_decodes_as_a_smaller_buffer(
        (mode, frames_data) in mode().prop_flat_map(|mode| (
            Just(mode),
            proptest::collection::vec((data_near_limit(mode), any::<bool>()), 1..8),
        )),
        garbage in proptest::collection::vec(any::<u8>(), 0..4),
        reads in fifo_reads(),
    ) {
        let stream = frames_among(Vec::new(), &frames_data, &garbage, mode);
        // 16 bytes of frame data in mode 2, 12 in mode 1 (the frame's 4 other bytes).
        let limited = || Decoder::<64>::with_max_len(mode, 16 - 4 * usize::from(mode == ApiMode::Unescaped));
        let (expected, expected_stats) = decode_bytes::<16>(mode, &stream);
        // A byte at a time, in reads, through `decode_each` in reads and whole.
        for (events, stats) in every_way(limited, &stream, &reads) {
            prop_assert_eq!(&events, &expected);
            prop_assert_eq!(stats, expected_stats);
        }
    }
}

/// `stream` followed by each frame of `frames` on the wire in `mode` (with a wrong
/// checksum where it is not `good`), `garbage` after each.
fn frames_among(
    mut stream: Vec<u8>,
    frames: &[(Vec<u8>, bool)],
    garbage: &[u8],
    mode: ApiMode,
) -> Vec<u8> {
    for (data, good) in frames {
        let check = checksum(data).wrapping_add(u8::from(!good));
        stream.extend(wire(data, check, mode));
        stream.extend_from_slice(garbage);
    }
    stream
}

/// Decodes `stream` with a decoder made by `new` in every way (a byte at a time, in
/// `reads`, through `decode_each`, whole); each run's events and counters.
fn every_way<M: DecoderMode>(
    new: impl Fn() -> Decoder<64, M>,
    stream: &[u8],
    reads: &[usize],
) -> [(Vec<common::Owned>, xbee_api::DecoderStats); 4] {
    [
        decode_bytes_with(new(), stream),
        decode_slices_with(new(), stream, reads),
        decode_each_slices_with(new(), stream, reads),
        decode_each_slices_with(new(), stream, &[1 << 20]),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    /// A decoder whose type fixes the mode decodes exactly as one given the mode, in
    /// every way of feeding it, limited or not: the same events and counters.
    #[test]
    fn a_mode_fixed_in_the_type_decodes_as_one_given_at_run_time(
        (mode, frames_data) in mode().prop_flat_map(|mode| (
            Just(mode),
            proptest::collection::vec((data_near_limit(mode), any::<bool>()), 1..8),
        )),
        garbage in proptest::collection::vec(any::<u8>(), 0..4),
        noise in proptest::collection::vec(any::<u8>(), 0..64),
        reads in fifo_reads(),
        max_len in prop_oneof![Just(usize::MAX), 8..=24usize],
    ) {
        let stream = frames_among(noise, &frames_data, &garbage, mode);
        let given = every_way(|| Decoder::<64>::with_max_len(mode, max_len), &stream, &reads);
        let fixed = match mode {
            ApiMode::Unescaped => {
                every_way(|| Decoder::<64, Mode1>::fixed_with_max_len(max_len), &stream, &reads)
            }
            ApiMode::Escaped => {
                every_way(|| Decoder::<64, Mode2>::fixed_with_max_len(max_len), &stream, &reads)
            }
        };
        prop_assert_eq!(fixed, given);
    }
}

#[test]
fn a_decoder_of_a_fixed_mode_says_its_mode_and_capacity() {
    let one: Decoder<100, Mode1> = Decoder::fixed();
    let two: Decoder<100, Mode2> = Decoder::fixed();
    assert_eq!((one.mode(), one.capacity()), (ApiMode::Unescaped, 96));
    assert_eq!((two.mode(), two.capacity()), (ApiMode::Escaped, 100));
    let limited: Decoder<100, Mode2> = Decoder::fixed_with_max_len(60);
    assert_eq!(limited.capacity(), 60);
    // The mode is the type's, whatever the decoder holds: it costs no byte more.
    assert_eq!(
        core::mem::size_of::<Decoder<100, Mode2>>(),
        core::mem::size_of::<Decoder<100>>()
    );
}
