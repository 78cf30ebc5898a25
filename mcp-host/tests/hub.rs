//! One radio shared by several ground stations through a `Hub`, over real TCP sockets:
//! a simulated MAV behind a virtual radio, a hub on its link, ground stations on the
//! hub.

mod common;

use std::time::Duration;

use common::hub_wire::*;
use futures::StreamExt;
use mcp_core::{Command, LandingState, Packet, Report, StatusRequest, TelemetryId};
use mcp_host::hub::Hub;
use mcp_host::{CommandSender, DeliveryReport, Event, Link, LinkOptions, PacketStream, SendError};
use xbee_api::{Address64, ApiMode, DeliveryStatus};

/// Failure guard only: every wait ends on a packet long before this.
const GUARD: Duration = Duration::from_secs(20);
const MAV: Address64 = Address64(0x0013_A200_40B5_99B9);
/// No radio has this address: its transmissions fail.
const NOBODY: Address64 = Address64(0x0013_A200_0000_0001);

async fn client(hub: &Hub, mode: ApiMode) -> (PacketStream, CommandSender) {
    let link: Link = format!("tcp:{}", hub.local_addr()).parse().unwrap();
    let options = LinkOptions {
        api_mode: mode,
        ..LinkOptions::default()
    };
    mcp_host::connect(&link, options).await.unwrap()
}

/// The next telemetry packet's altitude on `stream`.
async fn next_altitude(stream: &mut PacketStream) -> f32 {
    loop {
        let event = tokio::time::timeout(GUARD, stream.next())
            .await
            .expect("no telemetry")
            .expect("stream ended");
        if let Event::Packet(rx) = event {
            if let Packet::Telemetry(t) = &rx.packet {
                if let Some(value) = t.value(TelemetryId::Altitude) {
                    return value;
                }
            }
        }
    }
}

async fn shares_one_radio(mode: ApiMode) {
    let (sim, hub) = sim_and_hub(mode).await;
    let (mut watch_a, a) = client(&hub, mode).await;
    let (mut watch_b, b) = client(&hub, mode).await;

    // Both ground stations count their frame ids from 1: at the same time, one's
    // transmission fails and the other's is delivered, and each gets its own status.
    let (off, on) = (
        Command::landing(false),
        Command::telemetry_to_coordinator(true, TelemetryId::Altitude),
    );
    let (failed, delivered) = tokio::join!(a.send(NOBODY, &off), b.send(MAV, &on));
    assert!(
        matches!(
            failed,
            Err(SendError::Delivery { to: NOBODY, status, .. }) if status != DeliveryStatus::Success
        ),
        "{failed:?}"
    );
    assert!(
        matches!(delivered, Ok(DeliveryReport::Delivered { .. })),
        "{delivered:?}"
    );

    // Telemetry turned on by one reaches both.
    next_altitude(&mut watch_a).await;
    next_altitude(&mut watch_b).await;

    // Requests from both at once, each answered.
    let (ra, rb) = tokio::join!(
        a.request(MAV, StatusRequest::Landing),
        b.request(MAV, StatusRequest::Time),
    );
    assert!(
        matches!(ra, Ok(Report::Landing(LandingState::Flight))),
        "{ra:?}"
    );
    assert!(matches!(rb, Ok(Report::Time(_))), "{rb:?}");

    // AT commands from both at once (frame id 1 each), each answered with its own.
    let (sh, sl) = tokio::join!(a.at(*b"SH", &[], None), b.at(*b"SL", &[], None));
    let (sh, sl) = (sh.unwrap(), sl.unwrap());
    assert_eq!(&sh.data()[2..4], b"SH");
    assert_eq!(&sl.data()[2..4], b"SL");

    let stats = hub.stats();
    assert!(stats.listening);
    assert_eq!(stats.clients, 2);
    assert!(stats.frames_from_radio > 0 && stats.frames_from_clients >= 6);
    // Every frame read from the clients answered: none waits, none was refused.
    assert_eq!(
        stats.frames_read_from_clients, stats.frames_from_clients,
        "{stats:?}"
    );
    assert_eq!(stats.frames_refused, 0, "{stats:?}");
    // The hub's own link saw every frame it passed on, whole, and kept up.
    assert!(stats.radio.frames >= stats.frames_from_radio, "{stats:?}");
    assert_eq!(stats.radio.decode_errors(), 0, "{stats:?}");
    assert_eq!(stats.radio.events_dropped, 0, "{stats:?}");
    a.close();
    b.close();
    a.closed().await;
    b.closed().await;
    hub.stop().await;
    sim.stop().await;
}

