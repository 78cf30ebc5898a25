//! The identifier tables (1, 2, 17, 25 to 29): values, names, Display and FromStr.

use std::collections::HashSet;

use mcp_core::{Category, CommandType, Controller, LandingState, TelemetryId};

#[test]
fn table_25_categories() {
    let table = [
        (0x63, Category::Command, "command"),
        (0x74, Category::Telemetry, "telemetry"),
        (0x72, Category::Report, "report"),
        (0x6D, Category::Message, "message"),
        (0x77, Category::Warning, "warning"),
    ];
    for (byte, value, name) in table {
        assert_eq!(Category::from(byte), value);
        assert_eq!(u8::from(value), byte);
        assert_eq!(value.name(), Some(name));
        assert_eq!(name.parse::<Category>(), Ok(value));
    }
    assert_eq!(Category::ALL.len(), 5);
}

#[test]
fn table_26_command_types() {
    let names = [
        "telemetry_to_coordinator",
        "landing",
        "controllers",
        "trajectory_set",
        "position_slave_set",
        "time",
        "position_set",
    ];
    for (i, name) in names.iter().enumerate() {
        let t = CommandType::from(i as u8 + 1);
        assert_eq!(t.name(), Some(*name));
        assert_eq!(name.parse::<CommandType>(), Ok(t));
    }
    assert_eq!(CommandType::from(0), CommandType::Unknown(0));
    assert_eq!(CommandType::from(8), CommandType::Unknown(8));
}

#[test]
fn table_27_landing_states() {
    let names = [
        "on_ground",
        "landing",
        "stabilization",
        "take_off",
        "flight",
    ];
    let got: Vec<_> = LandingState::iter().map(|s| s.name().unwrap()).collect();
    assert_eq!(got, names);
    assert_eq!(LandingState::from(4), LandingState::Flight);
    assert_eq!(LandingState::from(5), LandingState::Unknown(5));
}

#[test]
fn table_28_controllers() {
    assert_eq!(Controller::from(1), Controller::Manual);
    assert_eq!(Controller::from(2), Controller::Altitude);
    assert_eq!(Controller::from(3), Controller::Mpc);
    assert_eq!(Controller::from(0), Controller::Unknown(0));
    assert_eq!(Controller::Mpc.name(), Some("mpc"));
}

#[test]
fn table_29_telemetry_ids() {
    let names = [
        "estimated_altitude",
        "altitude",
        "elevator_speed",
        "aileron_speed",
        "estimated_elevator_speed",
        "estimated_aileron_speed",
        "elevator_position",
        "aileron_position",
        "altitude_controller_output",
        "altitude_speed",
        "aileron_controller_output",
        "elevator_controller_output",
        "altitude_setpoint",
        "elevator_position_setpoint",
        "aileron_position_setpoint",
        "elevator_acceleration",
        "aileron_acceleration",
        "valid_blob",
        "output_throttle",
        "output_elevator",
        "output_aileron",
        "output_rudder",
        "blob_elevator",
        "blob_aileron",
        "blob_altitude",
        "pitch_angle",
        "roll_angle",
        "elevator_shift",
        "aileron_shift",
        "elevator_acceleration_input",
        "elevator_acceleration_error",
        "aileron_acceleration_input",
        "aileron_acceleration_error",
    ];
    assert_eq!(TelemetryId::ALL.len(), names.len());
    for (i, name) in names.iter().enumerate() {
        let id = TelemetryId::from(i as u8);
        assert_eq!(id.name(), Some(*name), "id {i:#04x}");
        assert_eq!(name.parse::<TelemetryId>(), Ok(id));
        assert_eq!(TelemetryId::ALL[i], id);
    }
    for n in 0x21..=0xFF {
        assert_eq!(TelemetryId::from(n), TelemetryId::Unknown(n));
        assert_eq!(TelemetryId::from(n).name(), None);
    }
}

#[test]
fn every_byte_round_trips_through_every_enum() {
    for n in 0..=255u8 {
        assert_eq!(u8::from(Category::from(n)), n);
        assert_eq!(u8::from(CommandType::from(n)), n);
        assert_eq!(u8::from(TelemetryId::from(n)), n);
        assert_eq!(u8::from(Controller::from(n)), n);
        assert_eq!(u8::from(LandingState::from(n)), n);
        // Display -> FromStr is lossless, names and unknowns alike.
        let id = TelemetryId::from(n);
        assert_eq!(id.to_string().parse::<TelemetryId>(), Ok(id));
    }
}

#[test]
fn unknown_displays_as_hex_and_equals_its_byte() {
    assert_eq!(TelemetryId::from(0x2a).to_string(), "unknown(0x2a)");
    assert_eq!(Controller::Unknown(1), Controller::Manual);
    let set: HashSet<_> = [Controller::Unknown(1), Controller::Manual].into();
    assert_eq!(set.len(), 1);
    assert!(LandingState::OnGround < LandingState::Unknown(9));
}

#[test]
fn from_str_accepts_numbers_and_rejects_junk() {
    assert_eq!("25".parse::<TelemetryId>(), Ok(TelemetryId::PitchAngle));
    assert_eq!("0x19".parse::<TelemetryId>(), Ok(TelemetryId::PitchAngle));
    assert_eq!(
        "0xF0".parse::<TelemetryId>(),
        Ok(TelemetryId::Unknown(0xF0))
    );
    let err = "pitch".parse::<TelemetryId>().unwrap_err();
    assert_eq!(err.what(), "telemetry id");
    assert!("256".parse::<Controller>().is_err());
    assert!("".parse::<LandingState>().is_err());
    assert!("Manual".parse::<Controller>().is_err());
}

/// A set of telemetry ids is at the crate root, beside `TelemetryId`, and builds in a
/// `const`.
#[test]
fn telemetry_set_at_the_crate_root() {
    const ENABLED: mcp_core::TelemetrySet = mcp_core::TelemetrySet::new()
        .with(TelemetryId::Altitude)
        .with(TelemetryId::PitchAngle);
    let ids: Vec<TelemetryId> = ENABLED.iter().collect();
    assert_eq!(ids, [TelemetryId::Altitude, TelemetryId::PitchAngle]);
    assert_eq!(ENABLED, mcp_core::mav::TelemetrySet::from_iter(ids));
}
