//! What the virtual network's radios take from their devices in API mode 1: a stray
//! start delimiter holds the frames behind it back for the partial frame timeout at
//! most, and frames longer than any request are dropped as oversize at once.

use std::time::Duration;

use futures::{SinkExt, StreamExt};
use mcp_host::codec::{CodecItem, MAX_REQUEST_DATA, XBeeCodec};
use mcp_host::options::DEFAULT_PARTIAL_FRAME_TIMEOUT;
use mcp_host::radio::{Network, NetworkConfig, NodeOptions};
use tokio::io::{AsyncWriteExt, DuplexStream};
use tokio::time::Instant;
use tokio_util::codec::Framed;
use xbee_api::{Address64, ApiMode, AtCommandRepr, AtStatus, Frame, ModemStatus};

/// Failure guard only: every wait ends on a frame long before this.
const GUARD: Duration = Duration::from_secs(20);

type Device = Framed<DuplexStream, XBeeCodec>;

/// A network with a coordinator, and its device past its modem status.
async fn coordinator() -> (Network, Device) {
    let network = Network::new(NetworkConfig::default());
    let (_, io) = network
        .add_in_process(Address64::COORDINATOR, NodeOptions::default())
        .expect("add the coordinator");
    let mut device = Framed::new(io, XBeeCodec::new(ApiMode::Unescaped));
    match parse(&frame(&mut device).await) {
        Frame::ModemStatus(status) => assert_eq!(status.status, ModemStatus::CoordinatorStarted),
        other => panic!("{other:?}"),
    }
    (network, device)
}

async fn frame(device: &mut Device) -> Vec<u8> {
    match tokio::time::timeout(GUARD, device.next()).await {
        Ok(Some(Ok(CodecItem::Frame(frame)))) => frame.data().to_vec(),
        other => panic!("no frame in time: {other:?}"),
    }
}

fn parse(data: &[u8]) -> Frame<'_> {
    Frame::parse_bytes(data).expect("a frame")
}

async fn at(device: &mut Device, frame_id: u8, command: [u8; 2], parameter: &[u8]) {
    device
        .send(&Frame::AtCommand(AtCommandRepr {
            queued: false,
            frame_id,
            command,
            parameter,
        }))
        .await
        .expect("write a frame");
}

/// The next frame: an AT Command Response, its frame id and status.
async fn at_answer(device: &mut Device) -> (u8, AtStatus) {
    match parse(&frame(device).await) {
        Frame::AtCommandResponse(r) => (r.frame_id, r.status),
        other => panic!("expected an AT answer, got {other:?}"),
    }
}

// Paused clock: the partial frame timeout passes as soon as nothing else is to be done,
// and the guard would only after it.
#[tokio::test(start_paused = true)]
async fn a_stray_start_delimiter_holds_the_frames_behind_it_back_for_a_second_at_most() {
    let (network, mut device) = coordinator().await;
    // Noise: a start delimiter and a length of 240 bytes (less than the longest
    // request), then a whole request.
    device
        .get_mut()
        .write_all(&[0x7E, 0x00, 0xF0])
        .await
        .unwrap();
    let start = Instant::now();
    at(&mut device, 1, *b"AP", &[]).await;
    assert_eq!(at_answer(&mut device).await, (1, AtStatus::Ok));
    let waited = start.elapsed();
    assert!(
        (DEFAULT_PARTIAL_FRAME_TIMEOUT..DEFAULT_PARTIAL_FRAME_TIMEOUT * 2).contains(&waited),
        "answered after {waited:?}"
    );
    let stats = network.stats(Address64::COORDINATOR).unwrap();
    assert_eq!((stats.frames_in, stats.decode_errors), (1, 1), "{stats:?}");
    network.shutdown();
}

/// The longest request a device writes fits; one byte more is oversize, dropped as soon
/// as its length is read, and the frame after it is read at once.
#[tokio::test]
async fn a_frame_longer_than_any_request_is_oversize() {
    let (network, mut device) = coordinator().await;
    // AT command: 4 bytes before the parameter.
    let parameter = vec![b'x'; MAX_REQUEST_DATA - 4];
    at(&mut device, 1, *b"NI", &parameter).await;
    // Read (too long a node identifier, but answered).
    assert_eq!(
        at_answer(&mut device).await,
        (1, AtStatus::InvalidParameter)
    );

    let parameter = vec![b'x'; MAX_REQUEST_DATA - 3];
    at(&mut device, 2, *b"NI", &parameter).await;
    at(&mut device, 3, *b"AP", &[]).await;
    assert_eq!(at_answer(&mut device).await, (3, AtStatus::Ok));
    let stats = network.stats(Address64::COORDINATOR).unwrap();
    assert_eq!((stats.frames_in, stats.decode_errors), (2, 1), "{stats:?}");
    network.shutdown();
}
