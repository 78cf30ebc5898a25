//! API mode 2 unescaping of bytes that lie whole in one slice, 16 bytes a step (8 on
//! 32-bit targets).

#[cfg(any(test, target_pointer_width = "64"))]
use wide::u8x16;

use crate::wire::{ESCAPE, ESCAPE_XOR, START_DELIMITER, needs_escape, sum};

/// Whether a raw mode 2 byte stands for itself after a start delimiter.
#[inline]
pub(crate) const fn is_plain(raw: u8) -> bool {
    // 0x7D and 0x7E map to 0 and 1; every other byte to 2 or more.
    (raw as u32).wrapping_sub(ESCAPE as u32) > 1
}

/// [`is_plain`], for the byte-at-a-time path's test of every byte.
///
/// On ARM the byte is tested in the top 8 bits of a word: the narrow form, which LLVM
/// makes of `is_plain`, needs the difference cut back to 8 bits (`uxtb`) before the
/// compare, one instruction more a byte; there a shifted operand comes free. Elsewhere
/// (x86-64 compares bytes directly) the narrow form is the shorter, and the slice paths
/// on ARM came out no better with this one.
#[inline(always)]
pub(crate) const fn is_plain_byte(raw: u8) -> bool {
    if cfg!(target_arch = "arm") {
        is_plain_top(raw)
    } else {
        is_plain(raw)
    }
}

