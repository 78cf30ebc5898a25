//! A virtual XBee network: radios emulated in software, each attached to a device
//! through a link (serial, TCP, pseudo-terminal) or an in-process byte stream.
//!
//! Each node's device speaks XBee API frames to its (virtual) radio, exactly as it would
//! over a UART to a real XBee: it writes Transmit Requests (0x10) and local AT commands
//! (0x08), and reads Receive Packets (0x90), Transmit Statuses (0x8B), AT Command
//! Responses (0x88) and Modem Statuses (0x8A).
//!
//! - The coordinator has the 64-bit address 0000000000000000 and the 16-bit address
//!   0000. Other nodes get a 16-bit address folded from their 64-bit address
//!   ([`Network::addr16`]).
//! - A Transmit Request to a known node is delivered as a Receive Packet carrying the
//!   sender's addresses (receive options 0x01); to 000000000000FFFF it goes to every
//!   other connected node (receive options 0x02). A Transmit Request with a non-zero frame
//!   id is answered with a Transmit Status: success (0x00, the destination's 16-bit
//!   address, no retries, no discovery), 0x24 address not found (discovery 0x01) for an
//!   unknown destination, 0x74 payload too large beyond [`NetworkConfig::max_unicast`]
//!   (84 bytes unless fragmentation is assumed, up to 255) or
//!   [`NetworkConfig::max_broadcast`] (92), 0x21 network ACK failure when the destination
//!   is known but its link is down or cut, 0x23 to itself. Explicit Addressing Commands
//!   (0x11) are delivered the same way, as Explicit Rx Indicators (0x91) carrying their
//!   endpoints, cluster and profile.
//! - Local AT commands (0x08, and 0x09, queued) are answered as an XBee S2C module with
//!   Zigbee firmware would: `AP` (the node's API mode), `NP` (the unicast payload
//!   limit), `SH`/`SL` (the 64-bit address), `MY` (the 16-bit address), `AI` (0,
//!   joined), `CE` (1 on the coordinator), `SM` (0, no sleep), `HV` (2E00: an S2C
//!   through-hole module), `VR` (4060: Zigbee 3.0 firmware), `ID` (0, the configured
//!   extended PAN ID: any), `OP` (the operating extended PAN ID, 0013A2004D435000),
//!   `OI` (the operating 16-bit PAN ID, 4D43), `CH` (the operating channel, 0x17),
//!   `NT` (the node discovery time, 0x3C tenths of a second) and `NI` (the node
//!   identifier: a space, the default, until set). `NI` can be set to 1 to 20 printable
//!   ASCII characters and `NT` to 0x20..=0xFF; `AP` to 0, 1 or 2: the answer comes in
//!   the old mode, and from then on the radio speaks the new one to its device (0 is
//!   transparent mode, below); the others are read-only: a value gets status 3, invalid
//!   parameter. `BD` (the UART's baud rate: 3, 9600 baud, on a radio that starts in
//!   transparent mode, else 7, 115200) can be set to 0..=8; `GT` (0x3E8) and `CT`
//!   (0x64) are read-only. A new `AP` or `BD` applies once answered (remotely: at once),
//!   even when queued, unlike on a module, where a queued one waits for `AC`.
//!   Node discovery (`ND`, or `ND NAME` for the node named NAME) is answered at once
//!   with an AT Command Response for each other node the radio can reach (its
//!   [`xbee_api::NodeInfo`]: the coordinator as coordinator, the others as routers,
//!   parent FFFE), as a network of quick radios would within `NT`; `ND NAME` that
//!   finds nobody gets one with status 1, error. These are what
//!   Digi's xbee-python library reads when it opens a device. A name set is read back
//!   at once, even when it was queued (AT Command - Queue Parameter Value, 0x09, or a
//!   remote command without the apply option), as a module's register is; nothing else
//!   in the emulation depends on it, so `AC` (apply changes) and `WR` (write to
//!   non-volatile memory) answer ok and have nothing more to do. `CB` 1 (the
//!   commissioning button pressed once) makes the radio broadcast its identification:
//!   every other radio it reaches hands its device a Node Identification Indicator
//!   (0x95) with the same node information. Any other command gets status 2, invalid
//!   command.
//!   Remote AT commands (0x17) get the same answers from the destination's radio
//!   (0x97), or status 4, transmission failure, when it cannot be reached. One to the
//!   broadcast address (000000000000FFFF) is carried out by every other node the
//!   sender can reach, and, as on Zigbee radios (Digi discourages it there), the sender
//!   hands over a single answer, the first node's; none for a sender cut off from the
//!   network.
//! - When a link comes up its device gets a Modem Status: 0x06 coordinator started on the
//!   coordinator, 0x02 joined network on other nodes. Links that go down are reopened
//!   (a `tcp-listen` node's next peer is the node back); frames for a node whose link is
//!   down are not queued. A link that cannot be opened, and will not be by waiting (a
//!   serial port's path that is a regular file), ends: [`NetEvent::LinkEnded`].
//! - A `pty` node's link is up only while a device has the far end of its
//!   pseudo-terminal open (the radio looks every 20 ms while nobody has): until then,
//!   and after the device closes it, the node is down and nothing is written for it, and
//!   what a device leaves unread when it closes the far end is dropped, so that the
//!   next device starts with its modem status, not with stale frames.
//! - A node added with [`NodeOptions::transparent`] starts in transparent mode
//!   (`AP` = 0), as XBee modules leave the factory. Its device gets the payloads of the
//!   Receive Packets (and Explicit Rx Indicators) for it as bytes, and nothing else: no
//!   modem status, no frame. What the device writes is data, which goes nowhere in this
//!   emulation, except `+++` written alone between two guard times of silence (`GT`,
//!   1 s), which the radio answers `OK` to: AT command mode, where nothing received is
//!   passed on (what was on its way to the device is dropped). There each line `AT`,
//!   command, value (hex, `0x` allowed; text for `NI`) and carriage return is answered
//!   with the value read (hex), `OK` or `ERROR`, as the radio's API answers the same
//!   command (`ND` excepted); commands chained with commas (`ATAP1,WR,CN`) are answered
//!   one by one; `AP` takes 0, 1 or 2, and `BD` 0 to 8 (the link is not slowed down).
//!   `ATCN`, or `CT` (10 s) without a command, leaves command mode: with `AP` set to 1
//!   or 2 the radio speaks API frames in that mode from then on, as a node added in API
//!   mode does, until an `AP` in an API frame changes it. A radio in API mode does not
//!   take `+++` (as older firmware).
//! - Every radio's UART runs at the rate `BD` sets: 9600 baud for a node started in
//!   transparent mode, 115200 for one started in API mode, until set (a new one takes
//!   effect when command mode is left, or once answered in an API frame). A device on
//!   a `pty` link set to another rate reads garbage and is not understood, as on a real
//!   serial line (a pseudo-terminal's ends share their settings); links of other kinds
//!   have no rate.
//! - [`Faults`] (loss, latency, jitter, duplication, reordering, corruption) apply to the
//!   frames written to a link, network-wide or per node, drawn from a generator seeded
//!   with [`NetworkConfig::seed`] and the node's address, so that a run replays.
//!   [`Network::cut`] takes a node out of radio range until [`Network::restore`].
//!
//! ```
//! use mcp_host::radio::{Network, NetworkConfig, NodeOptions};
//! use tokio::io::{AsyncReadExt, AsyncWriteExt};
//! use mcp_host::xbee_api::{Address64, Address16, EncodeFrame, TransmitRequestRepr, ApiMode};
//!
//! # #[tokio::main(flavor = "current_thread")]
//! # async fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let network = Network::new(NetworkConfig::default());
//! // Two in-process devices: the coordinator and a MAV.
//! let (_, mut ground) = network.add_in_process(Address64::COORDINATOR, NodeOptions::default())?;
//! let mav: Address64 = "0013A20040B599B9".parse()?;
//! let (_, mut device) = network.add_in_process(mav, NodeOptions::default())?;
//!
//! // The MAV sends "r\x02\x04" to the coordinator, asking for no status (frame id 0).
//! let tx = TransmitRequestRepr {
//!     frame_id: 0, dst64: Address64::COORDINATOR, dst16: Address16::UNKNOWN,
//!     radius: 0, options: 0, data: b"r\x02\x04",
//! };
//! let mut buf = vec![0; tx.encoded_len(ApiMode::Unescaped)];
//! tx.encode(ApiMode::Unescaped, &mut buf)?;
//! device.write_all(&buf).await?;
//!
//! // The coordinator's device reads its modem status (6 bytes), then the Receive Packet.
//! let mut frame = [0u8; 6 + 4 + 12 + 3];
//! ground.read_exact(&mut frame).await?;
//! assert_eq!(frame[3..5], [0x8A, 0x06]);
//! assert_eq!(frame[9], 0x90);
//! assert_eq!(frame[10..18], mav.to_bytes());
//! assert_eq!(&frame[21..24], b"r\x02\x04");
//! # Ok(())
//! # }
//! ```

