//! A set command confirmed by the MAV's report (`CommandSender::send_confirmed`),
//! against the simulated MAV behind the virtual network, and the MAV state machine's
//! reports confirming every command it takes.

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
    assert!(
        matches!(&error, ConfirmError::NotTaken { report, .. } if *report == Report::Landing(LandingState::Landing)),
        "{error:?}"
    );
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
