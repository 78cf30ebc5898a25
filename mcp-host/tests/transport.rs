//! Links opened for real: pseudo-terminals and TCP on 127.0.0.1.

use std::time::Duration;

use mcp_host::{Connector, Link, LinkError, LinkOptions, ReconnectPolicy};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::{TcpListener, TcpStream};
use tokio::time::timeout;

mod common;

/// Failure guard only: every wait below ends on an event long before this.
const GUARD: Duration = Duration::from_secs(10);

fn fast_reconnect() -> LinkOptions {
    LinkOptions {
        reconnect: ReconnectPolicy {
            enabled: true,
            initial_delay: Duration::from_millis(5),
            max_delay: Duration::from_millis(50),
        },
        ..LinkOptions::default()
    }
}

/// A `tcp-listen` connector on a free port of 127.0.0.1, and its address.
async fn listening() -> (Connector, std::net::SocketAddr) {
    let link: Link = "tcp-listen:127.0.0.1:0".parse().unwrap();
    let connector = Connector::new(&link, &fast_reconnect()).await.unwrap();
    let addr = connector.local_addr().unwrap();
    (connector, addr)
}

/// A peer that connects to `addr`, writes `bytes` and waits for its turn: it has the
/// waiting place once a peer after it is turned away.
async fn waiting_peer(addr: std::net::SocketAddr, bytes: &[u8]) -> TcpStream {
    let mut peer = TcpStream::connect(addr).await.unwrap();
    peer.write_all(bytes).await.unwrap();
    let mut turned_away = TcpStream::connect(addr).await.unwrap();
    is_turned_away(&mut turned_away).await;
    peer
}

/// The transport of the next peer the connector serves.
async fn next_served(connector: &mut Connector) -> mcp_host::Transport {
    timeout(GUARD, connector.reopen(&fast_reconnect().reconnect))
        .await
        .expect("no peer served in time")
        .unwrap()
}

/// The transport of the next peer the connector serves, whose first bytes are `bytes`.
async fn served_next_with(connector: &mut Connector, bytes: &[u8]) -> mcp_host::Transport {
    let mut transport = next_served(connector).await;
    assert_eq!(read_exact_n(&mut transport, bytes.len()).await, bytes);
    transport
}

/// A peer hangs up: it shuts its sending side (the link reads the end of its stream)
/// and closes.
async fn hang_up(mut peer: TcpStream) {
    peer.shutdown().await.unwrap();
}

/// Waits for the end of `r`'s stream: the peer hung up, with nothing more to read.
async fn reads_end<R: AsyncReadExt + Unpin>(r: &mut R) {
    let mut buf = [0u8; 8];
    let n = timeout(GUARD, r.read(&mut buf))
        .await
        .expect("read timed out")
        .expect("read failed");
    assert_eq!(n, 0, "bytes after the peer hung up: {:02X?}", &buf[..n]);
}

/// A peer turned away reads the end of its stream, or a reset if it wrote first.
async fn is_turned_away(peer: &mut TcpStream) {
    let mut buf = [0u8; 8];
    match timeout(GUARD, peer.read(&mut buf)).await {
        Ok(Ok(0) | Err(_)) => {}
        other => panic!("not turned away: {other:?}"),
    }
}

async fn read_exact_n<R: AsyncReadExt + Unpin>(r: &mut R, n: usize) -> Vec<u8> {
    let mut buf = vec![0; n];
    timeout(GUARD, r.read_exact(&mut buf))
        .await
        .expect("read timed out")
        .expect("read failed");
    buf
}

