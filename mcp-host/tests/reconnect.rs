//! Transports going away and coming back, over real TCP on 127.0.0.1.

mod common;

use std::time::Duration;

use common::*;
use futures::StreamExt;
use mcp_core::{Command, Packet, Report, StatusRequest};
use mcp_host::{
    Event, LinkEvent, LinkOptions, LinkState, PacketStream, ReconnectPolicy, RequestError,
    SendError,
};
use tokio::net::{TcpListener, TcpStream};
use xbee_api::{ApiMode, DecodeError, DeliveryStatus};

fn options(mode: ApiMode, reconnect: bool) -> LinkOptions {
    LinkOptions {
        api_mode: mode,
        reconnect: ReconnectPolicy {
            enabled: reconnect,
            initial_delay: Duration::from_millis(5),
            max_delay: Duration::from_millis(50),
        },
        ..LinkOptions::default()
    }
}

fn time_report(t: u32) -> Vec<u8> {
    mcp(&Packet::<&[u8]>::Report(Report::Time(t)))
}

async fn expect_time_report(stream: &mut PacketStream, t: u32) {
    let rx = next_packet(stream).await;
    assert_eq!(&rx.payload[..], &time_report(t)[..]);
}

async fn accept(listener: &TcpListener, mode: ApiMode) -> FakeXBee {
    let (socket, _) = tokio::time::timeout(GUARD, listener.accept())
        .await
        .expect("no connection")
        .unwrap();
    FakeXBee::new(socket, mode)
}

/// A link to a fake radio on TCP, its `Connected` event taken: the listener (for the
/// reconnections), the stream, the sender and the radio.
async fn tcp_radio(
    options: LinkOptions,
) -> (TcpListener, PacketStream, mcp_host::CommandSender, FakeXBee) {
    let listener = TcpListener::bind("127.0.0.1:0").await.unwrap();
    let port = listener.local_addr().unwrap().port();
    let link = format!("tcp:127.0.0.1:{port}").parse().unwrap();
    let mode = options.api_mode;
    let (mut stream, sender) = mcp_host::connect(&link, options).await.unwrap();
    let fake = accept(&listener, mode).await;
    assert!(matches!(
        next_link_event(&mut stream).await,
        LinkEvent::Connected { .. }
    ));
    (listener, stream, sender, fake)
}

#[tokio::test]
async fn tcp_link_reconnects_and_fails_requests_in_flight() {
    let (listener, mut stream, sender, mut fake) = tcp_radio(options(ApiMode::Escaped, true)).await;

    fake.receive(MAV, &time_report(1)).await;
    expect_time_report(&mut stream, 1).await;

    // A send and a request are in flight when the peer goes away mid-frame.
    let send = tokio::spawn({
        let sender = sender.clone();
        async move { sender.send(MAV, &Command::time(5)).await }
    });
    let request = tokio::spawn({
        let sender = sender.clone();
        async move { sender.request(MAV, StatusRequest::Time).await }
    });
    fake.next_tx().await;
    fake.next_tx().await;
    let frame = fake.encode(&rx(MAV, &time_report(2)));
    fake.write_raw(&frame[..frame.len() / 2]).await;
    fake.close().await;

    // The cut-off frame is reported, then the disconnection.
    match next_event(&mut stream).await {
        Event::DecodeError(DecodeError::Truncated { .. }) => {}
        other => panic!("{other:?}"),
    }
    let LinkEvent::Disconnected { reason, .. } = next_link_event(&mut stream).await else {
        panic!()
    };
    assert!(reason.contains("end of stream"), "{reason}");
    let err = send.await.unwrap().unwrap_err();
    assert!(matches!(err, SendError::Disconnected { .. }), "{err}");
    assert!(err.to_string().starts_with("link down: "), "{err}");
    let err = request.await.unwrap().unwrap_err();
    assert!(
        matches!(err, RequestError::Send(SendError::Disconnected { .. })),
        "{err}"
    );

    // The link reconnects by itself, and the stream carries on.
    let mut fake = accept(&listener, ApiMode::Escaped).await;
    assert!(matches!(
        next_link_event(&mut stream).await,
        LinkEvent::Reconnected { .. }
    ));
    fake.receive(MAV, &time_report(3)).await;
    expect_time_report(&mut stream, 3).await;
    let send = tokio::spawn({
        let sender = sender.clone();
        async move { sender.send(MAV, &Command::time(6)).await }
    });
    let tx = fake.next_tx().await;
    fake.status(tx.frame_id, DeliveryStatus::Success).await;
    send.await.unwrap().unwrap();
    let stats = stream.stats();
    assert_eq!((stats.disconnects, stats.reconnects), (1, 1));
    assert_eq!(stats.truncated, 1);
}

