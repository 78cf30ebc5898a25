//! Opening links: the [`Connector`] turns a [`Link`] into [`Transport`]s, again and again
//! when the link reconnects.

mod listen;

use std::io;
use std::net::SocketAddr;
use std::path::Path;
use std::pin::Pin;
use std::sync::{Arc, Mutex, PoisonError};
use std::task::{Context, Poll};
use std::time::Duration;

use bytes::Bytes;
use futures::future::BoxFuture;
use tokio::io::{AsyncRead, AsyncWrite, ReadBuf};
use tokio::net::{TcpListener, TcpStream};
use tokio_serial::{SerialPortBuilderExt, SerialStream};

use self::listen::{Listen, Turn};
use crate::keepalive::{LINK_KEEPALIVE, keep_alive};
use crate::link::Link;
use crate::mutex::lock;
use crate::options::{LinkOptions, ReconnectPolicy};
use crate::pty::{PtyPort, PtyStream};

/// Why a link could not be opened.
///
/// What the system said is in the message, and in a field to match on; it is no
/// [`source`](std::error::Error::source), so that a report that follows the chain of
/// sources (`anyhow`'s `{:#}`) says it once.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LinkError {
    /// The serial port could not be opened or configured.
    #[error("cannot open serial port {path} at {baud} baud: {error}")]
    #[non_exhaustive]
    Serial {
        /// Device path.
        path: String,
        /// Requested baud rate.
        baud: u32,
        /// What the system said.
        error: tokio_serial::Error,
    },
    /// The TCP connection failed.
    #[error("cannot connect to {addr}: {error}")]
    #[non_exhaustive]
    Connect {
        /// `HOST:PORT` as given.
        addr: String,
        /// What the system said.
        error: io::Error,
    },
    /// The TCP connection did not complete within the connect timeout.
    #[error(
        "timed out after {secs} connecting to {addr}",
        secs = crate::render::Seconds(*.timeout)
    )]
    #[non_exhaustive]
    ConnectTimeout {
        /// `HOST:PORT` as given.
        addr: String,
        /// The connect timeout.
        timeout: Duration,
    },
    /// The TCP listener could not be bound.
    #[error("cannot listen on {addr}: {error}")]
    #[non_exhaustive]
    Listen {
        /// The link as given, `tcp-listen:ADDR:PORT`.
        addr: String,
        /// What the system said.
        error: io::Error,
    },
    /// Accepting a peer failed.
    #[error("cannot accept a peer on {addr}: {error}")]
    #[non_exhaustive]
    Accept {
        /// The link as given, `tcp-listen:ADDR:PORT`.
        addr: String,
        /// What the system said.
        error: io::Error,
    },
    /// A stream the program opens itself (an `io:` link) could not be opened: its
    /// opener failed, or, for [`connect_io`](crate::connect_io)'s stream, it was asked
    /// for another after the one it was given (which cannot be retried), or
    /// [`connect`](crate::connect) was given an `io:` link, which it has nothing to open
    /// with.
    #[error("cannot open io:{name}: {error}")]
    #[non_exhaustive]
    Io {
        /// The stream's name.
        name: String,
        /// What its opener said.
        error: io::Error,
    },
    /// The pseudo-terminal pair could not be created.
    #[error("cannot create a pseudo-terminal pair: {0}")]
    Pty(tokio_serial::Error),
    /// The local side of a `pty` link is gone (still held by a transport that was not
    /// closed), so the link cannot wait for another device.
    #[error("the pseudo-terminal's local side is gone: the link cannot be reopened")]
    PtyClosed,
    /// The transport went away and reconnection is disabled by the options.
    #[error("the link went down and reconnection is disabled")]
    ReconnectDisabled,
}

