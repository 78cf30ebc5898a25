//! The virtual XBee network: devices on pseudo-terminals, TCP and in-process streams
//! exchange frames through it.

mod common;

use std::time::Duration;

use futures::{FutureExt, SinkExt, StreamExt};
use mcp_host::codec::{CodecItem, XBeeCodec};
use mcp_host::radio::{Faults, NetEvent, Network, NetworkConfig, NodeOptions};
use mcp_host::{Link, OwnedFrame};
use tokio::io::{AsyncRead, AsyncReadExt, AsyncWrite, AsyncWriteExt};
use tokio::net::{TcpListener, TcpStream};
use tokio_util::codec::Framed;
use xbee_api::{
    Address16, Address64, ApiMode, AtCommandRepr, AtStatus, DecodeError, DeliveryStatus,
    DiscoveryStatus, Frame, ModemStatus, TransmitRequestRepr,
};

/// Failure guard only: every wait ends on a frame long before this.
const GUARD: Duration = Duration::from_secs(20);
const COORD: Address64 = Address64::COORDINATOR;
const MAV_A: Address64 = Address64(0x0013_A200_40B5_99B9);
const MAV_B: Address64 = Address64(0x0013_A200_40B5_99BF);
const NOBODY: Address64 = Address64(0x0013_A200_DEAD_BEEF);

trait Io: AsyncRead + AsyncWrite + Unpin + Send {}
impl<T: AsyncRead + AsyncWrite + Unpin + Send> Io for T {}

/// A device: the far side of a node's link.
struct Dev {
    framed: Framed<Box<dyn Io>, XBeeCodec>,
}

impl Dev {
    fn new(io: impl Io + 'static, mode: ApiMode) -> Self {
        let io: Box<dyn Io> = Box::new(io);
        Dev {
            framed: Framed::new(io, XBeeCodec::new(mode)),
        }
    }

    #[cfg(unix)]
    fn pty(path: &std::path::Path, mode: ApiMode) -> Self {
        let port = tokio_serial::SerialStream::open(&tokio_serial::new(
            path.to_str().expect("utf-8 path"),
            115_200,
        ))
        .expect("open the pty");
        Dev::new(port, mode)
    }

    async fn tcp(addr: std::net::SocketAddr, mode: ApiMode) -> Self {
        Dev::new(TcpStream::connect(addr).await.expect("connect"), mode)
    }

    /// The next `N` bytes, as a device in transparent mode reads them.
    async fn raw<const N: usize>(&mut self) -> [u8; N] {
        let mut raw = [0u8; N];
        tokio::time::timeout(GUARD, self.framed.get_mut().read_exact(&mut raw))
            .await
            .expect("bytes in time")
            .expect("the link stays open");
        raw
    }

    /// Reads and writes frames in `mode` from now on.
    fn set_mode(&mut self, mode: ApiMode) {
        *self.framed.codec_mut() = XBeeCodec::new(mode);
    }

    async fn send(&mut self, frame: &Frame<'_>) {
        self.framed.send(frame).await.expect("write a frame");
    }

    async fn tx(&mut self, frame_id: u8, dst64: Address64, data: &[u8]) {
        self.send(&Frame::TransmitRequest(TransmitRequestRepr {
            frame_id,
            dst64,
            dst16: Address16::UNKNOWN,
            radius: 0,
            options: 0,
            data,
        }))
        .await;
    }

    async fn item(&mut self) -> CodecItem {
        tokio::time::timeout(GUARD, self.framed.next())
            .await
            .expect("a frame in time")
            .expect("the link stays open")
            .expect("no I/O error")
    }

    async fn frame(&mut self) -> OwnedFrame {
        match self.item().await {
            CodecItem::Frame(frame) => frame,
            CodecItem::Error(e) => panic!("decode error {e}"),
        }
    }

    async fn modem_status(&mut self) -> ModemStatus {
        let frame = self.frame().await;
        match frame.parse() {
            Ok(Frame::ModemStatus(ms)) => ms.status,
            other => panic!("expected a modem status, got {other:?}"),
        }
    }

    /// The next Receive Packet: (source, source 16-bit, options, data).
    async fn rx(&mut self) -> (Address64, Address16, u8, Vec<u8>) {
        let frame = self.frame().await;
        match frame.parse() {
            Ok(Frame::ReceivePacket(rx)) => (rx.src64, rx.src16, rx.options, rx.data.to_vec()),
            other => panic!("expected a receive packet, got {other:?}"),
        }
    }

    /// The next Transmit Status: (frame id, 16-bit, delivery, discovery).
    async fn status(&mut self) -> (u8, Address16, DeliveryStatus, DiscoveryStatus) {
        let frame = self.frame().await;
        match frame.parse() {
            Ok(Frame::TransmitStatus(st)) => {
                assert_eq!(st.retries, 0);
                (st.frame_id, st.dst16, st.delivery, st.discovery)
            }
            other => panic!("expected a transmit status, got {other:?}"),
        }
    }

    async fn at(
        &mut self,
        frame_id: u8,
        command: &[u8; 2],
        parameter: &[u8],
    ) -> (AtStatus, Vec<u8>) {
        self.at_frame(false, frame_id, command, parameter).await
    }

    /// [`Dev::at`], as AT Command - Queue Parameter Value (0x09) if `queued`.
    async fn at_frame(
        &mut self,
        queued: bool,
        frame_id: u8,
        command: &[u8; 2],
        parameter: &[u8],
    ) -> (AtStatus, Vec<u8>) {
        self.send(&Frame::AtCommand(AtCommandRepr {
            queued,
            frame_id,
            command: *command,
            parameter,
        }))
        .await;
        let frame = self.frame().await;
        match frame.parse() {
            Ok(Frame::AtCommandResponse(r)) => {
                assert_eq!(r.frame_id, frame_id);
                assert_eq!(&r.command, command);
                (r.status, r.data.to_vec())
            }
            other => panic!("expected an AT response, got {other:?}"),
        }
    }
}

const OK: DiscoveryStatus = DiscoveryStatus::NoDiscoveryOverhead;

/// A network of in-process nodes, each device already past its modem status.
async fn in_process(config: NetworkConfig, nodes: &[Address64]) -> (Network, Vec<Dev>) {
    let network = Network::new(config);
    let mut devs = Vec::new();
    for &addr in nodes {
        let (_, io) = network
            .add_in_process(addr, NodeOptions::default())
            .expect("add a node");
        let mut dev = Dev::new(io, ApiMode::Unescaped);
        let expected = if addr == COORD {
            ModemStatus::CoordinatorStarted
        } else {
            ModemStatus::JoinedNetwork
        };
        assert_eq!(dev.modem_status().await, expected);
        devs.push(dev);
    }
    (network, devs)
}

