//! The background task that owns the transport: decodes frames into events, writes
//! frames, matches statuses, responses and reports to the requests in flight, and
//! reconnects.

mod op;
mod pending;

use std::collections::VecDeque;
use std::fmt;
use std::ops::Range;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, SystemTime};

use bytes::{Buf, Bytes, BytesMut};
use futures::StreamExt;
use tokio::io::AsyncWriteExt;
use tokio::sync::{Notify, mpsc, watch};
use tokio::time::Instant;
use tokio_util::codec::FramedRead;
use xbee_api::frame::frame_type::{answer_type, is_answer, is_from_radio};
use xbee_api::{Address64, EncodeFrame};

use crate::codec::{CodecItem, XBeeCodec, encode_frame};
use crate::diagnosis::Diagnoser;
use crate::error::{RequestError, SendError};
use crate::event::{Event, InvalidPacket, LinkEvent, LinkState, Origin, OwnedFrame, Received};
use crate::ids::IdTable;
use crate::options::LinkOptions;
use crate::record::{Direction, Record};
use crate::sender::DeliveryReport;
use crate::stats::{Counters, Stats, bump};
use crate::subscription::Subscribers;
use crate::tap::SentFrames;
use crate::transport::{Connector, Transport};

pub(crate) use self::op::{ANSWERS_HELD, Op};
use self::op::{fail_answers, refuse, refuse_closed};
pub(crate) use self::pending::ReportKey;
use self::pending::{Pending, PendingKind, Waiter};

/// Stop accepting new requests while this many bytes wait to be written.
const HIGH_WATER: usize = 16 * 1024;

/// Requests that need a frame id, taken while all 255 are in flight, wait in the order
/// they came, at most this many; beyond that no such request is taken until ids free
/// up. Requests that need no id come by a queue of their own
/// ([`crate::CommandSender`] picks it), so they still go out meanwhile.
const PARKED_MAX: usize = 64;

/// How often the link's task looks for callers that gave up on their requests while it
/// takes no new ones and requests wait for a frame id.
const PRUNE_EVERY: Duration = Duration::from_millis(100);

enum Served {
    /// Every sender and the stream are gone.
    Shutdown,
    /// A sender asked to close the link ([`CommandSender::close`](crate::CommandSender::close)).
    Closed,
    /// The transport failed.
    Failed(String),
}

/// The reason of [`LinkEvent::Closed`] after [`CommandSender::close`](crate::CommandSender::close).
const CLOSED_BY_APPLICATION: &str = "closed by the application";

enum Stop {
    Shutdown,
    Fatal(String),
}

pub(crate) struct Driver {
    pub(crate) connector: Connector,
    pub(crate) options: LinkOptions,
    pub(crate) ops: mpsc::Receiver<Op>,
    /// Requests that need no frame id (raw writes, transmits without status).
    pub(crate) writes: mpsc::Receiver<Op>,
    /// Closed once every handle that can send (a sender, a sink) is dropped: seen even
    /// while no request is taken (writes backed up), where `ops` and `writes` are not
    /// polled.
    alive: mpsc::Receiver<()>,
    /// Whether a handle that can send is left ([`Self::alive`] not closed yet): every
    /// [`crate::CommandSender`] and sink holds `alive` as well as `ops` or `writes`, so
    /// this alone says whether one is left.
    handles_alive: bool,
    pub(crate) events: mpsc::Sender<Event>,
    /// The [`Subscription`](crate::Subscription)s: every event goes there too.
    subscribers: EndSubscriptions,
    pub(crate) counters: Arc<Counters>,
    /// Asked by [`CommandSender::close`](crate::CommandSender::close).
    close_requested: Arc<CloseRequest>,
    /// The link's state, for the handles to read at any time.
    state: watch::Sender<LinkState>,
    ops_open: bool,
    writes_open: bool,
    ids: IdTable<Pending>,
    /// Bytes written to the transports so far: where the bytes queued for the current
    /// one start ([`Pending::bytes`]).
    written: u64,
    /// Requests that need a frame id, taken while none was free.
    parked: VecDeque<Op>,
    waiters: Vec<Waiter>,
    next_waiter: u64,
    healthy: bool,
    /// The counters of the transport being served, as they grow, and whether they
    /// were warned about ([`Self::watch_decoding`]).
    diagnoser: Diagnoser,
    warned: bool,
    /// Link events that found the event queue full, delivered (in order, before any
    /// other event) as soon as it has room: a slow consumer loses packets, never link
    /// state.
    pending_links: VecDeque<Event>,
}

/// Link events held back for a full event queue, at most: a consumer that has not read
/// for this many connects and disconnects loses the oldest ones.
const PENDING_LINKS_MAX: usize = 64;

/// [`CommandSender::close`](crate::CommandSender::close)'s request, shared by the
/// link's handles and its task: the handles refuse what comes after it at once (it may
/// come before the task has seen the request), and the task is woken to close.
#[derive(Debug, Default)]
pub(crate) struct CloseRequest {
    asked: AtomicBool,
    notify: Notify,
}

impl CloseRequest {
    /// Asks the link to close.
    pub(crate) fn ask(&self) {
        self.asked.store(true, Ordering::Release);
        self.notify.notify_one();
    }

    /// Whether the link was asked to close.
    pub(crate) fn asked(&self) -> bool {
        self.asked.load(Ordering::Acquire)
    }

    /// Resolves once the link was asked to close (at once if it was before).
    fn notified(&self) -> tokio::sync::futures::Notified<'_> {
        self.notify.notified()
    }
}

/// How long closing a link may take to write out the frames already queued.
const CLOSE_FLUSH: Duration = Duration::from_secs(1);

