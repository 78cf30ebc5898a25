//! Typed API frames: one module per frame type, each with a view over the frame data
//! (`new_checked`/`check_len`, a `field` module of byte positions, accessors) and a
//! `*Repr` holding the fields that parses from the view and encodes with
//! [`EncodeFrame`]; plus [`Frame`], the enum over all of them.

use crate::{Address64, EncodeFrame, FrameError, RawFrame};

pub mod at_command;
pub mod at_command_response;
pub mod explicit_addressing_command;
pub mod explicit_rx_indicator;
pub mod modem_status;
pub mod node_identification_indicator;
pub mod receive_packet;
pub mod remote_at_command;
pub mod remote_at_response;
pub mod transmit_request;
pub mod transmit_status;

/// Frame type bytes (API identifiers): those of the typed frames, and of the other
/// requests that take a frame id and their answers; which frame type answers which
/// request ([`answer_type`](frame_type::answer_type)).
pub mod frame_type {
    /// TX Request, 64-bit address (802.15.4 radios), answered by a [`TX_STATUS`].
    pub const TX_REQUEST_64: u8 = 0x00;
    /// TX Request, 16-bit address (802.15.4 radios), answered by a [`TX_STATUS`].
    pub const TX_REQUEST_16: u8 = 0x01;
    /// AT Command.
    pub const AT_COMMAND: u8 = 0x08;
    /// AT Command - Queue Parameter Value.
    pub const AT_COMMAND_QUEUE: u8 = 0x09;
    /// Transmit Request.
    pub const TRANSMIT_REQUEST: u8 = 0x10;
    /// Explicit Addressing Command.
    pub const EXPLICIT_ADDRESSING_COMMAND: u8 = 0x11;
    /// Remote AT Command.
    pub const REMOTE_AT_COMMAND: u8 = 0x17;
    /// Transmit Request IPv4 (Wi-Fi and Cellular radios), answered by a [`TX_STATUS`].
    pub const TX_REQUEST_IPV4: u8 = 0x20;
    /// Register Joining Device (Zigbee trust centre), answered by a
    /// [`REGISTER_JOINING_DEVICE_STATUS`].
    pub const REGISTER_JOINING_DEVICE: u8 = 0x24;
    /// AT Command Response.
    pub const AT_COMMAND_RESPONSE: u8 = 0x88;
    /// TX Status: the delivery status of an 802.15.4 or IPv4 transmit request.
    pub const TX_STATUS: u8 = 0x89;
    /// Modem Status.
    pub const MODEM_STATUS: u8 = 0x8A;
    /// Transmit Status.
    pub const TRANSMIT_STATUS: u8 = 0x8B;
    /// Receive Packet.
    pub const RECEIVE_PACKET: u8 = 0x90;
    /// Explicit Rx Indicator.
    pub const EXPLICIT_RX_INDICATOR: u8 = 0x91;
    /// Node Identification Indicator.
    pub const NODE_IDENTIFICATION_INDICATOR: u8 = 0x95;
    /// Remote AT Command Response.
    pub const REMOTE_AT_RESPONSE: u8 = 0x97;
    /// Register Joining Device Status.
    pub const REGISTER_JOINING_DEVICE_STATUS: u8 = 0xA4;

    /// The frame type of the answer to a request of type `frame_type`, which carries
    /// the request's frame id (byte 1 of every request and of its answer); `None` for
    /// a frame type that is no request answered so.
    ///
    /// ```
    /// use xbee_api::frame::frame_type::{self, answer_type};
    /// assert_eq!(answer_type(frame_type::AT_COMMAND), Some(frame_type::AT_COMMAND_RESPONSE));
    /// assert_eq!(answer_type(frame_type::TRANSMIT_REQUEST), Some(frame_type::TRANSMIT_STATUS));
    /// assert_eq!(answer_type(frame_type::RECEIVE_PACKET), None);
    /// ```
    pub const fn answer_type(frame_type: u8) -> Option<u8> {
        match frame_type {
            TX_REQUEST_64 | TX_REQUEST_16 | TX_REQUEST_IPV4 => Some(TX_STATUS),
            AT_COMMAND | AT_COMMAND_QUEUE => Some(AT_COMMAND_RESPONSE),
            TRANSMIT_REQUEST | EXPLICIT_ADDRESSING_COMMAND => Some(TRANSMIT_STATUS),
            REMOTE_AT_COMMAND => Some(REMOTE_AT_RESPONSE),
            REGISTER_JOINING_DEVICE => Some(REGISTER_JOINING_DEVICE_STATUS),
            _ => None,
        }
    }

