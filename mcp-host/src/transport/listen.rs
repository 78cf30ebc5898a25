//! A `tcp-listen` link's listener: a task that accepts peers all the time, one served,
//! one waiting for its turn, any more turned away.

use std::io;
use std::net::SocketAddr;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use bytes::{Bytes, BytesMut};
use tokio::net::{TcpListener, TcpStream};
use tokio_util::task::AbortOnDropHandle;

use crate::mutex::lock;
use crate::repeats::Repeats;

/// How long the accepting task waits after a failed accept (such as too many open
/// files) before it tries again.
const ACCEPT_RETRY: Duration = Duration::from_millis(100);

/// A `tcp-listen` link's listener. A task accepts all the time: one peer may wait for
/// its turn while another is served (a ground station that reconnects at once, before
/// the link has seen its first connection end, is served next); any more are turned
/// away at once (their connection closed). Its turn comes when the served peer's
/// transport reads the end of its stream or is dropped, or at once if no peer is
/// served, or the served one has hung up, when it connects. A waiting
/// peer that leaves before its turn is dropped with what it wrote, so that a command
/// whose sender gave up waiting is never carried out later; one that leaves after its
/// turn came (a command sent without waiting for an answer) is served, what it wrote
/// carried out.
pub(super) struct Listen {
    pub(super) slot: Arc<Slot>,
    pub(super) local_addr: Option<SocketAddr>,
    /// The task that owns the listener; `None` once [`Listen::shutdown`] ended it.
    pub(super) accepting: Option<AbortOnDropHandle<()>>,
}

/// The place of the peer that waits for its turn.
#[derive(Default)]
pub(super) struct Slot {
    pub(super) state: Mutex<SlotState>,
    /// Told when a peer takes the place.
    pub(super) filled: tokio::sync::Notify,
}

/// Who waits, and whether a peer is being served.
#[derive(Default)]
pub(super) struct SlotState {
    waiting: Option<Waiting>,
    /// A transport of a peer is open (from its [`Listen::next_peer`] until it is
    /// dropped or reads the end of the peer's stream).
    pub(super) serving: bool,
    /// The served peer's socket (a second handle on it), to see whether it has hung
    /// up before the link has read that it did.
    pub(super) served: Option<std::net::TcpStream>,
    /// The served peer's bytes read through `served` to reach its end of stream, for
    /// its transport to deliver before it reads on.
    pub(super) served_early: BytesMut,
    /// The served peer's transport, waiting for bytes: woken when some go to
    /// `served_early`.
    pub(super) served_waker: Option<std::task::Waker>,
    /// The number of the current turn ([`Turn::id`]).
    pub(super) turn: u64,
}

impl SlotState {
    /// Whether a peer is served that has not hung up: one that connects now waits for
    /// it (if it leaves first, it gave up). A served peer whose end of stream waits
    /// behind bytes not read yet counts as there.
    pub(super) fn busy(&mut self) -> bool {
        if !self.serving {
            return false;
        }
        let Some(served) = &self.served else {
            return true;
        };
        // Its end of stream may wait behind bytes the link has not read: they are read
        // here and kept for it (at most [`WAITED_MAX`]; beyond that it counts as there).
        let before = self.served_early.len();
        let ahead = read_ahead(&mut self.served_early, |into| read_direct(served, into));
        if self.served_early.len() > before {
            if let Some(waker) = self.served_waker.take() {
                waker.wake();
            }
        }
        ahead != Ahead::Gone
    }

    /// The served peer's turn is over: the peer waiting, if still there, is due.
    pub(super) fn turn_over(&mut self) {
        self.serving = false;
        self.served = None;
        self.served_early.clear();
        self.served_waker = None;
        if let Some(waiting) = self.waiting.as_mut() {
            waiting.due |= waiting.still_there();
        }
    }
}

impl Slot {
    pub(super) fn lock(&self) -> std::sync::MutexGuard<'_, SlotState> {
        lock(&self.state)
    }
}

/// A served peer's turn: when the transport reads the end of the peer's stream or is
/// dropped, the peer that waits (if it is still there) is due, and is served even if it
/// leaves before the link takes it.
pub(super) struct Turn {
    pub(super) slot: Arc<Slot>,
    /// Its number: a transport that outlives its turn (opened again meanwhile) ends no
    /// other.
    pub(super) id: u64,
    pub(super) over: bool,
}

