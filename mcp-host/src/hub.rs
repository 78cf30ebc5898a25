//! One radio shared by several ground-station programs.
//!
//! A serial port is opened by one program at a time, so an operator who watches the
//! telemetry (`mcp-gs monitor`) cannot send a command (`mcp-gs send`) through the same
//! radio. A [`Hub`] holds the link to the radio and serves it on a TCP port: each client
//! talks to the hub as to the radio itself (XBee API frames, in the hub's API mode), so
//! any link that takes `tcp:HOST:PORT` works unchanged.
//!
//! - **From the radio:** every frame that is not the answer to a client's request
//!   (received packets, modem status, unclaimed responses) goes to every client. A
//!   client that falls behind by [`CLIENT_QUEUE`] frames loses the newest ones (counted
//!   in [`HubStats::frames_dropped`], and said in a warning as it happens); the others
//!   are not held up. The answers to its own requests wait apart, [`ANSWER_QUEUE`] at
//!   most, and are not lost with them (those beyond are dropped, counted with the
//!   frames and said in a warning naming the client, at most one a second).
//! - **From a client:** frames go to the radio in the order the client sent them. A
//!   request with a frame id goes under an id the hub allocates, and its answers go
//!   back to that client alone, under the client's own id, ahead of the radio's other
//!   frames waiting for it: clients that each count their ids from 1 never get each
//!   other's answers. An answer completes a request only if its frame type answers the
//!   request's type, so a client cannot answer another's request with a frame of its
//!   own. The requests the hub knows, and their answers:
//!
//!   | request | answer |
//!   |---|---|
//!   | 0x08 AT Command, 0x09 AT Command - Queue Parameter Value | 0x88 AT Command Response |
//!   | 0x10 Transmit Request, 0x11 Explicit Addressing Command | 0x8B Transmit Status |
//!   | 0x17 Remote AT Command | 0x97 Remote AT Command Response |
//!   | 0x00, 0x01 Transmit Request 64-/16-bit (802.15.4), 0x20 Transmit Request IPv4 | 0x89 TX Status |
//!   | 0x24 Register Joining Device | 0xA4 Register Joining Device Status |
//!
//!   A request is answered once, but for node discovery (`ND`), find neighbors (`FN`),
//!   active scan (`AS`) and a remote AT command to the broadcast address, whose answers
//!   keep coming for [`ANSWER_WINDOW`] from when the hub writes the request to the
//!   radio (not while it waits its turn); a request unanswered by then gives its id
//!   back. An answer under the id of a request not yet written is dropped.
//! - **Fairness:** the hub takes its clients' frames in turn, one frame of each client
//!   with frames waiting, and writes them at the pace of the radio's UART (its baud
//!   rate on a serial link, [`DEFAULT_RADIO_BAUD`] on others), never more than
//!   [`RADIO_BACKLOG`] ahead of it: the queues of the link (the operating system's
//!   buffers, a serial-to-TCP bridge's) could otherwise hold seconds of one client's
//!   frames before another's. A client's frames wait their turn [`CLIENT_FRAMES_TO_RADIO`]
//!   at most; the hub reads no more of them meanwhile, so a client that writes nonstop
//!   slows itself alone (a client is a connection: a program that opens several gets
//!   a turn on each). What it wrote ahead waits in the operating system's buffers of
//!   its connection (on both machines: megabytes, minutes of a radio's time at 115200
//!   baud), which the hub cannot date: frames with frame id 0 have no age limit, and go
//!   to the radio even after their client has left. A client that must not have its
//!   frames sent late waits for each one's answer (gives it a frame id: requests not
//!   sent in [`REQUEST_WAIT`] are refused) rather than writing ahead of the radio.
//! - **Frame ids:** the radio's link has 255. A client has at most
//!   [`ROUTES_PER_CLIENT`] requests waiting for answers at once; its next request
//!   waits (and the hub reads no more of its frames meanwhile) until one is answered,
//!   so a client that floods the hub with requests slows itself first. A request
//!   holds its id until the radio answers it (a local AT command in milliseconds, a
//!   transmission or a remote AT command within seconds, with a status saying whether
//!   it got through); requests answered many times (node discovery, find neighbors,
//!   active scan, broadcast remote AT commands) hold theirs for [`ANSWER_WINDOW`], and
//!   a client has [`MANY_ANSWER_PER_CLIENT`] of those at most. A client's first
//!   [`IDS_PER_CLIENT`] requests waiting for answers always find an id (all
//!   [`MAX_CLIENTS`] clients' together, 128); its others share the other
//!   [`SHARED_IDS`] (127) with every client's, so that a few clients whose requests
//!   the radio is slow to answer, or never answers, cannot leave the others without
//!   ids. Requests waiting for a shared id get one in the order they came. A request
//!   that has not gone to the radio [`REQUEST_WAIT`] after the hub could first have
//!   read it (it waited for its client's places, for an id, or its turn; while a
//!   request waits, the hub reads none of the client's bytes, so the frames behind it
//!   that the hub had already read count as waiting since then; so does a request
//!   read in the second after the hub itself could read nothing for over 2 s, its
//!   process stopped (Ctrl-Z, `SIGSTOP`), from when that began, so that after a stop
//!   longer than [`REQUEST_WAIT`] the requests of that second are refused) is not
//!   sent: it is refused, and answered at
//!   once as the radio answers a request it could not carry out (an AT command
//!   `ERROR`, a transmission's delivery status 0x32, resource error, in its Transmit
//!   Status or TX Status, a remote AT command's transmission failure; a Register
//!   Joining Device gets no answer), so that a command
//!   does not reach a MAV after its client gave up on it, or left. When a client
//!   leaves (its connection fails, or the hub ends it), its requests not yet written
//!   give their ids back; those written keep them, each on one of the shared ids,
//!   until their answers come (which are dropped) or [`ANSWER_WINDOW`] ends, so that a
//!   late answer never reaches a new request under the same id (with no shared id
//!   free, one gives its id back: an answer also goes to a request only if it is of
//!   the request's type and, for an AT command, echoes its command). A client that
//!   closed its connection still gets its answers until it is let go (see below).
//!   Requests that waited are counted in [`HubStats::requests_held`]. A frame of a
//!   type a radio sends rather than takes (its high bit set: 0x88 AT Command
//!   Response, 0x90 Receive Packet, ...) is refused, whatever its second byte, and
//!   counted in [`HubStats::frames_refused`]: a radio would drop it unanswered. Other
//!   frames with frame id 0 (no answer wanted) are written as they are, whatever their
//!   type. A frame refused for what it is (its type, its id, its length, its checksum
//!   or escapes, not sent in time) is said as a warning (the first at once, then at
//!   most one a second with the number not said); one dropped because the radio's link
//!   was down or its client was ended is counted alone. A frame with a frame id (its
//!   second byte, in every XBee request) is refused and counted in
//!   [`HubStats::frames_refused`] if its type is not in the table (the hub cannot tell
//!   its answers from those to other clients' requests), or if it is cut short of the
//!   fixed fields of its type (`10 01`, a Transmit Request that ends after its frame
//!   id): a radio drops such a frame without an answer, and its id would be taken for
//!   nothing.
//! - **Clients:** [`MAX_CLIENTS`] at once. A client that comes while as many are
//!   connected takes the place of the one that closed its connection first (the hub
//!   read its end: it sends nothing more), else of the one that has taken none of the
//!   radio's frames the longest while frames were dropped for it, [`STALLED`] at least,
//!   else of the one that has written ahead of the radio the longest, [`STALLED`] at
//!   least (each of its frames since found its [`CLIENT_FRAMES_TO_RADIO`] places taken:
//!   a flood, or a program that left with megabytes of frames still in its connection,
//!   whose end the hub cannot read before them; its frames not yet written are
//!   dropped), or is turned away if none has (counted in
//!   [`HubStats::clients_turned_away`]; the first is logged as a warning, the next ones
//!   together at most once a second). A client that closed
//!   its connection is still served until its place is taken: the hub cannot tell a
//!   connection closed from one whose sending side alone is shut (a monitor, or
//!   `nc -N`, that still reads), so the frames it sent still go to the radio, and the
//!   radio's frames and its answers still go to it (its requests keep their ids
//!   meanwhile, [`ANSWER_WINDOW`] at most); it is let go at once if writing to it
//!   fails. A client falls behind once the radio has sent it more than the operating
//!   system's buffers of its connection (the hub asks for 64 KiB on its side; Linux
//!   doubles that) and its queue of [`CLIENT_QUEUE`] frames hold (1 500 frames of 250
//!   bytes on Linux): connections that read nothing (a script that forgot its sockets)
//!   give their places up only once they have fallen behind and taken nothing for
//!   [`STALLED`], while a monitor that reads, even slowly, even one that sends nothing
//!   for hours, never loses its place; no client is dropped for being quiet, as
//!   quiet is what a monitor is on a quiet network. A client is not dropped either for
//!   falling behind while the hub has room. A connection whose peer is gone without a
//!   word (a laptop asleep, a cable pulled) is found out by TCP keepalive probes, from a
//!   minute quiet on, every 10 s until the system gives up (9 probes on Linux: two and
//!   a half minutes in all), and the client let go; one gone while the radio's frames to
//!   it wait unacknowledged, once the system stops sending them again (about a quarter
//!   of an hour on Linux), or when its place is needed.
//! - **Reading clients:** a client's frames are read as the radio's, with the hub's
//!   [`LinkOptions`]: a frame longer than [`LinkOptions::max_frame_len`] is refused
//!   (counted in [`HubStats::frames_refused`]) as soon as its length is read, and in
//!   API mode 1 a partial frame that gets no new byte for
//!   [`LinkOptions::partial_frame_timeout`] is given up and the bytes after its start
//!   delimiter scanned again, so that a stray 0x7E does not hold the requests behind
//!   it back. A hub open to untrusted clients in API mode 1 should take no longer
//!   frames than requests are ([`MAX_REQUEST_DATA`](crate::codec::MAX_REQUEST_DATA),
//!   which every radio's frame fits too): a longer length field costs a rescan of as
//!   many bytes (see the `Worst case` of [`xbee_api::Decoder`]). Bytes outside any
//!   frame (before a start delimiter: text typed into a connection, a program in
//!   transparent mode) are skipped, as a radio skips them, and counted in
//!   [`HubStats::bytes_skipped`]; the first a client sends (but for those between a
//!   frame refused and its next frame taken) are said as a warning, as the client
//!   itself hears nothing back.
//! - **Clients ended:** when the hub ends a client (its place taken, the radio's link
//!   lost, the hub stopped) or its connection fails, its frames not yet written are
//!   dropped (counted in [`HubStats::frames_refused`]): its commands are not carried out
//!   after it was disconnected.
//! - **Outages:** while the hub's link to the radio is down (a USB radio unplugged), the
//!   hub disconnects its clients and stops listening (connections are refused), so that
//!   their links see the outage, stay down quietly, and reconnect once the radio is
//!   back and the hub listens again on the same address. On Linux the hub holds its
//!   port meanwhile, so that no other program takes it and its clients' reconnections
//!   reach nobody else (a program of the same user that sets `SO_REUSEPORT` could still
//!   share it, but no other hub); elsewhere it listens again once the port is free. A
//!   radio on a link that waits for its first peer (`pty`, `tcp-listen:`) is down until
//!   that peer comes: the hub refuses clients from the start (holding its port, on
//!   Linux) and listens once the radio is there. The outage is logged as a warning,
//!   the radio there or back as a status line ([`STATUS_TARGET`]). A hub does not start
//!   on a port another hub serves or holds (a small window remains for two hubs started
//!   at the same moment).
//! - **No authentication:** every client may send the radio any frame, AT commands
//!   that change its settings (its API mode, its baud rate) or reset it included, and
//!   every client then hears the radio as changed. Serve it on an address other
//!   programs of this machine alone reach (127.0.0.1), or on a network whose every host
//!   is trusted (`mcp-gs hub` warns of any other).
//! - **The radio's mode:** each time the radio is there, before the hub listens, it
//!   asks the radio's `AP` (twice at most, waiting [`MODE_CHECK_TIMEOUT`] each time) and
//!   logs a warning if the radio is in another API mode than the hub, or does not
//!   answer (transparent mode, another baud rate): the hub drops the frames it cannot
//!   read, and its clients would hear nothing without knowing why.
//!
//! ```no_run
//! use mcp_host::hub::Hub;
//! use mcp_host::{Link, LinkOptions};
//!
//! # async fn run() -> Result<(), Box<dyn std::error::Error>> {
//! let radio: Link = "serial:/dev/ttyUSB0".parse()?;
//! let hub = Hub::start(&radio, LinkOptions::default(), "127.0.0.1:9750").await?;
//! // Ground stations now connect with `tcp:127.0.0.1:9750`.
//! println!("serving on {}", hub.local_addr());
//! tokio::signal::ctrl_c().await?;
//! hub.stop().await;
//! # Ok(())
//! # }
//! ```

