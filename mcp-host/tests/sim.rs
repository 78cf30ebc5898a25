//! Simulated MAVs behind the virtual network, driven by a ground station
//! (`mcp_host::connect`) over TCP and a pseudo-terminal.

use std::time::Duration;

use bytes::Bytes;
use futures::StreamExt;
use mcp_core::{
    Address, Command, Controller, LandingState, Packet, Report, SlaveAddresses, Slot,
    StatusRequest, TelemetryId, TrajectoryBuilder, Waypoint,
};
use mcp_host::radio::NetworkError;
use mcp_host::sim::{Simulator, fleet_addresses};
use mcp_host::{CommandSender, DeliveryReport, Event, Link, LinkOptions, PacketStream, SendError};
use xbee_api::{Address64, ApiMode, DeliveryStatus};

/// Failure guard only: every wait ends on a packet long before this.
const GUARD: Duration = Duration::from_secs(20);
const MAV: Address64 = Address64(0x0013_A200_40B5_99B9);

struct Ground {
    stream: PacketStream,
    sender: CommandSender,
    sim: Simulator,
}

async fn over_tcp(addresses: &[Address64]) -> Ground {
    let link: Link = "tcp-listen:127.0.0.1:0".parse().unwrap();
    let sim = Simulator::start(
        &link,
        ApiMode::Unescaped,
        addresses,
        Simulator::network_config(),
    )
    .await
    .unwrap();
    let addr = sim.coordinator().local_addr.unwrap();
    let link = sim.ground_station_link().unwrap();
    assert_eq!(link.to_string(), format!("tcp:{addr}"));
    let (stream, sender) = mcp_host::connect(&link, LinkOptions::default())
        .await
        .unwrap();
    Ground {
        stream,
        sender,
        sim,
    }
}

async fn over_pty(addresses: &[Address64], mode: ApiMode) -> Ground {
    let sim = Simulator::start(&Link::Pty, mode, addresses, Simulator::network_config())
        .await
        .unwrap();
    let path = sim.coordinator().pty_path.clone().unwrap();
    let link = sim.ground_station_link().unwrap();
    assert_eq!(link, Link::serial(path.display().to_string(), 115_200));
    let options = LinkOptions {
        api_mode: mode,
        ..LinkOptions::default()
    };
    let (stream, sender) = mcp_host::connect(&link, options).await.unwrap();
    Ground {
        stream,
        sender,
        sim,
    }
}

impl Ground {
    async fn send(&self, to: Address64, command: Command<&[u8]>) {
        let report = self.sender.send(to, &command).await.unwrap();
        let dst16 = self.sim.network().addr16(to).unwrap();
        assert!(
            matches!(report, DeliveryReport::Delivered { dst16: d, retries: 0, .. } if d == dst16),
            "{report:?}"
        );
    }

    async fn request(&self, to: Address64, request: StatusRequest) -> Report<Bytes> {
        self.sender
            .request_with(to, request, Some(GUARD))
            .await
            .unwrap()
    }

    /// The next packet from `from` on the stream.
    async fn packet(&mut self, from: Address64) -> mcp_host::OwnedPacket {
        tokio::time::timeout(GUARD, async {
            loop {
                match self.stream.next().await.expect("the stream goes on") {
                    Event::Packet(rx) if rx.origin.src64 == from => {
                        assert_eq!(rx.origin.options, 0x01);
                        return rx.packet;
                    }
                    Event::DecodeError(e) => panic!("decode error {e}"),
                    Event::InvalidPacket(p) => panic!("invalid packet {p:?}"),
                    _ => {}
                }
            }
        })
        .await
        .expect("a packet in time")
    }

    /// The next report from `from`, skipping telemetry.
    async fn report(&mut self, from: Address64) -> Report<Bytes> {
        loop {
            if let Packet::Report(report) = self.packet(from).await {
                return report;
            }
        }
    }

    /// Skips packets up to and including `report`.
    async fn until_report(&mut self, from: Address64, report: &Report<Bytes>) {
        while &self.report(from).await != report {}
    }

    /// The ids of the next telemetry packet.
    async fn telemetry_ids(&mut self, from: Address64) -> Vec<(TelemetryId, f32)> {
        loop {
            if let Packet::Telemetry(t) = self.packet(from).await {
                return t.iter().map(|r| (r.id, r.value)).collect();
            }
        }
    }
}