#[tokio::test]
async fn two_ground_stations_share_one_radio_in_api_mode_1() {
    shares_one_radio(ApiMode::Unescaped).await;
}

#[tokio::test]
async fn two_ground_stations_share_one_radio_in_api_mode_2() {
    shares_one_radio(ApiMode::Escaped).await;
}

#[tokio::test]
async fn a_client_that_leaves_does_not_disturb_the_others() {
    let mode = ApiMode::Unescaped;
    let (sim, hub) = sim_and_hub(mode).await;
    let (mut watch, a) = client(&hub, mode).await;
    let (gone_stream, gone) = client(&hub, mode).await;
    a.send(
        MAV,
        &Command::telemetry_to_coordinator(true, TelemetryId::Altitude),
    )
    .await
    .unwrap();
    next_altitude(&mut watch).await;
    gone.close();
    gone.closed().await;
    drop(gone_stream);
    // Telemetry goes on arriving, and requests are answered.
    next_altitude(&mut watch).await;
    let report = a.request(MAV, StatusRequest::Landing).await;
    assert!(matches!(report, Ok(Report::Landing(_))), "{report:?}");
    // The port is free once the hub has stopped.
    let port = hub.local_addr();
    hub.stop().await;
    std::net::TcpListener::bind(port).expect("the hub's port is free");
    sim.stop().await;
}

#[tokio::test]
async fn a_client_with_many_requests_in_flight_gets_every_answer() {
    use futures::SinkExt;
    use mcp_host::codec::XBeeCodec;
    use xbee_api::{AtCommandRepr, Frame};

    let mode = ApiMode::Unescaped;
    let (sim, hub) = sim_and_hub(mode).await;
    let socket = tokio::net::TcpStream::connect(hub.local_addr())
        .await
        .unwrap();
    let mut framed = tokio_util::codec::Framed::new(socket, XBeeCodec::new(mode));
    // 200 AT commands at once, frame ids 1 to 200, all waiting for answers together.
    for id in 1..=200u8 {
        let at = AtCommandRepr {
            queued: false,
            frame_id: id,
            command: *b"SH",
            parameter: &[],
        };
        framed.feed(&at).await.unwrap();
    }
    SinkExt::<&AtCommandRepr<'_>>::flush(&mut framed)
        .await
        .unwrap();
    let mut answered = [false; 256];
    let mut count = 0;
    while count < 200 {
        let data = next(&mut framed).await;
        if let Ok(Frame::AtCommandResponse(at)) = Frame::parse_bytes(&data) {
            assert_eq!(at.command, *b"SH");
            assert!(
                !answered[usize::from(at.frame_id)],
                "id {} twice",
                at.frame_id
            );
            answered[usize::from(at.frame_id)] = true;
            count += 1;
        }
    }
    assert!(answered[1..=200].iter().all(|&a| a));
    hub.stop().await;
    sim.stop().await;
}

/// A radio played by the test on a TCP socket: the hub's link connects to it.
struct FakeRadio {
    framed: tokio_util::codec::Framed<tokio::net::TcpStream, mcp_host::codec::XBeeCodec>,
}