mod input;
mod port;
mod stall;

use std::cell::Cell;
use std::net::SocketAddr;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, PoisonError};
use std::time::Duration;

use bytes::{Bytes, BytesMut};
use futures::FutureExt;
use futures::StreamExt;
use tokio::io::AsyncWriteExt;
use tokio::net::tcp::{OwnedReadHalf, OwnedWriteHalf};
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::{Notify, OwnedSemaphorePermit, Semaphore, mpsc};
use tokio::time::Instant;
use tokio_util::codec::FramedRead;
use tokio_util::sync::CancellationToken;
use tokio_util::task::TaskTracker;
use xbee_api::{ApiMode, RawFrame};

use self::input::{ClientCodec, ClientInput, ClientItem};
use self::port::Port;
use self::stall::Stalls;
use crate::codec::{CodecItem, encode_frame};
use crate::event::{answer_type, is_response};
use crate::ids::IdTable;
use crate::repeats::Repeats;
use crate::{
    CommandSender, ConnectError, Event, Link, LinkEvent, LinkInfo, LinkOptions, PacketStream, Stats,
};

/// Frames from the radio waiting for one client, at most; more are dropped for it.
pub const CLIENT_QUEUE: usize = 1024;

/// Answers to a client's own requests waiting for it, at most, apart from the radio's
/// other frames ([`CLIENT_QUEUE`]): a client that takes the radio's frames more slowly
/// than they come (and loses some) still gets the answers the radio gave it, each
/// ahead of the radio's frames waiting for it then.
pub const ANSWER_QUEUE: usize = 64;

/// Clients served at once, at most. A client that comes while as many are connected
/// takes the place of one that closed its connection, or of the one that has taken none
/// of the radio's frames the longest, [`STALLED`] at least, while frames were dropped
/// for it, or of the one that has written ahead of the radio the longest, [`STALLED`]
/// at least (see the [module](self) docs); without one, it is turned away.
pub const MAX_CLIENTS: usize = 64;

/// Requests of one client waiting for answers at once, at most (each holds one of the
/// 255 frame ids of the radio's link). The client's next request waits, and the hub
/// reads no more of its frames meanwhile, until an answer (or [`ANSWER_WINDOW`]) frees
/// one: a client that floods the hub with requests, answered or not, slows itself
/// first.
pub const ROUTES_PER_CLIENT: usize = 16;

/// Requests answered many times (node discovery, find neighbors, active scan, a
/// broadcast remote AT command: each keeps its frame id for [`ANSWER_WINDOW`]) of one
/// client waiting for answers at once, at most; its next such request waits (and the
/// hub reads no more of its frames meanwhile) until one ends.
pub const MANY_ANSWER_PER_CLIENT: usize = 2;

/// Requests waiting for answers of each client that always find a frame id:
/// [`MAX_CLIENTS`] clients with as many each hold 128 of the 255. A client's requests
/// beyond these (up to [`ROUTES_PER_CLIENT`]) share the other 127 ([`SHARED_IDS`]) with
/// every client's, so that a few clients sending many requests the radio is slow to
/// answer (or never answers) can hold no more: a client with fewer requests waiting
/// than this does not wait for an id (but for the hub's own few, held for late answers
/// to its `AT AP`).
pub const IDS_PER_CLIENT: usize = 2;

/// The frame ids shared by the clients' requests beyond their first
/// [`IDS_PER_CLIENT`]: 127.
pub const SHARED_IDS: usize = u8::MAX as usize - MAX_CLIENTS * IDS_PER_CLIENT;

/// How long after the hub could first have read a client's request it must have gone to
/// the radio: it may wait for one of its client's [`ROUTES_PER_CLIENT`] (or
/// [`MANY_ANSWER_PER_CLIENT`]) places, for a frame id, then for its turn. A request
/// still waiting then is refused, and answered at once with a failure of its type where
/// it has one (see the [module](self) docs): its client may have given up on it, or
/// gone, and a command must not reach a MAV long after its sender was told it failed.
/// While one request waits, the hub reads none of the client's bytes: the requests
/// behind it that the hub had already read (whole, in its buffer) count from when it
/// began to wait.
pub const REQUEST_WAIT: Duration = Duration::from_secs(5);

/// Frames of one client read by the hub and waiting for their turn to the radio, at
/// most; the hub reads no more of the client's frames meanwhile.
pub const CLIENT_FRAMES_TO_RADIO: usize = 4;

/// How much of the radio's time the hub writes ahead, at most: the bytes written to
/// the link and not yet through the radio's UART (as the hub reckons from its baud
/// rate, see [`DEFAULT_RADIO_BAUD`]) are worth no more than this, so that the next
/// client's frame never waits behind another's backlog for longer.
pub const RADIO_BACKLOG: Duration = Duration::from_millis(250);

/// The baud rate of the radio's UART (8N1: ten bits a byte) the hub reckons with on
/// links that do not give one: `tcp`, `tcp-listen` and `pty` (a serial link's own is
/// taken). A radio behind a serial-to-TCP bridge at another rate should be served
/// through a `serial:` link where it can.
pub const DEFAULT_RADIO_BAUD: u32 = 115_200;

/// How long the hub routes answers to a request: the first answer ends it, but for node
/// discovery, find neighbors, active scan and a broadcast remote AT command. A request
/// still unanswered then gives its id back (its client has given up long before:
/// `mcp-gs` waits 12 s by default).
pub const ANSWER_WINDOW: Duration = Duration::from_secs(30);

/// Why a hub could not start.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum HubError {
    /// The link to the radio could not be opened.
    #[error(transparent)]
    Connect(#[from] ConnectError),
    /// The TCP port could not be listened on.
    #[error("cannot listen on {addr}: {error}")]
    #[non_exhaustive]
    Listen {
        /// The address as given.
        addr: String,
        /// What the system said (in the message too, so no
        /// [`source`](std::error::Error::source)).
        error: std::io::Error,
    },
}

/// Counters of a hub. More may come: read them by name.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[non_exhaustive]
pub struct HubStats {
    /// Whether the hub listens for clients now: not while the radio's link is down, nor
    /// after an outage while another program holds its port (it retries every second).
    pub listening: bool,
    /// Clients connected so far.
    pub clients: u64,
    /// Frames from the radio passed on (counted once a frame, whatever the number of
    /// clients).
    pub frames_from_radio: u64,
    /// Frames from clients written to the radio.
    pub frames_from_clients: u64,
    /// Frames not given to a client that had fallen behind (its queue full): the
    /// radio's, and the hub's own answers to requests it refused. Not those for a client
    /// gone meanwhile.
    pub frames_dropped: u64,
    /// Frames of clients not written: a frame of a type a radio sends (0x80 and up), a
    /// request not sent in [`REQUEST_WAIT`], a frame id on a frame type the hub does not
    /// know or on a request cut short of its fixed fields (see the [module](self)
    /// docs), frames longer than the hub takes ([`LinkOptions::max_frame_len`]) or that
    /// fail their checksum or escapes (or are cut off), the link to the radio was
    /// down, or the client was ended before their turn.
    pub frames_refused: u64,
    /// Requests of clients that had to wait for a frame id before they went to the
    /// radio (or were refused for it): their client had [`ROUTES_PER_CLIENT`] requests
    /// waiting for answers (or [`MANY_ANSWER_PER_CLIENT`] answered many times), the
    /// [`SHARED_IDS`] were all taken, or all 255 ids were.
    pub requests_held: u64,
    /// Clients turned away: [`MAX_CLIENTS`] were connected and none could give its
    /// place. The first is logged as a warning, the next ones counted in a warning at
    /// most once a second.
    pub clients_turned_away: u64,
    /// Bytes of clients that began no frame (before a start delimiter: text typed into
    /// a connection, a program in transparent mode; in API mode 1 also the bytes of a
    /// refused frame scanned again for a start delimiter), skipped as a radio skips
    /// them. The first a client sends are logged as a warning, with what they may be,
    /// but for those between a refused frame and the client's next frame taken (the
    /// refused frame's own, perhaps); all of a client's are counted in the line that
    /// says it has gone.
    pub bytes_skipped: u64,
    /// The counters of the hub's own link to the radio: frames and framing errors,
    /// disconnects and reconnects, and in [`Stats::events_dropped`] the frames lost
    /// because the hub itself fell behind the radio (before any client saw them). The
    /// hub writes its clients' requests as raw frames, so the answers it routes to them
    /// count in [`Stats::unclaimed_responses`].
    pub radio: Stats,
}

#[derive(Debug, Default)]
struct Counters {
    listening: AtomicBool,
    clients: AtomicU64,
    frames_from_radio: AtomicU64,
    frames_from_clients: AtomicU64,
    frames_dropped: AtomicU64,
    frames_refused: AtomicU64,
    requests_held: AtomicU64,
    clients_turned_away: AtomicU64,
    bytes_skipped: AtomicU64,
    /// Clients' frames refused, for the warning: said as they come, a second apart at
    /// most, since a client that keeps sending what the hub refuses (a recording of
    /// what a radio said, played onto the hub) hears nothing back.
    refusals: Mutex<Repeats>,
}

fn bump(counter: &AtomicU64) {
    counter.fetch_add(1, Ordering::Relaxed);
}

/// A radio served to TCP clients (see the [module](self) docs). Runs until
/// [`stop`](Self::stop)ped, dropped, or the link to the radio ends for good.
#[derive(Debug)]
pub struct Hub {
    local_addr: SocketAddr,
    radio: LinkInfo,
    mode: ApiMode,
    stop: CancellationToken,
    tasks: TaskTracker,
    counters: Arc<Counters>,
    /// The counters of the link to the radio.
    radio_counters: Arc<crate::stats::Counters>,
    /// The subscriptions of the link to the radio, for [`Hub::tap_frames`].
    radio_subscribers: Arc<crate::subscription::Subscribers>,
}

impl Hub {
    /// Opens the link to the radio (with `options`: API mode, reconnection, ...) and
    /// listens on `listen` (`HOST:PORT`; port 0 picks a free one, see
    /// [`local_addr`](Self::local_addr)). Clients speak the API mode of `options`.
    ///
    /// With the radio there, it is asked its `AP` first (up to twice
    /// [`MODE_CHECK_TIMEOUT`]: see the module's docs). The radio's frames meanwhile go
    /// to no client, and wait in the link's event queue: beyond
    /// [`event_capacity`](LinkOptions::event_capacity) of them, the rest are counted in
    /// [`Stats::events_dropped`](crate::Stats::events_dropped) as lost behind
    /// (`mcp-gs hub` holds 65 536, more than a radio at 115200 baud can send in the
    /// time). Without it (a `pty` or
    /// `tcp-listen:` link, or `wait_for_link`), clients are refused from the moment this
    /// returns, the port held on Linux, until the radio is there.
    pub async fn start(link: &Link, options: LinkOptions, listen: &str) -> Result<Hub, HubError> {
        let (hub, ()) = Self::start_then(link, options, listen, |_| ()).await?;
        Ok(hub)
    }