mod command_mode;
mod faults;
mod port;
mod router;
mod uart;
mod wire;

use std::collections::BTreeMap;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use tokio::io::{AsyncRead, AsyncWrite, DuplexStream};
use tokio::sync::{broadcast, mpsc};
use tokio_util::sync::CancellationToken;
use tokio_util::task::TaskTracker;
use xbee_api::{Address16, Address64, ApiMode, AtStatus, DecodeError, DeliveryStatus};

pub use faults::{Faults, REORDER_WINDOW};

use crate::link::Link;
use crate::options::{DEFAULT_CONNECT_TIMEOUT, LinkOptions, ReconnectPolicy};
use crate::transport::{Connector, LinkError};
use port::Source;

use crate::mutex::lock;
use router::{Node, OUT_CAPACITY, State};

/// Largest unicast RF payload without fragmentation (`NP` = 0x54).
pub const MAX_UNICAST: usize = xbee_api::TransmitRequestRepr::MAX_UNICAST_DATA;
/// Largest unicast RF payload with fragmentation.
pub const MAX_UNICAST_FRAGMENTED: usize =
    xbee_api::TransmitRequestRepr::MAX_UNICAST_DATA_FRAGMENTED;
/// Largest broadcast RF payload.
pub const MAX_BROADCAST: usize = xbee_api::TransmitRequestRepr::MAX_BROADCAST_DATA;
/// Size of an in-process node's byte stream buffer, each way.
pub const IN_PROCESS_BUFFER: usize = 64 * 1024;

