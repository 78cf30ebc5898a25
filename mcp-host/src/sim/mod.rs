//! Simulated MAVs: the MCP state machine of `mcp_core::mav` over a small flight model,
//! speaking XBee API mode 1 to a virtual radio, as the deployed MAVs do.
//!
//! - [`SimVehicle`]: the flight model (landing state machine, controllers, trajectory,
//!   position, clock).
//! - [`SimMav`]: the protocol side without I/O: feed it payloads and ticks, get the
//!   payloads it sends (answers, unsolicited reports, 20 Hz telemetry).
//! - [`run_mav`]: a MAV on a byte stream to its XBee (Receive Packets in, Transmit
//!   Requests to the coordinator out: frame id 0, 16-bit address FFFE, option 0x01).
//! - [`Simulator`]: a fleet of MAVs behind a [virtual XBee network](crate::radio) whose
//!   coordinator is a link: the far end of the link sees what a ground station sees from
//!   its local XBee.
//!
//! ```no_run
//! use mcp_host::sim::{Simulator, fleet_addresses};
//! use mcp_host::xbee_api::ApiMode;
//!
//! # async fn run() -> Result<(), Box<dyn std::error::Error>> {
//! let sim = Simulator::start(&"pty".parse()?, ApiMode::Unescaped, &fleet_addresses(2),
//!                            Simulator::network_config()).await?;
//! println!("ground station: serial:{}", sim.coordinator().pty_path.as_ref().unwrap().display());
//! # Ok(())
//! # }
//! ```

mod vehicle;

use std::time::{Duration, SystemTime};

use bytes::Bytes;
use futures::{SinkExt, StreamExt};
use mcp_core::mav::Mav;
use tokio::io::{AsyncRead, AsyncWrite};
use tokio::time::{Instant, MissedTickBehavior};
use tokio_util::codec::Framed;
use xbee_api::{Address16, Address64, ApiMode, Frame, TransmitRequestRepr};

pub use vehicle::{CRUISE_ALTITUDE, LANDING_RATE, STABILIZATION_TIME, SimVehicle};

use crate::codec::{CodecItem, XBeeCodec};
use crate::link::Link;
use crate::radio::{AddedNode, Network, NetworkConfig, NetworkError, NodeOptions};

/// Period of the telemetry packets (20 Hz).
pub const TELEMETRY_PERIOD: Duration = Duration::from_millis(50);

/// The known MAV addresses, in fleet order.
pub const KNOWN_MAVS: [Address64; 4] = [
    Address64(0x0013_A200_40B5_99B9),
    Address64(0x0013_A200_40B5_99BF),
    Address64(0x0013_A200_40B5_99BD),
    Address64(0x0013_A200_40B5_99B8),
];

/// `n` MAV addresses: the known ones first, then made-up ones
/// (0013A20040B5A000, 0013A20040B5A001...).
///
/// ```
/// use mcp_host::sim::fleet_addresses;
/// let fleet = fleet_addresses(5);
/// assert_eq!(fleet[0].to_string().to_uppercase(), "0013A20040B599B9");
/// assert_eq!(fleet[4].0, 0x0013_A200_40B5_A000);
/// ```
pub fn fleet_addresses(n: usize) -> Vec<Address64> {
    (0..n)
        .map(|i| match KNOWN_MAVS.get(i) {
            Some(a) => *a,
            None => Address64(0x0013_A200_40B5_A000 + (i - KNOWN_MAVS.len()) as u64),
        })
        .collect()
}

/// The current POSIX time in seconds, saturated to `u32`.
pub fn posix_now() -> u32 {
    SystemTime::now()
        .duration_since(SystemTime::UNIX_EPOCH)
        .map(|d| u32::try_from(d.as_secs()).unwrap_or(u32::MAX))
        .unwrap_or(0)
}

/// One simulated MAV without I/O: the protocol state machine and the flight model.
///
/// ```
/// use mcp_host::sim::SimMav;
/// let mut mav = SimMav::new(1_700_000_000);
/// // Status request of the landing state: answered at once.
/// assert_eq!(mav.handle_payload(b"c\x02\xff"), vec![&b"r\x02\x04"[..]]);
/// // Telemetry of altitude: one packet per tick.
/// assert!(mav.handle_payload(b"c\x01\x01\x01").is_empty());
/// let out = mav.tick(0.05);
/// assert_eq!(out.len(), 1);
/// assert_eq!(&out[0][..], b"t\x01\x00\x00\x80\x3f"); // altitude 1.0 (little-endian f32)
/// ```
#[derive(Debug, Clone)]
pub struct SimMav {
    mav: Mav,
    vehicle: SimVehicle,
}

