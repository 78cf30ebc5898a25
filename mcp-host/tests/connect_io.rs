//! Links over byte streams the program opens itself (`io:` links): `connect_io` with
//! one stream, `connect_with` with the function that opens each, reconnecting.

mod common;

use std::time::Duration;

use common::*;
use mcp_core::{Report, StatusRequest};
use mcp_host::{ConnectError, Link, LinkError, LinkEvent, LinkOptions, ReconnectPolicy};
use tokio::sync::mpsc;
use xbee_api::{ApiMode, DeliveryStatus};

/// A landing request answered by the fake radio: its status, then the MAV's report.
async fn answer_landing(fake: &mut FakeXBee) {
    let tx = fake.next_tx().await;
    fake.status(tx.frame_id, DeliveryStatus::Success).await;
    fake.receive(MAV, b"r\x02\x04").await;
}

#[tokio::test]
async fn a_stream_handed_over_carries_requests_and_its_end_ends_the_link() {
    let (ours, radio) = tokio::io::duplex(1024);
    let (mut stream, sender) = mcp_host::connect_io("duplex", ours, LinkOptions::default())
        .await
        .unwrap();
    assert_eq!(stream.info().link.to_string(), "io:duplex");
    let mut fake = FakeXBee::new(radio, ApiMode::Unescaped);
    let request = tokio::spawn({
        let sender = sender.clone();
        async move { sender.request(MAV, StatusRequest::Landing).await }
    });
    answer_landing(&mut fake).await;
    let report = request.await.unwrap().unwrap();
    assert!(matches!(report, Report::Landing(_)), "{report:?}");
    assert_eq!(next_packet(&mut stream).await.origin.src64, MAV);

    // The radio's end goes: there is no other stream to open, so the link ends, though
    // reconnection is on.
    drop(fake);
    let LinkEvent::Disconnected { .. } = next_link_event(&mut stream).await else {
        panic!("a disconnection first")
    };
    match next_link_event(&mut stream).await {
        LinkEvent::Closed { reason, .. } => {
            assert!(reason.contains("io:duplex"), "{reason}");
            assert!(reason.contains("no other to open"), "{reason}");
        }
        other => panic!("{other:?}"),
    }
    tokio::time::timeout(GUARD, sender.closed()).await.unwrap();
}

#[tokio::test]
async fn an_opener_is_called_again_to_reconnect() {
    // Each stream it opens: the ground station's end kept, the radio's handed out.
    let (radios, mut next_radio) = mpsc::unbounded_channel();
    let opens = move || {
        let (ours, radio) = tokio::io::duplex(1024);
        let handed = radios.send(radio).map_err(std::io::Error::other);
        async move { handed.map(|()| ours) }
    };
    let options = LinkOptions {
        reconnect: ReconnectPolicy {
            enabled: true,
            initial_delay: Duration::from_millis(1),
            max_delay: Duration::from_millis(10),
        },
        ..LinkOptions::default()
    };
    let (mut stream, sender) = mcp_host::connect_with("bluetooth", opens, options)
        .await
        .unwrap();
    match next_link_event(&mut stream).await {
        LinkEvent::Connected { peer, .. } => assert_eq!(peer, "bluetooth"),
        other => panic!("{other:?}"),
    }
    let mut fake = FakeXBee::new(next_radio.recv().await.unwrap(), ApiMode::Unescaped);
    for round in 0..3 {
        let request = tokio::spawn({
            let sender = sender.clone();
            async move { sender.request(MAV, StatusRequest::Landing).await }
        });
        answer_landing(&mut fake).await;
        assert!(request.await.unwrap().is_ok(), "round {round}");
        // The stream breaks; the link opens the next.
        drop(fake);
        loop {
            match next_link_event(&mut stream).await {
                LinkEvent::Disconnected { .. } => {}
                LinkEvent::Reconnected { peer, .. } => {
                    assert_eq!(peer, "bluetooth");
                    break;
                }
                other => panic!("round {round}: {other:?}"),
            }
        }
        fake = FakeXBee::new(next_radio.recv().await.unwrap(), ApiMode::Unescaped);
    }
}

