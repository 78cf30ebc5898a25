//! An emulated radio that starts in transparent mode (`AP` = 0), as XBee modules leave the
//! factory: its device gets received payloads as bytes, enters AT command mode with
//! `+++` between guard times, reads and sets parameters there, and switches to API
//! frames once it sets `AP` and leaves with `ATCN`.

use std::time::Duration;

use futures::{SinkExt, StreamExt};
use mcp_host::codec::{CodecItem, XBeeCodec};
use mcp_host::radio::{Faults, Network, NetworkConfig, NodeOptions};
use tokio::io::{AsyncReadExt, AsyncWriteExt, DuplexStream};
use tokio_util::codec::Framed;
use xbee_api::{Address16, Address64, ApiMode, AtCommandRepr, Frame, TransmitRequestRepr};

const MAV: Address64 = Address64(0x0013_A200_40B5_99B9);
/// Digi's default guard time (`GT`).
const GT: Duration = Duration::from_secs(1);

/// The next bytes the device reads; none within a minute of (paused) time is `None`.
async fn read(device: &mut DuplexStream) -> Option<Vec<u8>> {
    let mut buf = [0u8; 256];
    match tokio::time::timeout(Duration::from_secs(60), device.read(&mut buf)).await {
        Ok(Ok(n)) if n > 0 => Some(buf[..n].to_vec()),
        Ok(_) => panic!("the radio closed the link"),
        Err(_) => None,
    }
}

/// Reads until a carriage return: one answer line of command mode.
async fn line(device: &mut DuplexStream) -> String {
    let mut got = Vec::new();
    while !got.ends_with(b"\r") {
        got.extend(read(device).await.expect("an answer line"));
    }
    String::from_utf8(got).unwrap()
}

/// Sends a command line and reads its answer.
async fn command(device: &mut DuplexStream, text: &str) -> String {
    device
        .write_all(format!("{text}\r").as_bytes())
        .await
        .unwrap();
    line(device).await
}

/// A transmit request from the MAV's device to the coordinator.
async fn send_from_mav(mav: &mut Framed<DuplexStream, XBeeCodec>, data: &[u8]) {
    mav.send(&Frame::TransmitRequest(TransmitRequestRepr {
        frame_id: 0,
        dst64: Address64::COORDINATOR,
        dst16: Address16::UNKNOWN,
        radius: 0,
        options: 0,
        data,
    }))
    .await
    .unwrap();
}

/// The next frame the device reads.
async fn next_frame(device: &mut Framed<DuplexStream, XBeeCodec>) -> mcp_host::OwnedFrame {
    match device.next().await.expect("the link stays open").unwrap() {
        CodecItem::Frame(frame) => frame,
        other => panic!("{other:?}"),
    }
}

/// The radio's `AP`, asked in an API frame.
async fn read_ap(device: &mut Framed<DuplexStream, XBeeCodec>) -> u8 {
    device
        .send(&Frame::AtCommand(AtCommandRepr {
            frame_id: 7,
            command: *b"AP",
            parameter: &[],
            queued: false,
        }))
        .await
        .unwrap();
    match next_frame(device).await.parse().unwrap() {
        Frame::AtCommandResponse(at) if at.frame_id == 7 && at.status.is_ok() => match at.data {
            [ap] => *ap,
            other => panic!("AP = {other:?}"),
        },
        other => panic!("{other:?}"),
    }
}

/// A network whose coordinator starts in transparent mode and a MAV in API mode 1.
fn network(faults: Faults) -> (Network, DuplexStream, Framed<DuplexStream, XBeeCodec>) {
    let network = Network::new(NetworkConfig {
        faults,
        ..NetworkConfig::default()
    });
    let factory = NodeOptions {
        transparent: true,
        ..NodeOptions::default()
    };
    let (info, ground) = network
        .add_in_process(Address64::COORDINATOR, factory)
        .unwrap();
    assert!(info.transparent);
    let (_, mav) = network.add_in_process(MAV, NodeOptions::default()).unwrap();
    let mav = Framed::new(mav, XBeeCodec::new(ApiMode::Unescaped));
    (network, ground, mav)
}

#[tokio::test(start_paused = true)]
async fn a_factory_radio_passes_payloads_on_and_is_put_into_api_mode_2() {
    let (_network, mut ground, mut mav) = network(Faults::default());

    // No modem status in transparent mode: the payload is the first thing to read.
    send_from_mav(&mut mav, b"t\x01telemetry").await;
    assert_eq!(read(&mut ground).await.unwrap(), b"t\x01telemetry");

    // +++ after a guard time of silence, answered after another.
    tokio::time::sleep(GT).await;
    ground.write_all(b"+++").await.unwrap();
    let typed = tokio::time::Instant::now();
    assert_eq!(line(&mut ground).await, "OK\r");
    assert!(typed.elapsed() >= GT);

    for (sent, answer) in [
        ("ATAP", "0"),
        ("ATBD", "3"),
        ("ATGT", "3E8"),
        ("ATCT", "64"),
        ("ATSL", "0"),
        ("ATCE", "1"),
        ("ATNT", "3C"),
        ("ATNT 10", "ERROR"),
        ("ATNI GS", "OK"),
        ("ATNI", "GS"),
        ("ATBD7", "OK"),
        ("ATBD", "7"),
        ("ATBD9", "ERROR"),
        ("ATXX", "ERROR"),
        ("ATND", "ERROR"),
        ("ATAP2", "OK"),
        ("ATAP", "2"),
        ("ATWR", "OK"),
        ("ATCN", "OK"),
    ] {
        assert_eq!(
            command(&mut ground, sent).await,
            format!("{answer}\r"),
            "{sent}"
        );
    }

    // API mode 2 from here on: an AT command frame is answered, payloads come framed.
    let mut ground = Framed::new(ground, XBeeCodec::new(ApiMode::Escaped));
    assert_eq!(read_ap(&mut ground).await, 2);
    // 0x7E and 0x11 in the payload are escaped now.
    send_from_mav(&mut mav, &[0x7E, 0x11]).await;
    let frame = next_frame(&mut ground).await;
    match frame.parse().unwrap() {
        Frame::ReceivePacket(rx) => {
            assert_eq!((rx.src64, rx.data), (MAV, &[0x7E, 0x11][..]));
        }
        other => panic!("{other:?}"),
    }
}