#[tokio::test]
async fn tcp_listen_waits_for_the_next_peer() {
    let link = "tcp-listen:127.0.0.1:0".parse().unwrap();
    let (mut stream, sender) = mcp_host::connect(&link, options(ApiMode::Unescaped, true))
        .await
        .unwrap();
    let addr = stream.info().local_addr.unwrap();

    // Before any peer, requests fail at once with a clear error.
    let err = sender.send(MAV, &Command::landing(true)).await.unwrap_err();
    match &err {
        SendError::Disconnected { reason, .. } => {
            assert!(reason.contains("not connected"), "{err}")
        }
        other => panic!("{other}"),
    }

    let mut fake = FakeXBee::new(TcpStream::connect(addr).await.unwrap(), ApiMode::Unescaped);
    assert!(matches!(
        next_link_event(&mut stream).await,
        LinkEvent::Connected { .. }
    ));
    fake.receive(MAV, &time_report(10)).await;
    expect_time_report(&mut stream, 10).await;

    let request = tokio::spawn({
        let sender = sender.clone();
        async move { sender.request(MAV, StatusRequest::Landing).await }
    });
    fake.next_tx().await;
    drop(fake);
    assert!(matches!(
        next_link_event(&mut stream).await,
        LinkEvent::Disconnected { .. }
    ));
    let err = request.await.unwrap().unwrap_err();
    assert!(
        matches!(err, RequestError::Send(SendError::Disconnected { .. })),
        "{err}"
    );
    // While no peer is connected, sends fail at once.
    let err = sender.send(MAV, &Command::time(1)).await.unwrap_err();
    assert!(matches!(err, SendError::Disconnected { .. }), "{err}");

    // The next peer is served.
    let mut fake = FakeXBee::new(TcpStream::connect(addr).await.unwrap(), ApiMode::Unescaped);
    assert!(matches!(
        next_link_event(&mut stream).await,
        LinkEvent::Reconnected { .. }
    ));
    fake.receive(MAV, &time_report(11)).await;
    expect_time_report(&mut stream, 11).await;
    let request = tokio::spawn({
        let sender = sender.clone();
        async move { sender.request(MAV, StatusRequest::Time).await }
    });
    let tx = fake.next_tx().await;
    fake.status(tx.frame_id, DeliveryStatus::Success).await;
    fake.receive(MAV, &time_report(12)).await;
    let report = request.await.unwrap().unwrap();
    assert_eq!(report.as_borrowed(), Report::Time(12));
}

#[tokio::test]
async fn without_reconnection_the_link_closes_and_the_stream_ends() {
    let (_listener, mut stream, sender, fake) = tcp_radio(options(ApiMode::Unescaped, false)).await;
    fake.close().await;
    assert!(matches!(
        next_link_event(&mut stream).await,
        LinkEvent::Disconnected { .. }
    ));
    match next_link_event(&mut stream).await {
        LinkEvent::Closed { reason, .. } => assert!(reason.contains("disabled"), "{reason}"),
        other => panic!("{other:?}"),
    }
    let end = tokio::time::timeout(GUARD, futures::StreamExt::next(&mut stream)).await;
    assert!(end.unwrap().is_none(), "the stream ends after Closed");
    let err = sender.send(MAV, &Command::time(1)).await.unwrap_err();
    assert_eq!(err, SendError::Closed);
}

#[tokio::test]
async fn connect_fails_fast_when_the_first_connection_fails() {
    let reserved = ReservedPort::new();
    let port = reserved.port;
    let link = format!("tcp:127.0.0.1:{port}").parse().unwrap();
    let err = mcp_host::connect(&link, LinkOptions::default())
        .await
        .unwrap_err();
    assert!(
        err.to_string().contains(&format!("127.0.0.1:{port}")),
        "{err}"
    );
}

