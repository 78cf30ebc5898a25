//! Mode 2 frames at the edges of the one-window path (a frame whole in the 64 bytes from
//! its start delimiter, with 128 bytes or more of input and a buffer as large): every
//! length from 1 to 64, escapes and escaped checksum bytes up to the window's last byte,
//! bad escapes, delimiters inside and right after a frame, length fields around the
//! window's limit. `decode` in a loop and `decode_each`, whatever the reads, yield
//! exactly the events and counters of `push`, for buffers below and above the window's
//! 128 bytes and for length limits around its 60.

mod common;

use common::{
    Owned, decode_bytes_with, decode_each_slices_with, decode_slices_with, frames, to_hex,
};
use proptest::prelude::*;
use xbee_api::wire::{checksum, needs_escape};
use xbee_api::{ApiMode, DecodeError, Decoder, DecoderStats};

const MODE: ApiMode = ApiMode::Escaped;

/// Length limits tried on every buffer: none, and around the window's 60 bytes of data.
const LIMITS: [Option<usize>; 4] = [None, Some(59), Some(60), Some(61)];

/// Reads tried on every stream (cycled): the whole of it, a byte at a time, sizes around
/// the window's 64 and 128 bytes, and a mix.
const READS: [&[usize]; 9] = [
    &[1 << 20],
    &[1],
    &[7],
    &[64],
    &[127],
    &[128],
    &[129],
    &[3, 128, 1, 200],
    &[61, 62, 63, 65, 66, 67],
];

fn decoder<const N: usize>(limit: Option<usize>) -> Decoder<N> {
    match limit {
        Some(max_len) => Decoder::with_max_len(MODE, max_len),
        None => Decoder::new(MODE),
    }
}

/// `decode` in a loop and `decode_each`, in each of `reads`, against `push`, on a
/// decoder of `N` bytes limited to `limit`; `push`'s events and counters.
fn same_as_push<const N: usize>(
    stream: &[u8],
    limit: Option<usize>,
    reads: &[&[usize]],
) -> (Vec<Owned>, DecoderStats) {
    let expected = decode_bytes_with(decoder::<N>(limit), stream);
    for reads in reads {
        let got = decode_slices_with(decoder::<N>(limit), stream, reads);
        assert_eq!(
            got,
            expected,
            "decode, N = {N}, limit {limit:?}, reads {reads:?}, stream {}",
            to_hex(stream)
        );
        let got = decode_each_slices_with(decoder::<N>(limit), stream, reads);
        assert_eq!(
            got,
            expected,
            "decode_each, N = {N}, limit {limit:?}, reads {reads:?}, stream {}",
            to_hex(stream)
        );
    }
    expected
}

/// [`same_as_push`] for buffers of 64, 127, 128, 129, 200 and 512 bytes and every limit
/// of [`LIMITS`]; also checks that a limit decodes as a buffer of that size does.
/// `push`'s events and counters on the largest buffer, without a limit.
fn check(stream: &[u8], reads: &[&[usize]]) -> (Vec<Owned>, DecoderStats) {
    let mut limited = Vec::new();
    for limit in LIMITS {
        let runs = [
            same_as_push::<64>(stream, limit, reads),
            same_as_push::<127>(stream, limit, reads),
            same_as_push::<128>(stream, limit, reads),
            same_as_push::<129>(stream, limit, reads),
            same_as_push::<200>(stream, limit, reads),
            same_as_push::<512>(stream, limit, reads),
        ];
        if limit.is_some() {
            // Buffers above the limit all decode alike.
            for run in &runs[1..] {
                assert_eq!(run, &runs[0], "limit {limit:?}, stream {}", to_hex(stream));
            }
            limited.push(runs[0].clone());
        }
    }
    let sized = [
        same_as_push::<59>(stream, None, reads),
        same_as_push::<60>(stream, None, reads),
        same_as_push::<61>(stream, None, reads),
    ];
    assert_eq!(limited, sized, "limits against buffers of that size");
    same_as_push::<512>(stream, None, reads)
}

/// Wire bytes of a mode 2 frame of `data` with checksum byte `check`, every special
/// byte escaped (the length field's too).
fn wire(data: &[u8], check: u8) -> Vec<u8> {
    let mut body = (data.len() as u16).to_be_bytes().to_vec();
    body.extend_from_slice(data);
    body.push(check);
    let mut out = vec![0x7E];
    for b in body {
        if needs_escape(b) {
            out.extend([0x7D, b ^ 0x20]);
        } else {
            out.push(b);
        }
    }
    out
}