impl FakeRadio {
    /// A hub on a fake radio: the radio's side once the hub has connected.
    async fn with_hub() -> (FakeRadio, Hub) {
        let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
        let (hub, socket) = hub_on(&listener).await;
        (FakeRadio::on(socket), hub)
    }

    fn on(socket: tokio::net::TcpStream) -> FakeRadio {
        let framed = tokio_util::codec::Framed::new(
            socket,
            mcp_host::codec::XBeeCodec::new(ApiMode::Unescaped),
        );
        FakeRadio { framed }
    }

    /// The next frame the hub writes to the radio (frame data).
    async fn next_frame(&mut self) -> Vec<u8> {
        loop {
            let item = tokio::time::timeout(GUARD, self.framed.next())
                .await
                .expect("a frame for the radio")
                .expect("the hub stays")
                .unwrap();
            if let mcp_host::codec::CodecItem::Frame(frame) = item {
                return frame.data().to_vec();
            }
        }
    }

    /// `data` `n` times, in one go.
    async fn send_many(&mut self, data: &[u8], n: usize) {
        use futures::SinkExt;
        let frame = xbee_api::RawFrame::new(data).unwrap();
        for _ in 0..n {
            self.framed.feed(&frame).await.unwrap();
        }
        SinkExt::<&xbee_api::RawFrame<'_>>::flush(&mut self.framed)
            .await
            .unwrap();
    }

    async fn send(&mut self, data: &[u8]) {
        use futures::SinkExt;
        let frame = xbee_api::RawFrame::new(data).unwrap();
        self.framed.send(&frame).await.unwrap();
    }
}

/// A hub whose radio link connects to `listener` (API mode 1), and the radio's socket.
async fn hub_on(listener: &tokio::net::TcpListener) -> (Hub, tokio::net::TcpStream) {
    let radio: Link = format!("tcp:{}", listener.local_addr().unwrap())
        .parse()
        .unwrap();
    let (hub, socket) = tokio::join!(
        Hub::start(&radio, LinkOptions::default(), "127.0.0.1:0"),
        radio_accepted(listener)
    );
    (hub.unwrap(), socket)
}

/// A client speaking frames on a raw TCP connection to the hub.
#[tokio::test]
async fn a_clients_frames_reach_the_radio_in_its_order() {
    let (mut radio, hub) = FakeRadio::with_hub().await;
    let mut client = raw_client(&hub).await;
    // Set a name (id 1), save it (id 2), then apply without an answer (id 0).
    send(&mut client, &[0x08, 0x01, b'N', b'I', b'A']).await;
    send(&mut client, &[0x08, 0x02, b'W', b'R']).await;
    send(&mut client, &[0x08, 0x00, b'A', b'C']).await;
    let commands: Vec<[u8; 2]> = [
        radio.next_frame().await,
        radio.next_frame().await,
        radio.next_frame().await,
    ]
    .iter()
    .map(|f| [f[2], f[3]])
    .collect();
    assert_eq!(commands, [*b"NI", *b"WR", *b"AC"]);
    hub.stop().await;
}

