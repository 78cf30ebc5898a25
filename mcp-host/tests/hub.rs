//! One radio shared by several ground stations through a `Hub`, over real TCP sockets:
//! a simulated MAV behind a virtual radio, a hub on its link, ground stations on the
//! hub.

use std::time::Duration;

use futures::StreamExt;
use mcp_core::{Command, LandingState, Packet, Report, StatusRequest, TelemetryId};
use mcp_host::hub::Hub;
use mcp_host::sim::Simulator;
use mcp_host::{CommandSender, DeliveryReport, Event, Link, LinkOptions, PacketStream, SendError};
use xbee_api::{Address64, ApiMode, DeliveryStatus};

/// Failure guard only: every wait ends on a packet long before this.
const GUARD: Duration = Duration::from_secs(20);
const MAV: Address64 = Address64(0x0013_A200_40B5_99B9);
/// No radio has this address: its transmissions fail.
const NOBODY: Address64 = Address64(0x0013_A200_0000_0001);

async fn sim_and_hub(mode: ApiMode) -> (Simulator, Hub) {
    let link: Link = "tcp-listen:127.0.0.1:0".parse().unwrap();
    let sim = Simulator::start(&link, mode, &[MAV], Simulator::network_config())
        .await
        .unwrap();
    let radio: Link = format!("tcp:{}", sim.coordinator().local_addr.unwrap())
        .parse()
        .unwrap();
    let options = LinkOptions {
        api_mode: mode,
        ..LinkOptions::default()
    };
    let hub = Hub::start(&radio, options, "127.0.0.1:0").await.unwrap();
    (sim, hub)
}

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
    assert_eq!(stats.clients, 2);
    assert!(stats.frames_from_radio > 0 && stats.frames_from_clients >= 6);
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
async fn a_client_with_more_requests_in_flight_than_the_hub_takes_gets_every_answer() {
    use futures::SinkExt;
    use mcp_host::codec::{CodecItem, XBeeCodec};
    use xbee_api::{AtCommandRepr, Frame};

    let mode = ApiMode::Unescaped;
    let (sim, hub) = sim_and_hub(mode).await;
    let socket = tokio::net::TcpStream::connect(hub.local_addr())
        .await
        .unwrap();
    let mut framed = tokio_util::codec::Framed::new(socket, XBeeCodec::new(mode));
    // 200 AT commands at once, frame ids 1 to 200: more than the hub has in flight for
    // one client (mcp_host::hub::CLIENT_IN_FLIGHT).
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
        let item = tokio::time::timeout(GUARD, framed.next())
            .await
            .expect("every answer")
            .expect("the hub stays")
            .unwrap();
        if let CodecItem::Frame(frame) = item {
            if let Ok(Frame::AtCommandResponse(at)) = frame.parse() {
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
    }
    assert!(answered[1..=200].iter().all(|&a| a));
    hub.stop().await;
    sim.stop().await;
}