#[cfg(unix)]
#[tokio::test]
async fn unicast_and_broadcast_between_a_tcp_coordinator_and_pty_nodes() {
    let network = Network::new(NetworkConfig::default());
    let coord = common::tcp_coordinator(&network).await;
    let a = network
        .add_link(MAV_A, &Link::Pty, NodeOptions::default())
        .await
        .unwrap();
    let b = network
        .add_link(MAV_B, &Link::Pty, NodeOptions::with_mode(ApiMode::Escaped))
        .await
        .unwrap();
    assert_eq!(coord.addr16, Address16::COORDINATOR);
    assert_ne!(a.addr16, b.addr16);
    for info in [&a, &b] {
        assert!(![0x0000, 0xFFFE, 0xFFFF].contains(&info.addr16.0));
        assert_eq!(network.addr16(info.addr64), Some(info.addr16));
    }
    let mut ground = Dev::tcp(coord.local_addr.unwrap(), ApiMode::Unescaped).await;
    let mut dev_a = Dev::pty(a.pty_path.as_deref().unwrap(), ApiMode::Unescaped);
    let mut dev_b = Dev::pty(b.pty_path.as_deref().unwrap(), ApiMode::Escaped);
    assert_eq!(ground.modem_status().await, ModemStatus::CoordinatorStarted);
    assert_eq!(dev_a.modem_status().await, ModemStatus::JoinedNetwork);
    assert_eq!(dev_b.modem_status().await, ModemStatus::JoinedNetwork);

    // Node to coordinator, with a status.
    dev_a.tx(1, COORD, b"r\x02\x04").await;
    assert_eq!(
        ground.rx().await,
        (MAV_A, a.addr16, 0x01, b"r\x02\x04".to_vec())
    );
    assert_eq!(
        dev_a.status().await,
        (1, Address16::COORDINATOR, DeliveryStatus::Success, OK)
    );

    // Coordinator to a node in API mode 2, with bytes that need escaping.
    let data = [b'c', 0x06, 0x7E, 0x7D, 0x11, 0x13];
    ground.tx(7, MAV_B, &data).await;
    assert_eq!(
        dev_b.rx().await,
        (COORD, Address16::COORDINATOR, 0x01, data.to_vec())
    );
    assert_eq!(
        ground.status().await,
        (7, b.addr16, DeliveryStatus::Success, OK)
    );

    // Frame id 0: delivered, no status (the next frame the sender sees is the answer).
    ground.tx(0, MAV_A, b"c\x02\xff").await;
    assert_eq!(dev_a.rx().await.3, b"c\x02\xff");
    dev_a.tx(0, COORD, b"r\x02\x01").await;
    assert_eq!(ground.rx().await.3, b"r\x02\x01");

    // Broadcast from B reaches the coordinator and A, with receive option 0x02.
    dev_b.tx(9, Address64::BROADCAST, b"hello").await;
    assert_eq!(
        ground.rx().await,
        (MAV_B, b.addr16, 0x02, b"hello".to_vec())
    );
    assert_eq!(dev_a.rx().await, (MAV_B, b.addr16, 0x02, b"hello".to_vec()));
    assert_eq!(
        dev_b.status().await,
        (9, Address16::UNKNOWN, DeliveryStatus::Success, OK)
    );

    // Node to node.
    dev_a.tx(3, MAV_B, b"x").await;
    assert_eq!(dev_b.rx().await, (MAV_A, a.addr16, 0x01, b"x".to_vec()));
    assert_eq!(
        dev_a.status().await,
        (3, b.addr16, DeliveryStatus::Success, OK)
    );
}

#[tokio::test]
async fn unknown_destination_self_and_oversize_payloads_fail_like_a_radio() {
    let (network, mut devs) = in_process(NetworkConfig::default(), &[COORD, MAV_A]).await;
    let a16 = network.addr16(MAV_A).unwrap();
    let [ground, dev_a] = &mut devs[..] else {
        unreachable!()
    };

    ground.tx(1, NOBODY, b"c\x02\xff").await;
    assert_eq!(
        ground.status().await,
        (
            1,
            Address16::UNKNOWN,
            DeliveryStatus::AddressNotFound,
            DiscoveryStatus::AddressDiscovery
        )
    );
    ground.tx(2, COORD, b"me").await;
    assert_eq!(
        ground.status().await,
        (2, Address16::COORDINATOR, DeliveryStatus::SelfAddressed, OK)
    );

    // 84 bytes unicast pass, 85 do not; 92 broadcast pass, 93 do not.
    ground.tx(3, MAV_A, &[0x55; 85]).await;
    assert_eq!(
        ground.status().await,
        (3, Address16::UNKNOWN, DeliveryStatus::PayloadTooLarge, OK)
    );
    ground.tx(4, MAV_A, &[0x55; 84]).await;
    assert_eq!(dev_a.rx().await.3, vec![0x55; 84]);
    assert_eq!(ground.status().await, (4, a16, DeliveryStatus::Success, OK));
    ground.tx(5, Address64::BROADCAST, &[0x66; 93]).await;
    assert_eq!(
        ground.status().await,
        (5, Address16::UNKNOWN, DeliveryStatus::PayloadTooLarge, OK)
    );
    ground.tx(6, Address64::BROADCAST, &[0x66; 92]).await;
    assert_eq!(
        dev_a.rx().await,
        (COORD, Address16::COORDINATOR, 0x02, vec![0x66; 92])
    );
    assert_eq!(
        ground.status().await,
        (6, Address16::UNKNOWN, DeliveryStatus::Success, OK)
    );

    // Addressed by 16-bit address alone.
    ground
        .send(&Frame::TransmitRequest(TransmitRequestRepr {
            frame_id: 8,
            dst64: Address64(u64::MAX),
            dst16: a16,
            radius: 0,
            options: 0,
            data: b"by16",
        }))
        .await;
    assert_eq!(dev_a.rx().await.3, b"by16");
    assert_eq!(ground.status().await, (8, a16, DeliveryStatus::Success, OK));
}

