//! Node discovery: `CommandSender::at_answers` gathers every answer to one request for
//! its window (`remote_at_answers` those of a remote AT command), and
//! `CommandSender::discover` reads the radios out of `ND`'s answers,
//! against a fake radio on a real pseudo-terminal and against the emulated network over
//! real TCP.

use std::time::Duration;

use mcp_host::discovery::{DISCOVERY_MARGIN, DiscoverError, Node};
use mcp_host::radio::{Network, NetworkConfig, NodeOptions};
use mcp_host::{Event, LinkOptions, SendError};
use xbee_api::{
    Address16, Address64, ApiMode, AtCommandRepr, AtCommandResponseRepr, AtStatus, DeviceType,
    NodeInfo,
};

mod common;

use common::{FakeXBee, next_event};

const MAV_A: Address64 = Address64(0x0013_A200_40B5_99B9);
const MAV_B: Address64 = Address64(0x0013_A200_40B5_99BF);
const MAV_C: Address64 = Address64(0x0013_A200_40B5_99BD);
/// Failure guard only.
const GUARD: Duration = Duration::from_secs(20);

/// The data of a node discovery answer from `addr64`, named `name`.
fn answer(addr64: Address64, name: &[u8]) -> Vec<u8> {
    let info = NodeInfo {
        addr16: Address16(0x7D84),
        addr64,
        identifier: name,
        parent: Address16::UNKNOWN,
        device_type: DeviceType::Router,
        status: 0,
        profile_id: 0xC105,
        manufacturer_id: 0x101E,
        device_type_identifier: None,
        rssi: Some(0x28),
    };
    let mut data = vec![0u8; info.len()];
    info.emit(&mut data).unwrap();
    data
}

/// The fake radio reads the host's next AT command, which must be `command`: its frame id.
async fn at_command(fake: &mut FakeXBee, command: [u8; 2]) -> u8 {
    let data = fake.next_frame().await;
    let at = AtCommandRepr::parse_bytes(&data).expect("an AT command");
    assert_eq!(at.command, command);
    at.frame_id
}

async fn respond(fake: &mut FakeXBee, frame_id: u8, status: AtStatus, data: &[u8]) {
    fake.send(&AtCommandResponseRepr {
        frame_id,
        command: *b"ND",
        status,
        data,
    })
    .await;
}

#[tokio::test]
async fn every_answer_comes_until_the_window_is_over() {
    let (mut stream, sender, mut fake) = common::pty_link(ApiMode::Unescaped).await;
    let window = Duration::from_secs(3);
    let mut answers = sender.at_answers(*b"ND", &[], window).await.unwrap();
    let id = at_command(&mut fake, *b"ND").await;
    respond(&mut fake, id, AtStatus::Ok, &answer(MAV_A, b"A")).await;
    respond(&mut fake, id, AtStatus::Ok, &answer(MAV_B, b"B")).await;
    // Another id's answer is not one of them, nor a frame of another type under its id
    // (a Transmit Status): they come on the stream.
    respond(&mut fake, id.wrapping_add(1), AtStatus::Ok, b"x").await;
    fake.status(id, xbee_api::DeliveryStatus::Success).await;
    let mut got = Vec::new();
    while let Some(answer) = tokio::time::timeout(GUARD, answers.next()).await.unwrap() {
        got.push(answer.unwrap().data().to_vec());
        // Not over until its end is read, as a `select!` loop needs.
        assert!(!futures::stream::FusedStream::is_terminated(&answers));
    }
    // Over, for good.
    assert!(futures::stream::FusedStream::is_terminated(&answers));
    assert!(answers.next().await.is_none());
    let header = |d: &[u8]| {
        [0x88, id, b'N', b'D', 0x00]
            .iter()
            .chain(d)
            .copied()
            .collect()
    };
    let expected: Vec<Vec<u8>> = vec![header(&answer(MAV_A, b"A")), header(&answer(MAV_B, b"B"))];
    assert_eq!(got, expected);
    match next_event(&mut stream).await {
        Event::Frame(frame) => assert_eq!(frame.data()[1], id.wrapping_add(1)),
        other => panic!("{other:?}"),
    }
    match next_event(&mut stream).await {
        Event::Frame(frame) => assert_eq!(frame.data()[..2], [0x8B, id]),
        other => panic!("{other:?}"),
    }
    // After the window an answer under the id is nobody's: it comes on the stream too.
    respond(&mut fake, id, AtStatus::Ok, &answer(MAV_C, b"C")).await;
    match next_event(&mut stream).await {
        Event::Frame(frame) => assert_eq!(frame.data()[1], id),
        other => panic!("{other:?}"),
    }
}

