//! A pseudo-terminal whose link is up only while a device has the far end open: a `pty`
//! link's, or a radio node's.
//!
//! The link keeps the local (master) side and does not hold the far (slave) end open
//! itself, so that the kernel tells whether anyone else does: while no process has the
//! far end open, a read on the master side fails with EIO (it polls as hung up), and
//! once one opens it the read waits for data instead. The link looks every
//! [`PEER_POLL`] while no peer is there, and reads until EIO while one is.
//!
//! A peer may open the far end, write and close it again between two looks (a program
//! that sends a few commands and exits). What it wrote stays on the master side, and a
//! serial port's close sends what was written: so the link serves it as a peer that
//! came and left, its bytes read at once and then the end of the stream. Nothing of it
//! waits for the next peer; if its bytes cannot be read, they are dropped.
//!
//! Writes to the master side succeed even with nobody on the far end: the kernel keeps
//! the bytes for the next process that opens it. So nothing is written while no peer is
//! there (the link is down: nothing is queued for it), and when a peer leaves, what it
//! left unread is emptied, so that the next one starts afresh rather than with stale
//! frames (a radio's UART output is lost with nobody listening, and a ground station's
//! commands must not reach a MAV long after they were reported as failed).

use std::io::{self, Read};
use std::path::{Path, PathBuf};
use std::pin::Pin;
use std::task::{Context, Poll};
use std::time::Duration;

use bytes::{Buf, Bytes, BytesMut};
use serialport::{ClearBuffer, SerialPort, TTYPort};
use tokio::io::{AsyncRead, AsyncWrite, ReadBuf};
use tokio_serial::SerialStream;

use crate::transport::LinkError;

/// How often the link looks for a peer on the far end while there is none.
pub(crate) const PEER_POLL: Duration = Duration::from_millis(20);

/// Errno of a read on a master side whose far end nobody has open (EIO on Linux and
/// the BSDs).
const EIO: i32 = 5;

/// More than the master side of a pseudo-terminal holds (a few dozen KiB): a peer that
/// has written that much is still there, writing.
const LEFT_MAX: usize = 1 << 17;

/// What a look at the master side found.
enum Look {
    /// Nobody has the far end open, and nobody left anything on it.
    Nobody,
    /// A peer has the far end open; what it wrote already comes first.
    Peer(Bytes),
    /// A peer opened the far end, wrote this and closed it since the last look.
    Left(Bytes),
}

/// A pseudo-terminal pair of which the link holds the master side.
pub(crate) struct PtyPort {
    /// The master side, not registered with the runtime; lent to [`PtyStream`] while a
    /// peer is connected.
    master: Option<TTYPort>,
    /// The far end's path.
    path: PathBuf,
}

impl PtyPort {
    /// A new pair; its far end is closed (no peer) until a device opens [`Self::path`].
    pub(crate) fn new() -> Result<Self, LinkError> {
        let (mut master, slave) = TTYPort::pair().map_err(LinkError::Pty)?;
        let path = slave.name().map(PathBuf::from).ok_or_else(|| {
            LinkError::Pty(tokio_serial::Error::new(
                tokio_serial::ErrorKind::Unknown,
                "the pseudo-terminal has no name",
            ))
        })?;
        // The pair came with the far end open (and set to raw mode, which stays): closed
        // here so that only a peer's opening counts.
        drop(slave);
        // A read looks (polls) first and fails at once if there is nothing to read.
        master.set_timeout(Duration::ZERO).map_err(LinkError::Pty)?;
        Ok(PtyPort {
            master: Some(master),
            path,
        })
    }

    /// The far end's path, for a device to open.
    pub(crate) fn path(&self) -> &Path {
        &self.path
    }

