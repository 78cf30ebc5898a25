//! No client can take the hub's frame ids from the others: each has at most
//! `ROUTES_PER_CLIENT` requests waiting for answers (`MANY_ANSWER_PER_CLIENT` answered
//! many times), and a client's requests give their ids back when it leaves. Over real
//! TCP sockets.

mod common;

use std::time::Duration;

use common::hub_wire::*;
use futures::{SinkExt, StreamExt};
use mcp_host::codec::CodecItem;
use mcp_host::hub::{ANSWER_WINDOW, MANY_ANSWER_PER_CLIENT, ROUTES_PER_CLIENT};
use mcp_host::{Link, LinkOptions, SendOptions};
use xbee_api::{Address64, ApiMode, RawFrame};

/// Failure guard only: every wait ends on a frame long before this.
const GUARD: Duration = Duration::from_secs(20);
const MAV: Address64 = Address64(0x0013_A200_40B5_99B9);

/// One client sends 255 node discoveries (`AT ND`), each answered at once by the radio.
/// Their answers could keep coming for the hub's answer window, so each keeps its frame
/// id meanwhile: the client gets `MANY_ANSWER_PER_CLIENT` of them through, the rest wait, and
/// a ground station on the same hub still gets its AT commands and transmissions
/// through at once.
#[tokio::test(flavor = "multi_thread")]
async fn a_client_flooding_the_hub_with_discoveries_leaves_frame_ids_for_the_others() {
    let (sim, hub) = sim_and_hub(ApiMode::Unescaped).await;
    let honest_link: Link = format!("tcp:{}", hub.local_addr()).parse().unwrap();
    let (_stream, honest) = mcp_host::connect(&honest_link, LinkOptions::default())
        .await
        .unwrap();

    let mut flood = flood(&hub, 1, 255, *b"ND").await.remove(0);
    // Until the flood has taken all it can: every discovery answered, or the hub holds
    // the client's next ones back.
    let mut answers = 0;
    while answers < 255 && (answers < MANY_ANSWER_PER_CLIENT || hub.stats().requests_held == 0) {
        tokio::select! {
            frame = next(&mut flood) => if frame[0] == 0x88 {
                answers += 1;
            },
            () = tokio::task::yield_now(), if answers >= MANY_ANSWER_PER_CLIENT => {}
        }
    }

    let quick = Some(Duration::from_secs(2));
    let at = honest.at(*b"SH", &[], quick).await;
    assert!(at.is_ok(), "{at:?}; {:?}", hub.stats());
    let options = SendOptions {
        timeout: quick,
        ..SendOptions::default()
    };
    let sent = honest
        .send_with(MAV, &mcp_core::Command::landing(true), options)
        .await;
    assert!(sent.is_ok(), "{sent:?}; {:?}", hub.stats());
    assert_eq!(hub.stats().frames_refused, 0);
    // The flooding client got through what the hub lets one client have at once.
    assert_eq!(answers, MANY_ANSWER_PER_CLIENT);
    hub.stop().await;
    sim.stop().await;
}

/// 16 clients of `hub`, each of which has sent 16 requests (`AT SL`): 256 together, one
/// more than the frame ids.
async fn clients_asking_16_each(hub: &mcp_host::hub::Hub) -> Vec<Wire> {
    let mut clients = Vec::new();
    for _ in 0..16 {
        let mut client = raw_client(hub).await;
        for id in 1..=16u8 {
            client
                .feed(&RawFrame::new(&[0x08, id, b'S', b'L']).unwrap())
                .await
                .unwrap();
        }
        SinkExt::<&RawFrame<'_>>::flush(&mut client).await.unwrap();
        clients.push(client);
    }
    clients
}

