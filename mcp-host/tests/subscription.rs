//! More readers of one link: subscriptions get every event beside the stream, each at
//! its own pace, and end with the link. Over a real pseudo-terminal, a fake radio on
//! its far end.

mod common;

use common::*;
use futures::StreamExt;
use mcp_core::{Packet, Report};
use mcp_host::{Event, LinkEvent, LinkOptions, Subscription};
use xbee_api::ApiMode;

fn time_report(t: u32) -> Vec<u8> {
    mcp(&Packet::<&[u8]>::Report(Report::Time(t)))
}

/// The next event of a subscription, within the guard time.
async fn next(subscription: &mut Subscription) -> Option<Event> {
    tokio::time::timeout(GUARD, subscription.next())
        .await
        .expect("no event in time")
}

/// The payloads of the packets among `events`.
fn payloads(events: &[Event]) -> Vec<Vec<u8>> {
    events
        .iter()
        .filter_map(|e| match e {
            Event::Packet(rx) => Some(rx.payload.to_vec()),
            _ => None,
        })
        .collect()
}

#[tokio::test]
async fn every_reader_gets_every_event_in_order_and_ends_with_the_link() {
    let (mut stream, sender, mut fake) = pty_link(ApiMode::Escaped).await;
    let (mut ui, mut log) = (sender.subscribe(), sender.subscribe());
    let sent: Vec<Vec<u8>> = (1..=5).map(time_report).collect();
    for payload in &sent {
        fake.receive(MAV, payload).await;
    }
    let mut from_stream = Vec::new();
    for _ in &sent {
        from_stream.push(next_packet(&mut stream).await.payload.to_vec());
    }
    assert_eq!(from_stream, sent);
    for subscription in [&mut ui, &mut log] {
        let mut events = Vec::new();
        while events.len() < sent.len() {
            events.push(next(subscription).await.expect("an event"));
        }
        assert_eq!(payloads(&events), sent);
        assert_eq!(subscription.missed(), 0);
    }

    // The link ends: each subscription's last event says so, then it ends, while the
    // stream is not read.
    sender.close();
    for subscription in [&mut ui, &mut log] {
        assert!(matches!(
            next(subscription).await,
            Some(Event::Link(LinkEvent::Closed { .. }))
        ));
        assert!(next(subscription).await.is_none());
    }
    // One taken afterwards ends at once.
    sender.closed().await;
    assert!(next(&mut sender.subscribe()).await.is_none());
    drop(stream);
}

#[tokio::test]
async fn a_reader_that_falls_behind_misses_the_oldest_and_holds_up_nobody() {
    let (mut stream, sender, mut fake) = pty_link_with(LinkOptions {
        api_mode: ApiMode::Escaped,
        event_capacity: 4,
        ..LinkOptions::default()
    })
    .await;
    let mut slow = sender.subscribe();
    let mut fast = sender.subscribe();
    let sent: Vec<Vec<u8>> = (1..=10).map(time_report).collect();
    let mut fast_got = Vec::new();
    for payload in &sent {
        fake.receive(MAV, payload).await;
        // The stream and the fast reader keep up; the slow one reads nothing yet.
        assert_eq!(&next_packet(&mut stream).await.payload[..], &payload[..]);
        fast_got.push(next(&mut fast).await.expect("an event"));
    }
    assert_eq!(payloads(&fast_got), sent);
    assert_eq!(fast.missed(), 0);
    // The slow reader gets the newest 4 and counts the 6 it missed.
    let mut slow_got = Vec::new();
    while slow_got.len() < 4 {
        slow_got.push(next(&mut slow).await.expect("an event"));
    }
    assert_eq!(payloads(&slow_got), sent[6..]);
    assert_eq!(slow.missed(), 6);
    // And goes on with what comes next.
    fake.receive(MAV, &time_report(11)).await;
    assert_eq!(
        payloads(&[next(&mut slow).await.expect("an event")]),
        [time_report(11)]
    );
}

#[tokio::test]
async fn a_link_dropped_by_its_owners_ends_its_subscriptions_with_closed() {
    let (stream, sender, _fake) = pty_link(ApiMode::Escaped).await;
    let mut watcher = sender.subscribe();
    drop((stream, sender));
    match next(&mut watcher).await {
        Some(Event::Link(LinkEvent::Closed { reason, .. })) => {
            assert_eq!(reason, "the stream and every sender were dropped");
        }
        other => panic!("{other:?}"),
    }
    assert!(next(&mut watcher).await.is_none());
}

