//! Sending every command and receiving every report through a real pseudo-terminal,
//! with a fake radio on the far end.

mod common;

use std::collections::HashSet;
use std::time::Duration;

use common::*;
use mcp_core::{
    Address, Command, Controller, LandingState, Packet, Report, SlaveAddresses, Slot,
    StatusRequest, TelemetryBuilder, TelemetryId, TrajectoryBuilder, Waypoint,
};
use mcp_host::{DeliveryReport, Event, FrameId, LinkOptions, RequestError, SendError, SendOptions};
use xbee_api::{Address16, Address64, ApiMode, DeliveryStatus};

fn trajectory_bytes(report: bool, n: u32) -> Vec<u8> {
    let mut buf = [0u8; mcp_core::MAX_PAYLOAD];
    let mut builder = if report {
        TrajectoryBuilder::report(&mut buf).unwrap()
    } else {
        TrajectoryBuilder::command(&mut buf).unwrap()
    };
    for i in 0..n {
        builder
            .push(Waypoint {
                time: 1000 + i,
                elevator: i as f32 * 0.5,
                aileron: -(i as f32),
                altitude: 2.0 + i as f32,
            })
            .unwrap();
    }
    let len = builder.finish();
    buf[..len].to_vec()
}

/// One of every command packet (set commands, both slave-set forms, every status
/// request), as encoded bytes.
fn every_command() -> Vec<Vec<u8>> {
    let addr = Address::from(0x0013_A200_40B5_99BD);
    let mut commands: Vec<Command<&[u8]>> = vec![
        Command::TelemetryToCoordinator {
            on: true,
            id: TelemetryId::Altitude,
        },
        Command::TelemetryToCoordinator {
            on: false,
            id: TelemetryId::Unknown(0x42),
        },
        Command::Landing { on: true },
        Command::Landing { on: false },
        Command::Controllers(Controller::Mpc),
        Command::Controllers(Controller::Unknown(0x10)),
        Command::PositionSlaveSet {
            slot: None,
            address: addr,
        },
        Command::PositionSlaveSet {
            slot: Slot::new(3),
            address: addr,
        },
        Command::Time(1_700_000_000),
        Command::PositionSet {
            elevator: 1.25,
            aileron: -3.5,
        },
    ];
    for request in [
        StatusRequest::TelemetryToCoordinator(TelemetryId::ValidBlob),
        StatusRequest::Landing,
        StatusRequest::Controllers,
        StatusRequest::TrajectorySet,
        StatusRequest::PositionSlaveSet,
        StatusRequest::Time,
    ] {
        commands.push(Command::StatusRequest(request));
    }
    let mut out: Vec<Vec<u8>> = commands.iter().map(|c| mcp(&Packet::Command(*c))).collect();
    // Trajectory set commands, empty and with waypoints.
    out.push(trajectory_bytes(false, 0));
    out.push(trajectory_bytes(false, 3));
    out
}

#[tokio::test]
async fn every_command_type_is_sent_and_decoded_on_the_far_side() {
    let (_stream, sender, mut fake) = pty_link(ApiMode::Unescaped).await;
    for bytes in every_command() {
        let Ok(Packet::Command(command)) = mcp_core::parse(&bytes) else {
            panic!("test command does not parse: {bytes:02X?}");
        };
        let send = {
            let sender = sender.clone();
            let bytes = bytes.clone();
            tokio::spawn(async move {
                let Ok(Packet::Command(command)) = mcp_core::parse(&bytes) else {
                    unreachable!()
                };
                sender.send(MAV, &command).await
            })
        };
        let tx = fake.next_tx().await;
        assert_ne!(tx.frame_id, 0);
        assert_eq!(tx.dst64, MAV);
        assert_eq!(tx.dst16, Address16::UNKNOWN);
        assert_eq!((tx.radius, tx.options), (0, 0));
        assert_eq!(
            mcp_core::parse(&tx.data).unwrap(),
            Packet::Command(command),
            "{:02X?}",
            tx.data
        );
        fake.status(tx.frame_id, DeliveryStatus::Success).await;
        let report = send.await.unwrap().unwrap();
        assert!(
            matches!(report, DeliveryReport::Delivered { frame_id, dst16, .. }
                if frame_id == tx.frame_id && dst16 == Address16(0x1234)),
            "{report:?}"
        );
    }
}

#[tokio::test]
async fn every_packet_category_is_sendable_fire_and_forget_and_broadcast() {
    let (_stream, sender, mut fake) = pty_link(ApiMode::Escaped).await;
    let no_status = SendOptions {
        frame_id: FrameId::None,
        ..SendOptions::default()
    };

    let mut buf = [0u8; 64];
    let mut t = TelemetryBuilder::new(&mut buf).unwrap();
    t.push(TelemetryId::PitchAngle, 0.25).unwrap();
    let len = t.finish();
    let telemetry = buf[..len].to_vec();
    let message = b"mHello World\x11\x13\x7E\x7D\xFF".to_vec();
    let warning = b"wlow battery".to_vec();
    let report = mcp(&Packet::<&[u8]>::Report(Report::Landing(
        LandingState::Flight,
    )));

    for bytes in [telemetry, message, warning, report] {
        let packet = mcp_core::parse(&bytes).unwrap();
        let written = sender
            .send_packet(Address64::BROADCAST, &packet, no_status)
            .await
            .unwrap();
        assert_eq!(written, DeliveryReport::Written);
        let tx = fake.next_tx().await;
        assert_eq!(tx.frame_id, 0);
        assert_eq!(tx.dst64, Address64::BROADCAST);
        assert_eq!(tx.data, bytes);
    }
}

