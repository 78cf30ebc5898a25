//! API mode 2 unescaping of a short frame in one 64-byte window (64-bit targets).
//!
//! A frame that lies whole, escapes included, in the 64 bytes from its start delimiter
//! (an MCP telemetry frame of 8 values takes about 59) is unescaped with no loop over
//! steps: the 64 bytes are copied to the buffer and scanned at once into a mask of
//! escapes (16 bytes a compare, 32 in a build for AVX2), each escape inside the frame moves what follows it
//! one byte down, and the frame's raw bytes, masked in their lanes, are summed for the
//! checksum and searched for a start delimiter together. One branch a frame and one an
//! escape, wherever the escapes fall.

#[cfg(not(all(target_arch = "x86_64", target_feature = "avx2")))]
use wide::u8x16 as Step;
#[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
use wide::{CmpEq, u8x32 as Step};

use crate::wire::{ESCAPE, ESCAPE_XOR, START_DELIMITER, needs_escape};

/// Bytes the window covers.
pub(crate) const WINDOW: usize = 64;

/// Bytes a step takes: 32 in a build for AVX2 (`-C target-cpu=x86-64-v3` or `native`
/// on most x86-64 processors since 2013), else 16 (SSE2 on x86-64, NEON on AArch64).
const LANES: usize = Step::LANES as usize;

/// Steps in the window.
const STEPS: usize = WINDOW / LANES;

/// Bytes of input and of buffer [`frame_in_window`] needs: each escape (at most at
/// byte 63) copies the 64 bytes from the one after it, one byte down.
pub(crate) const WINDOW_ROOM: usize = 2 * WINDOW;

/// Lane masks: the 64 bytes from `KEEP[64 - k]` keep the first `k`.
// Evaluated at compile time: an index out of bounds would fail the build, not panic.
#[allow(clippy::indexing_slicing)]
const KEEP: [u8; 2 * WINDOW] = {
    let mut mask = [0u8; 2 * WINDOW];
    let mut i = 0;
    while i < WINDOW {
        mask[i] = 0xFF;
        i += 1;
    }
    mask
};

/// A frame in one window: where it lies in the buffer and what it took of the input.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct WindowFrame {
    /// Bytes of input the frame took, start delimiter to checksum byte.
    pub(crate) taken: usize,
    /// Frame data length (the length field); the data is at `out[DATA..DATA + len]`
    /// and the checksum byte after it.
    pub(crate) len: usize,
    /// Wrapping sum of the frame data and the checksum byte: 0xFF for a valid frame.
    pub(crate) total: u8,
}

/// Where [`frame_in_window`] leaves the frame data in `out`: after the delimiter and
/// the length field, which it copies along.
pub(crate) const DATA: usize = 3;

/// Longest frame data [`frame_in_window`] takes: with its checksum byte and the three
/// bytes before it, it fills the window.
pub(crate) const MAX_LEN: usize = WINDOW - DATA - 1;

/// Unescapes the frame that starts at `src[0]` into `out` when the whole of it lies in
/// the first [`WINDOW`] bytes of `src` and its length field is from 1 to [`MAX_LEN`];
/// writes `out[..WINDOW]` and, after an escape, as far as `out[WINDOW_ROOM - 1]`. The
/// caller has checked that `src[0]` is a start delimiter.
///
/// `None` if the frame runs past the window, or has another length, a start delimiter
/// inside it or an invalid escape: the caller then takes a path that reports what went
/// wrong or takes longer frames.
#[inline(always)]
pub(crate) fn frame_in_window(
    src: &[u8; WINDOW_ROOM],
    out: &mut [u8; WINDOW_ROOM],
) -> Option<WindowFrame> {
    let steps = load(src);
    for (step, to) in steps.iter().zip(out.chunks_exact_mut(LANES)) {
        to.copy_from_slice(step.as_array_ref());
    }
    let mut escapes = mask(&steps, ESCAPE);
    let [_, hi, lo, ..] = *src;
    let len = usize::from(u16::from_be_bytes([hi, lo]));
    // In range, both length bytes are plain (0x7D and 0x7E are over `MAX_LEN`).
    if len.wrapping_sub(1) >= MAX_LEN {
        return None;
    }
    // The data and the checksum byte end before `end + k` after `k` escapes.
    let end = DATA + len + 1;
    // The bytes after each escape: `after[i]` follows the escape at `i`.
    let after = src.get(1..)?;
    let mut k = 0;
    // What the escapes add to the sum of the raw bytes.
    let mut adjust = 0u8;
    while escapes != 0 {
        let i = escapes.trailing_zeros() as usize;
        if i - k >= end {
            break;
        }
        // What the pair adds to the raw sum, 0 if the escape is invalid.
        let add = *ESCAPED.get(usize::from(*after.get(i)?))?;
        if add == 0 {
            return None;
        }
        adjust = adjust.wrapping_add(add);
        // The escaped byte and the rest of the window one byte down, then the escaped
        // byte unescaped in place. `k <= i < 64`: the mask changes nothing but spares
        // the bounds tests.
        let o = (i - k) % WINDOW;
        let rest = after.get(i..)?.first_chunk::<WINDOW>()?;
        let to = out.get_mut(o..)?.first_chunk_mut::<WINDOW>()?;
        to.copy_from_slice(rest);
        to[0] ^= ESCAPE_XOR;
        k += 1;
        escapes &= escapes - 1;
    }
    let taken = end + k;
    if taken > WINDOW {
        return None;
    }
    // The frame's bytes after its length field, the rest of the window masked off:
    // summed, and searched for a start delimiter, which would cut the frame off.
    let mut lanes = Step::ZERO;
    let mut delimiters = Step::ZERO;
    for (step, keep) in steps.iter().zip(frame_lanes(taken)) {
        let kept = *step & keep;
        lanes += kept;
        delimiters |= kept.cmp_eq(Step::splat(START_DELIMITER));
    }
    if delimiters.any() {
        return None;
    }
    let total = reduce(lanes).wrapping_add(adjust);
    Some(WindowFrame { taken, len, total })
}