#[tokio::test]
async fn fragmentation_raises_the_unicast_limit_to_255() {
    let config = NetworkConfig {
        max_unicast: mcp_host::radio::MAX_UNICAST_FRAGMENTED,
        ..NetworkConfig::default()
    };
    let (network, mut devs) = in_process(config, &[COORD, MAV_A]).await;
    let a16 = network.addr16(MAV_A).unwrap();
    let [ground, dev_a] = &mut devs[..] else {
        unreachable!()
    };
    ground.tx(1, MAV_A, &[0xAA; 255]).await;
    assert_eq!(dev_a.rx().await.3, vec![0xAA; 255]);
    assert_eq!(ground.status().await, (1, a16, DeliveryStatus::Success, OK));
    ground.tx(2, MAV_A, &[0xAA; 256]).await;
    assert_eq!(ground.status().await.2, DeliveryStatus::PayloadTooLarge);
    assert_eq!(
        ground.at(3, b"NP", &[]).await,
        (AtStatus::Ok, vec![0x00, 0xFF])
    );
}

#[tokio::test]
async fn local_at_commands_are_answered() {
    let network = Network::new(NetworkConfig::default());
    let (_, io) = network
        .add_in_process(MAV_A, NodeOptions::with_mode(ApiMode::Escaped))
        .unwrap();
    // An in-process node is reachable as soon as it is added.
    assert!(network.is_connected(MAV_A));
    let a16 = network.addr16(MAV_A).unwrap();
    let mut dev = Dev::new(io, ApiMode::Escaped);
    assert_eq!(dev.modem_status().await, ModemStatus::JoinedNetwork);
    assert_eq!(dev.at(1, b"AP", &[]).await, (AtStatus::Ok, vec![2]));
    assert_eq!(
        dev.at(2, b"NP", &[]).await,
        (AtStatus::Ok, vec![0x00, 0x54])
    );
    assert_eq!(
        dev.at(3, b"SH", &[]).await,
        (AtStatus::Ok, vec![0x00, 0x13, 0xA2, 0x00])
    );
    assert_eq!(
        dev.at(4, b"SL", &[]).await,
        (AtStatus::Ok, vec![0x40, 0xB5, 0x99, 0xB9])
    );
    assert_eq!(
        dev.at(5, b"MY", &[]).await,
        (AtStatus::Ok, a16.to_bytes().to_vec())
    );
    assert_eq!(dev.at(6, b"CE", &[]).await, (AtStatus::Ok, vec![0]));
    assert_eq!(dev.at(9, b"SM", &[]).await, (AtStatus::Ok, vec![0]));
    assert_eq!(dev.at(10, b"HV", &[]).await, (AtStatus::Ok, vec![0x2E, 0]));
    assert_eq!(
        dev.at(11, b"VR", &[]).await,
        (AtStatus::Ok, vec![0x40, 0x60])
    );
    assert_eq!(dev.at(12, b"NI", &[]).await, (AtStatus::Ok, b" ".to_vec()));
    assert_eq!(
        dev.at(13, b"HV", &[1, 2]).await,
        (AtStatus::InvalidParameter, vec![])
    );
    // A queued query (0x09) is answered as an immediate one.
    assert_eq!(
        dev.at_frame(true, 14, b"AP", &[]).await,
        (AtStatus::Ok, vec![2])
    );
    assert_eq!(
        dev.at(7, b"ZZ", &[]).await,
        (AtStatus::InvalidCommand, vec![])
    );
    assert_eq!(
        dev.at(8, b"AP", &[3]).await,
        (AtStatus::InvalidParameter, vec![])
    );
}

#[tokio::test]
async fn ap_set_in_an_api_frame_changes_the_devices_link_once_answered() {
    let (_network, mut devs) = in_process(NetworkConfig::default(), &[COORD, MAV_A]).await;
    let [ground, dev_a] = &mut devs[..] else {
        unreachable!()
    };
    // Answered in API mode 1, the mode it was asked in; escaped frames from then on.
    assert_eq!(dev_a.at(1, b"AP", &[2]).await, (AtStatus::Ok, vec![]));
    dev_a.set_mode(ApiMode::Escaped);
    // `}` is 0x7D, escaped both ways now: a radio still reading mode 1 would store
    // `}]`, and a device reading mode 1 would not find the frame's end.
    assert_eq!(dev_a.at(2, b"NI", b"a}b").await, (AtStatus::Ok, vec![]));
    assert_eq!(
        dev_a.at(3, b"NI", &[]).await,
        (AtStatus::Ok, b"a}b".to_vec())
    );
    assert_eq!(dev_a.at(4, b"AP", &[]).await, (AtStatus::Ok, vec![2]));
    // AP 0: transparent mode, where a received payload comes as its bytes alone.
    assert_eq!(dev_a.at(5, b"AP", &[0]).await, (AtStatus::Ok, vec![]));
    ground.tx(6, MAV_A, b"raw").await;
    assert_eq!(ground.status().await.2, DeliveryStatus::Success);
    assert_eq!(&dev_a.raw::<3>().await, b"raw");
}

// Paused clock: the guard times around `+++` pass at once.
#[tokio::test(start_paused = true)]
async fn ap_set_remotely_changes_the_devices_link_at_once() {
    use xbee_api::RemoteAtCommandRepr;
    let (_network, mut devs) = in_process(NetworkConfig::default(), &[COORD, MAV_A]).await;
    let [ground, dev_a] = &mut devs[..] else {
        unreachable!()
    };
    for (frame_id, ap) in [(1, 0), (2, 1)] {
        ground
            .send(&Frame::RemoteAtCommand(RemoteAtCommandRepr {
                frame_id,
                dst64: MAV_A,
                dst16: Address16::UNKNOWN,
                options: RemoteAtCommandRepr::APPLY_CHANGES,
                command: *b"AP",
                parameter: &[ap],
            }))
            .await;
        match ground.frame().await.parse() {
            Ok(Frame::RemoteAtResponse(r)) => {
                assert_eq!(
                    (r.frame_id, r.src64, r.status),
                    (frame_id, MAV_A, AtStatus::Ok)
                );
            }
            other => panic!("expected a remote AT response, got {other:?}"),
        }
        if ap == 0 {
            // Transparent mode: a received payload comes as its bytes alone, and the
            // device's `+++` between guard times enters AT command mode.
            ground.tx(3, MAV_A, b"raw").await;
            assert_eq!(ground.status().await.2, DeliveryStatus::Success);
            assert_eq!(&dev_a.raw::<3>().await, b"raw");
            let guard = Duration::from_millis(1100);
            tokio::time::sleep(guard).await;
            dev_a.framed.get_mut().write_all(b"+++").await.unwrap();
            tokio::time::sleep(guard).await;
            assert_eq!(&dev_a.raw::<3>().await, b"OK\r");
            dev_a.framed.get_mut().write_all(b"ATCN\r").await.unwrap();
            assert_eq!(&dev_a.raw::<3>().await, b"OK\r");
        }
    }
    // Back in API mode 1 without the device writing a frame meanwhile: its first one is
    // read as a frame, not as transparent mode's data.
    assert_eq!(dev_a.at(4, b"AP", &[]).await, (AtStatus::Ok, vec![1]));
}

