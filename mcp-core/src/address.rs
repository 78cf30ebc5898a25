//! MAV addresses and position slave slots.

use core::{fmt, str::FromStr};

/// An 8-byte (64-bit) MAV address, as carried by position slave set packets.
///
/// The bytes are kept in wire order. The `u64` conversions read them big-endian, the
/// order in which XBee addresses are written (`0013A20040B599B9`), and `Display`
/// writes 16 lower-case hex digits in that order, as `xbee_api::Address64` does. To
/// address a slave MAV over the radio: `Address64(u64::from(address))`; back:
/// `Address::from(address64.0)`.
///
/// ```
/// use mcp_core::Address;
/// let a: Address = "0013A20040B599B9".parse().unwrap();
/// assert_eq!(a.0, [0x00, 0x13, 0xA2, 0x00, 0x40, 0xB5, 0x99, 0xB9]);
/// assert_eq!(u64::from(a), 0x0013_A200_40B5_99B9);
/// assert_eq!(a.to_string(), "0013a20040b599b9");
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct Address(pub [u8; 8]);

impl From<u64> for Address {
    fn from(value: u64) -> Self {
        Address(value.to_be_bytes())
    }
}

impl From<Address> for u64 {
    fn from(value: Address) -> Self {
        u64::from_be_bytes(value.0)
    }
}

impl fmt::Display for Address {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.0.iter().try_for_each(|b| write!(f, "{b:02x}"))
    }
}

/// In hex, as [`Display`](fmt::Display) writes it.
#[cfg(feature = "defmt")]
impl defmt::Format for Address {
    fn format(&self, f: defmt::Formatter<'_>) {
        defmt::write!(f, "{=u64:016x}", u64::from_be_bytes(self.0));
    }
}

/// Text that is not 1 to 16 hex digits (optionally prefixed by `0x`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[error("not a 64-bit address: expected 1 to 16 hex digits")]
pub struct ParseAddressError;

impl FromStr for Address {
    type Err = ParseAddressError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let s = s.trim();
        let digits = s
            .strip_prefix("0x")
            .or_else(|| s.strip_prefix("0X"))
            .unwrap_or(s);
        if digits.is_empty() || digits.len() > 16 || digits.starts_with('+') {
            return Err(ParseAddressError);
        }
        u64::from_str_radix(digits, 16)
            .map(Address::from)
            .map_err(|_| ParseAddressError)
    }
}

/// A position slave slot, 0 to 3 (the firmware form of position slave set). The
/// default is slot 0, the one a spec-form command sets.
///
/// ```
/// use mcp_core::Slot;
/// assert_eq!(Slot::new(3).map(Slot::get), Some(3));
/// assert_eq!(Slot::new(4), None);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Slot(u8);

impl Slot {
    /// The four slots.
    pub const ALL: [Slot; 4] = [Slot(0), Slot(1), Slot(2), Slot(3)];

    /// The slot with this number, if it is 0 to 3.
    pub const fn new(n: u8) -> Option<Slot> {
        if n < 4 { Some(Slot(n)) } else { None }
    }

    /// The slot number, 0 to 3.
    pub const fn get(self) -> u8 {
        self.0
    }

    /// The slot number as an index into four addresses.
    pub const fn index(self) -> usize {
        self.0 as usize
    }
}

impl TryFrom<u8> for Slot {
    type Error = u8;

    /// Fails with the given byte if it is not 0 to 3.
    fn try_from(value: u8) -> Result<Self, u8> {
        Slot::new(value).ok_or(value)
    }
}

impl From<Slot> for u8 {
    fn from(value: Slot) -> u8 {
        value.0
    }
}

impl fmt::Display for Slot {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0)
    }
}
