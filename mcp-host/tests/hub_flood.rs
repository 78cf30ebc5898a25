//! A hub client that writes frames nonstop slows itself alone: the hub takes its
//! clients' frames in turn, at the pace the radio takes them. Over real TCP sockets,
//! with a radio as slow as a 115200-baud UART.

use std::time::Duration;

use mcp_host::hub::Hub;
use mcp_host::{Link, LinkOptions};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::{TcpListener, TcpStream};
use xbee_api::{ApiMode, AtCommandResponseRepr, AtStatus, EncodeFrame, Frame, RawFrame};

fn encode(frame: &impl EncodeFrame) -> Vec<u8> {
    let mut buf = vec![0u8; frame.encoded_len(ApiMode::Unescaped)];
    let n = frame.encode(ApiMode::Unescaped, &mut buf).unwrap();
    buf.truncate(n);
    buf
}

/// A radio on a 115200-baud UART: takes 11.5 kB/s (1152 bytes every 100 ms), answers
/// AT commands at once; the bytes it took so far on `took`.
async fn slow_radio(listener: TcpListener, took: tokio::sync::watch::Sender<usize>) {
    let (mut sock, _) = listener.accept().await.unwrap();
    let mut decoder: Box<xbee_api::Decoder> = Box::new(xbee_api::Decoder::new(ApiMode::Unescaped));
    let mut buf = vec![0u8; 1152];
    let mut uart = tokio::time::interval(Duration::from_millis(100));
    loop {
        uart.tick().await;
        let n = match sock.read(&mut buf).await {
            Ok(0) | Err(_) => return,
            Ok(n) => n,
        };
        took.send_modify(|took| *took += n);
        let mut answers = Vec::new();
        decoder.decode_each(&buf[..n], |item| {
            if let Ok(frame) = item {
                if let Ok(Frame::AtCommand(at)) = Frame::parse(frame) {
                    answers.push(encode(&AtCommandResponseRepr {
                        frame_id: at.frame_id,
                        command: at.command,
                        status: AtStatus::Ok,
                        data: &[0, 0x13, 0xA2, 0],
                    }));
                }
            }
        });
        for answer in answers {
            if sock.write_all(&answer).await.is_err() {
                return;
            }
        }
    }
}

#[tokio::test(flavor = "multi_thread")]
async fn a_client_writing_nonstop_does_not_hold_up_the_others() {
    let listener = TcpListener::bind("127.0.0.1:0").await.unwrap();
    let radio: Link = format!("tcp:{}", listener.local_addr().unwrap())
        .parse()
        .unwrap();
    let (took, mut radio_took) = tokio::sync::watch::channel(0);
    tokio::spawn(slow_radio(listener, took));
    let hub = Hub::start(&radio, LinkOptions::default(), "127.0.0.1:0")
        .await
        .unwrap();
    let link: Link = format!("tcp:{}", hub.local_addr()).parse().unwrap();
    let (_stream, honest) = mcp_host::connect(&link, LinkOptions::default())
        .await
        .unwrap();
    honest
        .at(*b"SH", &[], None)
        .await
        .expect("an idle hub answers");

    // Transmit Requests of 500 bytes without a status (frame id 0), as fast as the hub
    // takes them.
    let mut flooder = TcpStream::connect(hub.local_addr()).await.unwrap();
    let mut data = vec![0x10, 0x00, 0, 0, 0, 0, 0, 0, 0xFF, 0xFF, 0xFF, 0xFE, 0, 0];
    data.resize(500, b'x');
    let one = encode(&RawFrame::new(&data).unwrap());
    let flood = tokio::spawn(async move { while flooder.write_all(&one).await.is_ok() {} });
    // Until the radio has taken two seconds of the flood: the flooder has been ahead of
    // everyone for that long.
    let start = *radio_took.borrow();
    radio_took
        .wait_for(|took| *took > start + 2 * 11_520)
        .await
        .unwrap();

    let at = honest.at(*b"SH", &[], Some(Duration::from_secs(3))).await;
    assert!(at.is_ok(), "{at:?}: {:?}", hub.stats());
    // The flooder's frames go on reaching the radio, in turn with the others.
    let before = hub.stats().frames_from_clients;
    let more = async {
        while hub.stats().frames_from_clients < before + 2 {
            tokio::task::yield_now().await;
        }
    };
    tokio::time::timeout(Duration::from_secs(20), more)
        .await
        .expect("the flooder's frames go on");
    flood.abort();
    hub.stop().await;
}