/// [`is_plain`] computed on the byte shifted to the top of a 32-bit word.
#[inline(always)]
const fn is_plain_top(raw: u8) -> bool {
    ((raw as u32) << 24).wrapping_sub((ESCAPE as u32) << 24) >= 2 << 24
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
/// bytes of `src` they took and their sum (the running part of the checksum).
///
/// Goes a step of [`STEP`] bytes at a time (16 with SIMD compares on 64-bit targets; 8,
/// two words each tested for special bytes at once, on 32-bit ones such as a Cortex-M),
/// storing whole steps even when fewer of their bytes count, so it needs `STEP` bytes of
/// scratch space past `len` in `dst` (without them, or near the end of `src`, it goes a
/// byte at a time). The sum is taken afterwards from `dst[..len]` ([`sum`]). `None` as for
/// [`unescape_byte`], and `dst` may have been written to.
#[inline(always)]
pub(crate) fn unescape(src: &[u8], dst: &mut [u8], len: usize) -> Option<(usize, u8)> {
    #[cfg(target_pointer_width = "64")]
    let scan = |step: &[u8; STEP], to: &mut [u8]| {
        // Loaded once, then stored and compared from the register.
        let bytes = u8x16::new(*step);
        to.copy_from_slice(bytes.as_array_ref());
        let specials = special_mask(bytes);
        (specials != 0).then(|| specials.trailing_zeros() as usize)
    };
    // Two words a step: the fewest instructions a byte on a Cortex-M3 (one word a
    // step costs more loop, four spill registers).
    #[cfg(not(target_pointer_width = "64"))]
    let scan = |step: &[u8; STEP], to: &mut [u8]| {
        to.copy_from_slice(step);
        let [a, b, c, d, e, f, g, h] = *step;
        let lo = special_lanes(u32::from_le_bytes([a, b, c, d]));
        let hi = special_lanes(u32::from_le_bytes([e, f, g, h]));
        if lo != 0 {
            Some((lo.trailing_zeros() / 8) as usize)
        } else if hi != 0 {
            Some(4 + (hi.trailing_zeros() / 8) as usize)
        } else {
            None
        }
    };
    unescape_steps(src, dst, len, scan)
}

/// Bytes [`unescape`] takes a step.
#[cfg(target_pointer_width = "64")]
pub(crate) const STEP: usize = 16;
/// Bytes [`unescape`] takes a step.
#[cfg(not(target_pointer_width = "64"))]
pub(crate) const STEP: usize = 8;

/// [`unescape`] with the step's `scan`: it stores the step's bytes into `to` (`STEP`
/// bytes) and returns the index of its first special byte (0x7D or 0x7E), if any.
#[inline(always)]
fn unescape_steps(
    src: &[u8],
    dst: &mut [u8],
    len: usize,
    scan: impl Fn(&[u8; STEP], &mut [u8]) -> Option<usize>,
) -> Option<(usize, u8)> {
    let Some(out) = dst.get_mut(..len + STEP) else {
        return unescape_bytes(src, 0, dst, 0, len);
    };
    // `rest` is what is left of `src`, `o` the offset in `out`: a whole plain step may
    // take `o` past `len`, and the start of `rest` as far past the end of the frame
    // data; the two are taken back together at the end.
    let mut rest = src;
    let mut o = 0;
    while o < len {
        let Some((step, after)) = rest.split_first_chunk::<STEP>() else {
            // Near the end of `src`: the rest a byte at a time. In line rather than a
            // call of `unescape_bytes`, whose result came back through memory on every
            // frame; the sum below then covers these bytes too.
            let mut i = src.len() - rest.len();
            while o < len {
                *out.get_mut(o)? = unescape_byte(src, &mut i)?;
                o += 1;
            }
            rest = src.get(i..)?;
            break;
        };
        let Some(plain) = scan(step, out.get_mut(o..o + STEP)?) else {
            rest = after;
            o += STEP;
            continue;
        };
        // Plain bytes before the first special one; it may lie past the frame data.
        if o + plain >= len {
            rest = rest.get(len - o..)?;
            o = len;
            break;
        }
        // An escape (or a delimiter, which ends the fast path).
        let byte = unescape_pair(rest, plain)?;
        if let Some(slot) = out.get_mut(o + plain) {
            *slot = byte;
        }
        rest = rest.get(plain + 2..)?;
        o += plain + 1;
    }
    let i = src.len() - rest.len() - (o - len);
    Some((i, sum(out.get(..len)?)))
}

/// [`unescape`] a byte at a time, from `src[i..]` into `dst[o..len]`.
#[inline(never)]
#[cold]
fn unescape_bytes(
    src: &[u8],
    mut i: usize,
    dst: &mut [u8],
    mut o: usize,
    len: usize,
) -> Option<(usize, u8)> {
    while o < len {
        *dst.get_mut(o)? = unescape_byte(src, &mut i)?;
        o += 1;
    }
    Some((i, sum(dst.get(..len)?)))
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

/// Bit `k` set if `step[k]` is 0x7D or 0x7E: two SIMD compares and a mask move.
#[inline(always)]
#[cfg(any(test, target_pointer_width = "64"))]
pub(crate) fn special_mask(bytes: u8x16) -> u32 {
    let specials = bytes.cmp_eq(u8x16::splat(ESCAPE)) | bytes.cmp_eq(u8x16::splat(START_DELIMITER));
    specials.move_mask() as u32
}

/// Whether any of the 4 bytes of `word` is 0x7D or 0x7E: each compared at once, word
/// at a time (a byte of `word ^ 0x7D7D7D7D` is zero exactly where `word` holds 0x7D,
/// and `(x - 0x01..) & !x & 0x80..` is non-zero exactly when `x` has a zero byte).
#[inline(always)]
#[cfg(any(test, not(target_pointer_width = "64")))]
pub(crate) const fn special_in_word(word: u32) -> bool {
    special_lanes(word) != 0
}

/// The high bit of each byte of `word` that is 0x7D or 0x7E, and maybe of bytes above
/// (more significant than) such a byte, where the subtraction borrowed: the lowest bit
/// set always marks the first special byte (little-endian order), and none is set if
/// there is none.
#[inline(always)]
#[cfg(any(test, not(target_pointer_width = "64")))]
pub(crate) const fn special_lanes(word: u32) -> u32 {
    const ONES: u32 = 0x0101_0101;
    const HIGHS: u32 = 0x8080_8080;
    let escapes = word ^ (ONES * ESCAPE as u32);
    let delimiters = word ^ (ONES * START_DELIMITER as u32);
    let zero_bytes =
        (escapes.wrapping_sub(ONES) & !escapes) | (delimiters.wrapping_sub(ONES) & !delimiters);
    zero_bytes & HIGHS
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_form_of_is_plain_refuses_exactly_0x7d_and_0x7e() {
        for b in 0..=255u8 {
            let plain = b != ESCAPE && b != START_DELIMITER;
            assert_eq!(is_plain(b), plain, "{b:#04X}");
            assert_eq!(is_plain_top(b), plain, "{b:#04X}");
            assert_eq!(is_plain_byte(b), plain, "{b:#04X}");
        }
    }

    #[test]
    fn special_mask_marks_exactly_0x7d_and_0x7e() {
        for at in 0..16 {
            for b in 0..=255u8 {
                let mut step = [0x41u8; 16];
                step[at] = b;
                let expected = if b == ESCAPE || b == START_DELIMITER {
                    1 << at
                } else {
                    0
                };
                assert_eq!(special_mask(u8x16::new(step)), expected, "{step:02X?}");
            }
        }
        assert_eq!(special_mask(u8x16::new([ESCAPE; 16])), 0xFFFF);
    }

    #[test]
    fn special_in_word_finds_exactly_0x7d_and_0x7e() {
        for at in 0..4 {
            for b in 0..=255u8 {
                for fill in [0x00, 0x41, 0x7C, 0x7F, 0xFD, 0xFE, 0xFF] {
                    let mut word = [fill; 4];
                    word[at] = b;
                    let expected = word.iter().any(|&x| x == ESCAPE || x == START_DELIMITER);
                    assert_eq!(
                        special_in_word(u32::from_le_bytes(word)),
                        expected,
                        "{word:02X?}"
                    );
                }
            }
        }
    }

    #[test]
    fn special_lanes_mark_the_first_special_byte() {
        for at in 0..4 {
            for b in [ESCAPE, START_DELIMITER] {
                for fill in [0x00, 0x41, 0x7C, 0x7D, 0x7E, 0x7F, 0xFF] {
                    let mut word = [fill; 4];
                    word[at] = b;
                    let first = word
                        .iter()
                        .position(|&x| x == ESCAPE || x == START_DELIMITER);
                    let lanes = special_lanes(u32::from_le_bytes(word));
                    assert_eq!(
                        Some((lanes.trailing_zeros() / 8) as usize),
                        first,
                        "{word:02X?}"
                    );
                }
            }
        }
        assert_eq!(
            special_lanes(u32::from_le_bytes([0x7C, 0x7F, 0x00, 0xFF])),
            0
        );
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
            let mut dst = [0u8; 52];
            let (taken, total) = unescape(&src, &mut dst, len).unwrap();
            assert_eq!(total, sum(&expected[..len]), "len {len}");
            assert_eq!(dst[..len], expected[..len], "len {len}");
            let escapes = [3, 14].iter().filter(|&&e| e < len).count();
            assert_eq!(taken, len + escapes, "len {len}");
            // Without scratch space past `len`, the same.
            let mut exact = [0u8; 36];
            assert_eq!(unescape(&src, &mut exact[..len], len), Some((taken, total)));
            assert_eq!(exact[..len], expected[..len]);
        }
    }

    #[test]
    fn a_plain_step_past_the_frame_data_is_taken_back() {
        // Every overshoot of the last whole step, 0 to 15 bytes.
        let src: [u8; 48] = core::array::from_fn(|i| 0x80 + i as u8);
        for len in 0..=40 {
            let mut dst = [0u8; 56];
            let got = unescape(&src, &mut dst[..len + 16], len);
            assert_eq!(got, Some((len, sum(&src[..len]))), "len {len}");
            assert_eq!(dst[..len], src[..len]);
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
        assert_eq!(unescape(&src[..12], &mut dst, 11).map(|r| r.0), Some(12));
        assert_eq!(dst[10], 0x13);
        assert_eq!(unescape(&src, &mut [], 0), Some((0, 0)));
        assert_eq!(unescape(&src, &mut [0; 4], 5), None);
    }

    proptest::proptest! {
        /// The 16-byte steps agree with the byte-at-a-time reference on any input:
        /// escapes (valid or not) and delimiters anywhere, before, at and past `len`,
        /// with and without scratch space, and inputs cut short.
        #[test]
        fn steps_agree_with_bytes(
            src in proptest::collection::vec(
                proptest::prop_oneof![
                    4 => proptest::prelude::any::<u8>(),
                    1 => proptest::sample::select(&[ESCAPE, START_DELIMITER, 0x5E, 0x31, 0x33][..]),
                ],
                0..80,
            ),
            len in 0usize..70,
            extra in 0usize..18,
        ) {
            let mut expected = [0u8; 70];
            let reference = unescape_bytes(&src, 0, &mut expected, 0, len);
            let mut scratch = [0u8; 87];
            let got = unescape(&src, &mut scratch[..len + extra], len);
            proptest::prop_assert_eq!(got, reference);
            if got.is_some() {
                proptest::prop_assert_eq!(&scratch[..len], &expected[..len]);
            }
        }
    }
}
