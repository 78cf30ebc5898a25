//! The MAV state machine behaves like the deployed MAV.

use mcp_core::{
    Address, BufferTooSmall, Command, Controller, LandingState, Packet, Report, SlaveAddresses,
    Slot, StatusRequest, TelemetryId, Waypoint, Waypoints,
    mav::{Mav, Vehicle},
    parse,
};

/// A simulated vehicle recording what the commands did.
#[derive(Debug, Default)]
struct Sim {
    landing: Option<LandingState>,
    controller: Option<Controller>,
    time: u32,
    position: Option<(f32, f32)>,
    trajectory: Vec<Waypoint>,
    slaves: Vec<(Slot, Address)>,
}

impl Sim {
    fn flying() -> Self {
        Sim {
            landing: Some(LandingState::Flight),
            controller: Some(Controller::Manual),
            ..Sim::default()
        }
    }
}

impl Vehicle for Sim {
    fn landing_state(&self) -> LandingState {
        self.landing.unwrap_or(LandingState::OnGround)
    }
    fn set_landing(&mut self, on: bool) {
        self.landing = Some(if on {
            LandingState::Landing
        } else {
            LandingState::Flight
        });
    }
    fn controller(&self) -> Controller {
        self.controller.unwrap_or(Controller::Manual)
    }
    fn set_controller(&mut self, controller: Controller) {
        self.controller = Some(controller);
    }
    fn time(&self) -> u32 {
        self.time
    }
    fn set_time(&mut self, time: u32) {
        self.time = time;
    }
    fn set_position(&mut self, elevator: f32, aileron: f32) {
        self.position = Some((elevator, aileron));
    }
    fn telemetry(&self, id: TelemetryId) -> f32 {
        f32::from(u8::from(id)) + 0.5
    }
    fn set_trajectory(&mut self, waypoints: Waypoints<&[u8]>) {
        self.trajectory = waypoints.iter().collect();
    }
    fn waypoint(&self, index: usize) -> Option<Waypoint> {
        self.trajectory.get(index).copied()
    }
    fn set_slave(&mut self, slot: Slot, address: Address) {
        self.slaves.push((slot, address));
    }
}

/// Parses and handles one command, returning the direct reply.
fn send(mav: &mut Mav, sim: &mut Sim, bytes: &[u8]) -> Option<Vec<u8>> {
    let Ok(Packet::Command(command)) = parse(bytes) else {
        panic!("not a command: {bytes:02x?}");
    };
    let mut buf = [0u8; 255];
    mav.handle(sim, &command, &mut buf)
        .unwrap()
        .map(|len| buf[..len].to_vec())
}

fn poll(mav: &mut Mav, sim: &Sim) -> Option<Vec<u8>> {
    let mut buf = [0u8; 255];
    mav.poll_changes(sim, &mut buf)
        .unwrap()
        .map(|len| buf[..len].to_vec())
}

fn telemetry(mav: &mut Mav, sim: &Sim) -> Option<Vec<u8>> {
    let mut buf = [0u8; 255];
    mav.telemetry(sim, &mut buf)
        .unwrap()
        .map(|len| buf[..len].to_vec())
}

fn ids_in(packet: &[u8]) -> Vec<u8> {
    let Ok(Packet::Telemetry(t)) = parse(packet) else {
        panic!("not telemetry: {packet:02x?}");
    };
    t.iter().map(|r| u8::from(r.id)).collect()
}

#[test]
fn telemetry_without_room_for_one_record_is_an_error_not_an_empty_packet() {
    let mut sim = Sim::flying();
    let mut mav = Mav::new(&sim);
    send(&mut mav, &mut sim, b"c\x01\x01\x05");
    let mut small = [0u8; 5];
    assert_eq!(
        mav.telemetry(&sim, &mut small),
        Err(BufferTooSmall {
            needed: 6,
            available: 5
        })
    );
    let mut enough = [0u8; 6];
    assert_eq!(mav.telemetry(&sim, &mut enough), Ok(Some(6)));
}

