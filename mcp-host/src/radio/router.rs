//! The network's shared state and routing: what a frame from one node turns into.

use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::Duration;

use bytes::Bytes;
use tokio::sync::{Notify, broadcast, mpsc};
use tokio::time::Instant;
use xbee_api::frame::receive_packet::options::{
    ACKNOWLEDGED as RX_ACKNOWLEDGED, BROADCAST as RX_BROADCAST,
};
use xbee_api::{
    Address16, Address64, ApiMode, AtCommandRepr, AtCommandResponseRepr, AtStatus, DeliveryStatus,
    DiscoveryStatus, EncodeFrame, ExplicitRxIndicatorRepr, Frame, ModemStatus, ModemStatusRepr,
    NodeIdentificationIndicatorRepr, ReceivePacketRepr, RemoteAtCommandRepr, RemoteAtResponseRepr,
    SourceEvent, TransmitStatusRepr,
};

use super::faults::{FaultRng, Faults};
use super::wire;
use super::{NetEvent, NetworkConfig, NodeStats};
use crate::command_mode::BAUD_RATES;

/// The longest AT command value the emulated radios answer with (`NI`, 20 characters).
const AT_VALUE_MAX: usize = 20;
/// `HV`: the hardware id of an XBee S2C through-hole module (0x2E), revision 0.
const HARDWARE_VERSION: [u8; 2] = [0x2E, 0x00];
/// `VR`: a Zigbee 3.0 firmware version (API, 0x4060).
const FIRMWARE_VERSION: [u8; 2] = [0x40, 0x60];
/// `NI`: a module's default node identifier, one space.
pub(crate) const NODE_IDENTIFIER: &[u8] = b" ";
/// `ID`: the configured 64-bit extended PAN ID, 0 (Digi's default: the coordinator
/// picks one when it forms the network).
const EXTENDED_PAN_ID: u64 = 0;
/// `OP`: the 64-bit extended PAN ID the network operates on.
const OPERATING_PAN_ID: u64 = 0x0013_A200_4D43_5000;
/// `OI`: the 16-bit PAN ID the network operates on.
const OPERATING_PAN_ID_16: u16 = 0x4D43;
/// `CH`: the operating channel (one of 0x0B..=0x1A; an S2C uses 0x0C..=0x1A).
const OPERATING_CHANNEL: u8 = 0x17;
/// `BD`: the UART baud rate setting a module leaves the factory with, 3 (9600 baud).
pub(crate) const BAUD_RATE: u8 = 3;
/// `BD` of a radio that starts in API mode: 7 (115200 baud, the links' default).
pub(crate) const BAUD_RATE_API: u8 = 7;
/// `GT`: the guard time of AT command mode, in milliseconds (Digi's default, 1 s).
pub(crate) const GUARD_TIME_MS: u16 = 0x3E8;
/// `CT`: how long AT command mode waits for a command, in tenths of a second (Digi's
/// default, 10 s).
pub(crate) const COMMAND_TIMEOUT: u16 = 0x64;

/// `NT`: the node discovery time by default, in tenths of a second (Digi's default, 6 s).
pub(crate) const DISCOVERY_TIME: u16 = 0x3C;
/// The range of `NT` a Zigbee radio accepts (3.2 s to 25.5 s).
const DISCOVERY_TIME_RANGE: std::ops::RangeInclusive<u16> = 0x20..=0xFF;
/// Digi's profile id and manufacturer id, as node discovery answers give them.
const DIGI_PROFILE_ID: u16 = 0xC105;
const DIGI_MANUFACTURER_ID: u16 = 0x101E;

/// Capacity of the queue of frames waiting to be written to one link.
pub(crate) const OUT_CAPACITY: usize = 1024;
/// The 64-bit address that means "use the 16-bit address".
const ADDRESS64_UNKNOWN: Address64 = Address64(0xFFFF_FFFF_FFFF_FFFF);

/// A frame ready for a link: when to write it and whether to hold it back.
#[derive(Debug)]
pub(crate) struct Out {
    pub(crate) at: Instant,
    pub(crate) bytes: Bytes,
    /// Held back behind the next frame for at most this long.
    pub(crate) reorder: Option<Duration>,
    /// The `BD` the node's UART runs at once this is written: a rate set by the AT
    /// command this answers.
    pub(crate) uart_after: Option<u8>,
}

