//! Host side of the MAV communication protocol (MCP): talk to MAVs through a local XBee
//! radio from a ground station, a simulator or a test.
//!
//! [`connect`] opens a [`Link`] and starts a background task that owns the transport. It
//! returns a [`PacketStream`] of [`Event`]s (MCP packets with their source address,
//! other XBee frames, link state changes, framing errors) and a [`CommandSender`] that
//! sends commands and waits for the radio's delivery status, or for the MAV's report.
//! Reading and sending run at the same time; the sender is `Clone + Send + Sync`.
//!
//! # Links
//!
//! | Link string | Meaning |
//! |---|---|
//! | `serial:PATH[:BAUD][:rtscts]` | Serial port `PATH` (e.g. `/dev/ttyUSB0`, `COM3`), `BAUD` default 115200, 8N1, no flow control unless `:rtscts` asks for RTS/CTS ([`link::FlowControl`]), for exclusive use (TIOCEXCL and an exclusive `flock`; on Linux, the far end of a pseudo-terminal by a shared `flock` alone, which turns away every opener that asks for exclusive use and goes with the process: a ground station killed while holding a simulator's pseudo-terminal leaves it free). Reopened after the device disappears (USB unplugged). |
//! | `tcp:HOST:PORT` | TCP connection to `HOST:PORT` (a serial-to-TCP bridge, a simulator). Reconnected after the peer goes away, even without a word (a bridge powered off, a cable pulled): TCP keepalive probes a connection quiet for 10 s and gives it up after about 30 s unanswered (a minute on Windows before 10). IPv6 hosts in brackets: `tcp:[::1]:9750`. |
//! | `tcp-listen:ADDR:PORT` | Listens on `ADDR:PORT` and serves one peer at a time (a peer gone without a word is found out as on `tcp:`): while one is served the next may wait for its turn (if it leaves first, what it wrote is dropped, never carried out later) and any more are turned away (connection closed at once). Port 0 picks a free port ([`LinkInfo::local_addr`]). |
//! | `pty` | Creates a pseudo-terminal pair; the far end's path ([`LinkInfo::pty_path`], e.g. `/dev/pts/7`) is for a simulator or test to open. The path stays valid for the life of the link; the link is up while a device has it open (connected, disconnected and reconnected as simulators come and go), and nothing written for one device reaches the next. |
//!
//! A program that opens the byte stream to the radio itself (a Bluetooth serial socket,
//! a serial port with settings of its own, an in-memory stream in a test) hands it over
//! with [`connect_io`], or the function that opens it with [`connect_with`], which
//! reconnects by calling it again: an `io:NAME` link.
//!
//! [`LinkOptions`] sets the XBee API mode (1, as the deployed MAVs use, or 2), the frame
//! size limit, timeouts and the [`ReconnectPolicy`] (exponential backoff, or none).
//! While the transport is down, requests fail at once with [`SendError::Disconnected`];
//! requests in flight when it goes down fail with the same error. A request that awaits a
//! status or response takes one of the 255 XBee frame ids until it is answered or times
//! out; while all are taken (a radio that leaves statuses unanswered), such requests wait
//! in order for the first free id (or their deadline), and raw writes and transmits
//! without status still go out at once.
//!
//! A radio in another API mode than the link's, at another baud rate or in transparent
//! mode sends frames that fail to decode, and they are dropped: the link logs a warning
//! (target `mcp_host::diagnosis`) once a connection when its counters show the signs
//! (looked at when a frame fails to decode and when a request times out),
//! [`Stats::diagnose`] reads them at any time ([`Diagnoser`] as they grow), and a
//! [`RequestError::Timeout`] counts the frames dropped while its report was awaited.
//!
//! A radio in transparent mode (`AP=0`, as XBee modules leave the factory) speaks no API
//! frames: [`command_mode`] puts it into API mode through its AT command mode (`+++`).
//!
//! # Logging
//!
//! The library says what goes wrong beside the errors it returns (a radio whose frames
//! fail to decode, a link not there yet and waited for, answers dropped) through
//! [`tracing`](https://docs.rs/tracing), at `warn` and below; a program sees it once it
//! installs a subscriber, as `tracing_subscriber::fmt().init()` of the
//! `tracing-subscriber` crate does. Without one it is lost.
//!
//! [`CommandSender::discover`] finds the radios the local one can reach (node
//! discovery, `ND`, in [`discovery`]); [`CommandSender::at_answers`] gathers every
//! answer to any AT command that many radios answer.
//!
//! A serial port serves one program at a time: [`hub::Hub`] holds the link to the radio
//! and serves it on a TCP port to any number of programs (`tcp:HOST:PORT` links), each
//! getting every received frame and the answers to its own requests.
//!
//! # Dependencies
//!
//! Packets, commands and identifiers are [`mcp_core`]'s, addresses and frames
//! [`xbee_api`]'s, payloads [`bytes::Bytes`]: all three are re-exported here, so that a
//! program that depends on this crate alone names them at the versions it uses
//! (`use mcp_host::mcp_core::Command;`), as every example of these docs does. So is
//! [`tokio_serial`], whose errors a [`LinkError::Serial`] holds
//! (`mcp_host::tokio_serial::ErrorKind::NoDevice`: on Unix, the port is in use), and
//! [`tokio_util`], whose `Decoder` and `Encoder` traits [`codec::XBeeCodec`] implements,
//! and [`serde_json`], whose `Value`s the JSON of [`render::json`] is.
//!
//! ```
//! use mcp_host::bytes::Bytes;
//! use mcp_host::mcp_core::{Command, Packet};
//! use mcp_host::xbee_api::Address64;
//!
//! let mav: Address64 = "0013A20040B599B9".parse().unwrap();
//! let payload = Bytes::from_static(b"c\x02\x01");
//! assert_eq!(mcp_host::mcp_core::parse(&payload), Ok(Packet::Command(Command::landing(true))));
//! # let _ = mav;
//! ```
//!
//! # Features
//!
//! - `cli` (on by default): the `mcp-gs` ground station binary, and the clap,
//!   tracing-subscriber and shlex it needs. A program that uses the library alone
//!   leaves it out: `mcp-host = { version = "0.1", default-features = false }`.
//!
//! # Example
//!
//! ```no_run
//! use futures::StreamExt;
//! use mcp_host::mcp_core::{Command, StatusRequest, TelemetryId};
//! use mcp_host::{Event, Link, LinkOptions};
//! use mcp_host::xbee_api::Address64;
//!
//! # async fn run() -> Result<(), Box<dyn std::error::Error>> {
//! let link: Link = "serial:/dev/ttyUSB0".parse()?;
//! let (mut stream, sender) = mcp_host::connect(&link, LinkOptions::default()).await?;
//! let mav: Address64 = "0013A20040B599B9".parse()?;
//!
//! // Ask for altitude telemetry; wait for the radio's delivery status.
//! let on = Command::telemetry_to_coordinator(true, TelemetryId::Altitude);
//! sender.send(mav, &on).await?;
//!
//! // Ask the landing state and wait for the MAV's report.
//! let report = sender.request(mav, StatusRequest::Landing).await?;
//! println!("{report}");
//!
//! while let Some(event) = stream.next().await {
//!     match event {
//!         Event::Packet(rx) => println!("{} {}", rx.origin.src64, rx.packet),
//!         other => println!("{other}"),
//!     }
//! }
//! # Ok(())
//! # }
//! ```
//!
//! # Without hardware
//!
//! [`sim::Simulator`] runs simulated MAVs behind a simulated coordinator radio, in the
//! same program, on a link of its own: a ground station (this crate, `mcp-gs`, or
//! another program) connects to [`sim::Simulator::ground_station_link`] as it would
//! to a radio. The same program, in a test or a first try:
//!
//! ```
//! use mcp_host::mcp_core::{Command, LandingState, Report, StatusRequest};
//! use mcp_host::sim::{Simulator, fleet_addresses};
//! use mcp_host::xbee_api::ApiMode;
//! use mcp_host::{Link, LinkOptions};
//!
//! # #[tokio::main(flavor = "current_thread")]
//! # async fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let fleet = fleet_addresses(1);
//! let sim = Simulator::start(
//!     &Link::tcp_listen("127.0.0.1", 0),
//!     ApiMode::Unescaped,
//!     &fleet,
//!     Simulator::network_config(),
//! )
//! .await?;
//! let link = sim.ground_station_link().expect("a tcp-listen link has one");
//! let (_stream, sender) = mcp_host::connect(&link, LinkOptions::default()).await?;
//! sender.send_confirmed(fleet[0], &Command::landing(true)).await?;
//! let report = sender.request(fleet[0], StatusRequest::Landing).await?;
//! // Landing, or down already.
//! use LandingState::{Landing, OnGround};
//! assert!(matches!(report, Report::Landing(Landing | OnGround)), "{report}");
//! # Ok(())
//! # }
//! ```
#![forbid(unsafe_code)]
#![deny(missing_docs)]

