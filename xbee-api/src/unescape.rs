//! API mode 2 unescaping of bytes that lie whole in one slice, a word of 8 bytes a step.

use crate::wire::{ESCAPE, ESCAPE_XOR, START_DELIMITER, needs_escape};

const ONES: u64 = 0x0101_0101_0101_0101;
const HIGHS: u64 = 0x8080_8080_8080_8080;

/// Bit 7 set in each byte of `word` (little-endian) that is 0x7C..=0x7F, so that may be
/// an escape or a start delimiter. The lowest flag is exact; a flag above a flagged byte
/// may be spurious, which does not matter as only the lowest one is used.
#[inline]
fn flags(word: u64) -> u64 {
    // Bytes 0x7C..=0x7F become 0..=3; those below 4 borrow into their bit 7.
    let x = word ^ (0x7C * ONES);
    x.wrapping_sub(4 * ONES) & !x & HIGHS
}

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
/// Goes a word of 8 bytes a step, storing whole words even when fewer of their bytes
/// count, so `dst[len..]` is scratch space that may be written to (a `dst` without room
/// past `len` only makes the last bytes slower). `None` as for [`unescape_byte`], and
/// `dst` may have been written to.
#[inline]
pub(crate) fn unescape(src: &[u8], dst: &mut [u8], len: usize) -> Option<usize> {
    let mut i = 0;
    let mut o = 0;
    while o < len {
        let n = copy_plain(src.get(i..)?, dst.get_mut(o..)?, len - o);
        i += n;
        o += n;
        if o >= len {
            // The last word held bytes beyond the frame data.
            return Some(i - (o - len));
        }
        // A flagged byte, or one of the last bytes without room for a word.
        *dst.get_mut(o)? = unescape_byte(src, &mut i)?;
        o += 1;
    }
    Some(i)
}

/// Copies words of 8 bytes from `src` to `dst` until one holds a flagged byte or at
/// least `len` bytes are copied; how many bytes come before the flagged one, or were
/// copied (possibly more than `len`).
#[inline]
fn copy_plain(src: &[u8], dst: &mut [u8], len: usize) -> usize {
    let mut n = 0;
    for (s, d) in src.chunks_exact(8).zip(dst.chunks_exact_mut(8)) {
        d.copy_from_slice(s);
        let flags = s.try_into().map_or(HIGHS, |w| flags(u64::from_le_bytes(w)));
        if flags != 0 {
            return n + (flags.trailing_zeros() / 8) as usize;
        }
        n += 8;
        if n >= len {
            break;
        }
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flags_mark_the_first_special_byte_exactly() {
        for special in 0x7C..=0x7F_u8 {
            for at in 0..8 {
                for filler in [0x00, 0x7C, 0x7D, 0x7E, 0x7F, 0xFF, 0x5E] {
                    let mut bytes = [0x41u8; 8];
                    bytes[at] = special;
                    for b in &mut bytes[at + 1..] {
                        *b = filler;
                    }
                    let f = flags(u64::from_le_bytes(bytes));
                    assert_eq!(f.trailing_zeros() / 8, at as u32, "{bytes:02X?}");
                }
            }
        }
        for b in (0..=255u8).filter(|b| !(0x7C..=0x7F).contains(b)) {
            assert_eq!(flags(u64::from_le_bytes([b; 8])), 0, "{b:02X}");
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
