//! Decoder behaviour: every error kind with its counters, mode 2 escaping of every frame
//! id and of length bytes, mode 1 rescans.

mod common;

use common::{Owned, decode_bytes, decode_slices, encode, frames, hex};
use xbee_api::{
    Address16, Address64, ApiMode, DecodeError, Decoder, EncodeFrame, ExplicitRxIndicatorRepr,
    Frame, RawFrame, ReceivePacketRepr, TransmitRequestRepr, decoder_buffer_len,
};

const MODEM: &str = "7E 00 02 8A 06 6F";

fn both<const N: usize>(mode: ApiMode, stream: &[u8]) -> (Vec<Owned>, xbee_api::DecoderStats) {
    let slices = decode_slices::<N>(mode, stream, &[stream.len()]);
    let ones = decode_slices::<N>(mode, stream, &[1]);
    let bytes = decode_bytes::<N>(mode, stream);
    assert_eq!(slices, ones);
    assert_eq!(slices, bytes);
    slices
}

#[test]
fn bad_checksum_then_next_frame() {
    for mode in [ApiMode::Unescaped, ApiMode::Escaped] {
        let stream = hex(&format!("7E 00 02 8A 06 70 {MODEM}"));
        let (events, stats) = both::<64>(mode, &stream);
        assert_eq!(
            events[0],
            Owned::Error(DecodeError::BadChecksum {
                expected: 0x6F,
                got: 0x70
            })
        );
        assert_eq!(events[1..], [Owned::Frame(vec![0x8A, 0x06])]);
        assert_eq!(stats.bad_checksum, 1);
        assert_eq!(stats.frames_ok, 1);
        assert_eq!(stats.errors(), 1);
    }
}

#[test]
fn oversize_and_empty() {
    for mode in [ApiMode::Unescaped, ApiMode::Escaped] {
        let capacity = Decoder::<16>::new(mode).capacity();
        let stream = hex(&format!("7E 00 40 00 7E 00 00 FF {MODEM}"));
        let (events, stats) = both::<16>(mode, &stream);
        assert_eq!(
            events[0],
            Owned::Error(DecodeError::Oversize {
                length: 0x40,
                capacity
            })
        );
        assert_eq!(events[1], Owned::Error(DecodeError::EmptyFrame));
        assert_eq!(events[2..], [Owned::Frame(vec![0x8A, 0x06])]);
        assert_eq!((stats.oversize, stats.empty, stats.frames_ok), (1, 1, 1));
    }
    assert_eq!(Decoder::<16>::new(ApiMode::Unescaped).capacity(), 12);
    assert_eq!(Decoder::<16>::new(ApiMode::Escaped).capacity(), 16);
}

#[test]
fn frame_as_long_as_capacity_fits() {
    for mode in [ApiMode::Unescaped, ApiMode::Escaped] {
        let capacity = Decoder::<32>::new(mode).capacity();
        let data: Vec<u8> = (0..capacity as u8).map(|i| i | 0x80).collect();
        let stream = encode(&RawFrame::new(&data).unwrap(), mode);
        let (events, stats) = both::<32>(mode, &stream);
        assert_eq!(events, [Owned::Frame(data)]);
        assert_eq!(stats.errors(), 0);
    }
}

