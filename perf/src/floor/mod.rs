//! The least a byte-at-a-time XBee decoder can do, as a floor to measure `push` against.
//!
//! [`LengthSplitter`] (API mode 1) and [`EscapedSplitter`] (API mode 2) split a stream
//! into frames by their length field and do nothing else: no checksum, no resync after
//! a bad frame, no counters, and in mode 2 no test for a raw 0x7E inside a frame. They
//! are not decoders (a bad byte in the stream loses every frame after it); they show
//! what one call a byte costs before any of that work, with the same loop around them as
//! [`Decoder::push`](xbee_api::Decoder::push) has in [`run_push`](crate::run::run_push).
//!
//! Their frame data bytes take the shortest path a byte can take when a call handles
//! one byte and the splitter lives in memory between calls (as a decoder does in an
//! interrupt handler, and as any decoder does whose rarer bytes go through a call): the
//! cursor loaded, compared with a constant, the byte stored, the cursor stored back.
//! The frame data is stored so that it ends at the end of the buffer, so that "the
//! frame's data is still coming" is the cursor below the buffer's size, which is also
//! all the compiler needs to know that the store is in bounds. In mode 2 the byte is
//! also compared with 0x7D, the escape. The start delimiter, the length bytes, escapes
//! and the checksum byte take one step of a state machine, as in `push`: out of line in
//! mode 1; in line in mode 2 but for the checksum byte, which ends the frame through a
//! call.

mod escaped;
mod unescaped;

pub use escaped::EscapedSplitter;
pub use unescaped::LengthSplitter;

use xbee_api::wire::START_DELIMITER;

/// Where a splitter is in a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum State {
    /// Before a start delimiter.
    Hunt,
    /// After the start delimiter.
    LenHi,
    /// After the length's high byte.
    LenLo,
    /// After the length field: frame data while the splitter's cursor is below its
    /// size, then the checksum byte.
    Data,
}

/// The start delimiter and the length field, which both splitters read alike.
#[derive(Debug, Clone)]
struct Header {
    state: State,
    /// The length field's high byte.
    hi: u8,
}

impl Header {
    /// Hunting for a start delimiter.
    const fn new() -> Self {
        Self {
            state: State::Hunt,
            hi: 0,
        }
    }

    /// Takes a byte (unescaped) before the frame data: the frame's length once its
    /// length field is read, if it is at most `max` (else back to hunting). Takes
    /// nothing in [`State::Data`].
    #[inline(always)]
    fn step(&mut self, byte: u8, max: usize) -> Option<usize> {
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
                if len <= max {
                    self.state = State::Data;
                    return Some(len);
                }
                self.state = State::Hunt;
            }
            State::Data => {}
        }
        None
    }
}

/// Marks the path that calls it as the rare one, so that the compiler lays out the other
/// straight on, as `xbee_api`'s decoder does.
#[cold]
#[inline(never)]
fn unlikely() {}