mod answers;
mod api_mode;
pub mod codec;
pub mod command_mode;
mod confirm;
mod diagnosis;
pub mod discovery;
mod driver;
mod error;
mod event;
pub mod hub;
mod ids;
mod keepalive;
pub mod link;
mod mutex;
pub mod options;
// Pseudo-terminals are Unix's: elsewhere `pty` links fail to open, saying so.
#[cfg_attr(not(unix), path = "pty_unsupported.rs")]
mod pty;
pub mod radio;
pub mod record;
pub mod render;
mod repeats;
mod sender;
pub mod sim;
mod sink;
mod stats;
mod subscription;
mod tap;
pub mod transport;

use std::net::SocketAddr;
use std::path::PathBuf;
use std::pin::Pin;
use std::sync::Arc;
use std::task::{Context, Poll};

use tokio::sync::mpsc;

pub use bytes;
pub use mcp_core;
pub use serde_json;
pub use tokio_serial;
pub use tokio_util;
pub use xbee_api;

pub use answers::Answers;
pub use api_mode::{DetectError, detect_api_mode};
pub use confirm::{ConfirmError, Confirmed};
pub use diagnosis::{Diagnoser, Diagnosis};
pub use discovery::{DiscoverError, Discovery};
pub use error::{ConnectError, OptionsError, RequestError, SendError};
pub use event::{
    Event, InvalidPacket, LinkEvent, LinkState, Origin, OwnedFrame, OwnedPacket, Received,
};
pub use link::{Link, LinkParseError};
pub use options::{LinkOptions, MAX_EVENT_CAPACITY, MIN_RECONNECT_DELAY, ReconnectPolicy};
pub use sender::{CommandSender, DeliveryReport, FrameId, SendOptions};
pub use sink::PacketSink;
pub use stats::Stats;
pub use subscription::Subscription;
pub use transport::{Connector, LinkError, RadioIo, Transport};