/// A valid frame of `data`.
fn valid(data: &[u8]) -> Vec<u8> {
    wire(data, checksum(data))
}

/// `len` bytes of frame data, plain but for special bytes at `specials` (data offsets),
/// with its first byte set so that the checksum byte is `check`.
fn data_with(len: usize, specials: &[usize], check: u8) -> Vec<u8> {
    let mut data: Vec<u8> = (0..len).map(|i| 0x20 + (i % 0x40) as u8).collect();
    for (n, &at) in specials.iter().enumerate() {
        if let Some(b) = data.get_mut(at) {
            *b = [0x7D, 0x7E, 0x11, 0x13][n % 4];
        }
    }
    // Choose the first byte (plain, unless it is one of the specials) for the checksum.
    if !specials.contains(&0) {
        let rest = checksum(&data[1..]);
        // checksum = 0xFF - sum: the first byte must make the sum `0xFF - check`.
        let first = (0xFFu8.wrapping_sub(check)).wrapping_sub(0xFFu8.wrapping_sub(rest));
        data[0] = first;
    }
    data
}

/// Filler after the frames under test: plain bytes, no delimiter, so that the window
/// has its 128 bytes of input.
fn padding(n: usize) -> Vec<u8> {
    vec![0x42; n]
}

/// A trailing valid frame, so that what follows a damaged frame is seen to come out.
const NEXT: [u8; 3] = [0x8A, 0x06, 0x7D];

#[test]
fn every_length_with_escapes_up_to_the_window_end() {
    for len in 1..=64 {
        // Escapes among the last data bytes, the checksum byte escaped or not.
        let tails: [&[usize]; 6] = [
            &[],
            &[len - 1],
            &[len.saturating_sub(2), len - 1],
            &[len.saturating_sub(4), len.saturating_sub(3), len - 1],
            &[0, len - 1],
            &[0, 1, 2, 3],
        ];
        for specials in tails {
            for check in [0x00, 0x7D, 0x7E, 0x11, 0x13, 0x5E] {
                let data = data_with(len, specials, check);
                if specials.is_empty() || !specials.contains(&0) {
                    assert_eq!(checksum(&data), check);
                }
                let mut stream = valid(&data);
                let taken = stream.len();
                stream.extend(valid(&NEXT));
                stream.extend(padding(140));
                let (events, stats) = check_stream(&stream);
                assert_eq!(
                    frames(&events),
                    [data.clone(), NEXT.to_vec()],
                    "len {len}, taken {taken}, {}",
                    to_hex(&stream)
                );
                assert_eq!(stats.frames_ok, 2);
                assert_eq!(stats.errors(), 0);
            }
        }
    }
}

/// [`check`] with the reads of [`READS`].
fn check_stream(stream: &[u8]) -> (Vec<Owned>, DecoderStats) {
    check(stream, &READS)
}

#[test]
fn frames_of_exactly_64_and_65_bytes_with_escapes_at_the_end() {
    for len in 55..=61usize {
        for escapes in 0..=6 {
            // `escapes` special bytes at the end of the data: the frame takes
            // 4 + len + 1 + escapes bytes, around the window's 64.
            let specials: Vec<usize> = (len.saturating_sub(escapes)..len).collect();
            for check in [0x33, 0x7D] {
                let data = data_with(len, &specials, check);
                let mut stream = valid(&data);
                let taken = stream.len();
                stream.extend(padding(128));
                let (events, _) = check_stream(&stream);
                assert_eq!(frames(&events), [data], "taken {taken}");
            }
        }
    }
}

#[test]
fn bad_escapes_at_every_place_of_the_window() {
    for len in [1, 2, 30, 56, 58, 59, 60, 61] {
        let data = data_with(len, &[], 0x44);
        let good = valid(&data);
        for at in 3..good.len() + 1 {
            for partner in [0x7E, 0x7D, 0x00, 0x20, 0x5F, 0x31] {
                let mut stream = good.clone();
                stream.splice(at..at, [0x7D, partner]);
                stream.extend(valid(&NEXT));
                stream.extend(padding(128));
                let (events, stats) = check_stream(&stream);
                // A valid escape (0x31) only makes the frame longer by a byte: a bad
                // checksum or a truncated frame, but never a frame of the wrong data.
                assert!(!frames(&events).contains(&data) || at == good.len());
                assert_eq!(frames(&events).last(), Some(&NEXT.to_vec()));
                if partner != 0x31 && at < good.len() {
                    assert_eq!(stats.bad_escape, 1, "{}", to_hex(&stream));
                }
            }
        }
    }
}