impl LinkError {
    /// Whether trying again later may succeed (a device may come back, a peer may start
    /// listening); false for errors that no retry can fix: settings a serial port
    /// refuses, a serial path that is there but is no device (a regular file, a
    /// directory: on Unix, anything but a character device) or a device that is no
    /// terminal (`/dev/null`), an address nobody can
    /// connect to (port 0, an address of no interface), an `io:` link's opener that
    /// failed with `InvalidInput` or `Unsupported`, and the listening and
    /// pseudo-terminal errors.
    ///
    /// A serial path that is not there may be a device still to come (a USB adapter
    /// plugged in later): that counts as retryable, as does any other serial error. One
    /// that has become a regular file while its device was away (written to while
    /// unplugged) is not: a link waiting for the device back gives up on it.
    pub fn is_retryable(&self) -> bool {
        use std::io::ErrorKind as Io;
        match self {
            LinkError::Serial { path, error, .. } => {
                error.kind() != tokio_serial::ErrorKind::InvalidInput
                    && !is_no_device(path)
                    && !is_no_terminal(&error.description)
            }
            LinkError::Connect { error, .. } => {
                !matches!(error.kind(), Io::InvalidInput | Io::AddrNotAvailable)
            }
            LinkError::Io { error, .. } => {
                !matches!(error.kind(), Io::InvalidInput | Io::Unsupported)
            }
            LinkError::Listen { .. }
            | LinkError::Pty(_)
            | LinkError::PtyClosed
            | LinkError::ReconnectDisabled => false,
            _ => true,
        }
    }
}

/// Whether `path` is there but is not a device a serial port can be: on Unix, anything
/// but a character device. A path that is not there, or cannot be looked at, is not
/// known to be none.
fn is_no_device(path: &str) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        std::fs::metadata(path).is_ok_and(|meta| !meta.file_type().is_char_device())
    }
    #[cfg(not(unix))]
    {
        let _ = path;
        false
    }
}

/// Whether a serial port's open failed with ENOTTY: the device is there and is no
/// terminal (`/dev/null`), which it never becomes. The error's text is all there is to
/// go by (its kind is `Unknown`), and it depends on the C library.
fn is_no_terminal(description: &str) -> bool {
    ["Not a typewriter", "Inappropriate ioctl", "Not a tty"]
        .iter()
        .any(|text| description.contains(text))
}

enum Inner {
    Tcp(TcpStream),
    /// A `tcp-listen` peer.
    Accepted {
        stream: TcpStream,
        /// What it wrote while it waited for its turn.
        early: Bytes,
        /// Its turn, until the transport reads the end of the stream or is dropped.
        turn: Turn,
    },
    Serial(SerialStream),
    Pty(Lent),
    /// In a mutex only to be `Sync`, as the other transports are: polling takes
    /// `&mut self`, which reaches the stream without locking.
    Io(Mutex<Box<dyn RadioIo>>),
}

/// A byte stream to a radio that a program opens itself, for an `io:` link
/// ([`connect_with`](crate::connect_with)): any `AsyncRead + AsyncWrite` that can go to
/// another task.
pub trait RadioIo: AsyncRead + AsyncWrite + Send + Unpin + 'static {}

impl<T: AsyncRead + AsyncWrite + Send + Unpin + 'static> RadioIo for T {}

/// The stream of an `io:` transport, reached without locking.
fn io_of(stream: &mut Mutex<Box<dyn RadioIo>>) -> &mut Box<dyn RadioIo> {
    stream.get_mut().unwrap_or_else(PoisonError::into_inner)
}

/// What opens an `io:` link's stream, each time the link is opened.
pub(crate) type Opener =
    Box<dyn FnMut() -> BoxFuture<'static, io::Result<Box<dyn RadioIo>>> + Send>;

/// An open byte stream to the radio: a serial port, a TCP connection, the local side of
/// a pseudo-terminal or a stream the program opened itself (`io:`). Implements
/// [`AsyncRead`] and [`AsyncWrite`].
pub struct Transport {
    inner: Inner,
    peer: String,
}

