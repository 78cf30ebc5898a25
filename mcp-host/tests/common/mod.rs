//! A fake XBee radio for tests: the far side of a link, speaking XBee API frames encoded
//! and decoded with `xbee-api`.

#![allow(dead_code, unreachable_pub)]

pub mod hub_wire;

use std::time::Duration;

use bytes::BytesMut;
use futures::StreamExt;
use mcp_host::{Event, LinkEvent, PacketStream};
use tokio::io::{AsyncRead, AsyncReadExt, AsyncWrite, AsyncWriteExt};
use xbee_api::{
    Address16, Address64, ApiMode, DeliveryStatus, DiscoveryStatus, EncodeFrame,
    ExplicitRxIndicatorRepr, ReceivePacketRepr, TransmitRequestRepr, TransmitStatusRepr,
};

/// Failure guard only: every wait ends on an event long before this.
pub const GUARD: Duration = Duration::from_secs(20);

pub const MAV: Address64 = Address64(0x0013_A200_40B5_99B9);
pub const OTHER_MAV: Address64 = Address64(0x0013_A200_40B5_99BF);

/// An Explicit Rx Indicator (0x91) as a radio in AO=1 hands over `data` from `src64`:
/// Digi's data endpoints (0xE8), the transparent-data cluster (0x0011) and profile
/// (0xC105), acknowledged.
pub fn explicit_rx(src64: Address64, data: &[u8]) -> ExplicitRxIndicatorRepr<'_> {
    ExplicitRxIndicatorRepr {
        src64,
        src16: Address16(0x0102),
        src_endpoint: 0xE8,
        dst_endpoint: 0xE8,
        cluster_id: 0x0011,
        profile_id: 0xC105,
        options: 0x02,
        data,
    }
}

/// Byte stream of the far side.
pub trait Io: AsyncRead + AsyncWrite + Unpin + Send {}
impl<T: AsyncRead + AsyncWrite + Unpin + Send> Io for T {}

/// The radio side of a link.
pub struct FakeXBee {
    io: Box<dyn Io>,
    mode: ApiMode,
    decoder: Box<xbee_api::Decoder>,
    pending: BytesMut,
}

/// A Transmit Request as the fake radio received it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Tx {
    pub frame_id: u8,
    pub dst64: Address64,
    pub dst16: Address16,
    pub radius: u8,
    pub options: u8,
    pub data: Vec<u8>,
}

impl FakeXBee {
    pub fn new(io: impl Io + 'static, mode: ApiMode) -> Self {
        FakeXBee {
            io: Box::new(io),
            mode,
            decoder: Box::new(xbee_api::Decoder::new(mode)),
            pending: BytesMut::new(),
        }
    }

    /// Opens the far end of a `pty` link.
    pub fn open_pty(path: &std::path::Path, mode: ApiMode) -> Self {
        let port = tokio_serial::SerialStream::open(&tokio_serial::new(
            path.to_str().expect("utf-8 path"),
            115_200,
        ))
        .expect("open the pty far end");
        Self::new(port, mode)
    }

    /// The next frame the host wrote (frame data, type first), skipping decode errors.
    pub async fn next_frame(&mut self) -> Vec<u8> {
        tokio::time::timeout(GUARD, self.next_frame_inner())
            .await
            .expect("no frame from the host")
    }

    async fn next_frame_inner(&mut self) -> Vec<u8> {
        loop {
            let (consumed, event) = self.decoder.decode(&self.pending);
            let frame = match event {
                Some(Ok(frame)) => Some(frame.data().to_vec()),
                Some(Err(e)) => panic!("host wrote a corrupt frame: {e}"),
                None => None,
            };
            let _ = self.pending.split_to(consumed);
            if let Some(frame) = frame {
                return frame;
            }
            // All input taken, nothing pending: read more.
            let mut buf = [0u8; 512];
            let n = self.io.read(&mut buf).await.expect("fake radio read");
            assert!(n > 0, "host closed the link");
            self.pending.extend_from_slice(&buf[..n]);
        }
    }

    /// The next Transmit Request the host wrote (panics on any other frame).
    pub async fn next_tx(&mut self) -> Tx {
        let data = self.next_frame().await;
        let tx = TransmitRequestRepr::parse_bytes(&data).expect("a Transmit Request");
        assert_eq!(data[0], 0x10);
        Tx {
            frame_id: tx.frame_id,
            dst64: tx.dst64,
            dst16: tx.dst16,
            radius: tx.radius,
            options: tx.options,
            data: tx.data.to_vec(),
        }
    }

