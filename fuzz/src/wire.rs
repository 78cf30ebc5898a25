//! Checks on encoded frames and the decoding of a single encoded frame.

use xbee_api::{ApiMode, DEFAULT_CAPACITY, Decoder, EncodeFrame, Frame, InPlaceFrame, RawFrame};

use crate::events::{Event, decode_all, event_bound, finish_all, push_all};

/// Encodes `frame` in `mode`, checks the encoding (length, delimiter, escaping), then
/// decodes it whole, in `chunk`-byte reads and a byte at a time: each gives exactly the
/// frame data, which types back to `frame`; built in place ([`InPlaceFrame`]) from its
/// frame data split at a point `chunk` picks, it is the same bytes. Returns the
/// encoded bytes.
pub fn roundtrip(frame: &Frame<'_>, mode: ApiMode, chunk: usize) -> Vec<u8> {
    let len = frame.encoded_len(mode);
    let mut wire = vec![0u8; len];
    let n = frame
        .encode(mode, &mut wire)
        .expect("buffer of encoded_len");
    assert_eq!(n, len, "encode wrote other than encoded_len");
    assert!(
        frame.encode(mode, &mut vec![0u8; len - 1]).is_err(),
        "encode into a buffer one byte short succeeded"
    );
    assert_eq!(wire[0], 0x7E);
    if mode == ApiMode::Escaped {
        check_escaped(&wire[1..]);
    } else {
        assert_eq!(len, frame.frame_data_len() + 4);
    }

    let mut data = vec![0u8; frame.frame_data_len()];
    frame
        .emit_frame_data(&mut data)
        .expect("buffer of frame_data_len");
    let expected = [Event::Frame(data.clone())];
    let bound = event_bound(wire.len());

    let mut decoder: Decoder = Decoder::new(mode);
    let mut events = Vec::new();
    decode_all(&mut decoder, &wire, &mut events, bound);
    assert!(decoder.is_idle(), "decoder not idle after a whole frame");
    finish_all(&mut decoder, &mut events, bound);
    assert_eq!(events, expected, "whole decode");

    let mut decoder: Decoder = Decoder::new(mode);
    let mut events = Vec::new();
    for piece in wire.chunks(chunk.max(1)) {
        decode_all(&mut decoder, piece, &mut events, bound);
    }
    finish_all(&mut decoder, &mut events, bound);
    assert_eq!(events, expected, "chunked decode");

    let mut decoder = Decoder::<DEFAULT_CAPACITY>::new(mode);
    let mut events = Vec::new();
    push_all(&mut decoder, &wire, &mut events, bound);
    finish_all(&mut decoder, &mut events, bound);
    assert_eq!(events, expected, "byte-at-a-time decode");

    // Built in its own buffer: the frame data's first bytes (at least the type byte) as
    // the header, the rest written after it as the payload. The same bytes come out.
    let split = 1 + chunk % data.len();
    let header = RawFrame::new(&data[..split]).expect("a type byte");
    let mut buffer = vec![0u8; len];
    let mut built = InPlaceFrame::new(&mut buffer, &header).expect("room for the header");
    built.data_mut()[..data.len() - split].copy_from_slice(&data[split..]);
    let in_place = built
        .finish(data.len() - split, mode)
        .expect("a buffer of encoded_len");
    assert_eq!(in_place, &wire[..], "frame built in place");

    let typed = Frame::parse_bytes(&data).expect("encoded frame types");
    assert_eq!(&typed, frame, "frame types back to another frame");
    wire
}

/// Mode 2 bytes after the delimiter: no raw special byte, and every escape is one of
/// the four escaped special bytes.
fn check_escaped(bytes: &[u8]) {
    let mut iter = bytes.iter();
    while let Some(&b) = iter.next() {
        assert!(
            !matches!(b, 0x7E | 0x11 | 0x13),
            "raw special byte 0x{b:02X} in mode 2"
        );
        if b == 0x7D {
            let next = iter.next().copied();
            assert!(
                matches!(next, Some(0x5E | 0x5D | 0x31 | 0x33)),
                "bad escape 0x7D {next:02X?} from the encoder"
            );
        }
    }
}
