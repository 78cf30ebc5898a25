//! Transmit Request (0x10): sends RF data to a destination (host to radio).

use crate::frame::{be, check_frame, frame_type};
use crate::{Address16, Address64};
use crate::{EncodeFrame, FrameError};

/// Positions of the fields within the frame data (byte 0 is the frame type).
pub mod field {
    use core::ops::Range;
    /// Frame type byte.
    pub const FRAME_TYPE: usize = 0;
    /// Frame id: 0 asks for no Transmit Status, 1..=255 match one.
    pub const FRAME_ID: usize = 1;
    /// 64-bit destination address.
    pub const DST64: Range<usize> = 2..10;
    /// 16-bit destination address ([`Address16::UNKNOWN`](crate::Address16::UNKNOWN) if unknown).
    pub const DST16: Range<usize> = 10..12;
    /// Broadcast radius in hops (0: maximum).
    pub const RADIUS: usize = 12;
    /// Transmit options bit field.
    pub const OPTIONS: usize = 13;
    /// RF data (payload). Runs to the end of the frame data.
    pub const DATA: core::ops::RangeFrom<usize> = 14..;
    /// Length of the fixed fields: the least frame data length.
    pub const HEADER_LEN: usize = 14;
}

/// Bits of the transmit options field of a Zigbee XBee.
pub mod options {
    /// Disable retries and route repair (what the deployed MAV sends).
    pub const DISABLE_RETRIES: u8 = 0x01;
    /// Enable APS end-to-end encryption (shortens the largest payload: by 4 bytes on
    /// older Zigbee modules, by 9 on XBee 3; `AT NP` reads the radio's own limit).
    pub const APS_ENCRYPTION: u8 = 0x20;
    /// Use the extended transmission timeout.
    pub const EXTENDED_TIMEOUT: u8 = 0x40;
}

/// A read-only view of Transmit Request (0x10) frame data, type byte included.
///
/// Build it with [`new_checked`](Self::new_checked); the accessors of a checked view
/// cannot panic. Turn it into owned fields with
/// [`TransmitRequestRepr::parse`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TransmitRequest<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> TransmitRequest<T> {
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

    /// Checks the frame type byte (0x10) and that the fixed fields are present.
    pub fn check_len(&self) -> Result<(), FrameError> {
        check_frame(
            self.buffer.as_ref(),
            frame_type::TRANSMIT_REQUEST,
            field::HEADER_LEN,
        )
    }

    /// The wrapped buffer.
    pub fn into_inner(self) -> T {
        self.buffer
    }

    /// Frame id: 0 asks for no Transmit Status, 1..=255 match one.
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

impl<'a> TransmitRequest<&'a [u8]> {
    /// RF data (payload).
    pub fn data(&self) -> &'a [u8] {
        &self.buffer[field::DATA]
    }
}

/// The fields of a Transmit Request (0x10) frame: parse one from a view, or fill one
/// in and encode it with [`EncodeFrame`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TransmitRequestRepr<'a> {
    /// Frame id: 0 asks for no Transmit Status, 1..=255 match one.
    pub frame_id: u8,
    /// 64-bit destination address.
    pub dst64: Address64,
    /// 16-bit destination address ([`Address16::UNKNOWN`](crate::Address16::UNKNOWN) if unknown).
    pub dst16: Address16,
    /// Broadcast radius in hops (0: maximum).
    pub radius: u8,
    /// Transmit options bit field.
    pub options: u8,
    /// RF data (payload).
    pub data: &'a [u8],
}

impl<'a> TransmitRequestRepr<'a> {
    /// The frame type, 0x10.
    pub const FRAME_TYPE: u8 = frame_type::TRANSMIT_REQUEST;
    /// Frame data before the RF data: type, frame id, addresses, radius, options.
    pub const HEADER_LEN: usize = field::HEADER_LEN;
    /// The most RF data a unicast carries in one radio packet, without
    /// fragmentation: `NP` of a Zigbee XBee (84 bytes; less with APS encryption or
    /// source routing). A longer unicast goes out in fragments, up to
    /// [`MAX_UNICAST_DATA_FRAGMENTED`](Self::MAX_UNICAST_DATA_FRAGMENTED): more
    /// airtime, and lost whole if one fragment is. Size a MAV's packets by this to keep
    /// each in one radio packet.
    pub const MAX_UNICAST_DATA: usize = 84;
    /// The most RF data a unicast carries with fragmentation; longer ones fail with
    /// delivery status 0x74, payload too large.
    pub const MAX_UNICAST_DATA_FRAGMENTED: usize = 255;
    /// The most RF data a broadcast carries.
    pub const MAX_BROADCAST_DATA: usize = 92;