#[cfg(unix)]
#[tokio::test]
async fn pty_is_up_while_a_device_has_the_far_end_open_and_nothing_stale_reaches_the_next() {
    let mut connector = Connector::new(&Link::Pty, &LinkOptions::default())
        .await
        .unwrap();
    let path = connector.pty_path().unwrap().to_owned();
    assert!(path.exists(), "{path:?}");
    for round in 0..2u8 {
        // Opening waits for a device on the far end.
        let open = tokio::spawn(async move {
            let local = connector.open().await;
            (connector, local)
        });
        let mut far =
            tokio_serial::SerialStream::open(&tokio_serial::new(path.to_str().unwrap(), 115_200))
                .unwrap();
        let (back, local) = timeout(GUARD, open).await.unwrap().unwrap();
        connector = back;
        let mut local = local.unwrap();
        assert_eq!(local.peer(), path.display().to_string());
        // Bytes both ways; the first the device reads are the first written for it,
        // nothing left from the device before.
        far.write_all(&[0x7E, round, 0x11]).await.unwrap();
        assert_eq!(read_exact_n(&mut local, 3).await, [0x7E, round, 0x11]);
        local.write_all(&[0x7D, 0x33, round]).await.unwrap();
        assert_eq!(read_exact_n(&mut far, 3).await, [0x7D, 0x33, round]);
        // Written for this device, which leaves without reading it.
        local.write_all(&[0xAA; 8]).await.unwrap();
        local.flush().await.unwrap();
        drop(far);
        // The transport ends with the device.
        let mut rest = [0u8; 16];
        let n = timeout(GUARD, local.read(&mut rest))
            .await
            .unwrap()
            .unwrap();
        assert_eq!(n, 0, "end of stream once the device closed the far end");
        assert!(path.exists());
        drop(local);
    }
}

/// A request on a pty link before anything opened its far end fails saying which path
/// to open.
#[cfg(unix)]
#[tokio::test]
async fn a_pty_link_not_opened_yet_says_its_far_ends_path() {
    let (_stream, sender) = mcp_host::connect(&Link::Pty, LinkOptions::default())
        .await
        .unwrap();
    let path = sender.info().pty_path.clone().unwrap();
    let err = sender
        .send_payload(
            xbee_api::Address64(0x0013_A200_40B5_99B9),
            &b"c\x02\x01"[..],
            Default::default(),
        )
        .await
        .unwrap_err();
    assert_eq!(
        err.to_string(),
        format!(
            "link down: not connected yet to pty (its far end {}, which no program has open)",
            path.display()
        )
    );
}

/// Opens the far end of a pseudo-terminal as a short-lived program does (`echo > PATH`),
/// writes `bytes` and closes it again at once.
#[cfg(unix)]
fn write_and_leave(path: &std::path::Path, bytes: &[u8]) {
    use std::io::Write;
    use std::os::unix::fs::OpenOptionsExt;
    let mut far = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .custom_flags(libc::O_NOCTTY)
        .open(path)
        .unwrap();
    far.write_all(bytes).unwrap();
}

#[cfg(unix)]
#[tokio::test]
async fn pty_serves_a_device_that_writes_and_leaves_between_two_looks() {
    let mut connector = Connector::new(&Link::Pty, &LinkOptions::default())
        .await
        .unwrap();
    let path = connector.pty_path().unwrap().to_owned();
    // Many times: the link looks for a peer now and then, and a device that is gone
    // before the next look must be served all the same.
    for round in 0..20u8 {
        let open = tokio::spawn(async move {
            let local = connector.open().await;
            (connector, local)
        });
        write_and_leave(&path, &[0x7E, round, 0x22]);
        let (back, local) = timeout(GUARD, open)
            .await
            .unwrap_or_else(|_| panic!("round {round}: the device was not seen"))
            .unwrap();
        connector = back;
        let mut local = local.unwrap();
        // What it wrote now, then the end of the stream: it left.
        assert_eq!(read_exact_n(&mut local, 3).await, [0x7E, round, 0x22]);
        reads_end(&mut local).await;
    }
    // The next device finds nothing stale, and what it writes comes first.
    let open = tokio::spawn(async move { connector.open().await });
    let mut far =
        tokio_serial::SerialStream::open(&tokio_serial::new(path.to_str().unwrap(), 115_200))
            .unwrap();
    let mut local = timeout(GUARD, open).await.unwrap().unwrap().unwrap();
    far.write_all(&[0x7E, 0xFF]).await.unwrap();
    assert_eq!(read_exact_n(&mut local, 2).await, [0x7E, 0xFF]);
}

