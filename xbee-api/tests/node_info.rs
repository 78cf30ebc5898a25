//! Node discovery answers: one read off the wire in both API modes, field by field;
//! what `emit` writes `parse` reads back, and any bytes parse to an answer that writes
//! them back, or to an error, never a panic.

use proptest::prelude::*;
use xbee_api::{Address16, Address64, ApiMode, Decoder, DeviceType, Frame, NodeInfo};

/// An AT Command Response to `ND` (frame id 1, ok) carrying the answer of router
/// 0013A20040B599B9 (7D84) named "MAV 1", with the device type identifier and RSSI that
/// a radio whose `NO` asks for them adds, as API frames in mode 1 and mode 2 (where the
/// 0x13 of its address and the 0x7D of its 16-bit address are escaped).
const ND_MODE1: &str = "7E 00 22 88 01 4E 44 00 7D 84 00 13 A2 00 40 B5 99 B9 \
                        4D 41 56 20 31 00 FF FE 01 00 C1 05 10 1E 00 0B 00 00 28 8D";
const ND_MODE2: &str = "7E 00 22 88 01 4E 44 00 7D 5D 84 00 7D 33 A2 00 40 B5 99 B9 \
                        4D 41 56 20 31 00 FF FE 01 00 C1 05 10 1E 00 0B 00 00 28 8D";

fn bytes(hex: &str) -> Vec<u8> {
    hex.split_whitespace()
        .map(|b| u8::from_str_radix(b, 16).unwrap())
        .collect()
}

#[test]
fn a_node_discovery_answer_reads_off_the_wire_in_both_modes() {
    for (mode, wire) in [(ApiMode::Unescaped, ND_MODE1), (ApiMode::Escaped, ND_MODE2)] {
        let mut decoder: Decoder = Decoder::new(mode);
        let mut answers = Vec::new();
        decoder.decode_each(&bytes(wire), |event| {
            let frame = event.unwrap();
            let Ok(Frame::AtCommandResponse(at)) = Frame::parse(frame) else {
                panic!("not an AT Command Response: {frame:?}");
            };
            assert_eq!((at.frame_id, at.command), (1, *b"ND"));
            assert!(at.status.is_ok());
            let node = NodeInfo::parse(at.data).unwrap();
            let mut written = vec![0u8; node.len()];
            node.emit(&mut written).unwrap();
            assert_eq!(written, at.data);
            answers.push((
                node.addr16,
                node.addr64,
                node.identifier.to_vec(),
                node.parent,
                node.device_type,
                (node.profile_id, node.manufacturer_id),
                node.device_type_identifier,
                node.rssi,
            ));
        });
        assert_eq!(
            answers,
            [(
                Address16(0x7D84),
                Address64(0x0013_A200_40B5_99B9),
                b"MAV 1".to_vec(),
                Address16::UNKNOWN,
                DeviceType::Router,
                (0xC105, 0x101E),
                Some(0x000B_0000),
                Some(0x28),
            )],
            "{mode:?}"
        );
    }
}

proptest! {
    #[test]
    fn emit_then_parse_is_identity(
        (my, serial, parent, device_type, status) in any::<(u16, u64, u16, u8, u8)>(),
        (profile, manufacturer, dd, rssi) in any::<(u16, u16, Option<u32>, Option<u8>)>(),
        ni in proptest::collection::vec(1u8..=255, 0..24),
    ) {
        let node = NodeInfo {
            addr16: Address16(my),
            addr64: Address64(serial),
            identifier: &ni,
            parent: Address16(parent),
            device_type: DeviceType::from(device_type),
            status,
            profile_id: profile,
            manufacturer_id: manufacturer,
            device_type_identifier: dd,
            rssi,
        };
        let mut buf = [0u8; 64];
        let n = node.emit(&mut buf).unwrap();
        prop_assert_eq!(n, node.len());
        prop_assert_eq!(NodeInfo::parse(&buf[..n]), Ok(node));
    }

    #[test]
    fn any_bytes_parse_to_what_they_say_or_an_error(data in proptest::collection::vec(any::<u8>(), 0..48)) {
        if let Ok(node) = NodeInfo::parse(&data) {
            let mut buf = [0u8; 64];
            let n = node.emit(&mut buf).unwrap();
            prop_assert_eq!(&buf[..n], &data[..]);
        }
    }
}