#[tokio::test]
async fn a_tap_gets_every_frame_both_ways_as_it_is_on_the_link() {
    use mcp_host::record::Direction;
    let (mut stream, sender, mut fake) = pty_link(ApiMode::Escaped).await;
    let mut tap = sender.tap_frames();
    // A request whose bytes need escapes in mode 2: the tap has them unescaped, under
    // the frame id the link gave the request.
    let parameter = [0x7E, 0x7D, 0x11, 0x13];
    let asking = sender.clone();
    let request = tokio::spawn(async move { asking.at(*b"NI", &parameter, None).await });
    let written = fake.next_frame().await;
    assert_eq!(written[0], 0x08);
    assert_eq!(written[2..], [b'N', b'I', 0x7E, 0x7D, 0x11, 0x13]);
    // Its answer, which goes to the request and not to the stream, and a packet.
    let answer = [0x88, written[1], b'N', b'I', 0x00];
    fake.send(&xbee_api::Frame::parse_bytes(&answer).unwrap())
        .await;
    request.await.unwrap().expect("answered");
    let report = time_report(0x7E7D_1113);
    fake.receive(MAV, &report).await;
    assert_eq!(next_packet(&mut stream).await.payload.to_vec(), report);

    let mut records = Vec::new();
    while records.len() < 3 {
        let record = tokio::time::timeout(GUARD, tap.next())
            .await
            .expect("a frame in time")
            .expect("the tap goes on");
        records.push(record);
    }
    let ways: Vec<(Direction, Vec<u8>)> = records
        .iter()
        .map(|r| (r.direction, r.frame.clone()))
        .collect();
    let mut packet = vec![0x90];
    packet.extend_from_slice(&MAV.0.to_be_bytes());
    packet.extend_from_slice(&[0x7D, 0x33, 0x01]);
    packet.extend_from_slice(&report);
    assert_eq!(
        ways,
        [
            (Direction::Sent, written),
            (Direction::Received, answer.to_vec()),
            (Direction::Received, packet),
        ]
    );
    assert!(records.windows(2).all(|w| w[0].time <= w[1].time));
    assert_eq!(tap.missed(), 0);

    // It ends with the link.
    sender.close();
    let end = tokio::time::timeout(GUARD, tap.next())
        .await
        .expect("the end in time");
    assert!(end.is_none(), "{end:?}");
    // Read again after its end (in a `select!` loop), it ends again.
    assert!(futures::stream::FusedStream::is_terminated(&tap));
    assert!(tap.next().await.is_none());
}

#[tokio::test]
async fn packets_from_one_mav_leave_out_the_others_and_every_other_event() {
    let (mut stream, sender, mut fake) = pty_link(ApiMode::Escaped).await;
    let mut every = sender.subscribe();
    let mut packets = sender.subscribe().packets();
    let mut from_mav = sender.subscribe().packets_from(MAV);
    let ours: Vec<Vec<u8>> = (1..=3).map(time_report).collect();
    let theirs = time_report(99);
    for payload in &ours {
        fake.receive(OTHER_MAV, &theirs).await;
        // Not an MCP packet: an event with an origin, but no packet.
        fake.receive(MAV, b"\xFF").await;
        fake.receive(MAV, payload).await;
    }
    let mut events = Vec::new();
    while events.len() < 3 * ours.len() {
        events.push(next(&mut every).await.expect("an event"));
    }
    let origins: Vec<_> = events.iter().map(|e| e.origin().map(|o| o.src64)).collect();
    assert_eq!(origins, [Some(OTHER_MAV), Some(MAV), Some(MAV)].repeat(3));
    assert_eq!(
        events.iter().filter(|e| e.packet().is_some()).count(),
        2 * ours.len()
    );
    assert!(matches!(events[1], Event::InvalidPacket(_)));

    let mut got = Vec::new();
    while got.len() < ours.len() {
        let rx = tokio::time::timeout(GUARD, from_mav.next()).await.unwrap();
        let rx = rx.expect("a packet");
        assert_eq!(rx.origin.src64, MAV);
        got.push(rx.payload.to_vec());
    }
    assert_eq!(got, ours);
    let mut all = Vec::new();
    while all.len() < 2 * ours.len() {
        let rx = tokio::time::timeout(GUARD, packets.next()).await.unwrap();
        all.push(rx.expect("a packet").origin.src64);
    }
    assert_eq!(all, [OTHER_MAV, MAV].repeat(3));

    // They end with the link, what they left out included.
    sender.close();
    for subscription in [&mut from_mav, &mut packets] {
        let end = tokio::time::timeout(GUARD, subscription.next())
            .await
            .unwrap();
        assert!(end.is_none());
        assert_eq!(subscription.missed(), 0);
    }
    drop(stream.next().await);
}
