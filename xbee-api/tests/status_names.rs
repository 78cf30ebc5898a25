//! Status names: every named code's name is its variant's name in snake_case, names are
//! unique, and `Display` prints the name, `name(0xNN)` for a range of codes, or
//! `unknown(0xNN)`.

use std::collections::HashMap;
use std::fmt::{Debug, Display};

use xbee_api::{AtStatus, DeliveryStatus, DeviceType, DiscoveryStatus, ModemStatus, SourceEvent};

/// `Debug` of a named variant in snake_case, without the code of a range arm.
fn snake_case_of_debug(status: &dyn Debug) -> String {
    let debug = format!("{status:?}");
    let variant = debug.split('(').next().unwrap_or_default();
    let mut out = String::new();
    for (i, c) in variant.chars().enumerate() {
        if c.is_ascii_uppercase() && i > 0 {
            out.push('_');
        }
        out.push(c.to_ascii_lowercase());
    }
    out
}

/// For every code: the name is the variant's name in snake_case (`None` only for
/// `Unknown`), names are unique, and `Display` prints the name or `unknown(0xNN)`.
fn check_names<T>(status: impl Fn(u8) -> T)
where
    T: Debug + Display + Copy,
    T: Into<u8>,
    T: Named,
{
    let mut seen = HashMap::new();
    for code in 0..=255u8 {
        let s = status(code);
        let shown = s.to_string();
        match s.name() {
            None => {
                assert!(format!("{s:?}").starts_with("Unknown("), "{s:?}");
                assert_eq!(shown, format!("unknown(0x{code:02X})"));
            }
            Some(name) => {
                assert_eq!(name, snake_case_of_debug(&s), "{s:?}");
                assert!(
                    name.bytes()
                        .all(|b| b.is_ascii_lowercase() || b.is_ascii_digit() || b == b'_')
                );
                assert!(
                    shown == name || shown == format!("{name}(0x{code:02X})"),
                    "{shown}"
                );
                if shown == name {
                    assert_eq!(seen.insert(name, code), None, "{name} twice");
                }
            }
        }
    }
}

trait Named {
    fn name(&self) -> Option<&'static str>;
}

macro_rules! named {
    ($($t:ty),*) => {
        $(impl Named for $t {
            fn name(&self) -> Option<&'static str> {
                <$t>::name(self)
            }
        })*
    };
}
named!(
    AtStatus,
    DeliveryStatus,
    DiscoveryStatus,
    ModemStatus,
    DeviceType,
    SourceEvent
);

#[test]
fn names_are_snake_case_variant_names_and_display_them() {
    check_names(AtStatus::from);
    check_names(DeliveryStatus::from);
    check_names(DiscoveryStatus::from);
    check_names(ModemStatus::from);
    check_names(DeviceType::from);
    check_names(SourceEvent::from);
}

#[test]
fn names_of_common_codes() {
    assert_eq!(DeliveryStatus::from(0x00).name(), Some("success"));
    assert_eq!(DeliveryStatus::from(0x01).name(), Some("mac_ack_failure"));
    assert_eq!(DeliveryStatus::from(0x25).name(), Some("route_not_found"));
    assert_eq!(
        DiscoveryStatus::from(0x01).name(),
        Some("address_discovery")
    );
    assert_eq!(AtStatus::from(0x00).name(), Some("ok"));
    assert_eq!(AtStatus::from(0x03).name(), Some("invalid_parameter"));
    assert_eq!(ModemStatus::from(0x00).name(), Some("hardware_reset"));
    assert_eq!(ModemStatus::from(0x02).name(), Some("joined_network"));
    assert_eq!(ModemStatus::from(0x80).name(), Some("stack_error"));
    assert_eq!(ModemStatus::from(0x80).to_string(), "stack_error(0x80)");
    assert_eq!(DeliveryStatus::from(0x99).to_string(), "unknown(0x99)");
    assert_eq!(DiscoveryStatus::from(0x04).to_string(), "unknown(0x04)");
    assert_eq!(AtStatus::from(0x05).name(), None);
    assert_eq!(ModemStatus::from(0x7F).to_string(), "unknown(0x7F)");
}

/// Some firmware answers an AT command with upper bits set in the status byte (0x40 for
/// an OK); Digi's XCTU and xbee-python read only the low four bits, and so does
/// `AtStatus::is_ok`. The byte itself is kept.
#[test]
fn an_at_status_with_upper_bits_set_is_read_by_its_low_four_bits() {
    use xbee_api::{ApiMode, Decoder, Frame};
    let wire = [0x7E, 0x00, 0x05, 0x88, 0x01, 0x42, 0x44, 0x40, 0xB0];
    let mut decoder: Decoder = Decoder::new(ApiMode::Unescaped);
    let (_, event) = decoder.decode(&wire);
    let frame = event.expect("a frame").expect("a valid frame");
    let Ok(Frame::AtCommandResponse(at)) = Frame::parse(frame) else {
        panic!("not an AT Command Response: {frame:?}");
    };
    assert_eq!(at.command, *b"BD");
    assert_eq!(at.status, AtStatus::Unknown(0x40));
    assert!(at.status.is_ok());
    assert_eq!(at.status.meaning(), AtStatus::Ok);
    assert_eq!(AtStatus::from(0x44).meaning(), AtStatus::TxFailure);
    assert_eq!(AtStatus::from(0x4B).meaning(), AtStatus::NoSecureSession);
    assert_eq!(AtStatus::from(0x4E).meaning(), AtStatus::Unknown(0x4E));
}