#[tokio::test]
async fn an_opener_that_fails_for_good_fails_connect_and_a_link_string_cannot_open_one() {
    let refused = || async {
        Err::<tokio::io::DuplexStream, _>(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "no such device",
        ))
    };
    let err = mcp_host::connect_with("bt", refused, LinkOptions::default())
        .await
        .unwrap_err();
    assert_eq!(err.to_string(), "cannot open io:bt: no such device");
    assert!(matches!(
        err,
        ConnectError::Link(LinkError::Io { ref name, .. }) if name == "bt"
    ));

    // `io:` parses, and displays back, but `connect` has nothing to open it with.
    let link: Link = "io:bt".parse().unwrap();
    assert_eq!(link, Link::io("bt"));
    assert_eq!(link.to_string(), "io:bt");
    let err = mcp_host::connect(&link, LinkOptions::default())
        .await
        .unwrap_err();
    assert!(err.to_string().contains("mcp_host::connect_with"), "{err}");
}

#[tokio::test]
async fn an_opener_that_hangs_is_given_up_after_the_connect_timeout() {
    let hangs = || std::future::pending::<std::io::Result<tokio::io::DuplexStream>>();
    let options = LinkOptions {
        connect_timeout: Duration::from_millis(50),
        ..LinkOptions::default()
    };
    let connecting = mcp_host::connect_with("tunnel", hangs, options);
    let err = tokio::time::timeout(GUARD, connecting)
        .await
        .expect("connect_with returns")
        .unwrap_err();
    let ConnectError::Link(LinkError::Io { error, .. }) = &err else {
        panic!("{err:?}")
    };
    assert_eq!(error.kind(), std::io::ErrorKind::TimedOut);
    assert_eq!(
        err.to_string(),
        "cannot open io:tunnel: not opened within 0.05 s"
    );
    // A retry may fix it: with wait_for_link, the link waits for it.
    assert!(matches!(&err, ConnectError::Link(e) if e.is_retryable()));
}

#[test]
fn an_io_link_keeps_the_handles_shareable_between_threads() {
    fn shareable<T: Send + Sync>() {}
    shareable::<mcp_host::Transport>();
    shareable::<mcp_host::Connector>();
}

/// A radio that takes no more bytes (flow control held, a hung bridge) leaves requests
/// backed up in the link's task; once the stream and every sender are dropped, the link
/// still ends (its transport closed, its subscriptions told), rather than waiting for a
/// radio that may never read again.
#[tokio::test]
async fn dropping_every_handle_ends_the_link_while_writes_are_backed_up() {
    let (ours, mut radio) = tokio::io::duplex(64);
    let (stream, sender) = mcp_host::connect_io("stuck", ours, LinkOptions::default())
        .await
        .unwrap();
    let mut subscription = sender.subscribe();
    let options = mcp_host::SendOptions {
        timeout: None,
        frame_id: mcp_host::FrameId::None,
    };
    // Fire-and-forget frames (218 bytes each) are written, as far as their callers
    // know, once queued: the 76 first fill the queue past 16 KiB, after which the link's
    // task takes no more requests. The others wait to be taken.
    let mut sends = Vec::new();
    for _ in 0..100 {
        let sender = sender.clone();
        sends.push(tokio::spawn(async move {
            sender.send_payload(MAV, vec![0u8; 200], options).await
        }));
    }
    let waiting = sends.split_off(76);
    for send in sends {
        let written = tokio::time::timeout(GUARD, send).await.unwrap().unwrap();
        assert_eq!(written.unwrap(), mcp_host::DeliveryReport::Written);
    }
    for send in &waiting {
        send.abort();
    }
    // Given up, and every handle dropped: the link ends.
    for send in waiting {
        assert!(send.await.unwrap_err().is_cancelled());
    }
    drop(stream);
    drop(sender);
    let ended = tokio::time::timeout(GUARD, async {
        let mut last = None;
        while let Some(event) = futures::StreamExt::next(&mut subscription).await {
            last = Some(event);
        }
        last
    })
    .await
    .expect("the link ends");
    assert!(
        matches!(ended, Some(mcp_host::Event::Link(LinkEvent::Closed { .. }))),
        "{ended:?}"
    );
    // Its transport is closed: the radio's end finds no one there.
    let written = tokio::io::AsyncWriteExt::write_all(&mut radio, b"x").await;
    assert!(written.is_err(), "{written:?}");
}