#[tokio::test]
async fn a_ground_station_reads_the_coordinator_through_mcp_host() {
    let network = Network::new(NetworkConfig::default());
    let coord = common::tcp_coordinator(&network).await;
    let (_, io) = network
        .add_in_process(MAV_A, NodeOptions::default())
        .unwrap();
    let mut dev_a = Dev::new(io, ApiMode::Unescaped);
    assert_eq!(dev_a.modem_status().await, ModemStatus::JoinedNetwork);
    let link: Link = format!("tcp:{}", coord.local_addr.unwrap())
        .parse()
        .unwrap();
    let (_stream, sender) = mcp_host::connect(&link, mcp_host::LinkOptions::default())
        .await
        .unwrap();
    let ap = sender.at(*b"AP", &[], Some(GUARD)).await.unwrap();
    match ap.parse().unwrap() {
        Frame::AtCommandResponse(r) => assert_eq!((r.status, r.data), (AtStatus::Ok, &[1][..])),
        other => panic!("{other:?}"),
    }
    let command = mcp_core::Command::time(1_700_000_000);
    let report = sender.send(MAV_A, &command).await.unwrap();
    assert!(matches!(
        report,
        mcp_host::DeliveryReport::Delivered { dst16, .. } if Some(dst16) == network.addr16(MAV_A)
    ));
    let mut buf = [0u8; 16];
    let len = command.encode(&mut buf).unwrap();
    assert_eq!(
        dev_a.rx().await,
        (COORD, Address16::COORDINATOR, 0x01, buf[..len].to_vec())
    );
}

/// Sends `n` numbered payloads from `from` to the coordinator with frame ids, and
/// waits for every status, so that all of them have been routed.
async fn send_numbered(from: &mut Dev, n: u8) {
    for i in 1..=n {
        from.tx(i, COORD, &[b'm', i]).await;
    }
    for i in 1..=n {
        let (id, _, delivery, _) = from.status().await;
        assert_eq!((id, delivery), (i, DeliveryStatus::Success));
    }
}

/// Clears the coordinator's faults and sends a marker: everything before it has been
/// decided, and arrives before it.
async fn marker(network: &Network, from: &mut Dev) {
    network.set_faults(COORD, Some(Faults::default()));
    from.tx(0, COORD, b"end").await;
}

/// Reads the coordinator's side up to the marker: payloads and decode errors, in order.
async fn until_marker(ground: &mut Dev) -> Vec<Result<Vec<u8>, DecodeError>> {
    let mut seen = Vec::new();
    loop {
        match ground.item().await {
            CodecItem::Frame(f) => match f.parse() {
                Ok(Frame::ReceivePacket(rx)) if rx.data == b"end" => return seen,
                Ok(Frame::ReceivePacket(rx)) => seen.push(Ok(rx.data.to_vec())),
                other => panic!("unexpected {other:?}"),
            },
            CodecItem::Error(e) => seen.push(Err(e)),
        }
    }
}

async fn faulty(faults: Faults, seed: u64, n: u8) -> (Vec<Result<Vec<u8>, DecodeError>>, Network) {
    let config = NetworkConfig {
        seed,
        ..NetworkConfig::default()
    };
    let (network, mut devs) = in_process(config, &[COORD, MAV_A]).await;
    network.set_faults(COORD, Some(faults));
    let [ground, dev_a] = &mut devs[..] else {
        unreachable!()
    };
    send_numbered(dev_a, n).await;
    marker(&network, dev_a).await;
    let seen = until_marker(ground).await;
    (seen, network)
}

fn numbered(range: impl IntoIterator<Item = u8>) -> Vec<Result<Vec<u8>, DecodeError>> {
    range.into_iter().map(|i| Ok(vec![b'm', i])).collect()
}

#[tokio::test]
async fn loss_one_drops_everything_and_loss_zero_nothing() {
    let (seen, network) = faulty(
        Faults {
            loss: 1.0,
            ..Faults::default()
        },
        1,
        20,
    )
    .await;
    assert_eq!(seen, vec![]);
    assert_eq!(network.stats(COORD).unwrap().lost, 20);
    let (seen, network) = faulty(
        Faults {
            loss: 0.0,
            ..Faults::default()
        },
        1,
        20,
    )
    .await;
    assert_eq!(seen, numbered(1..=20));
    assert_eq!(network.stats(COORD).unwrap().lost, 0);
}

#[tokio::test]
async fn duplicate_one_writes_every_frame_twice() {
    let (seen, network) = faulty(
        Faults {
            duplicate: 1.0,
            ..Faults::default()
        },
        2,
        10,
    )
    .await;
    let twice: Vec<_> = numbered(1..=10)
        .into_iter()
        .flat_map(|f| [f.clone(), f])
        .collect();
    assert_eq!(seen, twice);
    assert_eq!(network.stats(COORD).unwrap().duplicated, 10);
}

#[tokio::test]
async fn reorder_one_swaps_each_pair() {
    let (seen, _) = faulty(
        Faults {
            reorder: 1.0,
            // Failure guard only: every held frame is released by the next one.
            reorder_window: GUARD,
            ..Faults::default()
        },
        3,
        6,
    )
    .await;
    assert_eq!(seen, numbered([2, 1, 4, 3, 6, 5]));
}

#[tokio::test]
async fn a_held_back_frame_is_written_when_nothing_overtakes_it() {
    let (network, mut devs) = in_process(NetworkConfig::default(), &[COORD, MAV_A]).await;
    let faults = Faults {
        reorder: 1.0,
        reorder_window: Duration::from_millis(10),
        ..Faults::default()
    };
    network.set_faults(COORD, Some(faults));
    let [ground, dev_a] = &mut devs[..] else {
        unreachable!()
    };
    dev_a.tx(0, COORD, b"alone").await;
    assert_eq!(ground.rx().await.3, b"alone");
    assert_eq!(network.stats(COORD).unwrap().reordered, 1);
}