#[tokio::test]
async fn every_report_type_and_category_is_received() {
    let (mut stream, _sender, mut fake) = pty_link(ApiMode::Escaped).await;
    let reports: Vec<Report<&[u8]>> = vec![
        Report::TelemetryToCoordinator {
            on: true,
            id: TelemetryId::AileronAccelerationError,
        },
        Report::Landing(LandingState::TakeOff),
        Report::Landing(LandingState::Unknown(9)),
        Report::Controllers(Controller::Manual),
        Report::PositionSlaveSet(SlaveAddresses::Single(Address::from(7))),
        Report::PositionSlaveSet(SlaveAddresses::Slots([
            Address::from(1),
            Address::from(2),
            Address::from(0x7E7D_1113),
            Address::from(4),
        ])),
        Report::Time(0x7E7D_1113),
    ];
    let mut payloads: Vec<Vec<u8>> = reports.iter().map(|r| mcp(&Packet::Report(*r))).collect();
    payloads.push(trajectory_bytes(true, 0));
    payloads.push(trajectory_bytes(true, 2));
    payloads.push(vec![b't']);
    payloads.push(b"mHi".to_vec());
    payloads.push(b"w\x80\xFF".to_vec());
    let mut buf = [0u8; 64];
    let mut t = TelemetryBuilder::new(&mut buf).unwrap();
    t.push(TelemetryId::Altitude, 1.5).unwrap();
    t.push(TelemetryId::Unknown(0xC4), f32::NAN).unwrap();
    let len = t.finish();
    payloads.push(buf[..len].to_vec());

    for payload in &payloads {
        fake.receive(OTHER_MAV, payload).await;
    }
    for payload in &payloads {
        let rx = next_packet(&mut stream).await;
        assert_eq!(rx.origin.src64, OTHER_MAV);
        assert_eq!(rx.origin.src16, Address16(0x7D33));
        assert_eq!(rx.origin.options, 0x01);
        assert_eq!(&rx.payload[..], &payload[..]);
        // The owned packet equals a fresh parse of the payload, and re-encodes to it.
        let expected = mcp_core::parse(payload).unwrap();
        assert_eq!(mcp(&rx.packet), *payload);
        assert_eq!(rx.packet.category(), expected.category());
    }
    // Telemetry values come through bit for bit (NaN included).
    let last = payloads.last().unwrap();
    let Ok(Packet::Telemetry(t)) = mcp_core::parse(last) else {
        panic!()
    };
    assert_eq!(t.value(TelemetryId::Altitude), Some(1.5));
}

#[tokio::test]
async fn invalid_mcp_payloads_and_other_frames_are_events() {
    let (mut stream, _sender, mut fake) = pty_link(ApiMode::Unescaped).await;
    fake.receive(MAV, b"c\x02").await; // landing command too short
    fake.receive(MAV, b"").await; // empty payload
    fake.write_raw(&[0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F]).await; // modem status
    fake.status(77, DeliveryStatus::Success).await; // nobody waits for id 77
    fake.write_raw(&[0x7E, 0x00, 0x02, 0x23, 0x11, 0xCB]).await; // unknown type 0x23

    match next_event(&mut stream).await {
        Event::InvalidPacket(p) => {
            assert_eq!(&p.payload[..], b"c\x02");
            assert_eq!(p.origin.src64, MAV);
            assert!(p.error.to_string().contains("landing"), "{}", p.error);
        }
        other => panic!("{other:?}"),
    }
    assert!(matches!(
        next_event(&mut stream).await,
        Event::InvalidPacket(_)
    ));
    let types: Vec<(u8, Option<u8>)> = [
        next_event(&mut stream).await,
        next_event(&mut stream).await,
        next_event(&mut stream).await,
    ]
    .into_iter()
    .map(|e| match e {
        Event::Frame(f) => (f.frame_type(), f.frame_id()),
        other => panic!("{other:?}"),
    })
    .collect();
    assert_eq!(types, [(0x8A, None), (0x8B, Some(77)), (0x23, None)]);
    // An MCP packet in an Explicit Rx Indicator (radio in AO=1) is a packet too.
    fake.send(&explicit_rx(OTHER_MAV, b"r\x03\x03")).await;
    let rx = next_packet(&mut stream).await;
    assert_eq!(rx.origin.src64, OTHER_MAV);
    assert_eq!(rx.origin.options, 0x02);
    // The frame it came in, endpoints and cluster included, with the payload at its end.
    assert_eq!(rx.frame[0], 0x91);
    assert_eq!(rx.frame[11..17], [0xE8, 0xE8, 0x00, 0x11, 0xC1, 0x05]);
    assert!(rx.frame.ends_with(&rx.payload));
    assert_eq!(
        rx.packet.as_borrowed(),
        Packet::Report(Report::Controllers(Controller::Mpc))
    );
    // Printed as `monitor` prints it, without its time.
    assert_eq!(
        rx.to_string(),
        format!(
            "rx  {OTHER_MAV}/{} opt 02: report controllers mpc",
            rx.origin.src16
        )
    );
    let stats = stream.stats();
    assert_eq!(stats.invalid_packets, 2);
    assert_eq!(stats.unclaimed_responses, 1);
    assert_eq!(stats.frames, 6);
}