#[test]
fn escape_cut_off_at_the_window_end() {
    // An escape as the window's last byte, its partner the 65th.
    for len in 55..=60 {
        let data = data_with(len, &[], 0x44);
        let mut stream = valid(&data);
        let at = 63.min(stream.len() - 1);
        stream.splice(at..at, [0x7D]);
        stream.extend(valid(&NEXT));
        stream.extend(padding(128));
        check_stream(&stream);
        let mut stream = valid(&data);
        stream.truncate(63);
        stream.resize(63, 0x41);
        stream.extend([0x7D, 0x31]);
        stream.extend(valid(&NEXT));
        stream.extend(padding(128));
        check_stream(&stream);
    }
}

#[test]
fn delimiters_inside_at_and_after_the_frame_end() {
    for len in [1, 2, 20, 57, 58, 59, 60, 61] {
        let data = data_with(len, &[len - 1], 0x7D);
        let good = valid(&data);
        // A raw delimiter in place of each byte after the length field, then one more
        // place: right after the frame (the next frame's delimiter).
        for at in 3..=good.len() {
            let mut stream = good.clone();
            if at < stream.len() {
                stream[at] = 0x7E;
            } else {
                stream.push(0x7E);
            }
            stream.extend(valid(&NEXT));
            stream.extend(padding(128));
            let (events, stats) = check_stream(&stream);
            assert_eq!(frames(&events).last(), Some(&NEXT.to_vec()));
            if at < good.len() {
                // Truncated, or a bad escape where the delimiter is an escape's partner
                // (and what follows it then cut off by the next frame).
                let errors = stats.truncated + stats.bad_escape;
                assert!((1..=2).contains(&errors), "{}", to_hex(&stream));
            }
        }
    }
}

#[test]
fn length_fields_around_the_window() {
    let body: Vec<u8> = (0..200).map(|i| 0x20 + (i % 0x40) as u8).collect();
    for (hi, lo) in [
        (0x00, 0x00),
        (0x00, 0x01),
        (0x00, 0x3B),
        (0x00, 0x3C),
        (0x00, 0x3D),
        (0x00, 0x3E),
        (0x00, 0x40),
        (0x00, 0x7D),
        (0x00, 0x7E),
        (0x00, 0x11),
        (0x00, 0x13),
        (0x01, 0x00),
        (0x7D, 0x00),
        (0x7E, 0x00),
        (0xFF, 0xFF),
    ] {
        for split in [0, 1, 5, 59, 60, 61, 62, 64, 70] {
            // A length field as it is, and escaped where it must be.
            for escape in [false, true] {
                let mut stream = vec![0x7E];
                for b in [hi, lo] {
                    if escape && needs_escape(b) {
                        stream.extend([0x7D, b ^ 0x20]);
                    } else {
                        stream.push(b);
                    }
                }
                stream.extend(&body[..split]);
                stream.extend(valid(&NEXT));
                stream.extend(padding(128));
                check_stream(&stream);
            }
        }
        // Escaped length fields whose value fits the window.
        let len = usize::from(u16::from_be_bytes([hi, lo]));
        if (1..=64).contains(&len) {
            let data = data_with(len, &[len - 1], 0x13);
            let mut stream = valid(&data);
            stream.extend(padding(128));
            let (events, _) = check_stream(&stream);
            assert_eq!(frames(&events), [data]);
        }
    }
}

