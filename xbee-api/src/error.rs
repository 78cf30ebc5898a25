//! Errors of frame views and encoders.

use core::fmt;

/// Why frame data is not a valid frame of the expected type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum FrameError {
    /// The frame data is empty: there is not even a frame type byte.
    Empty,
    /// The frame type byte is not the one the view is for.
    WrongType {
        /// Frame type the view expects.
        expected: u8,
        /// Frame type found (frame data byte 0).
        found: u8,
    },
    /// The frame data is shorter than the fixed fields of its frame type.
    TooShort {
        /// The frame type.
        frame_type: u8,
        /// Least frame data length (type byte included) this frame type takes.
        needed: usize,
        /// Frame data length received.
        got: usize,
    },
    /// The node information a frame carries (a Node Identification Indicator's) does
    /// not read: its identifier has no 0x00 after it, or bytes are left over.
    BadNodeInfo {
        /// The frame type.
        frame_type: u8,
        /// What is wrong with the node information.
        error: crate::NodeInfoError,
    },
}

impl FrameError {
    /// A one-byte code of the error's kind, without its values:
    ///
    /// | code | error |
    /// |---|---|
    /// | 0x11 | [`Empty`](Self::Empty) |
    /// | 0x12 | [`WrongType`](Self::WrongType) |
    /// | 0x13 | [`TooShort`](Self::TooShort) |
    /// | 0x14 | [`BadNodeInfo`](Self::BadNodeInfo) |
    ///
    /// As [`DecodeError::code`](crate::DecodeError::code) says, codes are stable and
    /// unique across `xbee-api` and `mcp-core`.
    pub const fn code(&self) -> u8 {
        match self {
            Self::Empty => 0x11,
            Self::WrongType { .. } => 0x12,
            Self::TooShort { .. } => 0x13,
            Self::BadNodeInfo { .. } => 0x14,
        }
    }
}

impl fmt::Display for FrameError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Empty => f.write_str("empty frame data"),
            Self::WrongType { expected, found } => {
                write!(f, "frame type 0x{found:02X}, expected 0x{expected:02X}")
            }
            Self::TooShort {
                frame_type,
                needed,
                got,
            } => write!(
                f,
                "frame type 0x{frame_type:02X} needs at least {needed} bytes of frame data, got {got}"
            ),
            Self::BadNodeInfo { frame_type, error } => {
                write!(f, "frame type 0x{frame_type:02X}: {error}")
            }
        }
    }
}

impl core::error::Error for FrameError {}

/// Why a frame could not be encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum EncodeError {
    /// The output buffer is shorter than the encoded frame.
    BufferTooSmall {
        /// Bytes the encoded frame takes.
        needed: usize,
        /// Bytes the buffer has.
        available: usize,
    },
    /// The frame has no frame data, not even a frame type byte: a radio (and
    /// [`Decoder`](crate::Decoder)) drops a frame whose length field is 0.
    EmptyFrame,
    /// The frame data is longer than the 16-bit length field (0xFFFF bytes) can say.
    FrameTooLong {
        /// Frame data length.
        len: usize,
    },
    /// An [`EncodeFrame`](crate::EncodeFrame) implementation wrote a different number of
    /// bytes than its `frame_data_len` announced.
    LengthMismatch {
        /// Length announced.
        announced: usize,
        /// Bytes written.
        written: usize,
    },
}

impl EncodeError {
    /// A one-byte code of the error's kind, without its values:
    ///
    /// | code | error |
    /// |---|---|
    /// | 0x21 | [`BufferTooSmall`](Self::BufferTooSmall) |
    /// | 0x22 | [`EmptyFrame`](Self::EmptyFrame) |
    /// | 0x23 | [`FrameTooLong`](Self::FrameTooLong) |
    /// | 0x24 | [`LengthMismatch`](Self::LengthMismatch) |
    ///
    /// As [`DecodeError::code`](crate::DecodeError::code) says, codes are stable and
    /// unique across `xbee-api` and `mcp-core`.
    pub const fn code(&self) -> u8 {
        match self {
            Self::BufferTooSmall { .. } => 0x21,
            Self::EmptyFrame => 0x22,
            Self::FrameTooLong { .. } => 0x23,
            Self::LengthMismatch { .. } => 0x24,
        }
    }
}

impl fmt::Display for EncodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::BufferTooSmall { needed, available } => {
                write!(f, "buffer too small: need {needed} bytes, have {available}")
            }
            Self::EmptyFrame => write!(f, "frame data is empty (no frame type byte)"),
            Self::FrameTooLong { len } => {
                write!(
                    f,
                    "frame data of {len} bytes exceeds the 65535-byte maximum"
                )
            }
            Self::LengthMismatch { announced, written } => write!(
                f,
                "frame data writer wrote {written} bytes, announced {announced}"
            ),
        }
    }
}

impl core::error::Error for EncodeError {}