#[tokio::test]
async fn tcp_reconnects_after_the_peer_goes_away() {
    let listener = TcpListener::bind("127.0.0.1:0").await.unwrap();
    let port = listener.local_addr().unwrap().port();
    let link: Link = format!("tcp:127.0.0.1:{port}").parse().unwrap();
    let options = fast_reconnect();
    let mut connector = Connector::new(&link, &options).await.unwrap();

    let mut transport = connector.open().await.unwrap();
    let (mut peer, _) = listener.accept().await.unwrap();
    peer.write_all(b"one").await.unwrap();
    assert_eq!(read_exact_n(&mut transport, 3).await, b"one");
    connector.mark_healthy();

    // The peer goes away: the transport reads end of file.
    drop(peer);
    reads_end(&mut transport).await;
    drop(transport);

    // Reconnection succeeds once the peer accepts again.
    let (reopened, accepted) =
        tokio::join!(connector.reopen(&options.reconnect), listener.accept());
    let mut transport = reopened.unwrap();
    let (mut peer, _) = accepted.unwrap();
    peer.write_all(b"two").await.unwrap();
    assert_eq!(read_exact_n(&mut transport, 3).await, b"two");
}

#[tokio::test]
async fn tcp_reconnect_retries_until_the_port_listens_again() {
    // A port held but not listening: the first attempts are refused.
    let reserved = common::ReservedPort::new();
    let port = reserved.port;
    let link: Link = format!("tcp:127.0.0.1:{port}").parse().unwrap();
    let options = fast_reconnect();
    let mut connector = Connector::new(&link, &options).await.unwrap();
    let err = connector.open().await.unwrap_err();
    assert!(matches!(err, LinkError::Connect { .. }), "{err}");
    assert!(err.is_retryable());
    assert!(
        err.to_string().contains(&format!("127.0.0.1:{port}")),
        "{err}"
    );
    // The system's reason is in the message, once in a report of the whole chain.
    let LinkError::Connect { error, .. } = &err else {
        unreachable!()
    };
    assert!(err.to_string().ends_with(&error.to_string()), "{err}");
    assert_eq!(common::error_chain(&err), [err.to_string()]);

    let reopen = tokio::spawn(async move {
        let transport = connector.reopen(&fast_reconnect().reconnect).await;
        transport.map(|t| t.peer().to_owned())
    });
    let listener = reserved.listen_tokio();
    let (_peer, _) = timeout(GUARD, listener.accept()).await.unwrap().unwrap();
    let peer = timeout(GUARD, reopen).await.unwrap().unwrap().unwrap();
    assert_eq!(peer, format!("127.0.0.1:{port}"));
}

#[tokio::test]
async fn disabled_reconnect_gives_up_at_once() {
    let listener = TcpListener::bind("127.0.0.1:0").await.unwrap();
    let port = listener.local_addr().unwrap().port();
    let link: Link = format!("tcp:127.0.0.1:{port}").parse().unwrap();
    let mut connector = Connector::new(&link, &LinkOptions::default())
        .await
        .unwrap();
    let err = connector
        .reopen(&ReconnectPolicy::disabled())
        .await
        .unwrap_err();
    assert!(matches!(err, LinkError::ReconnectDisabled));
    assert!(!err.is_retryable());
}