#[test]
fn bad_checksums_with_escaped_checksum_bytes() {
    for len in [1, 30, 58, 59, 60] {
        for check in [0x7D, 0x7E, 0x11, 0x13, 0x00, 0xFF] {
            let data = data_with(len, &[len / 2], 0x20);
            for off in [1u8, 0x5D, 0x80] {
                let mut stream = wire(&data, checksum(&data).wrapping_add(off) ^ check);
                stream.extend(valid(&NEXT));
                stream.extend(padding(128));
                let (events, stats) = check_stream(&stream);
                let expected = checksum(&data);
                let got = expected.wrapping_add(off) ^ check;
                if got != expected {
                    assert_eq!(
                        events[0],
                        Owned::Error(DecodeError::BadChecksum { expected, got })
                    );
                    assert_eq!(stats.bad_checksum, 1);
                }
            }
        }
    }
}

#[test]
fn input_just_long_enough_for_the_window() {
    // Frames followed by 129, 130 and 131 bytes of input from their delimiter on, fed
    // whole: the window takes them from 130 on.
    for len in [1, 10, 58, 60] {
        let data = data_with(len, &[len - 1], 0x7E);
        for total in 125..=135 {
            let mut stream = valid(&data);
            stream.resize(total.max(stream.len()), 0x42);
            let (events, stats) = check_stream(&stream);
            assert_eq!(frames(&events), std::slice::from_ref(&data));
            assert_eq!(
                stats.bytes_skipped as usize,
                stream.len() - valid(&data).len()
            );
        }
    }
}

#[test]
fn frames_back_to_back_then_cut_off() {
    // Many window frames in one input, then a frame cut off at the end in each state:
    // `finish` reports it with the length field it read, if any, not the last frame's.
    let data = data_with(40, &[39], 0x11);
    let mut frames_in = Vec::new();
    for _ in 0..8 {
        frames_in.extend(valid(&data));
    }
    frames_in.extend(padding(70));
    for tail in [
        &[0x7E][..],
        &[0x7E, 0x00],
        &[0x7E, 0x00, 0x05],
        &[0x7E, 0x00, 0x05, 0x01, 0x7D],
        &[0x7E, 0x00, 0x05, 0x01, 0x02],
        &[0x7E, 0x00, 0x28],
        &[0x7E, 0x7D],
    ] {
        let mut stream = frames_in.clone();
        stream.extend(tail);
        let (events, stats) = check_stream(&stream);
        assert_eq!(stats.frames_ok, 8);
        assert_eq!(stats.truncated, 1);
        let Some(Owned::Error(DecodeError::Truncated { length, .. })) = events.last() else {
            panic!("{events:?}");
        };
        let expected = tail.get(1..3).and_then(|l| {
            let [hi, lo] = *l else { return None };
            (hi != 0x7D).then(|| u16::from_be_bytes([hi, lo]))
        });
        assert_eq!(*length, expected, "{}", to_hex(tail));
    }
}

#[test]
fn window_frames_then_push_and_decode_on_the_same_decoder() {
    // After frames taken in the window, the byte path and short reads go on from where
    // it left off.
    // 63 bytes on the wire, the last data byte escaped.
    let data = data_with(58, &[57], 0x20);
    let mut stream = Vec::new();
    for _ in 0..3 {
        stream.extend(valid(&data));
    }
    stream.extend(padding(128));
    let tail = [valid(&data), valid(&NEXT)].concat();
    let mut decoder: Decoder<130> = Decoder::new(MODE);
    let mut events = Vec::new();
    decoder.decode_each(&stream, |e| events.push(e.map(|f| f.data().to_vec())));
    for &b in &tail[..10] {
        if let Some(e) = decoder.push(b) {
            events.push(e.map(|f| f.data().to_vec()));
        }
    }
    decoder.decode_each(&tail[10..], |e| events.push(e.map(|f| f.data().to_vec())));
    assert!(decoder.finish().is_none());
    assert_eq!(
        events,
        [
            Ok(data.clone()),
            Ok(data.clone()),
            Ok(data.clone()),
            Ok(data.clone()),
            Ok(NEXT.to_vec())
        ]
    );
    assert_eq!(decoder.stats().frames_ok, 5);
    assert_eq!(decoder.stats().bytes_skipped, 128);
}