impl Driver {
    pub(crate) fn new(
        connector: Connector,
        options: LinkOptions,
        // Requests that need a frame id, and those that need none.
        (ops, writes, alive): (mpsc::Receiver<Op>, mpsc::Receiver<Op>, mpsc::Receiver<()>),
        (events, subscribers): (mpsc::Sender<Event>, Arc<Subscribers>),
        counters: Arc<Counters>,
        close_requested: Arc<CloseRequest>,
        state: watch::Sender<LinkState>,
    ) -> Self {
        let api_mode = options.api_mode;
        Driver {
            connector,
            options,
            ops,
            writes,
            alive,
            handles_alive: true,
            events,
            subscribers: EndSubscriptions(subscribers),
            counters,
            close_requested,
            state,
            ops_open: true,
            writes_open: true,
            ids: IdTable::new(),
            written: 0,
            parked: VecDeque::new(),
            waiters: Vec::new(),
            next_waiter: 0,
            healthy: false,
            // Started afresh by each transport served.
            diagnoser: Diagnoser::new(api_mode, Stats::default()),
            warned: false,
            pending_links: VecDeque::new(),
        }
    }

    /// Runs until the link ends for good or nobody holds a sender or the stream. `tried`:
    /// `connect` tried the first open already (and it failed), so the next waits the
    /// reconnection delay.
    pub(crate) async fn run(mut self, mut transport: Option<Transport>, mut tried: bool) {
        let mut ever_connected = false;
        let mut last_failure = None;
        loop {
            let current = match transport.take() {
                Some(t) => t,
                None => match self
                    .wait_for_transport(
                        ever_connected,
                        std::mem::take(&mut tried),
                        last_failure.as_deref(),
                    )
                    .await
                {
                    Ok(t) => t,
                    Err(Stop::Shutdown) => return self.shut_down(),
                    Err(Stop::Fatal(reason)) => {
                        self.close(reason).await;
                        return;
                    }
                },
            };
            let peer = current.peer().to_owned();
            self.state.send_replace(LinkState::Connected);
            if ever_connected {
                bump(&self.counters.reconnects);
                tracing::info!(%peer, "reconnected");
                self.emit(Event::Link(LinkEvent::Reconnected { peer }));
            } else {
                tracing::info!(%peer, "connected");
                self.emit(Event::Link(LinkEvent::Connected { peer }));
            }
            ever_connected = true;
            match self.serve(current).await {
                Served::Shutdown => return self.shut_down(),
                // The transport is closed by now (`serve` owned it): say so last.
                Served::Closed => {
                    self.close(CLOSED_BY_APPLICATION.to_owned()).await;
                    return;
                }
                Served::Failed(reason) => {
                    self.state.send_replace(LinkState::Reconnecting);
                    bump(&self.counters.disconnects);
                    // Reported by `LinkEvent::Disconnected`; the log only traces it.
                    tracing::info!(%reason, "disconnected");
                    self.emit(Event::Link(LinkEvent::Disconnected {
                        reason: reason.clone(),
                    }));
                    self.fail_all(&reason);
                    if !self.options.reconnect.enabled {
                        self.close(format!("{reason}; reconnection is disabled"))
                            .await;
                        return;
                    }
                    last_failure = Some(reason);
                }
            }
        }
    }

    /// Waits for a transport while failing requests at once (saying why the link went
    /// down, `last_failure`, when it was up before).
    async fn wait_for_transport(
        &mut self,
        ever_connected: bool,
        tried: bool,
        last_failure: Option<&str>,
    ) -> Result<Transport, Stop> {
        // A tcp-listen link on port 0 is named by the port it got, a pty by the path of
        // its far end, which nothing has opened yet.
        let link = match (self.connector.link(), self.connector.local_addr()) {
            (crate::Link::TcpListen { .. }, Some(addr)) => {
                crate::Link::tcp_listen(addr.ip().to_string(), addr.port()).to_string()
            }
            (crate::Link::Pty, _) => match self.connector.pty_path() {
                Some(path) => format!(
                    "pty (its far end {}, which no program has open)",
                    path.display()
                ),
                None => "pty".to_owned(),
            },
            (link, _) => link.to_string(),
        };
        let down = if ever_connected {
            match last_failure {
                Some(reason) => format!("{reason}; reconnecting to {link}"),
                None => format!("reconnecting to {link}"),
            }
        } else {
            format!("not connected yet to {link}")
        };
        let policy = self.options.reconnect;
        let connector = &mut self.connector;
        let opening = async move {
            if !ever_connected && !tried {
                match connector.open().await {
                    Ok(t) => return Ok(t),
                    Err(e) if !e.is_retryable() => return Err(e),
                    Err(e) => tracing::warn!(error = %e, "opening the link failed"),
                }
            }
            connector.reopen(&policy).await
        };
        tokio::pin!(opening);
        loop {
            tokio::select! {
                result = &mut opening => {
                    return result.map_err(|e| Stop::Fatal(e.to_string()));
                }
                op = self.ops.recv(), if self.ops_open => match op {
                    Some(op) => refuse(op, &down),
                    None => self.ops_open = false,
                },
                op = self.writes.recv(), if self.writes_open => match op {
                    Some(op) => refuse(op, &down),
                    None => self.writes_open = false,
                },
                // In an async block, so that the sender is cloned only while link events
                // wait, not on every turn of the loop.
                permit = async { self.events.clone().reserve_owned().await }, if !self.pending_links.is_empty() => {
                    deliver_pending_link(&mut self.pending_links, permit);
                }
                None = self.alive.recv(), if self.handles_alive => self.handles_alive = false,
                _ = self.events.closed(), if !self.handles_alive => return Err(Stop::Shutdown),
                () = self.close_requested.notified() => {
                    return Err(Stop::Fatal(CLOSED_BY_APPLICATION.to_owned()));
                }
            }
        }
    }