impl std::fmt::Debug for Transport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Transport")
            .field("peer", &self.peer)
            .finish_non_exhaustive()
    }
}

impl Transport {
    /// What is at the other end: the serial device path, the TCP peer address, or the far
    /// end of the pseudo-terminal.
    pub fn peer(&self) -> &str {
        &self.peer
    }
}

impl AsyncRead for Transport {
    fn poll_read(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &mut ReadBuf<'_>,
    ) -> Poll<io::Result<()>> {
        match &mut self.get_mut().inner {
            Inner::Tcp(s) => Pin::new(s).poll_read(cx, buf),
            Inner::Accepted {
                stream: s,
                early,
                turn,
            } => {
                if !early.is_empty() {
                    let n = early.len().min(buf.remaining());
                    buf.put_slice(&early.split_to(n));
                    return Poll::Ready(Ok(()));
                }
                if turn.over {
                    return Pin::new(s).poll_read(cx, buf);
                }
                // Under the lock: what the listener read of the peer's bytes (to see
                // whether it hung up) comes first, and it reads no more meanwhile.
                let mut state = turn.slot.lock();
                if state.turn != turn.id {
                    // Another peer's turn (this transport outlived its own).
                    drop(state);
                    turn.over = true;
                    return Pin::new(s).poll_read(cx, buf);
                }
                if !state.served_early.is_empty() {
                    let n = state.served_early.len().min(buf.remaining());
                    buf.put_slice(&state.served_early.split_to(n));
                    return Poll::Ready(Ok(()));
                }
                let (room, before) = (buf.remaining(), buf.filled().len());
                let read = Pin::new(s).poll_read(cx, buf);
                // The end of its stream (or a failed connection): the next peer's turn
                // has come.
                let ended = match &read {
                    Poll::Ready(Ok(())) => room > 0 && buf.filled().len() == before,
                    Poll::Ready(Err(_)) => true,
                    Poll::Pending => {
                        // Bytes the listener reads meanwhile raise no readiness of the
                        // socket: it wakes the reader itself.
                        state.served_waker = Some(cx.waker().clone());
                        false
                    }
                };
                if ended {
                    state.turn_over();
                    drop(state);
                    turn.over = true;
                }
                read
            }
            Inner::Serial(s) => Pin::new(s).poll_read(cx, buf),
            Inner::Pty(s) => s.stream()?.poll_read(cx, buf),
            Inner::Io(s) => Pin::new(io_of(s)).poll_read(cx, buf),
        }
    }
}

impl AsyncWrite for Transport {
    fn poll_write(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &[u8],
    ) -> Poll<io::Result<usize>> {
        match &mut self.get_mut().inner {
            Inner::Tcp(s) | Inner::Accepted { stream: s, .. } => Pin::new(s).poll_write(cx, buf),
            Inner::Serial(s) => Pin::new(s).poll_write(cx, buf),
            Inner::Pty(s) => s.stream()?.poll_write(cx, buf),
            Inner::Io(s) => Pin::new(io_of(s)).poll_write(cx, buf),
        }
    }

    fn poll_flush(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        match &mut self.get_mut().inner {
            Inner::Tcp(s) | Inner::Accepted { stream: s, .. } => Pin::new(s).poll_flush(cx),
            Inner::Serial(s) => Pin::new(s).poll_flush(cx),
            Inner::Pty(s) => s.stream()?.poll_flush(cx),
            Inner::Io(s) => Pin::new(io_of(s)).poll_flush(cx),
        }
    }

    fn poll_shutdown(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        match &mut self.get_mut().inner {
            Inner::Tcp(s) | Inner::Accepted { stream: s, .. } => Pin::new(s).poll_shutdown(cx),
            Inner::Serial(s) => Pin::new(s).poll_shutdown(cx),
            Inner::Pty(s) => s.stream()?.poll_shutdown(cx),
            Inner::Io(s) => Pin::new(io_of(s)).poll_shutdown(cx),
        }
    }
}