/// Frame data of 1 to 64 bytes, plain at the front and rich in special bytes towards
/// the end, so that escapes fall near the window's last bytes.
fn edge_data() -> impl Strategy<Value = Vec<u8>> {
    let special = proptest::sample::select(vec![0x7Du8, 0x7E, 0x11, 0x13, 0x5D, 0x5E, 0x31]);
    let tail_byte = prop_oneof![1 => any::<u8>(), 1 => special];
    (
        proptest::collection::vec(any::<u8>(), 0..=64),
        proptest::collection::vec(tail_byte, 0..=8),
        1..=64usize,
    )
        .prop_map(|(head, tail, len)| {
            // The last `len` bytes: the special-rich tail stays at the end.
            let mut data = head;
            data.extend(tail);
            let data = data.split_off(data.len().saturating_sub(len));
            if data.is_empty() { vec![0x23] } else { data }
        })
}

/// What is done to a frame before it goes into the stream.
#[derive(Debug, Clone)]
enum Damage {
    None,
    /// The checksum byte changed by this much (0: left valid), possibly into a special
    /// byte, which is then escaped.
    Checksum(u8),
    /// The checksum byte made a special one (escaped on the wire).
    SpecialChecksum(u8),
    /// An escape and this partner inserted this many bytes before the frame's end.
    Escape(u8, usize),
    /// A raw delimiter in place of the byte this far before the frame's end.
    Delimiter(usize),
    /// The length field replaced by these two raw bytes.
    Length(u8, u8),
    /// The frame cut this many bytes before its end.
    Cut(usize),
}

fn damage() -> impl Strategy<Value = Damage> {
    let near_end = 0..8usize;
    prop_oneof![
        6 => Just(Damage::None),
        1 => any::<u8>().prop_map(Damage::Checksum),
        2 => proptest::sample::select(vec![0x7Du8, 0x7E, 0x11, 0x13]).prop_map(Damage::SpecialChecksum),
        2 => (
            proptest::sample::select(vec![0x7Eu8, 0x7D, 0x00, 0x20, 0x5E, 0x5D, 0x31, 0x33]),
            near_end.clone(),
        )
            .prop_map(|(p, at)| Damage::Escape(p, at)),
        1 => near_end.clone().prop_map(Damage::Delimiter),
        1 => (
            proptest::sample::select(vec![0x00u8, 0x01, 0x7D, 0x7E]),
            proptest::sample::select(vec![0x00u8, 0x01, 0x3B, 0x3C, 0x3D, 0x3E, 0x40, 0x7D, 0x7E, 0x11]),
        )
            .prop_map(|(hi, lo)| Damage::Length(hi, lo)),
        1 => near_end.prop_map(Damage::Cut),
    ]
}

/// A frame as it goes into the stream.
fn damaged(data: &[u8], damage: &Damage) -> Vec<u8> {
    let check = checksum(data);
    let mut w = match *damage {
        Damage::Checksum(off) => wire(data, check.wrapping_add(off)),
        Damage::SpecialChecksum(c) => {
            // The first data byte chosen so that the checksum is `c`.
            let mut data = data.to_vec();
            let first = data[0];
            data[0] = first.wrapping_add(check.wrapping_sub(c));
            wire(&data, c)
        }
        _ => valid(data),
    };
    let back = |k: usize, w: &Vec<u8>| w.len() - 1 - k.min(w.len() - 4);
    match *damage {
        Damage::Escape(partner, k) => {
            let at = back(k, &w);
            w.splice(at..at, [0x7D, partner]);
        }
        Damage::Delimiter(k) => {
            let at = back(k, &w);
            w[at] = 0x7E;
        }
        Damage::Length(hi, lo) => {
            // The length field as it was on the wire, escapes included, replaced.
            let mut i = 1;
            for _ in 0..2 {
                i += if w[i] == 0x7D { 2 } else { 1 };
            }
            w.splice(1..i, [hi, lo]);
        }
        Damage::Cut(k) => {
            let at = back(k, &w);
            w.truncate(at);
        }
        _ => {}
    }
    w
}

#[derive(Debug, Clone)]
enum Piece {
    Frame(Vec<u8>, Damage),
    /// Bytes between frames: any, delimiters and escapes included.
    Garbage(Vec<u8>),
    /// Plain filler.
    Pad(usize),
}

fn piece() -> impl Strategy<Value = Piece> {
    let garbage_byte = prop_oneof![
        4 => any::<u8>(),
        1 => proptest::sample::select(vec![0x7Du8, 0x7E, 0x00]),
    ];
    prop_oneof![
        8 => (edge_data(), damage()).prop_map(|(d, x)| Piece::Frame(d, x)),
        1 => proptest::collection::vec(garbage_byte, 1..6).prop_map(Piece::Garbage),
        1 => (0..140usize).prop_map(Piece::Pad),
    ]
}

