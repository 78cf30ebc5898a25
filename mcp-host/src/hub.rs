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

mod client;
mod input;
mod port;
mod radio_writer;
mod request;
mod routes;
mod serve;
mod stall;

#[cfg(feature = "fuzzing")]
#[doc(hidden)]
pub mod fuzzing;

use std::net::SocketAddr;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use bytes::{Bytes, BytesMut};
use tokio::sync::Semaphore;
use tokio_util::sync::CancellationToken;
use tokio_util::task::TaskTracker;
use xbee_api::{ApiMode, RawFrame};

use self::input::ClientInput;
use self::port::Port;
use self::radio_writer::{RadioWriter, ToRadio};
use self::routes::Routes;
use self::serve::{Serve, check_radio_mode};
use self::stall::Stalls;
use crate::codec::encode_frame;
use crate::repeats::Repeats;
use crate::{ConnectError, Link, LinkInfo, LinkOptions, Stats};

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

/// How long a client must have taken none of the radio's frames, while frames were
/// dropped for it, before its place may go to a new client. The hub hands frames to the
/// system in bursts, as a client's reads free about a third of the buffers of its
/// connection (some 40 KB): a client that reads 4 KB/s or more, a third of what an
/// XBee's UART carries at 115200 baud, takes some within this time, and keeps its
/// place. A client that has written ahead of the radio for as long (each of its frames
/// waiting its turn) may give its place up too.
pub const STALLED: Duration = Duration::from_secs(20);

/// The `tracing` target of the hub's status lines, logged at info level: the radio
/// there at last and the hub listening (`hub: radio there: listening on ADDR`), the
/// radio back after an outage (`hub: radio back: listening on ADDR`). The outage itself
/// is a warning. A program that shows warnings alone shows these too with the filter
/// `warn,mcp_host::hub::status=info`, as `mcp-gs hub` does.
pub const STATUS_TARGET: &str = "mcp_host::hub::status";

/// How long the radio has to answer the hub's `AT AP`: a local AT command is answered
/// in milliseconds.
pub const MODE_CHECK_TIMEOUT: Duration = Duration::from_secs(1);

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
    /// Frames read from clients, those that fail their checksum or escapes included:
    /// each is written to the radio ([`frames_from_clients`](Self::frames_from_clients)),
    /// refused ([`frames_refused`](Self::frames_refused)) or waits its turn. Never fewer
    /// than those two together: the difference is the clients' frames waiting.
    pub frames_read_from_clients: u64,
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

/// Counts a client's frame written to the radio or refused: after its count of frames
/// read ([`Hub::stats`] loads that last, so that its snapshot never shows more frames
/// written and refused than read).
fn settled(counter: &AtomicU64) {
    counter.fetch_add(1, Ordering::Release);
}

#[derive(Debug, Default)]
struct Counters {
    listening: AtomicBool,
    clients: AtomicU64,
    frames_from_radio: AtomicU64,
    frames_from_clients: AtomicU64,
    frames_read_from_clients: AtomicU64,
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
        // A frame is counted read before it is written or refused ([`settled`]): loaded
        // last, the count of frames read takes in those of the others.
        let (frames_from_clients, frames_refused) = (
            c.frames_from_clients.load(Ordering::Acquire),
            c.frames_refused.load(Ordering::Acquire),
        );
        HubStats {
            listening: c.listening.load(Ordering::Relaxed),
            clients: c.clients.load(Ordering::Relaxed),
            frames_from_radio: c.frames_from_radio.load(Ordering::Relaxed),
            frames_from_clients,
            frames_read_from_clients: c.frames_read_from_clients.load(Ordering::Acquire),
            frames_dropped: c.frames_dropped.load(Ordering::Relaxed),
            frames_refused,
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
    /// has that too); see [`CommandSender::tap_frames`](crate::CommandSender::tap_frames).
    /// A recording of them (`mcp-gs hub --record`) is what the radio heard and said,
    /// whichever client it was for. It ends when the hub does.
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

/// Frame data encoded whole for the wire; `None` for data no frame can hold.
fn encode(data: &[u8], mode: ApiMode) -> Option<Bytes> {
    let frame = RawFrame::new(data).ok()?;
    let mut buf = BytesMut::new();
    encode_frame(&frame, mode, &mut buf).ok()?;
    Some(buf.freeze())
}
