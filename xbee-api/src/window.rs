//! API mode 2 unescaping of a short frame in one 64-byte window (64-bit targets).
//!
//! A frame whose data and checksum byte lie, escapes included, within the 64 bytes after
//! its length field (an MCP telemetry frame of 8 values takes about 55) is unescaped
//! with no loop over steps: the 64 bytes are copied to the buffer and scanned at once
//! into one mask of escapes and one of start delimiters (16 bytes a compare), and each
//! escape inside the frame moves what follows it one byte down. One branch a frame, one
//! an escape, whatever the data.

use wide::u8x16;

use crate::wire::{ESCAPE, ESCAPE_XOR, START_DELIMITER, needs_escape};

/// Bytes the window covers.
pub(crate) const WINDOW: usize = 64;

/// Bytes of input and of buffer [`frame_in_window`] needs: each escape copies the 64
/// bytes after it.
pub(crate) const WINDOW_ROOM: usize = 2 * WINDOW + 2;

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

/// Unescapes the frame that starts at `src[0]` (a start delimiter) into `out` when the
/// whole of it lies in the first [`WINDOW`] bytes of `src` and its length field is plain
/// and from 1 to [`MAX_LEN`]; writes all of `out[..WINDOW_ROOM]`.
///
/// `None` if the frame runs past the window, or has an escaped length field, a start
/// delimiter inside it or an invalid escape: the caller then takes a path that reports
/// what went wrong or takes longer frames.
#[inline(always)]
pub(crate) fn frame_in_window(
    src: &[u8; WINDOW_ROOM],
    out: &mut [u8; WINDOW_ROOM],
) -> Option<WindowFrame> {
    let steps = load(src);
    for (step, to) in steps.iter().zip(out.chunks_exact_mut(16)) {
        to.copy_from_slice(step.as_array_ref());
    }
    let mut escapes = mask(&steps, ESCAPE);
    let [_, hi, lo, ..] = *src;
    let len = usize::from(u16::from_be_bytes([hi, lo]));
    // An escape in the length field, or a length out of range.
    if escapes & 0b110 != 0 || len.wrapping_sub(1) >= MAX_LEN {
        return None;
    }
    // The data and the checksum byte end before `end + k` after `k` escapes.
    let end = DATA + len + 1;
    let mut k = 0;
    // What the escapes add to the sum of the raw bytes.
    let mut adjust = 0u8;
    while escapes != 0 {
        let i = escapes.trailing_zeros() as usize;
        if i - k >= end {
            break;
        }
        let raw = *src.get(i + 1)?;
        let byte = raw ^ ESCAPE_XOR;
        if !needs_escape(byte) {
            return None;
        }
        // `k <= i < 64`: the mask changes nothing but spares the bounds tests.
        let o = (i - k) % WINDOW;
        *out.get_mut(o)? = byte;
        let tail = src.get(i + 2..)?.first_chunk::<WINDOW>()?;
        out.get_mut(o + 1..)?
            .first_chunk_mut::<WINDOW>()?
            .copy_from_slice(tail);
        adjust = adjust.wrapping_add(byte.wrapping_sub(raw).wrapping_sub(ESCAPE));
        k += 1;
        escapes &= escapes - 1;
    }
    let taken = end + k;
    // Past the window, or cut off by a start delimiter (bit 0 is its own).
    if taken > WINDOW || mask(&steps, START_DELIMITER) & (u64::MAX >> (WINDOW - taken)) != 1 {
        return None;
    }
    // The raw bytes before the frame data are not summed, and what the escapes add is.
    let header = START_DELIMITER.wrapping_add(hi).wrapping_add(lo);
    let total = sum_first(&steps, taken)
        .wrapping_add(adjust)
        .wrapping_sub(header);
    Some(WindowFrame { taken, len, total })
}

/// The window's four steps of 16 bytes.
#[inline(always)]
fn load(src: &[u8; WINDOW_ROOM]) -> [u8x16; 4] {
    core::array::from_fn(|j| {
        let step = src
            .get(16 * j..16 * j + 16)
            .and_then(|s| s.first_chunk::<16>());
        u8x16::new(step.copied().unwrap_or_default())
    })
}

/// Bit `k` set where byte `k` of the window is `byte`.
#[inline(always)]
fn mask(steps: &[u8x16; 4], byte: u8) -> u64 {
    steps.iter().enumerate().fold(0, |acc, (j, step)| {
        let bits = step.cmp_eq(u8x16::splat(byte)).move_mask() as u16;
        acc | u64::from(bits) << (16 * j)
    })
}

/// Wrapping sum of the first `k` (at most 64) bytes of the window.
#[inline(always)]
fn sum_first(steps: &[u8x16; 4], k: usize) -> u8 {
    let keep = KEEP.get(WINDOW - k..).unwrap_or_default();
    let mut lanes = u8x16::ZERO;
    for (j, step) in steps.iter().enumerate() {
        let m = keep
            .get(16 * j..16 * j + 16)
            .and_then(|m| m.first_chunk::<16>());
        lanes += *step & u8x16::new(m.copied().unwrap_or_default());
    }
    reduce(lanes)
}

/// Wrapping sum of the 16 lanes: one `psadbw` (SSE2's sum of absolute differences,
/// here against zero) on x86-64, where left to itself the compiler may add the lanes
/// one by one.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn reduce(lanes: u8x16) -> u8 {
    use safe_arch::{m128i, sum_of_u8_abs_diff_m128i, zeroed_m128i};
    let halves: [u64; 2] =
        sum_of_u8_abs_diff_m128i(m128i::from(lanes.to_array()), zeroed_m128i()).into();
    halves[0].wrapping_add(halves[1]) as u8
}

/// Wrapping sum of the 16 lanes.
#[cfg(not(target_arch = "x86_64"))]
#[inline(always)]
fn reduce(lanes: u8x16) -> u8 {
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
        let mut bad = [ok; 7];
        bad[0][2] = ESCAPE;
        bad[1][1..3].copy_from_slice(&[0, 0]);
        bad[2][1..3].copy_from_slice(&[0, MAX_LEN as u8 + 1]);
        bad[3][15] = START_DELIMITER;
        bad[4][11] = START_DELIMITER;
        bad[5][11] = 0x41;
        bad[6][0] = 0x41;
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
