//! A set command confirmed by the MAV's report (`CommandSender::send_confirmed`),
//! against the simulated MAV behind the virtual network, and the MAV state machine's
//! reports confirming every command it takes.

mod common;

use std::time::Duration;

use futures::StreamExt;
use mcp_core::mav::Mav;
use mcp_core::{
    Address, Command, Controller, LandingState, Report, Slot, StatusRequest, TelemetryId,
    TrajectoryBuilder, Waypoint,
};
use mcp_host::record::Direction;
use mcp_host::sim::{SimVehicle, Simulator};
use mcp_host::{
    CommandSender, ConfirmError, DeliveryReport, FrameId, LinkOptions, PacketStream, SendError,
    SendOptions,
};
use proptest::prelude::*;
use xbee_api::{Address64, ApiMode, DeliveryStatus};

const MAV: Address64 = Address64(0x0013_A200_40B5_99B9);
/// Failure guard only: every wait ends on a frame long before this.
const GUARD: Duration = Duration::from_secs(20);

/// A ground station on a simulated network of one MAV (in flight, on its altitude
/// controller).
async fn ground() -> (Simulator, PacketStream, CommandSender) {
    let link = "tcp-listen:127.0.0.1:0".parse().unwrap();
    let sim = Simulator::start(
        &link,
        ApiMode::Unescaped,
        &[MAV],
        Simulator::network_config(),
    )
    .await
    .unwrap();
    let link = sim.ground_station_link().unwrap();
    let (stream, sender) = mcp_host::connect(&link, LinkOptions::default())
        .await
        .unwrap();
    (sim, stream, sender)
}

/// Answers the host's next Transmit Request on `radio`, which must hold `payload`,
/// with a delivery success.
async fn delivered(radio: &mut common::FakeXBee, payload: &[u8]) {
    let tx = radio.next_tx().await;
    assert_eq!(tx.data, payload);
    radio.status(tx.frame_id, DeliveryStatus::Success).await;
}

/// What the spawned `task` gave (failure guard: GUARD).
async fn outcome<T>(task: tokio::task::JoinHandle<T>) -> T {
    tokio::time::timeout(GUARD, task).await.unwrap().unwrap()
}

/// Asserts that `error` is [`ConfirmError::NotTaken`] with `report`.
fn assert_not_taken(error: &ConfirmError, report: Report<mcp_host::bytes::Bytes>) {
    assert!(
        matches!(error, ConfirmError::NotTaken { report: got, .. } if *got == report),
        "{error:?}"
    );
}

/// A trajectory set command of `waypoints`, as bytes.
fn trajectory(waypoints: &[Waypoint]) -> Vec<u8> {
    let mut buf = [0u8; mcp_core::MAX_PAYLOAD];
    let mut builder = TrajectoryBuilder::command(&mut buf).unwrap();
    for waypoint in waypoints {
        builder.push(*waypoint).unwrap();
    }
    let len = builder.finish();
    buf[..len].to_vec()
}

#[tokio::test]
async fn every_set_command_the_simulated_mav_takes_is_confirmed_by_its_report() {
    let (_sim, _stream, sender) = ground().await;
    let waypoints = [
        Waypoint {
            time: 10,
            elevator: 0.5,
            aileron: -0.25,
            altitude: 1.0,
        },
        Waypoint {
            time: 20,
            elevator: 1.0,
            aileron: 0.0,
            altitude: 1.5,
        },
    ];
    let trajectory = trajectory(&waypoints);
    let Ok(mcp_core::Packet::Command(trajectory)) = mcp_core::parse(&trajectory) else {
        panic!("a trajectory set command");
    };
    let slave = Address::from_u64(0x0013_A200_40B5_99BF);
    let commands: Vec<Command<&[u8]>> = vec![
        Command::telemetry_to_coordinator(true, TelemetryId::Altitude),
        Command::telemetry_to_coordinator(false, TelemetryId::Altitude),
        Command::controllers(Controller::Mpc),
        Command::controllers(Controller::Manual),
        Command::landing(true),
        Command::landing(false),
        trajectory,
        Command::position_slave_set(Some(Slot::new(2).unwrap()), slave),
        Command::position_slave_set(None, slave),
        Command::time(1_800_000_000),
    ];
    for command in commands {
        let confirmed = sender
            .send_confirmed(MAV, &command)
            .await
            .unwrap_or_else(|e| panic!("{command}: {e}"));
        assert!(
            matches!(confirmed.delivery, DeliveryReport::Delivered { .. }),
            "{command}: {:?}",
            confirmed.delivery
        );
        assert!(
            command.is_confirmed_by(&confirmed.report),
            "{command}: {}",
            confirmed.report
        );
        assert_eq!(
            Some(confirmed.report.report_type()),
            command.confirming_request().map(|r| r.command_type()),
        );
        // Printed whole: the delivery, then the report.
        let DeliveryReport::Delivered {
            frame_id, dst16, ..
        } = confirmed.delivery
        else {
            unreachable!()
        };
        assert_eq!(
            confirmed.to_string(),
            format!(
                "delivered (16-bit address {dst16}, frame id {frame_id}, retries 0, discovery \
                 no_discovery_overhead); report: {}",
                confirmed.report
            )
        );
    }
}