/// Clients that send requests the radio never answers, enough together for every frame
/// id, and go away: their requests' ids are free again once the hub has seen them go,
/// long before the answer window ends.
#[tokio::test]
async fn the_ids_of_a_client_that_left_are_free_again() {
    let (hub, mut radio) = hub_and_radio().await;

    // 16 clients with 16 requests each: more than the 255 ids.
    let gone = clients_asking_16_each(&hub).await;
    // The radio got all it will get of them (none answered), then they leave.
    let mut written = 0;
    while written < usize::from(u8::MAX) {
        let frame = next(&mut radio).await;
        assert_eq!(&frame[2..], b"SL");
        written += 1;
    }
    drop(gone);

    // Another client asks; the hub sees the others gone when it writes to them (the
    // radio's modem status frames).
    let mut client = raw_client(&hub).await;
    send(&mut client, &[0x08, 0x01, b'S', b'H']).await;
    let deadline = tokio::time::Instant::now() + GUARD;
    let hub_id = loop {
        assert!(
            tokio::time::Instant::now() < deadline,
            "the request never reached the radio: {:?}",
            hub.stats()
        );
        send(&mut radio, &[0x8A, 0x00]).await;
        tokio::select! {
            frame = next(&mut radio) => {
                if &frame[2..] == b"SH" {
                    break frame[1];
                }
            }
            frame = next(&mut client) => assert_eq!(frame, [0x8A, 0x00]),
        }
    };
    send(
        &mut radio,
        &[0x88, hub_id, b'S', b'H', 0x00, 0x00, 0x13, 0xA2, 0x00],
    )
    .await;
    loop {
        let frame = next(&mut client).await;
        if frame[0] == 0x88 {
            assert_eq!(
                frame,
                [0x88, 0x01, b'S', b'H', 0x00, 0x00, 0x13, 0xA2, 0x00]
            );
            break;
        }
    }
    hub.stop().await;
}

/// While one client keeps the radio busy (transmissions nonstop), clients that each
/// take `ROUTES_PER_CLIENT` ids and leave (connection reset) with their requests
/// unanswered give their ids back at once: after more than 255 ids so taken, a new
/// client's requests still all reach the radio.
#[tokio::test(flavor = "multi_thread")]
async fn the_ids_of_clients_that_left_are_free_again_while_another_client_keeps_the_radio_busy() {
    let (hub, mut radio) = hub_and_radio().await;
    let (requests, mut written) = tokio::sync::mpsc::unbounded_channel();
    tokio::spawn(async move {
        while let Some(Ok(item)) = radio.next().await {
            if let CodecItem::Frame(frame) = item {
                if frame.data()[0] == 0x08 {
                    let _ = requests.send(frame.data().to_vec());
                }
            }
        }
    });
    let mut flood = raw_client(&hub).await;
    let flooding = tokio::spawn(async move {
        let mut data = vec![0x10, 0x00];
        data.resize(200, 0x55);
        while flood.send(&RawFrame::new(&data).unwrap()).await.is_ok() {}
    });
    let mut written_one = async || {
        tokio::time::timeout(GUARD, written.recv())
            .await
            .unwrap_or_else(|_| panic!("a request held: {:?}", hub.stats()))
            .expect("the radio stays")
    };
    for _ in 0..usize::from(u8::MAX) / ROUTES_PER_CLIENT {
        let mut client = raw_client(&hub).await;
        for id in 1..=ROUTES_PER_CLIENT as u8 {
            send(&mut client, &[0x08, id, b'S', b'H']).await;
        }
        for _ in 0..ROUTES_PER_CLIENT {
            written_one().await;
        }
        let socket = client.into_inner();
        #[allow(deprecated)]
        socket.set_linger(Some(Duration::ZERO)).unwrap();
        drop(socket);
    }
    let mut client = raw_client(&hub).await;
    for id in 1..=ROUTES_PER_CLIENT as u8 {
        send(&mut client, &[0x08, id, b'S', b'H']).await;
    }
    for _ in 0..ROUTES_PER_CLIENT {
        written_one().await;
    }
    flooding.abort();
    hub.stop().await;
}

/// A request that waits its turn to the radio longer than the answer window (other
/// frames ahead of it on a slow radio) still gets its answer: the window starts when
/// the hub writes the request. Time stands still but for `tokio::time::advance`.
#[tokio::test(flavor = "current_thread")]
async fn a_request_that_waited_its_turn_longer_than_the_answer_window_gets_its_answer() {
    let (hub, mut radio) = hub_and_radio().await;
    let mut client = raw_client(&hub).await;
    tokio::time::pause();
    // A blocking task running keeps the paused clock from moving by itself.
    let (release, held) = std::sync::mpsc::channel::<()>();
    let clock_held = tokio::task::spawn_blocking(move || held.recv());
    // Transmissions worth more of the radio's time than the hub writes ahead, then a
    // request.
    let mut filler = vec![0x10, 0x00];
    filler.resize(500, 0x55);
    for _ in 0..6 {
        send(&mut client, &filler).await;
    }
    send(&mut client, &[0x08, 0x01, b'N', b'I']).await;
    for _ in 0..6 {
        assert_eq!(next(&mut radio).await, filler);
    }
    // Until the hub has read the request (real time; the clock stands still).
    tokio::task::spawn_blocking(|| std::thread::sleep(Duration::from_millis(200)))
        .await
        .unwrap();
    tokio::time::advance(ANSWER_WINDOW + Duration::from_secs(5)).await;
    let request = next(&mut radio).await;
    assert_eq!(request[0], 0x08);
    send(&mut radio, &[0x88, request[1], b'N', b'I', 0x00]).await;
    // A frame for every client after the answer: the answer comes first.
    send(&mut radio, &[0x8A, 0x00]).await;
    assert_eq!(next(&mut client).await, [0x88, 0x01, b'N', b'I', 0x00]);
    release.send(()).unwrap();
    clock_held.await.unwrap().unwrap();
    hub.stop().await;
}