// mcp-core states the radio's unfragmented payload without depending on xbee-api:
// the two must agree.
const _: () =
    assert!(mcp_core::MAX_UNFRAGMENTED_PAYLOAD == xbee_api::TransmitRequestRepr::MAX_UNICAST_DATA);

/// Capacity of the queue of requests from senders to the background task.
const OPS_CAPACITY: usize = 256;

/// What a connected link is attached to.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub struct LinkInfo {
    /// The link.
    pub link: Link,
    /// The API mode the link reads and writes frames in ([`LinkOptions::api_mode`]).
    pub api_mode: xbee_api::ApiMode,
    /// For `pty`: the far end's path.
    pub pty_path: Option<PathBuf>,
    /// For `tcp-listen`: the bound address.
    pub local_addr: Option<SocketAddr>,
}

impl LinkInfo {
    /// [`Stats::diagnose`] of `stats` in the link's API mode.
    pub(crate) fn diagnose(&self, stats: &Stats) -> Option<Diagnosis> {
        stats.diagnose(self.api_mode)
    }
}

/// Opens `link` and starts the background task serving it.
///
/// For `serial` and `tcp` links the first connection is made before this returns (so a
/// wrong path or a refused connection fails here, unless
/// [`LinkOptions::wait_for_link`] has it waited for); `tcp-listen` binds and `pty`
/// creates the pair, and both return at once, the first peer being announced by
/// [`LinkEvent::Connected`].
///
/// The task runs until the link ends for good ([`LinkEvent::Closed`]) or the stream and
/// every sender (and every [`PacketSink`] made from one) are dropped. Must be called
/// within a tokio runtime.
pub async fn connect(
    link: &Link,
    options: LinkOptions,
) -> Result<(PacketStream, CommandSender), ConnectError> {
    let (stream, sender, ()) = connect_then(link, options, |_| ()).await?;
    Ok((stream, sender))
}