impl Turn {
    pub(super) fn end(&mut self) {
        if !std::mem::replace(&mut self.over, true) {
            let mut state = self.slot.lock();
            if state.turn == self.id {
                state.turn_over();
            }
        }
    }
}

impl Drop for Turn {
    fn drop(&mut self) {
        self.end();
    }
}

/// A peer waiting for its turn, and what it wrote meanwhile.
struct Waiting {
    pub(super) stream: TcpStream,
    /// A second handle on its socket, read directly: the runtime's view of whether
    /// the socket is readable lags until its I/O driver runs, which would take a peer
    /// that has left for one still there.
    direct: Option<std::net::TcpStream>,
    pub(super) peer: SocketAddr,
    pub(super) early: BytesMut,
    /// Its turn came while it was there: no peer was served when it connected (or the
    /// served one had hung up), or the served one ended while it waited. What it wrote
    /// is carried out even if it has left since (a command sent without waiting for an
    /// answer) before the link took it.
    due: bool,
}

impl Waiting {
    /// Reads what the peer wrote since it was last looked at; `false` if it has left
    /// (closed its side, or its connection failed). At most [`WAITED_MAX`] bytes are
    /// read ahead: a peer that wrote more while it waited counts as gone (whether it
    /// left cannot be seen behind them, and it must not be served if it did).
    fn still_there(&mut self) -> bool {
        let (direct, stream) = (&self.direct, &self.stream);
        let ahead = read_ahead(&mut self.early, |into| match direct {
            Some(direct) => read_direct(direct, into),
            None => {
                into.reserve(4096);
                stream.try_read_buf(into)
            }
        });
        ahead == Ahead::There
    }
}

/// What reading a peer's bytes ahead found.
#[derive(Debug, PartialEq, Eq)]
enum Ahead {
    /// All it wrote is read, and it is still connected.
    There,
    /// Its end of stream, or its connection failed.
    Gone,
    /// [`WAITED_MAX`] bytes are held: whether more follow, or its end, is not known.
    Full,
}

/// Reads a peer's bytes into `into` with `read` (a non-blocking read that appends)
/// until it has none more, its stream ends, or `into` holds [`WAITED_MAX`] bytes.
fn read_ahead(
    into: &mut BytesMut,
    mut read: impl FnMut(&mut BytesMut) -> io::Result<usize>,
) -> Ahead {
    while into.len() < WAITED_MAX {
        match read(into) {
            Ok(0) => return Ahead::Gone,
            Ok(_) => {}
            Err(e) if e.kind() == io::ErrorKind::WouldBlock => return Ahead::There,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(_) => return Ahead::Gone,
        }
    }
    Ahead::Full
}

/// One non-blocking read of `socket` (a second handle on a peer's), appended to `into`.
fn read_direct(socket: &std::net::TcpStream, into: &mut BytesMut) -> io::Result<usize> {
    let mut chunk = [0u8; 4096];
    let n = io::Read::read(&mut &*socket, &mut chunk)?;
    into.extend_from_slice(chunk.get(..n).unwrap_or_default());
    Ok(n)
}

impl Listen {
    pub(super) fn new(listener: TcpListener, name: String) -> Self {
        let local_addr = listener.local_addr().ok();
        let slot = Arc::new(Slot::default());
        let task = tokio::spawn(accept_peers(listener, name, slot.clone()));
        Listen {
            slot,
            local_addr,
            accepting: Some(AbortOnDropHandle::new(task)),
        }
    }

    /// Ends the accepting task and waits until it has dropped the listener, so that
    /// the port is free when this returns (dropping a `Listen` only asks the task to
    /// stop: on a multi-threaded runtime the socket may outlive it for a moment). The
    /// peer waiting for its turn, if any, is let go.
    pub(super) async fn shutdown(&mut self) {
        if let Some(task) = self.accepting.take() {
            task.abort();
            let _ = task.await;
        }
        self.slot.lock().waiting.take();
    }