#[tokio::test]
async fn discovery_reads_each_radio_once_and_stops_at_an_empty_answer() {
    let (_stream, sender, mut fake) = common::pty_link(ApiMode::Escaped).await;
    // A long window: the empty answer (as 802.15.4 radios end with) ends it early.
    let discovery = tokio::spawn({
        let sender = sender.clone();
        async move { sender.discover(Some(Duration::from_secs(60))).await }
    });
    let id = at_command(&mut fake, *b"ND").await;
    respond(&mut fake, id, AtStatus::Ok, &answer(MAV_A, b"MAV 1")).await;
    // An answer that cannot be read is left out.
    respond(&mut fake, id, AtStatus::Ok, &[1, 2, 3]).await;
    // A name that is no printable ASCII (a peer that breaks the rule) is kept byte for
    // byte.
    respond(&mut fake, id, AtStatus::Ok, &answer(MAV_B, b"MAV \xe9")).await;
    // The same radio again (it heard the request twice): once in the list, as last seen.
    respond(&mut fake, id, AtStatus::Ok, &answer(MAV_A, b"MAV 1b")).await;
    respond(&mut fake, id, AtStatus::Ok, &[]).await;
    let found = tokio::time::timeout(GUARD, discovery)
        .await
        .expect("discovery ends at the empty answer")
        .unwrap()
        .unwrap();
    assert_eq!(found.unreadable, 1);
    let nodes = found.nodes;
    let names: Vec<(Address64, &[u8])> = nodes
        .iter()
        .map(|n| (n.addr64, &n.identifier[..]))
        .collect();
    assert_eq!(names, [(MAV_A, &b"MAV 1b"[..]), (MAV_B, b"MAV \xe9")]);
    assert_eq!(nodes[1].rssi, Some(0x28));
    assert_eq!(
        nodes[1].to_string(),
        r#"0013a20040b599bf (7d84) router "MAV \xe9", -40 dBm"#
    );
    assert_eq!(
        mcp_host::render::json::node(&nodes[1])["identifier"],
        r"MAV \xe9"
    );
}

#[tokio::test]
async fn a_radio_that_refuses_discovery_says_so() {
    let (_stream, sender, mut fake) = common::pty_link(ApiMode::Unescaped).await;
    let discovery = tokio::spawn({
        let sender = sender.clone();
        async move { sender.discover(Some(Duration::from_secs(60))).await }
    });
    let id = at_command(&mut fake, *b"ND").await;
    respond(&mut fake, id, AtStatus::InvalidCommand, &[]).await;
    let error = tokio::time::timeout(GUARD, discovery)
        .await
        .unwrap()
        .unwrap()
        .unwrap_err();
    assert!(
        matches!(
            error,
            DiscoverError::Refused {
                status: AtStatus::InvalidCommand,
                ..
            }
        ),
        "{error:?}"
    );
    assert_eq!(
        error.to_string(),
        "node discovery: the radio answered invalid_command (0x02)"
    );
}

#[tokio::test]
async fn a_link_lost_during_discovery_ends_the_answers_with_why() {
    let (_stream, sender, mut fake) = common::pty_link(ApiMode::Unescaped).await;
    let mut answers = sender
        .at_answers(*b"ND", &[], Duration::from_secs(60))
        .await
        .unwrap();
    let id = at_command(&mut fake, *b"ND").await;
    respond(&mut fake, id, AtStatus::Ok, &answer(MAV_A, b"A")).await;
    assert!(answers.next().await.unwrap().is_ok());
    drop(fake);
    let end = tokio::time::timeout(GUARD, answers.next()).await.unwrap();
    assert!(
        matches!(end, Some(Err(SendError::Disconnected { .. }))),
        "{end:?}"
    );
    assert!(answers.next().await.is_none());
    // A closed link takes no more.
    sender.close();
    sender.closed().await;
    let after = sender.at_answers(*b"ND", &[], Duration::from_secs(1)).await;
    match after {
        Err(SendError::Closed) => {}
        Ok(mut answers) => assert_eq!(answers.next().await, Some(Err(SendError::Closed))),
        Err(other) => panic!("{other}"),
    }
}

/// The discovery window of a radio that answers `N?` with `data`.
async fn window_of_a_radio_answering(data: &[u8]) -> Duration {
    let (_stream, sender, mut fake) = common::pty_link(ApiMode::Unescaped).await;
    let window = tokio::spawn({
        let sender = sender.clone();
        async move { mcp_host::discovery::window(&sender).await }
    });
    let id = at_command(&mut fake, *b"N?").await;
    fake.send(&AtCommandResponseRepr {
        frame_id: id,
        command: *b"N?",
        status: AtStatus::Ok,
        data,
    })
    .await;
    tokio::time::timeout(GUARD, window)
        .await
        .unwrap()
        .unwrap()
        .unwrap()
}

#[tokio::test]
async fn the_window_is_the_radios_longest_discovery_time_where_it_gives_one() {
    // A DigiMesh radio: N? is NT and the network's delays, in milliseconds.
    let window = window_of_a_radio_answering(&[0x00, 0x00, 0x1F, 0x40]).await;
    assert_eq!(window, Duration::from_secs(8) + DISCOVERY_MARGIN);
}