#[cfg(unix)]
#[tokio::test]
async fn serial_link_reports_the_device_going_away() {
    // A pseudo-terminal stands in for a USB serial adapter: the test holds the radio
    // side, the link opens the device path, and closing the radio side removes the
    // device under the link.
    let (radio, device) = tokio_serial::SerialStream::pair().unwrap();
    let path = tokio_serial::SerialPort::name(&device).unwrap();
    drop(device);
    let link = format!("serial:{path}:115200").parse().unwrap();
    let (mut stream, sender) = mcp_host::connect(&link, options(ApiMode::Unescaped, true))
        .await
        .unwrap();
    assert!(matches!(
        next_link_event(&mut stream).await,
        LinkEvent::Connected { .. }
    ));
    let mut fake = FakeXBee::new(radio, ApiMode::Unescaped);
    fake.receive(MAV, &time_report(7)).await;
    expect_time_report(&mut stream, 7).await;

    let send = tokio::spawn({
        let sender = sender.clone();
        async move { sender.send(MAV, &Command::time(8)).await }
    });
    fake.next_tx().await;
    drop(fake); // "unplugged"
    assert!(matches!(
        next_link_event(&mut stream).await,
        LinkEvent::Disconnected { .. }
    ));
    let err = send.await.unwrap().unwrap_err();
    assert!(matches!(err, SendError::Disconnected { .. }), "{err}");
    // While the device is gone, the link keeps retrying and requests fail at once.
    let err = sender.send(MAV, &Command::time(9)).await.unwrap_err();
    match &err {
        SendError::Disconnected { reason, .. } => assert!(reason.contains("reconnecting"), "{err}"),
        other => panic!("{other}"),
    }
}

#[cfg(unix)]
#[tokio::test]
async fn a_closed_serial_link_frees_its_port_at_once() {
    // Serial ports are opened for exclusive use: each round opens the device again
    // right after the link before it was closed, which fails while the port is held.
    let (radio, device) = tokio_serial::SerialStream::pair().unwrap();
    let path = tokio_serial::SerialPort::name(&device).unwrap();
    drop(device);
    let link = format!("serial:{path}:115200").parse().unwrap();
    let mut fake = FakeXBee::new(radio, ApiMode::Unescaped);
    for round in 0..3 {
        let (mut stream, sender) = mcp_host::connect(&link, options(ApiMode::Unescaped, true))
            .await
            .unwrap_or_else(|e| panic!("round {round}: {e}"));
        assert!(matches!(
            next_link_event(&mut stream).await,
            LinkEvent::Connected { .. }
        ));
        fake.receive(MAV, &time_report(round)).await;
        expect_time_report(&mut stream, round).await;
        assert!(!futures::stream::FusedStream::is_terminated(&stream));

        sender.close();
        match next_link_event(&mut stream).await {
            LinkEvent::Closed { reason, .. } => assert_eq!(reason, "closed by the application"),
            other => panic!("round {round}: {other:?}"),
        }
        // Its last event read, it has not ended yet: a `select!` loop reads its end.
        assert!(!futures::stream::FusedStream::is_terminated(&stream));
        let end = tokio::time::timeout(GUARD, futures::StreamExt::next(&mut stream)).await;
        assert!(end.expect("the stream did not end").is_none());
        // Ended for good, as a `select!` loop asks.
        assert!(futures::stream::FusedStream::is_terminated(&stream));
        assert!(futures::StreamExt::next(&mut stream).await.is_none());
        let err = sender.send(MAV, &Command::time(round)).await.unwrap_err();
        assert!(matches!(err, SendError::Closed), "{err}");
    }
}

#[test]
fn handles_are_send_and_sync() {
    fn check<T: Send + Sync + 'static>() {}
    check::<mcp_host::CommandSender>();
    check::<mcp_host::PacketStream>();
    check::<mcp_host::Subscription>();
    check::<mcp_host::PacketSink>();
    check::<mcp_host::Event>();
    check::<mcp_host::SendError>();
    check::<mcp_host::RequestError>();
    check::<mcp_host::DiscoverError>();
    check::<mcp_host::Discovery>();
}

#[test]
fn plain_data_compares_as_tests_and_maps_want() {
    fn comparable<T: PartialEq + Clone + std::fmt::Debug>() {}
    fn keyed<T: Eq + std::hash::Hash + Copy>() {}
    comparable::<mcp_host::Event>();
    comparable::<mcp_host::Received>();
    comparable::<mcp_host::InvalidPacket>();
    keyed::<mcp_host::record::Direction>();
    fn copied<T: Copy>() {}
    copied::<mcp_host::ReconnectPolicy>();
}

