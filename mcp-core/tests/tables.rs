//! Every packet table of the specification (tables 3 to 24): the bytes parse to the
//! typed value, and the typed value encodes to the same bytes.

use mcp_core::{
    Address, Command, Controller, LandingState, Packet, Report, SlaveAddresses, StatusRequest,
    Telemetry, TelemetryId, Text, Waypoint, Waypoints, parse,
};

/// Parses `bytes`, checks the value, encodes it again and checks the bytes.
fn check(bytes: &[u8], expected: Packet<&[u8]>) {
    let parsed = parse(bytes).unwrap_or_else(|e| panic!("{bytes:02x?}: {e}"));
    assert_eq!(parsed, expected, "parse {bytes:02x?}");
    assert_eq!(expected.encoded_len(), bytes.len());
    let mut buf = [0u8; 300];
    let len = expected.encode(&mut buf).unwrap();
    assert_eq!(&buf[..len], bytes, "encode {expected:?}");
}

fn command(c: Command<&[u8]>) -> Packet<&[u8]> {
    Packet::Command(c)
}

fn report(r: Report<&[u8]>) -> Packet<&[u8]> {
    Packet::Report(r)
}

const MAV: [u8; 8] = [0x00, 0x13, 0xA2, 0x00, 0x40, 0xB5, 0x99, 0xB9];

fn waypoint_bytes(w: &Waypoint) -> [u8; 16] {
    let mut out = [0; 16];
    out[0..4].copy_from_slice(&w.time.to_le_bytes());
    out[4..8].copy_from_slice(&w.elevator.to_le_bytes());
    out[8..12].copy_from_slice(&w.aileron.to_le_bytes());
    out[12..16].copy_from_slice(&w.altitude.to_le_bytes());
    out
}

const WP1: Waypoint = Waypoint {
    time: 1_700_000_000,
    elevator: 1.5,
    aileron: -2.25,
    altitude: 1.0,
};
const WP2: Waypoint = Waypoint {
    time: 1_700_000_010,
    elevator: 0.0,
    aileron: 0.5,
    altitude: 2.75,
};

#[test]
fn table_03_telemetry_to_coordinator_command() {
    check(
        &[0x63, 0x01, 0x01, 0x00],
        command(Command::TelemetryToCoordinator {
            on: true,
            id: TelemetryId::EstimatedAltitude,
        }),
    );
    check(
        &[0x63, 0x01, 0x00, 0x20],
        command(Command::TelemetryToCoordinator {
            on: false,
            id: TelemetryId::AileronAccelerationError,
        }),
    );
}

#[test]
fn table_04_telemetry_to_coordinator_status_request() {
    check(
        &[0x63, 0x01, 0xFF, 0x1A],
        command(Command::StatusRequest(
            StatusRequest::TelemetryToCoordinator(TelemetryId::RollAngle),
        )),
    );
}

#[test]
fn table_05_landing_command() {
    check(&[0x63, 0x02, 0x01], command(Command::Landing { on: true }));
    check(&[0x63, 0x02, 0x00], command(Command::Landing { on: false }));
}

#[test]
fn table_06_landing_status_request() {
    check(
        &[0x63, 0x02, 0xFF],
        command(Command::StatusRequest(StatusRequest::Landing)),
    );
}

#[test]
fn table_07_controllers_command() {
    check(
        &[0x63, 0x03, 0x01],
        command(Command::Controllers(Controller::Manual)),
    );
    check(
        &[0x63, 0x03, 0x02],
        command(Command::Controllers(Controller::Altitude)),
    );
    check(
        &[0x63, 0x03, 0x03],
        command(Command::Controllers(Controller::Mpc)),
    );
    check(
        &[0x63, 0x03, 0xFE],
        command(Command::Controllers(Controller::Unknown(0xFE))),
    );
}

#[test]
fn table_08_controllers_status_request() {
    check(
        &[0x63, 0x03, 0xFF],
        command(Command::StatusRequest(StatusRequest::Controllers)),
    );
}

#[test]
fn table_09_trajectory_set_command() {
    let mut bytes = vec![0x63, 0x04, 0x02];
    bytes.extend_from_slice(&waypoint_bytes(&WP1));
    bytes.extend_from_slice(&waypoint_bytes(&WP2));
    // Table 9's field offsets: time at bytes 4-7, altitude of the second at 32-35.
    assert_eq!(&bytes[3..7], &1_700_000_000u32.to_le_bytes());
    assert_eq!(&bytes[31..35], &2.75f32.to_le_bytes());
    let expected = command(Command::TrajectorySet(Waypoints::new_unchecked(
        &bytes[3..],
    )));
    check(&bytes, expected);
    let Ok(Packet::Command(Command::TrajectorySet(w))) = parse(&bytes) else {
        panic!("not a trajectory set");
    };
    assert_eq!(w.size(), 2);
    assert_eq!(w.iter().collect::<Vec<_>>(), [WP1, WP2]);
}

