//! Explicit Addressing Command (0x11): sends RF data with explicit application-layer addressing (endpoints, cluster, profile).

use crate::frame::{be, check_frame, frame_type};
use crate::{Address16, Address64};
use crate::{EncodeFrame, FrameError};

/// Positions of the fields within the frame data (byte 0 is the frame type).
pub mod field {
    use core::ops::Range;
    /// Frame type byte.
    pub const FRAME_TYPE: usize = 0;
    /// Frame id: 0 asks for no Transmit Status.
    pub const FRAME_ID: usize = 1;
    /// 64-bit destination address.
    pub const DST64: Range<usize> = 2..10;
    /// 16-bit destination address ([`Address16::UNKNOWN`](crate::Address16::UNKNOWN) if unknown).
    pub const DST16: Range<usize> = 10..12;
    /// Source endpoint.
    pub const SRC_ENDPOINT: usize = 12;
    /// Destination endpoint.
    pub const DST_ENDPOINT: usize = 13;
    /// Cluster id.
    pub const CLUSTER_ID: Range<usize> = 14..16;
    /// Profile id.
    pub const PROFILE_ID: Range<usize> = 16..18;
    /// Broadcast radius in hops (0: maximum).
    pub const RADIUS: usize = 18;
    /// Transmit options bit field.
    pub const OPTIONS: usize = 19;
    /// RF data (payload). Runs to the end of the frame data.
    pub const DATA: core::ops::RangeFrom<usize> = 20..;
    /// Length of the fixed fields: the least frame data length.
    pub const HEADER_LEN: usize = 20;
}

/// A read-only view of Explicit Addressing Command (0x11) frame data, type byte included.
///
/// Build it with [`new_checked`](Self::new_checked); the accessors of a checked view
/// cannot panic. Turn it into owned fields with
/// [`ExplicitAddressingCommandRepr::parse`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ExplicitAddressingCommand<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> ExplicitAddressingCommand<T> {
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

    /// Checks the frame type byte (0x11) and that the fixed fields are present.
    pub fn check_len(&self) -> Result<(), FrameError> {
        check_frame(
            self.buffer.as_ref(),
            frame_type::EXPLICIT_ADDRESSING_COMMAND,
            field::HEADER_LEN,
        )
    }

    /// The wrapped buffer.
    pub fn into_inner(self) -> T {
        self.buffer
    }

    /// Frame id: 0 asks for no Transmit Status.
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

    /// Broadcast radius in hops (0: maximum).
    pub fn radius(&self) -> u8 {
        let d = self.buffer.as_ref();
        d[field::RADIUS]
    }

    /// Transmit options bit field.
    pub fn options(&self) -> u8 {
        let d = self.buffer.as_ref();
        d[field::OPTIONS]
    }
}

impl<'a> ExplicitAddressingCommand<&'a [u8]> {
    /// RF data (payload).
    pub fn data(&self) -> &'a [u8] {
        &self.buffer[field::DATA]
    }
}

/// The fields of a Explicit Addressing Command (0x11) frame: parse one from a view, or fill one
/// in and encode it with [`EncodeFrame`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ExplicitAddressingCommandRepr<'a> {
    /// Frame id: 0 asks for no Transmit Status.
    pub frame_id: u8,
    /// 64-bit destination address.
    pub dst64: Address64,
    /// 16-bit destination address ([`Address16::UNKNOWN`](crate::Address16::UNKNOWN) if unknown).
    pub dst16: Address16,
    /// Source endpoint.
    pub src_endpoint: u8,
    /// Destination endpoint.
    pub dst_endpoint: u8,
    /// Cluster id.
    pub cluster_id: u16,
    /// Profile id.
    pub profile_id: u16,
    /// Broadcast radius in hops (0: maximum).
    pub radius: u8,
    /// Transmit options bit field.
    pub options: u8,
    /// RF data (payload).
    pub data: &'a [u8],
}

impl<'a> ExplicitAddressingCommandRepr<'a> {
    /// The frame type, 0x11.
    pub const FRAME_TYPE: u8 = frame_type::EXPLICIT_ADDRESSING_COMMAND;

    /// Reads the fields of `frame`, checking it first.
    pub fn parse(frame: &ExplicitAddressingCommand<&'a [u8]>) -> Result<Self, FrameError> {
        frame.check_len()?;
        Ok(Self {
            frame_id: frame.frame_id(),
            dst64: frame.dst64(),
            dst16: frame.dst16(),
            src_endpoint: frame.src_endpoint(),
            dst_endpoint: frame.dst_endpoint(),
            cluster_id: frame.cluster_id(),
            profile_id: frame.profile_id(),
            radius: frame.radius(),
            options: frame.options(),
            data: frame.data(),
        })
    }

    /// Reads the fields of frame data (type byte included).
    pub fn parse_bytes(data: &'a [u8]) -> Result<Self, FrameError> {
        Self::parse(&ExplicitAddressingCommand::new_unchecked(data))
    }
}

impl EncodeFrame for ExplicitAddressingCommandRepr<'_> {
    fn frame_data_len(&self) -> usize {
        field::HEADER_LEN + self.data.len()
    }

    fn write_frame_data<F: FnMut(&[u8])>(&self, out: &mut F) {
        let mut h = [0u8; field::HEADER_LEN];
        h[field::FRAME_TYPE] = Self::FRAME_TYPE;
        h[field::FRAME_ID] = self.frame_id;
        h[field::DST64].copy_from_slice(&self.dst64.to_bytes());
        h[field::DST16].copy_from_slice(&self.dst16.to_bytes());
        h[field::SRC_ENDPOINT] = self.src_endpoint;
        h[field::DST_ENDPOINT] = self.dst_endpoint;
        h[field::CLUSTER_ID].copy_from_slice(&self.cluster_id.to_be_bytes());
        h[field::PROFILE_ID].copy_from_slice(&self.profile_id.to_be_bytes());
        h[field::RADIUS] = self.radius;
        h[field::OPTIONS] = self.options;
        out(&h);
        out(self.data);
    }
}