fn ids(records: &[(TelemetryId, f32)]) -> Vec<TelemetryId> {
    records.iter().map(|r| r.0).collect()
}

fn telemetry(on: bool, id: TelemetryId) -> Command<&'static [u8]> {
    Command::TelemetryToCoordinator { on, id }
}

#[tokio::test]
async fn telemetry_carries_exactly_the_enabled_ids_in_ascending_order() {
    let mut g = over_tcp(&[MAV]).await;
    use TelemetryId::*;
    for id in [PitchAngle, Altitude, EstimatedAltitude] {
        g.send(MAV, telemetry(true, id)).await;
    }
    let on = |id| Report::TelemetryToCoordinator { on: true, id };
    let off = |id| Report::TelemetryToCoordinator { on: false, id };
    assert_eq!(
        g.request(MAV, StatusRequest::TelemetryToCoordinator(Altitude))
            .await,
        on(Altitude)
    );
    assert_eq!(
        g.request(MAV, StatusRequest::TelemetryToCoordinator(RollAngle))
            .await,
        off(RollAngle)
    );
    // Every telemetry packet after that answer holds the three ids, ascending.
    g.until_report(MAV, &off(RollAngle)).await;
    for _ in 0..5 {
        let records = g.telemetry_ids(MAV).await;
        assert_eq!(ids(&records), [EstimatedAltitude, Altitude, PitchAngle]);
        assert!(
            (records[1].1 - 1.0).abs() < 0.1,
            "cruise altitude: {records:?}"
        );
    }

    g.send(MAV, telemetry(false, Altitude)).await;
    g.send(MAV, telemetry(true, TelemetryId::from(0x40))).await;
    assert_eq!(
        g.request(MAV, StatusRequest::TelemetryToCoordinator(Altitude))
            .await,
        off(Altitude)
    );
    g.until_report(MAV, &off(Altitude)).await;
    for _ in 0..5 {
        let records = g.telemetry_ids(MAV).await;
        assert_eq!(
            ids(&records),
            [EstimatedAltitude, PitchAngle, TelemetryId::from(0x40)]
        );
        assert_eq!(records[2].1, 0.0);
    }

    // All off: no telemetry after the answer, up to the next answers.
    for id in [EstimatedAltitude, PitchAngle, TelemetryId::from(0x40)] {
        g.send(MAV, telemetry(false, id)).await;
    }
    let last = off(TelemetryId::from(0x40));
    assert_eq!(
        g.request(
            MAV,
            StatusRequest::TelemetryToCoordinator(TelemetryId::from(0x40))
        )
        .await,
        last
    );
    g.until_report(MAV, &last).await;
    for _ in 0..5 {
        let report = g.request(MAV, StatusRequest::Landing).await;
        match g.packet(MAV).await {
            Packet::Report(r) => assert_eq!(r, report),
            other => panic!("expected the landing report, got {other:?}"),
        }
    }
}

#[tokio::test]
async fn landing_reports_follow_the_state_machine() {
    let mut g = over_tcp(&[MAV]).await;
    use LandingState::*;
    assert_eq!(
        g.request(MAV, StatusRequest::Landing).await,
        Report::Landing(Flight)
    );
    g.until_report(MAV, &Report::Landing(Flight)).await;
    g.send(MAV, Command::Landing { on: true }).await;
    assert_eq!(g.report(MAV).await, Report::Landing(Landing));
    assert_eq!(
        g.request(MAV, StatusRequest::Landing).await,
        Report::Landing(Landing)
    );
    assert_eq!(g.report(MAV).await, Report::Landing(Landing));
    // The descent ends on the ground, reported unsolicited.
    assert_eq!(g.report(MAV).await, Report::Landing(OnGround));
    g.send(MAV, Command::Landing { on: false }).await;
    assert_eq!(g.report(MAV).await, Report::Landing(TakeOff));
    assert_eq!(g.report(MAV).await, Report::Landing(Stabilization));
    assert_eq!(g.report(MAV).await, Report::Landing(Flight));
    assert_eq!(
        g.request(MAV, StatusRequest::Landing).await,
        Report::Landing(Flight)
    );
}

