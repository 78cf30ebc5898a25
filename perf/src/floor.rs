//! The least a byte-at-a-time XBee decoder can do, as a floor to measure `push` against.
//!
//! [`LengthSplitter`] splits an API mode 1 stream into frames by their length field and
//! does nothing else: no checksum, no escapes, no resync after a bad frame, no counters.
//! It is not a decoder (a bad byte in the stream loses every frame after it); it shows
//! what one call a byte costs before any of that work, with the same loop around it as
//! [`Decoder::push`](xbee_api::Decoder::push) has in [`run_push`](crate::run::run_push).
//!
//! Its frame data bytes take the path that plain frame data takes in `push`, without the
//! test of the byte: the cursor loaded from the splitter, compared with the frame's end,
//! the byte stored, the cursor stored back (the splitter lives in memory between calls,
//! as a decoder does in an interrupt handler, and as any decoder does whose rarer bytes
//! go through a call). The start delimiter, the length bytes and the checksum byte take
//! one step of a state machine out of line, as in `push`.

use xbee_api::wire::START_DELIMITER;

/// Marks the path that calls it as the rare one, so that the compiler lays out the other
/// straight on, as `xbee_api`'s decoder does.
#[cold]
#[inline(never)]
fn unlikely() {}

/// Where [`LengthSplitter`] is in a frame, for the bytes that are not frame data.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum State {
    /// Before a start delimiter.
    Hunt,
    /// After the start delimiter.
    LenHi,
    /// After the length's high byte.
    LenLo,
    /// After the frame data: the checksum byte is next.
    Checksum,
}

/// Splits an API mode 1 stream into frames by their length field alone (see the
/// [module](self)). `N`, a power of two, is the largest frame data it holds; a longer
/// length field sends it back to hunting for a start delimiter.
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
    /// Frame data bytes stored.
    at: usize,
    /// The frame's length while its data comes in, else 0: `push` stores a byte while
    /// `at < end` and does nothing else.
    end: usize,
    /// The length field's high byte.
    hi: u8,
    state: State,
}

impl<const N: usize> Default for LengthSplitter<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> LengthSplitter<N> {
    /// A splitter hunting for a start delimiter. `N` must be a power of two.
    pub const fn new() -> Self {
        const {
            assert!(
                N.is_power_of_two(),
                "LengthSplitter size N must be a power of two"
            )
        };
        Self {
            buf: [0; N],
            at: 0,
            end: 0,
            hi: 0,
            state: State::Hunt,
        }
    }

    /// Feeds one byte; returns the frame data of the frame its checksum byte ends.
    #[inline(always)]
    pub fn push(&mut self, byte: u8) -> Option<&[u8]> {
        let at = self.at;
        if at < self.end {
            // `at < end <= N`: the mask changes nothing but shows the index in bounds.
            self.buf[at & (N - 1)] = byte;
            self.at = at + 1;
            return None;
        }
        // As in `push`: on ARM the mark keeps the store straight on; not on x86-64,
        // where it costs more than it saves.
        if cfg!(target_arch = "arm") {
            unlikely();
        }
        let len = self.step(byte)?;
        self.buf.get(..len)
    }

    /// One step of the state machine for a byte that is not frame data; the length of
    /// the frame it ends, if it is a checksum byte.
    #[inline(never)]
    fn step(&mut self, byte: u8) -> Option<usize> {
        match self.state {
            State::Hunt => {
                if byte == START_DELIMITER {
                    self.state = State::LenHi;
                }
            }
            State::LenHi => {
                self.hi = byte;
                self.state = State::LenLo;
            }
            State::LenLo => {
                let len = usize::from(u16::from_be_bytes([self.hi, byte]));
                if len <= N {
                    self.at = 0;
                    self.end = len;
                    self.state = State::Checksum;
                } else {
                    self.state = State::Hunt;
                }
            }
            State::Checksum => {
                self.state = State::Hunt;
                let len = self.end;
                self.end = 0;
                return Some(len);
            }
        }
        None
    }
}
