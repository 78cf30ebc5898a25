//! Connections that take nothing from the hub cannot lock the others out: with
//! `MAX_CLIENTS` connected, a new client takes the place of one that has taken none of
//! the radio's frames for `STALLED`, never of one that keeps up or reads, however
//! slowly; and one falls behind after a bounded number of frames. Over real TCP sockets.

mod common;

use std::time::Duration;

use common::hub_wire::*;
use futures::{SinkExt, StreamExt};
use mcp_host::codec::{CodecItem, XBeeCodec};
use mcp_host::hub::{Hub, MAX_CLIENTS, STALLED};
use tokio::io::AsyncReadExt;
use tokio::net::TcpStream;
use tokio_util::codec::Framed;
use xbee_api::{ApiMode, RawFrame};

/// Failure guard only: every wait ends on a frame long before this.
const GUARD: Duration = Duration::from_secs(30);

/// Whether the hub closes `socket` at once, having turned it away (it writes nothing
/// to a client before the radio sends something).
async fn turned_away(socket: &mut TcpStream) -> bool {
    let mut byte = [0u8; 1];
    let read = tokio::time::timeout(GUARD, socket.read(&mut byte)).await;
    matches!(read, Ok(Ok(0) | Err(_)))
}

/// A connection to the hub with a small receive buffer of its own (4 KiB, which fixes
/// the window it offers): one that reads nothing is full at once, and stays so.
async fn small_buffered(hub: &Hub) -> TcpStream {
    let socket = tokio::net::TcpSocket::new_v4().unwrap();
    socket.set_recv_buffer_size(4096).unwrap();
    socket.connect(hub.local_addr()).await.unwrap()
}

/// A client served by the hub: its frame reaches the radio.
async fn served(hub: &Hub, radio: &mut Wire) -> Wire {
    let socket = TcpStream::connect(hub.local_addr()).await.unwrap();
    let mut client = Framed::new(socket, XBeeCodec::new(ApiMode::Unescaped));
    send(&mut client, &[0x08, 0x00, b'S', b'H']).await;
    assert_eq!(next(radio).await, [0x08, 0x00, b'S', b'H']);
    client
}

/// A monitor of `hub` that reads every frame: the number each received packet from
/// [`radio_batch`] carries, on the channel.
async fn numbered_monitor(
    hub: &Hub,
) -> (
    tokio::task::JoinHandle<()>,
    tokio::sync::mpsc::UnboundedReceiver<u32>,
) {
    let reader = TcpStream::connect(hub.local_addr()).await.unwrap();
    let (seen, seen_rx) = tokio::sync::mpsc::unbounded_channel();
    let reading = tokio::spawn(async move {
        let mut reader = Framed::new(reader, XBeeCodec::new(ApiMode::Unescaped));
        while let Some(Ok(CodecItem::Frame(frame))) = reader.next().await {
            let data = frame.data();
            let _ = seen.send(u32::from_be_bytes(data[12..16].try_into().unwrap()));
        }
    });
    (reading, seen_rx)
}

/// The radio sends `batch` received packets of 250 bytes, numbered on from `number`;
/// returns once the [`numbered_monitor`] has them all.
async fn radio_batch(
    radio: &mut Wire,
    number: &mut u32,
    batch: u32,
    seen: &mut tokio::sync::mpsc::UnboundedReceiver<u32>,
) {
    let mut packet = vec![
        0x90, 0, 0x13, 0xA2, 0, 0x40, 0xB5, 0x99, 0xB9, 0xFF, 0xFE, 0x01,
    ];
    for _ in 0..batch {
        *number += 1;
        packet.truncate(12);
        packet.extend_from_slice(&number.to_be_bytes());
        packet.resize(250, b'm');
        radio.feed(&RawFrame::new(&packet).unwrap()).await.unwrap();
    }
    SinkExt::<&RawFrame<'_>>::flush(radio).await.unwrap();
    loop {
        let got = tokio::time::timeout(GUARD, seen.recv()).await.unwrap();
        if got.expect("the monitor stays") == *number {
            return;
        }
    }
}

