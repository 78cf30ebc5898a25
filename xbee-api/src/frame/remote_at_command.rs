//! Remote AT Command (0x17): queries or sets a parameter of a remote radio.

use crate::frame::{be, check_frame, frame_type};
use crate::{Address16, Address64};
use crate::{EncodeFrame, FrameError};

/// Positions of the fields within the frame data (byte 0 is the frame type).
pub mod field {
    use core::ops::Range;
    /// Frame type byte.
    pub const FRAME_TYPE: usize = 0;
    /// Frame id: 0 asks for no response.
    pub const FRAME_ID: usize = 1;
    /// 64-bit destination address.
    pub const DST64: Range<usize> = 2..10;
    /// 16-bit destination address ([`Address16::UNKNOWN`](crate::Address16::UNKNOWN) if unknown).
    pub const DST16: Range<usize> = 10..12;
    /// Remote command options (0x02: apply changes).
    pub const OPTIONS: usize = 12;
    /// Two-character AT command.
    pub const COMMAND: Range<usize> = 13..15;
    /// Parameter value; empty to query. Runs to the end of the frame data.
    pub const PARAMETER: core::ops::RangeFrom<usize> = 15..;
    /// Length of the fixed fields: the least frame data length.
    pub const HEADER_LEN: usize = 15;
}

/// A read-only view of Remote AT Command (0x17) frame data, type byte included.
///
/// Build it with [`new_checked`](Self::new_checked); the accessors of a checked view
/// cannot panic. Turn it into owned fields with
/// [`RemoteAtCommandRepr::parse`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RemoteAtCommand<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> RemoteAtCommand<T> {
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

    /// Checks the frame type byte (0x17) and that the fixed fields are present.
    pub fn check_len(&self) -> Result<(), FrameError> {
        check_frame(
            self.buffer.as_ref(),
            frame_type::REMOTE_AT_COMMAND,
            field::HEADER_LEN,
        )
    }

    /// The wrapped buffer.
    pub fn into_inner(self) -> T {
        self.buffer
    }

    /// Frame id: 0 asks for no response.
    pub fn frame_id(&self) -> u8 {
        let d = self.buffer.as_ref();
        d[field::FRAME_ID]
    }

    /// 64-bit destination address.
    pub fn dst64(&self) -> Address64 {
        let d = self.buffer.as_ref();
        Address64::from_bytes(be::<8>(&d[field::DST64]))
    }

    /// 16-bit destination address ([`Address16::UNKNOWN`](crate::Address16::UNKNOWN) if unknown).
    pub fn dst16(&self) -> Address16 {
        let d = self.buffer.as_ref();
        Address16::from_bytes(be::<2>(&d[field::DST16]))
    }

    /// Remote command options (0x02: apply changes).
    pub fn options(&self) -> u8 {
        let d = self.buffer.as_ref();
        d[field::OPTIONS]
    }

    /// Two-character AT command.
    pub fn command(&self) -> [u8; 2] {
        let d = self.buffer.as_ref();
        be::<2>(&d[field::COMMAND])
    }
}

impl<'a> RemoteAtCommand<&'a [u8]> {
    /// Parameter value; empty to query.
    pub fn parameter(&self) -> &'a [u8] {
        &self.buffer[field::PARAMETER]
    }
}

/// The fields of a Remote AT Command (0x17) frame: parse one from a view, or fill one
/// in and encode it with [`EncodeFrame`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RemoteAtCommandRepr<'a> {
    /// Frame id: 0 asks for no response.
    pub frame_id: u8,
    /// 64-bit destination address.
    pub dst64: Address64,
    /// 16-bit destination address ([`Address16::UNKNOWN`](crate::Address16::UNKNOWN) if unknown).
    pub dst16: Address16,
    /// Remote command options ([`APPLY_CHANGES`](Self::APPLY_CHANGES), 0x02: apply
    /// changes).
    pub options: u8,
    /// Two-character AT command.
    pub command: [u8; 2],
    /// Parameter value; empty to query.
    pub parameter: &'a [u8],
}

impl<'a> RemoteAtCommandRepr<'a> {
    /// The frame type, 0x17.
    pub const FRAME_TYPE: u8 = frame_type::REMOTE_AT_COMMAND;

    /// The option bit that has the remote radio apply the change at once, with any it
    /// has queued; without it, changes wait for an `AC` command (or a later command with
    /// this option).
    pub const APPLY_CHANGES: u8 = 0x02;

    /// Reads the fields of `frame`, checking it first.
    pub fn parse(frame: &RemoteAtCommand<&'a [u8]>) -> Result<Self, FrameError> {
        frame.check_len()?;
        Ok(Self {
            frame_id: frame.frame_id(),
            dst64: frame.dst64(),
            dst16: frame.dst16(),
            options: frame.options(),
            command: frame.command(),
            parameter: frame.parameter(),
        })
    }

    /// Reads the fields of frame data (type byte included).
    pub fn parse_bytes(data: &'a [u8]) -> Result<Self, FrameError> {
        Self::parse(&RemoteAtCommand::new_unchecked(data))
    }
}

impl EncodeFrame for RemoteAtCommandRepr<'_> {
    fn frame_data_len(&self) -> usize {
        field::HEADER_LEN + self.parameter.len()
    }

    fn write_frame_data<F: FnMut(&[u8])>(&self, out: &mut F) {
        let mut h = [0u8; field::HEADER_LEN];
        h[field::FRAME_TYPE] = Self::FRAME_TYPE;
        h[field::FRAME_ID] = self.frame_id;
        h[field::DST64].copy_from_slice(&self.dst64.to_bytes());
        h[field::DST16].copy_from_slice(&self.dst16.to_bytes());
        h[field::OPTIONS] = self.options;
        h[field::COMMAND].copy_from_slice(&self.command);
        out(&h);
        out(self.parameter);
    }
}
