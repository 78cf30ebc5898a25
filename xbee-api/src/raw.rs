//! The untyped view of one frame's data.

use crate::{EncodeFrame, FrameError};

/// The frame data of one API frame, untyped: the frame type byte followed by the
/// type-specific bytes (start delimiter, length and checksum stripped, escapes removed).
///
/// It is what [`Decoder`](crate::Decoder) yields; [`Frame::parse`](crate::Frame::parse)
/// types it. Copy the bytes out with [`RawFrame::data`].
///
/// ```
/// use xbee_api::RawFrame;
/// let raw = RawFrame::new(&[0x8A, 0x06]).unwrap();
/// assert_eq!(raw.frame_type(), 0x8A);
/// assert_eq!(raw.body(), &[0x06]);
/// assert!(RawFrame::new(&[]).is_err());
/// ```
///
/// In firmware, dispatch on [`frame_type`](Self::frame_type) and read the one view
/// you need over [`data`](Self::data) rather than call `Frame::parse`, which links the
/// parser of every frame type: on a Cortex-M3 (`opt-level = "s"`, LTO) a receive loop
/// that takes Receive Packets and Transmit Statuses through `Frame::parse` takes about
/// 1.9 KB more flash than one that reads their views.
///
/// ```
/// use xbee_api::{RawFrame, ReceivePacket, ReceivePacketRepr, TransmitStatus, TransmitStatusRepr};
/// let data = [0x90, 0x00, 0x13, 0xA2, 0x00, 0x40, 0x52, 0x2B, 0xAA, 0x7D, 0x84, 0x01,
///             b'c', 0x02, 0xFF];
/// let raw = RawFrame::new(&data).unwrap();
/// match raw.frame_type() {
///     ReceivePacketRepr::FRAME_TYPE => {
///         if let Ok(rx) = ReceivePacket::new_checked(raw.data()) {
///             assert_eq!(rx.data(), b"c\x02\xFF"); // the MCP payload, read in place
///         }
///     }
///     TransmitStatusRepr::FRAME_TYPE => {
///         if let Ok(status) = TransmitStatus::new_checked(raw.data()) {
///             let _ = status.delivery();
///         }
///     }
///     _ => {} // not needed
/// }
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RawFrame<'a> {
    data: &'a [u8],
}

impl<'a> RawFrame<'a> {
    /// Wraps frame data, which must hold at least the frame type byte.
    pub const fn new(data: &'a [u8]) -> Result<Self, FrameError> {
        if data.is_empty() {
            Err(FrameError::Empty)
        } else {
            Ok(Self { data })
        }
    }

    /// Wraps frame data known to be non-empty.
    pub(crate) const fn from_data(data: &'a [u8]) -> Self {
        Self { data }
    }

    /// The frame type (API identifier), byte 0 of the frame data.
    pub const fn frame_type(&self) -> u8 {
        // `new` guarantees a first byte; `first` keeps this panic-free regardless.
        match self.data.first() {
            Some(t) => *t,
            None => 0,
        }
    }

    /// The whole frame data: type byte and the rest.
    pub const fn data(&self) -> &'a [u8] {
        self.data
    }

    /// The frame data after the type byte.
    pub fn body(&self) -> &'a [u8] {
        self.data.get(1..).unwrap_or_default()
    }

    /// Frame data length, the value of the length field.
    pub const fn len(&self) -> usize {
        self.data.len()
    }

    /// Always false: a raw frame holds at least its type byte.
    pub const fn is_empty(&self) -> bool {
        self.data.is_empty()
    }
}

impl EncodeFrame for RawFrame<'_> {
    fn frame_data_len(&self) -> usize {
        self.data.len()
    }

    fn write_frame_data<F: FnMut(&[u8])>(&self, out: &mut F) {
        out(self.data);
    }
}
