//! Byte-level facts of the API frame format: delimiters, escaping and the checksum.

/// Start delimiter of every API frame.
pub const START_DELIMITER: u8 = 0x7E;
/// Escape byte of API mode 2: the next byte is the original XOR [`ESCAPE_XOR`].
pub const ESCAPE: u8 = 0x7D;
/// Value XORed into an escaped byte.
pub const ESCAPE_XOR: u8 = 0x20;
/// Software flow control XON, escaped in API mode 2.
pub const XON: u8 = 0x11;
/// Software flow control XOFF, escaped in API mode 2.
pub const XOFF: u8 = 0x13;

/// Whether `byte` must be escaped in API mode 2 (0x7E, 0x7D, 0x11, 0x13).
///
/// ```
/// use xbee_api::wire::needs_escape;
/// assert!(needs_escape(0x7E) && needs_escape(0x7D) && needs_escape(0x11) && needs_escape(0x13));
/// assert!(!needs_escape(0x00) && !needs_escape(0x5E));
/// ```
#[inline]
pub const fn needs_escape(byte: u8) -> bool {
    matches!(byte, START_DELIMITER | ESCAPE | XON | XOFF)
}

/// Wrapping sum of `bytes`, the running part of the checksum.
///
/// A plain fold, which compilers vectorise on hosts with SIMD.
///
/// ```
/// assert_eq!(xbee_api::wire::sum(&[0xFF; 1000]), 0x18); // 1000 * 255 mod 256
/// ```
#[inline]
pub fn sum(bytes: &[u8]) -> u8 {
    bytes.iter().fold(0u8, |acc, b| acc.wrapping_add(*b))
}

/// The checksum of a frame whose frame data sums (wrapping) to `sum`: `0xFF - sum`.
#[inline]
pub const fn checksum_of_sum(sum: u8) -> u8 {
    0xFF - sum
}

/// The checksum of `frame_data`: `0xFF - (sum of the bytes & 0xFF)`.
///
/// ```
/// // Modem status "coordinator started": 7E 00 02 8A 06 6F
/// assert_eq!(xbee_api::wire::checksum(&[0x8A, 0x06]), 0x6F);
/// ```
#[inline]
pub fn checksum(frame_data: &[u8]) -> u8 {
    checksum_of_sum(sum(frame_data))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sum_wraps() {
        let bytes: [u8; 600] = core::array::from_fn(|i| (i * 151 + 7) as u8 ^ 0xA5);
        let expected = bytes.iter().map(|&b| u32::from(b)).sum::<u32>() % 256;
        assert_eq!(u32::from(sum(&bytes)), expected);
        assert_eq!(checksum(&bytes), 0xFF - expected as u8);
    }
}