#[tokio::test]
async fn controllers_trajectory_time_and_slaves_are_answered() {
    let mut g = over_tcp(&[MAV]).await;

    // Controller: the change is reported unsolicited, an unknown id is refused.
    assert_eq!(
        g.request(MAV, StatusRequest::Controllers).await,
        Report::Controllers(Controller::Altitude)
    );
    g.until_report(MAV, &Report::Controllers(Controller::Altitude))
        .await;
    g.send(MAV, Command::Controllers(Controller::Mpc)).await;
    assert_eq!(g.report(MAV).await, Report::Controllers(Controller::Mpc));
    g.send(MAV, Command::Controllers(Controller::Unknown(9)))
        .await;
    assert_eq!(
        g.request(MAV, StatusRequest::Controllers).await,
        Report::Controllers(Controller::Mpc)
    );
    g.until_report(MAV, &Report::Controllers(Controller::Mpc))
        .await;

    // Trajectory set: answered at once by a trajectory report of the same waypoints.
    let waypoints: Vec<Waypoint> = (0..5)
        .map(|i| Waypoint {
            time: 2_000_000_000 + i,
            elevator: i as f32 * 0.5,
            aileron: -(i as f32),
            altitude: 1.0 + i as f32 * 0.1,
        })
        .collect();
    let mut buf = [0u8; mcp_core::MAX_PAYLOAD];
    let mut builder = TrajectoryBuilder::command(&mut buf).unwrap();
    waypoints.iter().for_each(|w| builder.push(*w).unwrap());
    let len = builder.finish();
    let Ok(Packet::Command(command)) = mcp_core::parse(&buf[..len]) else {
        panic!()
    };
    g.send(MAV, command).await;
    let Report::TrajectorySet(reported) = g.report(MAV).await else {
        panic!("not a trajectory report")
    };
    assert_eq!(reported.iter().collect::<Vec<_>>(), waypoints);
    let Report::TrajectorySet(asked) = g.request(MAV, StatusRequest::TrajectorySet).await else {
        panic!()
    };
    assert_eq!(asked.iter().collect::<Vec<_>>(), waypoints);

    // Time set: the clock runs from there.
    g.send(MAV, Command::Time(1_000_000)).await;
    let Report::Time(t) = g.request(MAV, StatusRequest::Time).await else {
        panic!()
    };
    assert!((1_000_000..1_000_060).contains(&t), "{t}");

    // Position slave set: firmware form into its slot, spec form into slot 0.
    let a = Address(*b"\x00\x13\xA2\x00\x40\xB5\x99\xBF");
    let b = Address(*b"\x00\x13\xA2\x00\x40\xB5\x99\xBD");
    g.send(
        MAV,
        Command::PositionSlaveSet {
            slot: Slot::new(2),
            address: a,
        },
    )
    .await;
    g.send(
        MAV,
        Command::PositionSlaveSet {
            slot: None,
            address: b,
        },
    )
    .await;
    assert_eq!(
        g.request(MAV, StatusRequest::PositionSlaveSet).await,
        Report::PositionSlaveSet(SlaveAddresses::Slots([
            b,
            Address::default(),
            a,
            Address::default()
        ]))
    );
}

#[tokio::test]
async fn position_set_moves_the_setpoints() {
    let mut g = over_tcp(&[MAV]).await;
    g.send(
        MAV,
        Command::PositionSet {
            elevator: 2.5,
            aileron: -1.5,
        },
    )
    .await;
    use TelemetryId::*;
    for id in [
        ElevatorPositionSetpoint,
        AileronPositionSetpoint,
        ElevatorShift,
    ] {
        g.send(MAV, telemetry(true, id)).await;
    }
    let on = Report::TelemetryToCoordinator {
        on: true,
        id: ElevatorShift,
    };
    assert_eq!(
        g.request(MAV, StatusRequest::TelemetryToCoordinator(ElevatorShift))
            .await,
        on
    );
    g.until_report(MAV, &on).await;
    let records = g.telemetry_ids(MAV).await;
    assert_eq!(
        records,
        [
            (ElevatorPositionSetpoint, 2.5),
            (AileronPositionSetpoint, -1.5),
            (ElevatorShift, 2.5)
        ]
    );
}