/// A round trip through the link (an `AT AP` answered by the fake radio): every frame
/// the radio wrote before its answer has been taken by the background task when it
/// returns.
async fn round_trip(sender: &mcp_host::CommandSender, fake: &mut FakeXBee) {
    let at = tokio::spawn({
        let sender = sender.clone();
        async move { sender.at(*b"AP", &[], Some(GUARD)).await }
    });
    let command = fake.next_frame().await;
    assert_eq!(command[0], 0x08, "{command:02X?}");
    fake.send(&xbee_api::AtCommandResponseRepr {
        frame_id: command[1],
        command: *b"AP",
        status: xbee_api::AtStatus::Ok,
        data: &[1],
    })
    .await;
    at.await.unwrap().unwrap();
}

/// A consumer that does not read loses packets, never link state: with the event queue
/// full, the disconnection, the reconnection and the close still come, in order, and
/// the stream ends after `Closed`.
#[tokio::test]
async fn link_events_survive_a_full_event_queue() {
    let listener = TcpListener::bind("127.0.0.1:0").await.unwrap();
    let port = listener.local_addr().unwrap().port();
    let link = format!("tcp:127.0.0.1:{port}").parse().unwrap();
    let options = LinkOptions {
        event_capacity: 2,
        ..options(ApiMode::Unescaped, true)
    };
    let (mut stream, sender) = mcp_host::connect(&link, options).await.unwrap();
    let mut fake = accept(&listener, ApiMode::Unescaped).await;
    for t in 0..10 {
        fake.receive(MAV, &time_report(t)).await;
    }
    round_trip(&sender, &mut fake).await;
    fake.close().await;
    // The reconnection: the background task has seen the disconnection.
    let mut fake = accept(&listener, ApiMode::Unescaped).await;
    round_trip(&sender, &mut fake).await;
    sender.close();

    let mut links = Vec::new();
    let mut packets = 0;
    while let Some(event) = tokio::time::timeout(GUARD, stream.next())
        .await
        .expect("the stream did not end")
    {
        match event {
            Event::Link(link) => links.push(link),
            Event::Packet(_) => packets += 1,
            other => panic!("{other:?}"),
        }
    }
    let kinds: Vec<&str> = links
        .iter()
        .map(|l| match l {
            LinkEvent::Connected { .. } => "connected",
            LinkEvent::Disconnected { .. } => "disconnected",
            LinkEvent::Reconnected { .. } => "reconnected",
            LinkEvent::Closed { .. } => "closed",
            _ => "other",
        })
        .collect();
    assert_eq!(
        kinds,
        ["connected", "disconnected", "reconnected", "closed"],
        "{links:?}"
    );
    // The queue held `Connected` and one report; the other nine were dropped.
    assert_eq!(packets, 1);
    assert_eq!(stream.stats().events_dropped, 9);
}

/// `close` writes out what was already reported written before it closes the transport:
/// here the radio reads nothing until the link is closed, so that written frames are
/// still queued in the background task when `close` comes.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn close_writes_out_frames_already_written() {
    let socket = tokio::net::TcpSocket::new_v4().unwrap();
    socket.set_recv_buffer_size(4096).unwrap();
    socket.bind("127.0.0.1:0".parse().unwrap()).unwrap();
    let listener = socket.listen(1).unwrap();
    let port = listener.local_addr().unwrap().port();
    let link = format!("tcp:127.0.0.1:{port}").parse().unwrap();
    let (mut stream, sender) = mcp_host::connect(&link, options(ApiMode::Unescaped, true))
        .await
        .unwrap();
    let mut fake = accept(&listener, ApiMode::Unescaped).await;
    // Frames of 400 bytes until one is not taken within 100 ms: the socket and the
    // background task's queue are full.
    let mut frame = vec![0x23u8; 400];
    let mut written = 0u32;
    loop {
        frame[1..5].copy_from_slice(&written.to_be_bytes());
        let write = sender.write_frame(&frame);
        match tokio::time::timeout(Duration::from_millis(100), write).await {
            Ok(result) => result.unwrap(),
            Err(_) => break,
        }
        written += 1;
        assert!(written < 10_000, "the link never filled up");
    }
    sender.close();
    // Every frame reported written arrives, in order.
    for n in 0..written {
        let data = fake.next_frame().await;
        assert_eq!(data[1..5], n.to_be_bytes(), "frame {n} of {written}");
    }
    while stream.next().await.is_some() {}
}

