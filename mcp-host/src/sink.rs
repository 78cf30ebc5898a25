//! [`PacketSink`]: MCP packets sent as a [`Sink`], the other half of the
//! [`PacketStream`](crate::PacketStream).

use std::fmt;
use std::future::Future;
use std::marker::PhantomData;
use std::pin::Pin;
use std::sync::Arc;
use std::task::{Context, Poll};

use bytes::Bytes;
use futures::{Sink, Stream, StreamExt};
use tokio::sync::{mpsc, oneshot, watch};
use tokio_util::sync::PollSender;
use xbee_api::{Address64, EncodeFrame, TransmitRequestRepr};

use crate::driver::{CloseRequest, Op};
use crate::{LinkState, SendError};

/// A [`Sink`] of MCP packets, each item `(to, packet)` sent to the MAV `to` (or
/// [`Address64::BROADCAST`]) in a Transmit Request with frame id 0: the radio sends no
/// transmit status, and nothing is awaited, as
/// [`SendOptions`](crate::SendOptions) with [`FrameId::None`](crate::FrameId::None)
/// sends. For a stream of packets fed to a link, with the sink's combinators
/// (`send_all`, `forward`); to know that a packet was delivered, use
/// [`CommandSender::send_packet`](crate::CommandSender::send_packet).
///
/// Made by [`CommandSender::packet_sink`](crate::CommandSender::packet_sink). The sink
/// waits for room in the link's queue (`poll_ready`), so a fast stream is held back,
/// never buffered without bound. `poll_flush` (and so `send`, `send_all`, `close`) is
/// ready once the link's task has taken the packets from that queue and put them in
/// line for the transport, which it writes in the background.
///
/// While the link is not connected (before its first connection, or between a
/// disconnection and the reconnection) the sink is not ready: a stream fed to it waits,
/// and goes on once the link is up again. Only packets handed over just as the
/// transport failed, before the link saw it, are lost with it, as a radio loses a frame
/// it sent without a status. A packet handed over before
/// [`CommandSender::close`](crate::CommandSender::close) is written out before the link
/// ends (within a second); one handed over after it is refused with
/// [`SendError::Closed`], as the sender's requests are.
///
/// Errors: [`SendError::TooLarge`] for a packet over the 255-byte payload (from
/// `start_send`: driving the sink by hand, the next packet goes; `send_all` and
/// `forward` stop at the first error), and [`SendError::Closed`] once the link has
/// ended.
///
/// Closing the sink closes it alone: the link and its other senders go on. It flushes
/// first, so it waits as `poll_flush` does, for as long as the link's queue is full (a
/// radio that takes no bytes); dropping the sink waits for nothing. A sink keeps the link
/// open, as a [`CommandSender`](crate::CommandSender) does, until it is dropped.
///
/// Packets go out in order among themselves and with other writes without a frame id
/// (`send_with` and [`FrameId::None`](crate::FrameId::None), `write_frame`). Requests
/// that await an answer go through another queue: a request sent once the sink is
/// flushed (`sink.send(..).await`, then `sender.request(..)`) goes out after its
/// packets, while one sent meanwhile from another task may go before them.
///
/// The item's packet holds its bytes in `B` (`Bytes`, `&[u8]`, `Vec<u8>`...), which the
/// items sent fix: a sink fed [`Received`](crate::Received) packets takes
/// `Packet<Bytes>`, one fed packets built in place `Packet<&[u8]>` (`packet.map_bytes(Bytes::copy_from_slice)` makes the first
/// of the second, `as_borrowed` the second of the first). Name it where nothing else
/// does: `sender.packet_sink::<Bytes>()`.
///
/// ```no_run
/// # async fn run(sender: mcp_host::CommandSender) -> Result<(), mcp_host::SendError> {
/// use futures::{SinkExt, stream};
/// use mcp_host::mcp_core::{Command, Packet};
///
/// let mav = "0013A20040B599B9".parse().unwrap();
/// let mut sink = sender.packet_sink();
/// let commands = [Command::landing(false), Command::landing(true)];
/// let mut packets = stream::iter(commands.map(|c| Ok((mav, Packet::<&[u8]>::Command(c)))));
/// sink.send_all(&mut packets).await?;
/// # Ok(())
/// # }
/// ```
pub struct PacketSink<B = Bytes> {
    writes: PollSender<Op>,
    /// Held, never sent on, so that the link's task sees when the last handle that can
    /// send is gone (see [`CommandSender`](crate::CommandSender)).
    _alive: mpsc::Sender<()>,
    /// The answer of the last packet handed over and not yet flushed: the link's task
    /// takes the queue's packets in order, so once it took this one it took them all.
    last: Option<oneshot::Receiver<Result<(), SendError>>>,
    /// The link's state as last seen.
    state: LinkState,
    /// The link's state changes, each as it comes.
    changes: Pin<Box<dyn Stream<Item = LinkState> + Send + Sync>>,
    /// [`CommandSender::close`](crate::CommandSender::close)'s request: packets after
    /// it are refused, as the sender's requests are.
    close: Arc<CloseRequest>,
    /// The packets' bytes: `Bytes`, `&[u8]`, `Vec<u8>`...
    packets: PhantomData<fn(B)>,
}