#[tokio::test]
async fn a_controller_the_mav_does_not_have_is_not_taken_and_the_report_says_which_is_active() {
    let (_sim, _stream, sender) = ground().await;
    let unknown = Command::controllers(Controller::from(0x09));
    match sender.send_confirmed(MAV, &unknown).await {
        Err(error) => {
            assert_eq!(
                error.to_string(),
                "the MAV did not take the command: it reports controllers altitude"
            );
            assert!(!error.is_timeout());
            assert!(!error.is_link_down());
            let ConfirmError::NotTaken { report, .. } = error else {
                panic!("{error:?}")
            };
            assert_eq!(report, Report::Controllers(Controller::Altitude));
        }
        other => panic!("{other:?}"),
    }
}

#[tokio::test]
async fn a_command_sent_fire_and_forget_is_confirmed_afterwards() {
    let (_sim, _stream, sender) = ground().await;
    let forget = SendOptions {
        frame_id: FrameId::None,
        ..SendOptions::default()
    };
    let land = Command::landing(true);
    let written = sender.send_with(MAV, &land, forget).await.unwrap();
    assert_eq!(written, DeliveryReport::Written);
    let report = sender.confirm(MAV, &land).await.unwrap();
    assert_eq!(report, Report::Landing(LandingState::Landing));
    // Asked again, a command the MAV did not take (it lands) is not confirmed.
    let error = sender
        .confirm(MAV, &Command::landing(false))
        .await
        .unwrap_err();
    assert_not_taken(&error, Report::Landing(LandingState::Landing));
}

#[tokio::test]
async fn a_command_that_cannot_be_confirmed_is_refused_and_not_sent() {
    let (_sim, _stream, sender) = ground().await;
    let mut frames = sender.tap_frames();
    for (to, command, said) in [
        (
            MAV,
            Command::position_set(0.5, 0.5),
            "a position_set command cannot be confirmed: it has no status request",
        ),
        (
            MAV,
            Command::status_request(StatusRequest::Landing),
            "a status request cannot be confirmed: send it with `request`",
        ),
        (
            Address64::BROADCAST,
            Command::landing(true),
            "a broadcast command cannot be confirmed",
        ),
    ] {
        let error = sender.send_confirmed(to, &command).await.unwrap_err();
        assert!(error.to_string().starts_with(said), "{error}");
        assert!(matches!(
            error,
            ConfirmError::Unconfirmable { .. } | ConfirmError::Broadcast
        ));
    }
    // Nothing went out: the first frame written is this status request.
    let report = sender.request(MAV, StatusRequest::Landing).await.unwrap();
    assert_eq!(report, Report::Landing(LandingState::Flight));
    let sent = loop {
        let record = tokio::time::timeout(GUARD, frames.next())
            .await
            .expect("a frame")
            .expect("the tap stays");
        if record.direction == Direction::Sent {
            break record.frame;
        }
    };
    assert!(sent.ends_with(b"c\x02\xff"), "{sent:02x?}");
}

#[tokio::test]
async fn a_trajectory_is_sent_and_confirmed_from_its_waypoints() {
    let (_sim, _stream, sender) = ground().await;
    let waypoints: Vec<Waypoint> = (0..3)
        .map(|i| Waypoint {
            time: 1_700_000_000 + i,
            elevator: 0.25 * i as f32,
            aileron: -0.5,
            altitude: 1.0 + i as f32,
        })
        .collect();
    let confirmed = sender
        .send_trajectory_confirmed(MAV, &waypoints)
        .await
        .unwrap();
    let Report::TrajectorySet(reported) = &confirmed.report else {
        panic!("{}", confirmed.report)
    };
    assert_eq!(reported.iter().collect::<Vec<_>>(), waypoints);
    // An empty one clears the trajectory, and is confirmed so.
    let cleared = sender.send_trajectory_confirmed(MAV, &[]).await.unwrap();
    assert!(
        matches!(&cleared.report, Report::TrajectorySet(w) if w.is_empty()),
        "{}",
        cleared.report
    );
    // 16 do not fit a payload: refused, nothing sent.
    let error = sender
        .send_trajectory_confirmed(MAV, &[waypoints[0]; 16])
        .await
        .unwrap_err();
    assert!(
        matches!(
            error,
            ConfirmError::Send(SendError::TooLarge { len, .. }) if len == Waypoint::packet_len(16)
        ),
        "{error:?}"
    );
}