#[test]
fn no_telemetry_is_sent_when_none_is_enabled() {
    let sim = Sim::flying();
    let mut mav = Mav::new(&sim);
    assert_eq!(telemetry(&mut mav, &sim), None);
}

#[test]
fn telemetry_to_coordinator_enables_ids_and_reports_them() {
    let mut sim = Sim::flying();
    let mut mav = Mav::new(&sim);
    assert_eq!(send(&mut mav, &mut sim, b"c\x01\x01\x19"), None);
    assert_eq!(send(&mut mav, &mut sim, b"c\x01\x07\xf0"), None);
    assert_eq!(send(&mut mav, &mut sim, b"c\x01\x01\x01"), None);
    // Ascending id order, values from the vehicle.
    let packet = telemetry(&mut mav, &sim).unwrap();
    assert_eq!(ids_in(&packet), [0x01, 0x19, 0xF0]);
    let Ok(Packet::Telemetry(t)) = parse(&packet) else {
        unreachable!()
    };
    assert_eq!(t.value(TelemetryId::PitchAngle), Some(25.5));

    assert_eq!(
        send(&mut mav, &mut sim, b"c\x01\xff\x19").unwrap(),
        b"r\x01\x01\x19"
    );
    assert_eq!(send(&mut mav, &mut sim, b"c\x01\x00\x19"), None);
    assert_eq!(
        send(&mut mav, &mut sim, b"c\x01\xff\x19").unwrap(),
        b"r\x01\x00\x19"
    );
    assert_eq!(ids_in(&telemetry(&mut mav, &sim).unwrap()), [0x01, 0xF0]);
    assert_eq!(mav.enabled().len(), 2);
}

#[test]
fn telemetry_past_the_payload_limit_goes_on_in_the_next_packets() {
    let mut sim = Sim::flying();
    let mut mav = Mav::new(&sim);
    for id in 0..=255u8 {
        send(&mut mav, &mut sim, &[b'c', 0x01, 0x01, id]);
    }
    assert_eq!(mav.enabled().len(), 256);
    // 50 records a packet: 0-49, 50-99, ..., 250-255, then 0-49 again.
    for first in [0u8, 50, 100, 150, 200, 250, 0] {
        let packet = telemetry(&mut mav, &sim).unwrap();
        let last = first.saturating_add(49);
        assert_eq!(ids_in(&packet), (first..=last).collect::<Vec<u8>>());
        assert_eq!(packet.len(), 1 + (usize::from(last - first) + 1) * 5);
    }
    // Ids disabled meanwhile are not waited for: past the last one enabled, the next
    // packet starts from the lowest again.
    let packet = telemetry(&mut mav, &sim).unwrap();
    assert_eq!(ids_in(&packet)[0], 50);
    for id in 100..=255u8 {
        send(&mut mav, &mut sim, &[b'c', 0x01, 0x00, id]);
    }
    assert_eq!(
        ids_in(&telemetry(&mut mav, &sim).unwrap()),
        (0..50).collect::<Vec<u8>>()
    );
    assert_eq!(
        ids_in(&telemetry(&mut mav, &sim).unwrap()),
        (50..100).collect::<Vec<u8>>()
    );
}

proptest::proptest! {
    /// However many ids are enabled and whatever the buffer, every enabled id is sent
    /// within as many packets as a round takes, each packet in ascending order.
    #[test]
    fn every_enabled_id_is_sent_within_a_round(
        ids in proptest::collection::btree_set(proptest::prelude::any::<u8>(), 1..=256),
        buf_len in 6usize..=300,
    ) {
        let sim = Sim::flying();
        let mut mav = Mav::new(&sim);
        for id in &ids {
            mav.enabled_mut().insert(TelemetryId::from(*id));
        }
        let per_packet = ((buf_len.min(255) - 1) / 5).max(1);
        let round = ids.len().div_ceil(per_packet);
        let mut sent = std::collections::BTreeSet::new();
        let mut buf = vec![0u8; buf_len];
        for _ in 0..round {
            let len = mav.telemetry(&sim, &mut buf).unwrap().unwrap();
            let packet = ids_in(&buf[..len]);
            proptest::prop_assert!(packet.windows(2).all(|w| w[0] < w[1]), "{packet:?}");
            sent.extend(packet);
        }
        proptest::prop_assert_eq!(sent, ids);
    }
}

