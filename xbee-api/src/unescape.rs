//! API mode 2 unescaping of bytes that lie whole in one slice, 16 bytes a step.

use crate::wire::{ESCAPE, ESCAPE_XOR, START_DELIMITER, needs_escape};

const ONES: u64 = 0x0101_0101_0101_0101;
const HIGHS: u64 = 0x8080_8080_8080_8080;

/// Whether a raw mode 2 byte stands for itself after a start delimiter.
#[inline]
pub(crate) const fn is_plain(raw: u8) -> bool {
    // 0x7D and 0x7E map to 0 and 1; every other byte to 2 or more.
    (raw as u32).wrapping_sub(ESCAPE as u32) > 1
}

/// Reads one unescaped byte at `src[*i..]` and moves `*i` past it.
///
/// `None` if `src` ends first, or holds a raw 0x7E or an invalid escape there: the
/// byte-at-a-time path then takes over and reports exactly what went wrong.
#[inline]
pub(crate) fn unescape_byte(src: &[u8], i: &mut usize) -> Option<u8> {
    let raw = *src.get(*i)?;
    if is_plain(raw) {
        *i += 1;
        return Some(raw);
    }
    if raw == START_DELIMITER {
        return None;
    }
    let byte = *src.get(*i + 1)? ^ ESCAPE_XOR;
    if !needs_escape(byte) {
        return None;
    }
    *i += 2;
    Some(byte)
}

/// Unescapes `len` bytes from the start of `src` into `dst[..len]`; returns how many
/// bytes of `src` they took.
///
/// Goes 16 bytes a step (a SIMD compare where the target has one), storing whole steps
/// even when fewer of their bytes count, so `dst[len..]` is scratch space that may be
/// written to (a `dst` without room past `len` only makes the last bytes slower). `None`
/// as for [`unescape_byte`], and `dst` may have been written to.
#[inline]
pub(crate) fn unescape(src: &[u8], dst: &mut [u8], len: usize) -> Option<usize> {
    let mut i = 0;
    let mut o = 0;
    while o < len {
        let step = src.get(i..).and_then(<[u8]>::first_chunk::<16>);
        let out = dst.get_mut(o..).and_then(<[u8]>::first_chunk_mut::<16>);
        let (Some(step), Some(out)) = (step, out) else {
            // One of the last bytes, without room for a step.
            *dst.get_mut(o)? = unescape_byte(src, &mut i)?;
            o += 1;
            continue;
        };
        *out = *step;
        if !any_special(step) {
            i += 16;
            o += 16;
            continue;
        }
        let plain = first_special(step);
        i += plain;
        o += plain;
        if o >= len {
            break;
        }
        // An escape (or a delimiter, which ends the fast path).
        *dst.get_mut(o)? = unescape_pair(src, i)?;
        i += 2;
        o += 1;
    }
    // The last step may have copied plain bytes beyond the frame data.
    Some(i - (o - len))
}

/// The byte that the escape at `src[i]` stands for; `None` if `src[i]` is not an escape
/// (a delimiter), the escape is cut off, or it does not escape a special byte.
#[inline(always)]
fn unescape_pair(src: &[u8], i: usize) -> Option<u8> {
    match src.get(i..)?.first_chunk::<2>()? {
        &[ESCAPE, raw] if needs_escape(raw ^ ESCAPE_XOR) => Some(raw ^ ESCAPE_XOR),
        _ => None,
    }
}

/// Whether any of 16 raw bytes is 0x7D or 0x7E: written so that compilers make it two
/// SIMD compares and a mask test.
#[inline(always)]
fn any_special(step: &[u8; 16]) -> bool {
    step.iter().fold(false, |any, &raw| {
        any | (raw == ESCAPE) | (raw == START_DELIMITER)
    })
}

/// Index of the first 0x7D or 0x7E in `step` (16 if none), a word of 8 bytes at a time.
#[inline(always)]
fn first_special(step: &[u8; 16]) -> usize {
    let (lo, hi) = step.split_at(8);
    let word = |half: &[u8]| half.try_into().map_or(0, u64::from_le_bytes);
    match special_flags(word(lo)) {
        0 => 8 + (special_flags(word(hi)).trailing_zeros() / 8) as usize,
        flags => (flags.trailing_zeros() / 8) as usize,
    }
}

/// Bit 7 set in the lowest byte of `word` (little-endian) that is 0x7D or 0x7E, and
/// maybe in bytes above it, never below: only the lowest flag is exact.
#[inline(always)]
fn special_flags(word: u64) -> u64 {
    let zero_byte = |x: u64| x.wrapping_sub(ONES) & !x & HIGHS;
    zero_byte(word ^ (u64::from(ESCAPE) * ONES))
        | zero_byte(word ^ (u64::from(START_DELIMITER) * ONES))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_special_is_exact() {
        for special in [ESCAPE, START_DELIMITER] {
            for at in 0..16 {
                for filler in [0x00, 0x7C, 0x7D, 0x7E, 0x7F, 0xFF, 0x5E] {
                    let mut step = [0x41u8; 16];
                    step[at] = special;
                    for b in &mut step[at + 1..] {
                        *b = filler;
                    }
                    assert!(any_special(&step));
                    assert_eq!(first_special(&step), at, "{step:02X?}");
                }
            }
        }
        for b in (0..=255u8).filter(|&b| b != ESCAPE && b != START_DELIMITER) {
            assert!(!any_special(&[b; 16]), "{b:02X}");
            assert_eq!(first_special(&[b; 16]), 16, "{b:02X}");
        }
    }

    #[test]
    fn unescapes_and_sums_across_words() {
        let mut src = [0x90u8; 40];
        src[3] = 0x7D;
        src[4] = 0x5E;
        src[9] = 0x7C;
        src[15] = 0x7D;
        src[16] = 0x31;
        src[30] = 0x7F;
        let mut expected = [0x90u8; 36];
        expected[3] = 0x7E;
        expected[8] = 0x7C;
        expected[14] = 0x11;
        expected[28] = 0x7F;
        for len in 0..=36 {
            let mut dst = [0u8; 40];
            let taken = unescape(&src, &mut dst, len).unwrap();
            assert_eq!(dst[..len], expected[..len], "len {len}");
            let escapes = [3, 14].iter().filter(|&&e| e < len).count();
            assert_eq!(taken, len + escapes, "len {len}");
            // Without scratch space past `len`, the same.
            let mut exact = [0u8; 36];
            assert_eq!(unescape(&src, &mut exact[..len], len), Some(taken));
            assert_eq!(exact[..len], expected[..len]);
        }
    }

    #[test]
    fn stops_at_delimiters_bad_escapes_and_the_end() {
        let mut dst = [0u8; 16];
        let mut src = [0x20u8; 16];
        src[10] = 0x7E;
        assert_eq!(unescape(&src, &mut dst, 12), None);
        src[10] = 0x7D;
        src[11] = 0x00;
        assert_eq!(unescape(&src, &mut dst, 12), None);
        assert_eq!(unescape(&src[..10], &mut dst, 12), None);
        // An escape cut at the end of the input.
        src[11] = 0x33;
        assert_eq!(unescape(&src[..11], &mut dst, 12), None);
        assert_eq!(unescape(&src[..12], &mut dst, 11), Some(12));
        assert_eq!(dst[10], 0x13);
        assert_eq!(unescape(&src, &mut [], 0), Some(0));
        assert_eq!(unescape(&src, &mut [0; 4], 5), None);
    }
}