#[tokio::test]
async fn corrupt_one_turns_every_frame_into_a_checksum_error() {
    let (seen, network) = faulty(
        Faults {
            corrupt: 1.0,
            ..Faults::default()
        },
        4,
        12,
    )
    .await;
    assert_eq!(seen.len(), 12);
    assert!(
        seen.iter()
            .all(|s| matches!(s, Err(DecodeError::BadChecksum { .. }))),
        "{seen:?}"
    );
    assert_eq!(network.stats(COORD).unwrap().corrupted, 12);
}

#[tokio::test]
async fn latency_and_jitter_keep_every_frame_in_order() {
    let faults = Faults {
        latency: Duration::from_millis(5),
        jitter: Duration::from_millis(20),
        ..Faults::default()
    };
    let (seen, _) = faulty(faults, 5, 20).await;
    assert_eq!(seen, numbered(1..=20));
}

#[tokio::test]
async fn a_latency_of_forever_holds_frames_back_and_breaks_nothing() {
    let config = NetworkConfig {
        seed: 3,
        ..NetworkConfig::default()
    };
    let (network, mut devs) = in_process(config, &[COORD, MAV_A]).await;
    network.set_faults(
        COORD,
        Some(Faults {
            latency: Duration::MAX,
            ..Faults::default()
        }),
    );
    let [ground, dev_a] = &mut devs[..] else {
        unreachable!()
    };
    // Whatever goes to the coordinator's link waits "forever"; the network goes on.
    dev_a.tx(1, COORD, b"m\x01").await;
    assert_eq!(
        dev_a.status().await,
        (1, Address16::COORDINATOR, DeliveryStatus::Success, OK)
    );
    assert_eq!(dev_a.at(2, b"AP", &[]).await, (AtStatus::Ok, vec![1]));
    // The frame was queued for the coordinator's link before the status went back, and
    // two round trips on this single-threaded runtime later it would long have been
    // written: it is held back.
    assert_eq!(network.stats(COORD).unwrap().frames_out, 2);
    assert!(ground.framed.next().now_or_never().is_none());
}

#[tokio::test]
async fn seeded_faults_replay_identically() {
    let faults = Faults {
        loss: 0.3,
        duplicate: 0.3,
        corrupt: 0.3,
        ..Faults::default()
    };
    let (first, _) = faulty(faults, 1234, 60).await;
    let (again, _) = faulty(faults, 1234, 60).await;
    let (other, _) = faulty(faults, 4321, 60).await;
    assert_eq!(first, again);
    assert_ne!(first, other);
    // Every outcome happened: losses, duplicates and corruptions.
    let frames = first.iter().filter(|s| s.is_ok()).count();
    let errors = first.len() - frames;
    assert!(errors > 0 && frames > 0 && first.len() != 60, "{first:?}");
}

#[tokio::test]
async fn a_cut_node_is_unreachable_until_restored() {
    let (network, mut devs) = in_process(NetworkConfig::default(), &[COORD, MAV_A]).await;
    let a16 = network.addr16(MAV_A).unwrap();
    let [ground, dev_a] = &mut devs[..] else {
        unreachable!()
    };
    assert!(network.cut(MAV_A));
    ground.tx(1, MAV_A, b"c\x02\xff").await;
    assert_eq!(
        ground.status().await,
        (1, a16, DeliveryStatus::NetworkAckFailure, OK)
    );
    dev_a.tx(2, COORD, b"r\x02\x04").await;
    assert_eq!(
        dev_a.status().await,
        (
            2,
            Address16::COORDINATOR,
            DeliveryStatus::NetworkAckFailure,
            OK
        )
    );
    // Its own radio still answers it.
    assert_eq!(dev_a.at(3, b"AP", &[]).await, (AtStatus::Ok, vec![1]));
    assert!(network.restore(MAV_A));
    ground.tx(4, MAV_A, b"c\x02\xff").await;
    assert_eq!(dev_a.rx().await.3, b"c\x02\xff");
    assert_eq!(ground.status().await, (4, a16, DeliveryStatus::Success, OK));
    assert!(!network.cut(NOBODY));
}

async fn wait_for(
    events: &mut tokio::sync::broadcast::Receiver<NetEvent>,
    f: impl Fn(&NetEvent) -> bool,
) {
    tokio::time::timeout(GUARD, async {
        loop {
            if f(&events.recv().await.expect("events")) {
                return;
            }
        }
    })
    .await
    .expect("the event in time");
}

#[tokio::test]
async fn nodes_that_disconnect_come_back() {
    let network = Network::new(NetworkConfig::default());
    let mut events = network.subscribe();
    let coord = common::tcp_coordinator(&network).await;
    // MAV A is a device listening on TCP; its node connects to it.
    let listener = TcpListener::bind("127.0.0.1:0").await.unwrap();
    let link: Link = format!("tcp:{}", listener.local_addr().unwrap())
        .parse()
        .unwrap();
    let mut options = NodeOptions::default();
    options.reconnect.initial_delay = Duration::from_millis(10);
    network.add_link(MAV_A, &link, options).await.unwrap();
    let a16 = network.addr16(MAV_A).unwrap();

    let mut ground = Dev::tcp(coord.local_addr.unwrap(), ApiMode::Unescaped).await;
    assert_eq!(ground.modem_status().await, ModemStatus::CoordinatorStarted);
    let (io, _) = listener.accept().await.unwrap();
    let mut dev_a = Dev::new(io, ApiMode::Unescaped);
    assert_eq!(dev_a.modem_status().await, ModemStatus::JoinedNetwork);
    assert!(network.connected(MAV_A).await);

    // A goes away: transmissions to it fail until it is back.
    drop(dev_a);
    wait_for(
        &mut events,
        |e| matches!(e, NetEvent::Disconnected { node, .. } if *node == MAV_A),
    )
    .await;
    assert!(!network.is_connected(MAV_A));
    ground.tx(1, MAV_A, b"c\x02\xff").await;
    assert_eq!(
        ground.status().await,
        (1, a16, DeliveryStatus::NetworkAckFailure, OK)
    );
    let (io, _) = listener.accept().await.unwrap();
    let mut dev_a = Dev::new(io, ApiMode::Unescaped);
    assert_eq!(dev_a.modem_status().await, ModemStatus::JoinedNetwork);
    ground.tx(2, MAV_A, b"c\x02\xff").await;
    assert_eq!(dev_a.rx().await.3, b"c\x02\xff");
    assert_eq!(ground.status().await, (2, a16, DeliveryStatus::Success, OK));

    // The ground station goes away; the next TCP peer is the coordinator back.
    drop(ground);
    wait_for(
        &mut events,
        |e| matches!(e, NetEvent::Disconnected { node, .. } if *node == COORD),
    )
    .await;
    let mut ground = Dev::tcp(coord.local_addr.unwrap(), ApiMode::Unescaped).await;
    assert_eq!(ground.modem_status().await, ModemStatus::CoordinatorStarted);
    dev_a.tx(0, COORD, b"r\x02\x04").await;
    assert_eq!(ground.rx().await, (MAV_A, a16, 0x01, b"r\x02\x04".to_vec()));
    assert_eq!(network.stats(MAV_A).unwrap().connections, 2);
    assert_eq!(network.stats(COORD).unwrap().connections, 2);
}

