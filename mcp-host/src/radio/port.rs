//! The task serving one node: opens its byte stream (again after a disconnection),
//! decodes the frames its device writes and writes the frames the network sends it.

use std::collections::VecDeque;
use std::pin::Pin;
use std::sync::{Arc, Mutex};
use std::task::{Context, Poll};
use std::time::Duration;

use bytes::BytesMut;
use futures::{FutureExt, StreamExt};
use tokio::io::{AsyncRead, AsyncWrite, AsyncWriteExt, ReadBuf};
use tokio::sync::mpsc;
use tokio::time::{Instant, sleep_until};
use tokio_util::codec::{BytesCodec, Decoder, FramedRead};
use xbee_api::Address64;

use super::command_mode::{CommandMode, Step};
use super::router::{LinkMode, OUT_CAPACITY, Out, State};
use super::uart::Uart;
use crate::codec::{CodecItem, MAX_REQUEST_DATA, XBeeCodec};
use crate::mutex::lock;
use crate::options::ReconnectPolicy;
use crate::pty::{PtyPort, PtyStream};
use crate::repeats::Repeats;
use crate::transport::Connector;

/// The peer of a node added as a byte stream.
pub(crate) const IN_PROCESS: &str = "in-process";

/// A byte stream to a device.
pub(crate) trait Io: AsyncRead + AsyncWrite + Send + Unpin {}
impl<T: AsyncRead + AsyncWrite + Send + Unpin> Io for T {}

/// Where a node's byte streams come from.
pub(crate) enum Source {
    /// A link, reopened after each disconnection.
    Link {
        connector: Box<Connector>,
        policy: ReconnectPolicy,
        opened: bool,
    },
    /// A pseudo-terminal: up while a peer has its far end open.
    Pty(PtyPort),
    /// One stream; the node is gone when it ends.
    Once(Option<Box<dyn Io>>),
}

/// An open byte stream to a device.
enum Stream {
    /// A link's transport or a stream given to the network.
    Boxed(Box<dyn Io>),
    /// A pseudo-terminal's master side, given back to its [`PtyPort`] when its peer
    /// leaves.
    Pty(PtyStream),
}

impl AsyncRead for Stream {
    fn poll_read(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &mut ReadBuf<'_>,
    ) -> Poll<std::io::Result<()>> {
        match self.get_mut() {
            Stream::Boxed(io) => Pin::new(io).poll_read(cx, buf),
            Stream::Pty(io) => Pin::new(io).poll_read(cx, buf),
        }
    }
}

impl AsyncWrite for Stream {
    fn poll_write(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &[u8],
    ) -> Poll<std::io::Result<usize>> {
        match self.get_mut() {
            Stream::Boxed(io) => Pin::new(io).poll_write(cx, buf),
            Stream::Pty(io) => Pin::new(io).poll_write(cx, buf),
        }
    }