#[test]
fn landing_change_is_reported_unsolicited() {
    let mut sim = Sim::flying();
    let mut mav = Mav::new(&sim);
    assert_eq!(poll(&mut mav, &sim), None);
    assert_eq!(send(&mut mav, &mut sim, b"c\x02\x01"), None);
    assert_eq!(poll(&mut mav, &sim).unwrap(), b"r\x02\x01");
    assert_eq!(poll(&mut mav, &sim), None);
    // The vehicle finishes landing on its own.
    sim.landing = Some(LandingState::OnGround);
    assert_eq!(poll(&mut mav, &sim).unwrap(), b"r\x02\x00");
    assert_eq!(poll(&mut mav, &sim), None);
    // Status request.
    assert_eq!(
        send(&mut mav, &mut sim, b"c\x02\xff").unwrap(),
        b"r\x02\x00"
    );
}

#[test]
fn controller_change_is_reported_unsolicited() {
    let mut sim = Sim::flying();
    let mut mav = Mav::new(&sim);
    // Same controller: no change, no report.
    assert_eq!(send(&mut mav, &mut sim, b"c\x03\x01"), None);
    assert_eq!(poll(&mut mav, &sim), None);
    assert_eq!(send(&mut mav, &mut sim, b"c\x03\x03"), None);
    assert_eq!(sim.controller, Some(Controller::Mpc));
    assert_eq!(poll(&mut mav, &sim).unwrap(), b"r\x03\x03");
    assert_eq!(poll(&mut mav, &sim), None);
    assert_eq!(
        send(&mut mav, &mut sim, b"c\x03\xff").unwrap(),
        b"r\x03\x03"
    );
}

#[test]
fn a_state_answered_is_not_reported_again_as_a_change() {
    let mut sim = Sim::flying();
    let mut mav = Mav::new(&sim);
    sim.landing = Some(LandingState::Landing);
    sim.controller = Some(Controller::Altitude);
    // Asked before the main loop polled: the answer tells the new landing state...
    assert_eq!(
        send(&mut mav, &mut sim, b"c\x02\xff").unwrap(),
        b"r\x02\x01"
    );
    // ...so only the controller change is still to report; then the controller asked.
    assert_eq!(poll(&mut mav, &sim).unwrap(), b"r\x03\x02");
    assert_eq!(poll(&mut mav, &sim), None);
    sim.controller = Some(Controller::Mpc);
    assert_eq!(
        send(&mut mav, &mut sim, b"c\x03\xff").unwrap(),
        b"r\x03\x03"
    );
    assert_eq!(poll(&mut mav, &sim), None);
}

#[test]
fn both_changes_are_reported_landing_first() {
    let mut sim = Sim::flying();
    let mut mav = Mav::new(&sim);
    sim.landing = Some(LandingState::TakeOff);
    sim.controller = Some(Controller::Altitude);
    assert_eq!(poll(&mut mav, &sim).unwrap(), b"r\x02\x03");
    assert_eq!(poll(&mut mav, &sim).unwrap(), b"r\x03\x02");
    assert_eq!(poll(&mut mav, &sim), None);
}

#[test]
fn a_change_stays_pending_when_the_buffer_is_too_small() {
    let mut sim = Sim::flying();
    let mut mav = Mav::new(&sim);
    sim.landing = Some(LandingState::OnGround);
    let mut small = [0u8; 2];
    assert!(mav.poll_changes(&sim, &mut small).is_err());
    assert_eq!(poll(&mut mav, &sim).unwrap(), b"r\x02\x00");
}