/// Settings of the whole network.
#[derive(Debug, Clone, PartialEq)]
pub struct NetworkConfig {
    /// Seed of the fault generators.
    pub seed: u64,
    /// Faults of the nodes that have none of their own.
    pub faults: Faults,
    /// Largest unicast payload: [`MAX_UNICAST`] by default, up to
    /// [`MAX_UNICAST_FRAGMENTED`] with fragmentation.
    pub max_unicast: usize,
    /// Largest broadcast payload.
    pub max_broadcast: usize,
}

impl Default for NetworkConfig {
    /// Seed 0, no faults, the XBee's payload limits.
    fn default() -> Self {
        NetworkConfig {
            seed: 0,
            faults: Faults::default(),
            max_unicast: MAX_UNICAST,
            max_broadcast: MAX_BROADCAST,
        }
    }
}

/// Settings of one node.
#[derive(Debug, Clone, PartialEq)]
pub struct NodeOptions {
    /// API mode its device speaks.
    pub api_mode: ApiMode,
    /// The radio starts in transparent mode (`AP` = 0), as XBee modules leave the
    /// factory, rather than in `api_mode`: see [the module documentation](self)
    /// for what it does then. Its device puts it into API mode through AT command mode,
    /// as [`crate::command_mode::CommandMode`] does.
    pub transparent: bool,
    /// Its own faults; `None` uses the network's.
    pub faults: Option<Faults>,
    /// How its link is reopened after a disconnection.
    pub reconnect: ReconnectPolicy,
    /// Timeout of a TCP connection attempt.
    pub connect_timeout: Duration,
}

