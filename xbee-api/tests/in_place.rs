//! A frame built in its own buffer (`InPlaceFrame`) is byte for byte the frame its
//! header and payload encode to, in both modes and whatever bytes need escaping; a
//! buffer too small for it is an error that says what it needs.

use proptest::prelude::*;
use xbee_api::{
    Address16, Address64, ApiMode, EncodeError, EncodeFrame, ExplicitAddressingCommandRepr,
    InPlaceFrame, TransmitRequestRepr,
};

fn mode() -> impl Strategy<Value = ApiMode> {
    prop_oneof![Just(ApiMode::Unescaped), Just(ApiMode::Escaped)]
}

/// Bytes drawn often from those that mode 2 escapes.
fn bytes(max: usize) -> impl Strategy<Value = Vec<u8>> {
    proptest::collection::vec(
        prop_oneof![
            3 => any::<u8>(),
            1 => prop_oneof![Just(0x7Eu8), Just(0x7D), Just(0x11), Just(0x13)],
        ],
        0..=max,
    )
}

/// Builds `header` with `payload` in `buffer` (as much of the payload as it holds).
fn build<'b, F: EncodeFrame>(
    buffer: &'b mut [u8],
    header: &F,
    payload: &[u8],
    mode: ApiMode,
) -> Result<&'b [u8], EncodeError> {
    let mut frame = InPlaceFrame::new(buffer, header)?;
    let room = frame.data_mut();
    let n = payload.len().min(room.len());
    room[..n].copy_from_slice(&payload[..n]);
    frame.finish(payload.len(), mode)
}

/// What `frame` encodes to in `mode`.
fn encoded(frame: &impl EncodeFrame, mode: ApiMode) -> Vec<u8> {
    let mut wire = vec![0; frame.encoded_len(mode)];
    frame.encode(mode, &mut wire).unwrap();
    wire
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn a_transmit_request_built_in_place_is_the_one_encoded(
        payload in bytes(120),
        request_bits in (any::<u8>(), any::<u64>(), any::<u16>(), any::<u8>(), any::<u8>()),
        mode in mode(),
        slack in 0usize..8,
    ) {
        let (frame_id, dst64, dst16, radius, options) = request_bits;
        let full = TransmitRequestRepr {
            frame_id,
            dst64: Address64(dst64),
            dst16: Address16(dst16),
            radius,
            options,
            data: &payload,
        };
        let header = TransmitRequestRepr { data: &[], ..full };
        let expected = encoded(&full, mode);

        // Exactly the room it takes, and more.
        let mut buffer = vec![0; expected.len() + slack];
        prop_assert_eq!(build(&mut buffer, &header, &payload, mode), Ok(&expected[..]));

        // One byte less: what it needs, said exactly.
        let mut short = vec![0; expected.len() - 1];
        prop_assert_eq!(
            build(&mut short, &header, &payload, mode),
            Err(EncodeError::BufferTooSmall { needed: expected.len(), available: expected.len() - 1 })
        );
    }

    #[test]
    fn any_header_and_payload_built_in_place_are_the_frame_encoded(
        payload in bytes(60),
        header_data in bytes(20),
        frame_type in any::<u8>(),
        mode in mode(),
    ) {
        // An Explicit Addressing Command, and a raw frame whose header is anything.
        let full = ExplicitAddressingCommandRepr {
            frame_id: frame_type,
            dst64: Address64(0x0013_A200_4052_2BAA),
            dst16: Address16::UNKNOWN,
            src_endpoint: 0xE8,
            dst_endpoint: 0xE8,
            cluster_id: 0x0011,
            profile_id: 0xC105,
            radius: 0,
            options: 0,
            data: &payload,
        };
        let header = ExplicitAddressingCommandRepr { data: &[], ..full };
        let expected = encoded(&full, mode);
        let mut buffer = vec![0; expected.len()];
        prop_assert_eq!(build(&mut buffer, &header, &payload, mode), Ok(&expected[..]));

        let mut raw = vec![frame_type];
        raw.extend(&header_data);
        let head = xbee_api::RawFrame::new(&raw).unwrap();
        let mut whole = raw.clone();
        whole.extend(&payload);
        let expected = encoded(&xbee_api::RawFrame::new(&whole).unwrap(), mode);
        let mut buffer = vec![0; expected.len()];
        prop_assert_eq!(build(&mut buffer, &head, &payload, mode), Ok(&expected[..]));
    }
}

#[test]
fn a_buffer_too_small_for_the_header_or_the_payload_says_so() {
    let header = TransmitRequestRepr::unicast(Address64::COORDINATOR, &[]);
    // Delimiter, length, the 14-byte header and the checksum: 18 bytes at least.
    let mut buffer = [0u8; 17];
    assert_eq!(
        InPlaceFrame::new(&mut buffer, &header).err(),
        Some(EncodeError::BufferTooSmall {
            needed: 18,
            available: 17
        })
    );
    let mut buffer = [0u8; 20];
    let mut frame = InPlaceFrame::new(&mut buffer, &header).unwrap();
    assert_eq!(frame.data_mut().len(), 2);
    // A payload said to be longer than the buffer: the frame it makes unescaped.
    assert_eq!(
        frame.finish(5, ApiMode::Escaped),
        Err(EncodeError::BufferTooSmall {
            needed: 23,
            available: 20
        })
    );
}

