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
//!   in [`HubStats::frames_dropped`]); the others are not held up.
//! - **From a client:** a frame with a frame id (AT command, Transmit Request, ...) goes
//!   to the radio under an id the hub allocates, and the answer (AT response, Transmit
//!   Status, ...) goes back to that client alone, under the client's own id: clients
//!   that each count their ids from 1 never get each other's answers. Frames with id 0
//!   and frames of other types are written as they are.
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

use std::net::SocketAddr;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

use bytes::{Bytes, BytesMut};
use futures::StreamExt;
use tokio::io::AsyncWriteExt;
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::{Semaphore, mpsc};
use tokio_util::codec::FramedRead;
use tokio_util::sync::CancellationToken;
use tokio_util::task::TaskTracker;
use xbee_api::{ApiMode, RawFrame};

use crate::codec::{CodecItem, XBeeCodec, encode_frame};
use crate::event::carries_frame_id;
use crate::{CommandSender, ConnectError, Event, Link, LinkOptions, PacketStream};

/// Frames from the radio waiting for one client, at most; more are dropped for it.
pub const CLIENT_QUEUE: usize = 1024;

/// Requests of one client waiting for their answers, at most: the hub reads no more of
/// its frames until one is answered (or times out).
pub const CLIENT_IN_FLIGHT: usize = 64;

/// How long the hub waits for the radio's answer to a client's request. Clients have
/// their own timeouts; this only frees the frame id of an answer that never comes.
const ANSWER_TIMEOUT: Duration = Duration::from_secs(60);

/// Why a hub could not start.
#[derive(Debug, thiserror::Error)]
pub enum HubError {
    /// The link to the radio could not be opened.
    #[error(transparent)]
    Connect(#[from] ConnectError),
    /// The TCP port could not be listened on.
    #[error("cannot listen on {addr}: {source}")]
    Listen {
        /// The address as given.
        addr: String,
        /// What the system said.
        #[source]
        source: std::io::Error,
    },
}

/// Counters of a hub.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct HubStats {
    /// Clients connected so far.
    pub clients: u64,
    /// Frames from the radio passed to clients (counted once a frame, whatever the
    /// number of clients).
    pub frames_from_radio: u64,
    /// Frames from clients passed to the radio.
    pub frames_from_clients: u64,
    /// Frames from the radio not given to a client that had fallen behind.
    pub frames_dropped: u64,
}

#[derive(Debug, Default)]
struct Counters {
    clients: AtomicU64,
    frames_from_radio: AtomicU64,
    frames_from_clients: AtomicU64,
    frames_dropped: AtomicU64,
}

fn bump(counter: &AtomicU64) {
    counter.fetch_add(1, Ordering::Relaxed);
}

/// A radio served to TCP clients (see the [module](self) docs). Runs until
/// [`stop`](Self::stop)ped or until the link to the radio ends for good.
#[derive(Debug)]
pub struct Hub {
    local_addr: SocketAddr,
    stop: CancellationToken,
    tasks: TaskTracker,
    counters: Arc<Counters>,
}

impl Hub {
    /// Opens the link to the radio (with `options`: API mode, reconnection, ...) and
    /// listens on `listen` (`HOST:PORT`; port 0 picks a free one, see
    /// [`local_addr`](Self::local_addr)). Clients speak the API mode of `options`.
    pub async fn start(link: &Link, options: LinkOptions, listen: &str) -> Result<Hub, HubError> {
        let mode = options.api_mode;
        let listener = TcpListener::bind(listen)
            .await
            .map_err(|source| HubError::Listen {
                addr: listen.to_owned(),
                source,
            })?;
        let local_addr = listener.local_addr().map_err(|source| HubError::Listen {
            addr: listen.to_owned(),
            source,
        })?;
        let (stream, sender) = crate::connect(link, options).await?;
        let hub = Hub {
            local_addr,
            stop: CancellationToken::new(),
            tasks: TaskTracker::new(),
            counters: Arc::default(),
        };
        let serve = Serve {
            mode,
            sender,
            stop: hub.stop.clone(),
            tasks: hub.tasks.clone(),
            counters: hub.counters.clone(),
            clients: Vec::new(),
        };
        hub.tasks.spawn(serve.run(stream, listener));
        Ok(hub)
    }

    /// The address clients connect to.
    pub fn local_addr(&self) -> SocketAddr {
        self.local_addr
    }