    /// Encodes and writes a frame.
    pub async fn send(&mut self, frame: &impl EncodeFrame) {
        let mut buf = vec![0u8; frame.encoded_len(self.mode)];
        let n = frame.encode(self.mode, &mut buf).expect("encode");
        self.write_raw(&buf[..n]).await;
    }

    /// Encodes a frame into bytes (for tests that splice garbage around it).
    pub fn encode(&self, frame: &impl EncodeFrame) -> Vec<u8> {
        let mut buf = vec![0u8; frame.encoded_len(self.mode)];
        let n = frame.encode(self.mode, &mut buf).expect("encode");
        buf.truncate(n);
        buf
    }

    /// Writes raw bytes.
    pub async fn write_raw(&mut self, bytes: &[u8]) {
        self.io.write_all(bytes).await.expect("fake radio write");
        self.io.flush().await.expect("fake radio flush");
    }

    /// Answers a Transmit Request with a Transmit Status.
    pub async fn status(&mut self, frame_id: u8, delivery: DeliveryStatus) {
        self.send(&TransmitStatusRepr {
            frame_id,
            dst16: Address16(0x1234),
            retries: 0,
            delivery,
            discovery: DiscoveryStatus::from(0),
        })
        .await;
    }

    /// Sends an MCP payload as a Receive Packet from `src`.
    pub async fn receive(&mut self, src: Address64, payload: &[u8]) {
        self.send(&rx(src, payload)).await;
    }

    /// Shuts the byte stream down.
    pub async fn close(mut self) {
        let _ = self.io.shutdown().await;
    }
}

/// A Receive Packet from `src` (16-bit 0x7D33, acknowledged).
pub fn rx(src: Address64, payload: &[u8]) -> ReceivePacketRepr<'_> {
    ReceivePacketRepr {
        src64: src,
        src16: Address16(0x7D33),
        options: 0x01,
        data: payload,
    }
}

/// Encodes an MCP packet.
pub fn mcp<B: AsRef<[u8]>>(packet: &mcp_core::Packet<B>) -> Vec<u8> {
    let mut buf = [0u8; mcp_core::MAX_PAYLOAD];
    let n = packet.encode(&mut buf).expect("encode MCP packet");
    buf[..n].to_vec()
}

/// The next event of the stream (failure guard: GUARD).
pub async fn next_event(stream: &mut PacketStream) -> Event {
    tokio::time::timeout(GUARD, stream.next())
        .await
        .expect("no event")
        .expect("stream ended")
}

/// Skips events until a link event, returns it.
pub async fn next_link_event(stream: &mut PacketStream) -> LinkEvent {
    loop {
        if let Event::Link(e) = next_event(stream).await {
            return e;
        }
    }
}

/// Skips events until a packet arrives, returns it.
pub async fn next_packet(stream: &mut PacketStream) -> mcp_host::Received {
    loop {
        if let Event::Packet(p) = next_event(stream).await {
            return p;
        }
    }
}

/// Connects a ground station to a fresh pseudo-terminal in `mode`, opens a fake radio
/// on its far end and waits for the link to come up.
pub async fn pty_link(mode: ApiMode) -> (PacketStream, mcp_host::CommandSender, FakeXBee) {
    pty_link_with(mcp_host::LinkOptions {
        api_mode: mode,
        ..mcp_host::LinkOptions::default()
    })
    .await
}

/// The same with any link options.
pub async fn pty_link_with(
    options: mcp_host::LinkOptions,
) -> (PacketStream, mcp_host::CommandSender, FakeXBee) {
    let mode = options.api_mode;
    let (mut stream, sender) = mcp_host::connect(&mcp_host::Link::Pty, options)
        .await
        .unwrap();
    let path = stream.info().pty_path.clone().unwrap();
    let fake = FakeXBee::open_pty(&path, mode);
    assert!(matches!(
        next_link_event(&mut stream).await,
        LinkEvent::Connected { .. }
    ));
    (stream, sender, fake)
}

/// A child process, killed when dropped (also when a test fails part way, so that no
/// process outlives its test holding the test's standard error open).
pub struct Running(pub std::process::Child);