impl Default for NodeOptions {
    /// API mode 1, the network's faults, the default reconnection policy.
    fn default() -> Self {
        NodeOptions {
            api_mode: ApiMode::Unescaped,
            transparent: false,
            faults: None,
            reconnect: ReconnectPolicy::default(),
            connect_timeout: DEFAULT_CONNECT_TIMEOUT,
        }
    }
}

impl NodeOptions {
    /// Default options in `mode`.
    pub fn with_mode(api_mode: ApiMode) -> Self {
        NodeOptions {
            api_mode,
            ..Self::default()
        }
    }
}

/// A node as added to the network: its addresses, mode and where its link is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct AddedNode {
    /// Its 64-bit address.
    pub addr64: Address64,
    /// Its 16-bit address.
    pub addr16: Address16,
    /// Its API mode.
    pub api_mode: ApiMode,
    /// It started in transparent mode (`AP` = 0), not in `api_mode`.
    pub transparent: bool,
    /// For a `pty` link: the path its device opens.
    pub pty_path: Option<PathBuf>,
    /// For a `tcp-listen` link: the bound address.
    pub local_addr: Option<SocketAddr>,
}

/// Counters of one node.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct NodeStats {
    /// Frames received from its device.
    pub frames_in: u64,
    /// Frames queued for its device (duplicates included, lost ones not).
    pub frames_out: u64,
    /// Candidate frames from its device its decoder dropped.
    pub decode_errors: u64,
    /// Frames dropped by the loss fault.
    pub lost: u64,
    /// Frames duplicated.
    pub duplicated: u64,
    /// Frames held back behind the next one.
    pub reordered: u64,
    /// Frames corrupted.
    pub corrupted: u64,
    /// Frames dropped because its write queue was full.
    pub overflow: u64,
    /// Times its link came up.
    pub connections: u64,
}

/// What happens on the network, for monitoring ([`Network::subscribe`]).
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub enum NetEvent {
    /// A node's link came up.
    Connected {
        /// The node.
        node: Address64,
        /// What is at the other end of its link.
        peer: String,
    },
    /// A node's link went down.
    Disconnected {
        /// The node.
        node: Address64,
        /// Why.
        reason: String,
    },
    /// A node's link ended for good: it cannot be opened, and waiting will not change
    /// that (a serial port's path that is a regular file, reconnection disabled). The
    /// node stays in the network, unreachable; [`Network::link_ended`] says why later.
    LinkEnded {
        /// The node.
        node: Address64,
        /// Why.
        error: String,
    },
    /// A unicast payload was delivered.
    Delivered {
        /// Sender.
        from: Address64,
        /// Receiver.
        to: Address64,
        /// Payload length.
        len: usize,
    },
    /// A broadcast payload was sent.
    Broadcast {
        /// Sender.
        from: Address64,
        /// Payload length.
        len: usize,
        /// How many nodes it was delivered to.
        receivers: usize,
    },
    /// A transmission failed.
    Failed {
        /// Sender.
        from: Address64,
        /// Destination as requested.
        to: Address64,
        /// Payload length.
        len: usize,
        /// The delivery status the sender got.
        status: DeliveryStatus,
    },
    /// A local AT command was answered.
    AtCommand {
        /// The node.
        node: Address64,
        /// The command.
        command: [u8; 2],
        /// The answer's status.
        status: AtStatus,
    },
    /// A node's decoder dropped a candidate frame.
    DecodeError {
        /// The node.
        node: Address64,
        /// Why.
        error: DecodeError,
    },
    /// A frame a radio does not act on (a device sent, say, a Receive Packet).
    Ignored {
        /// The node.
        node: Address64,
        /// Its frame type.
        frame_type: u8,
    },
}

/// Why a node cannot be added.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum NetworkError {
    /// A node with this address is already in the network.
    #[error("node {0} is already in the network")]
    Duplicate(Address64),
    /// The broadcast address cannot be a node.
    #[error("{0} is the broadcast address")]
    Broadcast(Address64),
    /// The link could not be prepared.
    #[error("node {node}: {error}")]
    Link {
        /// The node.
        node: Address64,
        /// Why (in the message too, so no [`source`](std::error::Error::source)).
        error: LinkError,
    },
}

