//! The floor in API mode 1: frames by their length alone.

use super::{Header, State, unlikely};

/// Splits an API mode 1 stream into frames by their length field alone (see the
/// [module](super)). `N` is the largest frame data it holds; a longer length field sends
/// it back to hunting for a start delimiter.
///
/// ```
/// use perf::floor::LengthSplitter;
/// let mut splitter: LengthSplitter<64> = LengthSplitter::new();
/// let mut frames = Vec::new();
/// for byte in [0x00, 0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F, 0x7E, 0x00, 0x01, 0x8A, 0x75] {
///     if let Some(data) = splitter.push(byte) {
///         frames.push(data.to_vec());
///     }
/// }
/// assert_eq!(frames, [vec![0x8A, 0x06], vec![0x8A]]);
/// ```
#[derive(Debug, Clone)]
pub struct LengthSplitter<const N: usize> {
    buf: [u8; N],
    /// Where the next frame data byte goes while the frame's data comes in (it ends at
    /// `N`), else `N`: `push` stores a byte while `at < N` and does nothing else.
    at: usize,
    /// The frame's length.
    len: usize,
    header: Header,
}

impl<const N: usize> Default for LengthSplitter<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> LengthSplitter<N> {
    /// A splitter hunting for a start delimiter.
    pub const fn new() -> Self {
        Self {
            buf: [0; N],
            at: N,
            len: 0,
            header: Header::new(),
        }
    }

    /// Feeds one byte; returns the frame data of the frame its checksum byte ends.
    #[inline(always)]
    pub fn push(&mut self, byte: u8) -> Option<&[u8]> {
        let at = self.at;
        if at < N {
            self.buf[at] = byte;
            self.at = at + 1;
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

    /// One step of the state machine for a byte that is not frame data; where in the
    /// buffer the data of the frame it ends starts, if it is a checksum byte.
    #[inline(never)]
    fn step(&mut self, byte: u8) -> Option<usize> {
        if self.header.state == State::Data {
            self.header.state = State::Hunt;
            return Some(N - self.len);
        }
        self.len = self.header.step(byte, N)?;
        self.at = N - self.len;
        None
    }
}