#[tokio::test]
async fn every_answer_to_a_discovery_goes_to_the_client_that_asked_alone() {
    let (mut radio, hub) = FakeRadio::with_hub().await;
    let mut a = raw_client(&hub).await;
    let mut b = raw_client(&hub).await;
    // Both count their frame ids from 1.
    send(&mut a, &[0x08, 0x01, b'N', b'D']).await;
    let nd = radio.next_frame().await;
    send(&mut b, &[0x08, 0x01, b'N', b'I']).await;
    let ni = radio.next_frame().await;
    assert_ne!(nd[1], ni[1], "the hub gave them ids of its own");
    // Two nodes found, then the name, then a received packet for everyone.
    radio.send(&[0x88, nd[1], b'N', b'D', 0x00, 0xAA]).await;
    radio
        .send(&[0x88, ni[1], b'N', b'I', 0x00, b'G', b'S'])
        .await;
    radio.send(&[0x88, nd[1], b'N', b'D', 0x00, 0xBB]).await;
    let packet = [
        0x90, 0x00, 0x13, 0xA2, 0x00, 0x40, 0xB5, 0x99, 0xB9, 0xFF, 0xFE, 0x01, b'm', b'1',
    ];
    radio.send(&packet).await;
    // Each in the radio's order, under the client's own id.
    assert_eq!(next(&mut a).await, [0x88, 0x01, b'N', b'D', 0x00, 0xAA]);
    assert_eq!(next(&mut a).await, [0x88, 0x01, b'N', b'D', 0x00, 0xBB]);
    assert_eq!(next(&mut a).await, packet);
    assert_eq!(
        next(&mut b).await,
        [0x88, 0x01, b'N', b'I', 0x00, b'G', b'S']
    );
    assert_eq!(next(&mut b).await, packet);
    // The radio sent four frames, all passed on (and, before, the answer to the hub's
    // own AT AP); the hub's own link claimed none of the three answers (it wrote the
    // requests as raw frames).
    let stats = hub.stats();
    assert_eq!(stats.frames_from_radio, 4, "{stats:?}");
    assert_eq!(stats.radio.frames, 5, "{stats:?}");
    assert_eq!(stats.radio.unclaimed_responses, 3, "{stats:?}");
    hub.stop().await;
}

#[tokio::test]
async fn every_answer_to_a_broadcast_remote_at_command_goes_to_its_client() {
    let (mut radio, hub) = FakeRadio::with_hub().await;
    let mut client = raw_client(&hub).await;
    // VR to the broadcast address, as DigiMesh radios answer it: once from each radio.
    let mut request = vec![0x17, 0x01, 0, 0, 0, 0, 0, 0, 0xFF, 0xFF, 0xFF, 0xFE, 0x02];
    request.extend_from_slice(b"VR");
    send(&mut client, &request).await;
    let written = radio.next_frame().await;
    let answer = |id: u8, last: u8| {
        let mut frame = vec![0x97, id, 0x00, 0x13, 0xA2, 0x00, 0x40, 0xB5, 0x99, last];
        frame.extend_from_slice(&[0x7D, 0x84, b'V', b'R', 0x00, 0x40, 0x60]);
        frame
    };
    radio.send(&answer(written[1], 0xB9)).await;
    radio.send(&answer(written[1], 0xBF)).await;
    assert_eq!(next(&mut client).await, answer(0x01, 0xB9));
    assert_eq!(next(&mut client).await, answer(0x01, 0xBF));
    hub.stop().await;
}

#[tokio::test]
async fn a_client_that_reads_nothing_does_not_hold_up_stop() {
    let (mut radio, hub) = FakeRadio::with_hub().await;
    // Connected, never read from.
    let _idle = tokio::net::TcpStream::connect(hub.local_addr())
        .await
        .unwrap();
    // The radio sends until the client's socket buffers and queue are full (frames for
    // it are then dropped): its task is then stuck writing to it.
    let deadline = tokio::time::Instant::now() + GUARD;
    let mut frame = vec![
        0x90, 0x00, 0x13, 0xA2, 0x00, 0x40, 0xB5, 0x99, 0xB9, 0xFF, 0xFE, 0x01,
    ];
    frame.resize(250, b'w');
    while hub.stats().frames_dropped < 2_000 {
        assert!(tokio::time::Instant::now() < deadline, "{:?}", hub.stats());
        radio.send_many(&frame, 1000).await;
    }
    tokio::time::timeout(GUARD, hub.stop())
        .await
        .expect("stop returns");
}

/// A hub on the radio listening on `listener`, with a client, once the radio has gone
/// away and the client's link has seen it go down.
async fn hub_in_an_outage(
    listener: &tokio::net::TcpListener,
) -> (Hub, PacketStream, CommandSender) {
    let (hub, radio) = hub_on(listener).await;
    let (mut client_stream, client) = client(&hub, ApiMode::Unescaped).await;
    assert!(matches!(
        next_link(&mut client_stream).await,
        mcp_host::LinkEvent::Connected { .. }
    ));
    drop(radio);
    assert!(matches!(
        next_link(&mut client_stream).await,
        mcp_host::LinkEvent::Disconnected { .. }
    ));
    (hub, client_stream, client)
}