#[test]
fn trajectory_set_is_answered_at_once_with_a_report() {
    let mut sim = Sim::flying();
    let mut mav = Mav::new(&sim);
    let w = [
        Waypoint {
            time: 10,
            elevator: 1.0,
            aileron: 2.0,
            altitude: 3.0,
        },
        Waypoint {
            time: 20,
            elevator: -1.0,
            aileron: -2.0,
            altitude: 1.5,
        },
    ];
    let mut command = vec![b'c', 0x04, 0x02];
    command.extend(w.iter().flat_map(Waypoint::to_bytes));
    let reply = send(&mut mav, &mut sim, &command).unwrap();
    let mut expected = command.clone();
    expected[0] = b'r';
    assert_eq!(reply, expected);
    assert_eq!(sim.trajectory, w);
    // The status request gets the same report.
    assert_eq!(send(&mut mav, &mut sim, b"c\x04\xff").unwrap(), expected);
    // An empty trajectory.
    assert_eq!(
        send(&mut mav, &mut sim, b"c\x04\x00").unwrap(),
        b"r\x04\x00"
    );
}

#[test]
fn trajectory_report_holds_what_fits_the_payload() {
    let mut sim = Sim::flying();
    let mav = &mut Mav::new(&sim);
    sim.trajectory = vec![Waypoint::default(); 40];
    let reply = send(mav, &mut sim, b"c\x04\xff").unwrap();
    assert_eq!(reply.len(), 3 + 15 * 16);
    assert_eq!(reply[2], 15);
    assert!(parse(&reply).is_ok());
}

#[test]
fn position_slave_set_keeps_four_slots() {
    let mut sim = Sim::flying();
    let mut mav = Mav::new(&sim);
    let a = Address::from(0x0013_A200_40B5_99B9);
    let b = Address::from(0x0013_A200_40B5_99BD);
    // Spec form writes slot 0.
    let mut spec = vec![b'c', 0x05];
    spec.extend_from_slice(&a.0);
    assert_eq!(send(&mut mav, &mut sim, &spec), None);
    // Firmware form writes its slot.
    let mut firmware = vec![b'c', 0x05, 0x02];
    firmware.extend_from_slice(&b.0);
    assert_eq!(send(&mut mav, &mut sim, &firmware), None);
    let zero = Address::default();
    assert_eq!(mav.slaves(), [a, zero, b, zero]);
    assert_eq!(
        sim.slaves,
        [(Slot::new(0).unwrap(), a), (Slot::new(2).unwrap(), b)]
    );
    let reply = send(&mut mav, &mut sim, b"c\x05\xff").unwrap();
    assert_eq!(reply.len(), 34);
    assert_eq!(
        parse(&reply).unwrap(),
        Packet::Report(Report::PositionSlaveSet(SlaveAddresses::Slots([
            a, zero, b, zero
        ])))
    );
}

#[test]
fn a_mav_with_the_spec_slave_report_answers_with_slot_0_in_10_bytes() {
    let mut sim = Sim::flying();
    let mut mav = Mav::new(&sim).with_spec_slave_report();
    let a = Address::from(0x0013_A200_40B5_99B9);
    let b = Address::from(0x0013_A200_40B5_99BD);
    let mut spec = vec![b'c', 0x05];
    spec.extend_from_slice(&a.0);
    assert_eq!(send(&mut mav, &mut sim, &spec), None);
    let mut firmware = vec![b'c', 0x05, 0x01];
    firmware.extend_from_slice(&b.0);
    assert_eq!(send(&mut mav, &mut sim, &firmware), None);
    // The slots are kept as before; only the answer's form changes.
    let zero = Address::default();
    assert_eq!(mav.slaves(), [a, b, zero, zero]);
    let reply = send(&mut mav, &mut sim, b"c\x05\xff").unwrap();
    let mut expected = vec![b'r', 0x05];
    expected.extend_from_slice(&a.0);
    assert_eq!(reply, expected);
    assert_eq!(
        parse(&reply).unwrap(),
        Packet::Report(Report::PositionSlaveSet(SlaveAddresses::Single(a)))
    );
}

