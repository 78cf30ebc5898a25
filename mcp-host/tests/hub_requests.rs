//! What a hub takes from its clients: requests cut short take no frame id, shared ids
//! come free in order, requests answered many times leave ids for the others, frames longer than
//! any request are refused, and a stray start delimiter (API mode 1) holds nothing back
//! for long. Over real TCP sockets, with the radio played by the test.

mod common;

use std::time::Duration;

use common::hub_wire::*;
use futures::SinkExt;
use mcp_host::codec::{MAX_REQUEST_DATA, XBeeCodec};
use mcp_host::hub::{
    Hub, HubStats, IDS_PER_CLIENT, MANY_ANSWER_PER_CLIENT, ROUTES_PER_CLIENT, SHARED_IDS,
};
use mcp_host::options::DEFAULT_PARTIAL_FRAME_TIMEOUT;
use mcp_host::{Link, LinkOptions};
use tokio::io::AsyncWriteExt;
use tokio::net::TcpListener;
use tokio_util::codec::Framed;
use xbee_api::{ApiMode, RawFrame};

/// Failure guard only: every wait ends on a frame long before this.
const GUARD: Duration = Duration::from_secs(20);

/// Waits until the hub's counters satisfy `done`, looking every 5 ms (they change in
/// its tasks, which signal nothing); fails after [`GUARD`].
async fn until(hub: &Hub, done: impl Fn(&HubStats) -> bool) {
    let deadline = tokio::time::Instant::now() + GUARD;
    while !done(&hub.stats()) {
        assert!(tokio::time::Instant::now() < deadline, "{:?}", hub.stats());
        tokio::time::sleep(Duration::from_millis(5)).await;
    }
}

/// The radio's next frame, which must come within `within`.
async fn next_within(radio: &mut Wire, within: Duration, hub: &Hub) -> Vec<u8> {
    tokio::time::timeout(within, next(radio))
        .await
        .unwrap_or_else(|_| panic!("nothing reached the radio: {:?}", hub.stats()))
}

/// Requests of a type the hub routes, with a frame id, but cut short of the fixed fields
/// of their type (a Transmit Request ending after its frame id, `10 01`): no radio
/// answers them, so they are refused rather than given an id each for the answer
/// window. More of them than a client may have waiting leave its next request free to
/// go at once.
#[tokio::test]
async fn requests_cut_short_take_no_frame_id() {
    let (hub, mut radio) = hub_and_radio().await;
    let mut client = raw_client(&hub).await;
    let cut_short: [&[u8]; 8] = [
        &[0x10, 0x01],
        &[0x11, 0x01, 0, 0, 0, 0, 0, 0, 0xFF, 0xFF],
        &[0x08, 0x01, b'N'],
        &[0x17, 0x01, 0, 0x13, 0xA2, 0],
        &[0x00, 0x01, 0, 0x13, 0xA2, 0, 0x40, 0xB5, 0x99, 0xB9],
        &[0x01, 0x01, 0x12, 0x34],
        &[0x20, 0x01, 10, 0, 0, 1],
        &[
            0x24, 0x01, 0, 0x13, 0xA2, 0, 0x40, 0xB5, 0x99, 0xB9, 0xFF, 0xFE,
        ],
    ];
    let mut refused = 0;
    for _ in 0..ROUTES_PER_CLIENT {
        for data in cut_short {
            client.feed(&RawFrame::new(data).unwrap()).await.unwrap();
            refused += 1;
        }
    }
    client
        .feed(&RawFrame::new(&[0x08, 0x07, b'S', b'H']).unwrap())
        .await
        .unwrap();
    SinkExt::<&RawFrame<'_>>::flush(&mut client).await.unwrap();

    // The first frame the radio gets is the whole request, at once.
    let at = next_within(&mut radio, Duration::from_secs(5), &hub).await;
    assert_eq!((at[0], &at[2..]), (0x08, &b"SH"[..]), "{at:02X?}");
    send(&mut radio, &[0x88, at[1], b'S', b'H', 0x00, 0x00, 0x13]).await;
    assert_eq!(
        next(&mut client).await,
        [0x88, 0x07, b'S', b'H', 0x00, 0x00, 0x13]
    );
    let stats = hub.stats();
    assert_eq!(stats.frames_refused, refused, "{stats:?}");
    assert_eq!(stats.requests_held, 0, "{stats:?}");
    // Every frame read was refused or written: the refused ones and the request.
    assert_eq!(stats.frames_read_from_clients, refused + 1, "{stats:?}");
    assert_eq!(stats.frames_from_clients, 1, "{stats:?}");
    hub.stop().await;
}