#[tokio::test]
async fn unknown_mav_gets_address_not_found() {
    let g = over_tcp(&[MAV]).await;
    let err = g
        .sender
        .send(
            Address64(0x0013_A200_0000_0001),
            &Command::status_request(StatusRequest::Time),
        )
        .await
        .unwrap_err();
    assert!(
        matches!(
            err,
            SendError::Delivery {
                status: DeliveryStatus::AddressNotFound,
                ..
            }
        ),
        "{err:?}"
    );
}

#[tokio::test]
async fn a_fleet_on_a_pseudo_terminal_in_api_mode_2() {
    let fleet = fleet_addresses(3);
    let mut g = over_pty(&fleet, ApiMode::Escaped).await;
    assert_eq!(g.sim.mavs().len(), 3);
    for &mav in &fleet {
        g.send(mav, Command::Time(1_234_567)).await;
        let Report::Time(t) = g.request(mav, StatusRequest::Time).await else {
            panic!()
        };
        assert!((1_234_567..1_234_627).contains(&t), "{t}");
    }
    // Telemetry from one MAV only.
    g.send(fleet[1], telemetry(true, TelemetryId::Altitude))
        .await;
    let records = g.telemetry_ids(fleet[1]).await;
    assert_eq!(ids(&records), [TelemetryId::Altitude]);
    g.send(fleet[2], Command::Landing { on: true }).await;
    assert_eq!(
        g.report(fleet[2]).await,
        Report::Landing(LandingState::Landing)
    );
}

#[tokio::test]
async fn every_table_id_fits_one_packet_with_fragmentation() {
    let mut g = over_tcp(&[MAV]).await;
    for &id in TelemetryId::ALL.iter().rev() {
        g.send(MAV, telemetry(true, id)).await;
    }
    let last = Report::TelemetryToCoordinator {
        on: true,
        id: TelemetryId::EstimatedAltitude,
    };
    let answer = g
        .request(
            MAV,
            StatusRequest::TelemetryToCoordinator(TelemetryId::EstimatedAltitude),
        )
        .await;
    assert_eq!(answer, last);
    g.until_report(MAV, &last).await;
    let records = g.telemetry_ids(MAV).await;
    assert_eq!(ids(&records), TelemetryId::ALL);
}

#[tokio::test]
async fn a_receive_buffer_limit_drops_long_commands() {
    use mcp_host::sim::{MAV_RX_BUFFER, SimOptions};
    let link: Link = "tcp-listen:127.0.0.1:0".parse().unwrap();
    let options = SimOptions {
        rx_buffer: Some(MAV_RX_BUFFER),
        ..SimOptions::default()
    };
    let sim = Simulator::start_with(
        &link,
        ApiMode::Unescaped,
        &[MAV],
        Simulator::network_config(),
        options,
    )
    .await
    .unwrap();
    let addr = sim.coordinator().local_addr.unwrap();
    let link = sim.ground_station_link().unwrap();
    assert_eq!(link.to_string(), format!("tcp:{addr}"));
    let (stream, sender) = mcp_host::connect(&link, LinkOptions::default())
        .await
        .unwrap();
    let g = Ground {
        stream,
        sender,
        sim,
    };
    // Two waypoints: a 35-byte payload, a 51-byte frame: kept.
    // Three waypoints: a 51-byte payload, a 67-byte frame: dropped by the MAV.
    for (count, kept) in [(2u32, 2usize), (3, 2)] {
        let mut buf = [0u8; mcp_core::MAX_PAYLOAD];
        let mut builder = TrajectoryBuilder::command(&mut buf).unwrap();
        for i in 0..count {
            let w = Waypoint {
                time: i,
                elevator: 0.0,
                aileron: 0.0,
                altitude: 1.0,
            };
            builder.push(w).unwrap();
        }
        let len = builder.finish();
        let Ok(Packet::Command(command)) = mcp_core::parse(&buf[..len]) else {
            panic!()
        };
        g.send(MAV, command).await;
        let Report::TrajectorySet(w) = g.request(MAV, StatusRequest::TrajectorySet).await else {
            panic!()
        };
        assert_eq!(w.len(), kept);
    }
}