#[test]
fn time_and_position_set_get_no_reply() {
    let mut sim = Sim::flying();
    let mut mav = Mav::new(&sim);
    assert_eq!(send(&mut mav, &mut sim, b"c\x06\x00\xf1\x53\x65"), None);
    assert_eq!(sim.time, 1_700_000_000);
    assert_eq!(
        send(&mut mav, &mut sim, b"c\x06\xff").unwrap(),
        b"r\x06\x00\xf1\x53\x65"
    );
    assert_eq!(
        send(&mut mav, &mut sim, b"c\x07\x00\x00\xc0\x3f\x00\x00\x10\xc0"),
        None
    );
    assert_eq!(sim.position, Some((1.5, -2.25)));
    assert_eq!(poll(&mut mav, &sim), None);
}

#[test]
fn only_commands_are_handled() {
    let mut sim = Sim::flying();
    let mut mav = Mav::new(&sim);
    let mut buf = [0u8; 255];
    for bytes in [
        &b"m hello"[..],
        b"w\xff",
        b"r\x02\x01",
        b"t\x01\x00\x00\x00\x00",
    ] {
        let p = parse(bytes).unwrap();
        assert_eq!(mav.handle_packet(&mut sim, &p, &mut buf), Ok(None));
    }
    let p = parse(b"c\x06\xff").unwrap();
    assert_eq!(mav.handle_packet(&mut sim, &p, &mut buf), Ok(Some(6)));
    assert_eq!(sim.landing, Some(LandingState::Flight));
}

#[test]
fn a_reply_that_does_not_fit_is_an_error_but_the_command_is_done() {
    let mut sim = Sim::flying();
    let mut mav = Mav::new(&sim);
    let command: Command<&[u8]> = Command::TrajectorySet(Waypoints::new_unchecked(&[0u8; 16]));
    let mut small = [0u8; 2];
    assert!(mav.handle(&mut sim, &command, &mut small).is_err());
    assert_eq!(sim.trajectory.len(), 1);
    let status = Command::status_request(StatusRequest::Time);
    assert!(mav.handle(&mut sim, &status, &mut small).is_err());
}

#[test]
fn the_vehicle_trait_is_object_safe() {
    let mut sim = Sim::flying();
    let vehicle: &mut dyn Vehicle = &mut sim;
    let mut mav = Mav::new(vehicle);
    let mut buf = [0u8; 8];
    let command = Command::landing(true);
    assert_eq!(mav.handle(vehicle, &command, &mut buf), Ok(None));
    assert_eq!(mav.poll_changes(vehicle, &mut buf), Ok(Some(3)));
}

/// A vehicle with no position control and no trajectory: the required methods alone.
struct Hover;

impl Vehicle for Hover {
    fn landing_state(&self) -> LandingState {
        LandingState::Flight
    }
    fn set_landing(&mut self, _on: bool) {}
    fn controller(&self) -> Controller {
        Controller::Manual
    }
    fn set_controller(&mut self, _controller: Controller) {}
    fn time(&self) -> u32 {
        0
    }
    fn set_time(&mut self, _time: u32) {}
    fn telemetry(&self, _id: TelemetryId) -> f32 {
        0.0
    }
}

#[test]
fn a_vehicle_without_trajectories_reports_an_empty_one() {
    let mut hover = Hover;
    let mut mav = Mav::new(&hover);
    let mut reply = |bytes: &[u8]| {
        let Ok(Packet::Command(command)) = parse(bytes) else {
            panic!("not a command: {bytes:02x?}");
        };
        let mut buf = [0u8; 255];
        mav.handle(&mut hover, &command, &mut buf)
            .unwrap()
            .map(|len| buf[..len].to_vec())
    };
    // A trajectory of one waypoint: none was kept, and the report says so.
    let mut set = vec![b'c', 0x04, 0x01];
    set.extend(Waypoint::default().to_bytes());
    assert_eq!(reply(&set).unwrap(), b"r\x04\x00");
    assert_eq!(reply(b"c\x04\xff").unwrap(), b"r\x04\x00");
    // Position set: no reply, nothing to do.
    let mut position = vec![b'c', 0x07];
    position.extend(1.5f32.to_le_bytes());
    position.extend(2.5f32.to_le_bytes());
    assert_eq!(reply(&position), None);
}
