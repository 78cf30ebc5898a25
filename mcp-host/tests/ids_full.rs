//! While all 255 frame ids are in flight (a radio that leaves statuses unanswered),
//! requests that need no id still go out, and those that need one wait, in order, for
//! the first id to come free, or time out at their own deadline; ids whose callers
//! stopped waiting are taken back for them.

mod common;

use std::time::Duration;

use common::{FakeXBee, pty_link};
use mcp_host::{CommandSender, DeliveryReport, FrameId, SendError, SendOptions};
use xbee_api::{Address64, ApiMode, DeliveryStatus};

const MAV: Address64 = Address64(0x0013_A200_4000_0001);

/// Options of a transmit that waits for its status for `secs` seconds.
fn waiting(secs: u64) -> SendOptions {
    SendOptions {
        timeout: Some(Duration::from_secs(secs)),
        frame_id: FrameId::Auto,
    }
}

/// Takes all 255 frame ids with transmits the radio reads and leaves unanswered; the
/// tasks awaiting them, and the ids in the order the radio read them.
async fn fill_ids(
    sender: &CommandSender,
    fake: &mut FakeXBee,
) -> (
    Vec<tokio::task::JoinHandle<Result<DeliveryReport, SendError>>>,
    Vec<u8>,
) {
    let mut tasks = Vec::new();
    for i in 0..255u8 {
        let sender = sender.clone();
        tasks.push(tokio::spawn(async move {
            sender.send_payload(MAV, vec![b'm', i], waiting(60)).await
        }));
    }
    let mut ids = Vec::new();
    for _ in 0..255 {
        ids.push(fake.next_tx().await.frame_id);
    }
    let mut sorted = ids.clone();
    sorted.sort_unstable();
    assert_eq!(sorted, (1..=255).collect::<Vec<u8>>());
    (tasks, ids)
}

#[tokio::test]
async fn writes_go_out_and_requests_wait_for_a_free_id() {
    let (_stream, sender, mut fake) = pty_link(ApiMode::Escaped).await;
    let (tasks, ids) = fill_ids(&sender, &mut fake).await;

    // A 256th transmit with status: taken (its op is queued before the writes below),
    // then parked, as no id is free.
    let late = sender.send_payload(MAV, b"mlate".to_vec(), waiting(60));
    tokio::pin!(late);
    assert!(futures::poll!(&mut late).is_pending());

    // Ops that need no id go out meanwhile, in order.
    sender.write_frame(&[0x08, 0x00, b'N', b'I']).await.unwrap();
    let report = sender
        .send_payload(
            MAV,
            b"mfire".to_vec(),
            SendOptions {
                timeout: None,
                frame_id: FrameId::None,
            },
        )
        .await
        .unwrap();
    assert_eq!(report, DeliveryReport::Written);
    assert_eq!(fake.next_frame().await, [0x08, 0x00, b'N', b'I']);
    let fire = fake.next_tx().await;
    assert_eq!((fire.frame_id, fire.data.as_slice()), (0, &b"mfire"[..]));

    // One status frees one id: the parked transmit goes out with it.
    let freed = ids[7];
    fake.status(freed, DeliveryStatus::Success).await;
    let tx = fake.next_tx().await;
    assert_eq!((tx.frame_id, tx.data.as_slice()), (freed, &b"mlate"[..]));
    fake.status(freed, DeliveryStatus::Success).await;
    assert!(matches!(
        late.await,
        Ok(DeliveryReport::Delivered { frame_id, .. }) if frame_id == freed
    ));
    // The transmit that held the id first got its own status.
    let first = ids.iter().position(|&id| id == freed).unwrap();
    let mut tasks = tasks;
    let done = tasks.swap_remove(first).await.unwrap();
    assert!(matches!(
        done,
        Ok(DeliveryReport::Delivered { frame_id, .. }) if frame_id == freed
    ));
}

#[tokio::test]
async fn a_parked_request_times_out_at_its_deadline() {
    let (_stream, sender, mut fake) = pty_link(ApiMode::Unescaped).await;
    let (_tasks, ids) = fill_ids(&sender, &mut fake).await;
    let short = SendOptions {
        timeout: Some(Duration::from_millis(300)),
        frame_id: FrameId::Auto,
    };
    let result = tokio::time::timeout(
        Duration::from_secs(10),
        sender.send_payload(MAV, b"mshort".to_vec(), short),
    )
    .await
    .expect("the parked transmit is answered at its deadline, not when an id frees");
    assert!(
        matches!(result, Err(SendError::NoFreeFrameId { timeout, .. }) if timeout == Duration::from_millis(300)),
        "{result:?}"
    );
    assert_eq!(sender.stats().timeouts, 1);
    // It never went out: with an id free again, the next frame is the next request's.
    fake.status(ids[0], DeliveryStatus::Success).await;
    sender.write_frame(&[0x08, 0x00, b'N', b'I']).await.unwrap();
    assert_eq!(fake.next_frame().await, [0x08, 0x00, b'N', b'I']);
}

#[tokio::test]
async fn ids_of_requests_nobody_waits_for_stay_taken_until_their_late_answers() {
    let (_stream, sender, mut fake) = pty_link(ApiMode::Unescaped).await;
    // 255 transmits whose callers give up once they went out (dropped, as an outer
    // `tokio::time::timeout` drops them), long before their own 60 s deadline; the radio
    // has not answered them yet.
    let mut ids = Vec::new();
    for i in 0..255u8 {
        let sender = sender.clone();
        let abandoned =
            tokio::spawn(async move { sender.send_payload(MAV, vec![b'm', i], waiting(60)).await });
        ids.push(fake.next_tx().await.frame_id);
        abandoned.abort();
        assert!(abandoned.await.unwrap_err().is_cancelled());
    }
    let next = tokio::spawn({
        let sender = sender.clone();
        async move {
            sender
                .send_payload(MAV, b"mnext".to_vec(), waiting(60))
                .await
        }
    });
    // The radio answers the first late: that answer is nobody's, and frees its id,
    // under which the next request goes out. Its own status is the one it gets.
    fake.status(ids[0], DeliveryStatus::Success).await;
    let tx = fake.next_tx().await;
    assert_eq!((tx.data.as_slice(), tx.frame_id), (&b"mnext"[..], ids[0]));
    fake.status(tx.frame_id, DeliveryStatus::from(0x24)).await;
    assert!(matches!(
        next.await.unwrap(),
        Err(SendError::Delivery { frame_id, .. }) if frame_id == tx.frame_id
    ));
    assert_eq!(sender.stats().unclaimed_responses, 1);
}