/// For each raw byte after an escape, what the pair adds to the wrapping sum of the
/// raw bytes to make it the sum of the unescaped ones (`byte - raw - 0x7D`, never 0),
/// or 0 if the byte does not stand for a special byte (an invalid escape).
// Evaluated at compile time: an index out of bounds would fail the build, not panic.
#[allow(clippy::indexing_slicing)]
const ESCAPED: [u8; 256] = {
    let mut escaped = [0; 256];
    let mut raw = 0;
    while raw < 256 {
        let byte = raw as u8 ^ ESCAPE_XOR;
        if needs_escape(byte) {
            escaped[raw] = byte.wrapping_sub(raw as u8).wrapping_sub(ESCAPE);
            assert!(escaped[raw] != 0);
        }
        raw += 1;
    }
    escaped
};

/// Lane masks of the window's bytes from [`DATA`] up to `taken` (at most 64).
#[inline(always)]
fn frame_lanes(taken: usize) -> [Step; STEPS] {
    let keep = KEEP.get(WINDOW - taken..).unwrap_or_default();
    core::array::from_fn(|j| {
        let m = keep
            .get(LANES * j..LANES * (j + 1))
            .and_then(|m| m.first_chunk::<LANES>());
        let m = Step::new(m.copied().unwrap_or_default());
        if j == 0 {
            m & Step::new(AFTER_HEADER)
        } else {
            m
        }
    })
}

/// The first step's lanes after the delimiter and the length field.
const AFTER_HEADER: [u8; LANES] = {
    let mut mask = [0xFF; LANES];
    mask[0] = 0;
    mask[1] = 0;
    mask[2] = 0;
    mask
};

/// The window's steps.
#[inline(always)]
fn load(src: &[u8; WINDOW_ROOM]) -> [Step; STEPS] {
    core::array::from_fn(|j| {
        let step = src
            .get(LANES * j..LANES * (j + 1))
            .and_then(|s| s.first_chunk::<LANES>());
        Step::new(step.copied().unwrap_or_default())
    })
}

/// Bit `k` set where byte `k` of the window is `byte`.
#[inline(always)]
fn mask(steps: &[Step; STEPS], byte: u8) -> u64 {
    steps.iter().enumerate().fold(0, |acc, (j, step)| {
        // The step's lanes as its low bits (32 lanes fill the `i32`, sign bit too).
        let bits =
            step.cmp_eq(Step::splat(byte)).move_mask() as u32 as u64 & (u64::MAX >> (64 - LANES));
        acc | bits << (LANES * j)
    })
}

/// Wrapping sum of the 16 lanes: one `psadbw` (SSE2's sum of absolute differences,
/// here against zero) on x86-64, where left to itself the compiler may add the lanes
/// one by one.
#[cfg(all(target_arch = "x86_64", not(target_feature = "avx2")))]
#[inline(always)]
fn reduce(lanes: Step) -> u8 {
    use safe_arch::{m128i, sum_of_u8_abs_diff_m128i, zeroed_m128i};
    let halves: [u64; 2] =
        sum_of_u8_abs_diff_m128i(m128i::from(lanes.to_array()), zeroed_m128i()).into();
    halves[0].wrapping_add(halves[1]) as u8
}

/// Wrapping sum of the 32 lanes: one `vpsadbw` (AVX2).
#[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
#[inline(always)]
fn reduce(lanes: Step) -> u8 {
    use safe_arch::{m256i, sum_of_u8_abs_diff_m256i, zeroed_m256i};
    let quarters: [u64; 4] =
        sum_of_u8_abs_diff_m256i(m256i::from(lanes.to_array()), zeroed_m256i()).into();
    quarters.iter().fold(0u64, |a, q| a.wrapping_add(*q)) as u8
}