    /// Serves one transport until it fails.
    async fn serve(&mut self, transport: Transport) -> Served {
        let (rd, mut wr) = tokio::io::split(transport);
        let codec = XBeeCodec::with_counters(
            self.options.api_mode,
            self.options.max_frame_len,
            self.counters.clone(),
        );
        let mut reader = FramedRead::new(rd, codec);
        let mut out = BytesMut::new();
        let mut sent = SentFrames::new(self.options.api_mode);
        self.healthy = false;
        self.diagnoser = Diagnoser::new(self.options.api_mode, self.counters.snapshot());
        self.warned = false;
        let mut prune = tokio::time::interval(PRUNE_EVERY);
        prune.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
        loop {
            self.unpark(&mut out);
            let deadline = self.next_deadline();
            let accept_ops =
                self.ops_open && self.parked.len() < PARKED_MAX && out.len() < HIGH_WATER;
            let accept_writes = self.writes_open && out.len() < HIGH_WATER;
            // API mode 1: a partial frame is given up after a quiet spell (see
            // `LinkOptions::partial_frame_timeout`).
            let stale_after = self.options.partial_frame_timeout;
            let check_stale_at = reader.decoder().stale_check_at(stale_after);
            tokio::select! {
                item = reader.next() => if let Some(failed) = self.on_read(item) {
                    return failed;
                },
                written = wr.write(&out), if !out.is_empty() => match written {
                    Ok(0) => return Served::Failed("the transport accepts no more data".into()),
                    Ok(n) => {
                        // An `AsyncWrite` writes no more than it was given.
                        let n = n.min(out.len());
                        sent.written(&out[..n], &self.subscribers.0);
                        out.advance(n);
                        self.written += n as u64;
                    }
                    Err(e) => return Served::Failed(format!("write error: {e}")),
                },
                op = self.ops.recv(), if accept_ops => match op {
                    Some(op) => self.start(op, &mut out),
                    None => self.ops_open = false,
                },
                op = self.writes.recv(), if accept_writes => match op {
                    Some(op) => self.start(op, &mut out),
                    None => self.writes_open = false,
                },
                _ = tokio::time::sleep_until(deadline.unwrap_or_else(Instant::now)), if deadline.is_some() => {
                    self.expire(Instant::now(), &mut out);
                }
                // No request taken (parked ones fill their queue, or writes are backed
                // up) while some wait for a frame id: the next turn looks for callers
                // that gave up (`unpark`), now and then, nothing else waking this task.
                _ = prune.tick(), if !accept_ops && !self.parked.is_empty() => {}
                _ = tokio::time::sleep_until(check_stale_at.unwrap_or_else(Instant::now)), if check_stale_at.is_some() => {
                    // Bytes may be waiting unread (this task ran late): they come first,
                    // and the next turn looks again.
                    match futures::FutureExt::now_or_never(reader.next()) {
                        Some(item) => if let Some(failed) = self.on_read(item) {
                            return failed;
                        },
                        // Unless bytes came in meanwhile (the next turn waits again).
                        None => if reader.decoder().is_stale(stale_after, Instant::now()) {
                            for item in reader.decoder_mut().drop_partial() {
                                self.handle_item(item);
                            }
                        },
                    }
                }
                // In an async block, so that the sender is cloned only while link events
                // wait, not on every turn of the loop.
                permit = async { self.events.clone().reserve_owned().await }, if !self.pending_links.is_empty() => {
                    deliver_pending_link(&mut self.pending_links, permit);
                }
                // The last handle that can send gone, seen even while writes are backed up
                // and no request is taken.
                None = self.alive.recv(), if self.handles_alive => self.handles_alive = false,
                _ = self.events.closed(), if !self.handles_alive => {
                    self.flush_before_end(&mut wr, &mut out, &mut sent).await;
                    return Served::Shutdown;
                }
                () = self.close_requested.notified() => {
                    self.flush_before_end(&mut wr, &mut out, &mut sent).await;
                    return Served::Closed;
                }
            }
        }
    }

    /// What the transport's reader gave: handled, or how serving the transport ends.
    fn on_read(&mut self, item: Option<std::io::Result<CodecItem>>) -> Option<Served> {
        match item {
            Some(Ok(item)) => {
                self.handle_item(item);
                None
            }
            Some(Err(e)) => Some(Served::Failed(format!("read error: {e}"))),
            None => Some(Served::Failed(
                "end of stream (peer closed or device gone)".into(),
            )),
        }
    }

    /// Writes out what was already reported written (`Written` transmits, raw writes)
    /// and what waits in the queue of requests without a frame id (a
    /// [`PacketSink`](crate::PacketSink)'s packets, which were handed over), before the
    /// link ends, within [`CLOSE_FLUSH`]. A tap of the frames is given them as they are
    /// handed to the transport.
    async fn flush_before_end(
        &mut self,
        wr: &mut (impl tokio::io::AsyncWrite + Unpin),
        out: &mut BytesMut,
        sent: &mut SentFrames,
    ) {
        while let Ok(op) = self.writes.try_recv() {
            self.start(op, out);
        }
        sent.written(out, &self.subscribers.0);
        let flush = async {
            wr.write_all_buf(out).await?;
            wr.flush().await
        };
        if let Err(error) = tokio::time::timeout(CLOSE_FLUSH, flush)
            .await
            .unwrap_or_else(|_| Err(std::io::ErrorKind::TimedOut.into()))
        {
            tracing::warn!(%error, "closing: queued frames not all written");
        }
    }

