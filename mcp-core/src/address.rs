//! MAV addresses and position slave slots.

use core::{fmt, str::FromStr};

/// An 8-byte (64-bit) MAV address, as carried by position slave set packets.
///
/// The bytes are kept in wire order. The `u64` conversions ([`from_u64`](Self::from_u64),
/// [`to_u64`](Self::to_u64) and the `From` impls) read them big-endian, the order in
/// which XBee addresses are written (`0013A20040B599B9`), and `Display` writes 16
/// lower-case hex digits in that order, as `xbee_api::Address64` does. To address a
/// slave MAV over the radio: `Address64(address.to_u64())`; back:
/// `Address::from_u64(address64.0)`.
///
/// ```
/// use mcp_core::Address;
/// let a: Address = "0013A20040B599B9".parse().unwrap();
/// assert_eq!(a.0, [0x00, 0x13, 0xA2, 0x00, 0x40, 0xB5, 0x99, 0xB9]);
/// assert_eq!(a.to_u64(), 0x0013_A200_40B5_99B9);
/// assert_eq!(a.to_string(), "0013a20040b599b9");
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct Address(pub [u8; 8]);

impl Address {
    /// The address whose big-endian bytes are `value`: the most significant byte comes
    /// first on the wire. `const`, for addresses fixed at compile time.
    ///
    /// ```
    /// use mcp_core::Address;
    /// const SLAVE: Address = Address::from_u64(0x0013_A200_40B5_99B9);
    /// assert_eq!(SLAVE.0, [0x00, 0x13, 0xA2, 0x00, 0x40, 0xB5, 0x99, 0xB9]);
    /// ```
    pub const fn from_u64(value: u64) -> Self {
        Address(value.to_be_bytes())
    }

    /// The address as a number, its bytes read big-endian: what `xbee_api::Address64`
    /// holds for the same radio.
    ///
    /// ```
    /// use mcp_core::Address;
    /// let a = Address([0x00, 0x13, 0xA2, 0x00, 0x40, 0xB5, 0x99, 0xB9]);
    /// assert_eq!(a.to_u64(), 0x0013_A200_40B5_99B9);
    /// ```
    pub const fn to_u64(self) -> u64 {
        u64::from_be_bytes(self.0)
    }
}

impl From<u64> for Address {
    /// As [`Address::from_u64`].
    fn from(value: u64) -> Self {
        Address::from_u64(value)
    }
}

impl From<Address> for u64 {
    /// As [`Address::to_u64`].
    fn from(value: Address) -> Self {
        value.to_u64()
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
        defmt::write!(f, "{=u64:016x}", self.to_u64());
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The `u64` forms read the wire bytes big-endian, in a `const` as at run time, and
    /// agree with the `From` impls.
    #[test]
    fn u64_forms_are_big_endian_and_const() {
        const SLAVE: Address = Address::from_u64(0x0013_A200_40B5_99B9);
        const BACK: u64 = SLAVE.to_u64();
        assert_eq!(SLAVE.0, [0x00, 0x13, 0xA2, 0x00, 0x40, 0xB5, 0x99, 0xB9]);
        assert_eq!(BACK, 0x0013_A200_40B5_99B9);
        for value in [0, 1, 0xFF, 0x0100, u64::MAX, 0x0102_0304_0506_0708] {
            let address = Address::from_u64(value);
            assert_eq!(address, Address::from(value));
            assert_eq!(address.to_u64(), value);
            assert_eq!(u64::from(address), value);
            assert_eq!(address.0, value.to_be_bytes());
        }
    }
}
