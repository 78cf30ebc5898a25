//! Node discovery: which radios the local one can reach, from [`CommandSender::discover`].

use std::collections::HashMap;
use std::fmt;
use std::time::Duration;

use xbee_api::{Address16, Address64, AtStatus, DeviceType, Frame, NodeInfo};

use crate::error::SendError;
use crate::sender::CommandSender;

/// The discovery time of a radio whose `N?` and `NT` cannot be read: Digi's default
/// `NT`, 6 s.
pub const DEFAULT_DISCOVERY_TIME: Duration = Duration::from_secs(6);

/// Added to the radio's discovery time (`N?` or `NT`) for the last answer to reach the
/// host.
pub const DISCOVERY_MARGIN: Duration = Duration::from_secs(1);

/// The longest discovery time [`window`] takes from a radio: a DigiMesh radio's longest
/// `NT` (0x2EE0 tenths of a second, 20 minutes). A longer `N?` or `NT` (a peer that is
/// no radio) is cut to it, with a warning.
pub const MAX_DISCOVERY_TIME: Duration = Duration::from_secs(1200);

/// The most radios one discovery keeps ([`Discovery::left_out`] counts those beyond):
/// as many as a network's 16-bit addresses.
pub const MAX_NODES: usize = 65_536;

/// A radio found by node discovery.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub struct Node {
    /// Its 64-bit address: the one to send to.
    pub addr64: Address64,
    /// Its 16-bit network address.
    pub addr16: Address16,
    /// Its node identifier (`NI`), its bytes as the radio sent them: 1 to 20 printable
    /// ASCII characters from a real radio, but any bytes from a peer that breaks the
    /// rule. [`Node`]'s `Display` quotes it as message text prints, any byte that is
    /// not printable ASCII as `\xNN`; `String::from_utf8_lossy` gives a `str`.
    pub identifier: Vec<u8>,
    /// Its role in the network.
    pub device_type: DeviceType,
    /// Its parent's 16-bit address (`FFFE`: none).
    pub parent: Address16,
    /// The signal strength of the last hop in -dBm, when the local radio's `NO` asks for
    /// it.
    pub rssi: Option<u8>,
}

impl From<&NodeInfo<'_>> for Node {
    fn from(info: &NodeInfo<'_>) -> Self {
        Node {
            addr64: info.addr64,
            addr16: info.addr16,
            identifier: info.identifier.to_vec(),
            device_type: info.device_type,
            parent: info.parent,
            rssi: info.rssi,
        }
    }
}

/// `0013a20040000002 (7d84) router "MAV 1"`, with `, -40 dBm` when the RSSI is known.
impl fmt::Display for Node {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} ({}) {} {}",
            self.addr64,
            self.addr16,
            self.device_type,
            mcp_core::Text::new(&self.identifier[..]).quoted()
        )?;
        if let Some(rssi) = self.rssi {
            write!(f, ", -{rssi} dBm")?;
        }
        Ok(())
    }
}

/// What node discovery found.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
#[non_exhaustive]
pub struct Discovery {
    /// The radios that answered, each once, in the order they first answered (as they
    /// last answered, for one heard twice).
    pub nodes: Vec<Node>,
    /// Answers left out because they are no Zigbee or DigiMesh node discovery answer
    /// ([`NodeInfo`]; an 802.15.4 radio's have another layout); the first is logged as
    /// a warning.
    pub unreadable: usize,
    /// Radios left out beyond [`MAX_NODES`] (a peer that is no radio, answering
    /// without end).
    pub left_out: usize,
}

impl Discovery {
    /// Adds `node`, or puts it in the place of its radio's earlier answer (`index` says
    /// where each radio is in `nodes`); beyond `max` radios, counts it left out.
    fn add(&mut self, index: &mut HashMap<Address64, usize>, node: Node, max: usize) {
        match index.get(&node.addr64) {
            Some(&at) => self.nodes[at] = node,
            None if self.nodes.len() < max => {
                index.insert(node.addr64, self.nodes.len());
                self.nodes.push(node);
            }
            None => self.left_out += 1,
        }
    }
}

/// Why node discovery failed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum DiscoverError {
    /// The `ND` command could not be sent, or the link went down meanwhile.
    #[error("node discovery: {0}")]
    Send(SendError),
    /// The radio answered `ND` with a status other than ok.
    #[error("node discovery: the radio answered {status} (0x{code:02x})", code = u8::from(*.status))]
    #[non_exhaustive]
    Refused {
        /// The status it answered.
        status: AtStatus,
    },
}

