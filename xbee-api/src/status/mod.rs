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
        ///
        /// Equality and hashing follow the code (the byte), not the variant: a value
        /// built by hand with a code its variant does not stand for (an `Unknown` of a
        /// code this crate names) equals the variant the code parses to, and its
        /// [`name`](Self::name) and `Display` are that variant's. A `match` on the
        /// variants does not see through it, so build values with `From<u8>`, which
        /// never yields one.
        #[derive(Debug, Clone, Copy)]
        #[cfg_attr(feature = "defmt", derive(defmt::Format))]
        pub enum $name {
            $( $(#[$vmeta])* $variant, )+
            $( $(#[$rmeta])* $range(u8), )?
            /// A code this crate does not name, kept as received. Parsing (`From<u8>`)
            /// turns a code this crate names into its named variant, never into
            /// `Unknown`; an `Unknown` built by hand with such a code equals that
            /// variant, encodes as its code and parses back as the named variant.
            Unknown(u8),
        }

        impl $name {
            /// The status of a code (`From<u8>`, in a `const` context).
            #[inline]
            pub const fn from_u8(code: u8) -> Self {
                match code {
                    $( $value => Self::$variant, )+
                    $( $lo..=$hi => Self::$range(code), )?
                    other => Self::Unknown(other),
                }
            }

            /// The code (`From<Self> for u8`, in a `const` context).
            #[inline]
            pub const fn to_u8(self) -> u8 {
                match self {
                    $( Self::$variant => $value, )+
                    $( Self::$range(code) => code, )?
                    Self::Unknown(other) => other,
                }
            }

            /// The variant `From<u8>` gives for this status's code: the named variant
            /// for a hand-built `Unknown` of a named code, else the status itself.
            #[inline]
            const fn normalized(self) -> Self {
                Self::from_u8(self.to_u8())
            }
        }

        impl From<u8> for $name {
            #[inline]
            fn from(code: u8) -> Self {
                Self::from_u8(code)
            }
        }

        impl From<$name> for u8 {
            #[inline]
            fn from(status: $name) -> u8 {
                status.to_u8()
            }
        }

        impl PartialEq for $name {
            #[inline]
            fn eq(&self, other: &Self) -> bool {
                self.to_u8() == other.to_u8()
            }
        }

        impl Eq for $name {}

        impl core::hash::Hash for $name {
            fn hash<H: core::hash::Hasher>(&self, state: &mut H) {
                self.to_u8().hash(state)
            }
        }

        impl $name {
            /// The status's stable snake_case name (the name of the variant its code
            /// parses to), for logs and machine-readable output beside the code; `None`
            /// for a code this crate does not name.
            pub const fn name(&self) -> Option<&'static str> {
                match self.normalized() {
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
                match (self.normalized(), self.name()) {
                    $( (Self::$range(code), Some(name)) => write!(f, "{name}(0x{code:02X})"), )?
                    (_, Some(name)) => f.write_str(name),
                    (_, None) => write!(f, "unknown(0x{:02X})", self.to_u8()),
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

    extern crate std;
    use std::hash::{BuildHasher, RandomState};
    use std::string::ToString;

    use crate::DeviceType;

    fn hash_of<T: core::hash::Hash>(value: &T) -> u64 {
        // One fixed state for every call, so that equal values hash equal.
        static STATE: std::sync::OnceLock<RandomState> = std::sync::OnceLock::new();
        STATE.get_or_init(RandomState::new).hash_one(value)
    }

    /// Every status enum compares, hashes, names and prints by its code: a hand-built
    /// `Unknown` (or range variant) of a code is the same value as what the code
    /// parses to, and round-trips through the byte to it.
    macro_rules! check_by_code {
        ($name:ident, $build:expr) => {
            for code in 0..=255u8 {
                let parsed = $name::from(code);
                let built: $name = $build(code);
                assert_eq!(built, parsed, "{} 0x{code:02X}", stringify!($name));
                assert_eq!(hash_of(&built), hash_of(&parsed));
                assert_eq!(built.name(), parsed.name());
                assert_eq!(built.to_string(), parsed.to_string());
                assert_eq!($name::from(u8::from(built)), parsed);
                assert_eq!(u8::from(built), code);
                assert_eq!($name::from_u8(code).to_u8(), code);
                // Statuses of different codes differ.
                assert_ne!(built, $name::from(code.wrapping_add(1)));
            }
        };
    }

    #[test]
    fn statuses_compare_by_code() {
        assert_eq!(DeliveryStatus::Unknown(0x00), DeliveryStatus::Success);
        assert_eq!(
            hash_of(&DeliveryStatus::Unknown(0x00)),
            hash_of(&DeliveryStatus::Success)
        );
        assert!(DeliveryStatus::Unknown(0x00).is_success());
        assert_eq!(DeliveryStatus::Unknown(0x00).name(), Some("success"));
        assert_ne!(DeliveryStatus::Unknown(0x01), DeliveryStatus::Success);
        assert_eq!(AtStatus::Unknown(0x00), AtStatus::Ok);
        assert!(AtStatus::Unknown(0x00).is_ok());
        assert_eq!(ModemStatus::Unknown(0x91), ModemStatus::StackError(0x91));
        assert_eq!(ModemStatus::Unknown(0x91).to_string(), "stack_error(0x91)");
        assert_eq!(ModemStatus::StackError(0x02), ModemStatus::JoinedNetwork);

        check_by_code!(AtStatus, AtStatus::Unknown);
        check_by_code!(DeliveryStatus, DeliveryStatus::Unknown);
        check_by_code!(DiscoveryStatus, DiscoveryStatus::Unknown);
        check_by_code!(ModemStatus, ModemStatus::Unknown);
        check_by_code!(ModemStatus, ModemStatus::StackError);
        check_by_code!(DeviceType, DeviceType::Unknown);
    }

    #[test]
    fn hand_built_unknown_round_trips_through_a_frame() {
        use crate::frame::transmit_status::TransmitStatusRepr;
        use crate::{Address16, EncodeFrame, Frame};
        let status = TransmitStatusRepr {
            frame_id: 1,
            dst16: Address16(0x7D84),
            retries: 0,
            delivery: DeliveryStatus::Unknown(0x00),
            discovery: DiscoveryStatus::Unknown(0x01),
        };
        let mut buf = [0u8; 7];
        assert_eq!(status.emit_frame_data(&mut buf), Ok(7));
        let parsed = Frame::parse_bytes(&buf).unwrap();
        let Frame::TransmitStatus(parsed) = parsed else {
            panic!("not a transmit status: {parsed:?}");
        };
        assert!(matches!(parsed.delivery, DeliveryStatus::Success));
        assert!(matches!(
            parsed.discovery,
            DiscoveryStatus::AddressDiscovery
        ));
        assert_eq!(parsed, status);
        assert_eq!(Frame::TransmitStatus(parsed), Frame::TransmitStatus(status));
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
