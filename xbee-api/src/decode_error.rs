//! Errors a [`Decoder`](crate::Decoder) reports.

use core::fmt;

/// A candidate frame the [`Decoder`](crate::Decoder) dropped, and why.
///
/// None of these stops the decoder: it goes on with the next frame (see the
/// [`Decoder`](crate::Decoder) docs for where it resumes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum DecodeError {
    /// The checksum byte does not match the frame data.
    BadChecksum {
        /// Checksum computed from the frame data received.
        expected: u8,
        /// Checksum byte received.
        got: u8,
    },
    /// The length field is larger than the decoder can hold.
    Oversize {
        /// The length field (frame data bytes announced).
        length: u16,
        /// Largest frame data length this decoder holds in its mode.
        capacity: usize,
    },
    /// The length field is 0: a frame needs at least its type byte.
    EmptyFrame,
    /// The frame was cut off: by a new start delimiter (mode 2) or by the end of input
    /// ([`Decoder::finish`](crate::Decoder::finish)).
    Truncated {
        /// The length field, if it had been received.
        length: Option<u16>,
        /// Frame data bytes received before the cut.
        received: usize,
    },
    /// Mode 2: the byte after an escape (0x7D) is not an escaped special byte
    /// (0x5E, 0x5D, 0x31 or 0x33). A raw 0x7E after 0x7D is reported so too, and starts
    /// the next frame.
    BadEscape {
        /// The byte that followed 0x7D.
        byte: u8,
        /// Frame data bytes received before the escape.
        received: usize,
    },
}

impl DecodeError {
    /// A one-byte code of the error's kind, without its values:
    ///
    /// | code | error |
    /// |---|---|
    /// | 0x01 | [`BadChecksum`](Self::BadChecksum) |
    /// | 0x02 | [`Oversize`](Self::Oversize) |
    /// | 0x03 | [`EmptyFrame`](Self::EmptyFrame) |
    /// | 0x04 | [`Truncated`](Self::Truncated) |
    /// | 0x05 | [`BadEscape`](Self::BadEscape) |
    ///
    /// [`FrameError::code`](crate::FrameError::code) gives 0x11-0x14,
    /// [`EncodeError::code`](crate::EncodeError::code) 0x21-0x24, and `io::WriteError`'s
    /// 0x31-0x32.
    ///
    /// Codes are stable (one is never given to another error) and unique across `xbee-api`
    /// (0x01-0x3F) and `mcp-core` (0x40-0x7F), 0 being left for "no error": one byte says
    /// which error it was, for a debug UART or a status register, without the flash that
    /// formatting the message takes.
    ///
    /// ```
    /// use xbee_api::DecodeError;
    /// assert_eq!(DecodeError::EmptyFrame.code(), 0x03);
    /// ```
    pub const fn code(&self) -> u8 {
        match self {
            Self::BadChecksum { .. } => 0x01,
            Self::Oversize { .. } => 0x02,
            Self::EmptyFrame => 0x03,
            Self::Truncated { .. } => 0x04,
            Self::BadEscape { .. } => 0x05,
        }
    }
}

impl fmt::Display for DecodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::BadChecksum { expected, got } => write!(
                f,
                "bad checksum: computed 0x{expected:02X}, received 0x{got:02X}"
            ),
            Self::Oversize { length, capacity } => write!(
                f,
                "frame length {length} exceeds decoder capacity {capacity}"
            ),
            Self::EmptyFrame => f.write_str("frame length 0"),
            Self::Truncated {
                length: Some(length),
                received,
            } if *received >= usize::from(*length) => write!(
                f,
                "frame truncated before its checksum byte (all {length} data bytes received)"
            ),
            Self::Truncated {
                length: Some(length),
                received,
            } => write!(f, "frame truncated after {received} of {length} data bytes"),
            Self::Truncated {
                length: None,
                received: _,
            } => f.write_str("frame truncated in its length field"),
            Self::BadEscape { byte, received } => write!(
                f,
                "invalid escape 0x7D 0x{byte:02X} after {received} data bytes"
            ),
        }
    }
}

impl core::error::Error for DecodeError {}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::DecodeError;
    use std::string::ToString;

    #[test]
    fn each_error_has_its_own_code_in_the_crates_range() {
        use crate::{EncodeError, FrameError, NodeInfoError};
        let codes = [
            DecodeError::BadChecksum {
                expected: 1,
                got: 2,
            }
            .code(),
            DecodeError::Oversize {
                length: 300,
                capacity: 100,
            }
            .code(),
            DecodeError::EmptyFrame.code(),
            DecodeError::Truncated {
                length: None,
                received: 0,
            }
            .code(),
            DecodeError::BadEscape {
                byte: 0,
                received: 0,
            }
            .code(),
            FrameError::Empty.code(),
            FrameError::WrongType {
                expected: 0x90,
                found: 0x8B,
            }
            .code(),
            FrameError::TooShort {
                frame_type: 0x90,
                needed: 12,
                got: 3,
            }
            .code(),
            FrameError::BadNodeInfo {
                frame_type: 0x95,
                error: NodeInfoError::UnterminatedIdentifier,
            }
            .code(),
            EncodeError::BufferTooSmall {
                needed: 9,
                available: 8,
            }
            .code(),
            EncodeError::EmptyFrame.code(),
            EncodeError::FrameTooLong { len: 70_000 }.code(),
            EncodeError::LengthMismatch {
                announced: 3,
                written: 2,
            }
            .code(),
        ];
        assert_eq!(
            codes,
            [
                0x01, 0x02, 0x03, 0x04, 0x05, 0x11, 0x12, 0x13, 0x14, 0x21, 0x22, 0x23, 0x24
            ]
        );
    }

    #[test]
    fn a_frame_cut_before_its_checksum_says_so() {
        let cut = |received| DecodeError::Truncated {
            length: Some(2),
            received,
        };
        assert_eq!(
            cut(1).to_string(),
            "frame truncated after 1 of 2 data bytes"
        );
        assert_eq!(
            cut(2).to_string(),
            "frame truncated before its checksum byte (all 2 data bytes received)"
        );
    }
}