impl Drop for Running {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Starts `mcp-gs` with `args`; its standard output comes line by line on the channel
/// (read to the end, so that the process never writes into a closed pipe).
pub fn spawn_lines(args: &[&str]) -> (std::process::Child, std::sync::mpsc::Receiver<String>) {
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
        .args(args)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::inherit())
        .spawn()
        .expect("start mcp-gs");
    let lines = stdout_lines(&mut child);
    (child, lines)
}

/// The standard output of `child` (started with it piped), line by line on a channel,
/// read to the end by a thread of its own.
pub fn stdout_lines(child: &mut std::process::Child) -> std::sync::mpsc::Receiver<String> {
    lines_of(child.stdout.take().expect("stdout piped"))
}

/// The standard error of `child` (started with it piped), as [`stdout_lines`] gives
/// its standard output.
pub fn stderr_lines(child: &mut std::process::Child) -> std::sync::mpsc::Receiver<String> {
    lines_of(child.stderr.take().expect("stderr piped"))
}

/// What `from` gives, line by line on a channel, read to the end by a thread of its own.
fn lines_of(from: impl std::io::Read + Send + 'static) -> std::sync::mpsc::Receiver<String> {
    use std::io::BufRead;
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in std::io::BufReader::new(from).lines().map_while(Result::ok) {
            let _ = tx.send(line);
        }
    });
    rx
}

/// A TCP peer that takes `connections` connections in turn and reads each until the
/// other side hangs up, never answering: a radio that is not there. Its `tcp:` link,
/// and the thread to join.
pub fn silent_peer(connections: usize) -> (String, std::thread::JoinHandle<()>) {
    peer_writing(connections, Vec::new())
}

/// A TCP peer that takes `connections` connections in turn and closes each at once, as
/// a simulator serving two clients already does to a third. Its `tcp:` link, and the
/// thread to join.
pub fn closing_peer(connections: usize) -> (String, std::thread::JoinHandle<()>) {
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let link = format!("tcp:{}", listener.local_addr().unwrap());
    let peer = std::thread::spawn(move || {
        for stream in listener.incoming().take(connections) {
            drop(stream.unwrap());
        }
    });
    (link, peer)
}

/// A TCP peer that takes one connection, writes `bytes` and then reads until the other
/// side hangs up: a radio with something to say. Its `tcp:` link, and the thread to
/// join.
pub fn talking_peer(bytes: Vec<u8>) -> (String, std::thread::JoinHandle<()>) {
    peer_writing(1, bytes)
}

/// [`silent_peer`] and [`talking_peer`]: `connections` in turn, `bytes` written to each.
fn peer_writing(connections: usize, bytes: Vec<u8>) -> (String, std::thread::JoinHandle<()>) {
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let link = format!("tcp:{}", listener.local_addr().unwrap());
    let peer = std::thread::spawn(move || {
        for _ in 0..connections {
            let (mut socket, _) = listener.accept().unwrap();
            std::io::Write::write_all(&mut socket, &bytes).unwrap();
            let mut buf = [0u8; 64];
            while matches!(std::io::Read::read(&mut socket, &mut buf), Ok(n) if n > 0) {}
        }
    });
    (link, peer)
}

/// A TCP peer that takes one connection and answers every Transmit Request (0x10) it
/// reads, in API mode 1, with a Transmit Status of `delivery` (from the 16-bit address
/// 0xFFFE, no retries), until the other side hangs up: a radio that refuses. Its `tcp:`
/// link, and the thread to join.
pub fn refusing_radio(delivery: u8) -> (String, std::thread::JoinHandle<()>) {
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let link = format!("tcp:{}", listener.local_addr().unwrap());
    let peer = std::thread::spawn(move || {
        let (mut socket, _) = listener.accept().unwrap();
        let mut decoder = xbee_api::Decoder::<512>::new(ApiMode::Unescaped);
        let mut buf = [0u8; 256];
        while let Ok(n @ 1..) = std::io::Read::read(&mut socket, &mut buf) {
            let mut ids = Vec::new();
            decoder.decode_each(&buf[..n], |event| {
                if let Ok(frame) = event {
                    // As a radio: no status for frame id 0.
                    if let [0x10, id @ 1..=255, ..] = frame.data() {
                        ids.push(*id);
                    }
                }
            });
            for id in ids {
                let status = [0x8B, id, 0xFF, 0xFE, 0x00, delivery, 0x00];
                let frame = xbee_api::RawFrame::new(&status).unwrap();
                let mut out = [0u8; 32];
                let len =
                    xbee_api::EncodeFrame::encode(&frame, ApiMode::Unescaped, &mut out).unwrap();
                std::io::Write::write_all(&mut socket, &out[..len]).unwrap();
            }
        }
    });
    (link, peer)
}