#[tokio::test]
async fn the_ground_station_link_of_a_coordinator_on_every_interface_is_loopback() {
    let link = Link::tcp_listen("0.0.0.0", 0);
    let sim = Simulator::start(
        &link,
        ApiMode::Unescaped,
        &[MAV],
        Simulator::network_config(),
    )
    .await
    .unwrap();
    let port = sim.coordinator().local_addr.unwrap().port();
    let link = sim.ground_station_link().unwrap();
    assert_eq!(link, Link::tcp("127.0.0.1", port));
    let (_stream, sender) = mcp_host::connect(&link, LinkOptions::default())
        .await
        .unwrap();
    let report = tokio::time::timeout(GUARD, sender.request(MAV, StatusRequest::Landing))
        .await
        .unwrap();
    assert!(matches!(report, Ok(Report::Landing(_))), "{report:?}");
    sim.stop().await;

    // A coordinator that connects out has its ground station elsewhere.
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let out = Link::from(listener.local_addr().unwrap());
    let sim = Simulator::start(
        &out,
        ApiMode::Unescaped,
        &[MAV],
        Simulator::network_config(),
    )
    .await
    .unwrap();
    assert_eq!(sim.ground_station_link(), None);
    sim.stop().await;
    drop(listener);
}

#[tokio::test]
async fn a_dropped_ground_station_link_comes_back_to_mavs_that_kept_their_state() {
    let mut g = over_tcp(&[MAV]).await;
    g.send(MAV, Command::Controllers(Controller::Mpc)).await;
    assert_eq!(g.report(MAV).await, Report::Controllers(Controller::Mpc));
    let coordinator = g.sim.coordinator().addr64;
    assert!(g.sim.network().disconnect(coordinator));
    // The ground station sees its link drop and come back (its `tcp:` link reconnects
    // to the coordinator's `tcp-listen:` port, which takes it again).
    let events = tokio::time::timeout(GUARD, async {
        let mut seen = Vec::new();
        while let Some(event) = g.stream.next().await {
            if let Event::Link(link) = event {
                let back = matches!(link, mcp_host::LinkEvent::Reconnected { .. });
                seen.push(link);
                if back {
                    break;
                }
            }
        }
        seen
    })
    .await
    .expect("the link comes back");
    assert!(
        matches!(
            &events[..],
            [
                mcp_host::LinkEvent::Disconnected { .. },
                mcp_host::LinkEvent::Reconnected { .. }
            ]
        ),
        "{events:?}"
    );
    // The MAV flew on: its controller is the one set before.
    assert_eq!(
        g.request(MAV, StatusRequest::Controllers).await,
        Report::Controllers(Controller::Mpc)
    );
    // Unknown nodes, and links that are not up, are not hung up on.
    assert!(!g.sim.network().disconnect(Address64(0x1234)));
}

#[tokio::test]
async fn a_mav_added_while_running_flies_like_the_others() {
    let fleet = fleet_addresses(2);
    let mut g = over_tcp(&fleet[..1]).await;
    g.send(fleet[0], Command::Controllers(Controller::Mpc))
        .await;
    let info = g.sim.add_mav(fleet[1]).unwrap();
    assert_eq!(info.addr64, fleet[1]);
    assert_eq!(
        g.sim.mavs().iter().map(|m| m.addr64).collect::<Vec<_>>(),
        fleet
    );
    // It takes commands and sends telemetry; the first MAV keeps its state.
    g.send(fleet[1], telemetry(true, TelemetryId::Altitude))
        .await;
    assert_eq!(
        ids(&g.telemetry_ids(fleet[1]).await),
        [TelemetryId::Altitude]
    );
    g.send(fleet[1], Command::Controllers(Controller::Altitude))
        .await;
    assert_eq!(
        g.request(fleet[1], StatusRequest::Controllers).await,
        Report::Controllers(Controller::Altitude)
    );
    assert_eq!(
        g.request(fleet[0], StatusRequest::Controllers).await,
        Report::Controllers(Controller::Mpc)
    );
    // An address taken, by a MAV or by the coordinator, and the broadcast address are
    // refused, and the fleet stays as it was.
    for address in [fleet[0], Address64::COORDINATOR] {
        assert!(matches!(g.sim.add_mav(address), Err(NetworkError::Duplicate(a)) if a == address));
    }
    assert!(matches!(
        g.sim.add_mav(Address64::BROADCAST),
        Err(NetworkError::Broadcast(_))
    ));
    assert_eq!(g.sim.mavs().len(), 2);
    g.sim.stop().await;
}