impl SimMav {
    /// A MAV in flight, its clock at `time`.
    pub fn new(time: u32) -> Self {
        let vehicle = SimVehicle::new(time);
        SimMav {
            mav: Mav::new(&vehicle),
            vehicle,
        }
    }

    /// The flight model.
    pub fn vehicle(&self) -> &SimVehicle {
        &self.vehicle
    }

    /// The protocol state.
    pub fn mav(&self) -> &Mav {
        &self.mav
    }

    /// Handles a received payload; returns the payloads to send: the direct answer, if
    /// any, then the unsolicited reports. Invalid packets and non-commands are ignored.
    pub fn handle_payload(&mut self, payload: &[u8]) -> Vec<Bytes> {
        let mut out = Vec::new();
        let mut buf = [0u8; mcp_core::MAX_PAYLOAD];
        match mcp_core::parse(payload) {
            Ok(packet) => {
                if let Ok(Some(len)) = self.mav.handle_packet(&mut self.vehicle, &packet, &mut buf)
                {
                    out.push(Bytes::copy_from_slice(&buf[..len]));
                }
            }
            Err(error) => tracing::debug!(%error, "invalid packet ignored"),
        }
        self.changes(&mut out);
        out
    }

    /// Advances the flight model by `dt` seconds; returns the payloads to send: the
    /// unsolicited reports of state changes, then the telemetry packet (if any id is
    /// enabled).
    pub fn tick(&mut self, dt: f32) -> Vec<Bytes> {
        self.vehicle.step(dt);
        let mut out = Vec::new();
        self.changes(&mut out);
        let mut buf = [0u8; mcp_core::MAX_PAYLOAD];
        if let Ok(Some(len)) = self.mav.telemetry(&self.vehicle, &mut buf) {
            out.push(Bytes::copy_from_slice(&buf[..len]));
        }
        out
    }

    fn changes(&mut self, out: &mut Vec<Bytes>) {
        let mut buf = [0u8; mcp_core::MAX_PAYLOAD];
        while let Ok(Some(len)) = self.mav.poll_changes(&self.vehicle, &mut buf) {
            out.push(Bytes::copy_from_slice(&buf[..len]));
        }
    }
}

/// Size of the deployed MAV's UART receive buffer, bytes.
pub const MAV_RX_BUFFER: usize = 60;

/// Options of the simulated MAVs and of the ground station's radio.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SimOptions {
    /// Drop received frames longer than this many bytes on the wire (start delimiter,
    /// length, frame data and checksum), as a firmware with a fixed receive buffer
    /// would ([`MAV_RX_BUFFER`] for the deployed MAV). `None`: no limit.
    pub rx_buffer: Option<usize>,
    /// The ground station's radio (the coordinator) starts in transparent mode
    /// (`AP` = 0), as XBee modules leave the factory, until it is put into API mode
    /// through its AT command mode ([`NodeOptions::transparent`]).
    pub coordinator_transparent: bool,
}

/// Runs a simulated MAV on `io`, the UART to its XBee in API mode 1, until the stream
/// ends. Commands arrive as Receive Packets; answers, reports and 20 Hz telemetry leave as
/// Transmit Requests to the coordinator.
pub async fn run_mav<S>(io: S, mav: SimMav) -> std::io::Result<()>
where
    S: AsyncRead + AsyncWrite + Unpin,
{
    run_mav_with(io, mav, SimOptions::default()).await
}