    /// The next peer whose turn came while it was there, what it wrote while it
    /// waited, and its turn.
    pub(super) async fn next_peer(&mut self) -> (TcpStream, SocketAddr, Bytes, Turn) {
        loop {
            let taken = {
                let mut state = self.slot.lock();
                if let Some(mut waiting) = state.waiting.take() {
                    // Read ahead even when it is due: what it wrote before it left.
                    if waiting.still_there() || waiting.due {
                        state.serving = true;
                        state.served = second_handle(&waiting.stream);
                        state.served_early.clear();
                        state.served_waker = None;
                        state.turn += 1;
                        Some(Ok((waiting, state.turn)))
                    } else {
                        Some(Err(waiting.peer))
                    }
                } else {
                    None
                }
            };
            match taken {
                Some(Ok((waiting, id))) => {
                    let turn = Turn {
                        slot: self.slot.clone(),
                        id,
                        over: false,
                    };
                    return (waiting.stream, waiting.peer, waiting.early.freeze(), turn);
                }
                Some(Err(peer)) => left_before_its_turn(peer),
                None => self.slot.filled.notified().await,
            }
        }
    }
}

/// A second handle on `stream`'s socket, non-blocking, to look at it from elsewhere.
pub(super) fn second_handle(stream: &TcpStream) -> Option<std::net::TcpStream> {
    #[cfg(unix)]
    let owned = std::os::fd::AsFd::as_fd(stream).try_clone_to_owned();
    #[cfg(windows)]
    let owned = std::os::windows::io::AsSocket::as_socket(stream).try_clone_to_owned();
    let served = std::net::TcpStream::from(owned.ok()?);
    served.set_nonblocking(true).ok()?;
    Some(served)
}

/// Says that `peer` was turned away: to the operator of a simulator or an emulated
/// radio (the peer sees only its connection closed), the first at once and then a count
/// at most once a second ([`Repeats`]), as a peer that connects again and again would
/// make a line each.
fn turned_away(peer: SocketAddr, repeats: &mut Repeats) {
    if let Some(more) = repeats.count(tokio::time::Instant::now()) {
        let more = match more {
            0 => String::new(),
            n => format!(" ({} turned away since the last line)", n + 1),
        };
        tracing::warn!(%peer, "turned a peer away: the link serves another one, and one more waits its turn (to share the link, use a hub){more}");
    }
}

fn left_before_its_turn(peer: SocketAddr) {
    tracing::info!(%peer, "a waiting peer left before its turn: what it wrote is dropped");
}

/// How much of what a waiting peer wrote is read ahead to see whether it is still there
/// (the rest is read as usual).
const WAITED_MAX: usize = 64 * 1024;

/// Accepts peers for a `tcp-listen` link, for as long as the connector lives: one waits
/// for the link at most (a new peer takes the place of one that has left meanwhile); the
/// others are closed at once.
async fn accept_peers(listener: TcpListener, name: String, slot: Arc<Slot>) {
    let mut failures = 0u64;
    let mut turned_away_repeats = Repeats::default();
    loop {
        match listener.accept().await {
            Ok((stream, peer)) => {
                failures = 0;
                let mut state = slot.lock();
                let free = match state.waiting.as_mut() {
                    None => true,
                    // Its turn has come: it is served, whether or not it has left since.
                    Some(w) if w.due => false,
                    Some(w) => {
                        let gone = !w.still_there();
                        if gone {
                            left_before_its_turn(w.peer);
                        }
                        gone
                    }
                };
                if free {
                    let mut waiting = Waiting {
                        direct: second_handle(&stream),
                        stream,
                        peer,
                        early: BytesMut::new(),
                        due: false,
                    };
                    // Its turn has come if nobody is ahead of it: no peer is served, or
                    // the served one has hung up. (Peers are accepted as they connect:
                    // one that waited for a served peer and gave up would have to have
                    // connected long before, its seconds of waiting unseen.)
                    waiting.due = !state.busy();
                    state.waiting = Some(waiting);
                    drop(state);
                    slot.filled.notify_one();
                } else {
                    drop(state);
                    turned_away(peer, &mut turned_away_repeats);
                }
            }
            Err(error) => {
                failures += 1;
                // One warning an outage of the listener, not one each retry.
                if failures == 1 {
                    tracing::warn!(addr = %name, %error, "accepting a peer failed (retrying)");
                } else {
                    tracing::debug!(addr = %name, %error, "accepting a peer failed");
                }
                tokio::time::sleep(ACCEPT_RETRY).await;
            }
        }
    }
}