/// Frames a radio sends (a recording of what one said, played onto the hub) are refused
/// whatever their second byte, and counted: a Receive Packet from 0013A2... has a 0 there,
/// which read as "frame id 0" let it through to a radio that drops it, uncounted.
#[tokio::test]
async fn frames_a_radio_sends_are_refused_and_counted() {
    let (hub, mut radio) = hub_and_radio().await;
    let mut client = raw_client(&hub).await;
    let from_radio: [&[u8]; 4] = [
        &[
            0x90, 0x00, 0x13, 0xA2, 0x00, 0x40, 0xB5, 0x99, 0xB9, 0x7B, 0x1F, 0x01, b'r', 0x02,
            0x04,
        ],
        &[0x8A, 0x06],
        &[0x8B, 0x01, 0xFF, 0xFE, 0, 0, 0],
        &[0x88, 0x00, b'A', b'P', 0x00, 0x01],
    ];
    for data in from_radio {
        send(&mut client, data).await;
    }
    send(&mut client, &[0x08, 0x00, b'A', b'C']).await;
    // The first frame the radio gets is the request after them.
    assert_eq!(next(&mut radio).await, [0x08, 0x00, b'A', b'C']);
    let stats = hub.stats();
    // Counted as they were read, before the request after them.
    assert_eq!(stats.frames_refused, 4, "{stats:?}");
    hub.stop().await;
}

/// With the shared frame ids all taken by requests the radio has not answered yet,
/// requests beyond their clients' own ids wait for one in the order they came, whoever
/// sent them, while newcomers' first requests, on their own ids, go at once. Each
/// request says whose it is: `AT NI` with its client's number and its own id as the
/// parameter.
#[tokio::test(flavor = "multi_thread")]
async fn requests_beyond_their_own_ids_get_the_shared_ids_that_come_free_in_order() {
    let (hub, mut radio) = hub_and_radio().await;
    let ask = async |client: &mut Wire, number: u8, own: std::ops::RangeInclusive<u8>| {
        for own in own {
            let frame = [0x08, own, b'N', b'I', number, own];
            client.feed(&RawFrame::new(&frame).unwrap()).await.unwrap();
        }
        SinkExt::<&RawFrame<'_>>::flush(client).await.unwrap();
    };
    // Hub ids of the requests on shared ids (a client's third on), as the radio got them.
    let mut shared = Vec::new();
    let mut clients = Vec::new();
    let went = async |radio: &mut Wire, n: usize, shared: &mut Vec<u8>| {
        for _ in 0..n {
            let frame = next_within(radio, Duration::from_secs(5), &hub).await;
            if usize::from(frame[5]) > IDS_PER_CLIENT {
                shared.push(frame[1]);
            }
        }
    };
    // Nine clients with 16 requests each, and one with 3: every shared id taken.
    for number in 0..10 {
        let mut client = raw_client(&hub).await;
        let last = if number < 9 { 16 } else { 3 };
        ask(&mut client, number, 1..=last).await;
        went(&mut radio, usize::from(last), &mut shared).await;
        clients.push(client);
    }
    assert_eq!(shared.len(), SHARED_IDS);
    // The tenth client's fourth request waits; then two newcomers' first two go at once
    // and their third waits, in that order.
    let held = hub.stats().requests_held;
    ask(&mut clients[9], 9, 4..=4).await;
    until(&hub, |stats| stats.requests_held > held).await;
    for number in [10, 11] {
        let mut client = raw_client(&hub).await;
        let held = hub.stats().requests_held;
        ask(&mut client, number, 1..=3).await;
        went(&mut radio, 2, &mut shared).await;
        until(&hub, |stats| stats.requests_held > held).await;
        clients.push(client);
    }
    assert_eq!(shared.len(), SHARED_IDS);
    // The radio answers requests on shared ids one at a time: each id that comes free
    // goes to the next request in line.
    for (&answered, waiting) in shared.iter().zip([[9, 4], [10, 3], [11, 3]]) {
        send(&mut radio, &[0x88, answered, b'N', b'I', 0x00]).await;
        let frame = next_within(&mut radio, Duration::from_secs(5), &hub).await;
        assert_eq!(frame[4..], waiting, "{frame:02X?}");
    }
    assert_eq!(hub.stats().frames_refused, 0);
    hub.stop().await;
}