/// A radio back after an outage that is slow to answer the hub's `AT AP` (up to
/// `MODE_CHECK_TIMEOUT` twice): the hub stops at once all the same.
#[tokio::test]
async fn a_hub_stops_while_it_asks_a_radio_back_for_its_mode() {
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let (hub, _client_stream, _client) = hub_in_an_outage(&listener).await;
    let (socket, _) = listener.accept().await.unwrap();
    let mut radio =
        tokio_util::codec::Framed::new(socket, mcp_host::codec::XBeeCodec::new(ApiMode::Unescaped));
    let asked = next(&mut radio).await;
    assert_eq!((asked[0], &asked[2..]), (0x08, &b"AP"[..]), "{asked:02X?}");
    // Unanswered: stopped before the hub would give the radio up (twice the check).
    let check = mcp_host::hub::MODE_CHECK_TIMEOUT;
    tokio::time::timeout(check * 3 / 2, hub.stop())
        .await
        .expect("the hub stops without waiting for the radio's answer");
}

#[tokio::test]
async fn clients_see_the_radios_outage_and_come_back_with_it() {
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let (hub, mut client_stream, client) = hub_in_an_outage(&listener).await;
    // The hub stopped listening before it let its clients go, so that clients stay
    // down quietly rather than being taken in and dropped again.
    let refused = tokio::net::TcpStream::connect(hub.local_addr()).await;
    assert_eq!(
        refused.map(|_| ()).map_err(|e| e.kind()),
        Err(std::io::ErrorKind::ConnectionRefused)
    );
    assert!(!hub.stats().listening);
    // The radio is back: the hub's link reconnects, and then the client's.
    let socket = radio_accepted(&listener).await;
    assert!(matches!(
        next_link(&mut client_stream).await,
        mcp_host::LinkEvent::Reconnected { .. }
    ));
    // And frames flow again, once the hub has taken the client back (its connection
    // may be complete in the kernel before the hub accepts it).
    until(&hub, |stats| stats.clients >= 2).await;
    assert!(hub.stats().listening);
    let mut radio = FakeRadio::on(socket);
    radio.send(&[0x8A, 0x06]).await;
    loop {
        let event = tokio::time::timeout(GUARD, client_stream.next())
            .await
            .unwrap()
            .unwrap();
        if let Event::Frame(frame) = event {
            assert_eq!(&frame.data()[..], [0x8A, 0x06]);
            break;
        }
    }
    client.close();
    hub.stop().await;
}

#[cfg(unix)]
#[tokio::test]
async fn a_hub_whose_radio_is_not_there_yet_refuses_clients_from_the_start() {
    // A `pty` link has no radio until a device opens its far end.
    let hub = Hub::start(&Link::Pty, LinkOptions::default(), "127.0.0.1:0")
        .await
        .unwrap();
    assert!(!hub.stats().listening);
    // At once, before the hub's tasks have run (a single-threaded runtime).
    let refused = tokio::net::TcpStream::connect(hub.local_addr()).await;
    assert_eq!(
        refused.map(|_| ()).map_err(|e| e.kind()),
        Err(std::io::ErrorKind::ConnectionRefused)
    );
    hub.stop().await;
}