/// A TCP peer that takes one connection and keeps what it reads until the other side
/// hangs up: where a replay goes. Its `tcp:` link, and the thread that gives the bytes.
pub fn recording_peer() -> (String, std::thread::JoinHandle<Vec<u8>>) {
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let link = format!("tcp:{}", listener.local_addr().unwrap());
    let peer = std::thread::spawn(move || {
        let (mut socket, _) = listener.accept().unwrap();
        let mut bytes = Vec::new();
        std::io::Read::read_to_end(&mut socket, &mut bytes).unwrap();
        bytes
    });
    (link, peer)
}

/// Whether the pseudo-terminal far end at `path` is in exclusive mode (TIOCEXCL): read
/// with TIOCGEXCL where it can be opened (root opens it regardless), and true where it
/// cannot be opened for being busy (anyone else).
#[cfg(target_os = "linux")]
pub fn far_end_is_exclusive(path: &std::path::Path) -> bool {
    use std::os::fd::AsRawFd;
    use std::os::unix::fs::OpenOptionsExt;
    let far = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NOCTTY | libc::O_NONBLOCK)
        .open(path);
    let far = match far {
        Ok(far) => far,
        Err(e) if e.raw_os_error() == Some(libc::EBUSY) => return true,
        Err(e) => panic!("cannot open {}: {e}", path.display()),
    };
    let mut exclusive: libc::c_int = 0;
    // SAFETY: TIOCGEXCL writes one int through the pointer, which points at one; the
    // file descriptor is open for the call.
    let done = unsafe { libc::ioctl(far.as_raw_fd(), libc::TIOCGEXCL, &mut exclusive) };
    assert_eq!(done, 0, "TIOCGEXCL: {}", std::io::Error::last_os_error());
    exclusive != 0
}

/// A TCP port of 127.0.0.1 held bound but not listening: a connection to it is
/// refused, and no other test can take it meanwhile. [`ReservedPort::listen`] starts
/// listening on it; a program that binds it with `SO_REUSEADDR` (as tokio does) can
/// listen there itself.
pub struct ReservedPort {
    socket: socket2::Socket,
    pub port: u16,
}

impl ReservedPort {
    pub fn new() -> Self {
        use socket2::{Domain, Socket, Type};
        let socket = Socket::new(Domain::IPV4, Type::STREAM, None).expect("a socket");
        socket.set_reuse_address(true).expect("SO_REUSEADDR");
        let any: std::net::SocketAddr = "127.0.0.1:0".parse().unwrap();
        socket.bind(&any.into()).expect("a free port");
        let port = socket
            .local_addr()
            .ok()
            .and_then(|a| a.as_socket())
            .expect("a bound address")
            .port();
        ReservedPort { socket, port }
    }

    /// Listens on the port now.
    pub fn listen(self) -> std::net::TcpListener {
        self.socket.listen(16).expect("listen");
        self.socket.into()
    }

    /// [`listen`](Self::listen), for tokio.
    pub fn listen_tokio(self) -> tokio::net::TcpListener {
        let listener = self.listen();
        listener.set_nonblocking(true).expect("non-blocking");
        tokio::net::TcpListener::from_std(listener).expect("in the runtime")
    }
}

/// Adds `network`'s coordinator on a TCP port of this machine, found free (its
/// `local_addr`), for a ground station to connect to.
pub async fn tcp_coordinator(network: &mcp_host::radio::Network) -> mcp_host::radio::AddedNode {
    network
        .add_link(
            Address64::COORDINATOR,
            &"tcp-listen:127.0.0.1:0".parse().unwrap(),
            mcp_host::radio::NodeOptions::default(),
        )
        .await
        .unwrap()
}

/// A recording of `n` received modem statuses ("coordinator started"), as `monitor
/// --record` writes it.
pub fn modem_status_recording(n: usize) -> Vec<u8> {
    let mut writer = mcp_host::record::RecordWriter::new(Vec::new()).unwrap();
    for _ in 0..n {
        writer
            .write(
                std::time::SystemTime::now(),
                mcp_host::record::Direction::Received,
                &[0x8A, 0x06],
            )
            .unwrap();
    }
    writer.into_inner()
}