    /// [`start`](Self::start), with every frame between the hub and its radio from the
    /// link's very first ([`tap_frames`](Self::tap_frames) taken before the link's task
    /// starts): the radio's first frames and the hub's own `AT AP` included, which a
    /// tap taken once `start` returns misses. For a recording of the whole session, as
    /// `mcp-gs hub --record` makes.
    pub async fn start_tapped(
        link: &Link,
        options: LinkOptions,
        listen: &str,
    ) -> Result<(Hub, crate::Subscription<crate::record::Record>), HubError> {
        Self::start_then(
            link,
            options,
            listen,
            crate::subscription::Subscribers::tap_frames,
        )
        .await
    }

    /// [`start`](Self::start), with `before` given the radio link's subscriptions
    /// before its task starts ([`crate::connect_then`]), and what it gives.
    async fn start_then<T>(
        link: &Link,
        options: LinkOptions,
        listen: &str,
        before: impl FnOnce(&crate::subscription::Subscribers) -> T,
    ) -> Result<(Hub, T), HubError> {
        let mode = options.api_mode;
        // The clients' frames are read as the radio's: as long, and their partial
        // frames waiting as long.
        let client_input = ClientInput {
            max_frame_len: options.max_frame_len,
            partial_frame_timeout: options.partial_frame_timeout,
        };
        let (mut port, listener) = Port::bind(listen).await.map_err(|error| HubError::Listen {
            addr: listen.to_owned(),
            error,
        })?;
        let local_addr = port.addr();
        let bytes_per_second = match link {
            Link::Serial { baud, .. } => *baud,
            _ => DEFAULT_RADIO_BAUD,
        } / 10;
        let (stream, sender, taken) = crate::connect_then(link, options, before).await?;
        let hub = Hub {
            local_addr,
            radio: sender.info().clone(),
            mode,
            stop: CancellationToken::new(),
            tasks: TaskTracker::new(),
            counters: Arc::default(),
            radio_counters: sender.counters.clone(),
            radio_subscribers: sender.subscribers.clone(),
        };
        // A `pty` or `tcp-listen:` link has no radio on it yet: clients are refused from
        // the moment this returns, the port held.
        let radio_up = sender.link_state() == crate::LinkState::Connected;
        let routes = Arc::new(Mutex::new(Routes::new()));
        let ids = Arc::new(Semaphore::new(usize::from(u8::MAX)));
        let shared = Arc::new(Semaphore::new(SHARED_IDS));
        let listener = if radio_up {
            check_radio_mode(&sender, mode, &routes, &ids).await;
            Some(listener)
        } else {
            port.hold();
            None
        };
        hub.counters.listening.store(radio_up, Ordering::Relaxed);
        let to_radio = Arc::new(ToRadio::default());
        let writer = RadioWriter {
            mode,
            sender: sender.clone(),
            counters: hub.counters.clone(),
            routes: routes.clone(),
            to_radio: to_radio.clone(),
            bytes_per_second: f64::from(bytes_per_second.max(1)),
        };
        hub.tasks.spawn(writer.run(hub.stop.clone()));
        let stalls = Arc::new(Stalls::new());
        hub.tasks
            .spawn(stall::beat(stalls.clone(), hub.stop.clone()));
        let serve = Serve {
            stalls,
            to_radio,
            mode,
            sender,
            stop: hub.stop.clone(),
            tasks: hub.tasks.clone(),
            counters: hub.counters.clone(),
            routes,
            ids,
            shared,
            client_input,
            turned_away: Repeats::default(),
            clients: Vec::new(),
            next_client: 0,
            radio_up,
            radio_seen: radio_up,
            port,
            rebind_failures: 0,
        };
        hub.tasks.spawn(serve.run(stream, listener));
        Ok((hub, taken))
    }

    /// The address clients connect to.
    pub fn local_addr(&self) -> SocketAddr {
        self.local_addr
    }

    /// The link to the radio (for `pty`, the path of its far end).
    pub fn radio_link(&self) -> &LinkInfo {
        &self.radio
    }

    /// The API mode the hub's clients speak: the radio's.
    pub fn api_mode(&self) -> ApiMode {
        self.mode
    }

    /// Counters so far.
    pub fn stats(&self) -> HubStats {
        let c = &self.counters;
        HubStats {
            listening: c.listening.load(Ordering::Relaxed),
            clients: c.clients.load(Ordering::Relaxed),
            frames_from_radio: c.frames_from_radio.load(Ordering::Relaxed),
            frames_from_clients: c.frames_from_clients.load(Ordering::Relaxed),
            frames_dropped: c.frames_dropped.load(Ordering::Relaxed),
            frames_refused: c.frames_refused.load(Ordering::Relaxed),
            requests_held: c.requests_held.load(Ordering::Relaxed),
            clients_turned_away: c.clients_turned_away.load(Ordering::Relaxed),
            bytes_skipped: c.bytes_skipped.load(Ordering::Relaxed),
            radio: self.radio_counters.snapshot(),
        }
    }

    /// Every frame between the hub and the radio from now on, both ways: the radio's
    /// frames, and the clients' frames as the hub wrote them (under the frame ids it
    /// gave them), with the hub's own `AT AP` each time the radio comes back (not the
    /// one [`start`](Self::start) asks before it returns: [`start_tapped`](Self::start_tapped)
    /// has that too); see
    /// [`CommandSender::tap_frames`]. A recording of them (`mcp-gs hub --record`) is
    /// what the radio heard and said, whichever client it was for. It ends when the hub
    /// does.
    pub fn tap_frames(&self) -> crate::Subscription<crate::record::Record> {
        self.radio_subscribers.tap_frames()
    }

    /// Whether the hub has ended (stopped, or its link to the radio closed for good).
    pub fn is_finished(&self) -> bool {
        self.stop.is_cancelled()
    }

    /// Waits until the hub ends by itself: its link to the radio closed for good.
    pub async fn finished(&self) {
        self.stop.cancelled().await;
    }

    /// Disconnects the clients, closes the link to the radio and waits until the
    /// listening port and the radio's device are free.
    pub async fn stop(self) {
        self.stop.cancel();
        self.tasks.close();
        self.tasks.wait().await;
    }
}

impl Drop for Hub {
    /// Ends the hub's tasks (without waiting for them: [`Hub::stop`] waits).
    fn drop(&mut self) {
        self.stop.cancel();
    }
}

/// Where the answers under each of the hub's frame ids go: ids handed out round-robin
/// (as the link's own), so that a late answer rarely meets a new request under its id.
struct Routes(IdTable<Route>, Held);

/// The frame ids the hub's own requests went out under (its `AT AP`), until when they
/// are kept from clients (a late answer under one is no client's), and the permits of
/// the 255 ids they hold meanwhile.
#[derive(Default)]
struct Held(Vec<(u8, Instant, Option<OwnedSemaphorePermit>)>);

impl Held {
    fn expire(&mut self, now: Instant) {
        self.0.retain(|(_, until, _)| *until > now);
    }

    fn contains(&self, id: u8) -> bool {
        self.0.iter().any(|(held, ..)| *held == id)
    }
}

struct Route {
    /// The client's number (see [`Serve::next_client`]).
    client: u64,
    /// The client's queue of answers.
    queue: AnswerQueue,
    own_id: u8,
    /// The frame type of the answers (see [`answer_type`]): an answer of another type
    /// under the same id is not this request's.
    answer_type: u8,
    /// The AT command of an AT or remote AT request ([`at_command`]): an answer that
    /// echoes another is not this request's either.
    command: Option<[u8; 2]>,
    /// Until when answers are due: [`ANSWER_WINDOW`] from when the request was written
    /// to the radio; `None` while it waits its turn (no answer is due yet, and the route
    /// does not expire).
    until: Cell<Option<Instant>>,
    /// Answers keep coming until `until` (node discovery, find neighbors, active scan,
    /// broadcast remote AT).
    many: bool,
    /// Its client has gone since the request was written: its answers are dropped, and
    /// its id stays taken until they have come (or `until`), so that no late answer
    /// of its reaches a new request under the same id. An orphan holds one of the
    /// [`SHARED_IDS`] (taken when it became one, if it had none): orphans never take
    /// the ids each client's first requests find.
    orphan: Cell<bool>,
    /// One of the client's [`ROUTES_PER_CLIENT`] permits, given back with the route.
    _permit: OwnedSemaphorePermit,
    /// For a request answered many times, one of the client's
    /// [`MANY_ANSWER_PER_CLIENT`] permits.
    _many: Option<OwnedSemaphorePermit>,
    /// For a request beyond its client's first [`IDS_PER_CLIENT`], one of the
    /// [`SHARED_IDS`] permits.
    _shared: Option<OwnedSemaphorePermit>,
    /// One of the 255 frame ids' permits: requests of all clients wait for a free id in
    /// the order they came.
    _id: OwnedSemaphorePermit,
}

impl Routes {
    fn new() -> Self {
        Routes(IdTable::new(), Held::default())
    }

    /// A hub id for `route`; `None` while all 255 wait for answers (or are held).
    fn insert(&mut self, route: Route, now: Instant) -> Option<u8> {
        if !self.0.has_free() {
            self.expire(now);
        }
        let held = &self.1;
        self.0.insert_unless(route, |id| held.contains(id)).ok()
    }

    /// Keeps `ids`, which the hub's own requests went out under, from clients for
    /// [`ANSWER_WINDOW`]: their late answers then reach no client. Each holds one of
    /// the 255 ids of `permits`, so that clients wait for an id rather than find none
    /// free.
    fn hold(&mut self, ids: &[u8], permits: &Arc<Semaphore>, now: Instant) {
        self.1.expire(now);
        let until = now + ANSWER_WINDOW;
        for &id in ids {
            let permit = permits.clone().try_acquire_owned().ok();
            self.1.0.push((id, until, permit));
        }
    }

    /// Ends the routes whose answers are no longer due, giving their clients' permits
    /// back.
    fn expire(&mut self, now: Instant) {
        self.0.remove_where(
            |r| r.until.get().is_some_and(|until| until <= now),
            |_, _| {},
        );
        self.1.expire(now);
    }

    /// The request under hub id `id` goes to the radio at `now`: its answers are due
    /// for [`ANSWER_WINDOW`].
    fn written(&mut self, id: u8, now: Instant) {
        if let Some(route) = self.0.get(id) {
            route.until.set(Some(now + ANSWER_WINDOW));
        }
    }

    /// Ends the routes of client `client` (gone) whose requests were not written: the
    /// others stay, orphans, until their answers have come or are no longer due, each
    /// on one of the `shared` ids. One that finds none free ends too (its late answer,
    /// if any comes, could then reach another request under its id, of the same type
    /// and, for an AT command, the same command: rare).
    fn forget(&mut self, client: u64, shared: &Arc<Semaphore>) {
        for route in self.0.values_mut() {
            if route.client == client && route.until.get().is_some() {
                if route._shared.is_none() {
                    route._shared = shared.clone().try_acquire_owned().ok();
                }
                route.orphan.set(route._shared.is_some());
            }
        }
        self.0
            .remove_where(|r| r.client == client && !r.orphan.get(), |_, _| {});
    }