/// A hub on a radio that left both of the hub's `AT AP` unanswered, with the ids they
/// went out under.
async fn hub_whose_radio_did_not_answer_ap() -> (mcp_host::hub::Hub, Wire, [u8; 2]) {
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let radio_link: Link = format!("tcp:{}", listener.local_addr().unwrap())
        .parse()
        .unwrap();
    let (hub, (radio, ap1, ap2)) = tokio::join!(
        mcp_host::hub::Hub::start(&radio_link, LinkOptions::default(), "127.0.0.1:0"),
        async {
            let (socket, _) = listener.accept().await.unwrap();
            let mut wire = tokio_util::codec::Framed::new(
                socket,
                mcp_host::codec::XBeeCodec::new(ApiMode::Unescaped),
            );
            // Asked twice, neither answered in time.
            let first = next(&mut wire).await;
            let second = next(&mut wire).await;
            (wire, first[1], second[1])
        }
    );
    (hub.unwrap(), radio, [ap1, ap2])
}

/// The hub asks the radio `AT AP` under its link's own frame ids before it takes
/// clients. A radio that answers late (behind a bridge busy with another connection)
/// answers after a client has asked: the late answer is dropped, and the client's
/// request, never under one of those ids, gets its own answer.
#[tokio::test]
async fn a_late_answer_to_the_hubs_own_at_ap_goes_to_no_client() {
    let (hub, mut radio, [ap1, ap2]) = hub_whose_radio_did_not_answer_ap().await;
    let mut client = raw_client(&hub).await;
    send(&mut client, &[0x08, 0x07, b'N', b'I']).await;
    let ni = next(&mut radio).await;
    assert!(
        ![ap1, ap2].contains(&ni[1]),
        "{ni:?} under an id of the AT AP"
    );
    // The radio catches up: both AT AP answered, late, then the client's NI.
    send(&mut radio, &[0x88, ap1, b'A', b'P', 0x00, 0x01]).await;
    send(&mut radio, &[0x88, ap2, b'A', b'P', 0x00, 0x01]).await;
    send(&mut radio, &[0x88, ni[1], b'N', b'I', 0x00, b'G', b'S']).await;
    let got = tokio::time::timeout(GUARD, next(&mut client))
        .await
        .unwrap();
    assert_eq!(got, [0x88, 0x07, b'N', b'I', 0x00, b'G', b'S']);
    hub.stop().await;
}

/// The ids held for the hub's own late answers count among the 255: with the other 253
/// waiting for answers, requests wait for an id rather than being refused.
#[tokio::test]
async fn with_ids_held_for_late_answers_requests_wait_rather_than_being_refused() {
    let (hub, mut radio, held) = hub_whose_radio_did_not_answer_ap().await;
    // 16 clients with 16 requests each: 256, more than the 253 ids left.
    let _clients = clients_asking_16_each(&hub).await;
    // 253 go out, under none of the held ids; then, answered, they let the rest go.
    let mut ids = Vec::new();
    for _ in 0..253 {
        let frame = tokio::time::timeout(GUARD, next(&mut radio)).await.unwrap();
        assert!(!held.contains(&frame[1]), "{frame:02X?} under a held id");
        ids.push(frame[1]);
    }
    for id in ids {
        send(&mut radio, &[0x88, id, b'S', b'L', 0x00, 1, 2, 3, 4]).await;
    }
    for _ in 0..3 {
        let frame = tokio::time::timeout(GUARD, next(&mut radio))
            .await
            .expect("a request was refused rather than held");
        assert_eq!(&frame[2..], b"SL");
    }
    assert_eq!(hub.stats().frames_refused, 0);
    hub.stop().await;
}