/// Capacity of the event channel of [`Network::subscribe`].
const EVENT_CAPACITY: usize = 1024;

/// A running virtual XBee network. Dropping it (or [`Network::shutdown`]) stops every
/// node; [`Network::stop`] also waits until they have stopped. See the
/// [module docs](self).
#[derive(Debug)]
pub struct Network {
    state: Arc<Mutex<State>>,
    shutdown: CancellationToken,
    /// The nodes' tasks.
    tasks: TaskTracker,
}

impl Network {
    /// An empty network. Nodes are added with [`Network::add_link`],
    /// [`Network::add_stream`] or [`Network::add_in_process`], within a tokio runtime.
    pub fn new(config: NetworkConfig) -> Self {
        let (events, _) = broadcast::channel(EVENT_CAPACITY);
        Network {
            state: Arc::new(Mutex::new(State {
                config,
                nodes: BTreeMap::new(),
                events,
            })),
            shutdown: CancellationToken::new(),
            tasks: TaskTracker::new(),
        }
    }

    /// The seed of the fault generators.
    pub fn seed(&self) -> u64 {
        lock(&self.state).config.seed
    }

    /// Adds a node whose device is at the other end of `link`: a serial port, a TCP
    /// connection, a TCP listener (each new peer is the device back) or a
    /// pseudo-terminal (its path is in the returned [`AddedNode::pty_path`]; the link is
    /// up while a device has that path open). The link is opened in the background and
    /// reopened after each disconnection; a `serial` or `tcp` link that is not there yet
    /// is retried.
    pub async fn add_link(
        &self,
        address: Address64,
        link: &Link,
        options: NodeOptions,
    ) -> Result<AddedNode, NetworkError> {
        self.check_new(address)?;
        if matches!(link, Link::Pty) {
            let port = crate::pty::PtyPort::new().map_err(|error| NetworkError::Link {
                node: address,
                error,
            })?;
            let pty_path = port.path().to_owned();
            let mut info = self.insert(address, options, Source::Pty(port))?;
            info.pty_path = Some(pty_path);
            return Ok(info);
        }
        let link_options = LinkOptions {
            api_mode: options.api_mode,
            connect_timeout: options.connect_timeout,
            ..LinkOptions::default()
        };
        let connector =
            Connector::new(link, &link_options)
                .await
                .map_err(|error| NetworkError::Link {
                    node: address,
                    error,
                })?;
        let pty_path = connector.pty_path().map(PathBuf::from);
        let local_addr = connector.local_addr();
        let source = Source::Link {
            connector: Box::new(connector),
            policy: options.reconnect,
            opened: false,
        };
        let mut info = self.insert(address, options, source)?;
        info.pty_path = pty_path;
        info.local_addr = local_addr;
        Ok(info)
    }

    /// Adds a node whose device is at the other end of `stream`: reachable as soon as
    /// this returns (its modem status is queued). The node stays in the network when the
    /// stream ends, unreachable.
    pub fn add_stream<S>(
        &self,
        address: Address64,
        stream: S,
        options: NodeOptions,
    ) -> Result<AddedNode, NetworkError>
    where
        S: AsyncRead + AsyncWrite + Send + Unpin + 'static,
    {
        self.check_new(address)?;
        self.insert(address, options, Source::Once(Some(Box::new(stream))))
    }

    /// Adds an in-process node and returns its device's end of an in-memory byte stream
    /// ([`tokio::io::duplex`]), for a simulator or a test.
    pub fn add_in_process(
        &self,
        address: Address64,
        options: NodeOptions,
    ) -> Result<(AddedNode, DuplexStream), NetworkError> {
        let (device, radio) = tokio::io::duplex(IN_PROCESS_BUFFER);
        let info = self.add_stream(address, radio, options)?;
        Ok((info, device))
    }