#[tokio::test]
async fn tcp_listen_serves_one_peer_at_a_time() {
    let (mut connector, addr) = listening().await;

    let mut first = TcpStream::connect(addr).await.unwrap();
    let mut transport = connector.open().await.unwrap();
    assert_eq!(transport.peer(), first.local_addr().unwrap().to_string());

    // A second peer connects while the first is served: it waits for its turn, and
    // what it sends is not mixed into the first peer's stream. A third is turned away
    // (closed at once).
    let mut second = TcpStream::connect(addr).await.unwrap();
    second.write_all(b"2nd").await.unwrap();
    let mut third = TcpStream::connect(addr).await.unwrap();
    let _ = third.write_all(b"3rd").await;
    let mut rest = Vec::new();
    let closed = timeout(GUARD, third.read_to_end(&mut rest))
        .await
        .expect("the third peer was not turned away");
    assert!(closed.is_err() || rest.is_empty(), "{closed:?} {rest:?}");
    first.write_all(b"1st").await.unwrap();
    assert_eq!(read_exact_n(&mut transport, 3).await, b"1st");

    drop(first);
    reads_end(&mut transport).await;

    // The next open takes the waiting peer, with what it wrote while it waited.
    let mut transport = next_served(&mut connector).await;
    assert_eq!(transport.peer(), second.local_addr().unwrap().to_string());
    assert_eq!(read_exact_n(&mut transport, 3).await, b"2nd");
    transport.write_all(b"ack").await.unwrap();
    assert_eq!(read_exact_n(&mut second, 3).await, b"ack");

    // A peer that waits, writes and leaves before its turn is dropped with what it
    // wrote: the next open takes the peer after it. (It waits once another is turned
    // away.)
    let mut gone = waiting_peer(addr, b"old").await;
    gone.shutdown().await.unwrap();
    drop(second);
    reads_end(&mut transport).await;
    drop(transport);
    let policy = fast_reconnect().reconnect;
    let reopened = connector.reopen(&policy);
    tokio::pin!(reopened);
    // The open drops `gone`, which then reads the end of its stream; only then is the
    // waiting place free for the next peer.
    tokio::select! {
        t = &mut reopened => panic!("served a peer that had left: {:?}", t.map(|t| t.peer().to_owned())),
        () = reads_end(&mut gone) => {}
    }
    let mut last = TcpStream::connect(addr).await.unwrap();
    last.write_all(b"new").await.unwrap();
    let mut transport = timeout(GUARD, reopened).await.unwrap().unwrap();
    assert_eq!(transport.peer(), last.local_addr().unwrap().to_string());
    assert_eq!(read_exact_n(&mut transport, 3).await, b"new");
    transport.write_all(b"ack").await.unwrap();
    assert_eq!(read_exact_n(&mut last, 3).await, b"ack");
}

#[tokio::test]
async fn tcp_listen_gives_the_waiting_place_of_a_peer_that_left_to_the_next() {
    let (mut connector, addr) = listening().await;
    let mut first = TcpStream::connect(addr).await.unwrap();
    let mut transport = connector.open().await.unwrap();

    // A second peer waits, writes and leaves; a third comes: it takes the place.
    let mut gone = TcpStream::connect(addr).await.unwrap();
    gone.write_all(b"old").await.unwrap();
    drop(gone);
    let mut third = TcpStream::connect(addr).await.unwrap();
    third.write_all(b"new").await.unwrap();

    drop(first.shutdown().await);
    drop(first);
    reads_end(&mut transport).await;
    drop(transport);
    let mut transport = next_served(&mut connector).await;
    assert_eq!(transport.peer(), third.local_addr().unwrap().to_string());
    assert_eq!(read_exact_n(&mut transport, 3).await, b"new");
}

#[tokio::test]
async fn tcp_listen_serves_a_peer_that_left_after_its_turn_came() {
    let (mut connector, addr) = listening().await;
    let first = TcpStream::connect(addr).await.unwrap();
    let mut transport = connector.open().await.unwrap();

    // A second peer waits and writes; its turn comes when the first's transport ends,
    // and it leaves after that, before the link takes it (as a command sent without
    // waiting for an answer does): what it wrote is carried out.
    let mut second = TcpStream::connect(addr).await.unwrap();
    second.write_all(b"2nd").await.unwrap();
    drop(first);
    reads_end(&mut transport).await;
    drop(transport);
    hang_up(second).await;
    let mut transport = served_next_with(&mut connector, b"2nd").await;
    reads_end(&mut transport).await;
    drop(transport);

    // Between peers nobody is ahead of a new one: its turn comes as it connects.
    let mut third = TcpStream::connect(addr).await.unwrap();
    third.write_all(b"3rd").await.unwrap();
    hang_up(third).await;
    served_next_with(&mut connector, b"3rd").await;
}