    fn poll_flush(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<std::io::Result<()>> {
        match self.get_mut() {
            Stream::Boxed(io) => Pin::new(io).poll_flush(cx),
            Stream::Pty(io) => Pin::new(io).poll_flush(cx),
        }
    }

    fn poll_shutdown(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<std::io::Result<()>> {
        match self.get_mut() {
            Stream::Boxed(io) => Pin::new(io).poll_shutdown(cx),
            Stream::Pty(io) => Pin::new(io).poll_shutdown(cx),
        }
    }
}

impl Source {
    /// The next stream and a description of the peer, or `None` when there will be none
    /// (a link that ended for good is marked so in `state`).
    async fn next(&mut self, state: &Mutex<State>, node: Address64) -> Option<(Stream, String)> {
        match self {
            Source::Once(io) => io
                .take()
                .map(|io| (Stream::Boxed(io), IN_PROCESS.to_owned())),
            Source::Pty(port) => {
                let peer = port.path().display().to_string();
                port.peer().await.map(|io| (Stream::Pty(io), peer))
            }
            Source::Link {
                connector,
                policy,
                opened,
            } => loop {
                let result = if *opened {
                    connector.reopen(policy).await
                } else {
                    *opened = true;
                    connector.open().await
                };
                match result {
                    Ok(t) => {
                        let peer = t.peer().to_owned();
                        return Some((Stream::Boxed(Box::new(t)), peer));
                    }
                    Err(e) if e.is_retryable() => {
                        let link = connector.link();
                        tracing::warn!(%node, %link, error = %e, "node link not available yet");
                    }
                    Err(e) => {
                        // Reported as an event, for whoever runs the network to say (and
                        // to stop, if the node was all it was for).
                        let link = connector.link();
                        tracing::debug!(%node, %link, error = %e, "node link ended");
                        lock(state).link_ended(node, e.to_string());
                        return None;
                    }
                }
            },
        }
    }

    fn mark_healthy(&mut self) {
        if let Source::Link { connector, .. } = self {
            connector.mark_healthy();
        }
    }

    /// Lets go of the link's resources, waiting until they are (a port is free).
    async fn shutdown(&mut self) {
        if let Source::Link { connector, .. } = self {
            connector.shutdown().await;
        }
    }

    /// Takes back a stream that ended.
    fn give_back(&mut self, stream: Stream) {
        if let (Source::Pty(port), Stream::Pty(io)) = (self, stream) {
            port.give_back(io);
        }
    }
}

/// Serves a node until its source runs dry or the network is shut down.
pub(crate) async fn run(
    shutdown: tokio_util::sync::CancellationToken,
    state: Arc<Mutex<State>>,
    addr: Address64,
    mut source: Source,
    out: mpsc::Receiver<Out>,
) {
    tokio::select! {
        () = shutdown.cancelled() => {}
        () = run_node(state, addr, &mut source, out) => {}
    }
    // Before the network's stop returns: a `tcp-listen` port is free then.
    source.shutdown().await;
}

async fn run_node(
    state: Arc<Mutex<State>>,
    addr: Address64,
    source: &mut Source,
    mut out: mpsc::Receiver<Out>,
) {
    // A single stream is up from the start: the network marked the node connected
    // when it was added.
    let mut up_already = matches!(source, Source::Once(_));
    while let Some((mut io, peer)) = source.next(&state, addr).await {
        if !std::mem::take(&mut up_already) {
            // Frames queued while the link was down are stale.
            while out.try_recv().is_ok() {}
            lock(&state).connected(addr, peer);
        }
        let (reason, healthy) = serve(&state, addr, &mut io, &mut out).await;
        if healthy {
            source.mark_healthy();
        }
        source.give_back(io);
        let ended = matches!(reason, End::NetworkGone);
        let mut shared = lock(&state);
        // A hang-up asked for as this stream ended on its own is for this stream alone,
        // not the next.
        if let Some(node) = shared.nodes.get(&addr) {
            let _ = node.hangup.notified().now_or_never();
        }
        shared.disconnected(addr, reason.to_string());
        drop(shared);
        if ended {
            return;
        }
    }
}

enum End {
    Closed,
    Io(std::io::Error),
    NetworkGone,
    HungUp,
}

impl std::fmt::Display for End {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            End::Closed => f.write_str("the peer closed the link"),
            End::Io(e) => write!(f, "{e}"),
            End::NetworkGone => f.write_str("the network was shut down"),
            End::HungUp => f.write_str("the network hung up (Network::disconnect)"),
        }
    }
}

/// Serves one stream until it ends: why, and whether it carried a frame from the device.
async fn serve(
    state: &Mutex<State>,
    addr: Address64,
    io: &mut Stream,
    out: &mut mpsc::Receiver<Out>,
) -> (End, bool) {
    let mut healthy = false;
    // Frames for the device dropped because its write queue was full (each counted in
    // `NodeStats::overflow`): a device that sends requests and reads none of the
    // answers fills its queue at the pace it writes.
    let mut overflow = Repeats::default();
    let end = serve_until_end(state, addr, io, out, &mut healthy, &mut overflow).await;
    say_overflow_rest(addr, &mut overflow);
    (end, healthy)
}

