//! A hub client speaking raw XBee frames over TCP, and a hub whose radio the test plays.

use futures::{SinkExt, StreamExt};
use mcp_host::codec::{CodecItem, XBeeCodec};
use mcp_host::hub::Hub;
use mcp_host::sim::Simulator;
use mcp_host::{Link, LinkOptions};
use tokio::net::{TcpListener, TcpStream};
use tokio_util::codec::Framed;
use xbee_api::{ApiMode, RawFrame};

use super::{GUARD, MAV};

/// XBee frames (API mode 1) over a TCP connection.
pub type Wire = Framed<TcpStream, XBeeCodec>;

/// A new client of `hub`.
pub async fn raw_client(hub: &Hub) -> Wire {
    let socket = TcpStream::connect(hub.local_addr()).await.unwrap();
    Framed::new(socket, XBeeCodec::new(ApiMode::Unescaped))
}

/// Writes a frame of `data` (frame data, type first).
pub async fn send(wire: &mut Wire, data: &[u8]) {
    wire.send(&RawFrame::new(data).unwrap()).await.unwrap();
}

/// The next frame's data, skipping decode errors.
pub async fn next(wire: &mut Wire) -> Vec<u8> {
    loop {
        let item = tokio::time::timeout(GUARD, wire.next())
            .await
            .expect("a frame")
            .expect("the connection stays")
            .unwrap();
        if let CodecItem::Frame(frame) = item {
            return frame.data().to_vec();
        }
    }
}

/// `clients` new clients of `hub`, each sending the AT command `command` under frame
/// ids 1 to `requests` (flushed): a flood of requests.
pub async fn flood(hub: &Hub, clients: usize, requests: u8, command: [u8; 2]) -> Vec<Wire> {
    let mut flood = Vec::new();
    for _ in 0..clients {
        let mut client = raw_client(hub).await;
        for id in 1..=requests {
            let frame = [0x08, id, command[0], command[1]];
            client.feed(&RawFrame::new(&frame).unwrap()).await.unwrap();
        }
        SinkExt::<&RawFrame<'_>>::flush(&mut client).await.unwrap();
        flood.push(client);
    }
    flood
}

/// A hub whose radio is played by the test: the radio's side of the link.
pub async fn hub_and_radio() -> (Hub, Wire) {
    let listener = TcpListener::bind("127.0.0.1:0").await.unwrap();
    let radio: Link = format!("tcp:{}", listener.local_addr().unwrap())
        .parse()
        .unwrap();
    let (hub, socket) = tokio::join!(
        Hub::start(&radio, LinkOptions::default(), "127.0.0.1:0"),
        radio_accepted(&listener)
    );
    (
        hub.unwrap(),
        Framed::new(socket, XBeeCodec::new(ApiMode::Unescaped)),
    )
}

/// The hub's link to the radio, accepted on `listener`, once the radio (played here,
/// in API mode 1) has answered the `AT AP` the hub asks before it listens for clients.
pub async fn radio_accepted(listener: &TcpListener) -> TcpStream {
    let (socket, _) = listener.accept().await.unwrap();
    let mut wire = Framed::new(socket, XBeeCodec::new(ApiMode::Unescaped));
    let asked = next(&mut wire).await;
    assert_eq!((asked[0], &asked[2..]), (0x08, &b"AP"[..]), "{asked:02X?}");
    send(&mut wire, &[0x88, asked[1], b'A', b'P', 0x00, 0x01]).await;
    // Nothing more comes before the hub listens: no byte read is left behind.
    wire.into_inner()
}

/// A simulated MAV (`MAV`) behind a virtual radio, and a hub on the radio's link, both in
/// API mode `mode`.
pub async fn sim_and_hub(mode: ApiMode) -> (Simulator, Hub) {
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