    /// Counters so far.
    pub fn stats(&self) -> HubStats {
        let c = &self.counters;
        HubStats {
            clients: c.clients.load(Ordering::Relaxed),
            frames_from_radio: c.frames_from_radio.load(Ordering::Relaxed),
            frames_from_clients: c.frames_from_clients.load(Ordering::Relaxed),
            frames_dropped: c.frames_dropped.load(Ordering::Relaxed),
        }
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

/// The hub's main task: frames from the radio to the clients, new clients accepted.
struct Serve {
    mode: ApiMode,
    sender: CommandSender,
    stop: CancellationToken,
    tasks: TaskTracker,
    counters: Arc<Counters>,
    /// Each client's queue of encoded frames.
    clients: Vec<mpsc::Sender<Bytes>>,
}

impl Serve {
    async fn run(mut self, mut stream: PacketStream, listener: TcpListener) {
        loop {
            tokio::select! {
                () = self.stop.cancelled() => break,
                accepted = listener.accept() => match accepted {
                    Ok((socket, peer)) => self.accept(socket, peer),
                    Err(error) => tracing::warn!(%error, "hub: accepting a client failed"),
                },
                event = stream.next() => match event {
                    Some(event) => self.broadcast(&event),
                    None => break,
                },
            }
        }
        // Ends the clients' tasks too, if the link ended first.
        self.stop.cancel();
        self.sender.close();
        // Until the radio's device is free.
        self.sender.closed().await;
    }

    fn accept(&mut self, socket: TcpStream, peer: SocketAddr) {
        tracing::info!(%peer, "hub: client connected");
        bump(&self.counters.clients);
        let (queue, frames) = mpsc::channel(CLIENT_QUEUE);
        self.clients.push(queue.clone());
        let client = Client {
            mode: self.mode,
            sender: self.sender.clone(),
            queue,
            in_flight: Arc::new(Semaphore::new(CLIENT_IN_FLIGHT)),
            tasks: self.tasks.clone(),
            counters: self.counters.clone(),
        };
        self.tasks
            .spawn(client.run(socket, peer, frames, self.stop.clone()));
    }

    fn broadcast(&mut self, event: &Event) {
        let data = match event {
            Event::Packet(rx) => &rx.frame,
            Event::InvalidPacket(rx) => &rx.frame,
            Event::Frame(frame) => frame.data(),
            Event::Link(link) => {
                tracing::info!(?link, "hub: radio link");
                return;
            }
            Event::DecodeError(_) => return,
        };
        let Some(bytes) = encode(data, self.mode) else {
            return;
        };
        bump(&self.counters.frames_from_radio);
        let counters = &self.counters;
        self.clients
            .retain(|client| match client.try_send(bytes.clone()) {
                Ok(()) => true,
                Err(mpsc::error::TrySendError::Full(_)) => {
                    bump(&counters.frames_dropped);
                    true
                }
                Err(mpsc::error::TrySendError::Closed(_)) => false,
            });
    }
}

/// One client's connection.
struct Client {
    mode: ApiMode,
    sender: CommandSender,
    /// Its own queue, for the answers to its requests.
    queue: mpsc::Sender<Bytes>,
    /// Permits for its requests in flight ([`CLIENT_IN_FLIGHT`]).
    in_flight: Arc<Semaphore>,
    tasks: TaskTracker,
    counters: Arc<Counters>,
}

impl Client {
    async fn run(
        self,
        socket: TcpStream,
        peer: SocketAddr,
        mut frames: mpsc::Receiver<Bytes>,
        stop: CancellationToken,
    ) {
        let (rd, mut wr) = socket.into_split();
        let mut reader = FramedRead::new(rd, XBeeCodec::new(self.mode));
        let reason = loop {
            tokio::select! {
                () = stop.cancelled() => break "the hub stopped".to_owned(),
                item = reader.next() => match item {
                    Some(Ok(CodecItem::Frame(frame))) => self.forward(frame.data().clone()).await,
                    Some(Ok(CodecItem::Error(error))) => {
                        tracing::debug!(%peer, %error, "hub: a client's frame dropped");
                    }
                    Some(Err(error)) => break error.to_string(),
                    None => break "disconnected".to_owned(),
                },
                Some(bytes) = frames.recv() => {
                    if let Err(error) = wr.write_all(&bytes).await {
                        break error.to_string();
                    }
                }
            }
        };
        tracing::info!(%peer, %reason, "hub: client gone");
    }

    /// A client's frame to the radio: under an id of the hub's if it carries one, the
    /// answer then back to this client under its own id (in a task of its own, so that
    /// the client's next frames go on meanwhile); any other frame written at once, in
    /// the order the client sent it.
    async fn forward(&self, data: Bytes) {
        bump(&self.counters.frames_from_clients);
        let own_id = match (data.first(), data.get(1)) {
            (Some(&frame_type), Some(&id)) if carries_frame_id(frame_type) && id != 0 => id,
            _ => {
                if let Err(error) = self.sender.write_frame(&data).await {
                    tracing::debug!(%error, "hub: a client's frame not written");
                }
                return;
            }
        };
        let Ok(permit) = self.in_flight.clone().acquire_owned().await else {
            return;
        };
        let sender = self.sender.clone();
        let (mode, queue) = (self.mode, self.queue.clone());
        self.tasks.spawn(async move {
            let answer = sender.send_frame(&data, Some(ANSWER_TIMEOUT)).await;
            // Answered: the client's loop may read its next frame while this one waits
            // for room in its queue (which that loop empties).
            drop(permit);
            let answer = match answer {
                Ok(answer) => answer,
                Err(error) => {
                    tracing::debug!(%error, "hub: no answer to a client's frame");
                    return;
                }
            };
            let mut answer = answer.data().to_vec();
            if let Some(id) = answer.get_mut(1) {
                *id = own_id;
            }
            if let Some(bytes) = encode(&answer, mode) {
                // The client may be gone by now.
                let _ = queue.send(bytes).await;
            }
        });
    }
}

/// Frame data encoded whole for the wire; `None` for data no frame can hold.
fn encode(data: &[u8], mode: ApiMode) -> Option<Bytes> {
    let frame = RawFrame::new(data).ok()?;
    let mut buf = BytesMut::new();
    encode_frame(&frame, mode, &mut buf).ok()?;
    Some(buf.freeze())
}
