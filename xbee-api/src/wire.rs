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
/// On 64-bit targets 16 bytes a step in 16 lanes (one SIMD add where the target has
/// SIMD: SSE2 on x86-64, NEON on AArch64), the last partial step masked; elsewhere
/// (microcontrollers without SIMD) a word of 4 bytes a step, in two lanes of 16 bits.
///
/// ```
/// assert_eq!(xbee_api::wire::sum(&[0xFF; 1000]), 0x18); // 1000 * 255 mod 256
/// ```
#[inline]
pub fn sum(bytes: &[u8]) -> u8 {
    if cfg!(target_pointer_width = "64") {
        sum_lanes(bytes)
    } else {
        sum_words(bytes)
    }
}

/// Lane masks: the 16 bytes from `TAIL_MASK[k]` keep the last `k` lanes of a step.
// Evaluated at compile time: an index out of bounds would fail the build, not panic.
#[allow(clippy::indexing_slicing)]
const TAIL_MASK: [u8; 32] = {
    let mut mask = [0u8; 32];
    let mut i = 16;
    while i < 32 {
        mask[i] = 0xFF;
        i += 1;
    }
    mask
};

/// [`sum`] 16 bytes a step in 16 lanes of 8 bits, which compilers turn into one SIMD
/// add a step; a partial last step sums the last 16 bytes with the lanes already summed
/// masked off.
#[inline(always)]
fn sum_lanes(bytes: &[u8]) -> u8 {
    let Some(last) = bytes.last_chunk::<16>() else {
        return bytes.iter().fold(0u8, |acc, b| acc.wrapping_add(*b));
    };
    let mut lanes = [0u8; 16];
    let mut steps = bytes;
    // Four steps an iteration, then up to three written out: a loop of one step the
    // compiler unrolls eight times, and the set-up of that costs short frames (most
    // MCP frames are under 64 bytes) more than their steps do.
    while let Some((block, after)) = steps.split_first_chunk::<64>() {
        for step in block.chunks_exact(16) {
            if let Ok(step) = <&[u8; 16]>::try_from(step) {
                add_lanes(&mut lanes, step, &[0xFF; 16]);
            }
        }
        steps = after;
    }
    for _ in 0..3 {
        if let Some((step, after)) = steps.split_first_chunk::<16>() {
            add_lanes(&mut lanes, step, &[0xFF; 16]);
            steps = after;
        }
    }
    let rest = steps.len();
    if let Some(mask) = TAIL_MASK.get(rest..rest + 16).and_then(|m| m.first_chunk()) {
        add_lanes(&mut lanes, last, mask);
    }
    lanes.iter().fold(0u8, |acc, b| acc.wrapping_add(*b))
}

/// `lanes[i] += step[i] & mask[i]` for the 16 lanes.
#[inline(always)]
fn add_lanes(lanes: &mut [u8; 16], step: &[u8; 16], mask: &[u8; 16]) {
    for ((lane, byte), keep) in lanes.iter_mut().zip(step).zip(mask) {
        *lane = lane.wrapping_add(byte & keep);
    }
}

/// [`sum`] a word of 4 bytes a step, in two lanes of 16 bits.
#[inline]
fn sum_words(bytes: &[u8]) -> u8 {
    const EVEN: u32 = 0x00FF_00FF;
    let mut total = 0u8;
    // 128 words add at most 128 * 2 * 255 to a lane: below 65536.
    for block in bytes.chunks(4 * 128) {
        let mut words = block.chunks_exact(4);
        let mut acc = 0u32;
        for word in &mut words {
            let w = word.try_into().map_or(0, u32::from_le_bytes);
            acc += (w & EVEN) + ((w >> 8) & EVEN);
        }
        total = total.wrapping_add((acc + (acc >> 16)) as u8);
        for b in words.remainder() {
            total = total.wrapping_add(*b);
        }
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

    #[test]
    fn sum_by_words_matches_the_fold() {
        let bytes: [u8; 1100] = core::array::from_fn(|i| (i * 151 + 7) as u8 | 0x80);
        for start in 0..5 {
            for end in (start..bytes.len())
                .step_by(7)
                .chain([511, 512, 513, 1024, 1100])
            {
                let fold = bytes[start..end]
                    .iter()
                    .fold(0u8, |a, b| a.wrapping_add(*b));
                assert_eq!(sum_words(&bytes[start..end]), fold, "{start}..{end}");
            }
        }
        assert_eq!(sum_words(&[0xFF; 2048]), sum(&[0xFF; 2048]));
    }

    #[test]
    fn sum_by_lanes_matches_the_fold() {
        let bytes: [u8; 300] = core::array::from_fn(|i| (i * 151 + 7) as u8 | 0x80);
        for start in 0..17 {
            for end in start..bytes.len() {
                let fold = bytes[start..end]
                    .iter()
                    .fold(0u8, |a, b| a.wrapping_add(*b));
                assert_eq!(sum_lanes(&bytes[start..end]), fold, "{start}..{end}");
            }
        }
    }
}