/// A `pty` link's pair: up while a device has the far end open.
struct PtyLink {
    port: PtyPort,
    /// The master side lent to the current transport, put back when it is dropped.
    back: Arc<Mutex<Option<PtyStream>>>,
}

/// The master side of a `pty` link, lent to a [`Transport`] while a peer is there.
struct Lent {
    /// Always `Some` until dropped.
    stream: Option<PtyStream>,
    back: Arc<Mutex<Option<PtyStream>>>,
}

impl Lent {
    /// The stream (taken only when dropped, so always there before).
    fn stream(&mut self) -> io::Result<Pin<&mut PtyStream>> {
        self.stream
            .as_mut()
            .map(Pin::new)
            .ok_or_else(|| io::Error::from(io::ErrorKind::NotConnected))
    }
}

impl Drop for Lent {
    fn drop(&mut self) {
        if let Some(stream) = self.stream.take() {
            *lock(&self.back) = Some(stream);
        }
    }
}

enum Kind {
    Serial {
        path: String,
        baud: u32,
        flow_control: crate::link::FlowControl,
    },
    Tcp {
        host: String,
        port: u16,
    },
    Listen(Listen),
    Pty(PtyLink),
    Io {
        /// The stream's name, as its opener gave it.
        name: String,
        /// In a mutex only to be `Sync`, as the other kinds are.
        open: Mutex<Opener>,
    },
}

/// Whether `path` is the far (slave) end of a Unix 98 pseudo-terminal (`/dev/pts/N`,
/// device majors 136 to 143), however it is named (a symbolic link, say).
#[cfg(target_os = "linux")]
fn is_pty_far_end(path: &Path) -> bool {
    use std::os::unix::fs::{FileTypeExt, MetadataExt};
    std::fs::metadata(path).is_ok_and(|meta| {
        meta.file_type().is_char_device() && (136..=143).contains(&libc::major(meta.rdev()))
    })
}

/// Opens [`Transport`]s for a [`Link`], and reopens them after a disconnection.
///
/// Creating the connector binds a `tcp-listen` socket and creates the `pty` pair (so the
/// listening address and the far-end path are known before any peer shows up); serial
/// ports and TCP connections are opened by [`Connector::open`].
///
/// - `serial`: every open opens the device path again (after a USB unplug the device
///   comes back under the same path, or the retry waits for it).
/// - `tcp`: every open connects again, within the connect timeout.
/// - `tcp-listen`: every open takes the next peer. One peer is served at a time; while
///   one is, the next may wait for its turn and any more are turned away (their
///   connection closed at once). Its turn comes when the served peer hangs up (its
///   transport reads the end of its stream) or its transport is dropped, at once if
///   none is served or the served one has hung up. A waiting peer that leaves before its turn is
///   dropped with what it wrote, so that nothing it wrote is carried out after it gave
///   up; one that leaves after its turn came, as a command sent without waiting for an
///   answer does, is served all the same. There is no reconnection delay: the next
///   open takes the next peer.
/// - `pty`: every open waits for a device to open the far end (the path stays valid for
///   the life of the connector); the transport ends when the device closes it, and what
///   it left unread is dropped, so that nothing written for one device reaches the next.
pub struct Connector {
    link: Link,
    kind: Kind,
    connect_timeout: Duration,
    delay: Option<Duration>,
    /// When the current (or last) transport was opened.
    opened_at: Option<tokio::time::Instant>,
    /// Whether it carried data ([`Connector::mark_healthy`]).
    healthy: bool,
}

impl std::fmt::Debug for Connector {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Connector")
            .field("link", &self.link)
            .field("pty_path", &self.pty_path())
            .field("local_addr", &self.local_addr())
            .finish_non_exhaustive()
    }
}

