//! Status codes carried by response frames, each an enum with an `Unknown` arm so that
//! every byte converts both ways without loss, a stable snake_case name and a `Display`
//! that prints it.

macro_rules! code_enum {
    (
        $(#[$meta:meta])*
        pub enum $name:ident {
            $( $(#[$vmeta:meta])* $variant:ident = $value:expr => $vname:literal, )+
            $(
                ;
                $(#[$rmeta:meta])*
                $range:ident($lo:literal..=$hi:literal) => $rname:literal,
            )?
        }
    ) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
        #[cfg_attr(feature = "defmt", derive(defmt::Format))]
        pub enum $name {
            $( $(#[$vmeta])* $variant, )+
            $( $(#[$rmeta])* $range(u8), )?
            /// A code this crate does not name, kept as received.
            Unknown(u8),
        }

        impl From<u8> for $name {
            fn from(code: u8) -> Self {
                match code {
                    $( $value => Self::$variant, )+
                    $( $lo..=$hi => Self::$range(code), )?
                    other => Self::Unknown(other),
                }
            }
        }

        impl From<$name> for u8 {
            fn from(status: $name) -> u8 {
                match status {
                    $( $name::$variant => $value, )+
                    $( $name::$range(code) => code, )?
                    $name::Unknown(other) => other,
                }
            }
        }

        impl $name {
            /// The status's stable snake_case name (the variant's name), for logs and
            /// machine-readable output beside the code; `None` for a code this crate
            /// does not name.
            pub const fn name(&self) -> Option<&'static str> {
                match self {
                    $( Self::$variant => Some($vname), )+
                    $( Self::$range(_) => Some($rname), )?
                    Self::Unknown(_) => None,
                }
            }
        }

        /// The [`name`](Self::name), with the code after a name that stands for a range
        /// of codes (`name(0xNN)`), or `unknown(0xNN)` for a code this crate does not
        /// name.
        impl core::fmt::Display for $name {
            fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
                match (self, self.name()) {
                    $( (Self::$range(code), Some(name)) => write!(f, "{name}(0x{code:02X})"), )?
                    (_, Some(name)) => f.write_str(name),
                    (_, None) => write!(f, "unknown(0x{:02X})", u8::from(*self)),
                }
            }
        }
    };
}

mod at;
mod delivery;
mod discovery;
mod modem;

pub use at::AtStatus;
pub use delivery::DeliveryStatus;
pub use discovery::DiscoveryStatus;
pub use modem::ModemStatus;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_code_round_trips() {
        for code in 0..=255u8 {
            assert_eq!(u8::from(AtStatus::from(code)), code);
            assert_eq!(u8::from(DeliveryStatus::from(code)), code);
            assert_eq!(u8::from(DiscoveryStatus::from(code)), code);
            assert_eq!(u8::from(ModemStatus::from(code)), code);
        }
    }

    #[test]
    fn named_codes() {
        assert_eq!(DeliveryStatus::from(0x00), DeliveryStatus::Success);
        assert_eq!(
            DeliveryStatus::from(0x21),
            DeliveryStatus::NetworkAckFailure
        );
        assert_eq!(DeliveryStatus::from(0x24), DeliveryStatus::AddressNotFound);
        assert_eq!(
            DeliveryStatus::from(0x75),
            DeliveryStatus::IndirectMessageUnrequested
        );
        assert_eq!(DeliveryStatus::from(0x99), DeliveryStatus::Unknown(0x99));
        assert_eq!(
            DiscoveryStatus::from(0x40),
            DiscoveryStatus::ExtendedTimeoutDiscovery
        );
        assert_eq!(DiscoveryStatus::from(0x04), DiscoveryStatus::Unknown(0x04));
        assert_eq!(AtStatus::from(3), AtStatus::InvalidParameter);
        assert_eq!(ModemStatus::from(0x06), ModemStatus::CoordinatorStarted);
        // The modem status table's 0x34, not the delivery status table's.
        assert_eq!(
            ModemStatus::from(0x34).name(),
            Some("bandmask_configuration_failed")
        );
        assert_eq!(DeliveryStatus::from(0x34).name(), Some("no_secure_session"));
        assert_eq!(ModemStatus::from(0x80), ModemStatus::StackError(0x80));
        assert_eq!(ModemStatus::from(0x7F), ModemStatus::Unknown(0x7F));
        assert!(DeliveryStatus::Success.is_success());
        assert!(!DeliveryStatus::MacAckFailure.is_success());
        assert!(AtStatus::Ok.is_ok());
    }

    #[test]
    fn at_status_means_its_low_four_bits() {
        for code in 0..=255u8 {
            let status = AtStatus::from(code);
            let low = AtStatus::from(code & 0x0F);
            let expected = if matches!(low, AtStatus::Unknown(_)) {
                status
            } else {
                low
            };
            assert_eq!(status.meaning(), expected, "0x{code:02X}");
            assert_eq!(status.is_ok(), code & 0x0F == 0, "0x{code:02X}");
            // The code itself is kept.
            assert_eq!(u8::from(status), code);
        }
    }
}