fn stream_of(pieces: &[Piece]) -> Vec<u8> {
    let mut stream = Vec::new();
    for piece in pieces {
        match piece {
            Piece::Frame(data, damage) => stream.extend(damaged(data, damage)),
            Piece::Garbage(bytes) => stream.extend(bytes),
            Piece::Pad(n) => stream.extend(padding(*n)),
        }
    }
    stream
}

fn reads() -> impl Strategy<Value = Vec<usize>> {
    prop_oneof![
        (1..=140usize).prop_map(|n| vec![n]),
        proptest::collection::vec(
            prop_oneof![1..=16usize, 60..=70usize, 125..=135usize, 136..400usize],
            1..6
        ),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Streams of short frames, damaged near their ends or not, with garbage and filler
    /// between them: every path, buffer, limit and read yields `push`'s events and
    /// counters, and every undamaged frame comes out.
    #[test]
    fn window_edges_decode_as_byte_at_a_time(
        pieces in proptest::collection::vec(piece(), 1..12),
        tail in 0..200usize,
        reads in reads(),
    ) {
        let mut stream = stream_of(&pieces);
        stream.extend(padding(tail));
        let (events, stats) = check(&stream, &[&[1 << 20], &reads]);
        prop_assert_eq!(frames(&events).len(), stats.frames_ok as usize);
    }

    /// Undamaged frames only, back to back: all of them come out, in order.
    #[test]
    fn window_frames_all_come_out(
        data in proptest::collection::vec(edge_data(), 1..12),
        tail in 0..200usize,
        reads in reads(),
    ) {
        let mut stream = Vec::new();
        for d in &data {
            stream.extend(valid(d));
        }
        stream.extend(padding(tail));
        let (events, stats) = check(&stream, &[&[1 << 20], &reads]);
        prop_assert_eq!(frames(&events), data);
        prop_assert_eq!(stats.errors(), 0);
    }
}

/// Bytes that make short frames likely: delimiters, small lengths, escapes and what
/// follows them, among any bytes.
fn soup() -> impl Strategy<Value = Vec<u8>> {
    let byte = prop_oneof![
        6 => any::<u8>(),
        2 => Just(0x00u8),
        1 => Just(0x7Eu8),
        1 => 1..=64u8,
        2 => proptest::sample::select(vec![0x7Du8, 0x5E, 0x5D, 0x31, 0x33, 0x11, 0x13]),
    ];
    proptest::collection::vec(byte, 0..700)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Any bytes at all: the same events and counters every way, and no panic.
    #[test]
    fn any_bytes_decode_as_byte_at_a_time(bytes in soup(), reads in reads()) {
        check(&bytes, &[&[1 << 20], &reads]);
    }
}

#[test]
fn a_read_that_starts_at_a_delimiter_inside_a_frame() {
    // The frame in progress is cut off by the start delimiter that begins the next read,
    // a window frame: it is reported (cut off, or a bad escape right after its 0x7D)
    // before that frame is taken whole.
    let cut = valid(&data_with(40, &[7], 0x11));
    let data = data_with(50, &[10], 0x22);
    for k in 1..cut.len() {
        let mut stream = cut[..k].to_vec();
        stream.extend(valid(&data));
        stream.extend(padding(128));
        let (events, stats) = check(&stream, &[&[k, 1 << 20]]);
        let [Owned::Error(error), Owned::Frame(frame)] = &events[..] else {
            panic!("cut after {k}: {events:?}");
        };
        assert_eq!(*frame, data, "cut after {k}");
        // Frame data bytes before `end` (the one escape there takes two).
        let received = |end: usize| {
            let raw = cut.get(3..end).unwrap_or_default();
            raw.len() - raw.iter().filter(|&&b| b == 0x7D).count()
        };
        let expected = if cut[k - 1] == 0x7D {
            DecodeError::BadEscape {
                byte: 0x7E,
                received: received(k - 1),
            }
        } else {
            DecodeError::Truncated {
                length: (k >= 3).then_some(40),
                received: received(k),
            }
        };
        assert_eq!(*error, expected, "cut after {k}");
        assert_eq!(stats.frames_ok, 1, "cut after {k}");
    }
}