/// A send refused while the link is down says why it went down.
#[tokio::test]
async fn a_send_during_an_outage_says_why_the_link_went_down() {
    let (listener, mut stream, sender, fake) = tcp_radio(options(ApiMode::Escaped, true)).await;
    let port = listener.local_addr().unwrap().port();
    // Nothing listens any more: the link stays down.
    drop(listener);
    fake.close().await;
    assert!(matches!(
        next_link_event(&mut stream).await,
        LinkEvent::Disconnected { .. }
    ));
    let err = sender.send(MAV, &Command::time(1)).await.unwrap_err();
    assert!(matches!(err, SendError::Disconnected { .. }), "{err}");
    let message = err.to_string();
    assert!(
        message.contains("end of stream")
            && message.contains(&format!("reconnecting to tcp:127.0.0.1:{port}")),
        "{message}"
    );
}

/// The link's state can be read at any time, and `closed` waits for the end.
#[tokio::test]
async fn link_state_follows_the_transport() {
    let (listener, mut stream, sender, fake) = tcp_radio(options(ApiMode::Escaped, true)).await;
    assert_eq!(sender.link_state(), LinkState::Connected);
    assert_eq!(stream.link_state(), LinkState::Connected);
    drop(listener);
    fake.close().await;
    assert!(matches!(
        next_link_event(&mut stream).await,
        LinkEvent::Disconnected { .. }
    ));
    assert_eq!(sender.link_state(), LinkState::Reconnecting);
    sender.close();
    tokio::time::timeout(GUARD, sender.closed())
        .await
        .expect("the link did not close");
    assert_eq!(sender.link_state(), LinkState::Closed);
    assert_eq!(stream.link_state(), LinkState::Closed);
}

#[tokio::test]
async fn tcp_listen_drops_what_a_peer_wrote_if_it_left_before_its_turn() {
    let link = "tcp-listen:127.0.0.1:0".parse().unwrap();
    let (mut stream, _sender) = mcp_host::connect(&link, options(ApiMode::Unescaped, true))
        .await
        .unwrap();
    let addr = stream.info().local_addr.unwrap();
    let mut first = FakeXBee::new(TcpStream::connect(addr).await.unwrap(), ApiMode::Unescaped);
    assert!(matches!(
        next_link_event(&mut stream).await,
        LinkEvent::Connected { .. }
    ));

    // A second peer connects while the first is served, writes a frame (as a ground
    // station sending a command would) and gives up before its turn.
    let mut second = TcpStream::connect(addr).await.unwrap();
    let frame = first.encode(&rx(MAV, &time_report(20)));
    tokio::io::AsyncWriteExt::write_all(&mut second, &frame)
        .await
        .unwrap();
    tokio::io::AsyncWriteExt::shutdown(&mut second)
        .await
        .unwrap();

    first.receive(MAV, &time_report(21)).await;
    expect_time_report(&mut stream, 21).await;
    drop(first);
    assert!(matches!(
        next_link_event(&mut stream).await,
        LinkEvent::Disconnected { .. }
    ));
    // The link drops the second (it reads the end of its stream) ...
    let mut rest = Vec::new();
    tokio::time::timeout(
        GUARD,
        tokio::io::AsyncReadExt::read_to_end(&mut second, &mut rest),
    )
    .await
    .expect("the peer that left was not dropped")
    .unwrap();
    // ... and serves the next; the second's frame never shows up.
    let mut third = FakeXBee::new(TcpStream::connect(addr).await.unwrap(), ApiMode::Unescaped);
    assert!(matches!(
        next_link_event(&mut stream).await,
        LinkEvent::Reconnected { .. }
    ));
    third.receive(MAV, &time_report(22)).await;
    expect_time_report(&mut stream, 22).await;
}

/// Log lines written while the test runs (on its own thread: `#[tokio::test]` runs the
/// link's task there too).
#[derive(Clone, Default)]
struct Captured(std::sync::Arc<std::sync::Mutex<Vec<u8>>>);