#[tokio::test]
async fn explicit_addressing_and_remote_at_commands() {
    use xbee_api::{ExplicitAddressingCommandRepr, RemoteAtCommandRepr};
    let (network, mut devs) = in_process(NetworkConfig::default(), &[COORD, MAV_A]).await;
    let a16 = network.addr16(MAV_A).unwrap();
    let [ground, dev_a] = &mut devs[..] else {
        unreachable!()
    };
    ground
        .send(&Frame::ExplicitAddressingCommand(
            ExplicitAddressingCommandRepr {
                frame_id: 1,
                dst64: MAV_A,
                dst16: Address16::UNKNOWN,
                src_endpoint: 0xE8,
                dst_endpoint: 0xE6,
                cluster_id: 0x0011,
                profile_id: 0xC105,
                radius: 0,
                options: 0,
                data: b"hi",
            },
        ))
        .await;
    match dev_a.frame().await.parse() {
        Ok(Frame::ExplicitRxIndicator(rx)) => {
            assert_eq!((rx.src64, rx.src16), (COORD, Address16::COORDINATOR));
            assert_eq!((rx.src_endpoint, rx.dst_endpoint), (0xE8, 0xE6));
            assert_eq!((rx.cluster_id, rx.profile_id), (0x0011, 0xC105));
            assert_eq!((rx.options, rx.data), (0x01, &b"hi"[..]));
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(ground.status().await, (1, a16, DeliveryStatus::Success, OK));

    for (frame_id, dst64, expected) in [
        (
            2,
            MAV_A,
            (MAV_A, a16, AtStatus::Ok, vec![0x40, 0xB5, 0x99, 0xB9]),
        ),
        (
            3,
            NOBODY,
            (NOBODY, Address16::UNKNOWN, AtStatus::TxFailure, vec![]),
        ),
    ] {
        ground
            .send(&Frame::RemoteAtCommand(RemoteAtCommandRepr {
                frame_id,
                dst64,
                dst16: Address16::UNKNOWN,
                options: 0,
                command: *b"SL",
                parameter: &[],
            }))
            .await;
        match ground.frame().await.parse() {
            Ok(Frame::RemoteAtResponse(r)) => {
                assert_eq!((r.frame_id, r.command), (frame_id, *b"SL"));
                assert_eq!((r.src64, r.src16, r.status, r.data.to_vec()), expected);
            }
            other => panic!("{other:?}"),
        }
    }
}

#[tokio::test]
async fn network_parameters_read_and_the_node_identifier_can_be_set() {
    use xbee_api::RemoteAtCommandRepr;
    let (_network, mut devs) = in_process(NetworkConfig::default(), &[COORD, MAV_A]).await;
    let [ground, dev_a] = &mut devs[..] else {
        unreachable!()
    };
    // ID (the configured extended PAN ID, 0: any) and OP (the one in use): 8 bytes.
    let (status, id) = dev_a.at(1, b"ID", &[]).await;
    assert_eq!((status, id), (AtStatus::Ok, vec![0; 8]));
    let (status, op) = dev_a.at(2, b"OP", &[]).await;
    assert_eq!((status, op.len()), (AtStatus::Ok, 8));
    assert_ne!(op, vec![0; 8]);
    // Every node of the network operates on the same PAN and channel.
    assert_eq!(ground.at(3, b"OP", &[]).await, (AtStatus::Ok, op));
    let (status, oi) = dev_a.at(4, b"OI", &[]).await;
    assert_eq!((status, oi.len()), (AtStatus::Ok, 2));
    let (status, ch) = dev_a.at(5, b"CH", &[]).await;
    assert_eq!(status, AtStatus::Ok);
    assert!(matches!(ch[..], [0x0C..=0x1A]), "{ch:?}");
    assert_eq!(ground.at(6, b"CH", &[]).await, (AtStatus::Ok, ch));
    // Read-only ones refuse a value.
    assert_eq!(
        dev_a.at(7, b"CH", &[0x0C]).await,
        (AtStatus::InvalidParameter, vec![])
    );
    assert_eq!(
        dev_a.at(8, b"ID", &[0; 8]).await,
        (AtStatus::InvalidParameter, vec![])
    );

    // NI: set, then read back; other nodes keep theirs.
    assert_eq!(dev_a.at(9, b"NI", b"MAV one").await, (AtStatus::Ok, vec![]));
    assert_eq!(
        dev_a.at(10, b"NI", &[]).await,
        (AtStatus::Ok, b"MAV one".to_vec())
    );
    assert_eq!(
        ground.at(11, b"NI", &[]).await,
        (AtStatus::Ok, b" ".to_vec())
    );
    // At most 20 printable ASCII characters.
    let twenty = [b'x'; 20];
    assert_eq!(dev_a.at(12, b"NI", &twenty).await, (AtStatus::Ok, vec![]));
    assert_eq!(
        dev_a.at(13, b"NI", &[b'x'; 21]).await,
        (AtStatus::InvalidParameter, vec![])
    );
    assert_eq!(
        dev_a.at(14, b"NI", b"tab\there").await,
        (AtStatus::InvalidParameter, vec![])
    );
    assert_eq!(
        dev_a.at(15, b"NI", &[]).await,
        (AtStatus::Ok, twenty.to_vec())
    );

    // A remote NI write sets the destination's name.
    let mut remote = async |frame_id: u8, parameter: &[u8]| {
        ground
            .send(&Frame::RemoteAtCommand(RemoteAtCommandRepr {
                frame_id,
                dst64: MAV_A,
                dst16: Address16::UNKNOWN,
                options: 0x02,
                command: *b"NI",
                parameter,
            }))
            .await;
        match ground.frame().await.parse() {
            Ok(Frame::RemoteAtResponse(r)) => {
                assert_eq!((r.frame_id, r.src64), (frame_id, MAV_A));
                (r.status, r.data.to_vec())
            }
            other => panic!("{other:?}"),
        }
    };
    assert_eq!(remote(16, b"Left wing").await, (AtStatus::Ok, vec![]));
    assert_eq!(remote(17, b"").await, (AtStatus::Ok, b"Left wing".to_vec()));
    assert_eq!(
        dev_a.at(18, b"NI", &[]).await,
        (AtStatus::Ok, b"Left wing".to_vec())
    );

    // A queued name reads back at once, as a module's register does; AC and WR answer ok
    // and take no value.
    assert_eq!(
        dev_a.at_frame(true, 19, b"NI", b"Queued").await,
        (AtStatus::Ok, vec![])
    );
    assert_eq!(
        dev_a.at_frame(true, 20, b"NI", &[]).await,
        (AtStatus::Ok, b"Queued".to_vec())
    );
    assert_eq!(dev_a.at(21, b"AC", &[]).await, (AtStatus::Ok, vec![]));
    assert_eq!(dev_a.at(22, b"WR", &[]).await, (AtStatus::Ok, vec![]));
    assert_eq!(
        dev_a.at(23, b"WR", &[1]).await,
        (AtStatus::InvalidParameter, vec![])
    );
}

/// A peer on the far end of a pseudo-terminal, opened as a ground station would.
fn open_far_end(path: &std::path::Path) -> tokio_serial::SerialStream {
    tokio_serial::SerialStream::open(&tokio_serial::new(
        path.to_str().expect("utf-8 path"),
        115_200,
    ))
    .expect("open the pty")
}

/// A coordinator on a `pty` link and MAV A in process, joined: the pseudo-terminal's
/// far end, and MAV A's device.
async fn pty_coordinator_and_mav(network: &Network) -> (std::path::PathBuf, Dev) {
    let coord = network
        .add_link(COORD, &Link::Pty, NodeOptions::default())
        .await
        .unwrap();
    let path = coord.pty_path.clone().unwrap();
    let (_, io) = network
        .add_in_process(MAV_A, NodeOptions::default())
        .unwrap();
    let mut mav = Dev::new(io, ApiMode::Unescaped);
    assert_eq!(mav.modem_status().await, ModemStatus::JoinedNetwork);
    (path, mav)
}

#[tokio::test]
async fn a_pty_node_is_up_only_while_a_peer_has_it_open() {
    use tokio_serial::SerialPort;
    let network = Network::new(NetworkConfig::default());
    let mut events = network.subscribe();
    let (path, mut mav) = pty_coordinator_and_mav(&network).await;
    let connected = |e: &NetEvent| matches!(e, NetEvent::Connected { node, .. } if *node == COORD);
    let disconnected =
        |e: &NetEvent| matches!(e, NetEvent::Disconnected { node, .. } if *node == COORD);

    // Nobody has the pty open: the coordinator is down, what is sent to it fails and
    // nothing is kept for a ground station that opens it later.
    for id in 1..=40 {
        mav.tx(id, COORD, b"stale").await;
        assert_eq!(
            mav.status().await,
            (
                id,
                Address16::COORDINATOR,
                DeliveryStatus::NetworkAckFailure,
                OK
            )
        );
    }
    assert!(!network.is_connected(COORD));
    assert_eq!(network.stats(COORD).unwrap().connections, 0);

    // A ground station opens it: the link comes up, and the first frame it reads is
    // the modem status, then what is sent from now on.
    let mut ground = Dev::new(open_far_end(&path), ApiMode::Unescaped);
    wait_for(&mut events, connected).await;
    assert!(network.is_connected(COORD));
    assert_eq!(ground.modem_status().await, ModemStatus::CoordinatorStarted);
    mav.tx(41, COORD, b"fresh").await;
    assert_eq!(ground.rx().await.3, b"fresh");
    assert_eq!(
        mav.status().await,
        (41, Address16::COORDINATOR, DeliveryStatus::Success, OK)
    );
    drop(ground);
    wait_for(&mut events, disconnected).await;
    assert!(!network.is_connected(COORD));

    // A ground station that leaves with frames unread: the next one does not get them.
    let far = open_far_end(&path);
    wait_for(&mut events, connected).await;
    mav.tx(42, COORD, b"unread").await;
    assert_eq!(
        mav.status().await,
        (42, Address16::COORDINATOR, DeliveryStatus::Success, OK)
    );
    // Until both frames (modem status, receive packet: 6 + 22 bytes) wait on the far end.
    let deadline = tokio::time::Instant::now() + GUARD;
    while far.bytes_to_read().unwrap() < 28 {
        assert!(tokio::time::Instant::now() < deadline, "frames in time");
        tokio::time::sleep(Duration::from_millis(5)).await;
    }
    drop(far);
    wait_for(&mut events, disconnected).await;
    mav.tx(43, COORD, b"lost").await;
    assert_eq!(mav.status().await.2, DeliveryStatus::NetworkAckFailure);
    let mut ground = Dev::new(open_far_end(&path), ApiMode::Unescaped);
    wait_for(&mut events, connected).await;
    assert_eq!(ground.modem_status().await, ModemStatus::CoordinatorStarted);
    mav.tx(44, COORD, b"again").await;
    assert_eq!(ground.rx().await.3, b"again");
    assert_eq!(network.stats(COORD).unwrap().connections, 3);
}

#[tokio::test]
async fn a_pty_peer_that_writes_and_leaves_at_once_is_served_now() {
    // A program that opens the pty, writes and closes it (its close drains what it
    // wrote, as a serial port's does) between two of the radio's looks for a peer.
    use bytes::BytesMut;
    use tokio_util::codec::Encoder;

    let network = Network::new(NetworkConfig::default());
    let mut events = network.subscribe();
    let (path, mut mav) = pty_coordinator_and_mav(&network).await;
    let disconnected =
        |e: &NetEvent| matches!(e, NetEvent::Disconnected { node, .. } if *node == COORD);
    let rounds = 20u8;
    for round in 0..rounds {
        // Fire and forget: no transmit status asked for.
        let mut frame = BytesMut::new();
        XBeeCodec::new(ApiMode::Unescaped)
            .encode(
                &Frame::TransmitRequest(TransmitRequestRepr {
                    frame_id: 0,
                    dst64: MAV_A,
                    dst16: Address16::UNKNOWN,
                    radius: 0,
                    options: 0,
                    data: &[b'c', round],
                }),
                &mut frame,
            )
            .unwrap();
        // At the radio's rate, as a ground station opens it.
        let mut far = open_far_end(&path);
        far.write_all(&frame).await.unwrap();
        drop(far);
        // Delivered now, not when the next program opens the pty; and the link saw
        // the peer come and go.
        assert_eq!(mav.rx().await.3, [b'c', round], "round {round}");
        wait_for(&mut events, disconnected).await;
    }
    assert_eq!(network.stats(COORD).unwrap().connections, u64::from(rounds));
    // The next ground station starts afresh: its first frame is the modem status, and
    // the MAV gets what it sends, nothing left from before.
    let mut ground = Dev::new(open_far_end(&path), ApiMode::Unescaped);
    assert_eq!(ground.modem_status().await, ModemStatus::CoordinatorStarted);
    ground.tx(0, MAV_A, b"fresh").await;
    assert_eq!(mav.rx().await.3, b"fresh");
}

#[cfg(unix)]
#[tokio::test]
async fn a_pty_peer_that_writes_at_once_is_answered() {
    // The peer's first frame may arrive before the radio has seen it open the far end.
    let network = Network::new(NetworkConfig::default());
    let coord = network
        .add_link(COORD, &Link::Pty, NodeOptions::default())
        .await
        .unwrap();
    let mut ground = Dev::new(
        open_far_end(coord.pty_path.as_deref().unwrap()),
        ApiMode::Unescaped,
    );
    ground
        .send(&Frame::AtCommand(AtCommandRepr {
            queued: false,
            frame_id: 1,
            command: *b"AP",
            parameter: &[],
        }))
        .await;
    assert_eq!(ground.modem_status().await, ModemStatus::CoordinatorStarted);
    match ground.frame().await.parse() {
        Ok(Frame::AtCommandResponse(r)) => assert_eq!((r.status, r.data), (AtStatus::Ok, &[1][..])),
        other => panic!("{other:?}"),
    }
}

#[tokio::test]
async fn the_commissioning_button_announces_a_radio_to_the_others() {
    use xbee_api::{NodeIdentificationIndicatorRepr, RemoteAtCommandRepr, SourceEvent};
    let (_network, mut devs) = in_process(NetworkConfig::default(), &[COORD, MAV_A, MAV_B]).await;
    let [ground, dev_a, dev_b] = &mut devs[..] else {
        unreachable!()
    };
    assert_eq!(
        dev_a.at(1, b"NI", b"Left wing").await,
        (AtStatus::Ok, vec![])
    );
    // The ground station presses MAV A's button remotely (`CB` 1).
    ground
        .send(&Frame::RemoteAtCommand(RemoteAtCommandRepr {
            frame_id: 2,
            dst64: MAV_A,
            dst16: Address16::UNKNOWN,
            options: 0x02,
            command: *b"CB",
            parameter: &[1],
        }))
        .await;
    let mut announced = None;
    let mut answered = false;
    for _ in 0..2 {
        match ground.frame().await.parse().unwrap() {
            Frame::RemoteAtResponse(r) => {
                assert_eq!((r.frame_id, r.src64, r.status), (2, MAV_A, AtStatus::Ok));
                answered = true;
            }
            Frame::NodeIdentificationIndicator(ni) => announced = Some(ni.node.addr64),
            other => panic!("{other:?}"),
        }
    }
    assert!(answered);
    assert_eq!(announced, Some(MAV_A));
    // Every other radio hears it: MAV B too, with MAV A's name and role.
    let frame = dev_b.frame().await;
    let Ok(Frame::NodeIdentificationIndicator(ni)) = frame.parse() else {
        panic!("{frame:?}")
    };
    let a16 = ni.src16;
    assert_eq!(
        ni,
        NodeIdentificationIndicatorRepr {
            src64: MAV_A,
            src16: a16,
            options: 0x02,
            node: xbee_api::NodeInfo {
                addr16: a16,
                addr64: MAV_A,
                identifier: b"Left wing",
                parent: Address16::UNKNOWN,
                device_type: xbee_api::DeviceType::Router,
                status: 1,
                profile_id: 0xC105,
                manufacturer_id: 0x101E,
                device_type_identifier: None,
                rssi: None,
            },
        }
    );
    assert_eq!(ni.source_event(), SourceEvent::Pushbutton);
    // Only CB 1 is emulated.
    assert_eq!(
        dev_a.at(3, b"CB", &[4]).await,
        (AtStatus::InvalidParameter, vec![])
    );
}

#[cfg(unix)]
#[tokio::test]
async fn a_pty_node_hung_up_on_sees_no_end_only_a_new_modem_status() {
    let network = Network::new(NetworkConfig::default());
    let coord = common::tcp_coordinator(&network).await;
    let a = network
        .add_link(MAV_A, &Link::Pty, NodeOptions::default())
        .await
        .unwrap();
    let mut ground = Dev::tcp(coord.local_addr.unwrap(), ApiMode::Unescaped).await;
    let mut dev_a = Dev::pty(a.pty_path.as_deref().unwrap(), ApiMode::Unescaped);
    assert_eq!(ground.modem_status().await, ModemStatus::CoordinatorStarted);
    assert_eq!(dev_a.modem_status().await, ModemStatus::JoinedNetwork);
    // Its settings are kept through the hang-up.
    assert_eq!(dev_a.at(1, b"NI", b"kept").await, (AtStatus::Ok, vec![]));

    let mut events = network.subscribe();
    assert!(network.disconnect(MAV_A));
    let back = tokio::time::timeout(GUARD, async {
        let mut seen = Vec::new();
        loop {
            match events.recv().await.expect("events go on") {
                NetEvent::Connected { node, .. } if node == MAV_A => return seen,
                event => seen.push(event),
            }
        }
    })
    .await
    .expect("the link comes back");
    assert!(
        matches!(&back[..], [NetEvent::Disconnected { node, .. }] if *node == MAV_A),
        "{back:?}"
    );
    assert_eq!(network.stats(MAV_A).unwrap().connections, 2);

    // The device, which kept its end open all along, reads the new modem status next,
    // and the node works as before, with its settings.
    assert_eq!(dev_a.modem_status().await, ModemStatus::JoinedNetwork);
    assert_eq!(
        dev_a.at(2, b"NI", &[]).await,
        (AtStatus::Ok, b"kept".to_vec())
    );
    dev_a.tx(3, COORD, b"r\x02\x04").await;
    assert_eq!(
        ground.rx().await,
        (MAV_A, a.addr16, 0x01, b"r\x02\x04".to_vec())
    );
    assert_eq!(
        dev_a.status().await,
        (3, Address16::COORDINATOR, DeliveryStatus::Success, OK)
    );
}