#[test]
fn the_deployed_mavs_frame_to_the_coordinator_comes_out_escaped() {
    // A message `m` + XON to the coordinator, mode 2: the payload's 0x11 and the
    // checksum are escaped where they lie.
    let header = TransmitRequestRepr::unicast(Address64::COORDINATOR, &[]);
    let mut buffer = [0u8; 64];
    let mut frame = InPlaceFrame::new(&mut buffer, &header).unwrap();
    frame.data_mut()[..2].copy_from_slice(&[b'm', 0x11]);
    let wire = frame.finish(2, ApiMode::Escaped).unwrap();
    let request = TransmitRequestRepr::unicast(Address64::COORDINATOR, &[b'm', 0x11]);
    assert_eq!(wire, &encoded(&request, ApiMode::Escaped)[..]);
    assert!(wire.windows(2).any(|w| w == [0x7D, 0x31]));
}

#[test]
fn a_payload_length_past_what_a_frame_carries_is_too_long_not_a_wrapped_frame() {
    let header = TransmitRequestRepr::unicast(Address64::COORDINATOR, &[]);
    for (data_len, len) in [
        (usize::MAX, usize::MAX),
        (usize::MAX - 13, usize::MAX),
        (0xFFFF - 13, 0xFFFF + 1),
    ] {
        for mode in [ApiMode::Unescaped, ApiMode::Escaped] {
            let mut buffer = [0u8; 64];
            let frame = InPlaceFrame::new(&mut buffer, &header).unwrap();
            assert_eq!(
                frame.finish(data_len, mode),
                Err(EncodeError::FrameTooLong { len }),
                "{data_len}"
            );
        }
    }
}

#[test]
fn a_frame_that_does_not_fit_escaped_is_left_unescaped_in_the_buffer() {
    // Every payload byte needs escaping: 3 more bytes than the frame unescaped.
    let header = TransmitRequestRepr::unicast(Address64::COORDINATOR, &[]);
    let payload = [0x7E, 0x7D, 0x11];
    let request = TransmitRequestRepr::unicast(Address64::COORDINATOR, &payload);
    let plain = encoded(&request, ApiMode::Unescaped);
    let escaped = encoded(&request, ApiMode::Escaped);
    let mut buffer = vec![0u8; plain.len() + 1];
    let mut frame = InPlaceFrame::new(&mut buffer, &header).unwrap();
    frame.data_mut()[..3].copy_from_slice(&payload);
    assert_eq!(
        frame.finish(3, ApiMode::Escaped),
        Err(EncodeError::BufferTooSmall {
            needed: escaped.len(),
            available: plain.len() + 1
        })
    );
    assert_eq!(buffer[..plain.len()], plain[..]);
}

/// A header that writes fewer bytes than it announces.
struct Liar;

impl EncodeFrame for Liar {
    fn frame_data_len(&self) -> usize {
        4
    }
    fn write_frame_data<F: FnMut(&[u8])>(&self, out: &mut F) {
        out(&[0x10, 0x01]);
    }
}

#[test]
fn a_header_that_writes_other_than_it_announces_is_an_error() {
    let mut buffer = [0u8; 32];
    assert_eq!(
        InPlaceFrame::new(&mut buffer, &Liar).err(),
        Some(EncodeError::LengthMismatch {
            announced: 4,
            written: 2
        })
    );
}

proptest! {
    /// A payload that fills what `data_mut_for` gives, whatever its bytes, fits once
    /// framed in that mode; in a buffer sized by `max_encoded_len`, that room is the
    /// payload the buffer was sized for.
    #[test]
    fn the_room_for_a_mode_always_fits(
        mode in mode(),
        payload_max in 0usize..120,
        slack in 0usize..9,
        bytes in bytes(200),
    ) {
        let header = TransmitRequestRepr::unicast(Address64::COORDINATOR, &[]);
        let size = xbee_api::max_encoded_len(TransmitRequestRepr::HEADER_LEN + payload_max, mode);
        let mut buffer = vec![0u8; size + slack];
        let mut frame = InPlaceFrame::new(&mut buffer, &header).unwrap();
        let room = frame.data_mut_for(mode);
        prop_assert!(room.len() >= payload_max);
        let n = room.len().min(bytes.len());
        room[..n].copy_from_slice(&bytes[..n]);
        // Where `bytes` ran short, bytes that all need escaping.
        room[n..].fill(0x7E);
        let len = room.len();
        prop_assert!(frame.finish(len, mode).is_ok());
        if slack == 0 {
            let mut exact = vec![0u8; size];
            let mut frame = InPlaceFrame::new(&mut exact, &header).unwrap();
            prop_assert_eq!(frame.data_mut_for(mode).len(), payload_max);
        }
    }
}