impl Captured {
    /// Log lines up to `level`, captured until the guard is dropped.
    ///
    /// tracing decides once for the whole process whether a log line's call site is
    /// wanted, asking the subscriber of the thread that reaches it first: a test running
    /// on another thread with none would have it dropped for every thread. A global
    /// subscriber that takes everything (and prints nothing) answers those threads, so a
    /// line is never dropped before this thread's subscriber sees it.
    fn at(level: tracing::Level) -> (Self, tracing::subscriber::DefaultGuard) {
        static GLOBAL: std::sync::Once = std::sync::Once::new();
        GLOBAL.call_once(|| {
            let _ = tracing::subscriber::set_global_default(tracing_subscriber::registry());
        });
        let logs = Captured::default();
        let writer = logs.clone();
        let subscriber = tracing_subscriber::fmt()
            .with_ansi(false)
            .with_max_level(level)
            .with_writer(move || writer.clone())
            .finish();
        (logs, tracing::subscriber::set_default(subscriber))
    }

    fn text(&self) -> String {
        String::from_utf8(self.0.lock().unwrap().clone()).unwrap()
    }
}

impl std::io::Write for Captured {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.lock().unwrap().extend_from_slice(buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

#[tokio::test]
async fn what_a_link_logs_names_the_link() {
    let (logs, _guard) = Captured::at(tracing::Level::DEBUG);

    let (listener, mut stream, _sender, fake) = tcp_radio(options(ApiMode::Escaped, true)).await;
    let link = stream.info().link.to_string();
    drop(fake);
    assert!(matches!(
        next_link_event(&mut stream).await,
        LinkEvent::Disconnected { .. }
    ));
    let _fake = accept(&listener, ApiMode::Escaped).await;
    assert!(matches!(
        next_link_event(&mut stream).await,
        LinkEvent::Reconnected { .. }
    ));

    let text = logs.text();
    let span = format!("link{{link={link}}}");
    for message in ["connected", "disconnected", "reconnected"] {
        assert!(
            text.lines()
                .any(|l| l.contains(&span) && l.contains(&format!(": {message}"))),
            "no {message:?} line in the link's span {span}:\n{text}"
        );
    }
}

#[tokio::test]
async fn malformed_frames_from_a_peer_are_not_warnings() {
    let (logs, _guard) = Captured::at(tracing::Level::WARN);

    let (_listener, mut stream, _sender, mut fake) =
        tcp_radio(options(ApiMode::Escaped, true)).await;
    // A Receive Packet of one byte (its fields missing), a hundred times.
    for _ in 0..100 {
        fake.write_raw(&[0x7E, 0x00, 0x01, 0x90, 0x6F]).await;
    }
    fake.receive(MAV, &time_report(30)).await;
    let mut malformed = 0;
    loop {
        match next_event(&mut stream).await {
            Event::Frame(frame) if frame.frame_type() == 0x90 => malformed += 1,
            Event::Packet(rx) => {
                assert_eq!(&rx.payload[..], &time_report(30)[..]);
                break;
            }
            other => panic!("{other:?}"),
        }
    }
    assert_eq!(malformed, 100);
    assert_eq!(stream.stats().malformed_frames, 100);
    let text = logs.text();
    assert!(text.is_empty(), "{text}");
}

#[tokio::test]
async fn wait_for_link_connects_once_the_peer_is_there() {
    // A port nobody listens on yet.
    let reserved = ReservedPort::new();
    let port = reserved.port;
    let link: mcp_host::Link = format!("tcp:127.0.0.1:{port}").parse().unwrap();
    // Without the option, connect fails at once.
    assert!(
        mcp_host::connect(&link, options(ApiMode::Escaped, true))
            .await
            .is_err()
    );
    // Nor can it wait without reconnection.
    let no_reconnect = LinkOptions {
        wait_for_link: true,
        ..options(ApiMode::Escaped, false)
    };
    assert!(mcp_host::connect(&link, no_reconnect).await.is_err());
    let waiting = LinkOptions {
        wait_for_link: true,
        ..options(ApiMode::Escaped, true)
    };
    let (mut stream, sender) = mcp_host::connect(&link, waiting).await.unwrap();
    assert_eq!(sender.link_state(), LinkState::Connecting);
    // Meanwhile requests fail at once, saying why.
    let err = sender.send(MAV, &Command::time(1)).await.unwrap_err();
    assert!(err.to_string().contains("not connected yet"), "{err}");

    let listener = reserved.listen_tokio();
    let mut fake = accept(&listener, ApiMode::Escaped).await;
    assert!(matches!(
        next_link_event(&mut stream).await,
        LinkEvent::Connected { .. }
    ));
    assert_eq!(sender.link_state(), LinkState::Connected);
    fake.receive(MAV, &time_report(7)).await;
    expect_time_report(&mut stream, 7).await;
}

/// A Receive Packet of `payload` from the MAV as a radio in API mode 2 writes it: its
/// 16-bit address 0x7D33 escaped, which a link in mode 1 reads as a bad frame.
fn escaped_rx(payload: &[u8]) -> Vec<u8> {
    use xbee_api::EncodeFrame;
    let frame = rx(MAV, payload);
    let mut buf = vec![0u8; frame.encoded_len(ApiMode::Escaped)];
    let n = frame.encode(ApiMode::Escaped, &mut buf).unwrap();
    buf.truncate(n);
    buf
}

#[tokio::test]
async fn a_radio_in_the_other_api_mode_is_warned_about_once_a_connection() {
    let (logs, _guard) = Captured::at(tracing::Level::WARN);
    let warnings = |text: &str| {
        text.lines()
            .filter(|l| l.contains("what the radio sends is dropped"))
            .count()
    };
    let (listener, mut stream, sender, mut fake) =
        tcp_radio(options(ApiMode::Unescaped, true)).await;
    for round in 0..2u32 {
        for _ in 0..10 {
            fake.write_raw(&escaped_rx(&time_report(1))).await;
        }
        // A frame with nothing to escape reads the same in both modes: once it is
        // here, so are the failures before it.
        fake.receive(OTHER_MAV, b"mx").await;
        loop {
            if let Event::Packet(rx) = next_event(&mut stream).await {
                assert_eq!(rx.origin.src64, OTHER_MAV);
                break;
            }
        }
        let text = logs.text();
        assert_eq!(warnings(&text), round as usize + 1, "{text}");
        let line = text.lines().rev().find(|l| l.contains("is dropped"));
        assert!(
            line.is_some_and(|l| l.contains("the radio may be in API mode 2 (AP=2)")),
            "{text}"
        );
        if round == 0 {
            // Once a connection: a new one is watched afresh.
            drop(fake);
            assert!(matches!(
                next_link_event(&mut stream).await,
                LinkEvent::Disconnected { .. }
            ));
            fake = accept(&listener, ApiMode::Unescaped).await;
            assert!(matches!(
                next_link_event(&mut stream).await,
                LinkEvent::Reconnected { .. }
            ));
        }
    }

    // A request whose report came in a frame that could not be decoded says so, and
    // does not blame the MAV.
    let request = tokio::spawn({
        let sender = sender.clone();
        async move {
            sender
                .request_with(MAV, StatusRequest::Time, Some(Duration::from_millis(500)))
                .await
        }
    });
    let tx = fake.next_tx().await;
    fake.status(tx.frame_id, DeliveryStatus::Success).await;
    fake.write_raw(&escaped_rx(&time_report(7))).await;
    let error = request.await.unwrap().unwrap_err();
    assert!(
        matches!(
            error,
            RequestError::Timeout {
                delivered: true,
                undecodable: 1,
                ..
            }
        ),
        "{error:?}"
    );
    let text = error.to_string();
    assert!(
        text.contains("the radio delivered the request, but 1 frame from the radio could not be decoded meanwhile: the report may have been one"),
        "{text}"
    );
}

#[tokio::test]
async fn a_radio_in_transparent_mode_is_warned_about_when_a_request_times_out() {
    let (logs, _guard) = Captured::at(tracing::Level::WARN);
    let (_listener, stream, sender, mut fake) = tcp_radio(options(ApiMode::Unescaped, true)).await;
    // What a radio in transparent mode passes on: a MAV's console text, no frame.
    let text = b"MAV booting... IMU ok, GPS waiting for fix\r\n".repeat(4);
    fake.write_raw(&text).await;
    let read = async {
        while stream.stats().bytes_skipped < text.len() as u64 {
            tokio::task::yield_now().await;
        }
    };
    tokio::time::timeout(GUARD, read)
        .await
        .expect("the text is read");
    // Bytes that begin no frame make no event: the warning waits for a request that
    // the radio cannot answer.
    assert!(logs.text().is_empty(), "{}", logs.text());
    let at = sender
        .at(*b"AP", &[], Some(Duration::from_millis(100)))
        .await;
    assert!(matches!(at, Err(SendError::Timeout { .. })), "{at:?}");
    let text = logs.text();
    assert!(
        text.contains(
            "what the radio sends is dropped: 176 bytes came from the radio and none began a frame"
        ),
        "{text}"
    );
}

#[tokio::test]
async fn a_radio_switched_to_the_other_api_mode_while_the_link_is_up_is_warned_about() {
    let (logs, _guard) = Captured::at(tracing::Level::WARN);
    let (_listener, mut stream, _sender, mut fake) =
        tcp_radio(options(ApiMode::Unescaped, true)).await;
    // A long while in the right mode...
    for _ in 0..500 {
        fake.receive(OTHER_MAV, b"mx").await;
    }
    // ... then the radio is set to API mode 2 (AP=2 through a hub, say).
    for _ in 0..10 {
        fake.write_raw(&escaped_rx(&time_report(1))).await;
    }
    fake.receive(OTHER_MAV, b"my").await;
    loop {
        if let Event::Packet(rx) = next_event(&mut stream).await {
            if rx.payload[..] == b"my"[..] {
                break;
            }
        }
    }
    // The 500 good frames before do not outvote the 10 failing now.
    let text = logs.text();
    assert!(
        text.contains("what the radio sends is dropped: 5 frames failed the checksum and 0 passed"),
        "{text}"
    );
}

/// A request that went out before the link went down fails, but its frame id stays
/// taken after the link is back, until its late answer comes (a radio behind a serial
/// bridge stays up and answers): the answer then reaches no new request, however many
/// ids were handed out meanwhile.
#[tokio::test]
async fn an_answer_late_across_a_reconnection_reaches_no_new_request() {
    let (listener, mut stream, sender, mut fake) =
        tcp_radio(options(ApiMode::Unescaped, true)).await;
    let lost = tokio::spawn({
        let sender = sender.clone();
        async move { sender.send(MAV, &Command::time(5)).await }
    });
    let old_id = fake.next_tx().await.frame_id;
    fake.close().await;
    let err = lost.await.unwrap().unwrap_err();
    assert!(matches!(err, SendError::Disconnected { .. }), "{err}");
    let mut fake = accept(&listener, ApiMode::Unescaped).await;
    assert!(matches!(
        next_link_event(&mut stream).await,
        LinkEvent::Disconnected { .. }
    ));
    assert!(matches!(
        next_link_event(&mut stream).await,
        LinkEvent::Reconnected { .. }
    ));
    // Every other id once, answered at once: the next would be the old one again.
    for _ in 0..254 {
        let send = tokio::spawn({
            let sender = sender.clone();
            async move { sender.send(MAV, &Command::time(6)).await }
        });
        let tx = fake.next_tx().await;
        assert_ne!(
            tx.frame_id, old_id,
            "the id of a frame that went out reused"
        );
        fake.status(tx.frame_id, DeliveryStatus::Success).await;
        send.await.unwrap().unwrap();
    }
    let doomed = tokio::spawn({
        let sender = sender.clone();
        async move { sender.send(OTHER_MAV, &Command::time(7)).await }
    });
    let tx = fake.next_tx().await;
    assert_ne!(
        tx.frame_id, old_id,
        "the id of a frame that went out reused"
    );
    // The old frame's answer comes late, then the new one's: each is its own.
    fake.status(old_id, DeliveryStatus::Success).await;
    fake.status(tx.frame_id, DeliveryStatus::from(0x24)).await;
    let result = doomed.await.unwrap();
    assert!(
        matches!(result, Err(SendError::Delivery { .. })),
        "{result:?}"
    );
}

#[tokio::test]
async fn a_request_before_the_first_peer_says_the_link_is_not_connected_yet() {
    let link = mcp_host::Link::tcp_listen("127.0.0.1", 0);
    let (stream, sender) = mcp_host::connect(&link, LinkOptions::default())
        .await
        .unwrap();
    let addr = stream.info().local_addr.unwrap();
    let err = sender.send(MAV, &Command::landing(true)).await.unwrap_err();
    assert!(matches!(err, SendError::Disconnected { .. }), "{err:?}");
    assert_eq!(
        err.to_string(),
        format!("link down: not connected yet to tcp-listen:{addr}")
    );
}