/// One radio of the network.
#[derive(Debug)]
pub(crate) struct Node {
    pub(crate) addr16: Address16,
    pub(crate) mode: ApiMode,
    /// In transparent mode (`AP` = 0): its device gets the payloads it receives as bytes
    /// and nothing else; `mode` applies once its device sets `AP` to 1 or 2.
    pub(crate) transparent: bool,
    /// Its UART baud rate setting (`BD`).
    pub(crate) baud: u8,
    /// The `BD` its UART runs at, whatever a device's end is set to: `BD` as it was
    /// when AT command mode was last left or an API frame last set it.
    pub(crate) uart_baud: u8,
    /// Its device has it in AT command mode (in transparent mode): received payloads
    /// are not passed on meanwhile.
    pub(crate) command_mode: bool,
    pub(crate) faults: Option<Faults>,
    pub(crate) rng: FaultRng,
    pub(crate) out: mpsc::Sender<Out>,
    pub(crate) connected: bool,
    pub(crate) cut: bool,
    pub(crate) stats: NodeStats,
    /// Its node identifier (`NI`): at most [`AT_VALUE_MAX`] printable ASCII characters.
    pub(crate) name: Vec<u8>,
    /// Its node discovery time (`NT`), in tenths of a second.
    pub(crate) discovery_time: u16,
    /// An `AP` set in an API frame, applied once its answer is on its way.
    pub(crate) new_ap: Option<u8>,
    /// Told when what it speaks to its device changes (an `AP` applied), for its
    /// link's task to read its device's writes the new way.
    pub(crate) relink: Arc<Notify>,
    /// Told to close its device's stream of the moment (`Network::disconnect`); given a
    /// permit only while its link is up, under the state's lock.
    pub(crate) hangup: Arc<Notify>,
    /// Why its link ended for good (it cannot be opened, and waiting will not change
    /// that), once it did.
    pub(crate) ended: Option<String>,
}

impl Node {
    /// Whether the radio is in the network: its link up and not cut off.
    fn reachable(&self) -> bool {
        self.connected && !self.cut
    }
}

/// Everything the nodes share, behind one mutex; no lock is held across an await.
#[derive(Debug)]
pub(crate) struct State {
    pub(crate) config: NetworkConfig,
    pub(crate) nodes: BTreeMap<Address64, Node>,
    pub(crate) events: broadcast::Sender<NetEvent>,
}

impl State {
    /// A 16-bit address for `addr64`: the coordinator's is 0000; others fold the 64-bit
    /// address into 16 bits, stepping past reserved values and addresses in use.
    pub(crate) fn derive_addr16(&self, addr64: Address64) -> Address16 {
        if addr64 == Address64::COORDINATOR {
            return Address16::COORDINATOR;
        }
        let a = addr64.0;
        let mut n = ((a ^ (a >> 16) ^ (a >> 32) ^ (a >> 48)) & 0xFFFF) as u16;
        loop {
            let taken = self
                .nodes
                .iter()
                .any(|(k, node)| *k != addr64 && node.addr16.0 == n);
            if n != 0 && n < 0xFFF0 && !taken {
                return Address16(n);
            }
            n = n.wrapping_add(1);
        }
    }

    fn emit(&self, event: NetEvent) {
        let _ = self.events.send(event);
    }

    /// Queues `frame` for `to`, through that node's faults. Returns `false` if the node
    /// is unknown or its queue is full.
    pub(crate) fn send_to<F: EncodeFrame + ?Sized>(
        &mut self,
        to: Address64,
        frame: &F,
        with_faults: bool,
    ) -> bool {
        self.send_then(to, frame, with_faults, None)
    }

