//! The floor in API mode 2: frames by their length, escapes undone.

use xbee_api::wire::{ESCAPE, ESCAPE_XOR};

use super::{Header, State, unlikely};

/// Splits an API mode 2 stream into frames by their length field, undoing escapes (see
/// the [module](super)). `N` is the largest frame data it holds; a longer length field
/// sends it back to hunting for a start delimiter.
///
/// ```
/// use perf::floor::EscapedSplitter;
/// let mut splitter: EscapedSplitter<64> = EscapedSplitter::new();
/// let mut frames = Vec::new();
/// // A frame whose data holds an escaped 0x13, and one whose checksum (0x7D) is escaped.
/// for byte in [0x00, 0x7E, 0x00, 0x02, 0x8A, 0x7D, 0x33, 0x62,
///              0x7E, 0x00, 0x01, 0x82, 0x7D, 0x5D] {
///     if let Some(data) = splitter.push(byte) {
///         frames.push(data.to_vec());
///     }
/// }
/// assert_eq!(frames, [vec![0x8A, 0x13], vec![0x82]]);
/// ```
#[derive(Debug, Clone)]
pub struct EscapedSplitter<const N: usize> {
    buf: [u8; N],
    /// Where the next frame data byte goes while the frame's data comes in (it ends at
    /// `N`), else `N`; `N` more while the byte after an escape is awaited. `push` stores
    /// a byte other than 0x7D while `at < N` and does nothing else.
    at: usize,
    /// The frame's length.
    len: usize,
    header: Header,
    /// The byte before was an escape.
    escaped: bool,
}

impl<const N: usize> Default for EscapedSplitter<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> EscapedSplitter<N> {
    /// A splitter hunting for a start delimiter.
    pub const fn new() -> Self {
        Self {
            buf: [0; N],
            at: N,
            len: 0,
            header: Header::new(),
            escaped: false,
        }
    }

    /// Feeds one byte; returns the frame data of the frame its checksum byte ends.
    #[inline(always)]
    pub fn push(&mut self, byte: u8) -> Option<&[u8]> {
        let at = self.at;
        if at < N {
            if byte != ESCAPE {
                self.buf[at] = byte;
                self.at = at + 1;
            } else {
                // An escape inside the frame data: the next byte goes to `step`.
                self.escaped = true;
                self.at = at + N;
            }
            return None;
        }
        // As in `push`: on ARM the mark keeps the store straight on; not on x86-64,
        // where it costs more than it saves.
        if cfg!(target_arch = "arm") {
            unlikely();
        }
        let from = self.step(byte)?;
        self.buf.get(from..)
    }

    /// One step of the state machine for a byte that is not plain frame data; where in
    /// the buffer the data of the frame it ends starts, if it is a checksum byte.
    #[inline(always)]
    fn step(&mut self, raw: u8) -> Option<usize> {
        let byte = if self.escaped {
            self.escaped = false;
            self.at -= N;
            raw ^ ESCAPE_XOR
        } else if raw == ESCAPE && self.header.state != State::Hunt {
            // `at == N` here (an escape in the frame data is taken by `push`): the next
            // byte comes to this step whatever it is.
            self.escaped = true;
            self.at += N;
            return None;
        } else {
            raw
        };
        if self.header.state != State::Data {
            self.len = self.header.step(byte, N)?;
            self.at = N - self.len;
            return None;
        }
        match self.buf.get_mut(self.at) {
            // An escaped byte of frame data.
            Some(slot) => {
                *slot = byte;
                self.at += 1;
                None
            }
            // The checksum byte.
            None => self.end_frame(),
        }
    }

    /// Ends the frame at its checksum byte: where its data starts in the buffer. Out of
    /// line, as `push` checks the checksum: nothing but this call keeps the compiler
    /// from holding the splitter's fields in registers from byte to byte, which an
    /// interrupt handler cannot do.
    #[inline(never)]
    fn end_frame(&mut self) -> Option<usize> {
        self.header.state = State::Hunt;
        Some(N - self.len)
    }
}