    /// Where `answer` (frame data) under hub id `id` goes, and the client's own id; the
    /// route ends with it unless more answers are due.
    fn answer(&mut self, id: u8, answer: &[u8], now: Instant) -> Option<(AnswerQueue, u8)> {
        let route = self.0.get(id)?;
        // Not yet written: not its answer (a late one to an earlier request).
        let until = route.until.get()?;
        if Some(&route.answer_type) != answer.first() {
            return None;
        }
        if let (Some(asked), Some(echoed)) = (route.command, at_command(answer)) {
            if !asked.eq_ignore_ascii_case(&echoed) {
                return None;
            }
        }
        // An orphan's answer is taken, and goes nowhere.
        let to = (until > now && !route.orphan.get()).then(|| (route.queue.clone(), route.own_id));
        if until <= now || !route.many {
            self.0.remove(id);
        }
        to
    }
}

/// Whether a request gets several answers under its id: node discovery, find neighbors
/// and active scan, as local AT (or queued AT) commands or remote ones (a remote radio
/// sends each answer on its own), and any remote AT command to the broadcast address
/// (every radio in range answers).
fn answered_many_times(data: &[u8]) -> bool {
    // Command mode takes a command's letters in either case, and a radio may in API
    // frames too: kept open for the window at worst, never cut short.
    let gathers = at_command(data).is_some_and(|command| {
        [b"ND", b"AS", b"FN"]
            .iter()
            .any(|name| command.eq_ignore_ascii_case(*name))
    });
    gathers || matches!(data, [0x17, _, 0, 0, 0, 0, 0, 0, 0xFF, 0xFF, ..])
}

/// The AT command of an AT request or answer (frame data): local (0x08, 0x09, 0x88) or
/// remote (0x17, 0x97); `None` for other frames, or one cut short of it.
fn at_command(data: &[u8]) -> Option<[u8; 2]> {
    let at = match data.first()? {
        0x08 | 0x09 | 0x88 => 2,
        0x97 => 12,
        0x17 => 13,
        _ => return None,
    };
    data.get(at..at + 2)?.try_into().ok()
}

/// Whether `data`, a request of a type the hub routes (see [`answer_type`]), holds the
/// fixed fields of its type: a radio drops a request cut short without an answer.
fn is_whole_request(data: &[u8]) -> bool {
    match data.first() {
        // 802.15.4 Transmit Request, 64-bit address: type, id, address, options.
        Some(0x00) => data.len() >= 11,
        // 16-bit address: type, id, address, options.
        Some(0x01) => data.len() >= 5,
        // Transmit Request IPv4: type, id, address, two ports, protocol, options.
        Some(0x20) => data.len() >= 12,
        // Register Joining Device: type, id, 64-bit address, 0xFFFE, options (and the
        // key, none to take the device out of the table).
        Some(0x24) => data.len() >= 13,
        // The others `xbee-api` types (0x08, 0x09, 0x10, 0x11, 0x17).
        _ => xbee_api::Frame::parse_bytes(data).is_ok(),
    }
}

/// A client's queue of frames to the radio, and the client (kept until the queue is
/// drained, so that the routes of its last frames stay until these are written).
type ClientFrames = (mpsc::Receiver<Queued>, Arc<Client>);

/// A client's frame on its way to the radio.
struct Queued {
    /// Its frame data, a request's under its hub id.
    data: Vec<u8>,
    /// For a request: when it must have gone to the radio ([`REQUEST_WAIT`] after the
    /// hub could first have read it); one still waiting its turn then is not sent.
    deadline: Option<Instant>,
}

/// The clients' queues of frames to the radio, taken by the [`RadioWriter`].
#[derive(Default)]
struct ToRadio {
    /// Queues of new clients, not yet taken by the writer.
    new: Mutex<Vec<ClientFrames>>,
    /// A frame waits in a queue, or a new queue.
    ready: Notify,
}

/// The task that writes the clients' frames to the radio: one frame of each client in
/// turn (round-robin), at the pace the radio takes them (see [`RADIO_BACKLOG`]), so that
/// a client writing nonstop slows itself alone.
struct RadioWriter {
    mode: ApiMode,
    sender: CommandSender,
    counters: Arc<Counters>,
    /// The routes of the requests it writes: their answer windows start then.
    routes: Arc<Mutex<Routes>>,
    to_radio: Arc<ToRadio>,
    /// The radio UART's pace.
    bytes_per_second: f64,
}

impl RadioWriter {
    async fn run(self, stop: CancellationToken) {
        let mut queues: Vec<ClientFrames> = Vec::new();
        // The queue to look at first.
        let mut next = 0;
        // When the bytes written so far are through the radio's UART, as reckoned.
        let mut through = Instant::now();
        loop {
            let ahead = through.saturating_duration_since(Instant::now());
            if ahead > RADIO_BACKLOG {
                tokio::select! {
                    () = stop.cancelled() => return,
                    () = tokio::time::sleep(ahead - RADIO_BACKLOG) => {}
                }
            }
            let (Queued { data, deadline }, client) = tokio::select! {
                () = stop.cancelled() => return,
                queued = self.next_frame(&mut queues, &mut next) => queued,
            };
            let hub_id = match data[..] {
                [_, id, ..] if id != 0 => Some(id),
                _ => None,
            };
            // A request that waited its turn too long: not sent, answered as failed.
            if let (Some(deadline), Some(id)) = (deadline, hub_id) {
                if Instant::now() >= deadline {
                    self.give_up(&client, &data, id, "its turn to the radio");
                    continue;
                }
            }
            // A request's answers are due from now on (the window does not start while
            // the request waits its turn), and not before: the route is marked before the
            // radio can answer.
            if let Some(id) = hub_id {
                lock(&self.routes).written(id, Instant::now());
            }
            // A request is taken by the link by its deadline, or not written.
            let written = match deadline {
                Some(deadline) => self.sender.write_frame_until(&data, deadline).await,
                None => self.sender.write_frame(&data).await,
            };
            match written {
                Ok(()) => {
                    bump(&self.counters.frames_from_clients);
                    let len = encode(&data, self.mode).map_or(data.len(), |bytes| bytes.len());
                    let time = Duration::from_secs_f64(len as f64 / self.bytes_per_second);
                    through = through.max(Instant::now()) + time;
                }
                Err(error) => {
                    // Not written: no pacing time spent, and no answer due.
                    tracing::debug!(%error, "hub: a client's frame not written");
                    // The link did not take it in time: answered as failed.
                    let answered = matches!(error, crate::SendError::NotSent { .. })
                        && hub_id.is_some_and(|id| {
                            self.give_up(&client, &data, id, "the radio's link to take it")
                        });
                    if !answered {
                        if let Some(id) = hub_id {
                            lock(&self.routes).0.remove(id);
                        }
                        bump(&self.counters.frames_refused);
                    }
                }
            }
        }
    }

    /// Ends the route of `client`'s request `data`, under hub id `hub_id`, which waited
    /// for `what` in vain: answered as failed under the client's own id, not sent
    /// ([`Client::not_sent`]). Whether it had a route still.
    fn give_up(&self, client: &Client, data: &[u8], hub_id: u8, what: &str) -> bool {
        let Some(route) = lock(&self.routes).0.remove(hub_id) else {
            return false;
        };
        let mut request = data.to_vec();
        request[1] = route.own_id;
        client.not_sent(&request, what);
        true
    }

    /// The next client's next frame, in turn.
    async fn next_frame(
        &self,
        queues: &mut Vec<ClientFrames>,
        next: &mut usize,
    ) -> (Queued, Arc<Client>) {
        loop {
            queues.append(&mut lock(&self.to_radio.new));
            // Whatever the other queues hold: the queues of clients ended (their frames
            // not yet written are dropped: a client's commands are not carried out after
            // it was disconnected), and of clients that closed their connection once
            // their frames are all written. Each client then goes, and its routes with
            // it (see `Client`'s `Drop`).
            queues.retain_mut(|(queue, client)| {
                if client.end.is_cancelled() {
                    queue.close();
                    while queue.try_recv().is_ok() {
                        bump(&self.counters.frames_refused);
                    }
                    return false;
                }
                !(queue.is_closed() && queue.is_empty())
            });
            let n = queues.len();
            for step in 0..n {
                let index = (*next + step) % n;
                if let Ok(queued) = queues[index].0.try_recv() {
                    *next = index + 1;
                    return (queued, queues[index].1.clone());
                }
            }
            // A frame queued (or a queue added) since the look above has left a permit.
            self.to_radio.ready.notified().await;
        }
    }
}

/// A client as the hub's main task knows it.
struct Connected {
    peer: SocketAddr,
    /// Its queue of frames from the radio.
    queue: mpsc::Sender<Bytes>,
    /// Ends its tasks.
    end: CancellationToken,
    /// Since when frames have been dropped for it (its queue full) with none of its
    /// queue taken: the first frame dropped since it last took one.
    behind: Arc<Mutex<Option<Instant>>>,
    /// Since when it has sent nothing more: its connection closed (or its sending side
    /// shut), or failed.
    closed: Arc<Mutex<Option<Instant>>>,
    /// Since when it has written ahead of the radio: each of its frames since found its
    /// [`CLIENT_FRAMES_TO_RADIO`] places taken (see [`Client::ahead`]).
    ahead: Arc<Mutex<Option<Instant>>>,
    /// The radio's frames dropped for it, so far.
    dropped: Arc<AtomicU64>,
    /// When the frames dropped for it were last said, and how many there were then.
    said_dropped: Option<(Instant, u64)>,
}

impl Connected {
    /// A frame from the radio dropped for it, its queue full: counted, and said at once
    /// for the first, then at most every [`DROPS_SAID_EVERY`] while frames are dropped,
    /// so that a client's gaps show in the hub's lines as they happen (the client
    /// itself cannot tell: its link hears an XBee radio, which says nothing of them).
    fn dropped_one(&mut self, now: Instant) {
        let dropped = self.dropped.fetch_add(1, Ordering::Relaxed) + 1;
        let since = match self.said_dropped {
            Some((when, _)) if now.duration_since(when) < DROPS_SAID_EVERY => return,
            Some((when, then)) => Some((now.duration_since(when), dropped - then)),
            None => None,
        };
        self.said_dropped = Some((now, dropped));
        let peer = self.peer;
        let lately = since.map_or(String::new(), |(time, count)| {
            format!(
                ", {count} in the last {}",
                crate::render::Seconds(Duration::from_secs(time.as_secs()))
            )
        });
        tracing::warn!(
            "hub: client {peer} takes the radio's frames more slowly than they come: \
             {dropped} dropped for it so far{lately} (those that come while {CLIENT_QUEUE} \
             wait for it)"
        );
    }
}

/// How often, at most, the hub says that frames are dropped for a client: see
/// [`Connected::dropped_one`].
const DROPS_SAID_EVERY: Duration = Duration::from_secs(10);

/// A client's queue of the answers to its requests ([`ANSWER_QUEUE`] at most), apart
/// from the radio's other frames: the radio's answers routed to it, and the hub's own
/// to its requests refused.
#[derive(Clone)]
struct AnswerQueue {
    queue: mpsc::Sender<Bytes>,
    peer: SocketAddr,
    counters: Arc<Counters>,
    /// Answers dropped, for the warning.
    dropped: Arc<Mutex<Repeats>>,
}