/// Requests answered many times (node discovery here) keep their ids for the answer
/// window: a client has `MANY_ANSWER_PER_CLIENT` of them at most, so that clients
/// flooding the hub with them leave ids for a client that connects after them.
#[tokio::test(flavor = "multi_thread")]
async fn requests_answered_many_times_leave_ids_for_a_client_that_comes_later() {
    let (hub, mut radio) = hub_and_radio().await;
    let _flood = flood(&hub, 16, 16, *b"ND").await;
    for _ in 0..16 * MANY_ANSWER_PER_CLIENT {
        let frame = next(&mut radio).await;
        assert_eq!(&frame[2..], b"ND");
    }
    // The rest wait: none is written while the window of those written lasts.
    until(&hub, |stats| stats.requests_held >= 16).await;

    let mut late = raw_client(&hub).await;
    send(&mut late, &[0x08, 0x01, b'S', b'H']).await;
    let at = next_within(&mut radio, Duration::from_secs(5), &hub).await;
    assert_eq!(&at[2..], b"SH", "{at:02X?}; {:?}", hub.stats());
    hub.stop().await;
}

/// A hub that takes frames up to `MAX_REQUEST_DATA` (`LinkOptions::max_frame_len`)
/// from its clients, as from its radio: the longest request a client sends (an Explicit
/// Addressing Command with a 255-byte payload) goes to the radio; a frame one byte
/// longer is refused as oversize, and the frame after it goes.
#[tokio::test]
async fn a_frame_longer_than_the_hub_takes_is_refused() {
    let listener = TcpListener::bind("127.0.0.1:0").await.unwrap();
    let link: Link = format!("tcp:{}", listener.local_addr().unwrap())
        .parse()
        .unwrap();
    let options = LinkOptions {
        max_frame_len: MAX_REQUEST_DATA,
        ..LinkOptions::default()
    };
    let (hub, socket) = tokio::join!(
        Hub::start(&link, options, "127.0.0.1:0"),
        radio_accepted(&listener)
    );
    let hub = hub.unwrap();
    let mut radio = Framed::new(socket, XBeeCodec::new(ApiMode::Unescaped));
    let mut client = raw_client(&hub).await;
    let mut longest = vec![
        0x11, 0x00, 0, 0x13, 0xA2, 0, 0x40, 0xB5, 0x99, 0xB9, 0xFF, 0xFE, 0xE8, 0xE8, 0, 0x11,
        0xC1, 0x05, 0, 0,
    ];
    longest.resize(MAX_REQUEST_DATA, 0x55);
    assert_eq!(longest.len(), 20 + 255);
    send(&mut client, &longest).await;
    assert_eq!(next(&mut radio).await, longest);

    let mut too_long = longest.clone();
    too_long.push(0x55);
    send(&mut client, &too_long).await;
    send(&mut client, &[0x08, 0x00, b'A', b'C']).await;
    assert_eq!(next(&mut radio).await, [0x08, 0x00, b'A', b'C']);
    assert_eq!(hub.stats().frames_refused, 1, "{:?}", hub.stats());
    hub.stop().await;
}

/// API mode 1: a stray start delimiter with a length (`7E 00 F0`, noise) before a
/// client's request is given up once the client's bytes stop for the partial frame
/// timeout, and the request behind it goes to the radio then, not after 240 more bytes.
#[tokio::test]
async fn a_stray_start_delimiter_holds_a_request_back_for_the_partial_frame_timeout_at_most() {
    let (hub, mut radio) = hub_and_radio().await;
    let mut client = raw_client(&hub).await;
    client
        .get_mut()
        .write_all(&[0x7E, 0x00, 0xF0])
        .await
        .unwrap();
    let sent = tokio::time::Instant::now();
    send(&mut client, &[0x08, 0x05, b'S', b'H']).await;
    let within = DEFAULT_PARTIAL_FRAME_TIMEOUT + Duration::from_secs(4);
    let at = next_within(&mut radio, within, &hub).await;
    assert_eq!((at[0], &at[2..]), (0x08, &b"SH"[..]), "{at:02X?}");
    // Not before the timeout: the stray candidate could still have been a frame.
    assert!(sent.elapsed() >= DEFAULT_PARTIAL_FRAME_TIMEOUT - Duration::from_millis(50));
    send(&mut radio, &[0x88, at[1], b'S', b'H', 0x00]).await;
    assert_eq!(next(&mut client).await, [0x88, 0x05, b'S', b'H', 0x00]);
    // The candidate given up (refused) and the request found behind it (written) were
    // both read.
    let stats = hub.stats();
    assert_eq!(
        (stats.frames_refused, stats.frames_from_clients),
        (1, 1),
        "{stats:?}"
    );
    assert_eq!(stats.frames_read_from_clients, 2, "{stats:?}");
    hub.stop().await;
}