    /// [`Self::send_to`], with `to`'s UART set to run at `uart_after` once the frame is
    /// written (at once if it is not written: lost, or not queued).
    fn send_then<F: EncodeFrame + ?Sized>(
        &mut self,
        to: Address64,
        frame: &F,
        with_faults: bool,
        uart_after: Option<u8>,
    ) -> bool {
        let default_faults = self.config.faults;
        let Some(node) = self.nodes.get_mut(&to) else {
            return false;
        };
        // What is not written changes the rate now.
        let unwritten = |node: &mut Node| {
            if let Some(bd) = uart_after {
                node.uart_baud = bd;
            }
        };
        // In transparent mode only received payloads leave the radio, as bytes, and
        // none while its device has it in AT command mode.
        let payload = if node.transparent {
            match wire::payload(frame) {
                Some(payload) if !node.command_mode => Some(payload),
                _ => {
                    unwritten(node);
                    return false;
                }
            }
        } else {
            None
        };
        let faults = node.faults.unwrap_or(default_faults);
        let now = Instant::now();
        let fate = with_faults.then(|| node.rng.decide(&faults));
        let mut copies = 1;
        let mut at = now;
        let mut reorder = None;
        let bytes = match fate {
            Some(fate) => {
                if fate.lost {
                    node.stats.lost += 1;
                    unwritten(node);
                    return true;
                }
                if fate.duplicate {
                    node.stats.duplicated += 1;
                    copies = 2;
                }
                if fate.reorder {
                    node.stats.reordered += 1;
                    reorder = Some(faults.reorder_window);
                }
                at = crate::options::later(now, fate.delay);
                match (fate.corrupt, payload) {
                    (Some((index, mask)), Some(payload)) => {
                        node.stats.corrupted += 1;
                        Some(wire::corrupt_payload(&payload, index, mask))
                    }
                    (Some((index, mask)), None) => {
                        node.stats.corrupted += 1;
                        wire::encode_corrupt(frame, node.mode, index, mask)
                    }
                    (None, Some(payload)) => Some(payload),
                    (None, None) => wire::encode(frame, node.mode),
                }
            }
            None => payload.or_else(|| wire::encode(frame, node.mode)),
        };
        let Some(bytes) = bytes else {
            unwritten(node);
            return false;
        };
        for i in 0..copies {
            let out = Out {
                at,
                bytes: bytes.clone(),
                reorder: reorder.filter(|_| i == 0),
                uart_after: uart_after.filter(|_| i + 1 == copies),
            };
            if node.out.try_send(out).is_err() {
                node.stats.overflow += 1;
                unwritten(node);
                return false;
            }
            node.stats.frames_out += 1;
        }
        true
    }

    /// A link came up: the node is reachable again and gets its modem status.
    pub(crate) fn connected(&mut self, addr: Address64, peer: String) {
        if let Some(node) = self.nodes.get_mut(&addr) {
            node.connected = true;
            node.stats.connections += 1;
        }
        let status = if addr == Address64::COORDINATOR {
            ModemStatus::CoordinatorStarted
        } else {
            ModemStatus::JoinedNetwork
        };
        self.send_to(addr, &ModemStatusRepr { status }, false);
        self.emit(NetEvent::Connected { node: addr, peer });
    }

    /// A link went down.
    pub(crate) fn disconnected(&mut self, addr: Address64, reason: String) {
        if let Some(node) = self.nodes.get_mut(&addr) {
            node.connected = false;
        }
        self.emit(NetEvent::Disconnected { node: addr, reason });
    }

    /// A link ended for good: it cannot be opened, and waiting will not change that.
    pub(crate) fn link_ended(&mut self, addr: Address64, error: String) {
        if let Some(node) = self.nodes.get_mut(&addr) {
            node.connected = false;
            node.ended = Some(error.clone());
        }
        self.emit(NetEvent::LinkEnded { node: addr, error });
    }

    /// A link's decoder dropped a candidate frame.
    pub(crate) fn decode_error(&mut self, addr: Address64, error: xbee_api::DecodeError) {
        if let Some(node) = self.nodes.get_mut(&addr) {
            node.stats.decode_errors += 1;
        }
        self.emit(NetEvent::DecodeError { node: addr, error });
    }

    /// Handles a frame a node's device wrote to its radio.
    pub(crate) fn handle(&mut self, from: Address64, data: &[u8]) {
        let Some(node) = self.nodes.get_mut(&from) else {
            return;
        };
        node.stats.frames_in += 1;
        match Frame::parse_bytes(data) {
            Ok(Frame::TransmitRequest(tx)) => {
                self.transmit(from, tx.frame_id, tx.dst64, tx.dst16, tx.data, None);
            }
            Ok(Frame::ExplicitAddressingCommand(ex)) => {
                let explicit = Explicit {
                    src_endpoint: ex.src_endpoint,
                    dst_endpoint: ex.dst_endpoint,
                    cluster_id: ex.cluster_id,
                    profile_id: ex.profile_id,
                };
                self.transmit(
                    from,
                    ex.frame_id,
                    ex.dst64,
                    ex.dst16,
                    ex.data,
                    Some(explicit),
                );
            }
            Ok(Frame::AtCommand(at)) => self.at_command(from, &at),
            Ok(Frame::RemoteAtCommand(at)) => self.remote_at_command(from, &at),
            Ok(other) => {
                self.emit(NetEvent::Ignored {
                    node: from,
                    frame_type: other.frame_type(),
                });
            }
            Err(error) => {
                tracing::debug!(node = %from, %error, "malformed frame ignored");
                self.emit(NetEvent::Ignored {
                    node: from,
                    frame_type: data.first().copied().unwrap_or(0),
                });
            }
        }
    }