    /// Waits until a peer has the far end open, and returns the master side to talk to
    /// it; `None` if the master side is gone for good.
    pub(crate) async fn peer(&mut self) -> Option<PtyStream> {
        let mut buf = [0u8; 256];
        // An error that repeats is logged as a warning once, then at debug level.
        let mut failures = 0u32;
        let mut failed = |path: &Path, error: &dyn std::fmt::Display, what: &str| {
            failures = failures.saturating_add(1);
            if failures == 1 {
                tracing::warn!(path = %path.display(), %error, "pseudo-terminal: {what}");
            } else {
                tracing::debug!(path = %path.display(), %error, "pseudo-terminal: {what}");
            }
        };
        loop {
            let master = self.master.as_mut()?;
            // Straight from the file: a hang-up (BrokenPipe, or EIO from the read) while
            // nobody has the far end open, a timeout once someone does and has not
            // written yet.
            let look = match master.read(&mut buf) {
                Err(e) if e.kind() == io::ErrorKind::TimedOut => Look::Peer(Bytes::new()),
                // It wrote already: keep what it wrote.
                Ok(n) if n > 0 => Look::Peer(Bytes::copy_from_slice(&buf[..n])),
                Ok(_) => Look::Nobody,
                Err(e)
                    if e.kind() == io::ErrorKind::BrokenPipe || e.raw_os_error() == Some(EIO) =>
                {
                    // Also when a peer came and left, with bytes waiting.
                    self.left_behind().unwrap_or_else(|e| {
                        failed(&self.path, &e, "cannot read what a peer left");
                        self.drop_left_behind();
                        Look::Nobody
                    })
                }
                Err(e) => {
                    failed(&self.path, &e, "read failed");
                    Look::Nobody
                }
            };
            match look {
                Look::Nobody => {}
                Look::Peer(read) => match self.lend(read) {
                    Ok(stream) => return Some(stream),
                    Err(e) => failed(&self.path, &e, "cannot wait for its input"),
                },
                Look::Left(read) => {
                    // Not registered with the runtime: there is nothing more to wait
                    // for, and a registration made now would see the hang-up, which the
                    // runtime keeps (see `lend`) should a new peer come before the end.
                    let port = self.master.take()?;
                    return Some(PtyStream {
                        master: None,
                        port,
                        read,
                    });
                }
            }
            tokio::time::sleep(PEER_POLL).await;
        }
    }

    /// What a peer that came and left since the last look wrote, after a read found no
    /// peer ([`Look::Left`]); [`Look::Nobody`] if it wrote nothing (or nobody came). If
    /// a new peer has opened the far end meanwhile, what was read comes first in its
    /// stream ([`Look::Peer`]).
    fn left_behind(&self) -> io::Result<Look> {
        let Some(master) = self.master.as_ref() else {
            return Ok(Look::Nobody);
        };
        // Counted after the read that found the hang-up: its poll pushed what the peer
        // wrote through to the input the count sees (counted sooner, bytes still on
        // their way may be missed). A peer that comes after that poll is counted in
        // part or not at all: the read below, or the next look, takes the rest.
        if master.bytes_to_read()? == 0 {
            return Ok(Look::Nobody);
        }
        // Read from the file itself: the port's read polls first and fails on the
        // hang-up before reading. The registration this takes goes on return, before
        // any peer is served (see [`Self::lend`]).
        let mut file = SerialStream::try_from(master.try_clone_native()?)?;
        let mut left = BytesMut::new();
        let mut buf = [0u8; 4096];
        while left.len() < LEFT_MAX {
            match file.try_read(&mut buf) {
                Ok(n) if n > 0 => left.extend_from_slice(&buf[..n]),
                // All read: nobody has the far end open.
                Ok(_) => return Ok(Look::Left(left.freeze())),
                Err(e) if e.raw_os_error() == Some(EIO) => return Ok(Look::Left(left.freeze())),
                // All read, and a new peer has the far end open.
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => {
                    return Ok(Look::Peer(left.freeze()));
                }
                Err(e) => return Err(e),
            }
        }
        Ok(Look::Peer(left.freeze()))
    }

    /// Drops what a peer that left wrote, when it cannot be read: never for the next
    /// peer.
    fn drop_left_behind(&self) {
        let Some(master) = self.master.as_ref() else {
            return;
        };
        if let Err(e) = master.clear(ClearBuffer::Input) {
            tracing::debug!(path = %self.path.display(), error = %e,
                "pseudo-terminal: what a peer left not dropped");
        }
    }