#[tokio::test]
async fn any_frame_can_be_written_as_is() {
    let (_stream, sender, mut fake) = pty_link(ApiMode::Escaped).await;
    // An AT command queued with frame id 0x7E (escaped on the wire), no response awaited.
    sender
        .write_frame(&[0x09, 0x7E, b'N', b'J', 0x11])
        .await
        .unwrap();
    assert_eq!(fake.next_frame().await, [0x09, 0x7E, b'N', b'J', 0x11]);
    assert!(matches!(
        sender.write_frame(&[]).await,
        Err(SendError::EmptyFrame)
    ));
}

#[tokio::test]
async fn concurrent_sends_get_their_own_status_and_failures_are_typed() {
    let (_stream, sender, mut fake) = pty_link(ApiMode::Escaped).await;
    const N: u32 = 200;
    let mut tasks = Vec::new();
    for i in 0..N {
        let sender = sender.clone();
        tasks.push(tokio::spawn(async move {
            sender.send(MAV, &Command::time(i)).await
        }));
    }
    // Collect every request, then answer in reverse order; every third fails.
    let mut seen = Vec::new();
    for _ in 0..N {
        let tx = fake.next_tx().await;
        let Ok(Packet::Command(Command::Time(i))) = mcp_core::parse(&tx.data) else {
            panic!("{:02X?}", tx.data)
        };
        seen.push((tx.frame_id, i));
    }
    let ids: HashSet<u8> = seen.iter().map(|(id, _)| *id).collect();
    assert_eq!(ids.len(), N as usize, "frame ids in flight are distinct");
    assert!(!ids.contains(&0));
    for (id, i) in seen.iter().rev() {
        let status = if i % 3 == 0 {
            DeliveryStatus::AddressNotFound
        } else {
            DeliveryStatus::Success
        };
        fake.status(*id, status).await;
    }
    let by_value: std::collections::HashMap<u32, u8> =
        seen.iter().map(|(id, i)| (*i, *id)).collect();
    for (i, task) in tasks.into_iter().enumerate() {
        let i = i as u32;
        let result = task.await.unwrap();
        if i.is_multiple_of(3) {
            let err = result.unwrap_err();
            let SendError::Delivery {
                to,
                frame_id,
                dst16,
                status,
                retries,
                discovery,
                ..
            } = err
            else {
                panic!("{err:?}");
            };
            assert_eq!(
                (to, frame_id, dst16, status, retries, discovery),
                (
                    MAV,
                    by_value[&i],
                    Address16(0x1234),
                    DeliveryStatus::AddressNotFound,
                    0,
                    xbee_api::DiscoveryStatus::from(0),
                )
            );
            assert!(err.to_string().contains("0x24"), "{err}");
        } else {
            match result.unwrap() {
                DeliveryReport::Delivered { frame_id, .. } => assert_eq!(frame_id, by_value[&i]),
                other => panic!("{other:?}"),
            }
        }
    }
}

#[tokio::test]
async fn frame_ids_are_reused_and_no_send_is_lost_when_statuses_never_come() {
    let (stream, sender, mut fake) = pty_link(ApiMode::Unescaped).await;
    let short = SendOptions {
        timeout: Some(Duration::from_secs(1)),
        frame_id: FrameId::Auto,
    };
    const BATCHES: u32 = 8;
    const BATCH: u32 = 50; // 400 sends in all, more than 255 ids
    let mut used_ids = Vec::new();
    let mut timed_out = 0;
    for batch in 0..BATCHES {
        let tasks: Vec<_> = (0..BATCH)
            .map(|k| {
                let sender = sender.clone();
                let value = batch * BATCH + k;
                tokio::spawn(
                    async move { sender.send_with(MAV, &Command::time(value), short).await },
                )
            })
            .collect();
        let mut unanswered = HashSet::new();
        for _ in 0..BATCH {
            let tx = fake.next_tx().await;
            let Ok(Packet::Command(Command::Time(value))) = mcp_core::parse(&tx.data) else {
                panic!()
            };
            used_ids.push(tx.frame_id);
            if value % 5 == 0 {
                unanswered.insert(tx.frame_id); // this status never comes
            } else {
                fake.status(tx.frame_id, DeliveryStatus::Success).await;
            }
        }
        for (k, task) in tasks.into_iter().enumerate() {
            let value = batch * BATCH + k as u32;
            match task.await.unwrap() {
                Ok(DeliveryReport::Delivered { .. }) => assert_ne!(value % 5, 0),
                Err(SendError::Timeout {
                    frame_id, heard, ..
                }) => {
                    // Other statuses came on this link.
                    assert!(heard);
                    assert_eq!(value % 5, 0, "answered send {value} timed out");
                    let frame_id = frame_id.expect("sent under a frame id");
                    assert!(unanswered.contains(&frame_id), "{frame_id}");
                    timed_out += 1;
                }
                other => panic!("send {value}: {other:?}"),
            }
        }
    }
    assert_eq!(timed_out, BATCHES * BATCH / 5);
    assert_eq!(used_ids.len(), (BATCHES * BATCH) as usize);
    assert!(used_ids.iter().all(|id| *id != 0));
    let distinct: HashSet<u8> = used_ids.iter().copied().collect();
    assert!(distinct.len() <= 255);
    // Ids of sends that timed out came back into use.
    assert_eq!(stream.stats().timeouts, u64::from(timed_out));
}