    /// Whether a frame of `frame_type` answers a request under its frame id: one that
    /// [`answer_type`] gives.
    pub const fn is_answer(frame_type: u8) -> bool {
        matches!(
            frame_type,
            TX_STATUS
                | AT_COMMAND_RESPONSE
                | TRANSMIT_STATUS
                | REMOTE_AT_RESPONSE
                | REGISTER_JOINING_DEVICE_STATUS
        )
    }

    /// Whether byte 1 of a frame of `frame_type` is a frame id: a request of
    /// [`answer_type`], or its answer.
    pub const fn carries_frame_id(frame_type: u8) -> bool {
        answer_type(frame_type).is_some() || is_answer(frame_type)
    }

    /// Whether a frame of `frame_type` is one a radio sends, never one it takes: the
    /// API identifiers of responses and indications have the high bit set (0x88 AT
    /// Command Response, 0x90 Receive Packet...), those of requests not.
    pub const fn is_from_radio(frame_type: u8) -> bool {
        frame_type & 0x80 != 0
    }
}

use at_command::AtCommandRepr;
use at_command_response::AtCommandResponseRepr;
use explicit_addressing_command::ExplicitAddressingCommandRepr;
use explicit_rx_indicator::ExplicitRxIndicatorRepr;
use modem_status::ModemStatusRepr;
use node_identification_indicator::NodeIdentificationIndicatorRepr;
use receive_packet::ReceivePacketRepr;
use remote_at_command::RemoteAtCommandRepr;
use remote_at_response::RemoteAtResponseRepr;
use transmit_request::TransmitRequestRepr;
use transmit_status::TransmitStatusRepr;

/// Checks the type byte and the least length of frame data.
pub(crate) fn check_frame(data: &[u8], expected: u8, needed: usize) -> Result<(), FrameError> {
    let Some(&found) = data.first() else {
        return Err(FrameError::Empty);
    };
    if found != expected {
        return Err(FrameError::WrongType { expected, found });
    }
    if data.len() < needed {
        return Err(FrameError::TooShort {
            frame_type: found,
            needed,
            got: data.len(),
        });
    }
    Ok(())
}

/// Copies a field of exactly `N` bytes into an array (zeros if the length differs, which
/// the field ranges rule out).
pub(crate) fn be<const N: usize>(bytes: &[u8]) -> [u8; N] {
    bytes.try_into().unwrap_or([0; N])
}

