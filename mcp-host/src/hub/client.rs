//! One client's connection: its frames read, checked and queued for the radio, and the
//! radio's frames and its answers written to it.

use std::cell::Cell;
use std::net::SocketAddr;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

use bytes::Bytes;
use futures::{FutureExt, StreamExt};
use tokio::io::AsyncWriteExt;
use tokio::net::tcp::{OwnedReadHalf, OwnedWriteHalf};
use tokio::sync::{Semaphore, mpsc};
use tokio::time::Instant;
use tokio_util::codec::FramedRead;
use tokio_util::sync::CancellationToken;
use xbee_api::ApiMode;
use xbee_api::frame::frame_type::answer_type;

use super::input::{ClientCodec, ClientInput, ClientItem};
use super::radio_writer::{Queued, ToRadio};
use super::request::{answered_many_times, at_command, is_whole_request, not_sent_answer};
use super::routes::{Route, Routes};
use super::serve::AnswerQueue;
use super::stall::Stalls;
use super::{Counters, IDS_PER_CLIENT, REQUEST_WAIT, ROUTES_PER_CLIENT, encode, settled};
use crate::codec::CodecItem;
use crate::mutex::lock;
use crate::stats::bump;

/// One client's connection, served by two tasks: one reads its frames and writes them
/// to the radio, the other writes the radio's frames to it. The client is gone when
/// both have ended; its requests' routes then end too.
pub(super) struct Client {
    /// The hub's stalls: a request read just after one counts from its beginning.
    pub(super) stalls: Arc<Stalls>,
    /// Its number, in its routes.
    pub(super) number: u64,
    pub(super) peer: SocketAddr,
    pub(super) mode: ApiMode,
    /// Where its queue of frames to the radio is taken from.
    pub(super) to_radio: Arc<ToRadio>,
    /// Its queue of the answers to its requests.
    pub(super) queue: AnswerQueue,
    pub(super) routes: Arc<Mutex<Routes>>,
    /// The permits of the 255 frame ids, shared by all clients.
    pub(super) ids: Arc<Semaphore>,
    /// The permits of the [`SHARED_IDS`](super::SHARED_IDS), shared by all clients'
    /// requests beyond their first [`IDS_PER_CLIENT`].
    pub(super) shared: Arc<Semaphore>,
    /// Its [`ROUTES_PER_CLIENT`] permits to have a request waiting for answers.
    pub(super) permits: Arc<Semaphore>,
    /// Its [`MANY_ANSWER_PER_CLIENT`](super::MANY_ANSWER_PER_CLIENT) permits to have a
    /// request answered many times waiting.
    pub(super) many: Arc<Semaphore>,
    /// How its frames are read.
    pub(super) input: ClientInput,
    pub(super) counters: Arc<Counters>,
    /// Ends both its tasks: the hub stopped, the radio's link went down, its
    /// connection failed, or another client took its place.
    pub(super) end: CancellationToken,
    /// Since when its queue of frames from the radio has been full, without being
    /// drained since.
    pub(super) behind: Arc<Mutex<Option<Instant>>>,
    /// Since when it has sent nothing more (see
    /// [`Connected::closed`](super::serve::Connected::closed)).
    pub(super) closed: Arc<Mutex<Option<Instant>>>,
    /// Since when it has written ahead of the radio: a frame it sent found its
    /// [`CLIENT_FRAMES_TO_RADIO`](super::CLIENT_FRAMES_TO_RADIO) places taken, and waited
    /// its turn, and the hub has not read all it wrote since; `None` once it has (the
    /// client waits for more: a frame finding a place free says nothing, as the radio's
    /// writer may take two short frames of a flood at once). A client that writes faster
    /// than the radio sends keeps it: one that keeps it for [`STALLED`](super::STALLED)
    /// gives its place up when the hub is full (a program that left megabytes of frames
    /// in its connection, whose end the hub cannot read before them, is one).
    pub(super) ahead: Arc<Mutex<Option<Instant>>>,
    /// The radio's frames dropped for it (see
    /// [`Connected::dropped`](super::serve::Connected::dropped)).
    pub(super) dropped: Arc<AtomicU64>,
    /// Its bytes that began no frame, skipped.
    pub(super) skipped: AtomicU64,
    /// Whether its bytes skipped were said (the first not after a refused frame).
    pub(super) warned_skipped: AtomicBool,
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
    pub(super) async fn read(self: Arc<Self>, rd: OwnedReadHalf, to_radio: mpsc::Sender<Queued>) {
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
    pub(super) fn skipped(&self, bytes: u64, after_error: bool) {
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
    pub(super) fn refuse(&self, why: std::fmt::Arguments<'_>) {
        settled(&self.counters.frames_refused);
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
    /// (waiting while [`CLIENT_FRAMES_TO_RADIO`](super::CLIENT_FRAMES_TO_RADIO) frames
    /// wait their turn), its wait counted from `since` if it was read then already (see
    /// `read`). Since when it waited, if it did; `Err` once the hub stops.
    async fn pass(
        &self,
        item: CodecItem,
        to_radio: &mpsc::Sender<Queued>,
        since: Option<Instant>,
    ) -> Result<Option<Instant>, ()> {
        // Read, whichever way it goes (a partial frame given up comes here too).
        bump(&self.counters.frames_read_from_clients);
        // A frame on its way (waiting for a frame id or its turn) when the client is
        // ended, its reader dropped, or when the hub stops, is refused: never written.
        let on_its_way = RefusedIfDropped(&self.counters.frames_refused);
        let passed = self.pass_on(item, to_radio, since).await;
        if passed.is_ok() {
            std::mem::forget(on_its_way);
        }
        passed
    }

    /// [`pass`](Self::pass), but for the counting.
    async fn pass_on(
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
    pub(super) async fn write(
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
    pub(super) fn not_sent(&self, request: &[u8], what: &str) {
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
            if xbee_api::frame::frame_type::is_from_radio(frame_type) {
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

/// Counts a client's frame refused when dropped: one that never reached the radio's
/// queue, nor was refused on its way.
struct RefusedIfDropped<'a>(&'a AtomicU64);

impl Drop for RefusedIfDropped<'_> {
    fn drop(&mut self) {
        settled(self.0);
    }
}
