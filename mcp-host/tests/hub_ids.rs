//! No client can take the hub's frame ids from the others: each has at most
//! `ROUTES_PER_CLIENT` requests waiting for answers (`MANY_ANSWER_PER_CLIENT` answered
//! many times), its first `IDS_PER_CLIENT` on ids of its own and the others on
//! `SHARED_IDS`; a request that waits too long is answered as failed, never sent; and
//! the late answer to a client that left reaches no other. Over real TCP sockets.

mod common;

use std::time::Duration;

use common::hub_wire::*;
use futures::SinkExt;
use mcp_host::hub::{
    IDS_PER_CLIENT, MANY_ANSWER_PER_CLIENT, MAX_CLIENTS, REQUEST_WAIT, SHARED_IDS,
};
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

/// 16 clients of `hub`, each of which has sent 16 requests (`AT NI`, its number as the
/// parameter): 256 together, one more than the frame ids.
async fn clients_asking_16_each(hub: &mcp_host::hub::Hub) -> Vec<Wire> {
    let mut clients = Vec::new();
    for number in 0..16 {
        let mut client = raw_client(hub).await;
        for id in 1..=16u8 {
            client
                .feed(&RawFrame::new(&[0x08, id, b'N', b'I', number]).unwrap())
                .await
                .unwrap();
        }
        SinkExt::<&RawFrame<'_>>::flush(&mut client).await.unwrap();
        clients.push(client);
    }
    clients
}

/// Clients that send requests the radio never answers, more together than there are
/// frame ids: each gets its first `IDS_PER_CLIENT` through, and the others share
/// `SHARED_IDS`, so that a new client's request still goes out at once. The requests
/// left waiting are refused after `REQUEST_WAIT`, and answered as failed (AT `ERROR`)
/// under their clients' own ids, never sent.
#[tokio::test]
async fn clients_with_many_unanswered_requests_leave_ids_for_a_new_client() {
    let (hub, mut radio) = hub_and_radio().await;
    // 16 clients with 16 requests each: more than the 255 ids.
    let mut waiting = clients_asking_16_each(&hub).await;
    let through = 16 * IDS_PER_CLIENT + SHARED_IDS;
    let mut sent = [0; 16];
    for _ in 0..through {
        let frame = next(&mut radio).await;
        assert_eq!(&frame[2..4], b"NI");
        sent[usize::from(frame[4])] += 1;
    }
    // Every client got its own ids' worth through, some more.
    assert!(sent.iter().all(|&n| n >= IDS_PER_CLIENT), "{sent:?}");
    // Every request left waiting is answered as failed, under its own id, from the
    // hub: the radio saw none of them. They went out in order: the last ones failed.
    for (client, sent) in waiting.iter_mut().zip(sent) {
        for own_id in sent + 1..=16 {
            assert_eq!(next(client).await, [0x88, own_id as u8, b'N', b'I', 0x01]);
        }
    }
    assert_eq!(hub.stats().frames_refused, (16 * 16 - through) as u64);

    // A new client asks, while every request that went out still waits for its answer.
    let mut client = raw_client(&hub).await;
    send(&mut client, &[0x08, 0x01, b'S', b'H']).await;
    let frame = next(&mut radio).await;
    assert_eq!(&frame[2..], b"SH", "{frame:02X?}");
    send(
        &mut radio,
        &[0x88, frame[1], b'S', b'H', 0x00, 0x00, 0x13, 0xA2, 0x00],
    )
    .await;
    assert_eq!(
        next(&mut client).await,
        [0x88, 0x01, b'S', b'H', 0x00, 0x00, 0x13, 0xA2, 0x00]
    );
    hub.stop().await;
}

/// A client leaves with a request written and unanswered: its id is not given to
/// another request until the answer comes, so that the late answer reaches no one
/// (here another client's requests, answered at once, go round every id the hub has
/// more than once meanwhile).
#[tokio::test]
async fn the_late_answer_to_a_client_that_left_reaches_no_other_client() {
    let (hub, mut radio) = hub_and_radio().await;
    let mut gone = raw_client(&hub).await;
    send(&mut gone, &[0x08, 0x01, b'N', b'I']).await;
    let orphan = next(&mut radio).await[1];
    // It leaves at once (connection reset): the hub sees it gone when it reads.
    let socket = gone.into_inner();
    #[allow(deprecated)]
    socket.set_linger(Some(Duration::ZERO)).unwrap();
    drop(socket);

    let mut client = raw_client(&hub).await;
    for round in 0..2 * usize::from(u8::MAX) {
        send(&mut client, &[0x08, 0x01, b'V', b'R']).await;
        let frame = next(&mut radio).await;
        assert_eq!(&frame[2..], b"VR");
        assert_ne!(
            frame[1], orphan,
            "round {round}: the id of the unanswered request"
        );
        send(&mut radio, &[0x88, frame[1], b'V', b'R', 0x00, 0x20, 0x0B]).await;
        assert_eq!(
            next(&mut client).await,
            [0x88, 0x01, b'V', b'R', 0x00, 0x20, 0x0B]
        );
    }
    // The late answer is dropped; the client's next request gets its own.
    send(&mut radio, &[0x88, orphan, b'N', b'I', 0x00, b'G', b'S']).await;
    send(&mut client, &[0x08, 0x01, b'V', b'R']).await;
    let frame = next(&mut radio).await;
    send(&mut radio, &[0x88, frame[1], b'V', b'R', 0x00, 0x20, 0x0B]).await;
    assert_eq!(
        next(&mut client).await,
        [0x88, 0x01, b'V', b'R', 0x00, 0x20, 0x0B]
    );
    hub.stop().await;
}