impl AnswerQueue {
    /// Queues an answer (encoded); one that finds the queue full (the client sent
    /// requests and read nothing, while the radio's frames filled its connection) is
    /// dropped, counted in [`HubStats::frames_dropped`] and said, the first at once,
    /// then at most one a second with the number not said.
    fn send(&self, bytes: Bytes) {
        match self.queue.try_send(bytes) {
            Err(mpsc::error::TrySendError::Full(_)) => bump(&self.counters.frames_dropped),
            // Sent, or the client is gone.
            Ok(()) | Err(mpsc::error::TrySendError::Closed(_)) => return,
        }
        let more = match lock(&self.dropped).count(Instant::now()) {
            None => return,
            Some(0) => String::new(),
            Some(more) => format!(", and {more} more since the last such warning"),
        };
        let peer = self.peer;
        tracing::warn!(
            "hub: an answer to a request of client {peer} dropped: {ANSWER_QUEUE} of its \
             answers wait for it to read them{more}"
        );
    }
}

/// The hub's main task: frames from the radio to the clients, new clients accepted.
struct Serve {
    /// The hub's stalls, which the requests read after one count from.
    stalls: Arc<Stalls>,
    /// New clients' queues of frames to the radio, for the [`RadioWriter`].
    to_radio: Arc<ToRadio>,
    mode: ApiMode,
    sender: CommandSender,
    stop: CancellationToken,
    tasks: TaskTracker,
    counters: Arc<Counters>,
    routes: Arc<Mutex<Routes>>,
    /// The permits of the 255 frame ids, one held by each route.
    ids: Arc<Semaphore>,
    /// The permits of the [`SHARED_IDS`], one held by each route beyond its client's
    /// first [`IDS_PER_CLIENT`].
    shared: Arc<Semaphore>,
    /// How the clients' frames are read.
    client_input: ClientInput,
    /// Clients turned away, for the warning.
    turned_away: Repeats,
    /// Each client's queue of encoded frames, and what ends it.
    clients: Vec<Connected>,
    /// The number of the next client.
    next_client: u64,
    /// Whether the link to the radio is up: clients are served only then.
    radio_up: bool,
    /// Whether the link to the radio has been up.
    radio_seen: bool,
    /// Where clients connect, held during an outage and listened on again after it.
    port: Port,
    /// Failed attempts to listen again since the radio came back.
    rebind_failures: u32,
}

impl Serve {
    /// Listens on the hub's address again after an outage of the radio; `None` if that
    /// fails (see [`Port::listen`]), logged as a warning the first time, then at debug
    /// level.
    async fn listen_again(&mut self) -> Option<TcpListener> {
        let addr = self.port.addr();
        match self.port.listen().await {
            Ok(listener) => {
                // A status line, not a warning (see `STATUS_TARGET`).
                if self.radio_seen {
                    tracing::info!(target: STATUS_TARGET, "hub: radio back: listening on {addr}");
                } else {
                    tracing::info!(target: STATUS_TARGET, "hub: radio there: listening on {addr}");
                    self.radio_seen = true;
                }
                self.counters.listening.store(true, Ordering::Relaxed);
                Some(listener)
            }
            Err(error) => {
                if self.rebind_failures == 0 {
                    tracing::warn!(%addr, %error, "hub: cannot listen again yet (retrying)");
                } else {
                    tracing::debug!(%addr, %error, "hub: cannot listen again yet");
                }
                self.rebind_failures += 1;
                None
            }
        }
    }

    /// Serves until the hub stops or its link ends. `listener` is `None` while the
    /// radio's link is down: clients are refused by the system then rather than
    /// accepted and dropped, so that their links stay down quietly until the radio is
    /// back (or there for the first time).
    async fn run(mut self, mut stream: PacketStream, mut listener: Option<TcpListener>) {
        let mut rebind = tokio::time::interval(REBIND_RETRY);
        rebind.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
        let mut expire = tokio::time::interval(EXPIRE_EVERY);
        expire.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
        // After a failed accept (out of file descriptors, say), accepting waits a
        // moment; the radio's frames go on meanwhile.
        let accept_again = tokio::time::sleep(Duration::ZERO);
        tokio::pin!(accept_again);
        let mut accept_paused = false;
        let mut accept_failures = Repeats::default();
        loop {
            tokio::select! {
                () = self.stop.cancelled() => break,
                // Requests no longer answered give their ids, and their clients'
                // permits, back.
                _ = expire.tick() => {
                    lock(&self.routes).expire(Instant::now());
                    // The clients turned away since the last warning, once they stop.
                    if let Some(more) = self.turned_away.take_due(Instant::now()) {
                        let clients = if more == 1 { "client" } else { "clients" };
                        tracing::warn!(
                            "hub: {more} more {clients} turned away ({MAX_CLIENTS} connected)"
                        );
                    }
                    // Likewise the clients' frames refused since the last warning.
                    let refused = lock(&self.counters.refusals).take_due(Instant::now());
                    if let Some(more) = refused {
                        let frames = if more == 1 { "frame" } else { "frames" };
                        tracing::warn!(
                            "hub: {more} more {frames} of clients refused since the last such \
                             warning"
                        );
                    }
                    // And the failed accepts.
                    if let Some(more) = accept_failures.take_due(Instant::now()) {
                        tracing::warn!("hub: accepting a client failed {more} more times");
                    }
                }
                accepted = accept(listener.as_ref()), if !accept_paused => match accepted {
                    Ok((socket, peer)) => self.accept(socket, peer),
                    Err(error) => {
                        // Out of file descriptors, say: not again at once.
                        match accept_failures.count(Instant::now()) {
                            Some(0) => tracing::warn!(%error, "hub: accepting a client failed"),
                            Some(more) => tracing::warn!(
                                %error,
                                "hub: accepting a client failed, and {more} more times since \
                                 the last such warning"
                            ),
                            None => tracing::debug!(%error, "hub: accepting a client failed"),
                        }
                        accept_paused = true;
                        accept_again.as_mut().reset(Instant::now() + ACCEPT_RETRY);
                    }
                },
                () = &mut accept_again, if accept_paused => accept_paused = false,
                // The port again, if it could not be taken back at once.
                _ = rebind.tick(), if listener.is_none() && self.radio_up => {
                    listener = self.listen_again().await;
                }
                event = stream.next() => match event {
                    Some(event) => {
                        let was_up = self.radio_up;
                        if matches!(&event, Event::Link(link) if !is_up(link)) {
                            // Before the clients are disconnected: none comes back in.
                            // The port held first, then the listener dropped.
                            self.port.hold();
                            listener = None;
                            self.counters.listening.store(false, Ordering::Relaxed);
                        }
                        self.broadcast(&event);
                        if self.radio_up && !was_up && listener.is_none() {
                            // Ctrl-C does not wait for a radio slow to answer.
                            let check =
                                check_radio_mode(&self.sender, self.mode, &self.routes, &self.ids);
                            tokio::select! {
                                () = check => {}
                                () = self.stop.cancelled() => {}
                            }
                            // Unless the radio went away again, or the hub was stopped,
                            // while it was asked.
                            let still_up =
                                self.sender.link_state() == crate::LinkState::Connected;
                            if still_up && !self.stop.is_cancelled() {
                                self.rebind_failures = 0;
                                listener = self.listen_again().await;
                                rebind.reset();
                            }
                        }
                    }
                    None => break,
                },
            }
        }
        // Ends the clients' tasks too, if the link ended first.
        self.stop.cancel();
        self.sender.close();
        drop(stream);
        // Until the radio's device is free.
        self.sender.closed().await;
    }

    fn accept(&mut self, socket: TcpStream, peer: SocketAddr) {
        // Only while the radio's link is up: the hub does not listen otherwise.
        self.clients.retain(|client| !client.queue.is_closed());
        if self.clients.len() >= MAX_CLIENTS && !self.make_room(peer) {
            bump(&self.counters.clients_turned_away);
            match self.turned_away.count(Instant::now()) {
                Some(0) => {
                    tracing::warn!(%peer, "hub: client turned away ({MAX_CLIENTS} connected)");
                }
                Some(more) => tracing::warn!(
                    %peer,
                    "hub: client turned away ({MAX_CLIENTS} connected), and {more} more \
                     since the last such warning"
                ),
                None => tracing::debug!(%peer, "hub: client turned away"),
            }
            return;
        }
        tracing::info!(%peer, "hub: client connected");
        bump(&self.counters.clients);
        tune_client_socket(&socket);
        let (queue, frames) = mpsc::channel(CLIENT_QUEUE);
        let (answers_queue, answers) = mpsc::channel(ANSWER_QUEUE);
        let end = self.stop.child_token();
        let behind = Arc::new(Mutex::new(None));
        let closed = Arc::new(Mutex::new(None));
        let ahead = Arc::new(Mutex::new(None));
        let dropped = Arc::new(AtomicU64::new(0));
        self.clients.push(Connected {
            peer,
            queue: queue.clone(),
            end: end.clone(),
            behind: behind.clone(),
            closed: closed.clone(),
            ahead: ahead.clone(),
            dropped: dropped.clone(),
            said_dropped: None,
        });
        let number = self.next_client;
        self.next_client += 1;
        let client = Arc::new(Client {
            stalls: self.stalls.clone(),
            number,
            peer,
            mode: self.mode,
            to_radio: self.to_radio.clone(),
            queue: AnswerQueue {
                queue: answers_queue,
                peer,
                counters: self.counters.clone(),
                dropped: Arc::default(),
            },
            routes: self.routes.clone(),
            ids: self.ids.clone(),
            shared: self.shared.clone(),
            permits: Arc::new(Semaphore::new(ROUTES_PER_CLIENT)),
            many: Arc::new(Semaphore::new(MANY_ANSWER_PER_CLIENT)),
            input: self.client_input,
            counters: self.counters.clone(),
            end,
            behind,
            closed,
            ahead,
            dropped,
            skipped: AtomicU64::new(0),
            warned_skipped: AtomicBool::new(false),
        });
        let (rd, wr) = socket.into_split();
        let (frames_to_radio, queue) = mpsc::channel(CLIENT_FRAMES_TO_RADIO);
        lock(&self.to_radio.new).push((queue, client.clone()));
        self.to_radio.ready.notify_one();
        self.tasks.spawn(client.clone().read(rd, frames_to_radio));
        self.tasks.spawn(client.write(wr, frames, answers));
    }

    /// Ends, for `peer`, a new one, the client that closed its connection first, or
    /// without one the client that has taken none of the radio's frames the longest,
    /// [`STALLED`] at least, or without one the client that has written ahead of the
    /// radio the longest, [`STALLED`] at least; whether there was one.
    fn make_room(&mut self, peer: SocketAddr) -> bool {
        let longest = |state: fn(&Connected) -> &Mutex<Option<Instant>>, least: Duration| {
            self.clients
                .iter()
                .enumerate()
                .filter_map(|(index, client)| Some(((*lock(state(client)))?, index)))
                .filter(|(since, _)| since.elapsed() >= least)
                .min()
        };
        let (why, since, index) =
            if let Some((since, index)) = longest(|c| &c.closed, Duration::ZERO) {
                (
                    "it has sent nothing since it closed its connection",
                    since,
                    index,
                )
            } else if let Some((since, index)) = longest(|c| &c.behind, STALLED) {
                ("it has taken none of the radio's frames", since, index)
            } else if let Some((since, index)) = longest(|c| &c.ahead, STALLED) {
                (
                    "it has written frames faster than the radio sends them, its frames \
                     waiting their turn",
                    since,
                    index,
                )
            } else {
                return false;
            };
        let gone = self.clients.swap_remove(index);
        gone.end.cancel();
        let client = gone.peer;
        let since = crate::render::Seconds::measured(since.elapsed());
        if lock(&gone.closed).is_some() {
            // As a client that left.
            tracing::debug!("hub: client {client} let go for {peer}: {why} for {since}");
        } else {
            tracing::warn!(
                "hub: client {client} dropped for {peer} ({MAX_CLIENTS} connected): {why} for \
                 at least {since}"
            );
        }
        true
    }

