//! A radio's UART at a fixed baud rate: a device on a pseudo-terminal set to another rate
//! reads garbage and is not understood, as on a real serial line.

use std::pin::Pin;
use std::task::{Context, Poll};

use tokio::io::{AsyncRead, AsyncWrite, ReadBuf};

/// What bytes become between two ends at different rates: garbage, the same for the
/// same bytes.
pub(crate) fn garble(bytes: &mut [u8]) {
    for b in bytes {
        *b = b.rotate_left(3) ^ 0xA5;
    }
}

/// One half of a device's byte stream, garbled while `mismatched` says the two ends run
/// at different rates.
pub(crate) struct Uart<'a, T> {
    pub(crate) inner: T,
    pub(crate) mismatched: &'a (dyn Fn() -> bool + Send + Sync),
}

impl<T: AsyncRead + Unpin> AsyncRead for Uart<'_, T> {
    fn poll_read(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &mut ReadBuf<'_>,
    ) -> Poll<std::io::Result<()>> {
        let this = self.get_mut();
        let before = buf.filled().len();
        let polled = Pin::new(&mut this.inner).poll_read(cx, buf);
        if let Poll::Ready(Ok(())) = polled {
            if buf.filled().len() > before && (this.mismatched)() {
                if let Some(new) = buf.filled_mut().get_mut(before..) {
                    garble(new);
                }
            }
        }
        polled
    }
}

impl<T: AsyncWrite + Unpin> AsyncWrite for Uart<'_, T> {
    fn poll_write(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &[u8],
    ) -> Poll<std::io::Result<usize>> {
        let this = self.get_mut();
        if (this.mismatched)() {
            let mut garbled = buf.to_vec();
            garble(&mut garbled);
            Pin::new(&mut this.inner).poll_write(cx, &garbled)
        } else {
            Pin::new(&mut this.inner).poll_write(cx, buf)
        }
    }

    fn poll_flush(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<std::io::Result<()>> {
        Pin::new(&mut self.get_mut().inner).poll_flush(cx)
    }

    fn poll_shutdown(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<std::io::Result<()>> {
        Pin::new(&mut self.get_mut().inner).poll_shutdown(cx)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn garbage_is_no_frame_and_no_command() {
        // What a device at the wrong rate writes is not understood: a frame's start
        // delimiter and `+++` do not survive.
        let mut bytes = *b"\x7E+++ATAP\r";
        garble(&mut bytes);
        assert!(!bytes.contains(&0x7E));
        assert!(!bytes.contains(&b'+'));
        assert_ne!(&bytes, b"\x7E+++ATAP\r");
    }
}