/// The messages of `error` and of each of its sources, as a report that follows the
/// chain (`anyhow`'s `{:#}`) prints them.
pub fn error_chain(error: &dyn std::error::Error) -> Vec<String> {
    std::iter::successors(Some(error), |e| e.source())
        .map(ToString::to_string)
        .collect()
}

/// A FIFO (named pipe) made in `dir` under `name`: its path.
#[cfg(unix)]
pub fn fifo(dir: &std::path::Path, name: &str) -> std::path::PathBuf {
    let fifo = dir.join(name);
    assert!(
        std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success()
    );
    fifo
}

/// A FIFO made in `dir` whose read end is open, with room for 4 KiB, and never read:
/// a recording's reader that has stopped taking (a `gzip` paused, say). Its path, and
/// the read end, to keep open.
#[cfg(target_os = "linux")]
pub fn stuck_fifo(dir: &std::path::Path) -> (std::path::PathBuf, std::fs::File) {
    use std::os::fd::AsRawFd;
    use std::os::unix::fs::OpenOptionsExt;
    let fifo = fifo(dir, "stuck.fifo");
    // Opened without waiting for a writer.
    let reader = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(&fifo)
        .unwrap();
    // SAFETY: fcntl(2) on the pipe's read end, which `reader` owns. (A page at least:
    // more where pages are larger.)
    assert!(unsafe { libc::fcntl(reader.as_raw_fd(), libc::F_SETPIPE_SZ, 4096) } >= 4096);
    (fifo, reader)
}

/// The exit code of `child`, once it ends (failure guard: [`GUARD`]).
pub fn exit_code(child: &mut std::process::Child) -> Option<i32> {
    let deadline = std::time::Instant::now() + GUARD;
    loop {
        if let Some(status) = child.try_wait().expect("wait") {
            return status.code();
        }
        assert!(std::time::Instant::now() < deadline, "still running");
        std::thread::yield_now();
    }
}

/// Writes modem statuses (associated) to `radio`, a hundred at a time, until the pipe
/// read by `reader` (a [`stuck_fifo`]) takes no more: what it holds has not changed for
/// 20 looks in a row (100 ms), frames still coming. The recording's writer then waits.
/// (How much a pipe holds when full depends on the sizes of the writes.)
#[cfg(target_os = "linux")]
pub fn fill_the_pipe(radio: &mut std::net::TcpStream, reader: &std::fs::File) {
    use std::os::fd::AsRawFd;
    let modem_status = [0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F];
    let deadline = std::time::Instant::now() + GUARD;
    let (mut held, mut same) = (0, 0);
    while held == 0 || same < 20 {
        assert!(
            std::time::Instant::now() < deadline,
            "the pipe never filled"
        );
        std::io::Write::write_all(radio, &modem_status.repeat(100)).unwrap();
        // Polled, not spun on.
        std::thread::sleep(Duration::from_millis(5));
        let mut queued: libc::c_int = 0;
        // SAFETY: ioctl(2) FIONREAD on the pipe's read end, into a c_int.
        assert_eq!(
            unsafe { libc::ioctl(reader.as_raw_fd(), libc::FIONREAD, &mut queued) },
            0
        );
        same = if queued == held { same + 1 } else { 0 };
        held = queued;
    }
}

/// Writes `frame` to `socket` (a radio's side of a monitor's link) every tenth of a
/// second until a line of `errors` holds `text`: monitor drops the lines of frames that
/// come once a line has waited for its output for a while, so a reader that takes
/// nothing is said only as more frames come. The line, and how many frames were
/// written.
pub fn write_until_said(
    socket: &mut std::net::TcpStream,
    frame: &[u8],
    errors: &std::sync::mpsc::Receiver<String>,
    text: &str,
) -> (String, usize) {
    use std::io::Write;
    let deadline = std::time::Instant::now() + GUARD;
    let mut written = 0;
    loop {
        assert!(std::time::Instant::now() < deadline, "never said: {text}");
        socket.write_all(frame).unwrap();
        written += 1;
        while let Ok(line) = errors.recv_timeout(Duration::from_millis(100)) {
            assert!(
                !line.contains(" lost: "),
                "monitor fell behind its link: {line}"
            );
            if line.contains(text) {
                return (line, written);
            }
        }
    }
}