    fn status(
        &mut self,
        from: Address64,
        frame_id: u8,
        dst16: Address16,
        delivery: DeliveryStatus,
        discovery: DiscoveryStatus,
    ) {
        if frame_id == 0 {
            return;
        }
        let status = TransmitStatusRepr {
            frame_id,
            dst16,
            retries: 0,
            delivery,
            discovery,
        };
        self.send_to(from, &status, true);
    }

    /// Queues a received payload for `to`: a Receive Packet, or an Explicit Rx
    /// Indicator for an Explicit Addressing Command.
    fn deliver(
        &mut self,
        to: Address64,
        from: Address64,
        src16: Address16,
        options: u8,
        data: &[u8],
        explicit: Option<Explicit>,
    ) {
        match explicit {
            None => {
                let rx = ReceivePacketRepr {
                    src64: from,
                    src16,
                    options,
                    data,
                };
                self.send_to(to, &rx, true);
            }
            Some(e) => {
                let rx = ExplicitRxIndicatorRepr {
                    src64: from,
                    src16,
                    src_endpoint: e.src_endpoint,
                    dst_endpoint: e.dst_endpoint,
                    cluster_id: e.cluster_id,
                    profile_id: e.profile_id,
                    options,
                    data,
                };
                self.send_to(to, &rx, true);
            }
        }
    }

    /// Delivers a Transmit Request's payload and answers with a Transmit Status.
    fn transmit(
        &mut self,
        from: Address64,
        frame_id: u8,
        dst64: Address64,
        dst16: Address16,
        data: &[u8],
        explicit: Option<Explicit>,
    ) {
        let Some(src) = self.nodes.get(&from) else {
            return;
        };
        let src16 = src.addr16;
        let src_cut = src.cut;
        let broadcast = dst64 == Address64::BROADCAST;
        let limit = if broadcast {
            self.config.max_broadcast
        } else {
            self.config.max_unicast
        };
        let ok = DiscoveryStatus::NoDiscoveryOverhead;
        if data.len() > limit {
            self.emit(NetEvent::Failed {
                from,
                to: dst64,
                len: data.len(),
                status: DeliveryStatus::PayloadTooLarge,
            });
            self.status(
                from,
                frame_id,
                Address16::UNKNOWN,
                DeliveryStatus::PayloadTooLarge,
                ok,
            );
            return;
        }
        if broadcast {
            let others = self.reached_from(from);
            for to in &others {
                self.deliver(*to, from, src16, RX_BROADCAST, data, explicit);
            }
            self.emit(NetEvent::Broadcast {
                from,
                len: data.len(),
                receivers: others.len(),
            });
            self.status(
                from,
                frame_id,
                Address16::UNKNOWN,
                DeliveryStatus::Success,
                ok,
            );
            return;
        }
        let Some(dst) = self.resolve(dst64, dst16) else {
            self.emit(NetEvent::Failed {
                from,
                to: dst64,
                len: data.len(),
                status: DeliveryStatus::AddressNotFound,
            });
            self.status(
                from,
                frame_id,
                Address16::UNKNOWN,
                DeliveryStatus::AddressNotFound,
                DiscoveryStatus::AddressDiscovery,
            );
            return;
        };
        let Some(node) = self.nodes.get(&dst) else {
            return;
        };
        let dst16 = node.addr16;
        let delivery = if dst == from {
            DeliveryStatus::SelfAddressed
        } else if !node.connected || node.cut || src_cut {
            DeliveryStatus::NetworkAckFailure
        } else {
            DeliveryStatus::Success
        };
        if delivery == DeliveryStatus::Success {
            self.deliver(dst, from, src16, RX_ACKNOWLEDGED, data, explicit);
            self.emit(NetEvent::Delivered {
                from,
                to: dst,
                len: data.len(),
            });
        } else {
            self.emit(NetEvent::Failed {
                from,
                to: dst,
                len: data.len(),
                status: delivery,
            });
        }
        self.status(from, frame_id, dst16, delivery, ok);
    }

    /// The node a destination means: by 64-bit address, or by 16-bit address when the
    /// 64-bit one is FFFFFFFFFFFFFFFF.
    fn resolve(&self, dst64: Address64, dst16: Address16) -> Option<Address64> {
        if dst64 == ADDRESS64_UNKNOWN {
            self.nodes
                .iter()
                .find(|(_, n)| n.addr16 == dst16)
                .map(|(a, _)| *a)
        } else {
            self.nodes.contains_key(&dst64).then_some(dst64)
        }
    }

