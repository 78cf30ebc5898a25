//! A hub client cannot answer another client's request: every request type with a
//! frame id goes under a hub id, and an answer completes a request only if its frame
//! type answers that request's type. Over real TCP sockets, with the radio played by
//! the test.

mod common;

use common::hub_wire::*;

/// A 64-bit Transmit Request (802.15.4) under frame id `id`.
fn tx64(id: u8) -> Vec<u8> {
    let mut frame = vec![0x00, id, 0, 0x13, 0xA2, 0, 0x40, 0xB5, 0x99, 0xB9, 0x00];
    frame.extend_from_slice(b"hi");
    frame
}

/// A client sends an 802.15.4 Transmit Request (0x00) with the frame id under which
/// another client's AT command went to the radio: the hub gives it an id of its own,
/// so the radio's TX Status goes back to it, and the AT command's answer to the other.
#[tokio::test]
async fn a_client_cannot_answer_another_clients_request_with_its_own_frame() {
    let (hub, mut radio) = hub_and_radio().await;
    let mut victim = raw_client(&hub).await;
    let mut thief = raw_client(&hub).await;
    send(&mut victim, &[0x08, 0x01, b'S', b'H']).await;
    let at = next(&mut radio).await;
    assert_eq!(&at[2..], b"SH");
    let hub_id = at[1];
    // The thief guesses the hub id right.
    send(&mut thief, &tx64(hub_id)).await;
    let tx = next(&mut radio).await;
    assert_eq!(tx[0], 0x00);
    assert_ne!(
        tx[1], hub_id,
        "the thief's frame went under the victim's id"
    );
    assert_ne!(tx[1], 0);
    // The radio answers both.
    send(&mut radio, &[0x89, tx[1], 0x00]).await;
    send(
        &mut radio,
        &[0x88, hub_id, b'S', b'H', 0x00, 0x00, 0x13, 0xA2, 0x00],
    )
    .await;
    assert_eq!(next(&mut thief).await, [0x89, hub_id, 0x00]);
    assert_eq!(
        next(&mut victim).await,
        [0x88, 0x01, b'S', b'H', 0x00, 0x00, 0x13, 0xA2, 0x00]
    );
    hub.stop().await;
}

/// An answer whose frame type does not answer the request under its id (a TX Status
/// under an AT command's id) does not complete it: the request's own answer still
/// goes to its client.
#[tokio::test]
async fn an_answer_of_another_type_does_not_complete_a_request() {
    let (hub, mut radio) = hub_and_radio().await;
    let mut client = raw_client(&hub).await;
    send(&mut client, &[0x08, 0x07, b'S', b'L']).await;
    let at = next(&mut radio).await;
    let hub_id = at[1];
    send(&mut radio, &[0x89, hub_id, 0x00]).await;
    send(&mut radio, &[0x8B, hub_id, 0xFF, 0xFE, 0, 0, 0]).await;
    send(&mut radio, &[0x88, hub_id, b'S', b'L', 0x00, 0x01]).await;
    assert_eq!(
        next(&mut client).await,
        [0x88, 0x07, b'S', b'L', 0x00, 0x01]
    );
    hub.stop().await;
}

/// Every request type with a frame id that the hub knows goes under a hub id (a
/// client's raw id never reaches the radio), and its answer type comes back under the
/// client's id; a frame of a type the hub does not know goes as it is without a frame
/// id, and is refused with one.
#[tokio::test]
async fn every_known_request_type_goes_under_a_hub_id() {
    let (hub, mut radio) = hub_and_radio().await;
    let mut client = raw_client(&hub).await;
    let requests: [(&[u8], u8); 8] = [
        (&tx64(0xF0), 0x89),
        (&[0x01, 0xF0, 0x12, 0x34, 0x00, b'x'], 0x89),
        (&[0x08, 0xF0, b'N', b'I'], 0x88),
        (&[0x09, 0xF0, b'N', b'I', b'A'], 0x88),
        (
            &[
                0x10, 0xF0, 0, 0, 0, 0, 0, 0, 0xFF, 0xFF, 0xFF, 0xFE, 0, 0, b'x',
            ],
            0x8B,
        ),
        (
            &[
                0x11, 0xF0, 0, 0, 0, 0, 0, 0, 0xFF, 0xFF, 0xFF, 0xFE, 0xE8, 0xE8, 0, 0x11, 0xC1,
                0x05, 0, 0, b'x',
            ],
            0x8B,
        ),
        (
            &[
                0x17, 0xF0, 0, 0x13, 0xA2, 0, 0x40, 0xB5, 0x99, 0xB9, 0xFF, 0xFE, 0x02, b'S', b'L',
            ],
            0x97,
        ),
        (
            &[
                0x20, 0xF0, 10, 0, 0, 1, 0x26, 0x16, 0x26, 0x16, 0, 0, 0, b'x',
            ],
            0x89,
        ),
    ];
    for (request, answer_type) in requests {
        send(&mut client, request).await;
        let written = next(&mut radio).await;
        assert_eq!(written[0], request[0]);
        assert_ne!(
            written[1], 0xF0,
            "{request:02x?} went under the client's id"
        );
        assert_eq!(written[2..], request[2..]);
        send(&mut radio, &[answer_type, written[1], 0x00]).await;
        assert_eq!(next(&mut client).await, [answer_type, 0xF0, 0x00]);
    }
    // Create Source Route (0x21) without a frame id passes as it is; a frame type
    // the hub does not know, with a frame id, is refused (the next frame the radio
    // gets is the one after it).
    let source_route = [
        0x21, 0x00, 0, 0x13, 0xA2, 0, 0x40, 0xB5, 0x99, 0xB9, 0xFF, 0xFE, 0, 0,
    ];
    send(&mut client, &source_route).await;
    assert_eq!(next(&mut radio).await, source_route);
    send(&mut client, &[0x2D, 0x05, 0x02, b'x']).await;
    send(&mut client, &[0x08, 0x00, b'A', b'C']).await;
    assert_eq!(next(&mut radio).await, [0x08, 0x00, b'A', b'C']);
    assert_eq!(hub.stats().frames_refused, 1);
    hub.stop().await;
}