#[tokio::test]
async fn tcp_listen_serves_a_peer_that_came_after_the_served_one_hung_up() {
    let (mut connector, addr) = listening().await;
    let first = TcpStream::connect(addr).await.unwrap();
    let mut transport = connector.open().await.unwrap();
    // The first hangs up (a one-shot command that ended); the link has not read that
    // yet when the next connects and writes.
    drop(first);
    let mut second = TcpStream::connect(addr).await.unwrap();
    second.write_all(b"cmd").await.unwrap();
    // It has taken the waiting place once a third is turned away.
    let mut third = TcpStream::connect(addr).await.unwrap();
    reads_end(&mut third).await;
    // It leaves, done (a command sent without waiting for an answer), before the link
    // reads the first one's end: nobody was ahead of it, so it is served all the same.
    hang_up(second).await;
    reads_end(&mut transport).await;
    drop(transport);
    served_next_with(&mut connector, b"cmd").await;
}

#[tokio::test]
async fn tcp_listen_serves_two_commands_sent_back_to_back_before_it_read_the_first() {
    let (mut connector, addr) = listening().await;
    let mut first = TcpStream::connect(addr).await.unwrap();
    let mut transport = connector.open().await.unwrap();
    // Two commands sent without waiting for an answer, one after the other: the link
    // has read neither the first's bytes nor its end when the second comes.
    first.write_all(b"1st").await.unwrap();
    hang_up(first).await;
    let second = waiting_peer(addr, b"2nd").await;
    hang_up(second).await;
    // Both are carried out, in order.
    assert_eq!(read_exact_n(&mut transport, 3).await, b"1st");
    reads_end(&mut transport).await;
    drop(transport);
    served_next_with(&mut connector, b"2nd").await;
}

#[tokio::test]
async fn tcp_listen_keeps_the_place_of_a_peer_whose_turn_came() {
    let (mut connector, addr) = listening().await;
    let first = TcpStream::connect(addr).await.unwrap();
    let mut transport = connector.open().await.unwrap();
    let second = waiting_peer(addr, b"2nd").await;
    // The first hangs up: the second's turn has come; then it leaves, done.
    drop(first);
    reads_end(&mut transport).await;
    hang_up(second).await;
    // A third comes before the link takes the second: it is turned away, not let in
    // the second's place.
    let mut third = TcpStream::connect(addr).await.unwrap();
    let _ = third.write_all(b"3rd").await;
    is_turned_away(&mut third).await;
    drop(transport);
    let transport = served_next_with(&mut connector, b"2nd").await;

    // With nobody served, the same: the first to come is served.
    drop(transport);
    let mut fourth = TcpStream::connect(addr).await.unwrap();
    fourth.write_all(b"4th").await.unwrap();
    hang_up(fourth).await;
    let mut fifth = TcpStream::connect(addr).await.unwrap();
    let _ = fifth.write_all(b"5th").await;
    is_turned_away(&mut fifth).await;
    served_next_with(&mut connector, b"4th").await;
}

#[tokio::test]
async fn tcp_listen_a_read_into_no_room_is_no_end_of_stream() {
    let (mut connector, addr) = listening().await;
    let mut first = TcpStream::connect(addr).await.unwrap();
    let mut transport = connector.open().await.unwrap();
    first.write_all(b"1").await.unwrap();
    let empty = timeout(GUARD, transport.read(&mut [])).await.unwrap();
    assert_eq!(empty.unwrap(), 0);
    assert_eq!(read_exact_n(&mut transport, 1).await, b"1");
    // The first is still served: a peer that waits, writes and gives up meanwhile is
    // dropped.
    let gave_up = waiting_peer(addr, b"old").await;
    hang_up(gave_up).await;
    drop(first);
    reads_end(&mut transport).await;
    drop(transport);
    let mut last = TcpStream::connect(addr).await.unwrap();
    last.write_all(b"new").await.unwrap();
    served_next_with(&mut connector, b"new").await;
}

#[tokio::test]
async fn tcp_listen_a_transport_that_outlives_its_turn_ends_no_other() {
    let (mut connector, addr) = listening().await;
    let _first = TcpStream::connect(addr).await.unwrap();
    let old = connector.open().await.unwrap();
    // Opened again while the first transport lives: the next peer is served.
    let mut second = TcpStream::connect(addr).await.unwrap();
    let mut transport = connector.open().await.unwrap();
    assert_eq!(transport.peer(), second.local_addr().unwrap().to_string());
    drop(old);
    // The second is still served: a peer that waits, writes and gives up meanwhile is
    // dropped.
    let gave_up = waiting_peer(addr, b"old").await;
    hang_up(gave_up).await;
    second.shutdown().await.unwrap();
    reads_end(&mut transport).await;
    drop(transport);
    let mut last = TcpStream::connect(addr).await.unwrap();
    last.write_all(b"new").await.unwrap();
    served_next_with(&mut connector, b"new").await;
}