    /// Executes an AT command on `node`'s radio: its status and the value, written into
    /// `value`, of length returned. Reads answer as an S2C with Zigbee firmware would;
    /// `NI`, `NT`, `BD` and `AP` can be set (the last two change the device's link once
    /// the answer is on its way: [`Self::apply_ap`], [`Self::send_then`]); any other value gets invalid
    /// parameter, and a command the radio does not emulate invalid command.
    /// A value set is read back at once, whether it was applied or queued (nothing else
    /// in the emulation depends on it), so `AC` (apply changes) and `WR` (write to
    /// non-volatile memory) have nothing to do but answer ok. `CB` 1 (the commissioning
    /// button pressed once) broadcasts the node's identification.
    fn at_value(
        &mut self,
        node: Address64,
        command: [u8; 2],
        parameter: &[u8],
        value: &mut [u8; AT_VALUE_MAX],
    ) -> (AtStatus, usize) {
        let max_unicast = self.config.max_unicast;
        let Some(radio) = self.nodes.get_mut(&node) else {
            return (AtStatus::Error, 0);
        };
        // A read: `bytes` are the value (at most `AT_VALUE_MAX` of them).
        let mut read = |bytes: &[u8]| match value.get_mut(..bytes.len()) {
            Some(out) => {
                out.copy_from_slice(bytes);
                (AtStatus::Ok, bytes.len())
            }
            None => (AtStatus::Error, 0),
        };
        match (&command, parameter) {
            (b"AP", []) if radio.transparent => read(&[0]),
            (b"AP", []) => read(&[u8::from(radio.mode)]),
            (b"AP", [ap @ 0..=2]) => {
                radio.new_ap = Some(*ap);
                (AtStatus::Ok, 0)
            }
            (b"NP", []) => {
                let np = u16::try_from(max_unicast).unwrap_or(u16::MAX);
                read(&np.to_be_bytes())
            }
            (b"SH", []) => read(&node.to_bytes()[..4]),
            (b"SL", []) => read(&node.to_bytes()[4..]),
            (b"MY", []) => read(&radio.addr16.to_bytes()),
            (b"AI", []) => read(&[0]),
            (b"CE", []) => read(&[u8::from(node == Address64::COORDINATOR)]),
            (b"SM", []) => read(&[0]),
            (b"HV", []) => read(&HARDWARE_VERSION),
            (b"VR", []) => read(&FIRMWARE_VERSION),
            (b"ID", []) => read(&EXTENDED_PAN_ID.to_be_bytes()),
            (b"OP", []) => read(&OPERATING_PAN_ID.to_be_bytes()),
            (b"OI", []) => read(&OPERATING_PAN_ID_16.to_be_bytes()),
            (b"CH", []) => read(&[OPERATING_CHANNEL]),
            (b"NI", []) => {
                let name = radio.name.clone();
                read(&name)
            }
            (b"NI", name) if is_node_identifier(name) => {
                radio.name = name.to_vec();
                (AtStatus::Ok, 0)
            }
            (b"NT", []) => {
                let nt = radio.discovery_time;
                read(&nt.to_be_bytes())
            }
            // One or two bytes, big-endian.
            (b"NT", [_] | [_, _]) => {
                let nt = parameter.iter().fold(0u16, |n, &b| (n << 8) | u16::from(b));
                if !DISCOVERY_TIME_RANGE.contains(&nt) {
                    return (AtStatus::InvalidParameter, 0);
                }
                radio.discovery_time = nt;
                (AtStatus::Ok, 0)
            }
            (b"BD", []) => read(&[radio.baud]),
            // 0 to 8, 1200 to 230400 baud.
            (b"BD", [bd]) if usize::from(*bd) < BAUD_RATES.len() => {
                radio.baud = *bd;
                (AtStatus::Ok, 0)
            }
            (b"GT", []) => read(&GUARD_TIME_MS.to_be_bytes()),
            (b"CT", []) => read(&COMMAND_TIMEOUT.to_be_bytes()),
            (b"AC" | b"WR", []) => (AtStatus::Ok, 0),
            // The commissioning button pressed once: the node identification goes out.
            (b"CB", [1]) => {
                self.node_identification(node);
                (AtStatus::Ok, 0)
            }
            (
                b"AP" | b"NP" | b"SH" | b"SL" | b"MY" | b"AI" | b"CE" | b"SM" | b"HV" | b"VR"
                | b"NI" | b"NT" | b"ID" | b"OP" | b"OI" | b"CH" | b"BD" | b"GT" | b"CT" | b"AC"
                | b"WR" | b"CB",
                _,
            ) => (AtStatus::InvalidParameter, 0),
            _ => (AtStatus::InvalidCommand, 0),
        }
    }

