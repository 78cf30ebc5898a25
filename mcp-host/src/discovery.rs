//! Node discovery: which radios the local one can reach, from [`CommandSender::discover`].

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

/// A radio found by node discovery.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub struct Node {
    /// Its 64-bit address: the one to send to.
    pub addr64: Address64,
    /// Its 16-bit network address.
    pub addr16: Address16,
    /// Its node identifier (`NI`), bytes outside UTF-8 replaced.
    pub identifier: String,
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
            identifier: String::from_utf8_lossy(info.identifier).into_owned(),
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
            "{} ({}) {} {:?}",
            self.addr64, self.addr16, self.device_type, self.identifier
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
    /// ([`NodeInfo`]; an 802.15.4 radio's have another layout), each with a warning in
    /// the log.
    pub unreadable: usize,
}

/// Why node discovery failed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum DiscoverError {
    /// The `ND` command could not be sent, or the link went down meanwhile.
    #[error("node discovery: {0}")]
    Send(#[from] SendError),
    /// The radio answered `ND` with a status other than ok.
    #[error("node discovery: the radio answered {status} (0x{code:02x})", code = u8::from(*.status))]
    #[non_exhaustive]
    Refused {
        /// The status it answered.
        status: AtStatus,
    },
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
    while let Some(answer) = answers.next().await {
        let answer = answer?;
        let response = match answer.parse() {
            Ok(Frame::AtCommandResponse(response)) if response.command == *b"ND" => response,
            _ => {
                tracing::warn!(data = %crate::render::json::hex(answer.data()), "node discovery: not an answer to ND");
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
            Ok(info) => {
                let node = Node::from(&info);
                match found.nodes.iter_mut().find(|n| n.addr64 == node.addr64) {
                    Some(known) => *known = node,
                    None => found.nodes.push(node),
                }
            }
            Err(error) => {
                tracing::warn!(%error, data = %crate::render::json::hex(response.data), "node discovery: an answer cannot be read");
                found.unreadable += 1;
            }
        }
    }
    Ok(found)
}

/// How long [`CommandSender::discover`] listens when given no window: the radio's
/// longest discovery time, `N?` (in milliseconds, on DigiMesh and 802.15.4 radios, which
/// add the network's delays to `NT`), else its discovery time `NT` (tenths of a second,
/// on Zigbee radios, which have no `N?`), else [`DEFAULT_DISCOVERY_TIME`]; and
/// [`DISCOVERY_MARGIN`] more.
pub async fn window(sender: &CommandSender) -> Result<Duration, SendError> {
    let time = match read_number(sender, *b"N?").await? {
        Some(ms) => Duration::from_millis(ms),
        None => match read_number(sender, *b"NT").await? {
            Some(tenths) => Duration::from_millis(tenths * 100),
            None => DEFAULT_DISCOVERY_TIME,
        },
    };
    Ok(time + DISCOVERY_MARGIN)
}

/// A number the local radio answers `command` with (1 to 4 bytes, big-endian); `None` if
/// it refuses the command or answers otherwise.
async fn read_number(sender: &CommandSender, command: [u8; 2]) -> Result<Option<u64>, SendError> {
    let response = sender.at(command, &[], None).await?;
    Ok(match response.parse() {
        Ok(Frame::AtCommandResponse(at)) if at.status.is_ok() && matches!(at.data.len(), 1..=4) => {
            Some(at.data.iter().fold(0u64, |n, &b| (n << 8) | u64::from(b)))
        }
        _ => None,
    })
}