/// A serial link on the far end of a pseudo-terminal holds it by its lock alone, not by
/// the terminal's exclusive flag, which would outlive a process killed while holding
/// it; the lock still turns away a second link on the same path until the first closes.
#[cfg(target_os = "linux")]
#[tokio::test]
async fn a_serial_link_holds_a_pseudo_terminal_by_its_lock_alone() {
    let pty = Connector::new(&Link::Pty, &LinkOptions::default())
        .await
        .unwrap();
    let path = pty.pty_path().unwrap().to_owned();
    let link: Link = format!("serial:{}", path.display()).parse().unwrap();
    let mut first = Connector::new(&link, &LinkOptions::default())
        .await
        .unwrap();
    let held = first.open().await.unwrap();
    assert!(!common::far_end_is_exclusive(&path));
    let mut second = Connector::new(&link, &LinkOptions::default())
        .await
        .unwrap();
    let err = second.open().await.unwrap_err();
    assert!(
        matches!(&err, LinkError::Serial { error, .. }
            if error.kind == tokio_serial::ErrorKind::NoDevice),
        "{err}"
    );
    drop(held);
    second.open().await.unwrap();
}

/// The error of a `connect` to `link` that waits for a link not there yet, which gives
/// up at once all the same: no retry can make `link` work.
async fn refused_at_once(link: &Link) -> mcp_host::ConnectError {
    let options = LinkOptions {
        wait_for_link: true,
        ..LinkOptions::default()
    };
    // Bounded: waited on, it would never end.
    let connect = mcp_host::connect(link, options);
    let err = tokio::time::timeout(Duration::from_secs(20), connect)
        .await
        .expect("connect gives up at once")
        .unwrap_err();
    assert!(!err.is_retryable(), "{err}");
    err
}

#[tokio::test]
async fn open_errors_are_clear() {
    let link: Link = "serial:/dev/does-not-exist-mcp:9600".parse().unwrap();
    let mut connector = Connector::new(&link, &LinkOptions::default())
        .await
        .unwrap();
    let err = connector.open().await.unwrap_err();
    assert!(err.is_retryable());
    let text = err.to_string();
    assert!(
        text.contains("/dev/does-not-exist-mcp") && text.contains("9600"),
        "{text}"
    );

    let taken = TcpListener::bind("127.0.0.1:0").await.unwrap();
    let port = taken.local_addr().unwrap().port();
    let link: Link = format!("tcp-listen:127.0.0.1:{port}").parse().unwrap();
    let err = Connector::new(&link, &LinkOptions::default())
        .await
        .unwrap_err();
    assert!(matches!(err, LinkError::Listen { .. }));
    assert!(!err.is_retryable());

    // Port 0 can only be a mistake (`tcp:HOST:0` does not parse): not waited on.
    let link = Link::tcp("127.0.0.1", 0);
    let err = refused_at_once(&link).await;
    assert!(err.to_string().contains("port 0"), "{err}");

    // A path that is there but is no device (a directory, a regular file) never
    // becomes one: not waited on either.
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("not-a-device");
    std::fs::write(&file, b"").unwrap();
    for path in [dir.path().to_path_buf(), file] {
        let link = Link::serial(path.display().to_string(), 9600);
        let err = refused_at_once(&link).await;
        assert!(
            err.to_string().contains(&path.display().to_string()),
            "{err}"
        );
    }
    // Nor does a device that is no terminal.
    #[cfg(unix)]
    {
        let err = refused_at_once(&Link::serial("/dev/null", 9600)).await;
        assert!(err.to_string().contains("/dev/null"), "{err}");
    }
}