    /// A frame from the radio: an answer to its client, anything else to every client.
    fn broadcast(&mut self, event: &Event) {
        let data = match event {
            Event::Packet(rx) => &rx.frame,
            Event::InvalidPacket(rx) => &rx.frame,
            Event::Frame(frame) => frame.data(),
            Event::Link(link) => {
                match link {
                    LinkEvent::Disconnected { reason } if self.radio_up => tracing::warn!(
                        "hub: radio lost: {reason}; clients disconnected, and none accepted \
                         until it is back"
                    ),
                    _ => tracing::debug!(?link, "hub: radio link"),
                }
                self.radio_up = is_up(link);
                if !self.radio_up {
                    // The clients' links see the outage as the hub's own link does (and
                    // reconnect to the hub once the radio is back).
                    for client in self.clients.drain(..) {
                        client.end.cancel();
                    }
                }
                return;
            }
            Event::DecodeError(_) => return,
        };
        bump(&self.counters.frames_from_radio);
        if let [frame_type, id, ..] = data[..] {
            if is_response(frame_type) && id != 0 {
                self.answer(data, id);
                return;
            }
        }
        let Some(bytes) = encode(data, self.mode) else {
            return;
        };
        let counters = &self.counters;
        self.clients
            .retain_mut(|client| match client.queue.try_send(bytes.clone()) {
                Ok(()) => true,
                Err(mpsc::error::TrySendError::Full(_)) => {
                    bump(&counters.frames_dropped);
                    let now = Instant::now();
                    lock(&client.behind).get_or_insert(now);
                    client.dropped_one(now);
                    true
                }
                Err(mpsc::error::TrySendError::Closed(_)) => false,
            });
    }

    /// An answer under hub id `id`: to the client that asked, under its own id; dropped
    /// if nobody asked for an answer of that type (and AT command) under it (every id on
    /// the hub's link is the hub's).
    fn answer(&self, data: &[u8], id: u8) {
        let to = lock(&self.routes).answer(id, data, Instant::now());
        let Some((client, own_id)) = to else {
            tracing::debug!(id, "hub: an answer nobody waits for dropped");
            return;
        };
        let mut data = data.to_vec();
        if let Some(slot) = data.get_mut(1) {
            *slot = own_id;
        }
        if let Some(bytes) = encode(&data, self.mode) {
            client.send(bytes);
        }
    }
}

/// How long a client must have taken none of the radio's frames, while frames were
/// dropped for it, before its place may go to a new client. The hub hands frames to the
/// system in bursts, as a client's reads free about a third of the buffers of its
/// connection (some 40 KB): a client that reads 4 KB/s or more, a third of what an
/// XBee's UART carries at 115200 baud, takes some within this time, and keeps its
/// place. A client that has written ahead of the radio for as long (each of its frames
/// waiting its turn) may give its place up too.
pub const STALLED: Duration = Duration::from_secs(20);

/// The send buffer the hub asks the system for on each client's connection (Linux
/// doubles it): with [`CLIENT_QUEUE`], how far a client that reads nothing can be
/// behind before frames are dropped for it.
const CLIENT_SEND_BUFFER: usize = 64 * 1024;

/// A client's connection quiet for a minute is probed every 10 s, and given up after 9
/// probes unanswered (two and a half minutes in all): a client is let go later than a
/// radio's link gives its peer up, as a laptop on a weak network may be slow to answer.
/// No limit on data unacknowledged: Linux would count a client that stopped reading (a
/// monitor suspended, a pager paused) as gone once it held that long, where the hub
/// keeps it until its place is needed; one that is gone with data unacknowledged is
/// let go once the system stops sending it again (about a quarter of an hour on
/// Linux), or its place taken first.
const CLIENT_KEEPALIVE: crate::transport::KeepAlive = crate::transport::KeepAlive {
    idle: Duration::from_secs(60),
    interval: Duration::from_secs(10),
    probes: 9,
    unacknowledged: None,
};

/// How long the hub waits to accept clients again after accepting one failed (out of
/// file descriptors, say), serving the others meanwhile.
const ACCEPT_RETRY: Duration = Duration::from_millis(100);

/// How often routes whose answers are no longer due are ended.
const EXPIRE_EVERY: Duration = Duration::from_secs(1);

/// How often the hub tries to take its port back after an outage of the radio, if
/// another program took it meanwhile.
const REBIND_RETRY: Duration = Duration::from_secs(1);

/// Whether a link event leaves the radio's link up.
fn is_up(link: &LinkEvent) -> bool {
    matches!(
        link,
        LinkEvent::Connected { .. } | LinkEvent::Reconnected { .. }
    )
}

/// The `tracing` target of the hub's status lines, logged at info level: the radio
/// there at last and the hub listening (`hub: radio there: listening on ADDR`), the
/// radio back after an outage (`hub: radio back: listening on ADDR`). The outage itself
/// is a warning. A program that shows warnings alone shows these too with the filter
/// `warn,mcp_host::hub::status=info`, as `mcp-gs hub` does.
pub const STATUS_TARGET: &str = "mcp_host::hub::status";

/// How long the radio has to answer the hub's `AT AP`: a local AT command is answered
/// in milliseconds.
pub const MODE_CHECK_TIMEOUT: Duration = Duration::from_secs(1);

/// Asks the radio its `AP` each time it is there, before the hub listens (no client is
/// connected then), and warns if it is another API mode than the hub's, or if the radio
/// does not answer: the hub drops what it cannot read, and its clients would hear
/// nothing, not knowing why. Holds the frame ids of the requests not answered in time
/// from clients ([`Routes::hold`]): a radio that answers late would answer a client's
/// request under the same id.
async fn check_radio_mode(
    sender: &CommandSender,
    mode: ApiMode,
    routes: &Mutex<Routes>,
    permits: &Arc<Semaphore>,
) {
    let mut asked = Vec::new();
    let mut ask = async || {
        let answer = sender.at(*b"AP", &[], Some(MODE_CHECK_TIMEOUT)).await;
        // An answer may still come under the id of a request that had none in time.
        if let Err(error @ crate::SendError::Timeout { .. }) = &answer {
            asked.extend(error.frame_id());
        }
        answer
    };
    let mut answer = ask().await;
    if matches!(answer, Err(crate::SendError::Timeout { .. })) {
        // Asked once more: a radio just plugged in may still be starting.
        answer = ask().await;
    }
    lock(routes).hold(&asked, permits, Instant::now());
    let hub = u8::from(mode);
    match answer {
        Ok(response) => {
            // An answer under the request's id, of another command, is a late one to a
            // client's request from before an outage: nothing is said of it.
            if let Ok(xbee_api::Frame::AtCommandResponse(at)) = response.parse() {
                match (at.command == *b"AP" && at.status.is_ok(), at.data) {
                    (true, &[ap]) if ap != hub => tracing::warn!(
                        "hub: the radio is in API mode {ap} (AP={ap}) but the hub speaks \
                         API mode {hub}: most of its frames will be dropped, and clients \
                         will hear little; start the hub in API mode {ap} \
                         (`mcp-gs hub --api-mode {ap}`)"
                    ),
                    _ => {}
                }
            }
        }
        Err(crate::SendError::Timeout { .. }) => {
            // A peer that serves one connection at a time lets the next wait, silent.
            let busy = match sender.info().link {
                crate::Link::Tcp { .. } => {
                    ", or the peer on the other end of the tcp: link serves another \
                     connection (a simulator or a bridge that serves one at a time)"
                }
                _ => "",
            };
            tracing::warn!(
                "hub: the radio did not answer AT AP (asked twice, {} \
                 each) in API mode {hub}: it may be in transparent mode (AP=0), or its baud \
                 rate may differ from the link's{busy}, and clients would then hear \
                 nothing until that is fixed (or it is slow to answer, behind a bridge: \
                 then all is well)",
                crate::render::Seconds(MODE_CHECK_TIMEOUT)
            )
        }
        Err(_) => {}
    }
}

/// Sets a client's connection up: frames one at a time, as the radio writes them; what
/// the system holds for a client that reads nothing bounded (it would otherwise grow to
/// megabytes, thousands of frames); a peer that went away without a word (a laptop
/// asleep) found out even on a quiet network. A setting the system refuses is left as
/// it was.
fn tune_client_socket(socket: &TcpStream) {
    let _ = socket.set_nodelay(true);
    let sock = socket2::SockRef::from(socket);
    let _ = sock.set_send_buffer_size(CLIENT_SEND_BUFFER);
    // While the radio's frames flow to a peer that is gone, the system would otherwise
    // retransmit for a quarter of an hour before giving it up.
    crate::transport::keep_alive(socket, &CLIENT_KEEPALIVE);
}

/// The next client of `listener`; never, without one.
async fn accept(listener: Option<&TcpListener>) -> std::io::Result<(TcpStream, SocketAddr)> {
    match listener {
        Some(listener) => listener.accept().await,
        None => std::future::pending().await,
    }
}

fn lock<T>(shared: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    // A panic elsewhere leaves the table (or the list) as consistent as ever.
    shared.lock().unwrap_or_else(PoisonError::into_inner)
}

/// One client's connection, served by two tasks: one reads its frames and writes them
/// to the radio, the other writes the radio's frames to it. The client is gone when
/// both have ended; its requests' routes then end too.
struct Client {
    /// The hub's stalls: a request read just after one counts from its beginning.
    stalls: Arc<Stalls>,
    /// Its number, in its routes.
    number: u64,
    peer: SocketAddr,
    mode: ApiMode,
    /// Where its queue of frames to the radio is taken from.
    to_radio: Arc<ToRadio>,
    /// Its queue of the answers to its requests.
    queue: AnswerQueue,
    routes: Arc<Mutex<Routes>>,
    /// The permits of the 255 frame ids, shared by all clients.
    ids: Arc<Semaphore>,
    /// The permits of the [`SHARED_IDS`], shared by all clients' requests beyond their
    /// first [`IDS_PER_CLIENT`].
    shared: Arc<Semaphore>,
    /// Its [`ROUTES_PER_CLIENT`] permits to have a request waiting for answers.
    permits: Arc<Semaphore>,
    /// Its [`MANY_ANSWER_PER_CLIENT`] permits to have a request answered many times
    /// waiting.
    many: Arc<Semaphore>,
    /// How its frames are read.
    input: ClientInput,
    counters: Arc<Counters>,
    /// Ends both its tasks: the hub stopped, the radio's link went down, its
    /// connection failed, or another client took its place.
    end: CancellationToken,
    /// Since when its queue of frames from the radio has been full, without being
    /// drained since.
    behind: Arc<Mutex<Option<Instant>>>,
    /// Since when it has sent nothing more (see [`Connected::closed`]).
    closed: Arc<Mutex<Option<Instant>>>,
    /// Since when it has written ahead of the radio: a frame it sent found its
    /// [`CLIENT_FRAMES_TO_RADIO`] places taken, and waited its turn, and the hub has not
    /// read all it wrote since; `None` once it has (the client waits for more: a frame
    /// finding a place free says nothing, as the radio's writer may take two short
    /// frames of a flood at once). A client that writes faster than the radio sends
    /// keeps it:
    /// one that keeps it for [`STALLED`] gives its place up when the hub is full (a
    /// program that left megabytes of frames in its connection, whose end the hub
    /// cannot read before them, is one).
    ahead: Arc<Mutex<Option<Instant>>>,
    /// The radio's frames dropped for it (see [`Connected::dropped`]).
    dropped: Arc<AtomicU64>,
    /// Its bytes that began no frame, skipped.
    skipped: AtomicU64,
    /// Whether its bytes skipped were said (the first not after a refused frame).
    warned_skipped: AtomicBool,
}

impl Drop for Client {
    /// Once both its tasks have ended: its requests' answers are no longer routed; the
    /// frame ids of those not written are free again, and those written stay orphans
    /// ([`Routes::forget`]).
    fn drop(&mut self) {
        lock(&self.routes).forget(self.number, &self.shared);
    }
}