/// How long a partial frame from a device in API mode 1 waits for its next byte before
/// it is given up and the bytes after its start delimiter scanned again, as a link
/// does by default ([`crate::LinkOptions::partial_frame_timeout`]): a stray 0x7E on a
/// noisy line would otherwise hold the frames behind it back until its length is
/// reached, on a quiet line for ever.
const PARTIAL_FRAME_TIMEOUT: Option<Duration> = Some(crate::options::DEFAULT_PARTIAL_FRAME_TIMEOUT);

/// Says the frames dropped for a full write queue and not said yet.
fn say_overflow_rest(addr: Address64, overflow: &mut Repeats) {
    if let Some(more) = overflow.take_rest() {
        tracing::warn!(node = %addr, "write queue full: {more} more frames dropped");
    }
}

async fn serve_until_end(
    state: &Mutex<State>,
    addr: Address64,
    io: &mut Stream,
    out: &mut mpsc::Receiver<Out>,
    healthy: &mut bool,
    overflow: &mut Repeats,
) -> End {
    // A device on a pseudo-terminal set to another rate than its radio's UART's.
    let rate_probe = match &*io {
        Stream::Pty(pty) => pty.rate_probe(),
        Stream::Boxed(_) => None,
    };
    let mismatched = move || -> bool {
        let Some(probe) = &rate_probe else {
            return false;
        };
        let radio = lock(state).uart_rate(addr);
        radio.is_some_and(|radio| probe.baud_rate().is_some_and(|device| device != radio))
    };
    let (reader, writer) = tokio::io::split(io);
    let reader = Uart {
        inner: reader,
        mismatched: &mismatched,
    };
    let mut writer = Uart {
        inner: writer,
        mismatched: &mismatched,
    };
    let (mut link_mode, relink, hangup) = {
        let state = lock(state);
        let node = state.nodes.get(&addr);
        let relink = node.map(|node| node.relink.clone());
        let hangup = node.map(|node| node.hangup.clone());
        (
            state.link_mode(addr),
            relink.unwrap_or_default(),
            hangup.unwrap_or_default(),
        )
    };
    let mut command_mode = (link_mode == LinkMode::Transparent).then(CommandMode::new);
    let mut frames = FramedRead::new(reader, NodeCodec::new(link_mode));
    let mut pending: VecDeque<Out> = VecDeque::new();
    let mut held: Option<(Out, Instant)> = None;
    // What the reader gave outside its branch below (a partial frame given up), to be
    // handled there first.
    let mut early: VecDeque<Option<std::io::Result<Input>>> = VecDeque::new();
    loop {
        let next_at = pending.front().map(|o| o.at);
        let held_until = held.as_ref().map(|(_, until)| *until);
        let command_due = command_mode.as_ref().and_then(CommandMode::deadline);
        let check_stale_at = frames
            .decoder()
            .api()
            .and_then(|codec| codec.stale_check_at(PARTIAL_FRAME_TIMEOUT));
        let overflow_due = overflow.due_at();
        let steps = tokio::select! {
            item = next_input(&mut early, &mut frames) => match item {
                Some(Ok(Input::Frame(CodecItem::Frame(frame)))) => {
                    *healthy = true;
                    let now = {
                        let mut state = lock(state);
                        state.handle(addr, frame.data());
                        state.link_mode(addr)
                    };
                    // `AP` set in that frame: what the device writes from here on is
                    // read the new way.
                    relink_to(now, &mut link_mode, &mut command_mode, &mut frames);
                    continue;
                }
                Some(Ok(Input::Frame(CodecItem::Error(error)))) => {
                    lock(state).decode_error(addr, error);
                    continue;
                }
                Some(Ok(Input::Bytes(bytes))) => {
                    *healthy = true;
                    let Some(command_mode) = &mut command_mode else { continue };
                    command_mode.on_bytes(Instant::now(), &bytes, |command, value| {
                        lock(state).command_line(addr, command, value)
                    })
                }
                Some(Err(e)) => return End::Io(e),
                None => return End::Closed,
            },
            () = hangup.notified() => return End::HungUp,
            // `AP` set remotely (or in the frame just read: nothing left to do then).
            () = relink.notified() => {
                let now = lock(state).link_mode(addr);
                relink_to(now, &mut link_mode, &mut command_mode, &mut frames);
                continue;
            },
            () = sleep_until(command_due.unwrap_or_else(Instant::now)), if command_due.is_some() => {
                command_mode
                    .as_mut()
                    .and_then(|c| c.on_deadline(Instant::now()))
                    .into_iter()
                    .collect()
            },
            item = out.recv() => match item {
                Some(item) if pending.len() < OUT_CAPACITY => {
                    pending.push_back(item);
                    continue;
                }
                Some(_) => {
                    if let Some(node) = lock(state).nodes.get_mut(&addr) {
                        node.stats.overflow += 1;
                    }
                    match overflow.count(Instant::now()) {
                        Some(0) => tracing::warn!(node = %addr, "write queue full: frame dropped"),
                        Some(more) => tracing::warn!(
                            node = %addr,
                            "write queue full: frame dropped ({more} more since the last line)"
                        ),
                        None => {}
                    }
                    continue;
                }
                None => return End::NetworkGone,
            },
            () = sleep_until(overflow_due.unwrap_or_else(Instant::now)), if overflow_due.is_some() => {
                say_overflow_rest(addr, overflow);
                continue;
            },
            () = sleep_until(check_stale_at.unwrap_or_else(Instant::now)), if check_stale_at.is_some() => {
                // Bytes may be waiting unread (this task ran late): they come first, and
                // the next turn looks again.
                if let Some(item) = frames.next().now_or_never() {
                    early.push_back(item);
                } else if let Some(codec) = frames.decoder_mut().api_mut() {
                    if codec.is_stale(PARTIAL_FRAME_TIMEOUT, Instant::now()) {
                        let items = codec.drop_partial();
                        early.extend(items.into_iter().map(|item| Some(Ok(Input::Frame(item)))));
                    }
                }
                continue;
            },
            () = sleep_until(next_at.unwrap_or_else(Instant::now)), if next_at.is_some() => {
                let Some(item) = pending.pop_front() else { continue };
                if let (Some(window), None) = (item.reorder, &held) {
                    let until = crate::options::later(Instant::now(), window);
                    held = Some((item, until));
                    continue;
                }
                if let Err(e) = write_out(&mut writer, &item, state, addr).await {
                    return End::Io(e);
                }
                if let Some((item, _)) = held.take() {
                    if let Err(e) = write_out(&mut writer, &item, state, addr).await {
                        return End::Io(e);
                    }
                }
                continue;
            },
            () = sleep_until(held_until.unwrap_or_else(Instant::now)), if held_until.is_some() => {
                if let Some((item, _)) = held.take() {
                    if let Err(e) = write_out(&mut writer, &item, state, addr).await {
                        return End::Io(e);
                    }
                }
                continue;
            },
        };
        for step in steps {
            match step {
                Step::Enter => {
                    // What was queued for the device before is not written into the
                    // answers, and nothing more is queued until command mode ends.
                    {
                        let mut state = lock(state);
                        state.enter_command_mode(addr);
                        while out.try_recv().is_ok() {}
                    }
                    pending.clear();
                    held = None;
                    if let Err(e) = write(&mut writer, b"OK\r").await {
                        return End::Io(e);
                    }
                }
                Step::Answer(line) => {
                    if let Err(e) = write(&mut writer, &line).await {
                        return End::Io(e);
                    }
                }
                Step::Leave { ap, rest } => {
                    link_mode = lock(state).leave_command_mode(addr, ap);
                    if let LinkMode::Api(_) = link_mode {
                        // What the device wrote after `ATCN` is for the API decoder.
                        command_mode = None;
                        *frames.decoder_mut() = NodeCodec::new(link_mode);
                        frames.read_buffer_mut().extend_from_slice(&rest);
                    }
                }
            }
        }
    }
}