impl Connector {
    /// Prepares `link`: binds a listener or creates a pseudo-terminal pair where needed.
    pub async fn new(link: &Link, options: &LinkOptions) -> Result<Self, LinkError> {
        let kind = match link {
            Link::Serial {
                path,
                baud,
                flow_control,
            } => Kind::Serial {
                path: path.clone(),
                baud: *baud,
                flow_control: *flow_control,
            },
            Link::Tcp { host, port } => Kind::Tcp {
                host: host.clone(),
                port: *port,
            },
            Link::TcpListen { addr, port } => {
                let name = link.to_string();
                let listener =
                    TcpListener::bind((addr.as_str(), *port))
                        .await
                        .map_err(|error| LinkError::Listen {
                            addr: name.clone(),
                            error,
                        })?;
                Kind::Listen(Listen::new(listener, name))
            }
            Link::Pty => Kind::Pty(PtyLink {
                port: PtyPort::new()?,
                back: Arc::default(),
            }),
            Link::Io { name } => {
                return Err(LinkError::Io {
                    name: name.clone(),
                    error: io::Error::new(
                        io::ErrorKind::Unsupported,
                        "an io: link is opened by the program's own function \
                         (mcp_host::connect_with), which a link string does not give",
                    ),
                });
            }
        };
        Ok(Self::with_kind(link.clone(), kind, options))
    }

    /// Opens an `io:` link named `name` with `open`, each time it is opened.
    pub(crate) fn with_opener(name: String, open: Opener, options: &LinkOptions) -> Self {
        let kind = Kind::Io {
            name: name.clone(),
            open: Mutex::new(open),
        };
        Self::with_kind(Link::Io { name }, kind, options)
    }

    fn with_kind(link: Link, kind: Kind, options: &LinkOptions) -> Self {
        Connector {
            link,
            kind,
            connect_timeout: options.connect_timeout,
            delay: None,
            opened_at: None,
            healthy: false,
        }
    }

    /// The link this connector opens.
    pub fn link(&self) -> &Link {
        &self.link
    }

    /// For a `pty` link, the path of the far end, for a simulator or test to open.
    pub fn pty_path(&self) -> Option<&Path> {
        match &self.kind {
            Kind::Pty(pty) => Some(pty.port.path()),
            _ => None,
        }
    }

    /// For a `tcp-listen` link, the bound address (useful with port 0).
    pub fn local_addr(&self) -> Option<SocketAddr> {
        match &self.kind {
            Kind::Listen(listen) => listen.local_addr,
            _ => None,
        }
    }

    /// Lets go of what the connector holds, and waits until it has: a `tcp-listen`
    /// link's port is free when this returns, and a peer waiting for its turn is let
    /// go. Dropping the connector does the same, except that the port may stay bound a
    /// moment longer on a multi-threaded runtime. Opening the connector again after
    /// this fails.
    pub async fn shutdown(&mut self) {
        if let Kind::Listen(listen) = &mut self.kind {
            listen.shutdown().await;
        }
    }

    /// Opens a transport once: opens the serial port, connects, accepts the next peer
    /// (waiting for one), or hands out the local side of the pseudo-terminal.
    pub async fn open(&mut self) -> Result<Transport, LinkError> {
        let transport = self.open_kind().await?;
        self.opened_at = Some(tokio::time::Instant::now());
        self.healthy = false;
        Ok(transport)
    }

