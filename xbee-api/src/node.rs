//! Node discovery: the answer of one radio to the `ND` AT command.
//!
//! A local `ND` command (or a remote one) makes the radio ask the whole network who is
//! there; each radio that hears it answers, and the local radio hands over one AT
//! Command Response (0x88) per answer, all under the command's frame id, until the
//! network discovery timeout (`NT`, in tenths of a second) has passed. The response's
//! data is a [`NodeInfo`]. This is the layout of Zigbee and DigiMesh radios (the radios
//! that send Receive Packets, 0x90).

use core::fmt;

use crate::{Address16, Address64, EncodeError};

code_enum! {
    /// The role of a radio in its network, as node discovery reports it.
    pub enum DeviceType {
        /// 0x00: the network's coordinator.
        Coordinator = 0x00 => "coordinator",
        /// 0x01: a router.
        Router = 0x01 => "router",
        /// 0x02: an end device.
        EndDevice = 0x02 => "end_device",
    }
}

/// Why node information (a node discovery answer, a Node Identification Indicator's) is
/// not a [`NodeInfo`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum NodeInfoError {
    /// The data ends before the fields it must have.
    TooShort {
        /// Bytes the fields take, as far as the data says.
        needed: usize,
        /// Bytes there are.
        got: usize,
    },
    /// The node identifier has no 0x00 after it.
    UnterminatedIdentifier,
    /// After the fixed fields come bytes that are neither the device type identifier
    /// (4 bytes) nor the RSSI (1 byte) nor both.
    TrailingBytes {
        /// How many bytes follow the fixed fields.
        len: usize,
    },
}

impl fmt::Display for NodeInfoError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::TooShort { needed, got } => write!(
                f,
                "node information too short: needs {needed} bytes, got {got}"
            ),
            Self::UnterminatedIdentifier => {
                f.write_str("node information: the node identifier has no 0x00 after it")
            }
            Self::TrailingBytes { len } => write!(
                f,
                "node information: {len} bytes after the manufacturer id, expected 0, 1, 4 \
                 or 5"
            ),
        }
    }
}

impl core::error::Error for NodeInfoError {}

/// One radio's answer to node discovery (`ND`): the data of an AT Command Response to
/// `ND`, borrowed.
///
/// ```
/// use xbee_api::{Address16, Address64, DeviceType, NodeInfo};
/// let data = [
///     0x7D, 0x84, // MY
///     0x00, 0x13, 0xA2, 0x00, 0x40, 0x52, 0x2B, 0xAA, // SH, SL
///     b'M', b'A', b'V', b' ', b'1', 0x00, // NI
///     0xFF, 0xFE, // parent
///     0x01, 0x00, // device type, status
///     0xC1, 0x05, 0x10, 0x1E, // profile id, manufacturer id
/// ];
/// let node = NodeInfo::parse(&data).unwrap();
/// assert_eq!(node.addr64, Address64(0x0013A20040522BAA));
/// assert_eq!(node.addr16, Address16(0x7D84));
/// assert_eq!(node.identifier, b"MAV 1");
/// assert_eq!(node.device_type, DeviceType::Router);
///
/// let mut buf = [0u8; 64];
/// let n = node.emit(&mut buf).unwrap();
/// assert_eq!(&buf[..n], &data);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct NodeInfo<'a> {
    /// Its 16-bit network address (`MY`).
    pub addr16: Address16,
    /// Its 64-bit address (`SH`, `SL`).
    pub addr64: Address64,
    /// Its node identifier (`NI`), without the 0x00 that ends it on the wire.
    pub identifier: &'a [u8],
    /// The 16-bit address of its parent (`FFFE` for none).
    pub parent: Address16,
    /// Its role.
    pub device_type: DeviceType,
    /// A byte Digi reserves in a node discovery answer; in a Node Identification
    /// Indicator, the [`SourceEvent`](crate::SourceEvent).
    pub status: u8,
    /// Its profile id (Digi's: `C105`).
    pub profile_id: u16,
    /// Its manufacturer id (Digi's: `101E`).
    pub manufacturer_id: u16,
    /// Its device type identifier (`DD`), when the discovering radio's `NO` asks for it.
    pub device_type_identifier: Option<u32>,
    /// The signal strength of the last hop, in -dBm, when `NO` asks for it.
    pub rssi: Option<u8>,
}