/// [`connect`], with every frame of the link both ways from its very first
/// ([`CommandSender::tap_frames`] taken before the link's task starts): a recording of
/// the whole session, the frames that come the moment the link opens (a radio's Modem
/// Status, the answer to a first request) included, which a tap taken after `connect`
/// returns may miss.
///
/// ```
/// # #[tokio::main(flavor = "current_thread")]
/// # async fn main() -> Result<(), Box<dyn std::error::Error>> {
/// use mcp_host::{Link, LinkOptions};
///
/// let (_stream, sender, frames) = mcp_host::connect_tapped(&Link::Pty, LinkOptions::default()).await?;
/// drop(frames);
/// sender.close();
/// # Ok(())
/// # }
/// ```
pub async fn connect_tapped(
    link: &Link,
    options: LinkOptions,
) -> Result<(PacketStream, CommandSender, Subscription<record::Record>), ConnectError> {
    connect_then(link, options, subscription::Subscribers::tap_frames).await
}

/// [`connect`], with `before` given the link's subscriptions before its task starts
/// (a tap then misses none of its frames), and what it gives.
pub(crate) async fn connect_then<T>(
    link: &Link,
    options: LinkOptions,
    before: impl FnOnce(&subscription::Subscribers) -> T,
) -> Result<(PacketStream, CommandSender, T), ConnectError> {
    options.check()?;
    let connector = Connector::new(link, &options).await?;
    serve(connector, options, before).await
}

/// Serves a byte stream to the radio that the program opens itself, with `open`: a
/// Bluetooth serial socket, a serial port opened with settings of its own, a stream
/// through a tunnel, an in-memory stream in a test. The link is `io:NAME`, as events
/// and logs name it; `open` is called to open it first (before this returns, as a
/// `serial` link's port is opened, or in the background with
/// [`LinkOptions::wait_for_link`]), and again to reconnect after the stream ends or
/// fails, under [`LinkOptions::reconnect`]. An error of kind `InvalidInput` or
/// `Unsupported` from `open` is taken as final; any other is retried, and so is an
/// open that takes longer than [`LinkOptions::connect_timeout`]. Must be called within
/// a tokio runtime.
///
/// ```
/// # #[tokio::main(flavor = "current_thread")]
/// # async fn main() -> Result<(), Box<dyn std::error::Error>> {
/// use mcp_host::LinkOptions;
///
/// // A serial-to-TCP bridge reached through a port of the program's choosing, say.
/// let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await?;
/// let addr = listener.local_addr()?;
/// let (_stream, sender) = mcp_host::connect_with(
///     "bridge",
///     move || tokio::net::TcpStream::connect(addr),
///     LinkOptions::default(),
/// )
/// .await?;
/// assert_eq!(sender.info().link.to_string(), "io:bridge");
/// # Ok(())
/// # }
/// ```
pub async fn connect_with<F, Fut, S>(
    name: impl Into<String>,
    mut open: F,
    options: LinkOptions,
) -> Result<(PacketStream, CommandSender), ConnectError>
where
    F: FnMut() -> Fut + Send + 'static,
    Fut: std::future::Future<Output = std::io::Result<S>> + Send + 'static,
    S: transport::RadioIo,
{
    options.check()?;
    let opener: transport::Opener = Box::new(move || {
        let opening = open();
        Box::pin(async move { Ok(Box::new(opening.await?) as Box<dyn transport::RadioIo>) })
    });
    let connector = Connector::with_opener(name.into(), opener, &options);
    let (stream, sender, ()) = serve(connector, options, |_| ()).await?;
    Ok((stream, sender))
}