    /// Queues `event` for the stream. When the queue is full, a link event is held back
    /// and delivered once there is room; any other event is dropped and counted (as is
    /// every event while link events are held back, so that none overtakes them).
    fn emit(&mut self, event: Event) {
        self.publish(&event);
        let event = if self.pending_links.is_empty() {
            match self.events.try_send(event) {
                Ok(()) | Err(mpsc::error::TrySendError::Closed(_)) => return,
                Err(mpsc::error::TrySendError::Full(event)) => event,
            }
        } else {
            event
        };
        if matches!(event, Event::Link(_)) {
            if self.pending_links.len() == PENDING_LINKS_MAX {
                self.pending_links.pop_front();
                bump(&self.counters.events_dropped);
            }
            self.pending_links.push_back(event);
        } else {
            bump(&self.counters.events_dropped);
            tracing::debug!(?event, "event queue full, event dropped");
        }
    }

    /// Hands `event` to the subscriptions, if there are any.
    fn publish(&self, event: &Event) {
        self.subscribers.0.publish(event);
    }

    /// Nobody holds the stream or a sender any more: the link ends, and the
    /// subscriptions with it, told why. The answers of a request still gathered (an
    /// [`Answers`](crate::Answers) stream outlives the sender that made it) end with
    /// [`SendError::Closed`], not as a window that ran out.
    fn shut_down(&self) {
        for pending in self.ids.values() {
            if let PendingKind::Answers { answers, .. } = &pending.kind {
                fail_answers(answers, SendError::Closed);
            }
        }
        self.subscribers.0.end(Some(&Event::Link(LinkEvent::Closed {
            reason: DROPPED.to_owned(),
        })));
    }

    fn handle_item(&mut self, item: CodecItem) {
        match item {
            CodecItem::Error(error) => {
                // The event is how it is reported; the log only traces it.
                tracing::debug!(%error, "dropped a corrupt frame");
                self.emit(Event::DecodeError(error));
                self.watch_decoding();
            }
            CodecItem::Frame(frame) => {
                if !self.healthy {
                    self.healthy = true;
                    self.connector.mark_healthy();
                }
                self.subscribers.0.publish_frame(|| Record {
                    time: SystemTime::now(),
                    direction: Direction::Received,
                    frame: frame.data().to_vec(),
                });
                self.dispatch(frame);
            }
        }
    }

    /// Warns, once a connection, when what failed to decode on it says that the radio's
    /// settings differ from the link's ([`Diagnoser`]): nothing else would
    /// tell, as its frames are dropped. Looked at when a frame fails to decode and when
    /// a request times out (bytes that begin no frame, as from a radio in transparent
    /// mode, make no event of their own).
    fn watch_decoding(&mut self) {
        if self.warned {
            return;
        }
        if let Some(diagnosis) = self.diagnoser.look(self.counters.snapshot()) {
            self.warned = true;
            tracing::warn!(
                target: "mcp_host::diagnosis",
                link = %self.connector.link(),
                "what the radio sends is dropped: {diagnosis}"
            );
        }
    }

    fn dispatch(&mut self, frame: OwnedFrame) {
        let received_at = SystemTime::now();
        let data = frame.data().clone();
        match frame.frame_type() {
            0x90 => match xbee_api::ReceivePacketRepr::parse_bytes(&data) {
                Ok(rx) => {
                    let origin = Origin {
                        src64: rx.src64,
                        src16: rx.src16,
                        options: rx.options,
                        received_at,
                    };
                    let payload = data.slice_ref(rx.data);
                    self.on_payload(origin, payload, data.clone());
                }
                Err(error) => self.malformed(frame, &error),
            },
            0x91 => match xbee_api::ExplicitRxIndicatorRepr::parse_bytes(&data) {
                Ok(rx) => {
                    let origin = Origin {
                        src64: rx.src64,
                        src16: rx.src16,
                        options: rx.options,
                        received_at,
                    };
                    let payload = data.slice_ref(rx.data);
                    self.on_payload(origin, payload, data.clone());
                }
                Err(error) => self.malformed(frame, &error),
            },
            t if is_answer(t) => self.on_response(frame),
            t => {
                // A request's type, which a radio takes but never sends: an echo.
                if !is_from_radio(t) {
                    bump(&self.counters.echoed);
                }
                self.emit(Event::Frame(frame));
            }
        }
    }

    fn malformed(&mut self, frame: OwnedFrame, error: &dyn fmt::Display) {
        bump(&self.counters.malformed_frames);
        // Reported by the event and counted: a peer that sends many must not flood the
        // log.
        tracing::debug!(?frame, %error, "malformed frame");
        self.emit(Event::Frame(frame));
    }

    /// An MCP payload that came in `frame` (frame data, type byte first).
    fn on_payload(&mut self, origin: Origin, payload: Bytes, frame: Bytes) {
        match mcp_core::parse(&payload) {
            Ok(packet) => {
                let packet = packet.map_bytes(|s| payload.slice_ref(s));
                let report = match &packet {
                    mcp_core::Packet::Report(report) => Some(report.clone()),
                    _ => None,
                };
                self.emit(Event::Packet(Received {
                    origin,
                    packet,
                    payload,
                    frame,
                }));
                // After the event: a subscription taken once the request has its report
                // starts after that report, as it does after anything else it saw.
                if let Some(report) = report {
                    self.resolve_waiters(origin.src64, &report);
                }
            }
            Err(error) => {
                bump(&self.counters.invalid_packets);
                tracing::debug!(src64 = %origin.src64, %error, "invalid MCP packet");
                self.emit(Event::InvalidPacket(InvalidPacket {
                    origin,
                    error,
                    payload,
                    frame,
                }));
            }
        }
    }

    fn resolve_waiters(&mut self, src: Address64, report: &mcp_core::Report<Bytes>) {
        let key = ReportKey::of_report(report);
        let mut i = 0;
        while i < self.waiters.len() {
            let w = &self.waiters[i];
            if w.key == key && (w.from == src || w.from == Address64::BROADCAST) {
                let w = self.waiters.swap_remove(i);
                let _ = w.reply.send(Ok(report.clone()));
            } else {
                i += 1;
            }
        }
    }