    async fn open_kind(&mut self) -> Result<Transport, LinkError> {
        match &mut self.kind {
            Kind::Serial {
                path,
                baud,
                flow_control,
            } => {
                let serial_error = |error| LinkError::Serial {
                    path: path.clone(),
                    baud: *baud,
                    error,
                };
                // The driver adds the device namespace itself, and would double it when
                // it reopens the port (`\\.\\\.\COM10`).
                let name = match cfg!(windows) {
                    true => without_device_namespace(path),
                    false => path.as_str(),
                };
                #[cfg_attr(not(any(target_os = "linux", windows)), allow(unused_mut))]
                let mut stream = tokio_serial::new(name, *baud)
                    .data_bits(tokio_serial::DataBits::Eight)
                    .parity(tokio_serial::Parity::None)
                    .stop_bits(tokio_serial::StopBits::One)
                    .flow_control(match flow_control {
                        crate::link::FlowControl::RtsCts => tokio_serial::FlowControl::Hardware,
                        _ => tokio_serial::FlowControl::None,
                    })
                    .open_native_async()
                    .map_err(serial_error)?;
                // The far end of a pseudo-terminal (a virtual radio's, a simulator's) keeps
                // the exclusive flag (TIOCEXCL) of a process that dies without closing it,
                // killed say, for as long as its master side lives: nobody but root could
                // open it again. So there the port is kept by serialport's flock alone, then
                // shared, which goes with the process and still turns away every other
                // opener that asks for exclusive use (another mcp-gs, serialport, pyserial).
                #[cfg(target_os = "linux")]
                if is_pty_far_end(Path::new(path)) {
                    stream.set_exclusive(false).map_err(serial_error)?;
                }
                // Windows opens a port with DTR and RTS off, where Unix raises both: a
                // radio that waits for RTS before it sends (D6=1) would say nothing, and
                // one whose sleep request is wired to DTR would sleep. Raised as on Unix
                // (RTS only without flow control: with it, serialport sets the driver to
                // keep RTS raised itself, honouring CTS alone).
                #[cfg(windows)]
                {
                    use tokio_serial::SerialPort;
                    let _ = stream.write_data_terminal_ready(true);
                    if *flow_control == crate::link::FlowControl::None {
                        let _ = stream.write_request_to_send(true);
                    }
                }
                Ok(Transport {
                    inner: Inner::Serial(stream),
                    peer: path.clone(),
                })
            }
            Kind::Tcp { host, port } => {
                let addr = crate::link::host_port(host, *port);
                if *port == 0 {
                    // The system refuses it as it would an absent peer (ECONNREFUSED on
                    // Linux): retried, it would be waited on for ever.
                    return Err(LinkError::Connect {
                        addr,
                        error: std::io::Error::new(
                            std::io::ErrorKind::InvalidInput,
                            "port 0 cannot be connected to",
                        ),
                    });
                }
                let stream = tokio::time::timeout(
                    self.connect_timeout,
                    TcpStream::connect((host.as_str(), *port)),
                )
                .await
                .map_err(|_| LinkError::ConnectTimeout {
                    addr: addr.clone(),
                    timeout: self.connect_timeout,
                })?
                .map_err(|error| LinkError::Connect {
                    addr: addr.clone(),
                    error,
                })?;
                let _ = stream.set_nodelay(true);
                keep_alive(&stream, &LINK_KEEPALIVE);
                let peer = stream.peer_addr().map(|a| a.to_string()).unwrap_or(addr);
                Ok(Transport {
                    inner: Inner::Tcp(stream),
                    peer,
                })
            }
            Kind::Listen(listen) => {
                if listen.accepting.is_none() {
                    return Err(LinkError::Listen {
                        addr: self.link.to_string(),
                        error: io::Error::other("the link was shut down"),
                    });
                }
                let (stream, peer, early, turn) = listen.next_peer().await;
                let _ = stream.set_nodelay(true);
                keep_alive(&stream, &LINK_KEEPALIVE);
                Ok(Transport {
                    inner: Inner::Accepted {
                        stream,
                        early,
                        turn,
                    },
                    peer: peer.to_string(),
                })
            }
            Kind::Pty(pty) => {
                let lent = lock(&pty.back).take();
                if let Some(stream) = lent {
                    pty.port.give_back(stream);
                }
                let stream = pty.port.peer().await.ok_or(LinkError::PtyClosed)?;
                Ok(Transport {
                    inner: Inner::Pty(Lent {
                        stream: Some(stream),
                        back: pty.back.clone(),
                    }),
                    peer: pty.port.path().display().to_string(),
                })
            }
            Kind::Io { name, open } => {
                let name = name.clone();
                let open = open.get_mut().unwrap_or_else(PoisonError::into_inner);
                // An opener may hang (a connection to a host that stopped answering):
                // given up as a TCP connection is, and tried again.
                match tokio::time::timeout(self.connect_timeout, open()).await {
                    Ok(Ok(stream)) => Ok(Transport {
                        inner: Inner::Io(Mutex::new(stream)),
                        peer: name,
                    }),
                    Ok(Err(error)) => Err(LinkError::Io { name, error }),
                    Err(_) => Err(LinkError::Io {
                        name,
                        error: io::Error::new(
                            io::ErrorKind::TimedOut,
                            format!(
                                "not opened within {}",
                                crate::render::Seconds(self.connect_timeout)
                            ),
                        ),
                    }),
                }
            }
        }
    }