/// Serves `stream`, a byte stream to the radio that the program opened itself, as an
/// `io:NAME` link ([`connect_with`], once): when it ends or fails, the link says so
/// ([`LinkEvent::Disconnected`], with why) and ends ([`LinkEvent::Closed`]) once the
/// reconnection policy's first delay has passed, as there is nothing to open again
/// (requests fail with [`SendError::Disconnected`] meanwhile).
///
/// ```
/// # #[tokio::main(flavor = "current_thread")]
/// # async fn main() -> Result<(), Box<dyn std::error::Error>> {
/// use mcp_host::{LinkOptions, LinkState};
///
/// // One end for the ground station, the other for a radio (a simulated one, a test).
/// let (ours, radio) = tokio::io::duplex(4096);
/// let (_stream, sender) = mcp_host::connect_io("duplex", ours, LinkOptions::default()).await?;
/// assert_eq!(sender.link_state(), LinkState::Connected);
/// drop(radio);
/// sender.closed().await;
/// # Ok(())
/// # }
/// ```
pub async fn connect_io<S: transport::RadioIo>(
    name: impl Into<String>,
    stream: S,
    options: LinkOptions,
) -> Result<(PacketStream, CommandSender), ConnectError> {
    let mut stream = Some(stream);
    connect_with(
        name,
        move || {
            let once = stream.take().ok_or_else(|| {
                std::io::Error::new(
                    std::io::ErrorKind::Unsupported,
                    "the stream it was given has ended, and there is no other to open",
                )
            });
            std::future::ready(once)
        },
        options,
    )
    .await
}

/// Opens `connector`'s link where it opens at once, and starts the task serving it;
/// `before` is given its subscriptions before the task starts.
async fn serve<T>(
    mut connector: Connector,
    options: LinkOptions,
    before: impl FnOnce(&subscription::Subscribers) -> T,
) -> Result<(PacketStream, CommandSender, T), ConnectError> {
    let link = connector.link().clone();
    // Whether the first open was tried here already (and failed).
    let mut tried = false;
    let transport = match &link {
        // Their first peer may come at any time: announced by `LinkEvent::Connected`.
        Link::TcpListen { .. } | Link::Pty => None,
        _ => match connector.open().await {
            Ok(transport) => Some(transport),
            // Opened in the background, announced the same way.
            Err(e) if options.wait_for_link && options.reconnect.enabled && e.is_retryable() => {
                tracing::warn!(error = %e, "link not there yet: waiting for it");
                tried = true;
                None
            }
            Err(e) => return Err(e.into()),
        },
    };
    let info = Arc::new(LinkInfo {
        link: link.clone(),
        api_mode: options.api_mode,
        pty_path: connector.pty_path().map(PathBuf::from),
        local_addr: connector.local_addr(),
    });
    let counters = Arc::new(stats::Counters::default());
    let (ops_tx, ops_rx) = mpsc::channel(OPS_CAPACITY);
    let (writes_tx, writes_rx) = mpsc::channel(OPS_CAPACITY);
    // Never sent on: it closes when the last handle that can send (a sender, a sink) is
    // dropped, which the link's task sees even while it takes no requests.
    let (alive_tx, alive_rx) = mpsc::channel(1);
    let (events_tx, events_rx) = mpsc::channel(options.event_capacity);
    let subscribers = Arc::new(subscription::Subscribers::new(options.event_capacity));
    let close_requested = Arc::new(driver::CloseRequest::default());
    // Connected already when the transport is open: `link_state` right after `connect`
    // says so.
    let (state_tx, state) = tokio::sync::watch::channel(if transport.is_some() {
        LinkState::Connected
    } else {
        LinkState::Connecting
    });
    let sender = CommandSender {
        ops: ops_tx,
        writes: writes_tx,
        alive: alive_tx,
        default_timeout: options.send_timeout,
        counters: counters.clone(),
        info: info.clone(),
        close_requested: close_requested.clone(),
        state: state.clone(),
        subscribers: subscribers.clone(),
    };
    let taken = before(&subscribers);
    let driver = driver::Driver::new(
        connector,
        options,
        (ops_rx, writes_rx, alive_rx),
        (events_tx, subscribers),
        counters.clone(),
        close_requested,
        state_tx,
    );
    // Everything the link's task logs carries the link: `link{link=serial:...}: ...`.
    let span = tracing::info_span!("link", link = %link);
    tokio::spawn(tracing::Instrument::instrument(
        driver.run(transport, tried),
        span,
    ));
    let stream = PacketStream {
        events: events_rx,
        ended: false,
        counters,
        info,
        state,
    };
    Ok((stream, sender, taken))
}