    fn on_response(&mut self, frame: OwnedFrame) {
        let frame_type = frame.frame_type();
        let Some(id) = frame.frame_id().filter(|id| *id != 0) else {
            return self.unclaimed(frame);
        };
        let claims = match self.ids.get(id).map(|p| &p.kind) {
            Some(PendingKind::Answers {
                answers,
                answer_type,
                ..
            }) if *answer_type == frame_type => {
                if answers.is_closed() {
                    // Its caller stopped listening: the id waits for the last answers.
                    if let Some(pending) = self.ids.get_mut(id) {
                        if let Some(expired) = pending.expired(Instant::now()) {
                            *pending = expired;
                        }
                    }
                    return self.unclaimed(frame);
                }
                if answers.capacity() > 1 {
                    let _ = answers.try_send(Ok(frame));
                } else if let Some(PendingKind::Answers { dropped, .. }) =
                    self.ids.get_mut(id).map(|p| &mut p.kind)
                {
                    // Said once a request, and counted: answers that come faster than
                    // their caller takes them would make a line each.
                    *dropped += 1;
                    if *dropped == 1 {
                        tracing::warn!(
                            frame_id = id,
                            "an answer was dropped: {ANSWERS_HELD} answers wait for their \
                             caller (more are counted, and said when its window ends)"
                        );
                    }
                }
                return;
            }
            // Another type under its id is no answer of its.
            Some(PendingKind::Answers { .. }) => false,
            // A late answer: no caller waits for it any more.
            Some(PendingKind::Expired {
                answer_type,
                single,
            }) => {
                if *single && answer_type.is_none_or(|t| t == frame_type) {
                    self.ids.remove(id);
                }
                return self.unclaimed(frame);
            }
            Some(PendingKind::Frame { answer_type, .. }) => {
                answer_type.is_none_or(|t| t == frame_type)
            }
            Some(PendingKind::Transmit { .. } | PendingKind::Request { .. }) => frame_type == 0x8B,
            None => false,
        };
        if !claims {
            return self.unclaimed(frame);
        }
        let Some(pending) = self.ids.remove(id) else {
            return self.unclaimed(frame);
        };
        match pending.kind {
            PendingKind::Frame { reply, .. } => {
                let _ = reply.send(Ok(frame));
            }
            // Taken above.
            PendingKind::Answers { .. } | PendingKind::Expired { .. } => {}
            PendingKind::Transmit { to, reply } => {
                let result = match xbee_api::TransmitStatusRepr::parse_bytes(frame.data()) {
                    Ok(status) => delivery(to, &status),
                    Err(error) => {
                        self.malformed(frame, &error);
                        // The id answered, but its status is unreadable.
                        Err(SendError::Timeout {
                            frame_id: Some(id),
                            timeout: pending.timeout,
                            heard: true,
                        })
                    }
                };
                let _ = reply.send(result);
            }
            PendingKind::Request { to, waiter } => {
                match xbee_api::TransmitStatusRepr::parse_bytes(frame.data()) {
                    Ok(status) => {
                        let pos = self.waiters.iter().position(|w| w.id == waiter);
                        match (delivery(to, &status), pos) {
                            (Ok(_), Some(pos)) => self.waiters[pos].delivered = true,
                            (Err(error), Some(pos)) => {
                                let w = self.waiters.swap_remove(pos);
                                let _ = w.reply.send(Err(error.into()));
                            }
                            (_, None) => {}
                        }
                    }
                    Err(error) => self.malformed(frame, &error),
                }
            }
        }
    }

    fn unclaimed(&mut self, frame: OwnedFrame) {
        bump(&self.counters.unclaimed_responses);
        self.emit(Event::Frame(frame));
    }

    /// Takes a request: starts it, or parks it when it needs a frame id and none is free
    /// (or requests parked before it still wait). Requests that need no id (raw writes,
    /// transmits without status) start at once even while all ids are in flight.
    fn start(&mut self, op: Op, out: &mut BytesMut) {
        if op.needs_id() && !self.ids.has_free() {
            self.reclaim_abandoned(out);
        }
        if op.needs_id() && (!self.ids.has_free() || !self.parked.is_empty()) {
            self.parked.push_back(op);
            return;
        }
        self.begin(op, out, false);
    }

    /// Frees the frame ids of requests whose callers stopped waiting (a `send` in a
    /// `tokio::time::timeout`, say), when no id is free: without this they would hold
    /// them to their own deadlines. A frame not sent yet is taken back; the id of one
    /// sent is kept for its late answer, which comes as an unclaimed frame
    /// ([`Pending::expired`]).
    fn reclaim_abandoned(&mut self, out: &mut BytesMut) {
        let waiters = &self.waiters;
        let (written, now) = (self.written, Instant::now());
        let mut gone = Vec::new();
        let mut cut = Vec::new();
        self.ids.replace_where(
            |p| match &p.kind {
                PendingKind::Transmit { reply, .. } => reply.is_closed(),
                PendingKind::Frame { reply, .. } => reply.is_closed(),
                PendingKind::Answers { answers, .. } => answers.is_closed(),
                PendingKind::Request { waiter, .. } => waiters
                    .iter()
                    .find(|w| w.id == *waiter)
                    .is_none_or(|w| w.reply.is_closed()),
                PendingKind::Expired { .. } => false,
            },
            |_, p| {
                if let PendingKind::Request { waiter, .. } = p.kind {
                    gone.push(waiter);
                }
                if p.unsent(written) {
                    cut.push(p.bytes.clone());
                    return None;
                }
                p.expired(now)
            },
        );
        self.waiters.retain(|w| !gone.contains(&w.id));
        self.take_back(out, cut);
    }

