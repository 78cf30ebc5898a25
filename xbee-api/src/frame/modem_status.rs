//! Modem Status (0x8A): an event of the local radio (reset, joined, coordinator started...).

use crate::ModemStatus;
use crate::frame::{check_frame, frame_type};
use crate::{EncodeFrame, FrameError};

/// Positions of the fields within the frame data (byte 0 is the frame type).
pub mod field {

    /// Frame type byte.
    pub const FRAME_TYPE: usize = 0;
    /// Modem status.
    pub const STATUS: usize = 1;
    /// Length of the fixed fields: the least frame data length.
    pub const HEADER_LEN: usize = 2;
}

/// A read-only view of Modem Status (0x8A) frame data, type byte included.
///
/// Build it with [`new_checked`](Self::new_checked); the accessors of a checked view
/// cannot panic. Turn it into owned fields with
/// [`ModemStatusRepr::parse`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ModemStatusFrame<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> ModemStatusFrame<T> {
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

    /// Checks the frame type byte (0x8A) and that the fixed fields are present.
    pub fn check_len(&self) -> Result<(), FrameError> {
        check_frame(
            self.buffer.as_ref(),
            frame_type::MODEM_STATUS,
            field::HEADER_LEN,
        )
    }

    /// The wrapped buffer.
    pub fn into_inner(self) -> T {
        self.buffer
    }

    /// Modem status.
    pub fn status(&self) -> ModemStatus {
        let d = self.buffer.as_ref();
        ModemStatus::from(d[field::STATUS])
    }
}

/// The fields of a Modem Status (0x8A) frame: parse one from a view, or fill one
/// in and encode it with [`EncodeFrame`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ModemStatusRepr {
    /// Modem status.
    pub status: ModemStatus,
}

impl ModemStatusRepr {
    /// The frame type, 0x8A.
    pub const FRAME_TYPE: u8 = frame_type::MODEM_STATUS;

    /// Reads the fields of `frame`, checking it first.
    pub fn parse(frame: &ModemStatusFrame<&[u8]>) -> Result<Self, FrameError> {
        frame.check_len()?;
        Ok(Self {
            status: frame.status(),
        })
    }

    /// Reads the fields of frame data (type byte included).
    pub fn parse_bytes(data: &[u8]) -> Result<Self, FrameError> {
        Self::parse(&ModemStatusFrame::new_unchecked(data))
    }
}

impl EncodeFrame for ModemStatusRepr {
    fn frame_data_len(&self) -> usize {
        field::HEADER_LEN
    }

    fn write_frame_data<F: FnMut(&[u8])>(&self, out: &mut F) {
        let mut h = [0u8; field::HEADER_LEN];
        h[field::FRAME_TYPE] = Self::FRAME_TYPE;
        h[field::STATUS] = u8::from(self.status);
        out(&h);
    }
}