    /// A unicast of `data` to `dst64`, with the defaults: frame id 0 (no Transmit
    /// Status), 16-bit address unknown (FFFE), the largest radius, no options. Change
    /// a field with struct update syntax.
    ///
    /// ```
    /// use xbee_api::{Address64, TransmitRequestRepr, transmit_options};
    /// // What the deployed MAV sends: to the coordinator, without retries.
    /// let request = TransmitRequestRepr {
    ///     options: transmit_options::DISABLE_RETRIES,
    ///     ..TransmitRequestRepr::unicast(Address64::COORDINATOR, b"t")
    /// };
    /// assert_eq!(request.frame_id, 0);
    /// assert_eq!(request.dst16, xbee_api::Address16::UNKNOWN);
    /// ```
    pub const fn unicast(dst64: Address64, data: &'a [u8]) -> Self {
        TransmitRequestRepr {
            frame_id: 0,
            dst64,
            dst16: Address16::UNKNOWN,
            radius: 0,
            options: 0,
            data,
        }
    }

    /// An answer to the radio a Receive Packet came from: `data` to its 64-bit and
    /// 16-bit addresses (the 16-bit one known, so the radio skips address discovery),
    /// frame id 0, radius and options 0, as [`unicast`](Self::unicast).
    ///
    /// ```
    /// use xbee_api::{Address16, Frame, TransmitRequestRepr};
    /// // Digi's Receive Packet example.
    /// let data = [0x90, 0x00, 0x13, 0xA2, 0x00, 0x40, 0x52, 0x2B, 0xAA, 0x7D, 0x84, 0x01,
    ///             b'R', b'x', b'D', b'a', b't', b'a'];
    /// let Ok(Frame::ReceivePacket(rx)) = Frame::parse_bytes(&data) else { unreachable!() };
    /// let answer = TransmitRequestRepr::reply(&rx, b"ack");
    /// assert_eq!((answer.dst64, answer.dst16), (rx.src64, Address16(0x7D84)));
    /// assert_eq!((answer.frame_id, answer.data), (0, &b"ack"[..]));
    /// ```
    pub const fn reply(to: &crate::ReceivePacketRepr<'_>, data: &'a [u8]) -> Self {
        Self::reply_to(to.src64, to.src16, data)
    }

    /// [`reply`](Self::reply) to the addresses a Receive Packet came from, kept after
    /// its frame is gone (a firmware's interrupt handler copies them out with the
    /// payload, and its main loop answers).
    ///
    /// ```
    /// use xbee_api::{Address16, Address64, TransmitRequestRepr};
    /// let (src64, src16) = (Address64(0x0013_A200_4052_2BAA), Address16(0x7D84));
    /// let answer = TransmitRequestRepr::reply_to(src64, src16, b"ack");
    /// assert_eq!((answer.dst64, answer.dst16, answer.frame_id), (src64, src16, 0));
    /// ```
    pub const fn reply_to(src64: Address64, src16: Address16, data: &'a [u8]) -> Self {
        TransmitRequestRepr {
            dst16: src16,
            ..Self::unicast(src64, data)
        }
    }

    /// Reads the fields of `frame`, checking it first.
    pub fn parse(frame: &TransmitRequest<&'a [u8]>) -> Result<Self, FrameError> {
        frame.check_len()?;
        Ok(Self {
            frame_id: frame.frame_id(),
            dst64: frame.dst64(),
            dst16: frame.dst16(),
            radius: frame.radius(),
            options: frame.options(),
            data: frame.data(),
        })
    }

    /// Reads the fields of frame data (type byte included).
    pub fn parse_bytes(data: &'a [u8]) -> Result<Self, FrameError> {
        Self::parse(&TransmitRequest::new_unchecked(data))
    }
}

impl EncodeFrame for TransmitRequestRepr<'_> {
    fn frame_data_len(&self) -> usize {
        field::HEADER_LEN + self.data.len()
    }

    fn write_frame_data<F: FnMut(&[u8])>(&self, out: &mut F) {
        let mut h = [0u8; field::HEADER_LEN];
        h[field::FRAME_TYPE] = Self::FRAME_TYPE;
        h[field::FRAME_ID] = self.frame_id;
        h[field::DST64].copy_from_slice(&self.dst64.to_bytes());
        h[field::DST16].copy_from_slice(&self.dst16.to_bytes());
        h[field::RADIUS] = self.radius;
        h[field::OPTIONS] = self.options;
        out(&h);
        out(self.data);
    }
}