#[tokio::test]
async fn a_command_on_a_link_closed_fails_as_the_link_being_down() {
    let (_sim, _stream, sender) = ground().await;
    sender.close();
    sender.closed().await;
    let error = sender
        .send_confirmed(MAV, &Command::landing(true))
        .await
        .unwrap_err();
    assert!(
        matches!(error, ConfirmError::Send(SendError::Closed)),
        "{error:?}"
    );
    assert!(error.is_link_down() && !error.is_timeout(), "{error:?}");
}

#[tokio::test]
async fn a_command_to_a_mav_not_there_fails_on_its_delivery() {
    let (_sim, _stream, sender) = ground().await;
    let absent = Address64(0x0013_A200_40B5_99BF);
    let error = sender
        .send_confirmed_with(
            absent,
            &Command::landing(true),
            Some(Duration::from_secs(5)),
        )
        .await
        .unwrap_err();
    match &error {
        ConfirmError::Send(SendError::Delivery { status, .. }) => {
            assert_ne!(*status, DeliveryStatus::Success);
        }
        other => panic!("{other:?}"),
    }
}

/// `command`'s bytes.
fn bytes(command: Command<&[u8]>) -> Vec<u8> {
    let mut buf = [0u8; mcp_core::MAX_PAYLOAD];
    let len = command.encode(&mut buf).unwrap();
    buf[..len].to_vec()
}

/// A set command the simulated vehicle takes (a known controller, at most as many
/// waypoints as it keeps), as bytes.
fn command() -> impl Strategy<Value = Vec<u8>> {
    let waypoint = (any::<u32>(), any::<f32>(), any::<f32>(), any::<f32>()).prop_map(
        |(time, elevator, aileron, altitude)| Waypoint {
            time,
            elevator,
            aileron,
            altitude,
        },
    );
    let controllers = vec![Controller::Manual, Controller::Altitude, Controller::Mpc];
    prop_oneof![
        (any::<bool>(), 0u8..0x21)
            .prop_map(|(on, id)| bytes(Command::telemetry_to_coordinator(on, id.into()))),
        any::<bool>().prop_map(|on| bytes(Command::landing(on))),
        prop::sample::select(controllers).prop_map(|c| bytes(Command::controllers(c))),
        prop::collection::vec(waypoint, 0..=2).prop_map(|w| trajectory(&w)),
        (prop::option::of(0u8..4), any::<u64>()).prop_map(|(slot, address)| {
            let slot = slot.map(|n| Slot::new(n).unwrap());
            bytes(Command::position_slave_set(
                slot,
                Address::from_u64(address),
            ))
        }),
        any::<u32>().prop_map(|t| bytes(Command::time(t))),
    ]
}

proptest! {
    /// Whatever state earlier commands left the simulated MAV in, a command it takes
    /// is confirmed by the report that answers the command's confirming request.
    #[test]
    fn the_simulated_mav_confirms_every_command_it_takes(
        earlier in prop::collection::vec(command(), 0..8),
        steps in prop::collection::vec(0u8..40, 0..8),
        last in command(),
    ) {
        let mut vehicle = SimVehicle::new(1_700_000_000);
        let mut mav = Mav::new(&vehicle);
        let mut reply = [0u8; mcp_core::MAX_PAYLOAD];
        for (i, bytes) in earlier.iter().enumerate() {
            let Ok(mcp_core::Packet::Command(command)) = mcp_core::parse(bytes) else {
                panic!("{bytes:02x?}");
            };
            mav.handle(&mut vehicle, &command, &mut reply).unwrap();
            // Time goes by between commands: landings end, take-offs stabilize.
            for _ in 0..steps.get(i).copied().unwrap_or(0) {
                vehicle.step(0.05);
            }
        }
        let Ok(mcp_core::Packet::Command(command)) = mcp_core::parse(&last) else {
            panic!("{last:02x?}");
        };
        mav.handle(&mut vehicle, &command, &mut reply).unwrap();
        let request = command.confirming_request().expect("a set command");
        let asked = Command::<&[u8]>::status_request(request);
        let len = mav.handle(&mut vehicle, &asked, &mut reply).unwrap().expect("a report");
        let Ok(mcp_core::Packet::Report(report)) = mcp_core::parse(&reply[..len]) else {
            panic!("{:02x?}", &reply[..len]);
        };
        prop_assert!(command.is_confirmed_by(&report), "{} -> {}", command, report);
    }
}