    /// Carries out a command line of AT command mode on `node`'s radio, `AT` and the
    /// command (`AP` and `CN` excepted: the command mode itself handles them) and its
    /// value as typed: hex for a number, text for `NI`. The answer line, without its
    /// carriage return: the value read (hex, no leading zeros; text for `NI`), `OK`, or
    /// `ERROR` for a command or value the radio does not take (`ND` among them: node
    /// discovery is answered in API mode only).
    pub(crate) fn command_line(
        &mut self,
        node: Address64,
        command: [u8; 2],
        value: &str,
    ) -> String {
        let text = command == *b"NI";
        let parameter = if text {
            Some(value.trim_start().as_bytes().to_vec())
        } else {
            hex_value(value)
        };
        let Some(parameter) = parameter.filter(|_| command != *b"ND") else {
            return "ERROR".to_owned();
        };
        let mut value = [0u8; AT_VALUE_MAX];
        let (status, len) = self.at_value(node, command, &parameter, &mut value);
        self.emit(NetEvent::AtCommand {
            node,
            command,
            status,
        });
        let value = value.get(..len).unwrap_or_default();
        match status {
            AtStatus::Ok if value.is_empty() => "OK".to_owned(),
            AtStatus::Ok if text => String::from_utf8_lossy(value).into_owned(),
            AtStatus::Ok => {
                let n = value.iter().fold(0u64, |n, &b| (n << 8) | u64::from(b));
                format!("{n:X}")
            }
            _ => "ERROR".to_owned(),
        }
    }

    /// `node`'s radio entered AT command mode: received payloads are not passed on
    /// until it leaves.
    pub(crate) fn enter_command_mode(&mut self, node: Address64) {
        if let Some(radio) = self.nodes.get_mut(&node) {
            radio.command_mode = true;
        }
    }

    /// `node`'s radio left AT command mode with `ap` its API mode setting: 0 stays in
    /// transparent mode, 1 and 2 switch to API frames in that mode. Its mode now.
    pub(crate) fn leave_command_mode(&mut self, node: Address64, ap: u8) -> LinkMode {
        let Some(radio) = self.nodes.get_mut(&node) else {
            return LinkMode::Transparent;
        };
        radio.command_mode = false;
        // A new `BD` takes effect now, as on a radio.
        radio.uart_baud = radio.baud;
        if let Ok(mode) = ApiMode::try_from(ap) {
            radio.mode = mode;
            radio.transparent = false;
        }
        self.emit(NetEvent::AtCommand {
            node,
            command: *b"CN",
            status: AtStatus::Ok,
        });
        self.link_mode(node)
    }

    /// The baud rate `node`'s UART runs at.
    pub(crate) fn uart_rate(&self, node: Address64) -> Option<u32> {
        let baud = self.nodes.get(&node)?.uart_baud;
        BAUD_RATES.get(usize::from(baud)).copied()
    }

    /// What `node`'s radio speaks to its device.
    pub(crate) fn link_mode(&self, node: Address64) -> LinkMode {
        match self.nodes.get(&node) {
            Some(radio) if !radio.transparent => LinkMode::Api(radio.mode),
            _ => LinkMode::Transparent,
        }
    }

    /// Answers a local AT command.
    fn at_command(&mut self, from: Address64, at: &AtCommandRepr<'_>) {
        if at.command == *b"ND" {
            return self.node_discovery(from, at);
        }
        let mut value = [0u8; AT_VALUE_MAX];
        let (status, len) = self.at_value(from, at.command, at.parameter, &mut value);
        self.emit(NetEvent::AtCommand {
            node: from,
            command: at.command,
            status,
        });
        // A new rate, taken once the answer is written at the old one.
        let uart_after = self
            .nodes
            .get(&from)
            .and_then(|radio| (radio.uart_baud != radio.baud).then_some(radio.baud));
        if at.frame_id == 0 {
            self.set_uart(from, uart_after);
        } else {
            let response = AtCommandResponseRepr {
                frame_id: at.frame_id,
                command: at.command,
                status,
                data: &value[..len],
            };
            self.send_then(from, &response, true, uart_after);
        }
        self.apply_ap(from);
    }

    /// `node`'s UART runs at `bd` from now on, if given.
    pub(crate) fn set_uart(&mut self, node: Address64, bd: Option<u8>) {
        if let (Some(radio), Some(bd)) = (self.nodes.get_mut(&node), bd) {
            radio.uart_baud = bd;
        }
    }

    /// Applies what AT commands in API frames did to `node`'s radio, for the answer
    /// the destination's device reads from another radio: [`Self::apply_ap`], and a new
    /// `BD` at once.
    fn apply_remote(&mut self, node: Address64) {
        if let Some(radio) = self.nodes.get_mut(&node) {
            radio.uart_baud = radio.baud;
        }
        self.apply_ap(node);
    }