    fn check_new(&self, address: Address64) -> Result<(), NetworkError> {
        if address == Address64::BROADCAST {
            return Err(NetworkError::Broadcast(address));
        }
        if lock(&self.state).nodes.contains_key(&address) {
            return Err(NetworkError::Duplicate(address));
        }
        Ok(())
    }

    fn insert(
        &self,
        address: Address64,
        options: NodeOptions,
        source: Source,
    ) -> Result<AddedNode, NetworkError> {
        let (tx, rx) = mpsc::channel(OUT_CAPACITY);
        let up_already = matches!(source, Source::Once(_));
        let info = {
            let mut state = lock(&self.state);
            if state.nodes.contains_key(&address) {
                return Err(NetworkError::Duplicate(address));
            }
            let addr16 = state.derive_addr16(address);
            let seed = state.config.seed;
            // Its `BD`, and the rate its UART runs at until that is set.
            let baud = if options.transparent {
                router::BAUD_RATE
            } else {
                router::BAUD_RATE_API
            };
            state.nodes.insert(
                address,
                Node {
                    addr16,
                    mode: options.api_mode,
                    transparent: options.transparent,
                    baud,
                    command_mode: false,
                    uart_baud: baud,
                    faults: options.faults,
                    rng: faults::FaultRng::new(seed, address),
                    out: tx,
                    connected: false,
                    cut: false,
                    stats: NodeStats::default(),
                    name: router::NODE_IDENTIFIER.to_vec(),
                    discovery_time: router::DISCOVERY_TIME,
                    new_ap: None,
                    relink: Arc::default(),
                    hangup: Arc::default(),
                    ended: None,
                },
            );
            if up_already {
                // A stream is there at once: the node is reachable as soon as it is added.
                state.connected(address, port::IN_PROCESS.to_owned());
            }
            AddedNode {
                addr64: address,
                addr16,
                api_mode: options.api_mode,
                transparent: options.transparent,
                pty_path: None,
                local_addr: None,
            }
        };
        self.tasks.spawn(port::run(
            self.shutdown.clone(),
            self.state.clone(),
            address,
            source,
            rx,
        ));
        Ok(info)
    }

    /// The 16-bit address of a node.
    pub fn addr16(&self, address: Address64) -> Option<Address16> {
        lock(&self.state).nodes.get(&address).map(|n| n.addr16)
    }

    /// The nodes' 64-bit addresses, ascending.
    pub fn addresses(&self) -> Vec<Address64> {
        lock(&self.state).nodes.keys().copied().collect()
    }

    /// Whether a node's link is up.
    pub fn is_connected(&self, address: Address64) -> bool {
        lock(&self.state)
            .nodes
            .get(&address)
            .is_some_and(|n| n.connected)
    }

    /// Waits until a node's link is up (at once if it is). Returns `false` if the node
    /// is unknown, or once its link ended for good ([`NetEvent::LinkEnded`]).
    pub async fn connected(&self, address: Address64) -> bool {
        let mut events = self.subscribe();
        loop {
            {
                let state = lock(&self.state);
                match state.nodes.get(&address) {
                    None => return false,
                    Some(node) if node.connected => return true,
                    Some(node) if node.ended.is_some() => return false,
                    Some(_) => {}
                }
            }
            if let Err(broadcast::error::RecvError::Closed) = events.recv().await {
                return false;
            }
        }
    }

    /// Why a node's link ended for good ([`NetEvent::LinkEnded`]), if it did: a
    /// monitor that subscribed after the node was added asks this first, as the event
    /// may have come before.
    pub fn link_ended(&self, address: Address64) -> Option<String> {
        lock(&self.state)
            .nodes
            .get(&address)
            .and_then(|n| n.ended.clone())
    }

    /// Takes a node out of radio range: nothing reaches it (unicasts to it fail with
    /// 0x21 network ACK failure), nothing it sends gets through (its unicasts fail with
    /// 0x21, its broadcasts reach no one), though its local radio still answers it.
    /// Returns `false` if the node is unknown.
    pub fn cut(&self, address: Address64) -> bool {
        self.set_cut(address, true)
    }