/// Starts a second hub on `hub`'s address, which must fail: the port is in use (its
/// radio is never reached).
async fn no_second_hub_on(hub: &Hub) {
    let radio: Link = "tcp:127.0.0.1:9".parse().unwrap();
    let addr = hub.local_addr().to_string();
    let second = Hub::start(&radio, LinkOptions::default(), &addr).await;
    assert!(
        matches!(&second, Err(mcp_host::hub::HubError::Listen { error, .. })
            if error.kind() == std::io::ErrorKind::AddrInUse),
        "{:?}",
        second.as_ref().map(|hub| hub.local_addr())
    );
    // A report that follows the chain of sources says what the system said once.
    let error = second.err().unwrap();
    assert_eq!(common::error_chain(&error), [error.to_string()]);
}

#[tokio::test]
async fn no_second_hub_starts_on_a_port_a_hub_serves() {
    let (_radio, hub) = FakeRadio::with_hub().await;
    assert!(hub.stats().listening);
    no_second_hub_on(&hub).await;
    hub.stop().await;
}

/// Where the hub holds its port during an outage (`cfg(holds_port)`, set by the build
/// script); `clients_see_the_radios_outage_and_come_back_with_it` sees it listen there
/// again beside the socket that holds it.
#[cfg(holds_port)]
#[tokio::test]
async fn no_other_program_nor_hub_can_take_the_hubs_port_during_an_outage() {
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let (hub, _client_stream, client) = hub_in_an_outage(&listener).await;
    assert!(!hub.stats().listening);
    // Another program tries the port while the hub does not listen there: as servers
    // usually do (tokio's listeners set SO_REUSEADDR), or with a plain socket.
    let squatter = tokio::net::TcpListener::bind(hub.local_addr()).await;
    assert_eq!(
        squatter.map(|_| ()).map_err(|e| e.kind()),
        Err(std::io::ErrorKind::AddrInUse)
    );
    let plain = std::net::TcpListener::bind(hub.local_addr());
    assert_eq!(
        plain.map(|_| ()).map_err(|e| e.kind()),
        Err(std::io::ErrorKind::AddrInUse)
    );
    // Nor does another hub, whose listener would share the port (SO_REUSEPORT).
    no_second_hub_on(&hub).await;
    client.close();
    hub.stop().await;
}

/// Where the hub gives its port up during an outage.
#[cfg(not(holds_port))]
#[tokio::test]
async fn a_hub_whose_port_was_taken_during_an_outage_listens_again_once_it_is_free() {
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let (hub, _client_stream, client) = hub_in_an_outage(&listener).await;
    // Another program takes the port while the hub does not listen, and the radio
    // comes back meanwhile.
    let squatter = tokio::net::TcpListener::bind(hub.local_addr())
        .await
        .unwrap();
    let _radio = radio_accepted(&listener).await;
    until(&hub, |stats| stats.radio.reconnects >= 1).await;
    // The hub's clients reach the other program meanwhile, as any would.
    let (to_squatter, _) = tokio::time::timeout(GUARD, squatter.accept())
        .await
        .unwrap()
        .unwrap();
    assert!(!hub.stats().listening);
    drop(to_squatter);
    drop(squatter);
    // Once the port is free, the hub listens there again and takes the client back.
    until(&hub, |stats| stats.listening && stats.clients >= 2).await;
    client.close();
    hub.stop().await;
}

/// Waits until the hub's counters satisfy `done`, looking every 5 ms (they change in
/// its tasks, which signal nothing); fails after [`GUARD`].
async fn until(hub: &Hub, done: impl Fn(&mcp_host::hub::HubStats) -> bool) {
    let deadline = tokio::time::Instant::now() + GUARD;
    while !done(&hub.stats()) {
        assert!(tokio::time::Instant::now() < deadline, "{:?}", hub.stats());
        tokio::time::sleep(Duration::from_millis(5)).await;
    }
}

/// The next link event on `stream`.
async fn next_link(stream: &mut PacketStream) -> mcp_host::LinkEvent {
    let next = async {
        loop {
            match stream.next().await {
                Some(Event::Link(link)) => return link,
                Some(_) => {}
                None => panic!("stream ended"),
            }
        }
    };
    tokio::time::timeout(GUARD, next)
        .await
        .expect("a link event")
}