    /// Applies an `AP` set in an API frame to how `node`'s radio speaks to its device,
    /// once the answer is queued (encoded the old way), as a radio applies a setting
    /// after answering: 0 is transparent mode, 1 and 2 API frames in that mode.
    fn apply_ap(&mut self, node: Address64) {
        let Some(radio) = self.nodes.get_mut(&node) else {
            return;
        };
        match radio.new_ap.take().map(ApiMode::try_from) {
            Some(Ok(mode)) => {
                radio.mode = mode;
                radio.transparent = false;
            }
            // 0, the one other value `at_value` takes.
            Some(Err(_)) => radio.transparent = true,
            None => return,
        }
        radio.relink.notify_one();
    }

    /// The other nodes `from`'s radio reaches, as a broadcast from it would: none while
    /// it is down or cut off.
    fn reached_from(&self, from: Address64) -> Vec<Address64> {
        match self.nodes.get(&from) {
            Some(me) if me.reachable() => self
                .nodes
                .iter()
                .filter(|(a, n)| **a != from && n.reachable())
                .map(|(a, _)| *a)
                .collect(),
            _ => Vec::new(),
        }
    }

    /// Node discovery (`ND`) from `from`'s radio: an AT Command Response for each other
    /// node it can reach (with `ND NAME`: the one whose `NI` is NAME, or one response
    /// with status 1, error, if none is), all at once, as the answers of a network of
    /// quick radios (a real one spreads them over `NT`). A radio cut off from the
    /// network finds none.
    fn node_discovery(&mut self, from: Address64, at: &AtCommandRepr<'_>) {
        let found: Vec<(Address64, Address16, Vec<u8>)> = self
            .reached_from(from)
            .into_iter()
            .filter_map(|a| self.nodes.get(&a).map(|n| (a, n)))
            .filter(|(_, n)| at.parameter.is_empty() || n.name == at.parameter)
            .map(|(a, n)| (a, n.addr16, n.name.clone()))
            .collect();
        self.emit(NetEvent::AtCommand {
            node: from,
            command: at.command,
            status: AtStatus::Ok,
        });
        if at.frame_id == 0 {
            return;
        }
        if found.is_empty() && !at.parameter.is_empty() {
            let response = AtCommandResponseRepr {
                frame_id: at.frame_id,
                command: at.command,
                status: AtStatus::Error,
                data: &[],
            };
            self.send_to(from, &response, true);
            return;
        }
        for (addr64, addr16, name) in found {
            let info = node_info(addr64, addr16, &name, 0);
            let mut data = [0u8; 64];
            let Ok(len) = info.emit(&mut data) else {
                continue;
            };
            let response = AtCommandResponseRepr {
                frame_id: at.frame_id,
                command: at.command,
                status: AtStatus::Ok,
                data: data.get(..len).unwrap_or_default(),
            };
            self.send_to(from, &response, true);
        }
    }

    /// `from`'s radio broadcasts its node identification (its commissioning button was
    /// pressed once, `CB` 1): every other radio it reaches hands its device a Node
    /// Identification Indicator (radios in transparent mode hand over nothing).
    fn node_identification(&mut self, from: Address64) {
        let Some(me) = self.nodes.get(&from) else {
            return;
        };
        let (addr16, name) = (me.addr16, me.name.clone());
        let frame = NodeIdentificationIndicatorRepr {
            src64: from,
            src16: addr16,
            options: RX_BROADCAST,
            node: node_info(from, addr16, &name, u8::from(SourceEvent::Pushbutton)),
        };
        for target in self.reached_from(from) {
            self.send_to(target, &frame, true);
        }
    }

    /// Answers a remote AT command on behalf of the destination's radio; a destination
    /// that is unknown, down or cut gets status 4, transmission failure.
    fn remote_at_command(&mut self, from: Address64, at: &RemoteAtCommandRepr<'_>) {
        if at.dst64 == Address64::BROADCAST {
            return self.broadcast_remote_at_command(from, at);
        }
        let target = self.resolve(at.dst64, at.dst16).filter(|t| {
            let reachable = |a: &Address64| self.nodes.get(a).is_some_and(Node::reachable);
            reachable(t) && reachable(&from)
        });
        let mut value = [0u8; AT_VALUE_MAX];
        let (src64, src16, status, len) = match target {
            Some(t) => {
                let (status, len) = self.at_value(t, at.command, at.parameter, &mut value);
                // The answer goes to `from`'s device, not to `t`'s.
                self.apply_remote(t);
                let src16 = self.nodes.get(&t).map_or(Address16::UNKNOWN, |n| n.addr16);
                (t, src16, status, len)
            }
            None => (at.dst64, Address16::UNKNOWN, AtStatus::TxFailure, 0),
        };
        self.emit(NetEvent::AtCommand {
            node: src64,
            command: at.command,
            status,
        });
        if at.frame_id == 0 {
            return;
        }
        let response = RemoteAtResponseRepr {
            frame_id: at.frame_id,
            src64,
            src16,
            command: at.command,
            status,
            data: &value[..len],
        };
        self.send_to(from, &response, true);
    }

