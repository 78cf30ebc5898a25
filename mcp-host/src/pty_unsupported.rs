//! Where there are no pseudo-terminals (Windows): a `pty` link, or a radio node on one,
//! fails to open with [`LinkError::Pty`], saying so; serial ports and TCP work as
//! anywhere.

use std::io;
use std::path::Path;
use std::pin::Pin;
use std::task::{Context, Poll};

use tokio::io::{AsyncRead, AsyncWrite, ReadBuf};

use crate::transport::LinkError;

/// Nothing: no value of it exists.
enum Never {}

/// A pseudo-terminal pair: never made here.
pub(crate) struct PtyPort(Never);

impl PtyPort {
    /// Fails: this system has no pseudo-terminals.
    pub(crate) fn new() -> Result<Self, LinkError> {
        Err(LinkError::Pty(tokio_serial::Error::new(
            tokio_serial::ErrorKind::Unknown,
            "this system has no pseudo-terminals (pty links and nodes need Unix): use a \
             serial port or TCP",
        )))
    }

    pub(crate) fn path(&self) -> &Path {
        match self.0 {}
    }

    pub(crate) async fn peer(&mut self) -> Option<PtyStream> {
        match self.0 {}
    }

    pub(crate) fn give_back(&mut self, _stream: PtyStream) {
        match self.0 {}
    }
}

/// The master side of a pseudo-terminal: never made here.
pub(crate) struct PtyStream(Never);

impl PtyStream {
    pub(crate) fn rate_probe(&self) -> Option<RateProbe> {
        match self.0 {}
    }
}

/// The baud rate of a pseudo-terminal's peer: never made here.
pub(crate) struct RateProbe(Never);

impl RateProbe {
    pub(crate) fn baud_rate(&self) -> Option<u32> {
        match self.0 {}
    }
}

impl AsyncRead for PtyStream {
    fn poll_read(
        self: Pin<&mut Self>,
        _cx: &mut Context<'_>,
        _buf: &mut ReadBuf<'_>,
    ) -> Poll<io::Result<()>> {
        match self.0 {}
    }
}

impl AsyncWrite for PtyStream {
    fn poll_write(
        self: Pin<&mut Self>,
        _cx: &mut Context<'_>,
        _buf: &[u8],
    ) -> Poll<io::Result<usize>> {
        match self.0 {}
    }

    fn poll_flush(self: Pin<&mut Self>, _cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        match self.0 {}
    }

    fn poll_shutdown(self: Pin<&mut Self>, _cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        match self.0 {}
    }
}