/// [`run_mav`] with options.
pub async fn run_mav_with<S>(io: S, mut mav: SimMav, options: SimOptions) -> std::io::Result<()>
where
    S: AsyncRead + AsyncWrite + Unpin,
{
    let fits = |len: usize| options.rx_buffer.is_none_or(|max| len + 4 <= max);
    let mut framed = Framed::new(io, XBeeCodec::new(ApiMode::Unescaped));
    let mut ticks = tokio::time::interval(TELEMETRY_PERIOD);
    // A late tick does not put the next ones later: on a clock that fires timers up to
    // 15.6 ms late (Windows' default), the telemetry keeps its 20 Hz, where `Delay`
    // made it 16. A tick missed wholly (the process stopped) is skipped, not caught up.
    ticks.set_missed_tick_behavior(MissedTickBehavior::Skip);
    let mut last = Instant::now();
    loop {
        let out = tokio::select! {
            item = framed.next() => match item {
                Some(Ok(CodecItem::Frame(frame))) if !fits(frame.data().len()) => {
                    // A warning: the command is lost, as on the deployed MAV, and the
                    // ground station learns of it by a timeout at best.
                    tracing::warn!(
                        frame_bytes = frame.data().len() + 4,
                        rx_buffer = options.rx_buffer,
                        "simulated MAV: a frame over its UART receive buffer dropped"
                    );
                    Vec::new()
                }
                Some(Ok(CodecItem::Frame(frame))) => match frame.parse() {
                    Ok(Frame::ReceivePacket(rx)) => mav.handle_payload(rx.data),
                    _ => Vec::new(),
                },
                Some(Ok(CodecItem::Error(error))) => {
                    tracing::debug!(%error, "MAV UART: frame dropped");
                    Vec::new()
                }
                Some(Err(e)) => return Err(e),
                None => return Ok(()),
            },
            now = ticks.tick() => {
                let dt = now.duration_since(last).as_secs_f32();
                last = now;
                mav.tick(dt)
            }
        };
        for payload in out {
            let tx = TransmitRequestRepr {
                frame_id: 0,
                dst64: Address64::COORDINATOR,
                dst16: Address16::UNKNOWN,
                radius: 0,
                options: 0x01,
                data: &payload,
            };
            framed.feed(&tx).await?;
        }
        SinkExt::<&TransmitRequestRepr<'_>>::flush(&mut framed).await?;
    }
}

/// Simulated MAVs behind a virtual XBee network whose coordinator is a link.
///
/// It runs until [`stop`](Self::stop)ped, [`shutdown`](Self::shutdown) or dropped:
/// dropping it stops the network and its MAVs at once, so hold it for as long as a
/// ground station talks to it.
///
/// ```
/// # #[tokio::main(flavor = "current_thread")]
/// # async fn main() -> Result<(), Box<dyn std::error::Error>> {
/// use mcp_host::mcp_core::{Report, StatusRequest};
/// use mcp_host::sim::{Simulator, fleet_addresses};
/// use mcp_host::xbee_api::ApiMode;
/// use mcp_host::{Link, LinkOptions};
///
/// // One MAV; its ground station's radio on a free TCP port of this machine.
/// let mavs = fleet_addresses(1);
/// let sim = Simulator::start(
///     &Link::tcp_listen("127.0.0.1", 0),
///     ApiMode::Unescaped,
///     &mavs,
///     Simulator::network_config(),
/// )
/// .await?;
/// let link = sim.ground_station_link().expect("a tcp-listen link has one");
/// let (_stream, sender) = mcp_host::connect(&link, LinkOptions::default()).await?;
/// let report = sender.request(mavs[0], StatusRequest::Landing).await?;
/// assert!(matches!(report, Report::Landing(_)));
/// sim.stop().await;
/// # Ok(())
/// # }
/// ```
#[derive(Debug)]
#[must_use = "dropping a Simulator stops it at once"]
pub struct Simulator {
    network: Network,
    coordinator: AddedNode,
    mavs: Vec<AddedNode>,
    options: SimOptions,
}

impl Simulator {
    /// Starts the network with `link` as its coordinator (in `mode`) and one simulated
    /// MAV per address as in-process nodes in API mode 1, clocks at the current time.
    pub async fn start(
        link: &Link,
        mode: ApiMode,
        addresses: &[Address64],
        config: NetworkConfig,
    ) -> Result<Self, NetworkError> {
        Self::start_with(link, mode, addresses, config, SimOptions::default()).await
    }

    /// [`Simulator::start`] with options.
    pub async fn start_with(
        link: &Link,
        mode: ApiMode,
        addresses: &[Address64],
        config: NetworkConfig,
        options: SimOptions,
    ) -> Result<Self, NetworkError> {
        let network = Network::new(config);
        let coordinator_options = NodeOptions {
            transparent: options.coordinator_transparent,
            ..NodeOptions::with_mode(mode)
        };
        let coordinator = network
            .add_link(Address64::COORDINATOR, link, coordinator_options)
            .await?;
        let mut sim = Simulator {
            network,
            coordinator,
            mavs: Vec::with_capacity(addresses.len()),
            options,
        };
        for &address in addresses {
            sim.add_mav(address)?;
        }
        Ok(sim)
    }