/// Bytes of the fields before the node identifier: `MY`, `SH`, `SL`.
const HEAD_LEN: usize = 10;
/// Bytes of the fields after the node identifier's 0x00: parent, device type, status,
/// profile id, manufacturer id.
const TAIL_LEN: usize = 8;
/// The least length of node information: an empty identifier, no optional field.
pub(crate) const MIN_LEN: usize = HEAD_LEN + 1 + TAIL_LEN;

impl<'a> NodeInfo<'a> {
    /// Reads one node discovery answer.
    pub fn parse(data: &'a [u8]) -> Result<Self, NodeInfoError> {
        let too_short = |needed| NodeInfoError::TooShort {
            needed,
            got: data.len(),
        };
        let least = MIN_LEN;
        let (head, rest) = data
            .split_first_chunk::<HEAD_LEN>()
            .ok_or(too_short(least))?;
        let end = rest
            .iter()
            .position(|&b| b == 0)
            .ok_or(if data.len() < least {
                too_short(least)
            } else {
                NodeInfoError::UnterminatedIdentifier
            })?;
        let (identifier, rest) = rest.split_at(end);
        let rest = rest.get(1..).unwrap_or_default();
        let (tail, extra) = rest
            .split_first_chunk::<TAIL_LEN>()
            .ok_or(too_short(HEAD_LEN + end + 1 + TAIL_LEN))?;
        let [my0, my1, serial @ ..] = *head;
        let [p0, p1, device_type, status, f0, f1, m0, m1] = *tail;
        let (device_type_identifier, rssi) = match *extra {
            [] => (None, None),
            [rssi] => (None, Some(rssi)),
            [d0, d1, d2, d3] => (Some(u32::from_be_bytes([d0, d1, d2, d3])), None),
            [d0, d1, d2, d3, rssi] => (Some(u32::from_be_bytes([d0, d1, d2, d3])), Some(rssi)),
            _ => return Err(NodeInfoError::TrailingBytes { len: extra.len() }),
        };
        Ok(Self {
            addr16: Address16::from_bytes([my0, my1]),
            addr64: Address64::from_bytes(serial),
            identifier,
            parent: Address16::from_bytes([p0, p1]),
            device_type: DeviceType::from(device_type),
            status,
            profile_id: u16::from_be_bytes([f0, f1]),
            manufacturer_id: u16::from_be_bytes([m0, m1]),
            device_type_identifier,
            rssi,
        })
    }

    /// The bytes [`emit`](Self::emit) writes.
    pub fn len(&self) -> usize {
        HEAD_LEN
            + self.identifier.len()
            + 1
            + TAIL_LEN
            + self.device_type_identifier.map_or(0, |_| 4)
            + self.rssi.map_or(0, |_| 1)
    }

    /// Never: an answer holds its fixed fields at least.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Writes the answer into `buf`, as a radio sends it; the bytes written. An
    /// identifier holding a 0x00 would end early on the wire: it is written as given.
    pub fn emit(&self, buf: &mut [u8]) -> Result<usize, EncodeError> {
        let len = self.len();
        let available = buf.len();
        let out = buf.get_mut(..len).ok_or(EncodeError::BufferTooSmall {
            needed: len,
            available,
        })?;
        let mut at = 0;
        write_fields(self, &mut |field: &[u8]| {
            let end = at + field.len();
            if let Some(slot) = out.get_mut(at..end) {
                slot.copy_from_slice(field);
            }
            at = end;
        });
        Ok(len)
    }
}