#[tokio::test]
async fn request_gets_its_report_while_unrelated_telemetry_floods_in() {
    // A tiny event queue nobody reads: events are dropped, requests still resolve.
    let (stream, sender, mut fake) = pty_link_with(LinkOptions {
        event_capacity: 4,
        ..LinkOptions::default()
    })
    .await;
    let request = tokio::spawn({
        let sender = sender.clone();
        async move {
            sender
                .request(
                    MAV,
                    StatusRequest::TelemetryToCoordinator(TelemetryId::ElevatorSpeed),
                )
                .await
        }
    });
    let tx = fake.next_tx().await;
    assert_eq!(tx.data, b"c\x01\xFF\x02");
    fake.status(tx.frame_id, DeliveryStatus::Success).await;

    let mut buf = [0u8; 255];
    let mut t = TelemetryBuilder::new(&mut buf).unwrap();
    for id in 0..20u8 {
        t.push(TelemetryId::from(id), f32::from(id)).unwrap();
    }
    let len = t.finish();
    let telemetry = buf[..len].to_vec();
    for round in 0..200 {
        let src = if round % 2 == 0 { MAV } else { OTHER_MAV };
        fake.receive(src, &telemetry).await;
        if round == 50 {
            // Same report type, wrong telemetry id, right address.
            let wrong_id = Report::<&[u8]>::TelemetryToCoordinator {
                on: false,
                id: TelemetryId::AileronSpeed,
            };
            fake.receive(MAV, &mcp(&Packet::Report(wrong_id))).await;
            // Right report, wrong address.
            let other = Report::<&[u8]>::TelemetryToCoordinator {
                on: false,
                id: TelemetryId::ElevatorSpeed,
            };
            fake.receive(OTHER_MAV, &mcp(&Packet::Report(other))).await;
            // Another report type from the right address.
            let landing = Report::<&[u8]>::Landing(LandingState::Flight);
            fake.receive(MAV, &mcp(&Packet::Report(landing))).await;
        }
    }
    let right = Report::<&[u8]>::TelemetryToCoordinator {
        on: true,
        id: TelemetryId::ElevatorSpeed,
    };
    fake.receive(MAV, &mcp(&Packet::Report(right))).await;
    for _ in 0..50 {
        fake.receive(MAV, &telemetry).await;
    }
    let report = tokio::time::timeout(GUARD, request)
        .await
        .unwrap()
        .unwrap()
        .unwrap();
    assert_eq!(report.as_borrowed(), right);
    assert!(stream.stats().events_dropped > 0);
}

#[tokio::test]
async fn request_fails_on_delivery_failure_and_times_out_without_report() {
    let (_stream, sender, mut fake) = pty_link(ApiMode::Unescaped).await;
    let failing = tokio::spawn({
        let sender = sender.clone();
        async move { sender.request(MAV, StatusRequest::Time).await }
    });
    let tx = fake.next_tx().await;
    assert_eq!(tx.data, b"c\x06\xFF");
    fake.status(tx.frame_id, DeliveryStatus::RouteNotFound)
        .await;
    let err = failing.await.unwrap().unwrap_err();
    assert!(
        matches!(
            err,
            RequestError::Send(SendError::Delivery {
                status: DeliveryStatus::RouteNotFound,
                ..
            })
        ),
        "{err}"
    );

    let silent = tokio::spawn({
        let sender = sender.clone();
        async move {
            sender
                .request_with(
                    OTHER_MAV,
                    StatusRequest::Landing,
                    Some(Duration::from_millis(200)),
                )
                .await
        }
    });
    let tx = fake.next_tx().await;
    fake.status(tx.frame_id, DeliveryStatus::Success).await;
    // A landing report from somebody else does not answer it.
    let landing = Report::<&[u8]>::Landing(LandingState::OnGround);
    fake.receive(MAV, &mcp(&Packet::Report(landing))).await;
    let err = silent.await.unwrap().unwrap_err();
    match &err {
        RequestError::Timeout {
            from,
            request,
            delivered,
            ..
        } => {
            assert_eq!(*from, OTHER_MAV);
            assert_eq!(*request, StatusRequest::Landing);
            assert!(*delivered, "the radio confirmed delivery");
        }
        other => panic!("{other}"),
    }
    assert!(err.to_string().contains("the MAV did not answer"), "{err}");
}