/// The [`Event`]s of a link, as a [`futures::Stream`]. Ends after [`LinkEvent::Closed`].
///
/// Reading it is optional: requests are matched inside the background task. If the
/// consumer falls behind by [`LinkOptions::event_capacity`] events, newer packets and
/// frames are dropped and counted ([`Stats::events_dropped`]); link events are held back
/// and delivered first once there is room (up to 64 of them), so the link's state is
/// never lost and the stream always ends with [`LinkEvent::Closed`].
///
/// It has one reader; other tasks read the same events through
/// [`CommandSender::subscribe`]. For the MCP packets alone, as
/// [`Subscription::packets`] gives them:
/// `stream.filter_map(|event| std::future::ready(event.into_packet()))`
/// ([`Event::into_packet`]); [`by_ref`](futures::StreamExt::by_ref) first keeps the
/// stream's [`stats`](Self::stats) at hand.
#[derive(Debug)]
pub struct PacketStream {
    events: mpsc::Receiver<Event>,
    /// It has ended (given `None`): for [`FusedStream`](futures::stream::FusedStream).
    ended: bool,
    counters: Arc<stats::Counters>,
    info: Arc<LinkInfo>,
    state: tokio::sync::watch::Receiver<LinkState>,
}

impl PacketStream {
    /// The link's counters.
    pub fn stats(&self) -> Stats {
        self.counters.snapshot()
    }

    /// Where the link is now (the stream's [`LinkEvent`]s may lag behind it).
    pub fn link_state(&self) -> LinkState {
        *self.state.borrow()
    }

    /// What the link is attached to.
    pub fn info(&self) -> &LinkInfo {
        &self.info
    }

    /// What the link's counters say may be wrong with the radio's settings (its API
    /// mode, its baud rate), read in the link's API mode: [`Stats::diagnose`] of
    /// [`stats`](Self::stats) since `earlier`, a snapshot taken before a short exchange
    /// that went unanswered. It takes any sign as one: for the counters of a link over
    /// a long time, [`Stats::diagnose_running`] with [`LinkInfo::api_mode`].
    pub fn diagnose(&self, earlier: &Stats) -> Option<Diagnosis> {
        self.info.diagnose(&self.stats().since(earlier))
    }
}

impl futures::Stream for PacketStream {
    type Item = Event;

    fn poll_next(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<Option<Event>> {
        let this = &mut *self;
        poll_fused(&mut this.events, &mut this.ended, cx)
    }
}

/// The next item of `items`, noting in `ended` when it gives `None` (and giving `None`
/// from then on): a [`FusedStream`](futures::stream::FusedStream) over a channel,
/// terminated once its end was read, not merely once nothing more can come.
pub(crate) fn poll_fused<T>(
    items: &mut mpsc::Receiver<T>,
    ended: &mut bool,
    cx: &mut Context<'_>,
) -> Poll<Option<T>> {
    if *ended {
        return Poll::Ready(None);
    }
    let item = std::task::ready!(items.poll_recv(cx));
    *ended = item.is_none();
    Poll::Ready(item)
}

/// Read again after its end (in a `select!` loop, say), it ends again; terminated once
/// it has given `None`, not with its last event.
impl futures::stream::FusedStream for PacketStream {
    fn is_terminated(&self) -> bool {
        self.ended
    }
}

/// This crate's README, its example compiled as a doc test.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