    /// Takes the frames at `cut` (none of them sent) out of the bytes queued, `out`,
    /// and moves the frames queued after them back.
    fn take_back(&mut self, out: &mut BytesMut, mut cut: Vec<Range<u64>>) {
        if cut.is_empty() {
            return;
        }
        // From the last, so that the places of the others stay as they are.
        cut.sort_unstable_by_key(|r| std::cmp::Reverse(r.start));
        let place = |at: u64| {
            at.checked_sub(self.written)
                .and_then(|n| usize::try_from(n).ok())
                .unwrap_or(usize::MAX)
        };
        for range in &cut {
            let (start, end) = (place(range.start), place(range.end));
            if start <= end && end <= out.len() {
                let mut rest = out.split_off(start);
                let after = rest.split_off(end - start);
                out.unsplit(after);
            }
        }
        for p in self.ids.values_mut() {
            let before: u64 = cut
                .iter()
                .filter(|r| r.end <= p.bytes.start)
                .map(|r| r.end - r.start)
                .sum();
            p.bytes = p.bytes.start - before..p.bytes.end - before;
        }
    }

    /// Starts parked requests, in order, while frame ids are free. While none is, the
    /// parked requests whose callers gave up are dropped, and the ids of those in
    /// flight taken back ([`Self::reclaim_abandoned`]): at every turn, so that their
    /// frames not yet written are not (the transport may take them any moment).
    fn unpark(&mut self, out: &mut BytesMut) {
        if !self.parked.is_empty() && !self.ids.has_free() {
            self.parked.retain(|op| !op.caller_gone());
            self.reclaim_abandoned(out);
        }
        while self.ids.has_free() {
            let Some(op) = self.parked.pop_front() else {
                return;
            };
            self.begin(op, out, true);
        }
    }

    /// Starts a request: allocates a frame id where needed and queues its frame. A
    /// request whose caller is gone is dropped; one whose deadline has passed already is
    /// answered with its timeout error (`parked`: it waited for a frame id).
    fn begin(&mut self, op: Op, out: &mut BytesMut, parked: bool) {
        if op.caller_gone() {
            return;
        }
        if op.deadline().is_some_and(|d| d <= Instant::now()) {
            if op.time_out(parked) {
                bump(&self.counters.timeouts);
            }
            return;
        }
        match op {
            Op::Transmit {
                to,
                payload,
                with_status,
                deadline,
                timeout,
                reply,
            } => {
                if !with_status {
                    let result = write_transmit(self.options.api_mode, out, 0, to, &payload)
                        .map(|()| DeliveryReport::Written);
                    let _ = reply.send(result);
                    return;
                }
                let pending = Pending::new(deadline, timeout, PendingKind::Transmit { to, reply });
                match self.ids.insert(pending) {
                    Ok(id) => {
                        let start = self.queued_end(out);
                        match write_transmit(self.options.api_mode, out, id, to, &payload) {
                            Ok(()) => self.queued(id, start, out),
                            Err(e) => {
                                if let Some(pending) = self.ids.remove(id) {
                                    pending.kind.fail(e);
                                }
                            }
                        }
                    }
                    Err(pending) => {
                        if let PendingKind::Transmit { reply, .. } = pending.kind {
                            // Not sent: taken only while an id is free, so never here.
                            let _ = reply.send(Err(SendError::NoFreeFrameId { timeout }));
                        }
                    }
                }
            }
            Op::Request {
                to,
                payload,
                request,
                deadline,
                timeout,
                reply,
            } => {
                let waiter = self.next_waiter;
                self.next_waiter += 1;
                let pending = Pending::new(deadline, timeout, PendingKind::Request { to, waiter });
                // Without a free id (cannot happen: requests that need one are parked
                // until one is free) the request still goes out, without a delivery status.
                let id = self.ids.insert(pending).unwrap_or(0);
                let start = self.queued_end(out);
                if let Err(e) = write_transmit(self.options.api_mode, out, id, to, &payload) {
                    self.ids.remove(id);
                    let _ = reply.send(Err(e.into()));
                    return;
                }
                self.queued(id, start, out);
                // Those whose callers stopped waiting go now, not at their deadlines: a
                // caller that gives up early and asks again must not grow the list.
                self.waiters.retain(|w| !w.reply.is_closed());
                self.waiters.push(Waiter {
                    id: waiter,
                    from: to,
                    request,
                    key: ReportKey::of_request(&request),
                    deadline,
                    timeout,
                    delivered: false,
                    undecodable_before: self.counters.snapshot().decode_errors(),
                    reply,
                });
            }
            Op::Frame {
                data,
                deadline,
                timeout,
                reply,
            } => {
                let answer_type = data.first().and_then(|&t| answer_type(t));
                let kind = PendingKind::Frame { reply, answer_type };
                self.write_under_id(out, &data, deadline, timeout, kind);
            }
            Op::Write { data, reply, .. } => {
                let _ = reply.send(write_raw(self.options.api_mode, out, &data));
            }
            Op::Answers {
                data,
                deadline,
                timeout,
                answers,
            } => {
                // Its answers are of the type that answers its request (0x88 for AT
                // commands, the only requests queued as `Op::Answers` but remote ones).
                let answer_type = data
                    .first()
                    .and_then(|&t| answer_type(t))
                    .unwrap_or(xbee_api::frame::frame_type::AT_COMMAND_RESPONSE);
                let kind = PendingKind::Answers {
                    answers,
                    answer_type,
                    dropped: 0,
                };
                self.write_under_id(out, &data, deadline, timeout, kind);
            }
        }
    }

    /// Where the bytes queued for the transport, `out`, end ([`Pending::bytes`]).
    fn queued_end(&self, out: &BytesMut) -> u64 {
        self.written + out.len() as u64
    }

