//! Node Identification Indicator (0x95): a radio announced itself to the network (radio
//! to host, on Zigbee radios with `AO` = 0).
//!
//! A radio broadcasts its node identification when its commissioning button is pressed
//! once (or `CB` 1 is sent to it), and, with `JN` = 1, when it joins a network or is
//! power cycled. The radio that hears it hands this frame to its host: who sent it
//! ([`src64`](NodeIdentificationIndicatorRepr::src64)...), then the announcing radio's
//! [`NodeInfo`], laid out as in a node discovery answer, whose `status` byte is the
//! [`SourceEvent`].

use crate::frame::{be, check_frame, frame_type};
use crate::node::{self, NodeInfo, NodeInfoError};
use crate::{Address16, Address64};
use crate::{EncodeFrame, FrameError};

code_enum! {
    /// What made a radio send its node identification.
    pub enum SourceEvent {
        /// 0x01: its commissioning button was pressed once (or it was sent `CB` 1).
        Pushbutton = 0x01 => "pushbutton",
        /// 0x02: it joined a network (with `JN` = 1).
        Joined = 0x02 => "joined",
        /// 0x03: it was power cycled (with `JN` = 1).
        PowerCycle = 0x03 => "power_cycle",
    }
}

/// Positions of the fields within the frame data (byte 0 is the frame type).
pub mod field {
    use core::ops::{Range, RangeFrom};
    /// Frame type byte.
    pub const FRAME_TYPE: usize = 0;
    /// 64-bit address of the radio that sent the frame over the air.
    pub const SRC64: Range<usize> = 1..9;
    /// 16-bit address of the radio that sent the frame over the air.
    pub const SRC16: Range<usize> = 9..11;
    /// Receive options bit field (0x01 acknowledged, 0x02 broadcast...).
    pub const OPTIONS: usize = 11;
    /// The announcing radio's node information, as [`NodeInfo`](crate::NodeInfo)
    /// reads it. Runs to the end of the frame data.
    pub const NODE: RangeFrom<usize> = 12..;
    /// Length of the fields before the node information.
    pub const HEADER_LEN: usize = 12;
    /// The least frame data length: the header and node information with an empty
    /// node identifier.
    pub const MIN_LEN: usize = HEADER_LEN + crate::node::MIN_LEN;
}

/// A read-only view of Node Identification Indicator (0x95) frame data, type byte
/// included.
///
/// Build it with [`new_checked`](Self::new_checked); the accessors of a checked view
/// cannot panic. Turn it into owned fields with
/// [`NodeIdentificationIndicatorRepr::parse`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct NodeIdentificationIndicator<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> NodeIdentificationIndicator<T> {
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

    /// Checks the frame type byte (0x95) and that the fixed fields are present (those
    /// of the node information too; [`node`](NodeIdentificationIndicator::node) reads
    /// the rest).
    pub fn check_len(&self) -> Result<(), FrameError> {
        check_frame(
            self.buffer.as_ref(),
            frame_type::NODE_IDENTIFICATION_INDICATOR,
            field::MIN_LEN,
        )
    }

    /// The wrapped buffer.
    pub fn into_inner(self) -> T {
        self.buffer
    }

    /// 64-bit address of the radio that sent the frame over the air.
    pub fn src64(&self) -> Address64 {
        let d = self.buffer.as_ref();
        Address64::from_bytes(be::<8>(&d[field::SRC64]))
    }

    /// 16-bit address of the radio that sent the frame over the air.
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

impl<'a> NodeIdentificationIndicator<&'a [u8]> {
    /// The bytes of the announcing radio's node information.
    pub fn node_data(&self) -> &'a [u8] {
        &self.buffer[field::NODE]
    }

    /// The announcing radio's node information.
    pub fn node(&self) -> Result<NodeInfo<'a>, NodeInfoError> {
        NodeInfo::parse(self.node_data())
    }
}

