//! 64-bit and 16-bit XBee addresses.

use core::fmt;
use core::str::FromStr;

/// A 64-bit IEEE (extended) address, as sent big-endian on the wire.
///
/// Displays as 16 lowercase hex digits; parses from 1 to 16 hex digits, with an optional
/// `0x` prefix, in either case.
///
/// ```
/// use xbee_api::Address64;
/// let a: Address64 = "0x0013A20040522BAA".parse().unwrap();
/// assert_eq!(a, Address64(0x0013_a200_4052_2baa));
/// assert_eq!(a.to_string(), "0013a20040522baa");
/// assert_eq!(Address64::BROADCAST.to_string(), "000000000000ffff");
/// // Debug, in an error or a struct, is hex too.
/// assert_eq!(format!("{a:?}"), "Address64(0x0013a20040522baa)");
/// ```
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct Address64(pub u64);

/// A 16-bit network address, as sent big-endian on the wire.
///
/// Displays as 4 lowercase hex digits; parses like [`Address64`] with up to 4 digits.
///
/// ```
/// use xbee_api::Address16;
/// assert_eq!("FFFE".parse::<Address16>(), Ok(Address16::UNKNOWN));
/// assert_eq!(Address16(0x7d84).to_string(), "7d84");
/// assert_eq!(format!("{:?}", Address16(0x7d84)), "Address16(0x7d84)");
/// ```
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct Address16(pub u16);

impl Address64 {
    /// The coordinator's 64-bit address, `0000000000000000`.
    pub const COORDINATOR: Self = Self(0);
    /// The broadcast 64-bit address, `000000000000FFFF`.
    pub const BROADCAST: Self = Self(0xFFFF);

    /// The address from its 8 big-endian wire bytes.
    pub const fn from_bytes(bytes: [u8; 8]) -> Self {
        Self(u64::from_be_bytes(bytes))
    }

    /// The 8 big-endian wire bytes.
    pub const fn to_bytes(self) -> [u8; 8] {
        self.0.to_be_bytes()
    }
}

impl Address16 {
    /// "Unknown" 16-bit address (`FFFE`): the radio resolves it from the 64-bit one.
    pub const UNKNOWN: Self = Self(0xFFFE);
    /// The coordinator's 16-bit address, `0000`.
    pub const COORDINATOR: Self = Self(0);

    /// The address from its 2 big-endian wire bytes.
    pub const fn from_bytes(bytes: [u8; 2]) -> Self {
        Self(u16::from_be_bytes(bytes))
    }

    /// The 2 big-endian wire bytes.
    pub const fn to_bytes(self) -> [u8; 2] {
        self.0.to_be_bytes()
    }
}

impl fmt::Display for Address64 {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:016x}", self.0)
    }
}

impl fmt::Display for Address16 {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:04x}", self.0)
    }
}

/// `Address64(0x0013a20040522baa)`: in hex, as addresses are read everywhere else (a
/// decimal address in an error's `Debug` means nothing to anyone).
impl fmt::Debug for Address64 {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Address64(0x{:016x})", self.0)
    }
}

/// `Address16(0x7d84)`, in hex as [`Address64`]'s.
impl fmt::Debug for Address16 {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Address16(0x{:04x})", self.0)
    }
}

/// In hex, as [`Display`](fmt::Display) writes it.
#[cfg(feature = "defmt")]
impl defmt::Format for Address64 {
    fn format(&self, f: defmt::Formatter<'_>) {
        defmt::write!(f, "{=u64:016x}", self.0);
    }
}

/// In hex, as [`Display`](fmt::Display) writes it.
#[cfg(feature = "defmt")]
impl defmt::Format for Address16 {
    fn format(&self, f: defmt::Formatter<'_>) {
        defmt::write!(f, "{=u16:04x}", self.0);
    }
}