/// Hands `node`'s fields to `out` in their order on the wire, [`NodeInfo::len`] bytes
/// in all: for [`NodeInfo::emit`] and the frames that carry node information.
pub(crate) fn write_fields<F: FnMut(&[u8])>(node: &NodeInfo<'_>, out: &mut F) {
    let dd = node.device_type_identifier.map(u32::to_be_bytes);
    let fields: [&[u8]; 10] = [
        &node.addr16.to_bytes(),
        &node.addr64.to_bytes(),
        node.identifier,
        &[0],
        &node.parent.to_bytes(),
        &[u8::from(node.device_type), node.status],
        &node.profile_id.to_be_bytes(),
        &node.manufacturer_id.to_be_bytes(),
        dd.as_ref().map_or(&[], |d| &d[..]),
        node.rssi.as_slice(),
    ];
    for field in fields {
        out(field);
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::string::ToString;
    use std::vec::Vec;

    use super::*;

    fn answer(extra: &[u8]) -> Vec<u8> {
        let mut v = Vec::from([0x00, 0x00]);
        v.extend(0x0013_A200_4000_0001u64.to_be_bytes());
        v.extend(b"GS\0");
        v.extend([0xFF, 0xFE, 0x00, 0x00, 0xC1, 0x05, 0x10, 0x1E]);
        v.extend(extra);
        v
    }

    #[test]
    fn a_coordinator_with_and_without_the_optional_fields() {
        for (extra, dd, rssi) in [
            (&[][..], None, None),
            (&[0x28][..], None, Some(0x28)),
            (&[0x00, 0x12, 0x00, 0x00][..], Some(0x0012_0000), None),
            (
                &[0x00, 0x12, 0x00, 0x00, 0x28][..],
                Some(0x0012_0000),
                Some(0x28),
            ),
        ] {
            let data = answer(extra);
            let node = NodeInfo::parse(&data).unwrap();
            assert_eq!(node.addr16, Address16::COORDINATOR);
            assert_eq!(node.addr64, Address64(0x0013_A200_4000_0001));
            assert_eq!(node.identifier, b"GS");
            assert_eq!(node.parent, Address16::UNKNOWN);
            assert_eq!(node.device_type, DeviceType::Coordinator);
            assert_eq!((node.profile_id, node.manufacturer_id), (0xC105, 0x101E));
            assert_eq!((node.device_type_identifier, node.rssi), (dd, rssi));
            assert_eq!(node.len(), data.len());
            let mut buf = [0u8; 64];
            assert_eq!(node.emit(&mut buf), Ok(data.len()));
            assert_eq!(&buf[..data.len()], &data[..]);
            assert_eq!(
                node.emit(&mut buf[..data.len() - 1]),
                Err(EncodeError::BufferTooSmall {
                    needed: data.len(),
                    available: data.len() - 1
                })
            );
        }
    }

    #[test]
    fn broken_answers_say_what_is_wrong() {
        let data = answer(&[]);
        assert_eq!(
            NodeInfo::parse(&data[..5]),
            Err(NodeInfoError::TooShort { needed: 19, got: 5 })
        );
        // Cut in the fields after the identifier.
        assert_eq!(
            NodeInfo::parse(&data[..data.len() - 1]),
            Err(NodeInfoError::TooShort {
                needed: 21,
                got: 20
            })
        );
        // No 0x00 after the identifier.
        let mut no_end = [b'A'; 30];
        no_end[..10].copy_from_slice(&data[..10]);
        assert_eq!(
            NodeInfo::parse(&no_end),
            Err(NodeInfoError::UnterminatedIdentifier)
        );
        assert_eq!(
            NodeInfo::parse(&answer(&[1, 2])),
            Err(NodeInfoError::TrailingBytes { len: 2 })
        );
        assert!(
            NodeInfoError::TrailingBytes { len: 2 }
                .to_string()
                .contains("2 bytes after the manufacturer id")
        );
    }
}