    /// Closes a node's link of the moment, as if its cable were pulled, the node's
    /// state kept (its settings, a MAV's program), and opens it again as after any
    /// disconnection. What its device sees depends on the link: over TCP the
    /// connection ends (a `tcp-listen` link then takes the next peer, a `tcp` one
    /// connects again); a pseudo-terminal or serial port stays open on the device's
    /// side, so it sees no end, only the frames queued for it dropped and a new modem
    /// status; a stream given to [`add_stream`](Self::add_stream) or
    /// [`add_in_process`](Self::add_in_process) was the only one, and the node stays
    /// down. Returns `false` if the node is unknown or its link is not up.
    ///
    /// The simulator's ground-station link so dropped tests a ground station's
    /// reconnection while the MAVs fly on.
    pub fn disconnect(&self, address: Address64) -> bool {
        match lock(&self.state).nodes.get(&address) {
            Some(node) if node.connected => {
                node.hangup.notify_one();
                true
            }
            _ => false,
        }
    }

    /// Brings a node cut by [`Network::cut`] back in range.
    pub fn restore(&self, address: Address64) -> bool {
        self.set_cut(address, false)
    }

    fn set_cut(&self, address: Address64, cut: bool) -> bool {
        match lock(&self.state).nodes.get_mut(&address) {
            Some(node) => {
                node.cut = cut;
                true
            }
            None => false,
        }
    }

    /// Replaces a node's faults (`None`: the network's). Returns `false` if the node is
    /// unknown.
    pub fn set_faults(&self, address: Address64, faults: Option<Faults>) -> bool {
        match lock(&self.state).nodes.get_mut(&address) {
            Some(node) => {
                node.faults = faults;
                true
            }
            None => false,
        }
    }

    /// A node's counters.
    pub fn stats(&self, address: Address64) -> Option<NodeStats> {
        lock(&self.state).nodes.get(&address).map(|n| n.stats)
    }

    /// Events from now on. A receiver that falls more than 1024 events behind loses
    /// the oldest ones.
    pub fn subscribe(&self) -> broadcast::Receiver<NetEvent> {
        lock(&self.state).events.subscribe()
    }

    /// Tells every node to stop, and returns at once: each node's task then closes its
    /// link as it ends, shortly after. A listening port is free again once its task has
    /// ended, not when this returns: [`Network::stop`] waits for that.
    pub fn shutdown(&self) {
        self.shutdown.cancel();
    }

    /// Stops every node and waits until all of them have ended: their links are closed
    /// and their ports free (a `tcp-listen` port can be listened on again at once).
    ///
    /// ```
    /// # #[tokio::main(flavor = "current_thread")]
    /// # async fn main() {
    /// use mcp_host::radio::{Network, NetworkConfig, NodeOptions};
    /// let network = Network::new(NetworkConfig::default());
    /// let link = "tcp-listen:127.0.0.1:0".parse().unwrap();
    /// let node = network.add_link(mcp_host::xbee_api::Address64::COORDINATOR, &link, NodeOptions::default())
    ///     .await
    ///     .unwrap();
    /// network.stop().await;
    /// // The same port again, straight away.
    /// let again = format!("tcp-listen:{}", node.local_addr.unwrap()).parse().unwrap();
    /// let network = Network::new(NetworkConfig::default());
    /// network.add_link(mcp_host::xbee_api::Address64::COORDINATOR, &again, NodeOptions::default())
    ///     .await
    ///     .unwrap();
    /// # }
    /// ```
    pub async fn stop(&self) {
        self.shutdown.cancel();
        self.tasks.close();
        self.tasks.wait().await;
    }

    /// Runs `task` beside the nodes' tasks: [`stop`](Self::stop) waits for it too (it
    /// must end once the network shuts down, as a device on an in-process node's stream
    /// does when the stream ends).
    pub(crate) fn spawn_beside<F>(&self, task: F)
    where
        F: std::future::Future<Output = ()> + Send + 'static,
    {
        self.tasks.spawn(task);
    }
}

impl Drop for Network {
    fn drop(&mut self) {
        self.shutdown.cancel();
    }
}