    /// Opens a transport after a disconnection, following `policy`: waits the current
    /// backoff delay before each attempt and doubles it after each failure (capped at
    /// `max_delay`); a `tcp-listen` link takes its next peer with no delay. Returns the first error that no retry can fix, and
    /// [`LinkError::ReconnectDisabled`] at once when reconnection is disabled. Failed
    /// attempts are logged at debug level.
    ///
    /// The delay carries over between calls; it starts again from `initial_delay` after
    /// a transport that carried data ([`Connector::mark_healthy`]) and, for the links
    /// that open the radio themselves (`serial`, `tcp`, `io:`), stayed open for at least
    /// `max_delay`. So a transport that opens and fails at once keeps backing off, and
    /// so does a TCP peer that sends a frame and hangs up, again and again.
    ///
    /// Cancel-safe: dropping the future loses nothing but the attempt under way.
    pub async fn reopen(&mut self, policy: &ReconnectPolicy) -> Result<Transport, LinkError> {
        if !policy.enabled {
            return Err(LinkError::ReconnectDisabled);
        }
        // A link that waits for its peers (tcp-listen, pty) serves short-lived ones as
        // a matter of course; one that opens the radio itself backs off from a peer
        // that answers and hangs up at once.
        let waits_for_peers = matches!(self.kind, Kind::Listen(_) | Kind::Pty(_));
        let lasted = self.opened_at.map(|at| at.elapsed());
        if self.healthy && (waits_for_peers || lasted.is_some_and(|d| d >= policy.max_delay)) {
            self.delay = None;
        }
        self.healthy = false;
        // A listener waits for its next peer, who may be there already: no delay.
        let listens = matches!(self.kind, Kind::Listen(_));
        loop {
            let delay = *self.delay.get_or_insert(policy.initial_delay);
            if !listens {
                tokio::time::sleep(delay).await;
            }
            let next = policy.next_delay(delay);
            self.delay = Some(next);
            match self.open().await {
                Ok(transport) => return Ok(transport),
                // The outage was logged when it began (a warning); each attempt only
                // at debug level, so that a long outage is one line.
                Err(e) if e.is_retryable() => {
                    tracing::debug!(error = %e, retry_in = %crate::render::Seconds(next), "reconnect attempt failed");
                }
                Err(e) => return Err(e),
            }
        }
    }

    /// Tells the connector that the current transport works (it carried data), so the
    /// next reconnection starts again from the initial delay (for `serial` and `tcp`
    /// links, if the transport stays open for the policy's `max_delay`:
    /// [`Connector::reopen`]).
    pub fn mark_healthy(&mut self) {
        self.healthy = true;
    }
}

