//! Explicit Rx Indicator (0x91): RF data received with its application-layer addressing (`AO` = 1).

use crate::frame::{be, check_frame, frame_type};
use crate::{Address16, Address64};
use crate::{EncodeFrame, FrameError};

/// Positions of the fields within the frame data (byte 0 is the frame type).
pub mod field {
    use core::ops::Range;
    /// Frame type byte.
    pub const FRAME_TYPE: usize = 0;
    /// 64-bit source address.
    pub const SRC64: Range<usize> = 1..9;
    /// 16-bit source address.
    pub const SRC16: Range<usize> = 9..11;
    /// Source endpoint.
    pub const SRC_ENDPOINT: usize = 11;
    /// Destination endpoint.
    pub const DST_ENDPOINT: usize = 12;
    /// Cluster id.
    pub const CLUSTER_ID: Range<usize> = 13..15;
    /// Profile id.
    pub const PROFILE_ID: Range<usize> = 15..17;
    /// Receive options bit field.
    pub const OPTIONS: usize = 17;
    /// RF data (payload). Runs to the end of the frame data.
    pub const DATA: core::ops::RangeFrom<usize> = 18..;
    /// Length of the fixed fields: the least frame data length.
    pub const HEADER_LEN: usize = 18;
}

/// A read-only view of Explicit Rx Indicator (0x91) frame data, type byte included.
///
/// Build it with [`new_checked`](Self::new_checked); the accessors of a checked view
/// cannot panic. Turn it into owned fields with
/// [`ExplicitRxIndicatorRepr::parse`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ExplicitRxIndicator<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> ExplicitRxIndicator<T> {
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

    /// Checks the frame type byte (0x91) and that the fixed fields are present.
    pub fn check_len(&self) -> Result<(), FrameError> {
        check_frame(
            self.buffer.as_ref(),
            frame_type::EXPLICIT_RX_INDICATOR,
            field::HEADER_LEN,
        )
    }

    /// The wrapped buffer.
    pub fn into_inner(self) -> T {
        self.buffer
    }

    /// 64-bit source address.
    pub fn src64(&self) -> Address64 {
        let d = self.buffer.as_ref();
        Address64::from_bytes(be::<8>(&d[field::SRC64]))
    }

    /// 16-bit source address.
    pub fn src16(&self) -> Address16 {
        let d = self.buffer.as_ref();
        Address16::from_bytes(be::<2>(&d[field::SRC16]))
    }

    /// Source endpoint.
    pub fn src_endpoint(&self) -> u8 {
        let d = self.buffer.as_ref();
        d[field::SRC_ENDPOINT]
    }

    /// Destination endpoint.
    pub fn dst_endpoint(&self) -> u8 {
        let d = self.buffer.as_ref();
        d[field::DST_ENDPOINT]
    }

    /// Cluster id.
    pub fn cluster_id(&self) -> u16 {
        let d = self.buffer.as_ref();
        u16::from_be_bytes(be::<2>(&d[field::CLUSTER_ID]))
    }

    /// Profile id.
    pub fn profile_id(&self) -> u16 {
        let d = self.buffer.as_ref();
        u16::from_be_bytes(be::<2>(&d[field::PROFILE_ID]))
    }

    /// Receive options bit field.
    pub fn options(&self) -> u8 {
        let d = self.buffer.as_ref();
        d[field::OPTIONS]
    }
}

impl<'a> ExplicitRxIndicator<&'a [u8]> {
    /// RF data (payload).
    pub fn data(&self) -> &'a [u8] {
        &self.buffer[field::DATA]
    }
}

/// The fields of a Explicit Rx Indicator (0x91) frame: parse one from a view, or fill one
/// in and encode it with [`EncodeFrame`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ExplicitRxIndicatorRepr<'a> {
    /// 64-bit source address.
    pub src64: Address64,
    /// 16-bit source address.
    pub src16: Address16,
    /// Source endpoint.
    pub src_endpoint: u8,
    /// Destination endpoint.
    pub dst_endpoint: u8,
    /// Cluster id.
    pub cluster_id: u16,
    /// Profile id.
    pub profile_id: u16,
    /// Receive options bit field.
    pub options: u8,
    /// RF data (payload).
    pub data: &'a [u8],
}

impl<'a> ExplicitRxIndicatorRepr<'a> {
    /// The frame type, 0x91.
    pub const FRAME_TYPE: u8 = frame_type::EXPLICIT_RX_INDICATOR;
    /// Frame data before the RF data: type, addresses, endpoints, cluster and profile
    /// ids, options.
    pub const HEADER_LEN: usize = field::HEADER_LEN;
    /// The most frame data a radio hands over in an Explicit Rx Indicator (what it
    /// sends for received RF data with `AO=1`): the header and the largest RF data, 255
    /// bytes
    /// ([`MAX_UNICAST_DATA_FRAGMENTED`](crate::TransmitRequestRepr::MAX_UNICAST_DATA_FRAGMENTED),
    /// sent in fragments and put back together by the receiving radio), 273 bytes in
    /// all: the longest frame data that received RF data comes in. Size a decoder by it
    /// to take every payload a sender may send, whatever the radio's `AO` setting.
    ///
    /// ```
    /// use xbee_api::{ApiMode, Decoder, ExplicitRxIndicatorRepr, Mode1, decoder_buffer_len};
    /// const N: usize = decoder_buffer_len(ExplicitRxIndicatorRepr::MAX_LEN, ApiMode::Unescaped);
    /// assert_eq!(N, 277);
    /// assert_eq!(Decoder::<N, Mode1>::fixed().capacity(), 273);
    /// ```
    pub const MAX_LEN: usize =
        field::HEADER_LEN + crate::TransmitRequestRepr::MAX_UNICAST_DATA_FRAGMENTED;

    /// Reads the fields of `frame`, checking it first.
    pub fn parse(frame: &ExplicitRxIndicator<&'a [u8]>) -> Result<Self, FrameError> {
        frame.check_len()?;
        Ok(Self {
            src64: frame.src64(),
            src16: frame.src16(),
            src_endpoint: frame.src_endpoint(),
            dst_endpoint: frame.dst_endpoint(),
            cluster_id: frame.cluster_id(),
            profile_id: frame.profile_id(),
            options: frame.options(),
            data: frame.data(),
        })
    }

    /// Reads the fields of frame data (type byte included).
    pub fn parse_bytes(data: &'a [u8]) -> Result<Self, FrameError> {
        Self::parse(&ExplicitRxIndicator::new_unchecked(data))
    }
}

impl EncodeFrame for ExplicitRxIndicatorRepr<'_> {
    fn frame_data_len(&self) -> usize {
        field::HEADER_LEN + self.data.len()
    }

    fn write_frame_data<F: FnMut(&[u8])>(&self, out: &mut F) {
        let mut h = [0u8; field::HEADER_LEN];
        h[field::FRAME_TYPE] = Self::FRAME_TYPE;
        h[field::SRC64].copy_from_slice(&self.src64.to_bytes());
        h[field::SRC16].copy_from_slice(&self.src16.to_bytes());
        h[field::SRC_ENDPOINT] = self.src_endpoint;
        h[field::DST_ENDPOINT] = self.dst_endpoint;
        h[field::CLUSTER_ID].copy_from_slice(&self.cluster_id.to_be_bytes());
        h[field::PROFILE_ID].copy_from_slice(&self.profile_id.to_be_bytes());
        h[field::OPTIONS] = self.options;
        out(&h);
        out(self.data);
    }
}