#[tokio::test]
async fn a_request_the_radio_never_confirms_says_so_when_it_times_out() {
    let (mut stream, sender, mut fake) = pty_link(ApiMode::Unescaped).await;
    // A landing request the radio reads and says nothing to: its error.
    let unanswered = async |fake: &mut FakeXBee| {
        let request = tokio::spawn({
            let sender = sender.clone();
            async move {
                let timeout = Some(Duration::from_millis(200));
                sender
                    .request_with(MAV, StatusRequest::Landing, timeout)
                    .await
            }
        });
        fake.next_tx().await;
        request.await.unwrap().unwrap_err()
    };
    let err = unanswered(&mut fake).await;
    assert!(
        matches!(
            err,
            RequestError::Timeout {
                delivered: false,
                heard: false,
                ..
            }
        ),
        "{err:?}"
    );
    assert!(
        err.to_string().contains(
            "the radio did not confirm delivery; no valid frame has come from the radio since the \
             link came up"
        ),
        "{err}"
    );

    // Once the radio has said something, its silence is about this request alone.
    fake.receive(MAV, b"r\x02\x04").await;
    let heard = next_packet(&mut stream).await;
    assert_eq!(heard.origin.src64, MAV);
    let err = unanswered(&mut fake).await;
    assert!(
        matches!(
            err,
            RequestError::Timeout {
                delivered: false,
                heard: true,
                ..
            }
        ),
        "{err:?}"
    );
    assert!(
        err.to_string()
            .ends_with("(the radio did not confirm delivery)"),
        "{err}"
    );
}

#[tokio::test]
async fn an_at_command_is_answered_by_an_at_response_only() {
    let (mut stream, sender, mut fake) = pty_link(ApiMode::Unescaped).await;
    let at = tokio::spawn({
        let sender = sender.clone();
        async move { sender.at(*b"AP", &[], None).await }
    });
    let id = fake.next_frame().await[1];
    // A transmit status under the same id (a stale one, or through a hub another
    // program's) is no answer to it: it goes to the stream.
    fake.status(id, DeliveryStatus::Success).await;
    loop {
        if let Event::Frame(frame) = next_event(&mut stream).await {
            assert_eq!((frame.frame_type(), frame.frame_id()), (0x8B, Some(id)));
            break;
        }
    }
    assert!(!at.is_finished());
    fake.send(&xbee_api::AtCommandResponseRepr {
        frame_id: id,
        command: *b"AP",
        status: xbee_api::AtStatus::from(0),
        data: &[1],
    })
    .await;
    let response = at.await.unwrap().unwrap();
    assert_eq!(
        (response.frame_type(), response.frame_id()),
        (0x88, Some(id))
    );
}

#[tokio::test]
async fn at_and_remote_at_commands_get_their_responses() {
    let (_stream, sender, mut fake) = pty_link(ApiMode::Escaped).await;
    let at = tokio::spawn({
        let sender = sender.clone();
        async move { sender.at(*b"NI", &[], None).await }
    });
    let frame = fake.next_frame().await;
    assert_eq!((frame[0], &frame[2..]), (0x08, &b"NI"[..]));
    let id = frame[1];
    assert_ne!(id, 0);
    fake.send(&xbee_api::AtCommandResponseRepr {
        frame_id: id,
        command: *b"NI",
        status: xbee_api::AtStatus::from(0),
        data: b"GROUND",
    })
    .await;
    let response = at.await.unwrap().unwrap();
    match response.parse().unwrap() {
        xbee_api::Frame::AtCommandResponse(r) => {
            assert_eq!(
                (r.frame_id, r.command, r.data),
                (id, *b"NI", &b"GROUND"[..])
            );
        }
        other => panic!("{other:?}"),
    }

    let remote = tokio::spawn({
        let sender = sender.clone();
        async move { sender.remote_at(MAV, *b"D0", &[4], true, None).await }
    });
    let frame = fake.next_frame().await;
    let Ok(xbee_api::Frame::RemoteAtCommand(cmd)) = xbee_api::Frame::parse_bytes(&frame) else {
        panic!("{frame:02X?}")
    };
    assert_eq!(cmd.dst64, MAV);
    assert_eq!(cmd.command, *b"D0");
    assert_eq!(cmd.parameter, &[4]);
    fake.send(&xbee_api::RemoteAtResponseRepr {
        frame_id: cmd.frame_id,
        src64: MAV,
        src16: Address16(0x1111),
        command: *b"D0",
        status: xbee_api::AtStatus::from(0),
        data: &[],
    })
    .await;
    let response = remote.await.unwrap().unwrap();
    assert_eq!(response.frame_type(), 0x97);
    assert_eq!(response.frame_id(), Some(cmd.frame_id));

    // A frame type without a frame id cannot be awaited.
    assert_eq!(
        sender.send_frame(&[0x8A, 0x00], None).await,
        Err(SendError::NoFrameId(0x8A))
    );
    // Nor an empty frame, nor a frame type alone: each says what it lacks.
    assert_eq!(
        sender.send_frame(&[], None).await,
        Err(SendError::EmptyFrame)
    );
    let alone = sender.send_frame(&[0x08], None).await;
    assert_eq!(alone, Err(SendError::NoFrameIdByte(0x08)));
    assert_eq!(
        alone.unwrap_err().to_string(),
        "frame type 0x08 carries a frame id in its second byte, and the frame data ends \
         before it"
    );
}