#[tokio::test(start_paused = true)]
async fn commands_chained_on_one_line_set_a_factory_radio_up() {
    let (_network, mut ground, _mav) = network(Faults::default());
    tokio::time::sleep(GT).await;
    ground.write_all(b"+++").await.unwrap();
    assert_eq!(line(&mut ground).await, "OK\r");
    // One answer a command, in order; a value in hex may start with 0x (but is no
    // number without digits, nor with a sign).
    ground
        .write_all(b"ATNIGS,NT0x20,NT,XX,NT0x,AP+1,AP 0x1,WR,CN\r")
        .await
        .unwrap();
    let mut answers = String::new();
    while answers.matches('\r').count() < 9 {
        answers += &line(&mut ground).await;
    }
    assert_eq!(answers, "OK\rOK\r20\rERROR\rERROR\rERROR\rOK\rOK\rOK\r");
    let mut ground = Framed::new(ground, XBeeCodec::new(ApiMode::Unescaped));
    assert_eq!(read_ap(&mut ground).await, 1);
}

#[tokio::test(start_paused = true)]
async fn plus_plus_plus_without_silence_is_data_and_command_mode_times_out() {
    let (_network, mut ground, _mav) = network(Faults::default());
    // Right after other bytes: no command mode.
    tokio::time::sleep(GT).await;
    ground.write_all(b"data").await.unwrap();
    ground.write_all(b"+++").await.unwrap();
    assert_eq!(read(&mut ground).await, None);

    // Command mode, left after CT (10 s) with no command; AP set meanwhile applies.
    tokio::time::sleep(GT).await;
    ground.write_all(b"+++").await.unwrap();
    assert_eq!(line(&mut ground).await, "OK\r");
    assert_eq!(command(&mut ground, "ATAP1").await, "OK\r");
    // Past CT, counted from when the radio took the command.
    tokio::time::sleep(Duration::from_secs(11)).await;
    let mut ground = Framed::new(ground, XBeeCodec::new(ApiMode::Unescaped));
    assert_eq!(read_ap(&mut ground).await, 1);
}

#[tokio::test(start_paused = true)]
async fn a_transparent_radio_writes_payloads_only_and_corrupts_them_in_place() {
    let faults = Faults {
        corrupt: 1.0,
        ..Faults::default()
    };
    let (_network, mut ground, mut mav) = network(faults);
    send_from_mav(&mut mav, b"abcdef").await;
    let got = read(&mut ground).await.unwrap();
    assert_eq!(got.len(), 6);
    let changed = got.iter().zip(b"abcdef").filter(|(a, b)| a != b).count();
    assert_eq!(changed, 1, "{got:?}");
}

#[tokio::test(start_paused = true)]
async fn nothing_received_is_written_into_command_mode_or_after_it() {
    // Payloads take half a second to reach the device: one on its way when command mode
    // begins, and one sent during it, are both dropped, as a radio in command mode
    // passes nothing on.
    let faults = Faults {
        latency: Duration::from_millis(500),
        ..Faults::default()
    };
    let (_network, mut ground, mut mav) = network(faults);
    ground.write_all(b"+++").await.unwrap();
    tokio::time::sleep(Duration::from_millis(800)).await;
    send_from_mav(&mut mav, b"ON ITS WAY").await;
    assert_eq!(line(&mut ground).await, "OK\r");
    send_from_mav(&mut mav, b"DURING").await;
    tokio::time::sleep(Duration::from_secs(1)).await;
    assert_eq!(command(&mut ground, "ATAP").await, "0\r");
    assert_eq!(command(&mut ground, "ATAP1").await, "OK\r");
    assert_eq!(command(&mut ground, "ATCN").await, "OK\r");
    // API mode 1: the first thing read is the answer to AP, no stray bytes before it.
    let mut ground = Framed::new(ground, XBeeCodec::new(ApiMode::Unescaped));
    assert_eq!(read_ap(&mut ground).await, 1);
    // And payloads come framed from now on.
    send_from_mav(&mut mav, b"AFTER").await;
    match next_frame(&mut ground).await.parse().unwrap() {
        Frame::ReceivePacket(rx) => assert_eq!(rx.data, b"AFTER"),
        other => panic!("{other:?}"),
    }
}