/// The fields of a Node Identification Indicator (0x95) frame: parse one from a view,
/// or fill one in and encode it with [`EncodeFrame`].
///
/// ```
/// use xbee_api::{Address16, Address64, DeviceType, Frame, SourceEvent};
/// // Digi's example: the commissioning button of router 0013A20040522BAA was pressed.
/// let data = [
///     0x95, 0x00, 0x13, 0xA2, 0x00, 0x40, 0x52, 0x2B, 0xAA, 0x7D, 0x84, 0x02, // sender
///     0x7D, 0x84, 0x00, 0x13, 0xA2, 0x00, 0x40, 0x52, 0x2B, 0xAA, // its addresses
///     0x20, 0x00, 0xFF, 0xFE, 0x01, 0x01, 0xC1, 0x05, 0x10, 0x1E,
/// ];
/// let Frame::NodeIdentificationIndicator(ni) = Frame::parse_bytes(&data).unwrap() else {
///     unreachable!()
/// };
/// assert_eq!(ni.node.addr64, Address64(0x0013A20040522BAA));
/// assert_eq!(ni.node.identifier, b" ");
/// assert_eq!(ni.node.device_type, DeviceType::Router);
/// assert_eq!(ni.source_event(), SourceEvent::Pushbutton);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct NodeIdentificationIndicatorRepr<'a> {
    /// 64-bit address of the radio that sent the frame over the air.
    pub src64: Address64,
    /// 16-bit address of the radio that sent the frame over the air.
    pub src16: Address16,
    /// Receive options bit field (0x01 acknowledged, 0x02 broadcast...).
    pub options: u8,
    /// The announcing radio: its addresses, node identifier, parent, role, profile and
    /// manufacturer ids; its `status` byte is the [`SourceEvent`]. An identifier
    /// holding a 0x00 encodes as given, and so does not parse back (its 0x00 ends it on
    /// the wire), as [`NodeInfo::emit`] says.
    pub node: NodeInfo<'a>,
}

impl<'a> NodeIdentificationIndicatorRepr<'a> {
    /// The frame type, 0x95.
    pub const FRAME_TYPE: u8 = frame_type::NODE_IDENTIFICATION_INDICATOR;

    /// Reads the fields of `frame`, checking it first. Node information that does not
    /// read (an identifier with no 0x00 after it, bytes left over) is
    /// [`FrameError::BadNodeInfo`].
    pub fn parse(frame: &NodeIdentificationIndicator<&'a [u8]>) -> Result<Self, FrameError> {
        frame.check_len()?;
        let node = frame.node().map_err(|error| match error {
            // The node information's own lengths, as lengths of the frame data.
            NodeInfoError::TooShort { needed, got } => FrameError::TooShort {
                frame_type: Self::FRAME_TYPE,
                needed: field::HEADER_LEN + needed,
                got: field::HEADER_LEN + got,
            },
            error => FrameError::BadNodeInfo {
                frame_type: Self::FRAME_TYPE,
                error,
            },
        })?;
        Ok(Self {
            src64: frame.src64(),
            src16: frame.src16(),
            options: frame.options(),
            node,
        })
    }

    /// Reads the fields of frame data (type byte included).
    pub fn parse_bytes(data: &'a [u8]) -> Result<Self, FrameError> {
        Self::parse(&NodeIdentificationIndicator::new_unchecked(data))
    }

    /// What made the radio announce itself: the node information's `status` byte.
    pub fn source_event(&self) -> SourceEvent {
        SourceEvent::from(self.node.status)
    }
}