/// The next of what the device wrote: what waits in `early` first, then what `frames`
/// reads.
async fn next_input<R: AsyncRead + Unpin>(
    early: &mut VecDeque<Option<std::io::Result<Input>>>,
    frames: &mut FramedRead<R, NodeCodec>,
) -> Option<std::io::Result<Input>> {
    match early.pop_front() {
        Some(item) => item,
        None => frames.next().await,
    }
}

/// Reads what the device writes the way its radio speaks `now`, if that is no longer
/// `link_mode`: with a new decoder, and AT command mode in transparent mode.
fn relink_to<R>(
    now: LinkMode,
    link_mode: &mut LinkMode,
    command_mode: &mut Option<CommandMode>,
    frames: &mut FramedRead<R, NodeCodec>,
) {
    if now != *link_mode {
        *link_mode = now;
        *command_mode = (now == LinkMode::Transparent).then(CommandMode::new);
        *frames.decoder_mut() = NodeCodec::new(now);
    }
}

/// What a device writes to its radio: frames in API mode, bytes in transparent mode.
enum Input {
    Frame(CodecItem),
    Bytes(BytesMut),
}

/// The decoder of a device's writes, for the radio's mode.
enum NodeCodec {
    Api(XBeeCodec),
    Transparent(BytesCodec),
}

