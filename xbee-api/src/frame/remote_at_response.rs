//! Remote AT Command Response (0x97): the answer of a remote radio to a Remote AT Command.

use crate::frame::{be, check_frame, frame_type};
use crate::{Address16, Address64, AtStatus};
use crate::{EncodeFrame, FrameError};

/// Positions of the fields within the frame data (byte 0 is the frame type).
pub mod field {
    use core::ops::Range;
    /// Frame type byte.
    pub const FRAME_TYPE: usize = 0;
    /// Frame id of the command this answers.
    pub const FRAME_ID: usize = 1;
    /// 64-bit address of the remote radio.
    pub const SRC64: Range<usize> = 2..10;
    /// 16-bit address of the remote radio.
    pub const SRC16: Range<usize> = 10..12;
    /// Two-character AT command.
    pub const COMMAND: Range<usize> = 12..14;
    /// Command status.
    pub const STATUS: usize = 14;
    /// Register data, if any. Runs to the end of the frame data.
    pub const DATA: core::ops::RangeFrom<usize> = 15..;
    /// Length of the fixed fields: the least frame data length.
    pub const HEADER_LEN: usize = 15;
}

/// A read-only view of Remote AT Command Response (0x97) frame data, type byte included.
///
/// Build it with [`new_checked`](Self::new_checked); the accessors of a checked view
/// cannot panic. Turn it into owned fields with
/// [`RemoteAtResponseRepr::parse`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[doc(alias = "RemoteAtCommandResponse")]
pub struct RemoteAtResponse<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> RemoteAtResponse<T> {
    /// Wraps frame data without checking it; accessors may panic unless
    /// [`check_len`](Self::check_len) passed.
    pub const fn new_unchecked(buffer: T) -> Self {
        Self { buffer }
    }

    /// Wraps frame data after [`check_len`](Self::check_len).
    pub fn new_checked(buffer: T) -> Result<Self, FrameError> {
        let frame = Self::new_unchecked(buffer);
        frame.check_len()?;
        Ok(frame)
    }

    /// Checks the frame type byte (0x97) and that the fixed fields are present.
    pub fn check_len(&self) -> Result<(), FrameError> {
        check_frame(
            self.buffer.as_ref(),
            frame_type::REMOTE_AT_RESPONSE,
            field::HEADER_LEN,
        )
    }

    /// The wrapped buffer.
    pub fn into_inner(self) -> T {
        self.buffer
    }

    /// Frame id of the command this answers.
    pub fn frame_id(&self) -> u8 {
        let d = self.buffer.as_ref();
        d[field::FRAME_ID]
    }

    /// 64-bit address of the remote radio.
    pub fn src64(&self) -> Address64 {
        let d = self.buffer.as_ref();
        Address64::from_bytes(be::<8>(&d[field::SRC64]))
    }

    /// 16-bit address of the remote radio.
    pub fn src16(&self) -> Address16 {
        let d = self.buffer.as_ref();
        Address16::from_bytes(be::<2>(&d[field::SRC16]))
    }

    /// Two-character AT command.
    pub fn command(&self) -> [u8; 2] {
        let d = self.buffer.as_ref();
        be::<2>(&d[field::COMMAND])
    }

    /// Command status.
    pub fn status(&self) -> AtStatus {
        let d = self.buffer.as_ref();
        AtStatus::from(d[field::STATUS])
    }
}

impl<'a> RemoteAtResponse<&'a [u8]> {
    /// Register data, if any.
    pub fn data(&self) -> &'a [u8] {
        &self.buffer[field::DATA]
    }
}

/// The fields of a Remote AT Command Response (0x97) frame: parse one from a view, or fill one
/// in and encode it with [`EncodeFrame`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RemoteAtResponseRepr<'a> {
    /// Frame id of the command this answers.
    pub frame_id: u8,
    /// 64-bit address of the remote radio.
    pub src64: Address64,
    /// 16-bit address of the remote radio.
    pub src16: Address16,
    /// Two-character AT command.
    pub command: [u8; 2],
    /// Command status.
    pub status: AtStatus,
    /// Register data, if any.
    pub data: &'a [u8],
}

impl<'a> RemoteAtResponseRepr<'a> {
    /// The frame type, 0x97.
    pub const FRAME_TYPE: u8 = frame_type::REMOTE_AT_RESPONSE;

    /// Reads the fields of `frame`, checking it first.
    pub fn parse(frame: &RemoteAtResponse<&'a [u8]>) -> Result<Self, FrameError> {
        frame.check_len()?;
        Ok(Self {
            frame_id: frame.frame_id(),
            src64: frame.src64(),
            src16: frame.src16(),
            command: frame.command(),
            status: frame.status(),
            data: frame.data(),
        })
    }

    /// Reads the fields of frame data (type byte included).
    pub fn parse_bytes(data: &'a [u8]) -> Result<Self, FrameError> {
        Self::parse(&RemoteAtResponse::new_unchecked(data))
    }
}

impl EncodeFrame for RemoteAtResponseRepr<'_> {
    fn frame_data_len(&self) -> usize {
        field::HEADER_LEN + self.data.len()
    }

    fn write_frame_data<F: FnMut(&[u8])>(&self, out: &mut F) {
        let mut h = [0u8; field::HEADER_LEN];
        h[field::FRAME_TYPE] = Self::FRAME_TYPE;
        h[field::FRAME_ID] = self.frame_id;
        h[field::SRC64].copy_from_slice(&self.src64.to_bytes());
        h[field::SRC16].copy_from_slice(&self.src16.to_bytes());
        h[field::COMMAND].copy_from_slice(&self.command);
        h[field::STATUS] = u8::from(self.status);
        out(&h);
        out(self.data);
    }
}