/// The largest received frame data: the header and a 255-byte payload put back together
/// from fragments, 267 bytes in a Receive Packet and 273 in an Explicit Rx Indicator
/// (`AO=1`). A decoder sized by it takes that frame and drops one a byte longer.
#[test]
fn largest_received_frames_fit_a_decoder_sized_by_them() {
    assert_eq!(ReceivePacketRepr::MAX_LEN, 12 + 255);
    assert_eq!(ExplicitRxIndicatorRepr::HEADER_LEN, 18);
    assert_eq!(ExplicitRxIndicatorRepr::MAX_LEN, 18 + 255);
    assert_eq!(
        ReceivePacketRepr::MAX_LEN,
        ReceivePacketRepr::HEADER_LEN + TransmitRequestRepr::MAX_UNICAST_DATA_FRAGMENTED
    );
    let payload: Vec<u8> = (0..=254u8).collect();
    let rx = ReceivePacketRepr {
        src64: Address64(0x0013_A200_40B5_99B9),
        src16: Address16(0x1234),
        options: 0x01,
        data: &payload,
    };
    let explicit = ExplicitRxIndicatorRepr {
        src64: rx.src64,
        src16: rx.src16,
        src_endpoint: 0xE8,
        dst_endpoint: 0xE8,
        cluster_id: 0x0011,
        profile_id: 0xC105,
        options: 0x01,
        data: &payload,
    };
    assert_eq!(rx.frame_data_len(), ReceivePacketRepr::MAX_LEN);
    assert_eq!(explicit.frame_data_len(), ExplicitRxIndicatorRepr::MAX_LEN);
    const RX1: usize = decoder_buffer_len(ReceivePacketRepr::MAX_LEN, ApiMode::Unescaped);
    const RX2: usize = decoder_buffer_len(ReceivePacketRepr::MAX_LEN, ApiMode::Escaped);
    const AO1: usize = decoder_buffer_len(ExplicitRxIndicatorRepr::MAX_LEN, ApiMode::Unescaped);
    const AO2: usize = decoder_buffer_len(ExplicitRxIndicatorRepr::MAX_LEN, ApiMode::Escaped);
    for (mode, stream) in [
        (ApiMode::Unescaped, encode(&rx, ApiMode::Unescaped)),
        (ApiMode::Escaped, encode(&rx, ApiMode::Escaped)),
    ] {
        let (events, stats) = match mode {
            ApiMode::Unescaped => both::<RX1>(mode, &stream),
            ApiMode::Escaped => both::<RX2>(mode, &stream),
        };
        assert_eq!(stats.errors(), 0, "{mode:?}");
        let [Owned::Frame(data)] = &events[..] else {
            panic!("{mode:?}: {events:?}")
        };
        assert_eq!(ReceivePacketRepr::parse_bytes(data).unwrap(), rx);
    }
    // The Explicit Rx Indicator is too long for a decoder sized by the Receive Packet.
    let (events, stats) = both::<RX2>(ApiMode::Escaped, &encode(&explicit, ApiMode::Escaped));
    assert_eq!(stats.oversize, 1, "{events:?}");
    for mode in [ApiMode::Unescaped, ApiMode::Escaped] {
        let stream = encode(&explicit, mode);
        let (events, stats) = match mode {
            ApiMode::Unescaped => both::<AO1>(mode, &stream),
            ApiMode::Escaped => both::<AO2>(mode, &stream),
        };
        assert_eq!(stats.errors(), 0, "{mode:?}");
        let [Owned::Frame(data)] = &events[..] else {
            panic!("{mode:?}: {events:?}")
        };
        assert_eq!(
            ExplicitRxIndicatorRepr::parse_bytes(data).unwrap(),
            explicit
        );
    }
}

#[test]
fn mode2_truncated_by_start_delimiter() {
    let stream = hex(&format!("7E 00 05 8A 06 {MODEM}"));
    let (events, stats) = both::<64>(ApiMode::Escaped, &stream);
    assert_eq!(
        events,
        [
            Owned::Error(DecodeError::Truncated {
                length: Some(5),
                received: 2
            }),
            Owned::Frame(vec![0x8A, 0x06])
        ]
    );
    assert_eq!(stats.truncated, 1);
    // Cut inside the length field.
    let stream = hex(&format!("7E 00 {MODEM}"));
    let (events, _) = both::<64>(ApiMode::Escaped, &stream);
    assert_eq!(
        events[0],
        Owned::Error(DecodeError::Truncated {
            length: None,
            received: 0
        })
    );
}

#[test]
fn truncated_at_end_of_input() {
    for mode in [ApiMode::Unescaped, ApiMode::Escaped] {
        let stream = hex(&format!("{MODEM} 7E 00 05 8A 06"));
        let (events, stats) = both::<64>(mode, &stream);
        assert_eq!(
            events,
            [
                Owned::Frame(vec![0x8A, 0x06]),
                Owned::Error(DecodeError::Truncated {
                    length: Some(5),
                    received: 2
                })
            ]
        );
        assert_eq!((stats.truncated, stats.frames_ok), (1, 1));
    }
}

#[test]
fn mode2_bad_escapes() {
    // 7D followed by a byte that is not an escaped special byte.
    let stream = hex(&format!("7E 00 02 8A 7D 06 6F {MODEM}"));
    let (events, stats) = both::<64>(ApiMode::Escaped, &stream);
    assert_eq!(
        events[0],
        Owned::Error(DecodeError::BadEscape {
            byte: 0x06,
            received: 1
        })
    );
    assert_eq!(events[1..], [Owned::Frame(vec![0x8A, 0x06])]);
    assert_eq!(stats.bad_escape, 1);
    // The bytes after the bad escape up to the next 0x7E are skipped.
    assert_eq!(stats.bytes_skipped, 1);
    // 7D followed by a raw 7E: reported as a bad escape, and the 7E starts a frame.
    let stream = hex(&format!("7E 00 02 8A 7D {MODEM}"));
    let (events, stats) = both::<64>(ApiMode::Escaped, &stream);
    assert_eq!(
        events,
        [
            Owned::Error(DecodeError::BadEscape {
                byte: 0x7E,
                received: 1
            }),
            Owned::Frame(vec![0x8A, 0x06])
        ]
    );
    assert_eq!((stats.bad_escape, stats.truncated), (1, 0));
}