#[test]
fn table_10_trajectory_set_status_request() {
    check(
        &[0x63, 0x04, 0xFF],
        command(Command::StatusRequest(StatusRequest::TrajectorySet)),
    );
}

#[test]
fn table_11_position_slave_set_command() {
    let mut bytes = vec![0x63, 0x05];
    bytes.extend_from_slice(&MAV);
    check(
        &bytes,
        command(Command::PositionSlaveSet {
            slot: None,
            address: Address(MAV),
        }),
    );
}

#[test]
fn table_12_position_slave_set_status_request() {
    check(
        &[0x63, 0x05, 0xFF],
        command(Command::StatusRequest(StatusRequest::PositionSlaveSet)),
    );
}

#[test]
fn table_13_time_command() {
    let mut bytes = vec![0x63, 0x06];
    bytes.extend_from_slice(&1_700_000_000u32.to_le_bytes());
    assert_eq!(bytes, [0x63, 0x06, 0x00, 0xF1, 0x53, 0x65]);
    check(&bytes, command(Command::Time(1_700_000_000)));
}

#[test]
fn table_14_time_status_request() {
    check(
        &[0x63, 0x06, 0xFF],
        command(Command::StatusRequest(StatusRequest::Time)),
    );
}

#[test]
fn table_15_position_set_command() {
    // 1.5 = 0x3FC00000, -2.25 = 0xC0100000, little-endian.
    check(
        &[0x63, 0x07, 0x00, 0x00, 0xC0, 0x3F, 0x00, 0x00, 0x10, 0xC0],
        command(Command::PositionSet {
            elevator: 1.5,
            aileron: -2.25,
        }),
    );
}

#[test]
fn table_16_telemetry_packet() {
    let bytes = [
        0x74, 0x00, 0x00, 0x00, 0xC0, 0x3F, 0x19, 0x00, 0x00, 0x80, 0xBE,
    ];
    check(
        &bytes,
        Packet::Telemetry(Telemetry::new_unchecked(&bytes[1..])),
    );
    let Ok(Packet::Telemetry(t)) = parse(&bytes) else {
        panic!("not telemetry");
    };
    let records: Vec<_> = t.iter().map(|r| (r.id, r.value)).collect();
    assert_eq!(
        records,
        [
            (TelemetryId::EstimatedAltitude, 1.5),
            (TelemetryId::PitchAngle, -0.25)
        ]
    );
}

#[test]
fn table_18_telemetry_to_coordinator_report() {
    check(
        &[0x72, 0x01, 0x01, 0x07],
        report(Report::TelemetryToCoordinator {
            on: true,
            id: TelemetryId::AileronPosition,
        }),
    );
    check(
        &[0x72, 0x01, 0x00, 0x07],
        report(Report::TelemetryToCoordinator {
            on: false,
            id: TelemetryId::AileronPosition,
        }),
    );
}

#[test]
fn table_19_landing_report() {
    for (byte, state) in [
        (0x00, LandingState::OnGround),
        (0x01, LandingState::Landing),
        (0x02, LandingState::Stabilization),
        (0x03, LandingState::TakeOff),
        (0x04, LandingState::Flight),
    ] {
        check(&[0x72, 0x02, byte], report(Report::Landing(state)));
    }
}

#[test]
fn table_20_controllers_report() {
    check(
        &[0x72, 0x03, 0x03],
        report(Report::Controllers(Controller::Mpc)),
    );
}

#[test]
fn table_21_trajectory_set_report() {
    let mut bytes = vec![0x72, 0x04, 0x01];
    bytes.extend_from_slice(&waypoint_bytes(&WP2));
    check(
        &bytes,
        report(Report::TrajectorySet(Waypoints::new_unchecked(&bytes[3..]))),
    );
    check(
        &[0x72, 0x04, 0x00],
        report(Report::TrajectorySet(Waypoints::new_unchecked(&[]))),
    );
}

#[test]
fn table_22_position_slave_set_report() {
    let mut bytes = vec![0x72, 0x05];
    bytes.extend_from_slice(&MAV);
    check(
        &bytes,
        report(Report::PositionSlaveSet(SlaveAddresses::Single(Address(
            MAV,
        )))),
    );
}

#[test]
fn table_23_time_report() {
    check(
        &[0x72, 0x06, 0x78, 0x56, 0x34, 0x12],
        report(Report::Time(0x1234_5678)),
    );
}

#[test]
fn table_24_message_hello_world() {
    let bytes = [
        0x6D, 0x48, 0x65, 0x6C, 0x6C, 0x6F, 0x20, 0x57, 0x6F, 0x72, 0x6C, 0x64,
    ];
    check(&bytes, Packet::Message(Text::new(&b"Hello World"[..])));
    let Ok(Packet::Message(text)) = parse(&bytes) else {
        panic!("not a message");
    };
    assert_eq!(text.as_str(), Some("Hello World"));
    assert_eq!(text.to_string(), "Hello World");
}
