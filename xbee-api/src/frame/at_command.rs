//! AT Command (0x08): queries or sets a parameter of the local radio; and AT Command -
//! Queue Parameter Value (0x09), the same fields, whose setting waits until an `AC`
//! command or the next 0x08 frame applies the queue.

use crate::frame::{be, check_frame, frame_type};
use crate::{EncodeFrame, FrameError};

/// Positions of the fields within the frame data (byte 0 is the frame type).
pub mod field {
    use core::ops::Range;
    /// Frame type byte.
    pub const FRAME_TYPE: usize = 0;
    /// Frame id: 0 asks for no response.
    pub const FRAME_ID: usize = 1;
    /// Two-character AT command, e.g. `*b"NJ"`.
    pub const COMMAND: Range<usize> = 2..4;
    /// Parameter value; empty to query. Runs to the end of the frame data.
    pub const PARAMETER: core::ops::RangeFrom<usize> = 4..;
    /// Length of the fixed fields: the least frame data length.
    pub const HEADER_LEN: usize = 4;
}

/// A read-only view of AT Command (0x08) or AT Command - Queue Parameter Value (0x09)
/// frame data, type byte included.
///
/// Build it with [`new_checked`](Self::new_checked); the accessors of a checked view
/// cannot panic. Turn it into owned fields with
/// [`AtCommandRepr::parse`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AtCommand<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> AtCommand<T> {
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

    /// Checks the frame type byte (0x08 or 0x09) and that the fixed fields are
    /// present. A wrong type is reported as expecting 0x08.
    pub fn check_len(&self) -> Result<(), FrameError> {
        let data = self.buffer.as_ref();
        let expected = match data.first() {
            Some(&frame_type::AT_COMMAND_QUEUE) => frame_type::AT_COMMAND_QUEUE,
            _ => frame_type::AT_COMMAND,
        };
        check_frame(data, expected, field::HEADER_LEN)
    }

    /// The wrapped buffer.
    pub fn into_inner(self) -> T {
        self.buffer
    }

    /// Whether this is a 0x09 frame: a setting is queued, not applied.
    pub fn queued(&self) -> bool {
        let d = self.buffer.as_ref();
        d[field::FRAME_TYPE] == frame_type::AT_COMMAND_QUEUE
    }

    /// Frame id: 0 asks for no response.
    pub fn frame_id(&self) -> u8 {
        let d = self.buffer.as_ref();
        d[field::FRAME_ID]
    }

    /// Two-character AT command, e.g. `*b"NJ"`.
    pub fn command(&self) -> [u8; 2] {
        let d = self.buffer.as_ref();
        be::<2>(&d[field::COMMAND])
    }
}

impl<'a> AtCommand<&'a [u8]> {
    /// Parameter value; empty to query.
    pub fn parameter(&self) -> &'a [u8] {
        &self.buffer[field::PARAMETER]
    }
}

/// An AT parameter's value as a number: big-endian, in as many bytes as it has (a radio
/// answers `AP` with one byte, `NT` with two, `SH` with four, and drops leading zeros);
/// `None` for no byte, or for more than eight.
///
/// ```
/// assert_eq!(xbee_api::at_number(&[0x02]), Some(2));
/// assert_eq!(xbee_api::at_number(&[0x00, 0x13, 0xA2, 0x00]), Some(0x0013_A200));
/// assert_eq!(xbee_api::at_number(&[]), None);
/// assert_eq!(xbee_api::at_number(&[1; 9]), None);
/// ```
pub fn at_number(value: &[u8]) -> Option<u64> {
    if value.is_empty() || value.len() > 8 {
        return None;
    }
    Some(value.iter().fold(0, |n, &b| (n << 8) | u64::from(b)))
}

/// The fields of an AT Command (0x08) or AT Command - Queue Parameter Value (0x09)
/// frame: parse one from a view, or fill one in and encode it with [`EncodeFrame`].
///
/// ```
/// use xbee_api::{AtCommandRepr, EncodeFrame};
/// // Queue a baud rate of 115200 (BD = 7), from Digi's manual.
/// let queue = AtCommandRepr { queued: true, frame_id: 1, command: *b"BD", parameter: &[7] };
/// let mut wire = [0u8; 16];
/// let n = queue.encode(xbee_api::ApiMode::Unescaped, &mut wire).unwrap();
/// assert_eq!(wire[..n], [0x7E, 0x00, 0x05, 0x09, 0x01, 0x42, 0x44, 0x07, 0x68]);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AtCommandRepr<'a> {
    /// A 0x09 frame: the setting is queued until `AC` (or the next 0x08 frame)
    /// applies it; a query is answered as by 0x08.
    pub queued: bool,
    /// Frame id: 0 asks for no response.
    pub frame_id: u8,
    /// Two-character AT command, e.g. `*b"NJ"`.
    pub command: [u8; 2],
    /// Parameter value; empty to query.
    pub parameter: &'a [u8],
}

impl<'a> AtCommandRepr<'a> {
    /// The frame type of a command applied at once, 0x08.
    pub const FRAME_TYPE: u8 = frame_type::AT_COMMAND;
    /// The frame type of a queued command, 0x09.
    pub const QUEUE_FRAME_TYPE: u8 = frame_type::AT_COMMAND_QUEUE;

    /// The frame type: 0x09 if [`queued`](Self::queued), else 0x08.
    pub const fn frame_type(&self) -> u8 {
        if self.queued {
            Self::QUEUE_FRAME_TYPE
        } else {
            Self::FRAME_TYPE
        }
    }

    /// Reads the fields of `frame`, checking it first.
    pub fn parse(frame: &AtCommand<&'a [u8]>) -> Result<Self, FrameError> {
        frame.check_len()?;
        Ok(Self {
            queued: frame.queued(),
            frame_id: frame.frame_id(),
            command: frame.command(),
            parameter: frame.parameter(),
        })
    }

    /// Reads the fields of frame data (type byte included).
    pub fn parse_bytes(data: &'a [u8]) -> Result<Self, FrameError> {
        Self::parse(&AtCommand::new_unchecked(data))
    }
}

impl EncodeFrame for AtCommandRepr<'_> {
    fn frame_data_len(&self) -> usize {
        field::HEADER_LEN + self.parameter.len()
    }

    fn write_frame_data<F: FnMut(&[u8])>(&self, out: &mut F) {
        let mut h = [0u8; field::HEADER_LEN];
        h[field::FRAME_TYPE] = self.frame_type();
        h[field::FRAME_ID] = self.frame_id;
        h[field::COMMAND].copy_from_slice(&self.command);
        out(&h);
        out(self.parameter);
    }
}