impl Client {
    /// Reads the client's frames and writes them to the radio, until the client stops
    /// sending or its connection ends. A client that stops sending (its connection
    /// closed, or only its write side shut) is the first to give its place to a new
    /// client when the hub is full; until then it still gets its answers and the radio's
    /// frames, and its frames already read still go to the radio. A connection that
    /// fails ends the client. Its frames are read as the radio's (see [`ClientInput`]).
    async fn read(self: Arc<Self>, rd: OwnedReadHalf, to_radio: mpsc::Sender<Queued>) {
        let mut reader = FramedRead::new(rd, ClientCodec::new(self.mode, self.input));
        let timeout = self.input.partial_frame_timeout;
        // The client's bytes that were in the reader's buffer when one of its frames
        // began to wait (see `admit`), and since when: frames wholly among them were
        // there all that time, and their own wait counts from then.
        let mut old: Option<(Instant, usize)> = None;
        // When the bytes of the last item, skipped bytes, were read (see `old`), for the
        // frame the codec found after them, which it yields next from the same bytes.
        let mut held: Option<Option<Instant>> = None;
        let read = async {
            loop {
                let check_stale_at = reader.decoder().codec().stale_check_at(timeout);
                let before = reader.read_buffer().len();
                let ready = reader.next().now_or_never();
                let item = if let Some(item) = ready {
                    item
                } else {
                    // All it wrote is read: it is not ahead of the radio (a burst, then
                    // quiet), whatever its last frame found.
                    *lock(&self.ahead) = None;
                    tokio::select! {
                        item = reader.next() => item,
                        () = tokio::time::sleep_until(check_stale_at.unwrap_or_else(Instant::now)), if check_stale_at.is_some() => {
                            // Bytes may be waiting unread (this task ran late): they come
                            // first, and the next turn looks again.
                            if let Some(item) = reader.next().now_or_never() {
                                item
                            } else {
                                if reader.decoder().codec().is_stale(timeout, Instant::now()) {
                                    old = None;
                                    held = None;
                                    for item in reader.decoder_mut().drop_partial() {
                                        let item = match item {
                                            ClientItem::Codec(item) => item,
                                            ClientItem::Skipped { bytes, after_error } => {
                                                self.skipped(bytes, after_error);
                                                continue;
                                            }
                                        };
                                        if self.pass(item, &to_radio, None).await.is_err() {
                                            return;
                                        }
                                    }
                                }
                                continue;
                            }
                        }
                    }
                };
                // Taken from the old bytes alone (none read since), or not.
                let after = reader.read_buffer().len();
                let since = match old {
                    Some((since, bytes)) if after <= before && before - after <= bytes => {
                        old = (bytes > before - after).then(|| (since, bytes - (before - after)));
                        Some(since)
                    }
                    _ => {
                        old = None;
                        None
                    }
                };
                // A frame held behind bytes skipped was taken from the buffer with them:
                // read when they were.
                let since = match held.take() {
                    Some(held) if after == before => held,
                    _ => since,
                };
                if let Some(Ok(ClientItem::Skipped { .. })) = &item {
                    held = Some(since);
                }
                // Just after a stall of the hub, the request may have come as it began.
                let since = match (self.stalls.beat(), since) {
                    (Some(began), Some(since)) => Some(since.min(began)),
                    (began, since) => since.or(began),
                };
                match item {
                    Some(Ok(ClientItem::Skipped { bytes, after_error })) => {
                        self.skipped(bytes, after_error);
                    }
                    Some(Ok(ClientItem::Codec(item))) => {
                        match self.pass(item, &to_radio, since).await {
                            Err(()) => return, // The hub stops.
                            // The bytes waiting behind it now were there when it began to
                            // wait (or, if it was itself old, when the first of its line did).
                            Ok(Some(waited)) => {
                                let buffered = reader.read_buffer().len();
                                old = (buffered > 0).then(|| (since.unwrap_or(waited), buffered));
                            }
                            Ok(None) => {}
                        }
                    }
                    Some(Err(error)) => {
                        tracing::debug!(peer = %self.peer, %error, "hub: reading from a client failed");
                        self.end.cancel();
                        return;
                    }
                    None => {
                        tracing::debug!(peer = %self.peer, "hub: a client sends nothing more");
                        return;
                    }
                }
            }
        };
        tokio::select! {
            () = self.end.cancelled() => {}
            () = read => {}
        }
        lock(&self.closed).get_or_insert_with(Instant::now);
        // The writer sees the queue closed (or the client ended) and lets the client go
        // once it may.
        drop(to_radio);
        self.to_radio.ready.notify_one();
    }

    /// Counts `bytes` of this client's skipped, that began no frame; the first it sends
    /// are said as a warning (the client hears nothing back), unless they came
    /// `after_error` (the rest of a frame already said as refused, perhaps), the others
    /// counted when it goes.
    fn skipped(&self, bytes: u64, after_error: bool) {
        self.counters
            .bytes_skipped
            .fetch_add(bytes, Ordering::Relaxed);
        self.skipped.fetch_add(bytes, Ordering::Relaxed);
        if !after_error && !self.warned_skipped.swap(true, Ordering::Relaxed) {
            tracing::warn!(
                peer = %self.peer,
                "hub: a client's bytes skipped: {} that began no frame (the hub takes \
                 XBee API frames in API mode {}, each from a 0x7E: is the client sending \
                 text, or in transparent mode?); all the client's are counted when it \
                 goes",
                crate::diagnosis::counted(bytes, "byte"),
                u8::from(self.mode)
            );
        }
    }

    /// Counts a frame of this client's refused, and says why as a warning: the first at
    /// once, then at most one a second with the number of those not said.
    fn refuse(&self, why: std::fmt::Arguments<'_>) {
        bump(&self.counters.frames_refused);
        let peer = self.peer;
        match lock(&self.counters.refusals).count(Instant::now()) {
            Some(0) => tracing::warn!(%peer, "hub: a client's frame refused: {why}"),
            Some(more) => tracing::warn!(
                %peer,
                "hub: a client's frame refused: {why}; and {more} more frames refused since \
                 the last such warning (of any client, for any cause)"
            ),
            None => tracing::debug!(%peer, "hub: a client's frame refused: {why}"),
        }
    }

    /// Passes an item of the client's reader on: a frame admitted to the radio's queue
    /// (waiting while [`CLIENT_FRAMES_TO_RADIO`] frames wait their turn), its wait
    /// counted from `since` if it was read then already (see `read`). Since when it
    /// waited, if it did; `Err` once the hub stops.
    async fn pass(
        &self,
        item: CodecItem,
        to_radio: &mpsc::Sender<Queued>,
        since: Option<Instant>,
    ) -> Result<Option<Instant>, ()> {
        let mut waited = None;
        match item {
            CodecItem::Frame(frame) => {
                if let Some(queued) = self.admit(frame.data(), since, &mut waited).await {
                    let queued = match to_radio.try_send(queued) {
                        Ok(()) => None,
                        Err(mpsc::error::TrySendError::Full(queued)) => {
                            // Its turn waited for: the client's bytes are not read.
                            waited.get_or_insert_with(Instant::now);
                            lock(&self.ahead).get_or_insert_with(Instant::now);
                            Some(queued)
                        }
                        Err(mpsc::error::TrySendError::Closed(_)) => return Err(()),
                    };
                    if let Some(queued) = queued {
                        self.to_radio.ready.notify_one();
                        if to_radio.send(queued).await.is_err() {
                            return Err(());
                        }
                    }
                    self.to_radio.ready.notify_one();
                }
            }
            // Longer than the hub takes, or not a frame: refused, and said, as a radio
            // would drop it without a word.
            CodecItem::Error(error) => {
                let hint = match error {
                    xbee_api::DecodeError::BadChecksum { .. }
                    | xbee_api::DecodeError::BadEscape { .. } => format!(
                        " (the hub speaks API mode {}: is the client in the other?)",
                        u8::from(self.mode)
                    ),
                    _ => String::new(),
                };
                self.refuse(format_args!("{error}{hint}"));
            }
        }
        Ok(waited)
    }

    /// Writes the radio's frames to the client, until its connection fails or it is
    /// ended; a client that reads nothing does not hold the hub up.
    async fn write(
        self: Arc<Self>,
        mut wr: OwnedWriteHalf,
        mut frames: mpsc::Receiver<Bytes>,
        mut answers: mpsc::Receiver<Bytes>,
    ) {
        let write = async {
            loop {
                // Its answers first, ahead of the radio's frames that wait (the client
                // itself holds a sender of its answers: they never end first).
                let next = tokio::select! {
                    biased;
                    Some(bytes) = answers.recv() => Some(bytes),
                    bytes = frames.recv() => bytes,
                };
                let Some(bytes) = next else { break };
                if let Err(error) = wr.write_all(&bytes).await {
                    return error.to_string();
                }
                // A frame taken: a client that reads, however slowly, is not one that
                // stopped.
                *lock(&self.behind) = None;
            }
            "the hub stopped".to_owned()
        };
        let reason = tokio::select! {
            () = self.end.cancelled() => "the hub stopped, the radio's link went down, or another client took its place".to_owned(),
            reason = write => reason,
        };
        // A client that closed its connection has left as it meant to: the frames it
        // sent before still go to the radio.
        if lock(&self.closed).is_none() {
            self.end.cancel();
        }
        let dropped = match self.dropped.load(Ordering::Relaxed) {
            0 => None,
            dropped => Some(format!("{dropped} of the radio's frames dropped for it")),
        };
        let skipped = match self.skipped.load(Ordering::Relaxed) {
            0 => None,
            skipped => Some(format!(
                "{} from it that began no frame skipped",
                crate::diagnosis::counted(skipped, "byte")
            )),
        };
        let said: Vec<String> = dropped.into_iter().chain(skipped).collect();
        match said.is_empty() {
            true => tracing::info!(peer = %self.peer, %reason, "hub: client gone"),
            false => tracing::info!(
                peer = %self.peer,
                %reason,
                "hub: client gone ({})",
                said.join("; ")
            ),
        }
    }

    /// Refuses `request` (under the client's own id), which waited [`REQUEST_WAIT`] for
    /// `what` in vain: not sent, and answered as failed ([`not_sent_answer`]) as its
    /// answers are.
    fn not_sent(&self, request: &[u8], what: &str) {
        self.refuse_request(
            request,
            format_args!("waited {} for {what}", crate::render::Seconds(REQUEST_WAIT)),
        );
    }

    /// Refuses `request` (under the client's own id) for `why`, and answers it as failed
    /// ([`not_sent_answer`]) as its answers are, ahead of the radio's frames waiting for
    /// this client.
    fn refuse_request(&self, request: &[u8], why: std::fmt::Arguments<'_>) {
        // The answer first: once the refusal is counted, it is on its way.
        let answer = not_sent_answer(request).and_then(|answer| encode(&answer, self.mode));
        if let Some(bytes) = answer {
            self.queue.send(bytes);
        }
        let frame_type = request.first().copied().unwrap_or_default();
        self.refuse(format_args!(
            "a request of type 0x{frame_type:02x} {why}: not sent, and answered as failed"
        ));
    }

