//! Requests whose callers give up (a future dropped: a `tokio::time::timeout`, a
//! `select!`, a task aborted) leave nothing behind: their frames not yet gone out are
//! never sent, a later request goes at once, a `write_frame` that timed out is not
//! written after all, and an `Answers` stream ends with an error when the link does.

mod common;

use std::time::Duration;

use common::*;
use mcp_host::{DeliveryReport, FrameId, LinkOptions, SendError, SendOptions};
use xbee_api::{ApiMode, DeliveryStatus};

fn waiting(secs: u64) -> SendOptions {
    SendOptions {
        timeout: Some(Duration::from_secs(secs)),
        frame_id: FrameId::Auto,
    }
}

/// More requests than there are frame ids, and more than may wait for one, to a radio
/// that reads nothing yet, all given up; then one more. When the radio reads again, it
/// gets none of the given-up frames but the few already on their way, then the new one,
/// whose status comes back at once.
#[tokio::test(flavor = "current_thread")]
async fn requests_given_up_while_none_is_taken_are_never_sent() {
    let (ours, theirs) = tokio::io::duplex(64);
    let (_stream, sender) = mcp_host::connect_io("stuck", ours, LinkOptions::default())
        .await
        .unwrap();
    let mut tasks = Vec::new();
    for i in 0..255 + 100 {
        let sender = sender.clone();
        tasks.push(tokio::spawn(async move {
            let payload = vec![b'm', (i % 256) as u8];
            sender.send_payload(MAV, payload, waiting(60)).await
        }));
    }
    // Until the link's task has taken all it takes: 255 in flight, 64 waiting for an
    // id, the rest in its queue.
    for _ in 0..100 {
        tokio::task::yield_now().await;
    }
    for task in &tasks {
        task.abort();
    }
    for task in tasks {
        assert!(task.await.unwrap_err().is_cancelled());
    }
    let next = tokio::spawn({
        let sender = sender.clone();
        async move {
            sender
                .send_payload(MAV, b"mNEXT".to_vec(), waiting(5))
                .await
        }
    });
    let mut radio = FakeXBee::new(theirs, ApiMode::Unescaped);
    let mut before = 0;
    loop {
        let tx = radio.next_tx().await;
        if tx.data == b"mNEXT" {
            radio.status(tx.frame_id, DeliveryStatus::Success).await;
            break;
        }
        before += 1;
    }
    // 20 bytes a frame: those in the pipe's 64 bytes and in the link's write under way
    // when the radio reads again, 7 at most, rather than all 255 in flight.
    assert!(
        before <= 7,
        "{before} given-up frames sent before the new one"
    );
    let report = next.await.unwrap();
    assert!(
        matches!(report, Ok(DeliveryReport::Delivered { .. })),
        "{report:?}"
    );
}

/// A `write_frame` that times out, its link's writes backed up by a radio that reads
/// nothing, is not written once the radio reads again: its caller was told it was not
/// sent.
#[tokio::test]
async fn a_write_frame_that_timed_out_is_not_written_later() {
    let (ours, theirs) = tokio::io::duplex(64);
    let options = LinkOptions {
        send_timeout: Duration::from_millis(300),
        ..LinkOptions::default()
    };
    let (_stream, sender) = mcp_host::connect_io("stuck", ours, options).await.unwrap();
    // Fire-and-forget frames of 218 bytes: the first 76 fill the link's queue past
    // 16 KiB, after which it takes no more.
    let forget = SendOptions {
        timeout: Some(GUARD),
        frame_id: FrameId::None,
    };
    let mut backlog = Vec::new();
    for _ in 0..100 {
        let sender = sender.clone();
        backlog.push(tokio::spawn(async move {
            sender.send_payload(MAV, vec![0u8; 200], forget).await
        }));
    }
    for queued in backlog.drain(..76) {
        assert_eq!(queued.await.unwrap().unwrap(), DeliveryReport::Written);
    }
    let timed_out = sender.write_frame(&[0x08, 0x00, b'W', b'F']).await;
    assert!(
        matches!(timed_out, Err(SendError::NotSent { .. })),
        "{timed_out:?}"
    );

    // The radio reads again; a last frame after all the others.
    let mut radio = FakeXBee::new(theirs, ApiMode::Unescaped);
    let last = tokio::spawn({
        let sender = sender.clone();
        async move {
            for queued in backlog {
                queued.await.unwrap().unwrap();
            }
            let forget = SendOptions {
                timeout: Some(GUARD),
                frame_id: FrameId::None,
            };
            sender.send_payload(MAV, b"mEND".to_vec(), forget).await
        }
    });
    loop {
        let frame = radio.next_frame().await;
        assert_ne!(frame, [0x08, 0x00, b'W', b'F'], "written after its timeout");
        if frame.ends_with(b"mEND") {
            break;
        }
    }
    assert_eq!(last.await.unwrap().unwrap(), DeliveryReport::Written);
}

/// Answers still gathered when every handle of the link is dropped (the stream and the
/// senders: an `Answers` stream outlives them) end with an error, not as a window that
/// ran out.
#[tokio::test]
async fn answers_gathered_when_the_link_ends_end_with_an_error() {
    let (ours, theirs) = tokio::io::duplex(1024);
    let (stream, sender) = mcp_host::connect_io("radio", ours, LinkOptions::default())
        .await
        .unwrap();
    let mut radio = FakeXBee::new(theirs, ApiMode::Unescaped);
    let mut answers = sender
        .at_answers(*b"ND", &[], Duration::from_secs(30))
        .await
        .unwrap();
    let asked = radio.next_frame().await;
    assert_eq!(&asked[2..], b"ND");
    radio
        .send(&xbee_api::RawFrame::new(&[0x88, asked[1], b'N', b'D', 0x00, 0xFF, 0xFE]).unwrap())
        .await;
    let first = answers.next().await.unwrap().unwrap();
    assert_eq!(&first.data()[2..4], b"ND");
    drop(stream);
    drop(sender);
    let ended = tokio::time::timeout(GUARD, answers.next()).await.unwrap();
    assert!(matches!(ended, Some(Err(SendError::Closed))), "{ended:?}");
    assert!(answers.next().await.is_none());
}