#[tokio::test]
async fn a_report_sent_before_the_command_was_taken_is_asked_past() {
    let (_stream, sender, mut radio) = common::pty_link(ApiMode::Unescaped).await;
    let confirming =
        tokio::spawn(async move { sender.send_confirmed(MAV, &Command::landing(true)).await });
    delivered(&mut radio, b"c\x02\x01").await;
    delivered(&mut radio, b"c\x02\xff").await;
    // A report of the state before (in flight), then, asked again, the landing.
    radio.receive(MAV, b"r\x02\x04").await;
    delivered(&mut radio, b"c\x02\xff").await;
    radio.receive(MAV, b"r\x02\x01").await;
    let confirmed = outcome(confirming).await.unwrap();
    assert_eq!(confirmed.report, Report::Landing(LandingState::Landing));
}

#[tokio::test]
async fn a_report_that_came_is_not_lost_to_a_later_request_that_fails() {
    let (_stream, sender, mut radio) = common::pty_link(ApiMode::Unescaped).await;
    let confirming = tokio::spawn(async move {
        let quick = Some(Duration::from_millis(300));
        sender
            .send_confirmed_with(MAV, &Command::landing(true), quick)
            .await
    });
    delivered(&mut radio, b"c\x02\x01").await;
    delivered(&mut radio, b"c\x02\xff").await;
    radio.receive(MAV, b"r\x02\x04").await;
    // Asked again: no report this time.
    delivered(&mut radio, b"c\x02\xff").await;
    let error = outcome(confirming).await.unwrap_err();
    assert_not_taken(&error, Report::Landing(LandingState::Flight));
}

#[tokio::test]
async fn a_time_report_is_held_to_the_seconds_since_the_command_went() {
    let (_stream, sender, mut radio) = common::pty_link(ApiMode::Unescaped).await;
    let sender = std::sync::Arc::new(sender);
    let set = 1_800_000_000u32;
    // A MAV whose clock runs 45 s ahead of the time set, and which did not take it.
    let ahead = [b"r\x06".as_slice(), &(set + 45).to_le_bytes()].concat();
    let time = Command::time(set);
    let mut command = [0u8; 8];
    let len = time.encode(&mut command).unwrap();
    let confirming = tokio::spawn({
        let sender = sender.clone();
        async move { sender.send_confirmed(MAV, &time).await }
    });
    delivered(&mut radio, &command[..len]).await;
    for _ in 0..3 {
        delivered(&mut radio, b"c\x06\xff").await;
        radio.receive(MAV, &ahead).await;
    }
    let error = outcome(confirming).await.unwrap_err();
    assert_not_taken(&error, Report::Time(set + 45));
    // Asked alone, not knowing when the command went: within the window.
    let confirming = tokio::spawn(async move { sender.confirm(MAV, &time).await });
    delivered(&mut radio, b"c\x06\xff").await;
    radio.receive(MAV, &ahead).await;
    let report = outcome(confirming).await.unwrap();
    assert_eq!(report, Report::Time(set + 45));
}

#[tokio::test]
async fn a_spec_form_slave_report_cannot_say_of_another_slot() {
    let (_stream, sender, mut radio) = common::pty_link(ApiMode::Unescaped).await;
    let slave = Address::from_u64(0x0013_A200_40B5_99BF);
    let set = Command::position_slave_set(Slot::new(2), slave);
    let mut command = [0u8; 16];
    let len = set.encode(&mut command).unwrap();
    let confirming = tokio::spawn(async move { sender.send_confirmed(MAV, &set).await });
    delivered(&mut radio, &command[..len]).await;
    delivered(&mut radio, b"c\x05\xff").await;
    radio
        .receive(MAV, b"r\x05\x00\x00\x00\x00\x00\x00\x00\x00")
        .await;
    let error = outcome(confirming).await.unwrap_err();
    assert!(
        matches!(error, ConfirmError::Unverifiable { .. }),
        "{error:?}"
    );
    assert_eq!(
        error.to_string(),
        "the MAV's report cannot say whether it took the command: it reports \
         position_slave_set 0000000000000000"
    );
}
