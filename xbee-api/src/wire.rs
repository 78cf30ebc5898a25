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
/// Sums in wide lanes so that the compiler vectorises it on hosts.
#[inline]
pub fn sum(bytes: &[u8]) -> u8 {
    let mut chunks = bytes.chunks_exact(8);
    let mut lanes = [0u8; 8];
    for chunk in &mut chunks {
        for (lane, b) in lanes.iter_mut().zip(chunk) {
            *lane = lane.wrapping_add(*b);
        }
    }
    let mut total = chunks
        .remainder()
        .iter()
        .fold(0u8, |acc, b| acc.wrapping_add(*b));
    for lane in lanes {
        total = total.wrapping_add(lane);
    }
    total
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