/// A request that waits its turn to the radio (other frames ahead of it on a slow
/// radio) longer than `REQUEST_WAIT` is not sent: it is answered as failed, under its
/// client's own id, and the client's next frame goes. Time stands still but for
/// `tokio::time::advance`.
#[tokio::test(flavor = "current_thread")]
async fn a_request_that_waited_its_turn_too_long_is_answered_as_failed_not_sent() {
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
    // Until the hub has read the request, in real time: the clock stands still.
    let mut looks = 0;
    while hub.stats().frames_read_from_clients < 7 {
        looks += 1;
        assert!(looks < 30_000, "the hub never read the request");
        tokio::task::spawn_blocking(|| std::thread::sleep(Duration::from_millis(1)))
            .await
            .unwrap();
    }
    tokio::time::advance(REQUEST_WAIT + Duration::from_secs(1)).await;
    assert_eq!(next(&mut client).await, [0x88, 0x01, b'N', b'I', 0x01]);
    // The radio gets the client's next frame, never the request.
    send(&mut client, &[0x08, 0x00, b'V', b'R']).await;
    assert_eq!(next(&mut radio).await, [0x08, 0x00, b'V', b'R']);
    assert_eq!(hub.stats().frames_refused, 1);
    release.send(()).unwrap();
    clock_held.await.unwrap().unwrap();
    hub.stop().await;
}

/// A hub that could read nothing for longer than `REQUEST_WAIT` (its process stopped, a
/// machine suspended) sends none of the requests that came meanwhile: their clients may
/// have given up on them and left (a `send` that timed out), and newer commands of
/// others may have gone since. They are answered as failed, as a request that waited
/// its turn too long. In real time: the test holds the hub's runtime (its one thread)
/// for the stall, while a client connects and writes its request.
#[tokio::test(flavor = "current_thread")]
async fn a_request_that_came_while_the_hub_stalled_too_long_is_not_sent() {
    let (hub, mut radio) = hub_and_radio().await;
    let addr = hub.local_addr();
    let request = [0x08, 0x01, b'N', b'I'];
    let client = std::thread::spawn(move || {
        let mut socket = std::net::TcpStream::connect(addr).unwrap();
        let sum = request.iter().fold(0u8, |sum, b| sum.wrapping_add(*b));
        let wire = [&[0x7E, 0x00, 0x04][..], &request, &[0xFF - sum]].concat();
        std::io::Write::write_all(&mut socket, &wire).unwrap();
        socket
    });
    // The stall: nothing of the hub runs.
    std::thread::sleep(REQUEST_WAIT + Duration::from_secs(1));
    let socket = client.join().unwrap();
    socket.set_nonblocking(true).unwrap();
    let mut client = tokio_util::codec::Framed::new(
        tokio::net::TcpStream::from_std(socket).unwrap(),
        mcp_host::codec::XBeeCodec::new(ApiMode::Unescaped),
    );
    assert_eq!(next(&mut client).await, [0x88, 0x01, b'N', b'I', 0x01]);
    // The radio gets the client's next frame, never the request.
    send(&mut client, &[0x08, 0x00, b'V', b'R']).await;
    assert_eq!(next(&mut radio).await, [0x08, 0x00, b'V', b'R']);
    assert_eq!(hub.stats().frames_refused, 1);
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

/// The ids held for the hub's own late answers count among the 255: with every other
/// id waiting for an answer (`MAX_CLIENTS` clients, each with its own ids and a share
/// of the others), requests wait for an id rather than being refused.
#[tokio::test]
async fn with_ids_held_for_late_answers_requests_wait_rather_than_being_refused() {
    let (hub, mut radio, held) = hub_whose_radio_did_not_answer_ap().await;
    // 4 requests from each of the 64 clients: 256, more than the 253 ids left.
    let _clients = flood(&hub, MAX_CLIENTS, 4, *b"SL").await;
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

/// Clients that come, ask for node discoveries (answered many times: their ids are
/// kept for the answer window) and go, one after another, leave orphans that take only
/// shared ids: each new client's first requests still go at once, however many came
/// before it.
#[tokio::test]
async fn clients_that_come_and_go_leave_each_newcomer_its_own_ids() {
    let (hub, mut radio) = hub_and_radio().await;
    for round in 0..2 * MAX_CLIENTS {
        let mut client = raw_client(&hub).await;
        for own in 1..=IDS_PER_CLIENT as u8 {
            send(&mut client, &[0x08, own, b'N', b'D']).await;
            let asked = tokio::time::timeout(Duration::from_secs(4), next(&mut radio))
                .await
                .unwrap_or_else(|_| panic!("round {round}: held; {:?}", hub.stats()));
            assert_eq!(&asked[2..], b"ND");
            send(&mut radio, &[0x88, asked[1], b'N', b'D', 0x00, 0xFF, 0xFE]).await;
            assert_eq!(
                next(&mut client).await,
                [0x88, own, b'N', b'D', 0x00, 0xFF, 0xFE]
            );
        }
        // Gone (connection reset): the hub sees it when it reads.
        let socket = client.into_inner();
        #[allow(deprecated)]
        socket.set_linger(Some(Duration::ZERO)).unwrap();
        drop(socket);
    }
    assert_eq!(hub.stats().frames_refused, 0);
    hub.stop().await;
}