    /// Adds a simulated MAV to the running network, as one switched on mid-flight: its
    /// radio joins, and it takes commands, sends the telemetry they turn on and answers
    /// status requests like the MAVs given at the start, with the same [`SimOptions`],
    /// its clock at the current time.
    ///
    /// # Errors
    ///
    /// [`NetworkError::Duplicate`] if a node has this address (a MAV, or the coordinator),
    /// [`NetworkError::Broadcast`] for the broadcast address.
    ///
    /// ```
    /// use mcp_host::mcp_core::{Report, StatusRequest};
    /// use mcp_host::sim::{Simulator, fleet_addresses};
    /// use mcp_host::{Link, LinkOptions};
    /// use mcp_host::xbee_api::ApiMode;
    ///
    /// # #[tokio::main(flavor = "current_thread")]
    /// # async fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// let fleet = fleet_addresses(2);
    /// let mut sim = Simulator::start(
    ///     &Link::tcp_listen("127.0.0.1", 0),
    ///     ApiMode::Unescaped,
    ///     &fleet[..1],
    ///     Simulator::network_config(),
    /// )
    /// .await?;
    /// let link = sim.ground_station_link().expect("a tcp-listen link has one");
    /// let (_stream, sender) = mcp_host::connect(&link, LinkOptions::default()).await?;
    /// // The second MAV is switched on later.
    /// sim.add_mav(fleet[1])?;
    /// let report = sender.request(fleet[1], StatusRequest::Landing).await?;
    /// assert!(matches!(report, Report::Landing(_)));
    /// assert_eq!(sim.mavs().len(), 2);
    /// sim.stop().await;
    /// # Ok(())
    /// # }
    /// ```
    pub fn add_mav(&mut self, address: Address64) -> Result<&AddedNode, NetworkError> {
        let (info, io) = self
            .network
            .add_in_process(address, NodeOptions::with_mode(ApiMode::Unescaped))?;
        let options = self.options;
        self.network.spawn_beside(async move {
            if let Err(error) = run_mav_with(io, SimMav::new(posix_now()), options).await {
                tracing::warn!(mav = %address, %error, "simulated MAV stopped");
            }
        });
        self.mavs.push(info);
        Ok(&self.mavs[self.mavs.len() - 1])
    }

    /// The network settings a simulator should use unless it emulates something else:
    /// defaults, with unicast payloads up to 255 bytes (fragmentation), since MCP packets
    /// (telemetry of many ids, trajectories) go up to 255 bytes. Its fault `seed` is 0,
    /// so faults set on it fall the same way every run; set a seed from the clock (as
    /// `mcp-gs sim` does) for runs that differ.
    pub fn network_config() -> NetworkConfig {
        NetworkConfig {
            max_unicast: crate::radio::MAX_UNICAST_FRAGMENTED,
            ..NetworkConfig::default()
        }
    }

    /// The network.
    pub fn network(&self) -> &Network {
        &self.network
    }

    /// The coordinator: where its link listens ([`AddedNode::pty_path`],
    /// [`AddedNode::local_addr`]).
    pub fn coordinator(&self) -> &AddedNode {
        &self.coordinator
    }

    /// The simulated MAVs.
    pub fn mavs(&self) -> &[AddedNode] {
        &self.mavs
    }

    /// The link a ground station in this process takes to the coordinator: `tcp:` to
    /// where a `tcp-listen:` link listens (this machine's loopback address for one bound
    /// to every interface), or `serial:` to the far end of a `pty` link. `None` for a
    /// coordinator on a link that connects out (`tcp:`, `serial:`), whose ground station
    /// is elsewhere.
    pub fn ground_station_link(&self) -> Option<Link> {
        if let Some(mut addr) = self.coordinator.local_addr {
            if addr.ip().is_unspecified() {
                addr.set_ip(match addr.ip() {
                    std::net::IpAddr::V4(_) => std::net::Ipv4Addr::LOCALHOST.into(),
                    std::net::IpAddr::V6(_) => std::net::Ipv6Addr::LOCALHOST.into(),
                });
            }
            return Some(Link::from(addr));
        }
        let path = self.coordinator.pty_path.as_ref()?;
        Some(Link::serial(
            path.display().to_string(),
            crate::link::DEFAULT_BAUD,
        ))
    }

    /// Tells the MAVs and the network to stop, and returns at once; the links close
    /// as their tasks end, shortly after (see [`Network::shutdown`]).
    pub fn shutdown(&self) {
        self.network.shutdown();
    }

    /// Stops the MAVs and the network and waits until the MAVs have stopped and the
    /// coordinator's link is closed and its port free ([`Network::stop`]).
    pub async fn stop(&self) {
        self.network.stop().await;
    }
}