/// Why a string is not an address.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ParseAddressError {
    /// No hex digit (empty, or only `0x`).
    Empty,
    /// More hex digits than the address holds.
    TooLong {
        /// Number of digits given.
        digits: usize,
        /// Most digits the address takes.
        max: usize,
    },
    /// A character that is not a hex digit, at this byte offset of the string.
    InvalidDigit {
        /// Byte offset of the offending character in the input.
        at: usize,
    },
}

impl fmt::Display for ParseAddressError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Empty => f.write_str("empty address"),
            Self::TooLong { digits, max } => {
                write!(f, "address has {digits} hex digits, at most {max} allowed")
            }
            Self::InvalidDigit { at } => write!(f, "invalid hex digit at byte {at}"),
        }
    }
}

impl core::error::Error for ParseAddressError {}

/// Parses 1..=`max` hex digits with an optional `0x`/`0X` prefix.
fn parse_hex(s: &str, max: usize) -> Result<u64, ParseAddressError> {
    let (offset, digits) = match s.get(..2) {
        Some("0x" | "0X") => (2, &s[2..]),
        _ => (0, s),
    };
    if digits.is_empty() {
        return Err(ParseAddressError::Empty);
    }
    let mut value = 0u64;
    for (i, c) in digits.bytes().enumerate() {
        let nibble = match c {
            b'0'..=b'9' => c - b'0',
            b'a'..=b'f' => c - b'a' + 10,
            b'A'..=b'F' => c - b'A' + 10,
            _ => return Err(ParseAddressError::InvalidDigit { at: offset + i }),
        };
        if i >= max {
            return Err(ParseAddressError::TooLong {
                digits: digits.len(),
                max,
            });
        }
        value = (value << 4) | u64::from(nibble);
    }
    Ok(value)
}

impl FromStr for Address64 {
    type Err = ParseAddressError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        parse_hex(s, 16).map(Self)
    }
}

impl FromStr for Address16 {
    type Err = ParseAddressError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        // At most 4 digits, so the value fits a u16.
        parse_hex(s, 4).map(|v| Self(v as u16))
    }
}

impl From<u64> for Address64 {
    fn from(value: u64) -> Self {
        Self(value)
    }
}

impl From<Address64> for u64 {
    fn from(address: Address64) -> u64 {
        address.0
    }
}

impl From<u16> for Address16 {
    fn from(value: u16) -> Self {
        Self(value)
    }
}

impl From<Address16> for u16 {
    fn from(address: Address16) -> u16 {
        address.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_rejects() {
        assert_eq!("ffff".parse(), Ok(Address64::BROADCAST));
        assert_eq!("0".parse(), Ok(Address64::COORDINATOR));
        assert_eq!("0XaBcD".parse(), Ok(Address16(0xabcd)));
        assert_eq!("".parse::<Address16>(), Err(ParseAddressError::Empty));
        assert_eq!("0x".parse::<Address64>(), Err(ParseAddressError::Empty));
        assert_eq!(
            "12345".parse::<Address16>(),
            Err(ParseAddressError::TooLong { digits: 5, max: 4 })
        );
        assert_eq!(
            "00000000000000001".parse::<Address64>(),
            Err(ParseAddressError::TooLong {
                digits: 17,
                max: 16
            })
        );
        assert_eq!(
            "+ff".parse::<Address16>(),
            Err(ParseAddressError::InvalidDigit { at: 0 })
        );
        assert_eq!(
            "0x12g4".parse::<Address16>(),
            Err(ParseAddressError::InvalidDigit { at: 4 })
        );
        assert_eq!("ffffffffffffffff".parse(), Ok(Address64(u64::MAX)));
    }

    #[test]
    fn bytes_are_big_endian() {
        let a = Address64::from_bytes([0, 0x13, 0xa2, 0, 0x40, 0x52, 0x2b, 0xaa]);
        assert_eq!(a, Address64(0x0013_a200_4052_2baa));
        assert_eq!(a.to_bytes()[1], 0x13);
        assert_eq!(Address16::from_bytes([0x7d, 0x84]), Address16(0x7d84));
        assert_eq!(Address16(0xfffe).to_bytes(), [0xff, 0xfe]);
    }
}