/// Wrapping sum of the lanes.
#[cfg(not(target_arch = "x86_64"))]
#[inline(always)]
fn reduce(lanes: Step) -> u8 {
    lanes
        .to_array()
        .iter()
        .fold(0u8, |acc, b| acc.wrapping_add(*b))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::unescape::unescape_byte;
    use crate::wire::sum;
    extern crate std;
    use std::vec::Vec;

    /// What [`frame_in_window`] must find, a byte at a time: the frame, and its data and
    /// checksum byte unescaped.
    fn reference(src: &[u8; WINDOW_ROOM]) -> Option<(WindowFrame, Vec<u8>)> {
        let [START_DELIMITER, hi, lo, ..] = *src else {
            return None;
        };
        if [hi, lo]
            .iter()
            .any(|&b| b == ESCAPE || b == START_DELIMITER)
        {
            return None;
        }
        let len = usize::from(u16::from_be_bytes([hi, lo]));
        if len == 0 || len > MAX_LEN {
            return None;
        }
        let mut i = DATA;
        let bytes = (0..=len)
            .map(|_| unescape_byte(src, &mut i))
            .collect::<Option<Vec<u8>>>()?;
        (i <= WINDOW).then(|| {
            let total = sum(&bytes);
            (
                WindowFrame {
                    taken: i,
                    len,
                    total,
                },
                bytes,
            )
        })
    }

    fn check(src: &[u8; WINDOW_ROOM]) {
        let mut out = [0u8; WINDOW_ROOM];
        let got = frame_in_window(src, &mut out);
        let expected = reference(src);
        assert_eq!(got, expected.as_ref().map(|e| e.0), "{src:02X?}");
        if let Some((frame, bytes)) = expected {
            assert_eq!(out[DATA..=DATA + frame.len], bytes[..], "{src:02X?}");
        }
    }

    /// A window holding a frame of `len` data bytes of `fill`, escapes at `escapes`
    /// (input offsets), and the next frame's delimiter right after it.
    fn window(len: usize, fill: u8, escapes: &[usize]) -> [u8; WINDOW_ROOM] {
        let mut src = [fill; WINDOW_ROOM];
        src[0] = START_DELIMITER;
        src[1..3].copy_from_slice(&(len as u16).to_be_bytes());
        for &e in escapes {
            src[e] = ESCAPE;
            src[e + 1] = 0x33;
        }
        let taken = DATA + len + 1 + escapes.len();
        if taken < WINDOW_ROOM {
            src[taken] = START_DELIMITER;
        }
        src
    }

    #[test]
    fn frames_that_fill_the_window_to_the_last_byte() {
        for len in 1..=MAX_LEN {
            for at in DATA..WINDOW - 1 {
                check(&window(len, 0x41, &[at]));
                check(&window(len, 0x41, &[DATA, at.max(DATA + 2)]));
            }
            check(&window(len, 0x41, &[]));
        }
        // Exactly 64 bytes with an escaped checksum byte; one more escape is too many.
        let src = window(MAX_LEN - 1, 0x41, &[DATA + MAX_LEN - 1]);
        let mut out = [0; WINDOW_ROOM];
        assert_eq!(
            frame_in_window(&src, &mut out).map(|f| f.taken),
            Some(WINDOW)
        );
        assert_eq!(out[DATA + MAX_LEN - 1], 0x13);
        let src = window(MAX_LEN - 1, 0x41, &[DATA, DATA + MAX_LEN]);
        assert_eq!(frame_in_window(&src, &mut out), None);
    }

    #[test]
    fn what_it_leaves_to_the_other_paths() {
        let mut out = [0; WINDOW_ROOM];
        let ok = window(20, 0x41, &[10]);
        assert!(frame_in_window(&ok, &mut out).is_some());
        // An escaped length field, lengths 0 and over the window, a delimiter inside
        // the frame or as the escaped byte, an escape of a byte that needs none.
        let mut bad = [ok; 6];
        bad[0][2] = ESCAPE;
        bad[1][1..3].copy_from_slice(&[0, 0]);
        bad[2][1..3].copy_from_slice(&[0, MAX_LEN as u8 + 1]);
        bad[3][15] = START_DELIMITER;
        bad[4][11] = START_DELIMITER;
        bad[5][11] = 0x41;
        for src in &bad {
            assert_eq!(frame_in_window(src, &mut out), None, "{src:02X?}");
            check(src);
        }
    }

    proptest::proptest! {
        /// Agrees with the byte-at-a-time reference on any window: escapes (valid or
        /// not) and delimiters anywhere, lengths in and out of range.
        #[test]
        fn agrees_with_bytes(
            body in proptest::collection::vec(
                proptest::prop_oneof![
                    4 => proptest::prelude::any::<u8>(),
                    1 => proptest::sample::select(
                        &[ESCAPE, START_DELIMITER, 0x5E, 0x5D, 0x31, 0x33][..]
                    ),
                ],
                WINDOW_ROOM - DATA,
            ),
            len in 0usize..70,
        ) {
            let mut src = [0u8; WINDOW_ROOM];
            src[0] = START_DELIMITER;
            src[1..3].copy_from_slice(&(len as u16).to_be_bytes());
            src[DATA..].copy_from_slice(&body);
            check(&src);
        }
    }
}
