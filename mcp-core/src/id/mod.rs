//! Protocol identifiers: packet categories, command/report types, telemetry ids,
//! controllers and landing states (the tables of the specification's section 2).
//!
//! Every identifier is a one-byte value. The enums name the values listed in the
//! specification and keep any other byte in an `Unknown(u8)` arm, so that
//! `u8 -> enum -> u8` is lossless for all 256 values. Equality, ordering and hashing
//! follow the byte value, so a hand-built `Controller::Unknown(1)` equals
//! `Controller::Manual`; `From<u8>` never produces such an `Unknown`.

mod category;
mod command_type;
mod controller;
mod landing_state;
mod telemetry_id;

pub use category::Category;
pub use command_type::CommandType;
pub use controller::Controller;
pub use landing_state::LandingState;
pub use telemetry_id::TelemetryId;

/// The text given to an identifier's `FromStr` was neither one of its names nor a
/// number from 0 to 255. Its message lists the names.
///
/// ```
/// use mcp_core::Controller;
/// let err = "fast".parse::<Controller>().unwrap_err();
/// assert_eq!(
///     err.to_string(),
///     "not a controller: give a name (manual, altitude, mpc) or a number from 0 to 255 \
///      (decimal or 0x-hex)"
/// );
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ParseIdError {
    what: &'static str,
    names: &'static [&'static str],
}

impl ParseIdError {
    /// Which kind of identifier was being parsed, e.g. `"telemetry id"`.
    pub fn what(&self) -> &'static str {
        self.what
    }

    /// The names it takes, in ascending byte order.
    pub fn names(&self) -> &'static [&'static str] {
        self.names
    }
}

impl core::fmt::Display for ParseIdError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "not a {}: give a name (", self.what)?;
        for (i, name) in self.names.iter().enumerate() {
            if i > 0 {
                f.write_str(", ")?;
            }
            f.write_str(name)?;
        }
        f.write_str(") or a number from 0 to 255 (decimal or 0x-hex)")
    }
}

impl core::error::Error for ParseIdError {}

/// Parses `123`, `0x7b` / `0X7B`, or the `unknown(0x7b)` form that `Display` writes.
fn parse_number(s: &str) -> Option<u8> {
    let s = s.trim();
    let s = s
        .strip_prefix("unknown(")
        .and_then(|rest| rest.strip_suffix(')'))
        .unwrap_or(s);
    if let Some(hex) = s.strip_prefix("0x").or_else(|| s.strip_prefix("0X")) {
        u8::from_str_radix(hex, 16).ok()
    } else {
        s.parse().ok()
    }
}

/// Defines a one-byte identifier enum with an `Unknown(u8)` arm and its conversions.
macro_rules! id_enum {
    (
        $(#[$meta:meta])*
        $name:ident, $what:literal {
            $( $(#[$vmeta:meta])* $variant:ident = $value:literal => $text:literal, )*
        }
    ) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Copy)]
        #[cfg_attr(feature = "defmt", derive(defmt::Format))]
        pub enum $name {
            $( $(#[$vmeta])* $variant, )*
            /// A byte value the specification does not name.
            Unknown(u8),
        }

        impl $name {
            /// Every named value, in ascending byte order.
            pub const ALL: &'static [$name] = &[$($name::$variant),*];

            /// Iterates over every named value, in ascending byte order.
            pub fn iter() -> impl Iterator<Item = $name> + Clone {
                Self::ALL.iter().copied()
            }

            /// The stable snake_case name, or `None` for a byte the specification
            /// does not name.
            pub fn name(&self) -> Option<&'static str> {
                match u8::from(*self) {
                    $( $value => Some($text), )*
                    _ => None,
                }
            }

            /// The value with the given snake_case name.
            pub fn from_name(name: &str) -> Option<Self> {
                match name {
                    $( $text => Some($name::$variant), )*
                    _ => None,
                }
            }

            /// `true` if the byte is one the specification names.
            pub fn is_known(&self) -> bool {
                self.name().is_some()
            }
        }

        impl $name {
            /// The value of a byte (`From<u8>`, in a `const` context).
            #[inline]
            pub const fn from_u8(value: u8) -> Self {
                match value {
                    $( $value => $name::$variant, )*
                    other => $name::Unknown(other),
                }
            }

            /// The byte (`From<Self> for u8`, in a `const` context).
            #[inline]
            pub const fn to_u8(self) -> u8 {
                match self {
                    $( $name::$variant => $value, )*
                    $name::Unknown(other) => other,
                }
            }
        }

        impl From<u8> for $name {
            #[inline]
            fn from(value: u8) -> Self {
                Self::from_u8(value)
            }
        }

        impl From<$name> for u8 {
            #[inline]
            fn from(value: $name) -> u8 {
                value.to_u8()
            }
        }

        impl PartialEq for $name {
            fn eq(&self, other: &Self) -> bool {
                u8::from(*self) == u8::from(*other)
            }
        }

        impl Eq for $name {}

        impl PartialOrd for $name {
            fn partial_cmp(&self, other: &Self) -> Option<core::cmp::Ordering> {
                Some(self.cmp(other))
            }
        }

        impl Ord for $name {
            fn cmp(&self, other: &Self) -> core::cmp::Ordering {
                u8::from(*self).cmp(&u8::from(*other))
            }
        }

        impl core::hash::Hash for $name {
            fn hash<H: core::hash::Hasher>(&self, state: &mut H) {
                u8::from(*self).hash(state)
            }
        }

        impl core::fmt::Display for $name {
            /// The name, or `unknown(0xNN)` for a byte the specification does not name.
            fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
                match self.name() {
                    Some(name) => f.write_str(name),
                    None => write!(f, "unknown({:#04x})", u8::from(*self)),
                }
            }
        }

        impl core::str::FromStr for $name {
            type Err = $crate::id::ParseIdError;

            /// Accepts a name, a decimal or `0x` hexadecimal byte value, or the
            /// `unknown(0xNN)` form written by `Display`.
            fn from_str(s: &str) -> Result<Self, Self::Err> {
                Self::from_name(s.trim())
                    .or_else(|| $crate::id::parse_number(s).map(Self::from))
                    .ok_or($crate::id::ParseIdError {
                        what: $what,
                        names: &[$($text),*],
                    })
            }
        }
    };
}

pub(crate) use id_enum;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_parse_in_every_form() {
        assert_eq!(parse_number("42"), Some(42));
        assert_eq!(parse_number("0x2a"), Some(42));
        assert_eq!(parse_number("0X2A"), Some(42));
        assert_eq!(parse_number("unknown(0x2a)"), Some(42));
        assert_eq!(parse_number("256"), None);
        assert_eq!(parse_number("0x100"), None);
        assert_eq!(parse_number(""), None);
        assert_eq!(parse_number("-1"), None);
    }
}