#[tokio::test(flavor = "multi_thread")]
async fn connections_that_take_nothing_give_their_place_to_new_clients_but_readers_keep_theirs() {
    let (hub, mut radio) = hub_and_radio().await;

    // A monitor that reads all the radio's frames, and connections that never read.
    let (reading, mut seen_rx) = numbered_monitor(&hub).await;
    let mut idle = Vec::new();
    for _ in 1..MAX_CLIENTS {
        idle.push(TcpStream::connect(hub.local_addr()).await.unwrap());
    }
    // Full, and nobody behind yet: a new client is turned away (accepted in turn,
    // after the others).
    let mut late = TcpStream::connect(hub.local_addr()).await.unwrap();
    assert!(turned_away(&mut late).await);

    // The radio sends received packets until every idle connection has fallen behind:
    // each packet of a batch dropped for all of them.
    let mut number = 0u32;
    let batch = 200;
    loop {
        let dropped = hub.stats().frames_dropped;
        // The monitor keeps up.
        radio_batch(&mut radio, &mut number, batch, &mut seen_rx).await;
        let idle_count = (MAX_CLIENTS - 1) as u64;
        if hub.stats().frames_dropped - dropped == idle_count * u64::from(batch) {
            break;
        }
    }
    // Behind, but not for long yet: the next is turned away.
    let mut late = TcpStream::connect(hub.local_addr()).await.unwrap();
    assert!(turned_away(&mut late).await);
    // The time the hub gives a client that takes nothing.
    tokio::time::sleep(STALLED).await;

    // New clients take the idle connections' places, one each.
    let mut new = Vec::new();
    for _ in 1..MAX_CLIENTS {
        new.push(served(&hub, &mut radio).await);
    }
    // Now nobody is behind: the monitor kept its place, and the next is turned away.
    let mut late = TcpStream::connect(hub.local_addr()).await.unwrap();
    assert!(turned_away(&mut late).await);
    radio_batch(&mut radio, &mut number, 1, &mut seen_rx).await;
    assert!(!reading.is_finished());
    drop(idle);
    hub.stop().await;
}

/// A client that reads, but slower than the radio sends (a monitor on a slow network):
/// frames are dropped for it, yet it keeps its place when the hub is full; those that
/// read nothing lose theirs.
#[tokio::test(flavor = "multi_thread")]
async fn a_client_that_reads_slowly_keeps_its_place() {
    const BATCH: u32 = 600; // 150 KB
    const READ: usize = 64 * 1024; // a third of what it is sent
    let (hub, mut radio) = hub_and_radio().await;
    let (_reading, mut seen_rx) = numbered_monitor(&hub).await;
    // The slow reader takes READ bytes whenever told to.
    let slow = TcpStream::connect(hub.local_addr()).await.unwrap();
    let (take, mut told) = tokio::sync::mpsc::unbounded_channel::<()>();
    let (took, mut taken) = tokio::sync::mpsc::unbounded_channel::<usize>();
    let slow_reader = tokio::spawn(async move {
        let mut slow = slow;
        let mut buf = vec![0u8; READ];
        while told.recv().await.is_some() {
            if slow.read_exact(&mut buf).await.is_err() {
                return;
            }
            let _ = took.send(READ);
        }
    });
    let mut slowly = async || {
        take.send(()).unwrap();
        taken.recv().await
    };
    // Connections that read nothing, each with a small receive buffer of its own: the
    // system's buffers fill at once, and its window stays shut (a default buffer grows
    // the window it offers as frames come, unread, so that the hub's task may write a
    // frame to it well after a batch, which the hub takes for reading).
    let mut idle = Vec::new();
    for _ in 2..MAX_CLIENTS {
        idle.push(small_buffered(&hub).await);
    }
    // Batches until every batch is dropped whole for the idle connections and in part
    // for the slow reader, which reads a third of each: twice in a row, as a batch may
    // find a connection's queue full while its task still moves frames from it to the
    // system's buffers (the hub's tasks busy with the batch).
    let mut number = 0u32;
    let mut rounds = 0;
    let mut behind_in_a_row = 0;
    while behind_in_a_row < 2 {
        let dropped = hub.stats().frames_dropped;
        radio_batch(&mut radio, &mut number, BATCH, &mut seen_rx).await;
        assert_eq!(slowly().await, Some(READ), "the slow reader reads");
        rounds += 1;
        let idle_behind = (MAX_CLIENTS - 2) as u64 * u64::from(BATCH);
        if hub.stats().frames_dropped - dropped > idle_behind {
            behind_in_a_row += 1;
        } else {
            behind_in_a_row = 0;
        }
        assert!(rounds < 100, "never behind: {:?}", hub.stats());
    }
    // The time the hub gives a client that takes nothing; then one more batch, of which
    // the slow reader takes a third as before.
    tokio::time::sleep(STALLED).await;
    radio_batch(&mut radio, &mut number, BATCH, &mut seen_rx).await;
    assert_eq!(slowly().await, Some(READ), "the slow reader reads");
    // The idle connections' places go to new clients; the slow reader keeps its own.
    let mut new = Vec::new();
    for _ in 2..MAX_CLIENTS {
        new.push(served(&hub, &mut radio).await);
    }
    let mut late = TcpStream::connect(hub.local_addr()).await.unwrap();
    assert!(
        turned_away(&mut late).await,
        "the slow reader lost its place"
    );
    drop((idle, new));
    slow_reader.abort();
    hub.stop().await;
}

