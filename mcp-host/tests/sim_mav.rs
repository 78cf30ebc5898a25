//! One simulated MAV on an in-memory stream, under tokio's paused clock: telemetry
//! timing and the frames it writes.

use std::time::Duration;

use futures::{FutureExt, SinkExt, StreamExt};
use mcp_host::codec::{CodecItem, XBeeCodec};
use mcp_host::sim::{SimMav, run_mav};
use tokio::time::Instant;
use tokio_util::codec::Framed;
use xbee_api::{Address16, Address64, ApiMode, Frame, ReceivePacketRepr};

/// A simulated MAV on an in-memory stream of `buffer` bytes, told to send its altitude
/// telemetry: the radio's side of the stream.
async fn sending_altitude(buffer: usize) -> Framed<tokio::io::DuplexStream, XBeeCodec> {
    let (radio, mav) = tokio::io::duplex(buffer);
    tokio::spawn(run_mav(mav, SimMav::new(1_000)));
    let mut radio = Framed::new(radio, XBeeCodec::new(ApiMode::Unescaped));
    let rx = ReceivePacketRepr {
        src64: Address64::COORDINATOR,
        src16: Address16::COORDINATOR,
        options: 0x01,
        data: b"c\x01\x01\x1a",
    };
    radio.send(&rx).await.unwrap();
    radio
}

#[tokio::test(start_paused = true)]
async fn telemetry_comes_at_20_hz_as_transmit_requests_to_the_coordinator() {
    let mut radio = sending_altitude(4096).await;
    let start = Instant::now();
    let mut times = Vec::new();
    while times.len() < 40 {
        let Some(Ok(CodecItem::Frame(frame))) = radio.next().await else {
            panic!("the MAV stopped")
        };
        let Ok(Frame::TransmitRequest(tx)) = frame.parse() else {
            panic!("not a transmit request: {frame:?}")
        };
        assert_eq!(tx.frame_id, 0);
        assert_eq!(tx.dst64, Address64::COORDINATOR);
        assert_eq!(tx.dst16, Address16::UNKNOWN);
        assert_eq!(tx.options, 0x01);
        assert_eq!(tx.data.len(), 6);
        assert_eq!(&tx.data[..2], b"t\x1a");
        times.push(start.elapsed());
    }
    // Paused time: the ticks are exactly 50 ms apart.
    for pair in times.windows(2) {
        assert_eq!(pair[1] - pair[0], Duration::from_millis(50));
    }
}

#[tokio::test(start_paused = true)]
async fn telemetry_keeps_20_hz_on_a_coarse_clock() {
    let mut radio = sending_altitude(1 << 16).await;
    // Timers that fire up to a tick of 15.625 ms late, as Windows' do by default: 10 s
    // of such ticks, the MAV's frames taken as they come.
    let tick = Duration::from_micros(15_625);
    let mut telemetry = 0;
    for _ in 0..640 {
        tokio::time::advance(tick).await;
        for _ in 0..10 {
            tokio::task::yield_now().await;
        }
        while let Some(Some(Ok(CodecItem::Frame(frame)))) = radio.next().now_or_never() {
            if let Ok(Frame::TransmitRequest(tx)) = frame.parse() {
                telemetry += usize::from(tx.data.starts_with(b"t\x1a"));
            }
        }
    }
    // Late ticks do not push the next ones later: 200 in 10 s, not 160.
    assert!(
        (199..=201).contains(&telemetry),
        "{telemetry} telemetry packets in 10 s"
    );
}