    /// Notes where the frame of the request under `id` lies: from `start` to the end of
    /// `out`.
    fn queued(&mut self, id: u8, start: u64, out: &BytesMut) {
        let end = self.queued_end(out);
        if let Some(pending) = self.ids.get_mut(id) {
            pending.bytes = start..end;
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        let ids = self.ids.values().map(|p| p.deadline);
        let waiters = self.waiters.iter().map(|w| w.deadline);
        let parked = self.parked.iter().filter_map(Op::deadline);
        ids.chain(waiters).chain(parked).min()
    }

    /// Fails every request whose deadline has passed, and every parked one whose
    /// deadline has passed. A frame not sent yet is taken back (the request was
    /// [`NotSent`](SendError::NotSent)); the id of one sent is kept for its late answer
    /// ([`Pending::expired`]), and freed once that time is over too.
    fn expire(&mut self, now: Instant, out: &mut BytesMut) {
        let timeouts = self.counters.snapshot().timeouts;
        let (expired, parked): (VecDeque<Op>, VecDeque<Op>) = std::mem::take(&mut self.parked)
            .into_iter()
            .partition(|op| op.deadline().is_some_and(|d| d <= now));
        self.parked = parked;
        for op in expired {
            if op.time_out(true) {
                bump(&self.counters.timeouts);
            }
        }
        let counters = &self.counters;
        let written = self.written;
        let heard = self.healthy;
        let mut cut = Vec::new();
        let mut unsent_waiters = Vec::new();
        self.ids.replace_where(
            |p| p.deadline <= now,
            |id, p| {
                let unsent = p.unsent(written);
                let error = if unsent {
                    cut.push(p.bytes.clone());
                    SendError::NotSent { timeout: p.timeout }
                } else {
                    SendError::Timeout {
                        frame_id: Some(id),
                        timeout: p.timeout,
                        heard,
                    }
                };
                let kept = if unsent { None } else { p.expired(now) };
                match p.kind {
                    PendingKind::Transmit { reply, .. } => {
                        if reply.send(Err(error)).is_ok() {
                            bump(&counters.timeouts);
                        }
                    }
                    PendingKind::Frame { reply, .. } => {
                        if reply.send(Err(error)).is_ok() {
                            bump(&counters.timeouts);
                        }
                    }
                    // Its window is over: dropping the sender ends the answers; a
                    // request that never went out says so.
                    PendingKind::Answers {
                        answers, dropped, ..
                    } => {
                        if unsent {
                            fail_answers(&answers, error);
                        }
                        if dropped > 1 {
                            tracing::warn!(
                                frame_id = id,
                                "{dropped} answers were dropped in all: {ANSWERS_HELD} \
                                 answers waited for their caller"
                            );
                        }
                    }
                    // The report waiter has the same deadline and answers below (at
                    // once if its request never went out).
                    PendingKind::Request { waiter, .. } => {
                        if unsent {
                            unsent_waiters.push((waiter, error));
                        }
                    }
                    PendingKind::Expired { .. } => {}
                }
                kept
            },
        );
        self.take_back(out, cut);
        for (waiter, error) in unsent_waiters {
            if let Some(pos) = self.waiters.iter().position(|w| w.id == waiter) {
                let w = self.waiters.swap_remove(pos);
                if w.reply.send(Err(error.into())).is_ok() {
                    bump(&self.counters.timeouts);
                }
            }
        }
        let mut i = 0;
        while i < self.waiters.len() {
            if self.waiters[i].deadline <= now {
                let w = self.waiters.swap_remove(i);
                let undecodable = self.counters.snapshot().decode_errors();
                let told = w.reply.send(Err(RequestError::Timeout {
                    from: w.from,
                    request: w.request,
                    timeout: w.timeout,
                    delivered: w.delivered,
                    undecodable: undecodable.saturating_sub(w.undecodable_before),
                    heard: self.healthy,
                }));
                if told.is_ok() {
                    bump(&self.counters.timeouts);
                }
            } else {
                i += 1;
            }
        }
        // A radio that cannot answer: its counters may say why.
        if self.counters.snapshot().timeouts > timeouts {
            self.watch_decoding();
        }
    }

    /// Takes a frame id for a request that awaits its answers as `kind`, and writes its
    /// frame `data` under it; the request fails if the write does, or if no id is free.
    fn write_under_id(
        &mut self,
        out: &mut BytesMut,
        data: &[u8],
        deadline: Instant,
        timeout: Duration,
        kind: PendingKind,
    ) {
        match self.ids.insert(Pending::new(deadline, timeout, kind)) {
            Ok(id) => {
                let mut data = BytesMut::from(data);
                if let Some(slot) = data.get_mut(1) {
                    *slot = id;
                }
                let start = self.queued_end(out);
                match write_raw(self.options.api_mode, out, &data) {
                    Ok(()) => self.queued(id, start, out),
                    Err(e) => {
                        if let Some(pending) = self.ids.remove(id) {
                            pending.kind.fail(e);
                        }
                    }
                }
            }
            // Not sent: taken only while an id is free, so never here.
            Err(pending) => pending.kind.fail(SendError::NoFreeFrameId { timeout }),
        }
    }

    /// Fails every request in flight after a disconnection.
    fn fail_all(&mut self, reason: &str) {
        let error = SendError::Disconnected {
            reason: reason.to_owned(),
        };
        // A frame that went out may still be answered once the link is back (a radio
        // behind a serial bridge, or on a port, stays up): its id is kept for that as
        // after a timeout. One that never went out frees its id.
        let (written, now) = (self.written, Instant::now());
        self.ids.replace_where(
            |_| true,
            |_, p| {
                if matches!(p.kind, PendingKind::Expired { .. }) {
                    return Some(p);
                }
                let kept = if p.bytes.is_empty() || p.unsent(written) {
                    None
                } else {
                    p.expired(now)
                };
                p.kind.fail(error.clone());
                kept
            },
        );
        for w in self.waiters.drain(..) {
            let _ = w.reply.send(Err(error.clone().into()));
        }
        for op in self.parked.drain(..) {
            refuse(op, reason);
        }
    }

    /// Ends the link for good: fails what is in flight, refuses what comes, then
    /// delivers the held-back link events and [`LinkEvent::Closed`], waiting for room
    /// in the event queue (until the stream is dropped) so that the stream always ends
    /// with it.
    async fn close(&mut self, reason: String) {
        // The transport is closed by now; a `tcp-listen` port is freed before anyone
        // waiting on the state hears of it.
        self.connector.shutdown().await;
        self.state.send_replace(LinkState::Closed);
        // The stream ends with `LinkEvent::Closed`, which says why: the log only traces
        // it.
        if reason == CLOSED_BY_APPLICATION {
            tracing::debug!(%reason, "link closed");
        } else {
            tracing::info!(%reason, "link closed");
        }
        self.fail_all(&reason);
        self.ops.close();
        self.writes.close();
        while let Ok(op) = self.ops.try_recv().or_else(|_| self.writes.try_recv()) {
            refuse_closed(op);
        }
        // The subscriptions end with it now, whether the stream is read or not.
        let closed = Event::Link(LinkEvent::Closed { reason });
        self.subscribers.0.end(Some(&closed));
        let held = std::mem::take(&mut self.pending_links);
        for event in held.into_iter().chain([closed]) {
            if self.events.send(event).await.is_err() {
                return;
            }
        }
    }
}

/// Why the link ended when its stream and every sender were dropped, as its
/// subscriptions are told.
const DROPPED: &str = "the stream and every sender were dropped";

/// The link's subscriptions, ended when the driver goes, however it goes.
struct EndSubscriptions(Arc<Subscribers>);

impl Drop for EndSubscriptions {
    fn drop(&mut self) {
        self.0.end(None);
    }
}

/// Sends the oldest held-back link event of `pending` into the room `permit` holds.
fn deliver_pending_link(
    pending: &mut VecDeque<Event>,
    permit: Result<mpsc::OwnedPermit<Event>, mpsc::error::SendError<()>>,
) {
    match permit {
        Ok(permit) => {
            if let Some(event) = pending.pop_front() {
                permit.send(event);
            }
        }
        // Nobody reads any more.
        Err(_) => pending.clear(),
    }
}

/// The outcome of a Transmit Status.
fn delivery(
    to: Address64,
    status: &xbee_api::TransmitStatusRepr,
) -> Result<DeliveryReport, SendError> {
    if status.delivery == xbee_api::DeliveryStatus::Success {
        Ok(DeliveryReport::Delivered {
            frame_id: status.frame_id,
            dst16: status.dst16,
            retries: status.retries,
            discovery: status.discovery,
        })
    } else {
        Err(SendError::Delivery {
            to,
            frame_id: status.frame_id,
            dst16: status.dst16,
            status: status.delivery,
            retries: status.retries,
            discovery: status.discovery,
        })
    }
}

/// Queues a Transmit Request (16-bit address FFFE, radius 0, options 0).
fn write_transmit(
    mode: xbee_api::ApiMode,
    out: &mut BytesMut,
    frame_id: u8,
    to: Address64,
    payload: &[u8],
) -> Result<(), SendError> {
    let frame = xbee_api::TransmitRequestRepr {
        frame_id,
        ..xbee_api::TransmitRequestRepr::unicast(to, payload)
    };
    encode_frame(&frame, mode, out).map_err(|_| SendError::TooLarge {
        len: frame.frame_data_len(),
        max: xbee_api::MAX_FRAME_DATA_LEN,
    })
}

fn write_raw(mode: xbee_api::ApiMode, out: &mut BytesMut, data: &[u8]) -> Result<(), SendError> {
    let frame = xbee_api::RawFrame::new(data).map_err(|_| SendError::EmptyFrame)?;
    encode_frame(&frame, mode, out).map_err(|_| SendError::TooLarge {
        len: data.len(),
        max: xbee_api::MAX_FRAME_DATA_LEN,
    })
}

#[cfg(test)]
mod tests {
    use tokio::sync::oneshot;

