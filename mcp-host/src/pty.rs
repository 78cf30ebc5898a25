//! A pseudo-terminal whose link is up only while a device has the far end open: a `pty`
//! link's, or a radio node's.
//!
//! The link keeps the local (master) side and does not hold the far (slave) end open
//! itself, so that the kernel tells whether anyone else does: while no process has the
//! far end open, a read on the master side fails with EIO (it polls as hung up), and
//! once one opens it the read waits for data instead. The link looks every
//! [`PEER_POLL`] while no peer is there, and reads until EIO while one is.
//!
//! Writes to the master side succeed even with nobody on the far end: the kernel keeps
//! the bytes for the next process that opens it. So nothing is written while no peer is
//! there (the link is down: nothing is queued for it), and when a peer leaves, what it
//! left unread is emptied, so that the next one starts afresh rather than with stale
//! frames (a radio's UART output is lost with nobody listening, and a ground station's
//! commands must not reach a MAV long after they were reported as failed).

use std::io;
use std::path::{Path, PathBuf};
use std::pin::Pin;
use std::task::{Context, Poll};
use std::time::Duration;

use bytes::{Buf, Bytes};
use tokio::io::{AsyncRead, AsyncWrite, ReadBuf};
use tokio_serial::{SerialPort, SerialStream};

use crate::transport::LinkError;

/// How often the link looks for a peer on the far end while there is none.
pub(crate) const PEER_POLL: Duration = Duration::from_millis(20);

/// Errno of a read on a master side whose far end nobody has open (EIO on Linux and
/// the BSDs).
const EIO: i32 = 5;

/// A pseudo-terminal pair of which the link holds the master side.
pub(crate) struct PtyPort {
    /// The master side; lent to [`PtyStream`] while a peer is connected.
    master: Option<SerialStream>,
    /// The far end's path.
    path: PathBuf,
}

impl PtyPort {
    /// A new pair; its far end is closed (no peer) until a device opens [`Self::path`].
    pub(crate) fn new() -> Result<Self, LinkError> {
        let (master, slave, path) = pty_pair()?;
        // The pair came with the far end open (and set to raw mode, which stays): closed
        // here so that only a peer's opening counts.
        drop(slave);
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
        loop {
            let master = self.master.as_mut()?;
            // A read straight from the file (not through the runtime's readiness, which
            // may not know yet): EIO while nobody has the far end open.
            match master.try_read(&mut buf) {
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => return self.lend(Bytes::new()),
                // It wrote already: keep what it wrote.
                Ok(n) if n > 0 => return self.lend(Bytes::copy_from_slice(&buf[..n])),
                Ok(_) => {}
                Err(e) if e.raw_os_error() == Some(EIO) => {}
                Err(e) => {
                    tracing::warn!(path = %self.path.display(), error = %e, "pseudo-terminal read failed");
                }
            }
            tokio::time::sleep(PEER_POLL).await;
        }
    }

    fn lend(&mut self, read: Bytes) -> Option<PtyStream> {
        self.master.take().map(|master| PtyStream { master, read })
    }

    /// Takes the master side back after its peer left, and empties what the peer left
    /// unread on the far end.
    pub(crate) fn give_back(&mut self, stream: PtyStream) {
        self.master = Some(stream.master);
        self.drop_unread();
    }

    /// Empties the far end's input: opens it for a moment, without blocking and
    /// without a lock (a serial port library's shared lock would make a new peer's
    /// exclusive open fail if it came at that moment), and reads what is there. Does
    /// nothing if it cannot be opened (a new peer already has it, exclusively).
    fn drop_unread(&self) {
        use std::io::Read;
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
    master: SerialStream,
    read: Bytes,
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
        match Pin::new(&mut this.master).poll_read(cx, buf) {
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
        Pin::new(&mut self.get_mut().master).poll_write(cx, buf)
    }

    fn poll_flush(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        Pin::new(&mut self.get_mut().master).poll_flush(cx)
    }

    fn poll_shutdown(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        Pin::new(&mut self.get_mut().master).poll_shutdown(cx)
    }
}

/// A new pseudo-terminal pair: its master side, its far end (open, in raw mode) and the
/// far end's path.
fn pty_pair() -> Result<(SerialStream, SerialStream, PathBuf), LinkError> {
    let (master, slave) = SerialStream::pair().map_err(LinkError::Pty)?;
    let path = slave.name().map(PathBuf::from).ok_or_else(|| {
        LinkError::Pty(tokio_serial::Error::new(
            tokio_serial::ErrorKind::Unknown,
            "the pseudo-terminal has no name",
        ))
    })?;
    Ok((master, slave, path))
}