/// The message says why it could not be sent: no [`source`](std::error::Error::source),
/// so that a chain of errors says it once.
impl From<SendError> for DiscoverError {
    fn from(error: SendError) -> Self {
        DiscoverError::Send(error)
    }
}

/// What [`CommandSender::discover`] does.
pub(crate) async fn discover(
    sender: &CommandSender,
    window: Option<Duration>,
) -> Result<Discovery, DiscoverError> {
    let window = match window {
        Some(window) => window,
        None => self::window(sender).await?,
    };
    let mut answers = sender.at_answers(*b"ND", &[], window).await?;
    let mut found = Discovery::default();
    // Where each radio is in `found.nodes`: a radio heard again is found at once.
    let mut index = HashMap::new();
    while let Some(answer) = answers.next().await {
        let answer = answer?;
        let response = match answer.parse() {
            Ok(Frame::AtCommandResponse(response)) if response.command == *b"ND" => response,
            _ => {
                if found.unreadable == 0 {
                    tracing::warn!(data = %crate::render::json::hex(answer.data()), "node discovery: not an answer to ND (more are counted, not logged)");
                }
                found.unreadable += 1;
                continue;
            }
        };
        if !response.status.is_ok() {
            return Err(DiscoverError::Refused {
                status: response.status,
            });
        }
        if response.data.is_empty() {
            // The end of the answers, on radios that mark it.
            break;
        }
        match NodeInfo::parse(response.data) {
            Ok(info) => found.add(&mut index, Node::from(&info), MAX_NODES),
            Err(error) => {
                if found.unreadable == 0 {
                    tracing::warn!(%error, data = %crate::render::json::hex(response.data), "node discovery: an answer cannot be read (more are counted, not logged)");
                }
                found.unreadable += 1;
            }
        }
    }
    Ok(found)
}

/// How long [`CommandSender::discover`] listens when given no window: the radio's
/// longest discovery time, `N?` (in milliseconds, on DigiMesh and 802.15.4 radios, which
/// add the network's delays to `NT`), else its discovery time `NT` (tenths of a second,
/// on Zigbee radios, which have no `N?`), else [`DEFAULT_DISCOVERY_TIME`]; at most
/// [`MAX_DISCOVERY_TIME`]; and [`DISCOVERY_MARGIN`] more.
pub async fn window(sender: &CommandSender) -> Result<Duration, SendError> {
    let time = match read_number(sender, *b"N?").await? {
        Some(ms) => Duration::from_millis(ms),
        None => match read_number(sender, *b"NT").await? {
            Some(tenths) => Duration::from_millis(tenths * 100),
            None => DEFAULT_DISCOVERY_TIME,
        },
    };
    if time > MAX_DISCOVERY_TIME {
        tracing::warn!(
            "node discovery: the radio's discovery time, {}, is longer than any radio's: {} \
             taken",
            crate::render::Seconds(time),
            crate::render::Seconds(MAX_DISCOVERY_TIME)
        );
    }
    Ok(time.min(MAX_DISCOVERY_TIME) + DISCOVERY_MARGIN)
}

/// A number the local radio answers `command` with (1 to 4 bytes, big-endian); `None` if
/// it refuses the command or answers otherwise.
async fn read_number(sender: &CommandSender, command: [u8; 2]) -> Result<Option<u64>, SendError> {
    let response = sender.at(command, &[], None).await?;
    Ok(match response.parse() {
        Ok(Frame::AtCommandResponse(at)) if at.status.is_ok() && at.data.len() <= 4 => {
            xbee_api::at_number(at.data)
        }
        _ => None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn node(addr: u64, name: &str) -> Node {
        Node {
            addr64: Address64(addr),
            addr16: Address16(0x1234),
            identifier: name.as_bytes().to_vec(),
            device_type: DeviceType::Router,
            parent: Address16(0xFFFE),
            rssi: None,
        }
    }

    #[test]
    fn a_radio_heard_again_keeps_its_place_and_radios_beyond_the_most_are_counted() {
        let mut found = Discovery::default();
        let mut index = HashMap::new();
        found.add(&mut index, node(1, "a"), 2);
        found.add(&mut index, node(2, "b"), 2);
        found.add(&mut index, node(1, "a again"), 2);
        found.add(&mut index, node(3, "c"), 2);
        found.add(&mut index, node(4, "d"), 2);
        let names: Vec<&[u8]> = found.nodes.iter().map(|n| &n.identifier[..]).collect();
        assert_eq!(names, [&b"a again"[..], b"b"]);
        assert_eq!(found.left_out, 2);
    }
}