impl NodeCodec {
    /// In API mode, frames up to [`MAX_REQUEST_DATA`]: a device writes no longer ones.
    fn new(mode: LinkMode) -> Self {
        match mode {
            LinkMode::Api(mode) => NodeCodec::Api(XBeeCodec::with_counters(
                mode,
                MAX_REQUEST_DATA,
                Arc::default(),
            )),
            LinkMode::Transparent => NodeCodec::Transparent(BytesCodec::new()),
        }
    }

    /// The frame decoder, in API mode.
    fn api(&self) -> Option<&XBeeCodec> {
        match self {
            NodeCodec::Api(codec) => Some(codec),
            NodeCodec::Transparent(_) => None,
        }
    }

    fn api_mut(&mut self) -> Option<&mut XBeeCodec> {
        match self {
            NodeCodec::Api(codec) => Some(codec),
            NodeCodec::Transparent(_) => None,
        }
    }
}

impl Decoder for NodeCodec {
    type Item = Input;
    type Error = std::io::Error;

    fn decode(&mut self, src: &mut BytesMut) -> Result<Option<Input>, std::io::Error> {
        match self {
            NodeCodec::Api(codec) => Ok(codec.decode(src)?.map(Input::Frame)),
            NodeCodec::Transparent(codec) => Ok(codec.decode(src)?.map(Input::Bytes)),
        }
    }

    fn decode_eof(&mut self, src: &mut BytesMut) -> Result<Option<Input>, std::io::Error> {
        match self {
            NodeCodec::Api(codec) => Ok(codec.decode_eof(src)?.map(Input::Frame)),
            NodeCodec::Transparent(codec) => Ok(codec.decode_eof(src)?.map(Input::Bytes)),
        }
    }
}

/// Writes what the radio queued for its device, then takes the UART rate it comes with.
async fn write_out<W: AsyncWrite + Unpin>(
    writer: &mut W,
    item: &Out,
    state: &Mutex<State>,
    addr: Address64,
) -> std::io::Result<()> {
    write(writer, &item.bytes).await?;
    if item.uart_after.is_some() {
        lock(state).set_uart(addr, item.uart_after);
    }
    Ok(())
}

async fn write<W: AsyncWrite + Unpin>(writer: &mut W, bytes: &[u8]) -> std::io::Result<()> {
    writer.write_all(bytes).await?;
    writer.flush().await
}