/// A program that writes frames faster than the radio sends them (a flood of short
/// frames, a replay at full speed onto the hub), which may have left with megabytes of them still in its
/// connection, whose end the hub cannot read before them: when the hub is full, it
/// gives its place to a new client once it has been ahead of the radio for `STALLED`,
/// its frames not yet written dropped; quiet clients keep theirs, and so does a client
/// that wrote a burst ahead of the radio, then waited.
#[tokio::test(flavor = "multi_thread")]
async fn a_client_that_writes_ahead_of_the_radio_gives_its_place_up() {
    let (hub, mut radio) = hub_and_radio().await;
    // The radio takes every frame; the test looks at them as they come.
    let (to_test, mut frames) = tokio::sync::mpsc::unbounded_channel::<Vec<u8>>();
    let radio_task = tokio::spawn(async move {
        while let Some(Ok(item)) = radio.next().await {
            if let CodecItem::Frame(frame) = item {
                if to_test.send(frame.data().to_vec()).is_err() {
                    return;
                }
            }
        }
    });
    // Transmit Requests without a frame id, of 200 bytes of `fill`.
    let requests = |fill: u8, count: usize| {
        let mut codec = XBeeCodec::new(ApiMode::Unescaped);
        let mut data = vec![
            0x10, 0x00, 0, 0x13, 0xA2, 0, 0x40, 0xB5, 0xFF, 0xFF, 0xFF, 0xFE, 0, 0,
        ];
        data.extend([fill; 200]);
        let mut bytes = mcp_host::bytes::BytesMut::new();
        for _ in 0..count {
            tokio_util::codec::Encoder::encode(
                &mut codec,
                &RawFrame::new(&data).unwrap(),
                &mut bytes,
            )
            .unwrap();
        }
        bytes.to_vec()
    };
    // First a burst of 40, ahead of the radio while it lasts, then nothing: sent whole.
    let mut burst = TcpStream::connect(hub.local_addr()).await.unwrap();
    tokio::io::AsyncWriteExt::write_all(&mut burst, &requests(0xBB, 40))
        .await
        .unwrap();
    let mut sent = 0;
    while sent < 40 {
        let frame = tokio::time::timeout(GUARD, frames.recv())
            .await
            .unwrap()
            .unwrap();
        sent += usize::from(frame[14] == 0xBB);
    }
    // Then 100 000 short frames (`AT NI`, no frame id), of which the radio's writer may
    // take two at once: 800 KB, a minute of the radio's UART.
    let flood = (0..100_000)
        .flat_map(|_| [0x7E, 0x00, 0x04, 0x08, 0x00, b'N', b'I', 0x60])
        .collect::<Vec<u8>>();
    let flood_frame = [0x08, 0x00, b'N', b'I'];
    let flooder = TcpStream::connect(hub.local_addr()).await.unwrap();
    let (mut flooder, mut flooding) = flooder.into_split();
    let flooding = tokio::spawn(async move {
        use tokio::io::AsyncWriteExt;
        flooding.write_all(&flood).await
    });
    // Its frames go to the radio, at the radio's pace.
    for _ in 0..3 {
        let frame = tokio::time::timeout(GUARD, frames.recv())
            .await
            .unwrap()
            .unwrap();
        assert_eq!(frame, flood_frame);
    }
    // The others connect and keep quiet; the radio is quiet: nobody is behind.
    let mut quiet = Vec::new();
    for _ in 2..MAX_CLIENTS {
        quiet.push(TcpStream::connect(hub.local_addr()).await.unwrap());
    }
    // Full, and the flooder not ahead for long yet: a new client is turned away.
    let mut late = TcpStream::connect(hub.local_addr()).await.unwrap();
    assert!(turned_away(&mut late).await);
    // The time the hub gives a client ahead of the radio.
    tokio::time::sleep(STALLED).await;
    // A new client takes the flooder's place: its frame reaches the radio.
    let mut new = raw_client(&hub).await;
    send(&mut new, &[0x08, 0x00, b'S', b'H']).await;
    loop {
        let frame = tokio::time::timeout(GUARD, frames.recv())
            .await
            .unwrap()
            .unwrap();
        if frame == [0x08, 0x00, b'S', b'H'] {
            break;
        }
        assert_eq!(frame, flood_frame);
    }
    // The flooder was let go: its connection ends, its frames not yet written dropped.
    let mut byte = [0u8; 1];
    let read = tokio::time::timeout(GUARD, flooder.read(&mut byte)).await;
    assert!(matches!(read, Ok(Ok(0) | Err(_))), "{read:?}");
    assert!(hub.stats().frames_refused > 0, "{:?}", hub.stats());
    // Every frame the hub read went to the radio or was refused, the one the flooder's
    // reader held on its way when it was let go too: none waits now.
    let mut looks = 0;
    while {
        let stats = hub.stats();
        stats.frames_read_from_clients != stats.frames_from_clients + stats.frames_refused
    } {
        looks += 1;
        assert!(
            looks < 500,
            "frames read and never settled: {:?}",
            hub.stats()
        );
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
    flooding.abort();
    // The quiet clients and the burst's kept their places: the next is turned away.
    let mut late = TcpStream::connect(hub.local_addr()).await.unwrap();
    assert!(turned_away(&mut late).await);
    drop((quiet, new, burst));
    hub.stop().await;
    radio_task.abort();
}

/// One-shot clients (as `mcp-gs at`): each connects, sends a frame and closes its
/// connection, on a radio that sends nothing (so the hub never fails to write to them).
/// Once `MAX_CLIENTS` of them have come and gone, the next client is still served: it
/// takes the place of one that has closed.
#[tokio::test(flavor = "multi_thread")]
async fn clients_that_closed_their_connections_give_their_places_up_on_a_quiet_radio() {
    let (hub, mut radio) = hub_and_radio().await;
    for _ in 0..MAX_CLIENTS {
        drop(served(&hub, &mut radio).await);
    }
    let mut late = served(&hub, &mut radio).await;
    send(&mut late, &[0x08, 0x00, b'S', b'L']).await;
    assert_eq!(next(&mut radio).await, [0x08, 0x00, b'S', b'L']);
    hub.stop().await;
}

/// Batches of 100 [`radio_batch`] frames until the hub has dropped one for a client
/// (10 000 frames at most).
async fn batches_until_one_dropped(
    hub: &Hub,
    radio: &mut Wire,
    number: &mut u32,
    seen: &mut tokio::sync::mpsc::UnboundedReceiver<u32>,
) {
    while hub.stats().frames_dropped == 0 {
        radio_batch(radio, number, 100, seen).await;
        assert!(*number < 10_000, "never behind: {:?}", hub.stats());
    }
}

/// A client that has fallen behind, and lost some of the radio's frames, still gets the
/// answer to its request, ahead of the frames waiting for it at the hub.
#[tokio::test(flavor = "multi_thread")]
async fn a_client_that_fell_behind_still_gets_the_answer_to_its_request() {
    let (hub, mut radio) = hub_and_radio().await;
    let (_reading, mut seen_rx) = numbered_monitor(&hub).await;
    let mut slow = Framed::new(
        small_buffered(&hub).await,
        XBeeCodec::new(ApiMode::Unescaped),
    );
    // Its request, under its own id 7, reaches the radio under the hub's.
    send(&mut slow, &[0x08, 0x07, b'N', b'I']).await;
    let request = next(&mut radio).await;
    assert_eq!(request[2..], *b"NI");
    let hub_id = request[1];
    // The radio's frames, until some are dropped for the client, which reads nothing.
    let mut number = 0u32;
    batches_until_one_dropped(&hub, &mut radio, &mut number, &mut seen_rx).await;
    // Then the radio answers, and sends one more batch.
    let answer = [0x88, hub_id, b'N', b'I', 0x00, b'M', b'A', b'V'];
    radio.send(&RawFrame::new(&answer).unwrap()).await.unwrap();
    radio_batch(&mut radio, &mut number, 100, &mut seen_rx).await;
    // The client reads again: its answer is among the frames, under its own id.
    let mut frames = 0;
    let got = loop {
        let frame = tokio::time::timeout(GUARD, slow.next())
            .await
            .expect("the answer")
            .expect("the hub goes on")
            .unwrap();
        let CodecItem::Frame(frame) = frame else {
            continue;
        };
        frames += 1;
        if frame.data()[0] == 0x88 {
            break frame.data().to_vec();
        }
    };
    assert_eq!(got, [0x88, 0x07, b'N', b'I', 0x00, b'M', b'A', b'V']);
    // After the frames already in its connection's buffers when the answer came, ahead
    // of the hub's queue of them (over a thousand waited there).
    assert!(frames > 100 && frames < 1000, "{frames}");
    hub.stop().await;
}

/// A connection that reads nothing falls behind after a bounded number of the radio's
/// frames: the hub's queue of `CLIENT_QUEUE` and a send buffer of its own size, not the
/// megabytes the system would let it grow to (where thousands of frames would wait for
/// a client that is gone).
#[tokio::test(flavor = "multi_thread")]
async fn a_connection_that_reads_nothing_falls_behind_after_a_bounded_number_of_frames() {
    let (hub, mut radio) = hub_and_radio().await;
    // A monitor that reads, to know when the hub has passed every frame on.
    let (_reading, mut seen_rx) = numbered_monitor(&hub).await;
    // A connection that reads nothing, with a small receive buffer of its own.
    let mut idle = Framed::new(
        small_buffered(&hub).await,
        XBeeCodec::new(ApiMode::Unescaped),
    );
    // Served: its frame reaches the radio.
    send(&mut idle, &[0x08, 0x00, b'S', b'H']).await;
    assert_eq!(next(&mut radio).await, [0x08, 0x00, b'S', b'H']);

    // 250-byte frames in batches, until one is dropped for the idle connection.
    let mut number = 0u32;
    batches_until_one_dropped(&hub, &mut radio, &mut number, &mut seen_rx).await;
    // The queue, 1024 frames, and about 128 KiB in the system's buffers on the hub's
    // side (64 KiB asked, doubled by Linux: ~520 of these frames) and a little on the
    // client's; without the bound, more than 10 000.
    assert!(
        number <= 1024 + 1500,
        "{number} frames before falling behind"
    );
    hub.stop().await;
}
