//! `PacketSink`: MCP packets fed to a link as a `Sink` go out in order, each in a
//! Transmit Request without a status; a packet too large is refused and the next one
//! goes; once the link has ended the sink says so.

mod common;

use common::{Tx, mcp, pty_link};
use futures::{SinkExt, stream};
use mcp_core::{Command, Packet, Report, Text};
use mcp_host::SendError;
use xbee_api::{Address16, Address64, ApiMode};

const MAV: Address64 = Address64(0x0013_A200_40B5_99B9);

/// The Transmit Request a packet to `to` goes out in: frame id 0, FFFE, radius 0.
fn without_status(to: Address64, packet: &Packet<&[u8]>) -> Tx {
    Tx {
        frame_id: 0,
        dst64: to,
        dst16: Address16::UNKNOWN,
        radius: 0,
        options: 0,
        data: mcp(packet),
    }
}

#[tokio::test]
async fn a_stream_of_packets_goes_out_in_order_without_a_status() {
    for mode in [ApiMode::Unescaped, ApiMode::Escaped] {
        let (_stream, sender, mut radio) = pty_link(mode).await;
        let packets: Vec<(Address64, Packet<&[u8]>)> = vec![
            (MAV, Packet::Command(Command::landing(true))),
            (
                Address64::BROADCAST,
                Packet::Message(Text::new(b"all: \x11\x13 hold")),
            ),
            (MAV, Packet::Report(Report::Time(1_700_000_000))),
        ];
        let mut sink = sender.packet_sink();
        sink.send_all(&mut stream::iter(packets.clone().into_iter().map(Ok)))
            .await
            .unwrap();
        for (to, packet) in &packets {
            assert_eq!(radio.next_tx().await, without_status(*to, packet), "{mode}");
        }
        // Nothing awaited an answer: no frame id was taken.
        assert_eq!(sender.stats().timeouts, 0);
    }
}

#[tokio::test]
async fn a_packet_too_large_is_refused_and_the_next_one_goes() {
    let (_stream, sender, mut radio) = pty_link(ApiMode::Unescaped).await;
    let mut sink = sender.packet_sink();
    let long = [b'x'; 300];
    let refused = sink
        .send((MAV, Packet::Message(Text::new(&long[..]))))
        .await;
    assert!(
        matches!(
            refused,
            Err(SendError::TooLarge {
                len: 301,
                max: 255,
                ..
            })
        ),
        "{refused:?}"
    );
    let next = Packet::Command(Command::landing(false));
    sink.send((MAV, next)).await.unwrap();
    assert_eq!(radio.next_tx().await, without_status(MAV, &next));
}

#[tokio::test]
async fn a_sink_of_a_link_that_has_ended_says_it_is_closed() {
    let (_stream, sender, _radio) = pty_link(ApiMode::Unescaped).await;
    let mut sink = sender.packet_sink();
    sender.close();
    sender.closed().await;
    let sent = sink
        .send((MAV, Packet::Command(Command::landing(true))))
        .await;
    assert!(matches!(sent, Err(SendError::Closed)), "{sent:?}");
}

#[tokio::test]
async fn closing_a_sink_leaves_the_link_to_its_other_senders() {
    let (_stream, sender, mut radio) = pty_link(ApiMode::Unescaped).await;
    let mut sink = sender.packet_sink();
    sink.close().await.unwrap();
    let refused = sink
        .send((MAV, Packet::Command(Command::landing(true))))
        .await;
    assert!(matches!(refused, Err(SendError::Closed)), "{refused:?}");
    let packet = Packet::Command(Command::landing(false));
    let mut another = sender.packet_sink();
    another.send((MAV, packet)).await.unwrap();
    assert_eq!(radio.next_tx().await, without_status(MAV, &packet));
}