#[test]
fn skipped_bytes_are_counted() {
    for mode in [ApiMode::Unescaped, ApiMode::Escaped] {
        let stream = hex(&format!("00 01 02 {MODEM} 55 {MODEM} AA BB"));
        let (events, stats) = both::<64>(mode, &stream);
        assert_eq!(frames(&events).len(), 2);
        assert_eq!(stats.bytes_skipped, 6);
        assert_eq!(stats.errors(), 0);
    }
}

#[test]
fn mode1_rescan_finds_frames_inside_a_failed_candidate() {
    // A bogus 0x7E with length 0x0010 swallows two valid frames; its checksum fails,
    // and the rescan from the byte after it finds both.
    let stream = hex(&format!("7E 00 10 {MODEM} {MODEM} 01 02 03 04 05"));
    let (events, stats) = both::<64>(ApiMode::Unescaped, &stream);
    assert!(matches!(
        events[0],
        Owned::Error(DecodeError::BadChecksum { .. })
    ));
    assert_eq!(frames(&events), vec![vec![0x8A, 0x06]; 2]);
    assert_eq!(stats.frames_ok, 2);
    // Bogus candidate cut by the end of input: its frames come out of `finish`.
    let stream = hex(&format!("7E 01 00 {MODEM} {MODEM}"));
    let (events, stats) = both::<512>(ApiMode::Unescaped, &stream);
    assert_eq!(
        events[0],
        Owned::Error(DecodeError::Truncated {
            length: Some(0x100),
            received: 12
        })
    );
    assert_eq!(frames(&events).len(), 2);
    assert_eq!((stats.truncated, stats.frames_ok), (1, 2));
    // An oversize length in garbage does not hide the frame behind it.
    let stream = hex(&format!("7E FF FF {MODEM}"));
    let (events, _) = both::<64>(ApiMode::Unescaped, &stream);
    assert_eq!(frames(&events).len(), 1);
}

#[test]
fn mode1_push_without_poll_queues_the_byte() {
    let stream = hex(&format!("7E 00 08 {MODEM} 00 {MODEM}"));
    let mut decoder: Decoder<64> = Decoder::new(ApiMode::Unescaped);
    let mut frames = 0;
    for &b in &stream {
        // Deliberately never calls `poll`.
        if let Some(Ok(_)) = decoder.push(b) {
            frames += 1;
        }
    }
    while let Some(event) = decoder.finish() {
        frames += usize::from(event.is_ok());
    }
    assert_eq!(frames, 2);
}

#[test]
fn mode2_every_frame_id_and_special_lengths() {
    for id in 0..=255u8 {
        let request = TransmitRequestRepr {
            frame_id: id,
            dst64: Address64(0x0013_A200_7D7E_1113),
            dst16: Address16(0x117E),
            radius: 0x13,
            options: 0x7D,
            data: &[0x7E, 0x7D, 0x11, 0x13, id],
        };
        let wire = encode(&request, ApiMode::Escaped);
        assert!(wire[1..].iter().all(|&b| b != 0x7E), "raw 0x7E after start");
        let (events, stats) = both::<64>(ApiMode::Escaped, &wire);
        assert_eq!(stats.errors(), 0);
        let [Owned::Frame(data)] = &events[..] else {
            panic!("{events:?}")
        };
        assert_eq!(
            Frame::parse_bytes(data).unwrap(),
            Frame::TransmitRequest(request)
        );
    }
    for len in [0x11usize, 0x13, 0x7D, 0x7E] {
        let data: Vec<u8> = (0..len).map(|i| i as u8).collect();
        let raw = RawFrame::new(&data).unwrap();
        let wire = encode(&raw, ApiMode::Escaped);
        assert_eq!(&wire[..4], &[0x7E, 0x00, 0x7D, len as u8 ^ 0x20]);
        let (events, stats) = both::<512>(ApiMode::Escaped, &wire);
        assert_eq!(events, [Owned::Frame(data.clone())]);
        assert_eq!(stats.errors(), 0);
    }
}

#[test]
fn reset_drops_partial_frame() {
    let mut decoder: Decoder = Decoder::new(ApiMode::Escaped);
    assert!(decoder.decode(&hex("7E 00 02 8A")).1.is_none());
    assert!(!decoder.is_idle());
    decoder.reset();
    assert!(decoder.is_idle());
    let (_, event) = decoder.decode(&hex(MODEM));
    assert_eq!(event.unwrap().unwrap().data(), &[0x8A, 0x06]);
}

