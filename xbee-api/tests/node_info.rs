//! Node discovery answers: what `emit` writes `parse` reads back, and any bytes parse
//! to an answer that writes them back, or to an error, never a panic.

use proptest::prelude::*;
use xbee_api::{Address16, Address64, DeviceType, NodeInfo};

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