    use super::pending::LATE_ANSWER_WINDOW;
    use super::*;

    /// How long the id of a request given up (or failed with the link) is kept for its
    /// late answers, from `now`.
    fn held_for(kind: PendingKind, deadline: Instant, now: Instant) -> Duration {
        let pending = Pending::new(deadline, Duration::from_secs(1), kind);
        let expired = pending.expired(now).expect("kept");
        expired.deadline - now
    }

    #[test]
    fn ids_are_kept_for_late_answers_for_a_bounded_time() {
        let now = Instant::now();
        let hour = crate::options::later(now, Duration::from_secs(3600));
        let (reply, _answer) = oneshot::channel();
        let transmit = PendingKind::Transmit {
            to: Address64::COORDINATOR,
            reply,
        };
        // One answer: from now, whatever the request's own deadline.
        assert_eq!(held_for(transmit, hour, now), LATE_ANSWER_WINDOW);
        // Answers from every radio: to the end of their window, but not an hour on.
        let answers = |at| {
            let (answers, _rx) = mpsc::channel(1);
            held_for(
                PendingKind::Answers {
                    answers,
                    answer_type: 0x88,
                    dropped: 0,
                },
                at,
                now,
            )
        };
        let soon = now + Duration::from_secs(3);
        assert_eq!(answers(soon), Duration::from_secs(3) + LATE_ANSWER_WINDOW);
        assert_eq!(answers(hour), LATE_ANSWER_WINDOW * 2);
        // A request already kept is not kept again.
        let kept = Pending::new(
            now,
            Duration::ZERO,
            PendingKind::Expired {
                answer_type: None,
                single: true,
            },
        );
        assert!(kept.expired(now).is_none());
    }
}