#[test]
fn reset_after_an_escape_byte_leaves_nothing_of_it() {
    // Mode 2, cut off just after an escape byte: the next frame owes it nothing.
    let mut decoder: Decoder = Decoder::new(ApiMode::Escaped);
    for byte in hex("7E 00 02 8A 7D") {
        assert!(decoder.push(byte).is_none());
    }
    decoder.reset();
    assert!(decoder.is_idle(), "an escape pending after reset");
    let (_, event) = decoder.decode(&hex(MODEM));
    assert_eq!(event.unwrap().unwrap().data(), &[0x8A, 0x06]);
    assert_eq!(decoder.stats().errors(), 0);
}

#[test]
fn bytes_after_a_reset_inside_a_frame_are_skipped_until_a_start_delimiter() {
    // Mode 2, reset part way through a frame's data: what follows, up to the next 0x7E,
    // belongs to no frame and is counted as skipped, whichever way it is fed.
    for by_byte in [false, true] {
        let mut decoder: Decoder = Decoder::new(ApiMode::Escaped);
        let start = hex("7E 00 10 90 00 13");
        let rest = [0x41, 0x42, 0x43, 0x44, 0x45];
        if by_byte {
            start
                .iter()
                .for_each(|&byte| assert!(decoder.push(byte).is_none()));
        } else {
            assert!(decoder.decode(&start).1.is_none());
        }
        decoder.reset();
        let skipped = decoder.stats().bytes_skipped;
        if by_byte {
            rest.iter()
                .for_each(|&byte| assert!(decoder.push(byte).is_none()));
        } else {
            assert_eq!(decoder.decode(&rest), (rest.len(), None));
        }
        assert_eq!(
            decoder.stats().bytes_skipped - skipped,
            5,
            "by byte: {by_byte}"
        );
        assert!(decoder.is_idle());
        let (_, event) = decoder.decode(&hex(MODEM));
        assert_eq!(event.unwrap().unwrap().data(), &[0x8A, 0x06]);
    }
}

#[test]
fn decoder_ram_is_buffer_plus_a_few_words() {
    let overhead = std::mem::size_of::<Decoder>() - xbee_api::DEFAULT_CAPACITY;
    println!("size_of::<Decoder>() = {}", std::mem::size_of::<Decoder>());
    assert!(overhead <= 80, "overhead {overhead}");
}

#[test]
fn mode_1_a_read_that_starts_with_a_whole_frame_inside_a_frame() {
    // Mode 1 counts a frame's bytes: a read that starts with what looks like a whole
    // frame while a frame is in progress continues that frame (which then fails its
    // checksum and is scanned again); it is not a frame of its own at once.
    let inner = hex(MODEM);
    let data = [0x55; 40];
    let mut outer = vec![0x7E, 0x00, data.len() as u8];
    outer.extend(data);
    outer.push(xbee_api::wire::checksum(&data));
    for k in [1, 3, 10, 30] {
        // `inner` in place of the outer frame's bytes from `k` on.
        let mut stream = outer.clone();
        stream[k..k + inner.len()].copy_from_slice(&inner);
        let expected = decode_bytes::<128>(ApiMode::Unescaped, &stream);
        assert!(
            matches!(expected.0.first(), Some(Owned::Error(_))),
            "{:?}",
            expected.0
        );
        let decoder: Decoder<128> = Decoder::new(ApiMode::Unescaped);
        let got = common::decode_each_slices_with(decoder, &stream, &[k, 1 << 20]);
        assert_eq!(got, expected, "read from {k}");
    }
}

/// What `decode_each`'s docs promise an inbox: in one call, at most one frame for every
/// 5 bytes and one more, while errors can come as often as one a byte.
#[test]
fn decode_each_completes_a_frame_per_5_bytes_at_most_and_an_error_per_byte() {
    let minimal = hex(MODEM).repeat(20);
    for mode in [ApiMode::Unescaped, ApiMode::Escaped] {
        for (stream, least_errors) in [
            (minimal.clone(), 0),
            // Empty frames and oversize lengths fail 3 bytes in.
            (hex("7E 00 00").repeat(40), 40),
            (hex("7E FF 00").repeat(40), 40),
            // A run of delimiters: each one starts a candidate that fails.
            (vec![0x7E; 120], 100),
        ] {
            let mut decoder: Decoder<64> = Decoder::new(mode);
            let (mut frames, mut errors) = (0, 0);
            decoder.decode_each(&stream, |event| match event {
                Ok(_) => frames += 1,
                Err(_) => errors += 1,
            });
            assert!(frames <= stream.len() / 5 + 1, "{mode:?} {stream:02X?}");
            assert!(errors <= stream.len(), "{mode:?} {stream:02X?}");
            assert!(
                errors >= least_errors,
                "{mode:?}: {errors} errors {stream:02X?}"
            );
            if least_errors == 0 {
                assert_eq!(frames, 20);
            }
        }
    }
}