// A pseudo-terminal's master side reads the far end's settings (Linux).
#[cfg(target_os = "linux")]
#[tokio::test]
async fn a_serial_link_opens_its_port_with_the_flow_control_it_names() {
    use tokio_serial::{FlowControl, SerialPort};
    let (master, slave) = tokio_serial::SerialStream::pair().unwrap();
    let path = slave.name().unwrap();
    drop(slave);
    for (suffix, expected) in [
        (":rtscts", FlowControl::Hardware),
        ("", FlowControl::None),
        (":rtscts", FlowControl::Hardware),
    ] {
        let link: Link = format!("serial:{path}:57600{suffix}").parse().unwrap();
        let mut connector = Connector::new(&link, &LinkOptions::default())
            .await
            .unwrap();
        let transport = connector.open().await.unwrap();
        assert_eq!(master.flow_control().unwrap(), expected, "{link}");
        assert_eq!(master.baud_rate().unwrap(), 57_600, "{link}");
        drop(transport);
    }
}

// Paused clock: the delays below are the reconnection's own sleeps, exactly.
#[cfg(unix)]
#[tokio::test(start_paused = true)]
async fn backoff_starts_again_only_after_a_connection_that_lasted() {
    use tokio::time::Instant;
    // A serial link, on a pseudo-terminal whose far end stays there.
    let (_master, slave) = tokio_serial::SerialStream::pair().unwrap();
    let path = tokio_serial::SerialPort::name(&slave).unwrap();
    drop(slave);
    let link: Link = format!("serial:{path}").parse().unwrap();
    let policy = ReconnectPolicy {
        enabled: true,
        initial_delay: Duration::from_millis(100),
        max_delay: Duration::from_secs(1),
    };
    let mut connector = Connector::new(&link, &LinkOptions::default())
        .await
        .unwrap();
    let mut transport = connector.open().await.unwrap();

    // (carried data, stayed up for) -> the delay before the next transport.
    let steps = [
        // A radio that answers and goes away at once, again and again: backing off.
        (true, Duration::ZERO, 100),
        (true, Duration::ZERO, 200),
        (true, Duration::ZERO, 400),
        // A transport that worked for max_delay: from the start again.
        (true, Duration::from_secs(1), 100),
        // Up as long, but no data: backing off.
        (false, Duration::from_secs(1), 200),
    ];
    for (step, (carried, lasted, delay)) in steps.into_iter().enumerate() {
        if carried {
            connector.mark_healthy();
        }
        tokio::time::advance(lasted).await;
        drop(transport);
        let started = Instant::now();
        transport = connector.reopen(&policy).await.unwrap();
        assert_eq!(
            started.elapsed(),
            Duration::from_millis(delay),
            "step {step}"
        );
    }
}

/// A `tcp-listen` port is free as soon as the link has closed or the network that
/// listened on it has stopped, on a multi-threaded runtime too, and with a peer
/// connected and one waiting: the same port is listened on again at once.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_listening_port_is_free_once_its_link_closed_or_its_network_stopped() {
    use mcp_host::radio::{Network, NetworkConfig, NodeOptions};
    use xbee_api::Address64;
    let link: Link = "tcp-listen:127.0.0.1:0".parse().unwrap();
    for round in 0..20 {
        let (stream, sender) = mcp_host::connect(&link, LinkOptions::default())
            .await
            .unwrap();
        let addr = stream.info().local_addr.unwrap();
        let _peers = (
            TcpStream::connect(addr).await.unwrap(),
            TcpStream::connect(addr).await.unwrap(),
        );
        sender.close();
        sender.closed().await;
        let again = TcpListener::bind(addr).await;
        assert!(again.is_ok(), "round {round}, link: {again:?}");
        drop((again, stream));

        let network = Network::new(NetworkConfig::default());
        let node = network
            .add_link(Address64::COORDINATOR, &link, NodeOptions::default())
            .await
            .unwrap();
        let addr = node.local_addr.unwrap();
        let _peers = (
            TcpStream::connect(addr).await.unwrap(),
            TcpStream::connect(addr).await.unwrap(),
        );
        network.stop().await;
        let again = TcpListener::bind(addr).await;
        assert!(again.is_ok(), "round {round}, network: {again:?}");
    }
}