    /// The master side for a peer that is there now, registered with the runtime
    /// afresh. (A registration made while nobody had the far end open saw the hang-up,
    /// and the runtime keeps a hang-up for good: every read would then find the side
    /// ready, get nothing and try again at once, a core kept busy while the link idles.)
    /// The registration is dropped with the stream when the peer leaves.
    fn lend(&mut self, read: Bytes) -> Result<PtyStream, tokio_serial::Error> {
        let Some(port) = self.master.take() else {
            return Err(tokio_serial::Error::new(
                tokio_serial::ErrorKind::Unknown,
                "the master side is lent already",
            ));
        };
        let registered = port.try_clone_native().and_then(SerialStream::try_from);
        match registered {
            Ok(master) => Ok(PtyStream {
                master: Some(master),
                port,
                read,
            }),
            Err(e) => {
                self.master = Some(port);
                Err(e)
            }
        }
    }

    /// Takes the master side back after its peer left, and empties what the peer left
    /// unread on the far end.
    pub(crate) fn give_back(&mut self, stream: PtyStream) {
        // The stream's registration (its own file descriptor) goes with it.
        self.master = Some(stream.port);
        self.drop_unread();
    }

    /// Empties the far end's input: opens it for a moment, without blocking and
    /// without a lock (a serial port library's shared lock would make a new peer's
    /// exclusive open fail if it came at that moment), and reads what is there. Does
    /// nothing if it cannot be opened (a new peer already has it, exclusively).
    fn drop_unread(&self) {
        use std::os::unix::fs::OpenOptionsExt;
        let far = std::fs::OpenOptions::new()
            .read(true)
            .custom_flags(libc::O_NONBLOCK | libc::O_NOCTTY)
            .open(&self.path);
        let mut far = match far {
            Ok(far) => far,
            Err(e) => {
                tracing::debug!(path = %self.path.display(), error = %e,
                    "pseudo-terminal: far end not opened to drop unread bytes");
                return;
            }
        };
        // The far end is in raw mode: a read returns what is queued, WouldBlock once
        // nothing is. Bounded: a pseudo-terminal queues a few KiB.
        let mut buf = [0u8; 4096];
        for _ in 0..64 {
            match far.read(&mut buf) {
                Ok(n) if n > 0 => {}
                _ => break,
            }
        }
    }
}

/// The master side of a pseudo-terminal while a peer has its far end open. A read ends
/// (returns no bytes) when the peer closes it; bytes read while looking for
/// the peer come first.
pub(crate) struct PtyStream {
    /// The master side, registered while this peer is there; `None` for a peer that
    /// left before it was seen, whose stream is [`Self::read`] only.
    master: Option<SerialStream>,
    /// The master side as the port keeps it.
    port: TTYPort,
    /// What the peer wrote before it was seen.
    read: Bytes,
}

impl PtyStream {
    /// What tells the baud rate the peer set its end to, for as long as it likes.
    pub(crate) fn rate_probe(&self) -> Option<RateProbe> {
        self.port.try_clone_native().ok().map(RateProbe)
    }
}

/// The baud rate a pseudo-terminal's peer set its end to: the two ends share their
/// settings, so the master side reads what the peer's `tcsetattr` set.
pub(crate) struct RateProbe(TTYPort);

impl RateProbe {
    /// The peer's baud rate now; `None` if it cannot be read.
    pub(crate) fn baud_rate(&self) -> Option<u32> {
        self.0.baud_rate().ok()
    }
}