#[tokio::test]
async fn a_discovery_time_longer_than_any_radios_is_cut() {
    // 49.7 days, from a peer that is no radio.
    let window = window_of_a_radio_answering(&[0xFF; 4]).await;
    assert_eq!(
        window,
        mcp_host::discovery::MAX_DISCOVERY_TIME + DISCOVERY_MARGIN
    );
}

#[tokio::test]
async fn the_emulated_network_answers_with_every_radio_it_can_reach() {
    let network = Network::new(NetworkConfig::default());
    let coord = common::tcp_coordinator(&network).await;
    // Devices kept open: their nodes stay reachable.
    let (a, _dev_a) = network
        .add_in_process(MAV_A, NodeOptions::default())
        .unwrap();
    let (b, _dev_b) = network
        .add_in_process(MAV_B, NodeOptions::default())
        .unwrap();
    let (_, _dev_c) = network
        .add_in_process(MAV_C, NodeOptions::default())
        .unwrap();
    assert!(network.cut(MAV_C));
    let link = format!("tcp:{}", coord.local_addr.unwrap())
        .parse()
        .unwrap();
    let (_stream, sender) = mcp_host::connect(&link, LinkOptions::default())
        .await
        .unwrap();
    let named = sender
        .remote_at(MAV_A, *b"NI", b"MAV 1", true, None)
        .await
        .unwrap();
    assert_eq!(named.data()[named.data().len() - 1], 0x00, "NI set");

    let nodes = sender
        .discover(Some(Duration::from_secs(2)))
        .await
        .unwrap()
        .nodes;
    let expected = [
        (a.addr64, a.addr16, &b"MAV 1"[..]),
        (b.addr64, b.addr16, b" "),
    ];
    let found: Vec<(Address64, Address16, &[u8])> = nodes
        .iter()
        .map(|n: &Node| (n.addr64, n.addr16, &n.identifier[..]))
        .collect();
    assert_eq!(found, expected);
    assert!(
        nodes
            .iter()
            .all(|n| n.device_type == DeviceType::Router && n.parent == Address16::UNKNOWN)
    );

    // `ND NAME` finds the one named so.
    let mut answers = sender
        .at_answers(*b"ND", b"MAV 1", Duration::from_secs(2))
        .await
        .unwrap();
    let only = answers.next().await.unwrap().unwrap();
    let info = NodeInfo::parse(&only.data()[5..]).unwrap();
    assert_eq!(info.addr64, MAV_A);
    assert!(answers.next().await.is_none());
    // `ND NAME` for a name nobody has: one answer, status 1 (error).
    let mut answers = sender
        .at_answers(*b"ND", b"nobody", Duration::from_secs(2))
        .await
        .unwrap();
    let none = answers.next().await.unwrap().unwrap();
    assert_eq!(none.data()[..], [0x88, none.data()[1], b'N', b'D', 0x01]);
    assert!(answers.next().await.is_none());

    // A remote AT command to the broadcast address: every radio it reaches carries it
    // out (the cut one does not), and, as on Zigbee, one answer comes, the first's.
    let mut answers = sender
        .remote_at_answers(
            Address64::BROADCAST,
            *b"NI",
            b"ALL",
            true,
            Duration::from_secs(2),
        )
        .await
        .unwrap();
    let mut answered = Vec::new();
    while let Some(answer) = answers.next().await {
        match answer.unwrap().parse() {
            Ok(xbee_api::Frame::RemoteAtResponse(at)) => {
                assert_eq!(at.status, AtStatus::Ok);
                answered.push(at.src64);
            }
            other => panic!("{other:?}"),
        }
    }
    assert_eq!(answered, [MAV_A]);
    for mav in [MAV_A, MAV_B] {
        let name = sender
            .remote_at(mav, *b"NI", &[], true, None)
            .await
            .unwrap();
        assert!(name.data().ends_with(b"ALL"), "{mav}: {:02x?}", name.data());
    }

    // Without a window, the radio's discovery time tells how long to listen.
    let window = mcp_host::discovery::window(&sender).await.unwrap();
    assert_eq!(window, Duration::from_secs(6) + DISCOVERY_MARGIN);
    let set = sender.at(*b"NT", &[0x20], None).await.unwrap();
    assert_eq!(set.data()[4], 0x00, "NT set");
    let window = mcp_host::discovery::window(&sender).await.unwrap();
    assert_eq!(window, Duration::from_millis(3200) + DISCOVERY_MARGIN);
    let refused = sender.at(*b"NT", &[0x10], None).await.unwrap();
    assert_eq!(
        AtStatus::from(refused.data()[4]),
        AtStatus::InvalidParameter
    );
    network.shutdown();
}