impl<B> PacketSink<B> {
    pub(crate) fn new(
        writes: mpsc::Sender<Op>,
        alive: mpsc::Sender<()>,
        state: watch::Receiver<LinkState>,
        close: Arc<CloseRequest>,
    ) -> Self {
        let now = *state.borrow();
        let changes = futures::stream::unfold(state, |mut state| async move {
            state.changed().await.ok()?;
            let now = *state.borrow_and_update();
            Some((now, state))
        })
        .fuse();
        Self {
            writes: PollSender::new(writes),
            _alive: alive,
            last: None,
            state: now,
            changes: Box::pin(changes),
            close,
            packets: PhantomData,
        }
    }
}

impl<B> fmt::Debug for PacketSink<B> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("PacketSink")
            .field("closed", &self.writes.is_closed())
            .finish_non_exhaustive()
    }
}

impl<B: AsRef<[u8]>> Sink<(Address64, mcp_core::Packet<B>)> for PacketSink<B> {
    type Error = SendError;

    fn poll_ready(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<Result<(), SendError>> {
        let this = self.get_mut();
        if this.close.asked() {
            return Poll::Ready(Err(SendError::Closed));
        }
        // The newest state, and a wake-up at the next change. A link that has closed
        // stays closed: its changes, ended, are not polled again.
        while this.state != LinkState::Closed {
            match this.changes.as_mut().poll_next(cx) {
                Poll::Ready(Some(state)) => this.state = state,
                Poll::Ready(None) => this.state = LinkState::Closed,
                Poll::Pending => break,
            }
        }
        match this.state {
            LinkState::Connected => this.writes.poll_reserve(cx).map_err(|_| SendError::Closed),
            LinkState::Closed => Poll::Ready(Err(SendError::Closed)),
            // Not connected yet, or reconnecting: held back until the link is up.
            _ => Poll::Pending,
        }
    }

    fn start_send(
        self: Pin<&mut Self>,
        (to, packet): (Address64, mcp_core::Packet<B>),
    ) -> Result<(), SendError> {
        let data = transmit_frame_data(to, &packet)?;
        // Answered once the link's task has taken it (`poll_flush` waits for that).
        let (reply, taken) = oneshot::channel();
        let this = self.get_mut();
        this.writes
            .send_item(Op::Write {
                data,
                deadline: None,
                reply,
            })
            .map_err(|_| SendError::Closed)?;
        this.last = Some(taken);
        Ok(())
    }

    fn poll_flush(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<Result<(), SendError>> {
        let this = self.get_mut();
        let Some(taken) = &mut this.last else {
            return Poll::Ready(Ok(()));
        };
        let result = match Pin::new(taken).poll(cx) {
            Poll::Pending => return Poll::Pending,
            // Taken, or lost with a transport that failed first, as a radio loses a
            // frame it sent without a status: the sink goes on once the link is up.
            Poll::Ready(Ok(Ok(()) | Err(SendError::Disconnected { .. }))) => Ok(()),
            Poll::Ready(Ok(Err(error))) => Err(error),
            // Dropped unanswered: the link ended first.
            Poll::Ready(Err(_)) => Err(SendError::Closed),
        };
        this.last = None;
        Poll::Ready(result)
    }

    fn poll_close(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<Result<(), SendError>> {
        let flushed = std::task::ready!(self.as_mut().poll_flush(cx));
        self.get_mut().writes.close();
        Poll::Ready(flushed)
    }
}

/// The frame data of a Transmit Request with frame id 0 carrying `packet` to `to`.
fn transmit_frame_data<B: AsRef<[u8]>>(
    to: Address64,
    packet: &mcp_core::Packet<B>,
) -> Result<Bytes, SendError> {
    let payload = crate::sender::encode_packet(packet)?;
    let request = TransmitRequestRepr {
        frame_id: 0,
        ..TransmitRequestRepr::unicast(to, &payload)
    };
    let mut data = vec![0u8; request.frame_data_len()];
    // Room for the frame data it announces: it cannot fail.
    request
        .emit_frame_data(&mut data)
        .map_err(|_| SendError::TooLarge {
            len: payload.len(),
            max: mcp_core::MAX_PAYLOAD,
        })?;
    Ok(Bytes::from(data))
}