/// A Windows serial port's name without the device namespace it may be written with:
/// `COM10` for `\\.\COM10`.
fn without_device_namespace(path: &str) -> &str {
    path.strip_prefix(r"\\.\").unwrap_or(path)
}

#[cfg(test)]
mod tests {
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::task::Wake;

    use super::listen::{Slot, second_handle};
    use super::*;
    #[cfg(any(target_os = "linux", target_os = "macos"))]
    use crate::keepalive::assert_kept_alive;

    struct Flag(AtomicBool);

    impl Wake for Flag {
        fn wake(self: Arc<Self>) {
            self.0.store(true, Ordering::SeqCst);
        }
    }

    #[test]
    fn a_windows_port_is_opened_by_its_name_without_the_device_namespace() {
        assert_eq!(without_device_namespace(r"\\.\COM10"), "COM10");
        assert_eq!(without_device_namespace("COM3"), "COM3");
        assert_eq!(without_device_namespace("/dev/ttyUSB0"), "/dev/ttyUSB0");
    }

    /// A `tcp:` link's connection and a `tcp-listen:` link's peer are probed when
    /// quiet: a peer gone without a word (a bridge powered off) is found out, and the
    /// link reconnects, where nothing else would tell.
    #[cfg(any(target_os = "linux", target_os = "macos"))]
    #[tokio::test]
    async fn tcp_links_probe_a_quiet_peer() {
        let listener = TcpListener::bind("127.0.0.1:0").await.unwrap();
        let port = listener.local_addr().unwrap().port();
        let options = LinkOptions::default();
        let mut connector = Connector::new(&Link::tcp("127.0.0.1", port), &options)
            .await
            .unwrap();
        let transport = connector.open().await.unwrap();
        let Inner::Tcp(stream) = &transport.inner else {
            panic!("a tcp: link gives a TCP stream")
        };
        assert_kept_alive(stream, &LINK_KEEPALIVE);

        let mut connector = Connector::new(&Link::tcp_listen("127.0.0.1", 0), &options)
            .await
            .unwrap();
        let addr = connector.local_addr().unwrap();
        let _peer = std::net::TcpStream::connect(addr).unwrap();
        let transport = connector.open().await.unwrap();
        let Inner::Accepted { stream, .. } = &transport.inner else {
            panic!("a tcp-listen: link gives its peer's stream")
        };
        assert_kept_alive(stream, &LINK_KEEPALIVE);
    }

    /// The listener reads the served peer's bytes (to see whether it hung up) after its
    /// transport found none and waits: the socket then raises no readiness for them, so
    /// the listener wakes the transport, which delivers them.
    #[tokio::test]
    async fn bytes_the_listener_reads_wake_the_transport_waiting_for_them() {
        let listener = TcpListener::bind("127.0.0.1:0").await.unwrap();
        let mut peer = std::net::TcpStream::connect(listener.local_addr().unwrap()).unwrap();
        let (stream, _) = listener.accept().await.unwrap();
        let slot = Arc::new(Slot::default());
        {
            let mut state = slot.lock();
            state.serving = true;
            state.served = second_handle(&stream);
            state.turn = 1;
        }
        let turn = Turn {
            slot: slot.clone(),
            id: 1,
            over: false,
        };
        let mut transport = Transport {
            inner: Inner::Accepted {
                stream,
                early: Bytes::new(),
                turn,
            },
            peer: String::new(),
        };
        let flag = Arc::new(Flag(AtomicBool::new(false)));
        let waker = std::task::Waker::from(flag.clone());
        let mut cx = Context::from_waker(&waker);
        let mut room = [0u8; 8];
        let mut buf = ReadBuf::new(&mut room);
        assert!(
            Pin::new(&mut transport)
                .poll_read(&mut cx, &mut buf)
                .is_pending()
        );
        // The peer writes; the listener, looking at it, reads the bytes first.
        io::Write::write_all(&mut peer, b"cmd").unwrap();
        let mut state = slot.lock();
        while state.served_early.is_empty() {
            assert!(state.busy(), "the peer is there");
        }
        drop(state);
        assert!(flag.0.load(Ordering::SeqCst), "the transport was not woken");
        assert!(
            Pin::new(&mut transport)
                .poll_read(&mut cx, &mut buf)
                .is_ready()
        );
        assert_eq!(buf.filled(), b"cmd");
    }
}