    /// A client's frame as it goes to the radio: under a hub id if it is a request with
    /// a frame id, its answers then routed back to this client; `None` if refused. A
    /// frame of a type the hub does not know as a request is refused if it carries a
    /// frame id (byte 1): its answers could not be told from those to other clients'
    /// requests. So is a request with a frame id cut short of its fixed fields: no
    /// radio answers it.
    async fn admit(
        &self,
        data: &Bytes,
        since: Option<Instant>,
        waited: &mut Option<Instant>,
    ) -> Option<Queued> {
        let mut data = data.to_vec();
        // REQUEST_WAIT from when the hub could first have read it.
        let deadline = since.unwrap_or_else(Instant::now) + REQUEST_WAIT;
        let mut request_deadline = None;
        if let Some(&frame_type) = data.first() {
            // A radio drops such a frame unanswered; the hub refuses it, so that the
            // client's mistake is counted and said rather than lost at the radio.
            if crate::event::is_from_radio(frame_type) {
                self.refuse(format_args!(
                    "type 0x{frame_type:02x}{} is a frame a radio sends, not one it takes \
                     (a recording of what a radio said, played onto the hub?)",
                    crate::render::json::frame_type_name(frame_type)
                        .map(|name| format!(" ({name})"))
                        .unwrap_or_default()
                ));
                return None;
            }
        }
        if let [frame_type, own_id, ..] = data[..] {
            if own_id != 0 {
                let Some(answer_type) = answer_type(frame_type) else {
                    self.refuse(format_args!(
                        "a frame id on type 0x{frame_type:02x}, which the hub does not know \
                         (its answers could not be told from other clients')"
                    ));
                    return None;
                };
                if !is_whole_request(&data) {
                    self.refuse(format_args!(
                        "a request of type 0x{frame_type:02x} cut short of its fixed fields \
                         ({} bytes): no radio answers it",
                        data.len()
                    ));
                    return None;
                }
                // Waits while the client has ROUTES_PER_CLIENT requests waiting for
                // answers (MANY_ANSWER_PER_CLIENT answered many times), then, beyond its
                // first IDS_PER_CLIENT, for one of the shared ids, then for a free frame
                // id (the semaphores are never closed); REQUEST_WAIT in all at most.
                // Meanwhile the client's bytes are not read: the frames after it, there
                // already, wait as long, and not much longer (see `read`).
                let many = answered_many_times(&data);
                let mut held = false;
                let mut take = async |permits: &Arc<Semaphore>| {
                    if let Ok(permit) = permits.clone().try_acquire_owned() {
                        return Some(permit);
                    }
                    if !std::mem::replace(&mut held, true) {
                        bump(&self.counters.requests_held);
                        waited.get_or_insert_with(Instant::now);
                    }
                    permits.clone().acquire_owned().await.ok()
                };
                let taken = tokio::time::timeout_at(deadline, async {
                    let permit = take(&self.permits).await?;
                    let many = match many {
                        true => Some(take(&self.many).await?),
                        false => None,
                    };
                    let waiting = ROUTES_PER_CLIENT - self.permits.available_permits();
                    let shared = match waiting > IDS_PER_CLIENT {
                        true => Some(take(&self.shared).await?),
                        false => None,
                    };
                    let id = take(&self.ids).await?;
                    Some((permit, many, shared, id))
                })
                .await;
                let Ok(Some((permit, many_permit, shared, id))) = taken else {
                    self.not_sent(
                        &data,
                        "a frame id (this client's earlier requests, or other clients', wait \
                         for answers)",
                    );
                    return None;
                };
                let route = Route {
                    client: self.number,
                    queue: self.queue.clone(),
                    own_id,
                    answer_type,
                    command: at_command(&data),
                    until: Cell::new(None),
                    many,
                    orphan: Cell::new(false),
                    _permit: permit,
                    _many: many_permit,
                    _shared: shared,
                    _id: id,
                };
                // An id is free: the route holds one of the 255 permits (but for ids
                // the hub holds for late answers to its own requests without one).
                let Some(id) = lock(&self.routes).insert(route, Instant::now()) else {
                    self.refuse_request(
                        &data,
                        format_args!(
                            "found no frame id free (those left are kept for late answers \
                             to the hub's own requests)"
                        ),
                    );
                    return None;
                };
                if let Some(slot) = data.get_mut(1) {
                    *slot = id;
                }
                request_deadline = Some(deadline);
            }
        }
        Some(Queued {
            data,
            deadline: request_deadline,
        })
    }
}

/// The answer the hub gives a request it did not send ([`REQUEST_WAIT`]), as the radio
/// answers one it could not carry out, under the client's own id: an AT command
/// `ERROR` (1), a transmission's delivery status 0x32 (resource error: the radio's own
/// word for a lack of buffers; in a Transmit Status 0x8B, or a TX Status 0x89 for the
/// 802.15.4 and IPv4 Transmit Requests), a remote AT command's transmission failure
/// (4). `None` for the other requests (Register Joining Device), and for requests cut
/// short ([`is_whole_request`]), whose clients wait for their own timeouts.
fn not_sent_answer(request: &[u8]) -> Option<Vec<u8>> {
    if !is_whole_request(request) {
        return None;
    }
    match request {
        [0x08 | 0x09, id, a, b, ..] => Some(vec![0x88, *id, *a, *b, 0x01]),
        // Resource error in a TX Status too, as 802.15.4 (S2C) and IPv4 radios give it.
        [0x00 | 0x01 | 0x20, id, ..] => Some(vec![0x89, *id, 0x32]),
        // The 16-bit address after the 64-bit one; no retries, no discovery.
        [0x10 | 0x11, id, _, _, _, _, _, _, _, _, hi, lo, ..] => {
            Some(vec![0x8B, *id, *hi, *lo, 0x00, 0x32, 0x00])
        }
        // The 64- and 16-bit addresses, options, the command.
        [0x17, id, rest @ ..] => {
            let (addresses, command) = (rest.get(..10)?, rest.get(11..13)?);
            let mut answer = vec![0x97, *id];
            answer.extend_from_slice(addresses);
            answer.extend_from_slice(command);
            answer.push(0x04);
            Some(answer)
        }
        _ => None,
    }
}

/// Frame data encoded whole for the wire; `None` for data no frame can hold.
fn encode(data: &[u8], mode: ApiMode) -> Option<Bytes> {
    let frame = RawFrame::new(data).ok()?;
    let mut buf = BytesMut::new();
    encode_frame(&frame, mode, &mut buf).ok()?;
    Some(buf.freeze())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn discovery_is_answered_many_times_in_either_case_and_other_commands_once() {
        for many in [
            &[0x08, 1, b'N', b'D'][..],
            &[0x08, 1, b'n', b'd'],
            &[0x08, 1, b'F', b'N'],
            &[0x09, 1, b'A', b's', 0],
            // Any remote command to every radio, and a remote radio's discovery.
            &[
                0x17, 1, 0, 0, 0, 0, 0, 0, 0xFF, 0xFF, 0xFF, 0xFE, 0, b'N', b'I',
            ],
            &[
                0x17, 1, 0, 0, 0, 0, 0, 0, 0x12, 0x34, 0xFF, 0xFE, 0, b'f', b'n',
            ],
        ] {
            assert!(answered_many_times(many), "{many:02x?}");
        }
        for once in [
            &[0x08, 1, b'N', b'I'][..],
            &[0x08, 1, b'N'],
            &[0x08, 1],
            &[0x10, 1, b'N', b'D'],
            &[
                0x17, 1, 0, 0, 0, 0, 0, 0, 0x12, 0x34, 0xFF, 0xFE, 0, b'D', b'H',
            ],
            &[0x17, 1, 0, 0, 0, 0, 0, 0, 0x12, 0x34, 0xFF, 0xFE, 0, b'N'],
        ] {
            assert!(!answered_many_times(once), "{once:02x?}");
        }
    }

    #[test]
    fn a_request_not_sent_is_answered_as_the_radio_answers_one_it_could_not_carry_out() {
        use xbee_api::{AtStatus, DeliveryStatus, Frame};
        let at = not_sent_answer(&[0x08, 7, b'N', b'I', b'G', b'S']).unwrap();
        match Frame::parse_bytes(&at) {
            Ok(Frame::AtCommandResponse(r)) => {
                assert_eq!(
                    (r.frame_id, r.command, r.status),
                    (7, *b"NI", AtStatus::Error)
                );
            }
            other => panic!("{other:?}"),
        }
        let mut tx = vec![
            0x10, 9, 0, 0x13, 0xA2, 0, 0x40, 0xB5, 0x99, 0xB9, 0x12, 0x34, 0, 0,
        ];
        tx.extend_from_slice(b"c\x02\x01");
        match Frame::parse_bytes(&not_sent_answer(&tx).unwrap()) {
            Ok(Frame::TransmitStatus(s)) => {
                assert_eq!(s.frame_id, 9);
                assert_eq!(s.dst16.0, 0x1234);
                assert_eq!(s.delivery, DeliveryStatus::ResourceError);
            }
            other => panic!("{other:?}"),
        }
        let remote = [
            0x17, 3, 0, 0x13, 0xA2, 0, 0x40, 0xB5, 0x99, 0xB9, 0xFF, 0xFE, 0x02, b'D', b'H',
        ];
        match Frame::parse_bytes(&not_sent_answer(&remote).unwrap()) {
            Ok(Frame::RemoteAtResponse(r)) => {
                assert_eq!(r.frame_id, 3);
                assert_eq!(r.src64.0, 0x0013_A200_40B5_99B9);
                assert_eq!(r.src16.0, 0xFFFE);
                assert_eq!(r.command, *b"DH");
                assert_eq!(r.status, AtStatus::TxFailure);
            }
            other => panic!("{other:?}"),
        }
        // 802.15.4 (64- and 16-bit addresses) and IPv4 Transmit Requests: TX Status
        // 0x89, the same resource error.
        let tx64 = [
            0x00, 4, 0, 0x13, 0xA2, 0, 0x40, 0xB5, 0x99, 0xB9, 0x00, b'c',
        ];
        let tx16 = [0x01, 5, 0x12, 0x34, 0x00, b'c'];
        let ipv4 = [
            0x20, 6, 10, 0, 0, 2, 0x26, 0x16, 0x26, 0x16, 0x00, 0x00, b'c',
        ];
        for (request, id) in [(&tx64[..], 4), (&tx16[..], 5), (&ipv4[..], 6)] {
            assert_eq!(
                not_sent_answer(request),
                Some(vec![0x89, id, 0x32]),
                "{request:02x?}"
            );
            // Cut short of their fixed fields: no answer, as from the radio.
            let short = &request[..request.len() - 2];
            assert_eq!(not_sent_answer(short), None, "{short:02x?}");
        }
        // Requests cut short, and those of other types, get no answer.
        for none in [
            &[0x08, 1, b'N'][..],
            &tx[..11],
            &remote[..14],
            &[0x24, 1, 0],
            &[
                0x24, 1, 0, 0x13, 0xA2, 0, 0x40, 0xB5, 0x99, 0xB9, 0xFF, 0xFE, 0,
            ],
        ] {
            assert_eq!(not_sent_answer(none), None, "{none:02x?}");
        }
    }

    #[cfg(target_os = "linux")]
    #[tokio::test]
    async fn a_clients_connection_has_a_bounded_send_buffer_and_keepalive() {
        let listener = TcpListener::bind("127.0.0.1:0").await.unwrap();
        let (client, accepted) = tokio::join!(
            TcpStream::connect(listener.local_addr().unwrap()),
            listener.accept()
        );
        let (socket, _) = accepted.unwrap();
        let _client = client.unwrap();
        tune_client_socket(&socket);
        let sock = socket2::SockRef::from(&socket);
        assert!(socket.nodelay().unwrap());
        // Linux doubles what is asked, for its own bookkeeping.
        // (A system whose `net.core.wmem_max` is lower caps it.)
        let buffer = sock.send_buffer_size().unwrap();
        assert!(buffer <= 2 * CLIENT_SEND_BUFFER, "{buffer}");
        crate::transport::assert_kept_alive(&socket, &CLIENT_KEEPALIVE);
    }
}