impl AsyncRead for PtyStream {
    fn poll_read(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &mut ReadBuf<'_>,
    ) -> Poll<io::Result<()>> {
        let this = self.get_mut();
        if !this.read.is_empty() {
            let n = this.read.len().min(buf.remaining());
            buf.put_slice(&this.read[..n]);
            this.read.advance(n);
            return Poll::Ready(Ok(()));
        }
        let Some(master) = &mut this.master else {
            // The peer left before it was seen: all it wrote is read.
            return Poll::Ready(Ok(()));
        };
        match Pin::new(master).poll_read(cx, buf) {
            // The far end is closed: the peer left.
            Poll::Ready(Err(e)) if e.raw_os_error() == Some(EIO) => Poll::Ready(Ok(())),
            other => other,
        }
    }
}

impl AsyncWrite for PtyStream {
    fn poll_write(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &[u8],
    ) -> Poll<io::Result<usize>> {
        match &mut self.get_mut().master {
            Some(master) => Pin::new(master).poll_write(cx, buf),
            // Nobody is listening: lost, as a UART's output is (not kept by the kernel
            // for the next peer).
            None => Poll::Ready(Ok(buf.len())),
        }
    }

    fn poll_flush(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        match &mut self.get_mut().master {
            Some(master) => Pin::new(master).poll_flush(cx),
            None => Poll::Ready(Ok(())),
        }
    }

    fn poll_shutdown(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        match &mut self.get_mut().master {
            Some(master) => Pin::new(master).poll_shutdown(cx),
            None => Poll::Ready(Ok(())),
        }
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;
    use std::sync::atomic::{AtomicUsize, Ordering};
    use std::task::{Wake, Waker};

    use tokio::io::AsyncReadExt;

    use super::*;

    /// Counts the wake-ups of the task it belongs to.
    #[derive(Default)]
    struct Wakes(AtomicUsize);

    impl Wake for Wakes {
        fn wake(self: Arc<Self>) {
            self.0.fetch_add(1, Ordering::SeqCst);
        }
    }

    /// Returns after the runtime has waited for I/O events at least once (a TCP
    /// connection on the loopback made and accepted).
    async fn turn_the_reactor() {
        let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
        let addr = listener.local_addr().unwrap();
        let (accepted, connected) =
            tokio::join!(listener.accept(), tokio::net::TcpStream::connect(addr));
        accepted.unwrap();
        connected.unwrap();
    }

    /// Opens the far end as a device would.
    fn open_far_end(path: &Path) -> std::fs::File {
        use std::os::unix::fs::OpenOptionsExt;
        std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .custom_flags(libc::O_NOCTTY)
            .open(path)
            .unwrap()
    }

    // The clock is paused: the device comes (virtual) time after the port began to
    // wait for one, so that the runtime has looked at the port without a peer, as it
    // does when a device comes later.
    #[tokio::test(start_paused = true)]
    async fn an_idle_peer_leaves_the_task_asleep() {
        let mut port = PtyPort::new().unwrap();
        let path = port.path().to_owned();
        // Twice: the second peer comes after the first left.
        for round in 0..2 {
            let waiting = tokio::spawn(async move {
                let stream = port.peer().await;
                (port, stream)
            });
            tokio::time::sleep(PEER_POLL * 3).await;
            let far = open_far_end(&path);
            let (back, stream) = waiting.await.unwrap();
            port = back;
            let mut stream = stream.expect("the master side is there");
            let wakes = Arc::new(Wakes::default());
            let waker = Waker::from(wakes.clone());
            let mut buf = [0u8; 16];
            let mut read = std::pin::pin!(stream.read(&mut buf));
            let polled = read.as_mut().poll(&mut Context::from_waker(&waker));
            assert!(polled.is_pending(), "round {round}: nothing was written");
            turn_the_reactor().await;
            assert_eq!(
                wakes.0.load(Ordering::SeqCst),
                0,
                "round {round}: a read with nothing to read woke its task"
            );
            // Bytes from the peer arrive, and its leaving ends the stream.
            std::io::Write::write_all(&mut &far, b"\x7e").unwrap();
            assert_eq!(read.await.unwrap(), 1);
            assert_eq!(buf[0], 0x7e);
            drop(far);
            assert_eq!(stream.read(&mut buf).await.unwrap(), 0, "round {round}");
            port.give_back(stream);
        }
    }
}