    /// A remote AT command to the broadcast address: every other node `from` can reach
    /// carries it out, but, as on Zigbee radios, `from` hands over a single answer (the
    /// first node's, with its address), however many carried it out; a radio cut off
    /// from the network reaches none, and nobody answers.
    fn broadcast_remote_at_command(&mut self, from: Address64, at: &RemoteAtCommandRepr<'_>) {
        let mut answered = false;
        for target in self.reached_from(from) {
            let mut value = [0u8; AT_VALUE_MAX];
            let (status, len) = self.at_value(target, at.command, at.parameter, &mut value);
            self.apply_remote(target);
            self.emit(NetEvent::AtCommand {
                node: target,
                command: at.command,
                status,
            });
            if at.frame_id == 0 || answered {
                continue;
            }
            answered = true;
            let response = RemoteAtResponseRepr {
                frame_id: at.frame_id,
                src64: target,
                src16: self
                    .nodes
                    .get(&target)
                    .map_or(Address16::UNKNOWN, |n| n.addr16),
                command: at.command,
                status,
                data: value.get(..len).unwrap_or_default(),
            };
            self.send_to(from, &response, true);
        }
    }
}

/// What a radio speaks to its device.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum LinkMode {
    /// Transparent mode (`AP` = 0): received payloads as bytes, and AT command mode.
    Transparent,
    /// API frames in this mode.
    Api(ApiMode),
}

/// A number typed in AT command mode: up to 16 hex digits (spaces ignored, `0x` before
/// them allowed), as big-endian bytes without leading zero bytes (one 0x00 for zero);
/// nothing for no digits. `None` for anything else.
pub(super) fn hex_value(text: &str) -> Option<Vec<u8>> {
    let text = text.trim_start();
    let unprefixed = text.strip_prefix("0x").or_else(|| text.strip_prefix("0X"));
    let digits: String = unprefixed
        .unwrap_or(text)
        .chars()
        .filter(|c| *c != ' ')
        .collect();
    if digits.is_empty() {
        // No value: a read; `0x` alone is no number.
        return unprefixed.is_none().then(Vec::new);
    }
    if digits.len() > 16 || !digits.chars().all(|c| c.is_ascii_hexdigit()) {
        return None;
    }
    let n = u64::from_str_radix(&digits, 16).ok()?;
    let bytes = n.to_be_bytes();
    let first = bytes
        .iter()
        .position(|&b| b != 0)
        .unwrap_or(bytes.len() - 1);
    Some(bytes.get(first..).unwrap_or_default().to_vec())
}

/// Whether `name` is a node identifier a radio accepts: 1 to 20 printable ASCII
/// characters.
fn is_node_identifier(name: &[u8]) -> bool {
    (1..=AT_VALUE_MAX).contains(&name.len()) && name.iter().all(|b| (0x20..0x7F).contains(b))
}

/// The addressing fields of an Explicit Addressing Command, carried to the receiver.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Explicit {
    src_endpoint: u8,
    dst_endpoint: u8,
    cluster_id: u16,
    profile_id: u16,
}

/// What node discovery and node identification say of a radio of this network:
/// coordinator or router, no parent named, Digi's profile and manufacturer, and
/// `status` (0 in a discovery answer, the [`SourceEvent`] in an identification).
fn node_info(
    addr64: Address64,
    addr16: Address16,
    name: &[u8],
    status: u8,
) -> xbee_api::NodeInfo<'_> {
    xbee_api::NodeInfo {
        addr16,
        addr64,
        identifier: name,
        parent: Address16::UNKNOWN,
        device_type: if addr64 == Address64::COORDINATOR {
            xbee_api::DeviceType::Coordinator
        } else {
            xbee_api::DeviceType::Router
        },
        status,
        profile_id: DIGI_PROFILE_ID,
        manufacturer_id: DIGI_MANUFACTURER_ID,
        device_type_identifier: None,
        rssi: None,
    }
}