#[cfg(unix)]
#[tokio::test]
async fn link_state_says_connected_as_soon_as_connect_returns_with_a_transport() {
    use mcp_host::{Link, LinkState};
    // A TCP link connects before `connect` returns.
    let radio = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let tcp: Link = format!("tcp:{}", radio.local_addr().unwrap())
        .parse()
        .unwrap();
    let (_stream, sender) = mcp_host::connect(&tcp, LinkOptions::default())
        .await
        .unwrap();
    assert_eq!(sender.link_state(), LinkState::Connected);
    // Links that wait for their peer have none yet.
    for link in ["tcp-listen:127.0.0.1:0", "pty"] {
        let link: Link = link.parse().unwrap();
        let (stream, waiting) = mcp_host::connect(&link, LinkOptions::default())
            .await
            .unwrap();
        assert_eq!(waiting.link_state(), LinkState::Connecting, "{link}");
        assert_eq!(stream.link_state(), LinkState::Connecting, "{link}");
        waiting.close();
        waiting.closed().await;
    }
    sender.close();
    sender.closed().await;
}

#[tokio::test]
async fn a_trajectory_goes_out_as_one_trajectory_set_command() {
    let (_stream, sender, mut fake) = pty_link(ApiMode::Unescaped).await;
    let waypoints = [
        Waypoint {
            time: 10,
            elevator: 0.5,
            aileron: 0.0,
            altitude: 1.2,
        },
        Waypoint {
            time: 11,
            elevator: 0.0,
            aileron: 0.5,
            altitude: 1.4,
        },
    ];
    let send = tokio::spawn({
        let sender = sender.clone();
        async move { sender.send_trajectory(MAV, &waypoints).await }
    });
    let tx = fake.next_tx().await;
    let Ok(Packet::Command(Command::TrajectorySet(sent))) = mcp_core::parse(&tx.data) else {
        panic!("not a trajectory set: {:02x?}", tx.data);
    };
    assert_eq!(sent.iter().collect::<Vec<_>>(), waypoints);
    fake.status(tx.frame_id, DeliveryStatus::Success).await;
    assert!(matches!(
        send.await.unwrap(),
        Ok(DeliveryReport::Delivered { .. })
    ));
    // 16 waypoints do not fit a payload: refused, nothing sent.
    let too_many = [waypoints[0]; 16];
    let refused = sender.send_trajectory(MAV, &too_many).await;
    assert!(
        matches!(
            refused,
            Err(SendError::TooLarge { len, max, .. })
                if len == Waypoint::packet_len(16) && max == mcp_core::MAX_PAYLOAD
        ),
        "{refused:?}"
    );
}

#[tokio::test]
async fn timeouts_of_any_length_mean_a_long_wait_not_a_panic() {
    let (stream, sender, mut fake) = pty_link_with(LinkOptions {
        api_mode: ApiMode::Unescaped,
        send_timeout: Duration::MAX,
        partial_frame_timeout: Some(Duration::MAX),
        ..LinkOptions::default()
    })
    .await;
    let send = tokio::spawn({
        let sender = sender.clone();
        async move { sender.send(MAV, &Command::time(5)).await }
    });
    let tx = fake.next_tx().await;
    fake.status(tx.frame_id, DeliveryStatus::Success).await;
    let report = send.await.unwrap().unwrap();
    assert!(
        matches!(report, DeliveryReport::Delivered { frame_id, .. } if frame_id == tx.frame_id),
        "{report:?}"
    );
    // A partial frame starts the (never ending) wait for its rest; the link's task
    // goes on: it still writes what is sent.
    fake.write_raw(&[0x7E, 0x00]).await;
    let send = tokio::spawn({
        let sender = sender.clone();
        async move { sender.send(MAV, &Command::time(6)).await }
    });
    let tx = fake.next_tx().await;
    assert_eq!(tx.data, mcp(&Packet::<&[u8]>::Command(Command::time(6))));
    assert_eq!(stream.link_state(), mcp_host::LinkState::Connected);
    send.abort();
}

#[tokio::test]
async fn a_timeout_too_short_to_send_in_says_so_not_that_frame_ids_ran_out() {
    let (_stream, sender, mut fake) = pty_link(ApiMode::Unescaped).await;
    let zero = SendOptions {
        timeout: Some(Duration::ZERO),
        frame_id: FrameId::Auto,
    };
    // Every frame id is free: none of these waited for one.
    let sent = sender.send_with(MAV, &Command::landing(true), zero).await;
    let Err(not_sent @ SendError::NotSent { timeout, .. }) = sent else {
        panic!("{sent:?}");
    };
    assert_eq!(timeout, Duration::ZERO);
    let asked = sender
        .request_with(MAV, StatusRequest::Landing, Some(Duration::ZERO))
        .await;
    assert!(
        matches!(&asked, Err(RequestError::Send(e)) if *e == not_sent),
        "{asked:?}"
    );
    let at = sender.at(*b"AP", &[], Some(Duration::ZERO)).await;
    assert_eq!(at.err(), Some(not_sent.clone()));
    assert_eq!(
        not_sent.to_string(),
        "not sent: its timeout of 0 s ran out before it went out to the radio"
    );
    // None went out: the next frame the radio reads is the next request's.
    sender.write_frame(&[0x08, 0x00, b'N', b'I']).await.unwrap();
    assert_eq!(fake.next_frame().await, [0x08, 0x00, b'N', b'I']);
}