impl EncodeFrame for NodeIdentificationIndicatorRepr<'_> {
    fn frame_data_len(&self) -> usize {
        field::HEADER_LEN + self.node.len()
    }

    fn write_frame_data<F: FnMut(&[u8])>(&self, out: &mut F) {
        let mut h = [0u8; field::HEADER_LEN];
        h[field::FRAME_TYPE] = Self::FRAME_TYPE;
        h[field::SRC64].copy_from_slice(&self.src64.to_bytes());
        h[field::SRC16].copy_from_slice(&self.src16.to_bytes());
        h[field::OPTIONS] = self.options;
        out(&h);
        node::write_fields(&self.node, out);
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::vec::Vec;

    use super::*;
    use crate::{ApiMode, DeviceType, Frame};

    /// Digi's example frame (Zigbee manual, Node Identification Indicator), API mode 1.
    const DIGI: [u8; 36] = [
        0x7E, 0x00, 0x20, 0x95, 0x00, 0x13, 0xA2, 0x00, 0x40, 0x52, 0x2B, 0xAA, 0x7D, 0x84, 0x02,
        0x7D, 0x84, 0x00, 0x13, 0xA2, 0x00, 0x40, 0x52, 0x2B, 0xAA, 0x20, 0x00, 0xFF, 0xFE, 0x01,
        0x01, 0xC1, 0x05, 0x10, 0x1E, 0x1B,
    ];

    fn digi() -> NodeIdentificationIndicatorRepr<'static> {
        NodeIdentificationIndicatorRepr {
            src64: Address64(0x0013_A200_4052_2BAA),
            src16: Address16(0x7D84),
            options: 0x02,
            node: NodeInfo {
                addr16: Address16(0x7D84),
                addr64: Address64(0x0013_A200_4052_2BAA),
                identifier: b" ",
                parent: Address16::UNKNOWN,
                device_type: DeviceType::Router,
                status: 0x01,
                profile_id: 0xC105,
                manufacturer_id: 0x101E,
                device_type_identifier: None,
                rssi: None,
            },
        }
    }

    #[test]
    fn digis_example_decodes_and_encodes_to_its_bytes() {
        let data = &DIGI[3..DIGI.len() - 1];
        let frame = NodeIdentificationIndicator::new_checked(data).unwrap();
        assert_eq!(frame.src64(), Address64(0x0013_A200_4052_2BAA));
        assert_eq!(frame.options(), 0x02);
        let repr = NodeIdentificationIndicatorRepr::parse(&frame).unwrap();
        assert_eq!(repr, digi());
        assert_eq!(repr.source_event(), SourceEvent::Pushbutton);
        assert_eq!(
            Frame::parse_bytes(data),
            Ok(Frame::NodeIdentificationIndicator(digi()))
        );
        let mut buf = [0u8; 64];
        let n = digi().encode(ApiMode::Unescaped, &mut buf).unwrap();
        assert_eq!(&buf[..n], &DIGI[..]);
    }

    #[test]
    fn node_information_that_does_not_read_is_an_error() {
        let data = &DIGI[3..DIGI.len() - 1];
        // One byte short of the fixed fields.
        assert_eq!(
            Frame::parse_bytes(&data[..field::MIN_LEN - 1]),
            Err(FrameError::TooShort {
                frame_type: 0x95,
                needed: field::MIN_LEN,
                got: field::MIN_LEN - 1
            })
        );
        // A longer identifier, and the fields after it cut short.
        let mut long = Vec::from(&data[..field::HEADER_LEN + 10]);
        long.extend(b"MAV 1\0");
        long.extend([0xFF, 0xFE, 0x01]);
        assert_eq!(
            Frame::parse_bytes(&long),
            Err(FrameError::TooShort {
                frame_type: 0x95,
                needed: field::HEADER_LEN + 10 + 6 + 8,
                got: long.len()
            })
        );
        // Bytes left over that are neither device type identifier nor RSSI.
        let mut extra = Vec::from(data);
        extra.extend([0x00, 0x01]);
        assert_eq!(
            Frame::parse_bytes(&extra),
            Err(FrameError::BadNodeInfo {
                frame_type: 0x95,
                error: NodeInfoError::TrailingBytes { len: 2 }
            })
        );
        // The source events by name, and a code with none.
        let names: Vec<_> = (1..=4).map(|b| SourceEvent::from(b).name()).collect();
        assert_eq!(
            names,
            [
                Some("pushbutton"),
                Some("joined"),
                Some("power_cycle"),
                None
            ]
        );
    }
}
