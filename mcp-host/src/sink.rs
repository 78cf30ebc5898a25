//! [`PacketSink`]: MCP packets sent as a [`Sink`], the other half of the
//! [`PacketStream`](crate::PacketStream).

use std::fmt;
use std::marker::PhantomData;
use std::pin::Pin;
use std::task::{Context, Poll};

use bytes::Bytes;
use futures::Sink;
use tokio::sync::oneshot;
use tokio_util::sync::PollSender;
use xbee_api::{Address64, EncodeFrame, TransmitRequestRepr};

use crate::SendError;
use crate::driver::Op;

/// A [`Sink`] of MCP packets, each item `(to, packet)` sent to the MAV `to` (or
/// [`Address64::BROADCAST`]) in a Transmit Request with frame id 0: the radio sends no
/// transmit status, and nothing is awaited, as
/// [`SendOptions`](crate::SendOptions) with [`FrameId::None`](crate::FrameId::None)
/// sends. For a stream of packets fed to a link, with the sink's combinators
/// (`send_all`, `forward`); to know that a packet was delivered, use
/// [`CommandSender::send_packet`](crate::CommandSender::send_packet).
///
/// `B` holds a packet's bytes: [`Bytes`], as the [`PacketStream`](crate::PacketStream)'s
/// packets have them (the default), `&[u8]`, `Vec<u8>`...
///
/// Made by [`CommandSender::packet_sink`](crate::CommandSender::packet_sink). Packets
/// go out in the order they are sent, behind anything queued before them without a
/// frame id. The sink waits for room in the link's queue (`poll_ready`), so a fast
/// stream is held back, never buffered without bound. `poll_flush` is ready once the
/// packets are in that queue; the link's task writes them in the background.
///
/// Errors: [`SendError::TooLarge`] for a packet over the 255-byte payload (from
/// `start_send`; the sink takes the next one), and [`SendError::Closed`] once the link
/// has ended. A packet sent while the link is not connected (before its first
/// connection, or between a disconnection and the reconnection) is dropped, as a radio
/// drops a frame it cannot send without a status: watch
/// [`CommandSender::link_state`](crate::CommandSender::link_state) to hold a stream back
/// meanwhile.
///
/// Closing the sink closes it alone: the link and its other senders go on.
///
/// ```no_run
/// # async fn run(sender: mcp_host::CommandSender) -> Result<(), mcp_host::SendError> {
/// use futures::{SinkExt, stream};
/// use mcp_core::{Command, Packet};
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
    /// The packets' bytes: `Bytes`, `&[u8]`, `Vec<u8>`...
    packets: PhantomData<fn(B)>,
}

impl<B> PacketSink<B> {
    pub(crate) fn new(writes: tokio::sync::mpsc::Sender<Op>) -> Self {
        Self {
            writes: PollSender::new(writes),
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
        self.get_mut()
            .writes
            .poll_reserve(cx)
            .map_err(|_| SendError::Closed)
    }

    fn start_send(
        self: Pin<&mut Self>,
        (to, packet): (Address64, mcp_core::Packet<B>),
    ) -> Result<(), SendError> {
        let data = transmit_frame_data(to, &packet)?;
        // Nobody waits for the answer: a write is written all the same.
        let (reply, _) = oneshot::channel();
        self.get_mut()
            .writes
            .send_item(Op::Write { data, reply })
            .map_err(|_| SendError::Closed)
    }

    fn poll_flush(self: Pin<&mut Self>, _: &mut Context<'_>) -> Poll<Result<(), SendError>> {
        Poll::Ready(Ok(()))
    }

    fn poll_close(self: Pin<&mut Self>, _: &mut Context<'_>) -> Poll<Result<(), SendError>> {
        self.get_mut().writes.close();
        Poll::Ready(Ok(()))
    }
}

/// The frame data of a Transmit Request with frame id 0 carrying `packet` to `to`.
fn transmit_frame_data<B: AsRef<[u8]>>(
    to: Address64,
    packet: &mcp_core::Packet<B>,
) -> Result<Bytes, SendError> {
    let too_large = || SendError::TooLarge {
        len: packet.encoded_len(),
        max: mcp_core::MAX_PAYLOAD,
    };
    let mut payload = [0u8; mcp_core::MAX_PAYLOAD];
    let len = packet.encode(&mut payload).map_err(|_| too_large())?;
    let request = TransmitRequestRepr {
        frame_id: 0,
        ..TransmitRequestRepr::unicast(to, payload.get(..len).ok_or_else(too_large)?)
    };
    let mut data = vec![0u8; request.frame_data_len()];
    request
        .emit_frame_data(&mut data)
        .map_err(|_| too_large())?;
    Ok(Bytes::from(data))
}