#[tokio::test]
async fn sends_without_status_go_out_while_requests_wait_for_frame_ids() {
    let (_stream, sender, mut fake) = pty_link(ApiMode::Unescaped).await;
    // A radio that answers nothing: all 255 ids in flight, then more requests than
    // can wait for an id, waiting to be taken.
    let slow = SendOptions {
        timeout: Some(Duration::from_secs(3600)),
        frame_id: FrameId::Auto,
    };
    let mut waiting = Vec::new();
    for _ in 0..255 + 80 {
        let sender = sender.clone();
        waiting.push(tokio::spawn(async move {
            sender.send_payload(MAV, &b"c\x02\x01"[..], slow).await
        }));
    }
    for _ in 0..255 {
        assert_ne!(fake.next_tx().await.frame_id, 0);
    }
    // A transmit without status goes out at once all the same, and so does a raw write.
    let no_status = SendOptions {
        timeout: None,
        frame_id: FrameId::None,
    };
    let report = tokio::time::timeout(
        GUARD,
        sender.send_payload(MAV, &b"c\x02\x00"[..], no_status),
    )
    .await
    .expect("a transmit without status waited for the requests before it")
    .unwrap();
    assert_eq!(report, DeliveryReport::Written);
    let tx = fake.next_tx().await;
    assert_eq!((tx.frame_id, &tx.data[..]), (0, &b"c\x02\x00"[..]));
    let modem_status = [0x8A, 0x00];
    tokio::time::timeout(GUARD, sender.write_frame(&modem_status[..]))
        .await
        .expect("a raw write waited for the requests before it")
        .unwrap();
    assert_eq!(fake.next_frame().await, modem_status);
    assert!(waiting.iter().all(|w| !w.is_finished()));
    for w in waiting {
        w.abort();
    }
}

#[tokio::test]
async fn the_link_diagnoses_a_radio_in_the_other_api_mode_in_its_own_mode() {
    let (mut stream, sender, mut fake) = pty_link(ApiMode::Unescaped).await;
    assert_eq!(stream.info().api_mode, ApiMode::Unescaped);
    let before = sender.stats();
    // The radio writes in mode 2: its 16-bit address 7D33 is escaped, which a mode 1
    // link reads as data, and the checksum fails.
    let packet = rx(Address64(0x0013_A200_40B5_99B9), b"r\x02\x04");
    let mut wire = vec![0u8; xbee_api::EncodeFrame::encoded_len(&packet, ApiMode::Escaped)];
    xbee_api::EncodeFrame::encode(&packet, ApiMode::Escaped, &mut wire).unwrap();
    fake.write_raw(&wire).await;
    assert!(matches!(
        next_event(&mut stream).await,
        Event::DecodeError(_)
    ));
    for found in [stream.diagnose(&before), sender.diagnose(&before)] {
        assert!(
            matches!(
                found,
                Some(mcp_host::Diagnosis::OtherApiMode {
                    radio: ApiMode::Escaped,
                    ..
                })
            ),
            "{found:?}"
        );
    }
    // Since a snapshot taken after it: nothing.
    assert_eq!(sender.diagnose(&sender.stats()), None);
}

/// A transport that takes bytes more slowly than requests come (a radio's UART at a low
/// baud rate, a serial bridge; here a radio that stops reading for a while): frames
/// wait in the link's queue of bytes, and requests time out there. None of a frame still
/// queued when its timeout runs out reaches the radio (`NotSent`); the frame id of one
/// that went out stays taken until its late answer comes, so that a new request never
/// gets another frame's status under a reused id.
#[tokio::test]
async fn a_request_that_times_out_in_a_slow_transport_is_taken_back_or_keeps_its_id() {
    let (_stream, sender, mut radio) = pty_link_with(LinkOptions::default()).await;
    let quick = SendOptions {
        timeout: Some(Duration::from_millis(100)),
        ..SendOptions::default()
    };
    // The radio reads nothing for now: the pseudo-terminal's buffers fill, then the
    // link's own; every request to MAV times out.
    let (mut timed_out, mut not_sent) = (0, 0);
    for _ in 0..20 {
        let batch: Vec<_> = (0..200)
            .map(|_| {
                let sender = sender.clone();
                tokio::spawn(
                    async move { sender.send_payload(MAV, &b"c\x02\x01"[..], quick).await },
                )
            })
            .collect();
        for task in batch {
            match task.await.unwrap() {
                Err(SendError::Timeout { .. }) => timed_out += 1,
                Err(SendError::NotSent { .. } | SendError::NoFreeFrameId { .. }) => not_sent += 1,
                other => panic!("{other:?}"),
            }
        }
    }
    assert!(timed_out > 0 && not_sent > 0, "{timed_out} {not_sent}");
    // Then a request to a radio that is not there: its delivery fails.
    let doomed = {
        let sender = sender.clone();
        tokio::spawn(async move {
            let options = SendOptions {
                timeout: Some(GUARD),
                ..SendOptions::default()
            };
            sender
                .send_payload(OTHER_MAV, &b"c\x02\x01"[..], options)
                .await
        })
    };
    // The radio catches up: it gets the frames that went out, and no other, and
    // answers each.
    let mut received = 0;
    loop {
        let tx = radio.next_tx().await;
        if tx.dst64 == OTHER_MAV {
            radio.status(tx.frame_id, DeliveryStatus::from(0x24)).await;
            break;
        }
        received += 1;
        radio.status(tx.frame_id, DeliveryStatus::Success).await;
    }
    assert_eq!(received, timed_out, "frames that reached the radio");
    let result = doomed.await.unwrap();
    assert!(
        matches!(result, Err(SendError::Delivery { frame_id, .. }) if frame_id != 0),
        "{result:?}"
    );
}

