//! Transmit Status (0x8B): the outcome of a Transmit Request or Explicit Addressing Command.

use crate::frame::{be, check_frame, frame_type};
use crate::{Address16, DeliveryStatus, DiscoveryStatus};
use crate::{EncodeFrame, FrameError};

/// Positions of the fields within the frame data (byte 0 is the frame type).
pub mod field {
    use core::ops::Range;
    /// Frame type byte.
    pub const FRAME_TYPE: usize = 0;
    /// Frame id of the request this answers.
    pub const FRAME_ID: usize = 1;
    /// 16-bit address the frame was delivered to.
    pub const DST16: Range<usize> = 2..4;
    /// Transmit retry count.
    pub const RETRIES: usize = 4;
    /// Delivery status.
    pub const DELIVERY: usize = 5;
    /// Discovery status.
    pub const DISCOVERY: usize = 6;
    /// Length of the fixed fields: the least frame data length.
    pub const HEADER_LEN: usize = 7;
}

/// A read-only view of Transmit Status (0x8B) frame data, type byte included.
///
/// Build it with [`new_checked`](Self::new_checked); the accessors of a checked view
/// cannot panic. Turn it into owned fields with
/// [`TransmitStatusRepr::parse`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TransmitStatus<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> TransmitStatus<T> {
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

    /// Checks the frame type byte (0x8B) and that the fixed fields are present.
    pub fn check_len(&self) -> Result<(), FrameError> {
        check_frame(
            self.buffer.as_ref(),
            frame_type::TRANSMIT_STATUS,
            field::HEADER_LEN,
        )
    }

    /// The wrapped buffer.
    pub fn into_inner(self) -> T {
        self.buffer
    }

    /// Frame id of the request this answers.
    pub fn frame_id(&self) -> u8 {
        let d = self.buffer.as_ref();
        d[field::FRAME_ID]
    }

    /// 16-bit address the frame was delivered to.
    pub fn dst16(&self) -> Address16 {
        let d = self.buffer.as_ref();
        Address16::from_bytes(be::<2>(&d[field::DST16]))
    }

    /// Transmit retry count.
    pub fn retries(&self) -> u8 {
        let d = self.buffer.as_ref();
        d[field::RETRIES]
    }

    /// Delivery status.
    pub fn delivery(&self) -> DeliveryStatus {
        let d = self.buffer.as_ref();
        DeliveryStatus::from(d[field::DELIVERY])
    }

    /// Discovery status.
    pub fn discovery(&self) -> DiscoveryStatus {
        let d = self.buffer.as_ref();
        DiscoveryStatus::from(d[field::DISCOVERY])
    }
}

/// The fields of a Transmit Status (0x8B) frame: parse one from a view, or fill one
/// in and encode it with [`EncodeFrame`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TransmitStatusRepr {
    /// Frame id of the request this answers.
    pub frame_id: u8,
    /// 16-bit address the frame was delivered to.
    pub dst16: Address16,
    /// Transmit retry count.
    pub retries: u8,
    /// Delivery status.
    pub delivery: DeliveryStatus,
    /// Discovery status.
    pub discovery: DiscoveryStatus,
}

impl TransmitStatusRepr {
    /// The frame type, 0x8B.
    pub const FRAME_TYPE: u8 = frame_type::TRANSMIT_STATUS;

    /// Reads the fields of `frame`, checking it first.
    pub fn parse(frame: &TransmitStatus<&[u8]>) -> Result<Self, FrameError> {
        frame.check_len()?;
        Ok(Self {
            frame_id: frame.frame_id(),
            dst16: frame.dst16(),
            retries: frame.retries(),
            delivery: frame.delivery(),
            discovery: frame.discovery(),
        })
    }

    /// Reads the fields of frame data (type byte included).
    pub fn parse_bytes(data: &[u8]) -> Result<Self, FrameError> {
        Self::parse(&TransmitStatus::new_unchecked(data))
    }
}

impl EncodeFrame for TransmitStatusRepr {
    fn frame_data_len(&self) -> usize {
        field::HEADER_LEN
    }

    fn write_frame_data<F: FnMut(&[u8])>(&self, out: &mut F) {
        let mut h = [0u8; field::HEADER_LEN];
        h[field::FRAME_TYPE] = Self::FRAME_TYPE;
        h[field::FRAME_ID] = self.frame_id;
        h[field::DST16].copy_from_slice(&self.dst16.to_bytes());
        h[field::RETRIES] = self.retries;
        h[field::DELIVERY] = u8::from(self.delivery);
        h[field::DISCOVERY] = u8::from(self.discovery);
        out(&h);
    }
}
