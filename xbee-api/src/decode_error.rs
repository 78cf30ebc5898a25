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
