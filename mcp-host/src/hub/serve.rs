//! The hub's main task: the radio's frames handed to every client, answers routed to
//! the client that asked, new clients accepted (one's place given up for them when
//! full), the radio's API mode checked each time it is there.

use std::net::SocketAddr;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use bytes::Bytes;
use futures::StreamExt;
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::{Semaphore, mpsc};
use tokio::time::Instant;
use tokio_util::sync::CancellationToken;
use tokio_util::task::TaskTracker;
use xbee_api::ApiMode;
use xbee_api::frame::frame_type::is_answer;

use super::client::Client;
use super::input::ClientInput;
use super::port::Port;
use super::radio_writer::ToRadio;
use super::routes::Routes;
use super::stall::Stalls;
use super::{
    ANSWER_QUEUE, CLIENT_FRAMES_TO_RADIO, CLIENT_QUEUE, Counters, MANY_ANSWER_PER_CLIENT,
    MAX_CLIENTS, MODE_CHECK_TIMEOUT, ROUTES_PER_CLIENT, STALLED, STATUS_TARGET, encode,
};
use crate::mutex::lock;
use crate::repeats::Repeats;
use crate::stats::bump;
use crate::{CommandSender, Event, LinkEvent, PacketStream};

/// A client as the hub's main task knows it.
pub(super) struct Connected {
    pub(super) peer: SocketAddr,
    /// Its queue of frames from the radio.
    pub(super) queue: mpsc::Sender<Bytes>,
    /// Ends its tasks.
    pub(super) end: CancellationToken,
    /// Since when frames have been dropped for it (its queue full) with none of its
    /// queue taken: the first frame dropped since it last took one.
    pub(super) behind: Arc<Mutex<Option<Instant>>>,
    /// Since when it has sent nothing more: its connection closed (or its sending side
    /// shut), or failed.
    pub(super) closed: Arc<Mutex<Option<Instant>>>,
    /// Since when it has written ahead of the radio: each of its frames since found its
    /// [`CLIENT_FRAMES_TO_RADIO`] places taken (see [`Client::ahead`]).
    pub(super) ahead: Arc<Mutex<Option<Instant>>>,
    /// The radio's frames dropped for it, so far.
    pub(super) dropped: Arc<AtomicU64>,
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
pub(super) struct AnswerQueue {
    pub(super) queue: mpsc::Sender<Bytes>,
    pub(super) peer: SocketAddr,
    pub(super) counters: Arc<Counters>,
    /// Answers dropped, for the warning.
    pub(super) dropped: Arc<Mutex<Repeats>>,
}

impl AnswerQueue {
    /// Queues an answer (encoded); one that finds the queue full (the client sent
    /// requests and read nothing, while the radio's frames filled its connection) is
    /// dropped, counted in [`HubStats::frames_dropped`](super::HubStats::frames_dropped)
    /// and said, the first at once, then at most one a second with the number not said.
    pub(super) fn send(&self, bytes: Bytes) {
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
pub(super) struct Serve {
    /// The hub's stalls, which the requests read after one count from.
    pub(super) stalls: Arc<Stalls>,
    /// New clients' queues of frames to the radio, for the
    /// [`RadioWriter`](super::radio_writer::RadioWriter).
    pub(super) to_radio: Arc<ToRadio>,
    pub(super) mode: ApiMode,
    pub(super) sender: CommandSender,
    pub(super) stop: CancellationToken,
    pub(super) tasks: TaskTracker,
    pub(super) counters: Arc<Counters>,
    pub(super) routes: Arc<Mutex<Routes>>,
    /// The permits of the 255 frame ids, one held by each route.
    pub(super) ids: Arc<Semaphore>,
    /// The permits of the [`SHARED_IDS`](super::SHARED_IDS), one held by each route
    /// beyond its client's first [`IDS_PER_CLIENT`](super::IDS_PER_CLIENT).
    pub(super) shared: Arc<Semaphore>,
    /// How the clients' frames are read.
    pub(super) client_input: ClientInput,
    /// Clients turned away, for the warning.
    pub(super) turned_away: Repeats,
    /// Each client's queue of encoded frames, and what ends it.
    pub(super) clients: Vec<Connected>,
    /// The number of the next client.
    pub(super) next_client: u64,
    /// Whether the link to the radio is up: clients are served only then.
    pub(super) radio_up: bool,
    /// Whether the link to the radio has been up.
    pub(super) radio_seen: bool,
    /// Where clients connect, held during an outage and listened on again after it.
    pub(super) port: Port,
    /// Failed attempts to listen again since the radio came back.
    pub(super) rebind_failures: u32,
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
    pub(super) async fn run(mut self, mut stream: PacketStream, mut listener: Option<TcpListener>) {
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
    pub(super) fn broadcast(&mut self, event: &Event) {
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
            if is_answer(frame_type) && id != 0 {
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
    pub(super) fn answer(&self, data: &[u8], id: u8) {
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
const CLIENT_KEEPALIVE: crate::keepalive::KeepAlive = crate::keepalive::KeepAlive {
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

/// Asks the radio its `AP` each time it is there, before the hub listens (no client is
/// connected then), and warns if it is another API mode than the hub's, or if the radio
/// does not answer: the hub drops what it cannot read, and its clients would hear
/// nothing, not knowing why. Holds the frame ids of the requests not answered in time
/// from clients ([`Routes::hold`]): a radio that answers late would answer a client's
/// request under the same id.
pub(super) async fn check_radio_mode(
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
    crate::keepalive::keep_alive(socket, &CLIENT_KEEPALIVE);
}

/// The next client of `listener`; never, without one.
async fn accept(listener: Option<&TcpListener>) -> std::io::Result<(TcpStream, SocketAddr)> {
    match listener {
        Some(listener) => listener.accept().await,
        None => std::future::pending().await,
    }
}

// Linux alone tells a socket's keepalive settings back.
#[cfg(all(test, target_os = "linux"))]
mod tests {
    use super::*;

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
        crate::keepalive::assert_kept_alive(&socket, &CLIENT_KEEPALIVE);
    }
}