/// The 802.15.4 Transmit Request (0x00, 64-bit address) carries a frame id as the other
/// requests do, and its TX Status (0x89) answers it.
#[tokio::test]
async fn send_frame_takes_an_802_15_4_transmit_request() {
    let (_stream, sender, mut radio) = pty_link_with(LinkOptions::default()).await;
    // Frame id, destination, options, payload.
    let mut tx64 = vec![0x00, 0x00];
    tx64.extend_from_slice(&MAV.0.to_be_bytes());
    tx64.extend_from_slice(&[0x00, b'h', b'i']);
    let asked = tokio::spawn(async move { sender.send_frame(&tx64, None).await });
    let written = tokio::time::timeout(GUARD, radio.next_frame())
        .await
        .expect("the request written");
    assert_eq!(
        (written[0], &written[2..10]),
        (0x00, &MAV.0.to_be_bytes()[..])
    );
    assert_ne!(written[1], 0, "a frame id");
    let status = [0x89, written[1], 0x00];
    radio.send(&xbee_api::RawFrame::new(&status).unwrap()).await;
    let answer = asked.await.unwrap().expect("its TX Status");
    assert_eq!(answer.data()[..], status);
}

#[tokio::test]
async fn options_out_of_range_are_refused_before_the_link_opens() {
    use mcp_host::{ConnectError, Link, MAX_EVENT_CAPACITY, OptionsError, codec::MAX_FRAME_DATA};
    // Which option, the value given and the largest taken.
    let capacity = |given: usize| {
        move |e: &OptionsError| {
            matches!(*e, OptionsError::EventCapacity { value, max, .. }
                if value == given && max == MAX_EVENT_CAPACITY)
        }
    };
    let frame_len = |given: usize| {
        move |e: &OptionsError| {
            matches!(*e, OptionsError::MaxFrameLen { value, max, .. }
                if value == given && max == MAX_FRAME_DATA)
        }
    };
    type Expected<'a> = &'a dyn Fn(&OptionsError) -> bool;
    let cases: [(LinkOptions, Expected<'_>); 5] = [
        (
            LinkOptions {
                event_capacity: 0,
                ..LinkOptions::default()
            },
            &capacity(0),
        ),
        (
            LinkOptions {
                event_capacity: MAX_EVENT_CAPACITY + 1,
                ..LinkOptions::default()
            },
            &capacity(MAX_EVENT_CAPACITY + 1),
        ),
        // "Unbounded", as someone may try: an error, not a panic in the channel.
        (
            LinkOptions {
                event_capacity: usize::MAX,
                ..LinkOptions::default()
            },
            &capacity(usize::MAX),
        ),
        (
            LinkOptions {
                max_frame_len: 0,
                ..LinkOptions::default()
            },
            &frame_len(0),
        ),
        (
            LinkOptions {
                max_frame_len: MAX_FRAME_DATA + 1,
                ..LinkOptions::default()
            },
            &frame_len(MAX_FRAME_DATA + 1),
        ),
    ];
    for (options, expected) in cases {
        let checked = options.check().expect_err("out of range");
        assert!(expected(&checked), "{checked:?}");
        match mcp_host::connect(&Link::Pty, options).await {
            Err(ConnectError::Options(why)) => assert_eq!(why, checked),
            other => panic!("{checked}: {:?}", other.map(|_| ())),
        }
    }
    // The edges are in range.
    for options in [
        LinkOptions {
            event_capacity: 1,
            max_frame_len: 1,
            ..LinkOptions::default()
        },
        LinkOptions {
            event_capacity: MAX_EVENT_CAPACITY,
            max_frame_len: MAX_FRAME_DATA,
            ..LinkOptions::default()
        },
    ] {
        assert_eq!(options.check(), Ok(()));
    }
}

#[tokio::test]
async fn a_timeout_says_when_nothing_at_all_came_from_the_radio() {
    // A peer that reads and says nothing: the radio in another API mode or at another
    // baud rate, in transparent mode, or serving another connection first.
    let (_stream, sender, mut fake) = pty_link(ApiMode::Escaped).await;
    let short = SendOptions {
        timeout: Some(Duration::from_millis(200)),
        ..SendOptions::default()
    };
    let sent = sender.send_with(MAV, &Command::landing(true), short).await;
    let error = sent.expect_err("no status came");
    assert!(
        matches!(error, SendError::Timeout { heard: false, .. }),
        "{error:?}"
    );
    assert!(
        error
            .to_string()
            .ends_with(" (no valid frame has come from the radio since the link came up)"),
        "{error}"
    );
    let _ = fake.next_tx().await;
    // Once a frame came, a timeout does not say so.
    fake.send(&xbee_api::ModemStatusRepr {
        status: xbee_api::ModemStatus::CoordinatorStarted,
    })
    .await;
    let frames = sender.stats().frames;
    tokio::time::timeout(GUARD, async {
        while sender.stats().frames == frames {
            tokio::task::yield_now().await;
        }
    })
    .await
    .expect("the modem status read");
    let error = sender
        .send_with(MAV, &Command::landing(true), short)
        .await
        .expect_err("no status came");
    assert!(
        matches!(error, SendError::Timeout { heard: true, .. }),
        "{error:?}"
    );
}
