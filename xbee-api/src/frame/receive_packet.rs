//! Receive Packet (0x90): RF data received from a remote radio (radio to host).

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
    /// Receive options bit field (0x01 acknowledged, 0x02 broadcast...).
    pub const OPTIONS: usize = 11;
    /// RF data (payload). Runs to the end of the frame data.
    pub const DATA: core::ops::RangeFrom<usize> = 12..;
    /// Length of the fixed fields: the least frame data length.
    pub const HEADER_LEN: usize = 12;
}

/// Bits of the receive options field of a Zigbee XBee.
pub mod options {
    /// The packet was acknowledged (a unicast).
    pub const ACKNOWLEDGED: u8 = 0x01;
    /// The packet was a broadcast.
    pub const BROADCAST: u8 = 0x02;
    /// The packet was encrypted with APS encryption.
    pub const APS_ENCRYPTED: u8 = 0x20;
    /// The packet came from an end device.
    pub const FROM_END_DEVICE: u8 = 0x40;
}

/// A read-only view of Receive Packet (0x90) frame data, type byte included.
///
/// Build it with [`new_checked`](Self::new_checked); the accessors of a checked view
/// cannot panic. Turn it into owned fields with
/// [`ReceivePacketRepr::parse`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ReceivePacket<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> ReceivePacket<T> {
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

    /// Checks the frame type byte (0x90) and that the fixed fields are present.
    pub fn check_len(&self) -> Result<(), FrameError> {
        check_frame(
            self.buffer.as_ref(),
            frame_type::RECEIVE_PACKET,
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

    /// Receive options bit field (0x01 acknowledged, 0x02 broadcast...).
    pub fn options(&self) -> u8 {
        let d = self.buffer.as_ref();
        d[field::OPTIONS]
    }
}

impl<'a> ReceivePacket<&'a [u8]> {
    /// RF data (payload).
    #[inline]
    pub fn data(&self) -> &'a [u8] {
        &self.buffer[field::DATA]
    }
}

/// The fields of a Receive Packet (0x90) frame: parse one from a view, or fill one
/// in and encode it with [`EncodeFrame`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ReceivePacketRepr<'a> {
    /// 64-bit source address.
    pub src64: Address64,
    /// 16-bit source address.
    pub src16: Address16,
    /// Receive options bit field (0x01 acknowledged, 0x02 broadcast...).
    pub options: u8,
    /// RF data (payload).
    pub data: &'a [u8],
}

impl<'a> ReceivePacketRepr<'a> {
    /// The frame type, 0x90.
    pub const FRAME_TYPE: u8 = frame_type::RECEIVE_PACKET;
    /// Frame data before the RF data: type, addresses, options.
    pub const HEADER_LEN: usize = field::HEADER_LEN;
    /// The most frame data a radio hands over in a Receive Packet: the header and the
    /// largest RF data, 255 bytes
    /// ([`MAX_UNICAST_DATA_FRAGMENTED`](crate::TransmitRequestRepr::MAX_UNICAST_DATA_FRAGMENTED),
    /// sent in fragments and put back together by the receiving radio), 267 bytes in
    /// all. Size a decoder by it to take every payload a sender may send; a decoder
    /// sized for unfragmented payloads
    /// (`HEADER_LEN + TransmitRequestRepr::MAX_UNICAST_DATA`, 96 bytes) drops longer
    /// frames as [`DecodeError::Oversize`](crate::DecodeError::Oversize). With `AO=1`
    /// the radio hands over Explicit Rx Indicators instead, 6 bytes longer
    /// ([`ExplicitRxIndicatorRepr::MAX_LEN`](crate::ExplicitRxIndicatorRepr::MAX_LEN)).
    ///
    /// ```
    /// use xbee_api::{ApiMode, Decoder, Mode2, ReceivePacketRepr, decoder_buffer_len};
    /// type FirmwareDecoder =
    ///     Decoder<{ decoder_buffer_len(ReceivePacketRepr::MAX_LEN, ApiMode::Escaped) }, Mode2>;
    /// assert_eq!(FirmwareDecoder::fixed().capacity(), 267);
    /// ```
    pub const MAX_LEN: usize =
        field::HEADER_LEN + crate::TransmitRequestRepr::MAX_UNICAST_DATA_FRAGMENTED;

    /// Reads the fields of `frame`, checking it first.
    pub fn parse(frame: &ReceivePacket<&'a [u8]>) -> Result<Self, FrameError> {
        frame.check_len()?;
        Ok(Self {
            src64: frame.src64(),
            src16: frame.src16(),
            options: frame.options(),
            data: frame.data(),
        })
    }

    /// Reads the fields of frame data (type byte included).
    pub fn parse_bytes(data: &'a [u8]) -> Result<Self, FrameError> {
        Self::parse(&ReceivePacket::new_unchecked(data))
    }
}

impl EncodeFrame for ReceivePacketRepr<'_> {
    fn frame_data_len(&self) -> usize {
        field::HEADER_LEN + self.data.len()
    }

    fn write_frame_data<F: FnMut(&[u8])>(&self, out: &mut F) {
        let mut h = [0u8; field::HEADER_LEN];
        h[field::FRAME_TYPE] = Self::FRAME_TYPE;
        h[field::SRC64].copy_from_slice(&self.src64.to_bytes());
        h[field::SRC16].copy_from_slice(&self.src16.to_bytes());
        h[field::OPTIONS] = self.options;
        out(&h);
        out(self.data);
    }
}