/// Any API frame, typed when this crate knows its type, borrowed from the frame data.
///
/// Parse one from a [`RawFrame`] (as the [`Decoder`](crate::Decoder) yields) with
/// [`Frame::parse`]; encode one with [`EncodeFrame`]. Frame types this crate does not
/// know pass through intact as [`Frame::Unknown`].
///
/// ```
/// use xbee_api::{Address64, Frame, RawFrame};
/// // Receive Packet from Digi's manual.
/// let data = [0x90, 0x00, 0x13, 0xA2, 0x00, 0x40, 0x52, 0x2B, 0xAA, 0x7D, 0x84, 0x01,
///             b'R', b'x', b'D', b'a', b't', b'a'];
/// match Frame::parse(RawFrame::new(&data).unwrap()).unwrap() {
///     Frame::ReceivePacket(rx) => {
///         assert_eq!(rx.src64, Address64(0x0013A20040522BAA));
///         assert_eq!(rx.data, b"RxData");
///     }
///     other => panic!("unexpected {other:?}"),
/// }
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum Frame<'a> {
    /// 0x10 Transmit Request.
    TransmitRequest(TransmitRequestRepr<'a>),
    /// 0x90 Receive Packet.
    ReceivePacket(ReceivePacketRepr<'a>),
    /// 0x8B Transmit Status.
    TransmitStatus(TransmitStatusRepr),
    /// 0x08 AT Command, or 0x09 AT Command - Queue Parameter Value when
    /// [`queued`](AtCommandRepr::queued).
    AtCommand(AtCommandRepr<'a>),
    /// 0x88 AT Command Response.
    AtCommandResponse(AtCommandResponseRepr<'a>),
    /// 0x8A Modem Status.
    ModemStatus(ModemStatusRepr),
    /// 0x11 Explicit Addressing Command.
    ExplicitAddressingCommand(ExplicitAddressingCommandRepr<'a>),
    /// 0x91 Explicit Rx Indicator.
    ExplicitRxIndicator(ExplicitRxIndicatorRepr<'a>),
    /// 0x17 Remote AT Command.
    RemoteAtCommand(RemoteAtCommandRepr<'a>),
    /// 0x97 Remote AT Command Response.
    RemoteAtResponse(RemoteAtResponseRepr<'a>),
    /// 0x95 Node Identification Indicator.
    NodeIdentificationIndicator(NodeIdentificationIndicatorRepr<'a>),
    /// A frame type this crate does not model, kept intact: [`Frame::parse`] yields it
    /// for every type byte that no other variant stands for.
    ///
    /// It is not meant for the modelled types. One built by hand with such a type byte
    /// (0x8B, say) encodes as given, but its frame data parses back as that type's
    /// variant ([`Frame::TransmitStatus`]), or fails to parse when it is too short for
    /// that type, so it does not round-trip.
    Unknown {
        /// The frame type byte, one this crate does not model.
        frame_type: u8,
        /// The frame data after the type byte.
        data: &'a [u8],
    },
}

impl<'a> Frame<'a> {
    /// Types a raw frame. Fails with [`FrameError::TooShort`] when the data is shorter
    /// than the fixed fields of its (known) type, and with [`FrameError::BadNodeInfo`]
    /// for a Node Identification Indicator (0x95) whose node information does not read
    /// (see [`NodeInfo::parse`](crate::NodeInfo::parse)); never panics.
    ///
    /// It links the parser of every frame type. In firmware, dispatch on
    /// [`RawFrame::frame_type`] and read the one view you need instead
    /// (`ReceivePacket::new_checked(raw.data())`, as [`RawFrame`] shows): on a Cortex-M3
    /// that saves about 1.9 KB of flash in a receive loop.
    pub fn parse(raw: RawFrame<'a>) -> Result<Self, FrameError> {
        let data = raw.data();
        Ok(match raw.frame_type() {
            frame_type::TRANSMIT_REQUEST => {
                Self::TransmitRequest(TransmitRequestRepr::parse_bytes(data)?)
            }
            frame_type::RECEIVE_PACKET => {
                Self::ReceivePacket(ReceivePacketRepr::parse_bytes(data)?)
            }
            frame_type::TRANSMIT_STATUS => {
                Self::TransmitStatus(TransmitStatusRepr::parse_bytes(data)?)
            }
            frame_type::AT_COMMAND | frame_type::AT_COMMAND_QUEUE => {
                Self::AtCommand(AtCommandRepr::parse_bytes(data)?)
            }
            frame_type::AT_COMMAND_RESPONSE => {
                Self::AtCommandResponse(AtCommandResponseRepr::parse_bytes(data)?)
            }
            frame_type::MODEM_STATUS => Self::ModemStatus(ModemStatusRepr::parse_bytes(data)?),
            frame_type::EXPLICIT_ADDRESSING_COMMAND => {
                Self::ExplicitAddressingCommand(ExplicitAddressingCommandRepr::parse_bytes(data)?)
            }
            frame_type::EXPLICIT_RX_INDICATOR => {
                Self::ExplicitRxIndicator(ExplicitRxIndicatorRepr::parse_bytes(data)?)
            }
            frame_type::REMOTE_AT_COMMAND => {
                Self::RemoteAtCommand(RemoteAtCommandRepr::parse_bytes(data)?)
            }
            frame_type::REMOTE_AT_RESPONSE => {
                Self::RemoteAtResponse(RemoteAtResponseRepr::parse_bytes(data)?)
            }
            frame_type::NODE_IDENTIFICATION_INDICATOR => Self::NodeIdentificationIndicator(
                NodeIdentificationIndicatorRepr::parse_bytes(data)?,
            ),
            other => Self::Unknown {
                frame_type: other,
                data: raw.body(),
            },
        })
    }

    /// Types frame data (type byte included); see [`Frame::parse`].
    pub fn parse_bytes(data: &'a [u8]) -> Result<Self, FrameError> {
        Self::parse(RawFrame::new(data)?)
    }

    /// The frame type byte.
    pub fn frame_type(&self) -> u8 {
        match self {
            Self::TransmitRequest(_) => frame_type::TRANSMIT_REQUEST,
            Self::ReceivePacket(_) => frame_type::RECEIVE_PACKET,
            Self::TransmitStatus(_) => frame_type::TRANSMIT_STATUS,
            Self::AtCommand(f) => f.frame_type(),
            Self::AtCommandResponse(_) => frame_type::AT_COMMAND_RESPONSE,
            Self::ModemStatus(_) => frame_type::MODEM_STATUS,
            Self::ExplicitAddressingCommand(_) => frame_type::EXPLICIT_ADDRESSING_COMMAND,
            Self::ExplicitRxIndicator(_) => frame_type::EXPLICIT_RX_INDICATOR,
            Self::RemoteAtCommand(_) => frame_type::REMOTE_AT_COMMAND,
            Self::RemoteAtResponse(_) => frame_type::REMOTE_AT_RESPONSE,
            Self::NodeIdentificationIndicator(_) => frame_type::NODE_IDENTIFICATION_INDICATOR,
            Self::Unknown { frame_type, .. } => *frame_type,
        }
    }

    /// The frame id, for the frame types that carry one: the requests (AT Command
    /// 0x08 and 0x09, Transmit Request 0x10, Explicit Addressing Command 0x11, Remote
    /// AT Command 0x17) and their answers (AT Command Response 0x88, Transmit Status
    /// 0x8B, Remote AT Command Response 0x97), which repeat the request's id. `None`
    /// for the frames that carry none (Receive Packet, Explicit Rx Indicator, Modem
    /// Status) and for [`Frame::Unknown`], whose layout this crate does not know.
    ///
    /// ```
    /// use xbee_api::{Address16, DeliveryStatus, DiscoveryStatus, Frame, ModemStatus};
    /// use xbee_api::frame::modem_status::ModemStatusRepr;
    /// use xbee_api::frame::transmit_status::TransmitStatusRepr;
    ///
    /// let status = Frame::TransmitStatus(TransmitStatusRepr {
    ///     frame_id: 0x47,
    ///     dst16: Address16(0x7D84),
    ///     retries: 0,
    ///     delivery: DeliveryStatus::Success,
    ///     discovery: DiscoveryStatus::NoDiscoveryOverhead,
    /// });
    /// assert_eq!(status.frame_id(), Some(0x47));
    ///
    /// let modem = Frame::ModemStatus(ModemStatusRepr { status: ModemStatus::JoinedNetwork });
    /// assert_eq!(modem.frame_id(), None);
    /// ```
    pub fn frame_id(&self) -> Option<u8> {
        match self {
            Self::TransmitRequest(f) => Some(f.frame_id),
            Self::TransmitStatus(f) => Some(f.frame_id),
            Self::AtCommand(f) => Some(f.frame_id),
            Self::AtCommandResponse(f) => Some(f.frame_id),
            Self::ExplicitAddressingCommand(f) => Some(f.frame_id),
            Self::RemoteAtCommand(f) => Some(f.frame_id),
            Self::RemoteAtResponse(f) => Some(f.frame_id),
            Self::ReceivePacket(_)
            | Self::ModemStatus(_)
            | Self::ExplicitRxIndicator(_)
            | Self::NodeIdentificationIndicator(_)
            | Self::Unknown { .. } => None,
        }
    }

    /// The RF data of a frame that carries some over the air, with the other radio's
    /// address: the source of a Receive Packet (0x90) or an Explicit Rx Indicator
    /// (0x91), the destination of a Transmit Request (0x10) or an Explicit Addressing
    /// Command (0x11). `None` for every other frame. An MCP packet is such data, both
    /// ways, as a recording of a ground station's link holds them.
    ///
    /// ```
    /// use xbee_api::{Address64, Frame};
    ///
    /// // A Receive Packet from 0013A20040B599B9 carrying b"r\x02\x04".
    /// let data = [
    ///     0x90, 0x00, 0x13, 0xA2, 0x00, 0x40, 0xB5, 0x99, 0xB9, 0xFF, 0xFE, 0x01, b'r', 0x02,
    ///     0x04,
    /// ];
    /// let frame = Frame::parse_bytes(&data).unwrap();
    /// assert_eq!(
    ///     frame.rf_data(),
    ///     Some((Address64(0x0013_A200_40B5_99B9), &b"r\x02\x04"[..]))
    /// );
    /// ```
    pub fn rf_data(&self) -> Option<(Address64, &'a [u8])> {
        match self {
            Self::ReceivePacket(rx) => Some((rx.src64, rx.data)),
            Self::ExplicitRxIndicator(rx) => Some((rx.src64, rx.data)),
            Self::TransmitRequest(tx) => Some((tx.dst64, tx.data)),
            Self::ExplicitAddressingCommand(tx) => Some((tx.dst64, tx.data)),
            _ => None,
        }
    }
}

impl EncodeFrame for Frame<'_> {
    fn frame_data_len(&self) -> usize {
        match self {
            Self::TransmitRequest(f) => f.frame_data_len(),
            Self::ReceivePacket(f) => f.frame_data_len(),
            Self::TransmitStatus(f) => f.frame_data_len(),
            Self::AtCommand(f) => f.frame_data_len(),
            Self::AtCommandResponse(f) => f.frame_data_len(),
            Self::ModemStatus(f) => f.frame_data_len(),
            Self::ExplicitAddressingCommand(f) => f.frame_data_len(),
            Self::ExplicitRxIndicator(f) => f.frame_data_len(),
            Self::RemoteAtCommand(f) => f.frame_data_len(),
            Self::RemoteAtResponse(f) => f.frame_data_len(),
            Self::NodeIdentificationIndicator(f) => f.frame_data_len(),
            Self::Unknown { data, .. } => 1 + data.len(),
        }
    }

    fn write_frame_data<F: FnMut(&[u8])>(&self, out: &mut F) {
        match self {
            Self::TransmitRequest(f) => f.write_frame_data(out),
            Self::ReceivePacket(f) => f.write_frame_data(out),
            Self::TransmitStatus(f) => f.write_frame_data(out),
            Self::AtCommand(f) => f.write_frame_data(out),
            Self::AtCommandResponse(f) => f.write_frame_data(out),
            Self::ModemStatus(f) => f.write_frame_data(out),
            Self::ExplicitAddressingCommand(f) => f.write_frame_data(out),
            Self::ExplicitRxIndicator(f) => f.write_frame_data(out),
            Self::RemoteAtCommand(f) => f.write_frame_data(out),
            Self::RemoteAtResponse(f) => f.write_frame_data(out),
            Self::NodeIdentificationIndicator(f) => f.write_frame_data(out),
            Self::Unknown { frame_type, data } => {
                out(&[*frame_type]);
                out(data);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn too_short_for_every_known_type() {
        let types = [
            (frame_type::TRANSMIT_REQUEST, 14),
            (frame_type::RECEIVE_PACKET, 12),
            (frame_type::TRANSMIT_STATUS, 7),
            (frame_type::AT_COMMAND, 4),
            (frame_type::AT_COMMAND_QUEUE, 4),
            (frame_type::AT_COMMAND_RESPONSE, 5),
            (frame_type::MODEM_STATUS, 2),
            (frame_type::EXPLICIT_ADDRESSING_COMMAND, 20),
            (frame_type::EXPLICIT_RX_INDICATOR, 18),
            (frame_type::REMOTE_AT_COMMAND, 15),
            (frame_type::REMOTE_AT_RESPONSE, 15),
            (frame_type::NODE_IDENTIFICATION_INDICATOR, 31),
        ];
        let zeros = [0u8; 32];
        for (t, needed) in types {
            let mut data = zeros;
            data[0] = t;
            for got in 1..needed {
                assert_eq!(
                    Frame::parse_bytes(&data[..got]),
                    Err(FrameError::TooShort {
                        frame_type: t,
                        needed,
                        got
                    })
                );
            }
            let frame = Frame::parse_bytes(&data[..needed]).unwrap();
            assert_eq!(frame.frame_type(), t);
            assert_eq!(frame.frame_data_len(), needed);
        }
        assert_eq!(Frame::parse_bytes(&[]), Err(FrameError::Empty));
    }

    #[test]
    fn frame_id_of_every_type() {
        // Frame data of each modelled type with the byte after the type byte set to
        // 0x5A (the frame id, for the types that carry one), and the frame id expected.
        let types = [
            (frame_type::AT_COMMAND, 4, Some(0x5A)),
            (frame_type::AT_COMMAND_QUEUE, 4, Some(0x5A)),
            (frame_type::TRANSMIT_REQUEST, 14, Some(0x5A)),
            (frame_type::EXPLICIT_ADDRESSING_COMMAND, 20, Some(0x5A)),
            (frame_type::REMOTE_AT_COMMAND, 15, Some(0x5A)),
            (frame_type::AT_COMMAND_RESPONSE, 5, Some(0x5A)),
            (frame_type::TRANSMIT_STATUS, 7, Some(0x5A)),
            (frame_type::REMOTE_AT_RESPONSE, 15, Some(0x5A)),
            (frame_type::MODEM_STATUS, 2, None),
            (frame_type::RECEIVE_PACKET, 12, None),
            (frame_type::EXPLICIT_RX_INDICATOR, 18, None),
            (frame_type::NODE_IDENTIFICATION_INDICATOR, 31, None),
            // TX Status (0x89) and Route Record (0xA1) are not modelled.
            (0x89, 3, None),
            (0xA1, 13, None),
        ];
        for (t, len, expected) in types {
            let mut data = [0u8; 32];
            data[0] = t;
            data[1] = 0x5A;
            let frame = Frame::parse_bytes(&data[..len]).unwrap();
            assert_eq!(frame.frame_type(), t);
            assert_eq!(frame.frame_id(), expected, "type 0x{t:02X}");
        }
        let mut seen = 0;
        for t in 0..=255u8 {
            let mut data = [0u8; 31];
            data[..2].copy_from_slice(&[t, 0x5A]);
            let frame = Frame::parse_bytes(&data).unwrap();
            // Every variant, checked by name so that a new one must be listed here.
            let expected = match frame {
                Frame::TransmitRequest(_)
                | Frame::TransmitStatus(_)
                | Frame::AtCommand(_)
                | Frame::AtCommandResponse(_)
                | Frame::ExplicitAddressingCommand(_)
                | Frame::RemoteAtCommand(_)
                | Frame::RemoteAtResponse(_) => Some(0x5A),
                Frame::ReceivePacket(_)
                | Frame::ModemStatus(_)
                | Frame::ExplicitRxIndicator(_)
                | Frame::NodeIdentificationIndicator(_)
                | Frame::Unknown { .. } => None,
            };
            if expected.is_some() {
                seen += 1;
            }
            assert_eq!(frame.frame_id(), expected, "type 0x{t:02X}");
        }
        assert_eq!(seen, 8);
    }

    #[test]
    fn unknown_passes_through() {
        let frame = Frame::parse_bytes(&[0x23, 1, 2, 3]).unwrap();
        assert_eq!(
            frame,
            Frame::Unknown {
                frame_type: 0x23,
                data: &[1, 2, 3]
            }
        );
        let mut buf = [0u8; 4];
        assert_eq!(frame.emit_frame_data(&mut buf), Ok(4));
        assert_eq!(buf, [0x23, 1, 2, 3]);
    }

    #[test]
    fn views_check_type() {
        use transmit_status::TransmitStatus;
        assert_eq!(
            TransmitStatus::new_checked(&[0x8A, 0, 0, 0, 0, 0, 0][..]).err(),
            Some(FrameError::WrongType {
                expected: 0x8B,
                found: 0x8A
            })
        );
    }
}