/// An answer goes back only if it answers the request under its id: of the matching
/// type and, for an AT command, echoing the same command (in either case). A remote
/// radio's find neighbors (`FN`) is answered many times, each answer on its own, all to
/// the client that asked.
#[tokio::test]
async fn answers_echo_their_requests_command_and_a_remote_fn_gets_all_its_answers() {
    let (hub, mut radio) = hub_and_radio().await;
    let mut client = raw_client(&hub).await;
    send(&mut client, &[0x08, 0x01, b'n', b'i']).await;
    let asked = next(&mut radio).await;
    // A late answer to another command under the id, then the answer.
    send(&mut radio, &[0x88, asked[1], b'V', b'R', 0x00, 0x20, 0x0B]).await;
    send(&mut radio, &[0x88, asked[1], b'N', b'I', 0x00, b'G', b'S']).await;
    assert_eq!(
        next(&mut client).await,
        [0x88, 0x01, b'N', b'I', 0x00, b'G', b'S']
    );

    let remote = [
        0x17, 0x02, 0, 0x13, 0xA2, 0, 0x40, 0xB5, 0x99, 0xB9, 0xFF, 0xFE, 0x02, b'F', b'N',
    ];
    send(&mut client, &remote).await;
    let asked = next(&mut radio).await;
    assert_eq!(asked[2..], remote[2..]);
    for neighbor in [0xA1, 0xA2] {
        let mut answer = vec![0x97, asked[1]];
        answer.extend_from_slice(&remote[2..12]);
        answer.extend_from_slice(&[b'F', b'N', 0x00, neighbor]);
        send(&mut radio, &answer).await;
        let got = next(&mut client).await;
        assert_eq!(
            (got[1], &got[12..]),
            (0x02, &[b'F', b'N', 0x00, neighbor][..])
        );
    }
    hub.stop().await;
}

/// A client that keeps the hub's writes to the radio a little behind (frames without
/// frame id sent slightly faster than the radio's UART takes them) still gets its
/// requests through: their wait counts from when each could be read, not from when the
/// client's backlog began.
#[tokio::test(flavor = "multi_thread")]
async fn a_client_a_little_ahead_of_the_radio_gets_its_requests_through() {
    let (hub, mut radio) = hub_and_radio().await;
    // The radio answers every AT command at once.
    let answering = tokio::spawn(async move {
        loop {
            let frame = next(&mut radio).await;
            if frame[0] == 0x08 && frame[1] != 0 {
                send(
                    &mut radio,
                    &[0x88, frame[1], frame[2], frame[3], 0x00, 0x20],
                )
                .await;
            }
        }
    });
    let socket = tokio::net::TcpStream::connect(hub.local_addr())
        .await
        .unwrap();
    let (from_hub, mut to_hub) = socket.into_split();
    let mut from_hub =
        tokio_util::codec::FramedRead::new(from_hub, XBeeCodec::new(ApiMode::Unescaped));
    let frame = |data: &[u8]| {
        let mut bytes = vec![0u8; data.len() + 4];
        let n = xbee_api::EncodeFrame::encode(
            &RawFrame::new(data).unwrap(),
            ApiMode::Unescaped,
            &mut bytes,
        )
        .unwrap();
        bytes.truncate(n);
        bytes
    };
    // 100-byte frames every 8 ms: 12.5 kB/s, against the 11.5 kB/s of 115200 baud; an
    // AT command every second, for 7 s (past REQUEST_WAIT).
    let writing = tokio::spawn(async move {
        let mut filler = vec![0x10, 0x00];
        filler.resize(100, 0x55);
        let mut tick = tokio::time::interval(Duration::from_millis(8));
        for n in 1..=875u32 {
            tick.tick().await;
            to_hub.write_all(&frame(&filler)).await.unwrap();
            if n % 125 == 0 {
                let own = (n / 125) as u8;
                to_hub
                    .write_all(&frame(&[0x08, own, b'V', b'R']))
                    .await
                    .unwrap();
            }
        }
    });
    for own in 1..=7u8 {
        let answer = loop {
            let item = tokio::time::timeout(GUARD, futures::StreamExt::next(&mut from_hub))
                .await
                .expect("an answer")
                .expect("the connection stays")
                .unwrap();
            if let mcp_host::codec::CodecItem::Frame(frame) = item {
                break frame.data().to_vec();
            }
        };
        assert_eq!(
            answer,
            [0x88, own, b'V', b'R', 0x00, 0x20],
            "{:?}",
            hub.stats()
        );
    }
    writing.await.unwrap();
    answering.abort();
    assert_eq!(hub.stats().frames_refused, 0);
    hub.stop().await;
}
