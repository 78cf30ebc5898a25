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
    // Each time it is asked, not only the first (a loop that goes on after an error).
    for _ in 0..3 {
        let sent = sink
            .send((MAV, Packet::Command(Command::landing(true))))
            .await;
        assert!(matches!(sent, Err(SendError::Closed)), "{sent:?}");
    }
}

#[tokio::test]
async fn packets_after_close_are_refused_at_once_and_never_written() {
    // Over TCP, whose end says that nothing more was written.
    let (mut stream, sender, port) = listening().await;
    let mut radio = tokio::net::TcpStream::connect(("127.0.0.1", port))
        .await
        .unwrap();
    assert!(matches!(
        common::next_link_event(&mut stream).await,
        mcp_host::LinkEvent::Connected { .. }
    ));
    let mut sink = sender.packet_sink();
    // Right after `close`, before the link's task may have seen it: refused as the
    // sender's requests are, not written.
    sender.close();
    let sent = sink
        .send((MAV, Packet::Command(Command::landing(true))))
        .await;
    assert!(matches!(sent, Err(SendError::Closed)), "{sent:?}");
    let sent = sender
        .send_with(
            MAV,
            &Command::landing(true),
            mcp_host::SendOptions {
                frame_id: mcp_host::FrameId::None,
                ..mcp_host::SendOptions::default()
            },
        )
        .await;
    assert!(matches!(sent, Err(SendError::Closed)), "{sent:?}");
    sender.closed().await;
    let mut written = Vec::new();
    tokio::io::AsyncReadExt::read_to_end(&mut radio, &mut written)
        .await
        .unwrap();
    assert_eq!(written, [0u8; 0], "written after close");
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

/// A `tcp-listen` link on a free port, waiting for its radio: the link, its port.
async fn listening() -> (mcp_host::PacketStream, mcp_host::CommandSender, u16) {
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let port = listener.local_addr().unwrap().port();
    drop(listener);
    let link: mcp_host::Link = format!("tcp-listen:127.0.0.1:{port}").parse().unwrap();
    let options = mcp_host::LinkOptions {
        wait_for_link: true,
        ..mcp_host::LinkOptions::default()
    };
    let (stream, sender) = mcp_host::connect(&link, options).await.unwrap();
    (stream, sender, port)
}

/// A radio connecting to the link on `port`.
async fn radio_on(port: u16) -> common::FakeXBee {
    let radio = tokio::net::TcpStream::connect(("127.0.0.1", port))
        .await
        .unwrap();
    common::FakeXBee::new(radio, ApiMode::Unescaped)
}

#[tokio::test]
async fn packets_handed_over_before_close_are_written_before_the_link_ends() {
    // Over TCP, whose end comes after every byte written before it.
    let (mut stream, sender, port) = listening().await;
    let mut radio = radio_on(port).await;
    assert!(matches!(
        common::next_link_event(&mut stream).await,
        mcp_host::LinkEvent::Connected { .. }
    ));
    let mut sink = sender.packet_sink();
    let packets: Vec<(Address64, Packet<&[u8]>)> = (0..200u32)
        .map(|t| (MAV, Packet::Report(Report::Time(t))))
        .collect();
    sink.send_all(&mut stream::iter(packets.clone().into_iter().map(Ok)))
        .await
        .unwrap();
    sender.close();
    for (to, packet) in &packets {
        assert_eq!(radio.next_tx().await, without_status(*to, packet));
    }
    sender.closed().await;
}

#[tokio::test]
async fn a_sink_waits_while_the_link_is_down_and_goes_on_once_it_is_back() {
    // A `tcp-listen` link: down until a radio connects, and again while it is away.
    let (mut stream, sender, port) = listening().await;
    let mut sink = sender.packet_sink();
    let first = Packet::Report(Report::Time(1));
    // Not connected yet: the sink holds the packet back rather than dropping it.
    let mut sending = Box::pin(sink.send((MAV, first)));
    assert!(
        futures::poll!(sending.as_mut()).is_pending(),
        "a sink took a packet with no radio there"
    );
    let mut radio = radio_on(port).await;
    sending.await.unwrap();
    assert_eq!(radio.next_tx().await, without_status(MAV, &first));
    drop(sink);

    // The radio goes away: the sink waits again until the next one is there.
    radio.close().await;
    loop {
        if let mcp_host::LinkEvent::Disconnected { .. } = common::next_link_event(&mut stream).await
        {
            break;
        }
    }
    let mut sink = sender.packet_sink();
    let second = Packet::Report(Report::Time(2));
    let mut sending = Box::pin(sink.send((MAV, second)));
    assert!(futures::poll!(sending.as_mut()).is_pending());
    let mut radio = radio_on(port).await;
    sending.await.unwrap();
    assert_eq!(radio.next_tx().await, without_status(MAV, &second));
}

#[tokio::test]
async fn a_request_sent_after_a_flushed_packet_goes_out_after_it() {
    // `send` flushes: once it returns, the link's task has taken the packet, and a
    // request sent after it (through another queue, as it awaits a status) cannot
    // overtake it.
    let (_stream, sender, mut radio) = pty_link(ApiMode::Unescaped).await;
    let mut sink = sender.packet_sink();
    for round in 0..64u8 {
        let packet = Packet::Command(Command::landing(round % 2 == 0));
        sink.send((MAV, packet)).await.unwrap();
        // The request queued at once, before the link's task runs again: were the
        // packet still in its queue, the task would find both waiting, and could take
        // either first.
        let command = Command::landing(round % 2 == 1);
        let mut request = Box::pin(sender.send(MAV, &command));
        assert!(futures::poll!(&mut request).is_pending());
        let first = radio.next_tx().await;
        assert_eq!(first, without_status(MAV, &packet), "round {round}");
        let second = radio.next_tx().await;
        assert_ne!(second.frame_id, 0, "round {round}");
        radio
            .status(second.frame_id, xbee_api::DeliveryStatus::Success)
            .await;
        request.await.unwrap();
    }
}
