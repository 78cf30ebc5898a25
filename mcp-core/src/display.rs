//! One-line, human-readable `Display` for packets, e.g. `report landing flight` or
//! `telemetry altitude=1.5 pitch_angle=-0.25`.

use core::fmt;

use crate::{
    command::{Command, StatusRequest},
    packet::Packet,
    report::{Report, SlaveAddresses},
    telemetry::Telemetry,
    text::Quoted,
    trajectory::{Waypoint, Waypoints},
};

fn on_off(on: bool) -> &'static str {
    if on { "on" } else { "off" }
}

/// An `f32` as text, in the shortest digits that read back as the same `f32`:
/// positional for ordinary magnitudes (`1.5`, `-0.25`, `1200`), with an exponent below
/// 1e-4 and from 1e9 on (`3.4e38`, `1e-45`), where positional notation would print
/// dozens of zeros. NaN and the infinities print as `NaN`, `inf` and `-inf`.
struct Float(f32);

impl Float {
    /// Below this magnitude (but not 0), an exponent.
    const SMALL: f32 = 1e-4;
    /// From this magnitude on, an exponent.
    const LARGE: f32 = 1e9;
}

impl fmt::Display for Float {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let magnitude = self.0.abs();
        if magnitude.is_finite()
            && magnitude != 0.0
            && !(Self::SMALL..Self::LARGE).contains(&magnitude)
        {
            write!(f, "{:e}", self.0)
        } else {
            write!(f, "{}", self.0)
        }
    }
}

/// Writes to a formatter with every `"` escaped as `\"`: text between quotes (whose
/// backslashes are already escaped) reads back unambiguously.
struct EscapeQuotes<'a, 'f>(&'a mut fmt::Formatter<'f>);

impl fmt::Write for EscapeQuotes<'_, '_> {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        let mut parts = s.split('"');
        if let Some(first) = parts.next() {
            self.0.write_str(first)?;
        }
        for part in parts {
            self.0.write_str("\\\"")?;
            self.0.write_str(part)?;
        }
        Ok(())
    }
}

impl<B: AsRef<[u8]>> fmt::Display for Quoted<'_, B> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("\"")?;
        fmt::Write::write_fmt(&mut EscapeQuotes(f), format_args!("{}", self.0))?;
        f.write_str("\"")
    }
}

impl fmt::Display for Waypoint {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "(time={} elevator={} aileron={} altitude={})",
            self.time,
            Float(self.elevator),
            Float(self.aileron),
            Float(self.altitude)
        )
    }
}

impl<B: AsRef<[u8]>> fmt::Display for Waypoints<B> {
    /// `N waypoints` followed by each waypoint.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.len() {
            1 => f.write_str("1 waypoint")?,
            n => write!(f, "{n} waypoints")?,
        }
        self.iter().try_for_each(|w| write!(f, " {w}"))
    }
}

impl<B: AsRef<[u8]>> fmt::Display for Telemetry<B> {
    /// `id=value` pairs separated by spaces.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut sep = "";
        for r in self.iter() {
            write!(f, "{sep}{}={}", r.id, Float(r.value))?;
            sep = " ";
        }
        Ok(())
    }
}

impl<B: AsRef<[u8]>> fmt::Display for Command<B> {
    /// The command type and its fields, e.g. `landing on`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.command_type())?;
        match self {
            Command::TelemetryToCoordinator { on, id } => write!(f, " {} {id}", on_off(*on)),
            Command::Landing { on } => write!(f, " {}", on_off(*on)),
            Command::Controllers(c) => write!(f, " {c}"),
            Command::TrajectorySet(w) => write!(f, " {w}"),
            Command::PositionSlaveSet {
                slot: Some(slot),
                address,
            } => write!(f, " slot {slot} {address}"),
            Command::PositionSlaveSet {
                slot: None,
                address,
            } => write!(f, " {address}"),
            Command::Time(t) => write!(f, " {t}"),
            Command::PositionSet { elevator, aileron } => {
                write!(
                    f,
                    " elevator={} aileron={}",
                    Float(*elevator),
                    Float(*aileron)
                )
            }
            Command::StatusRequest(StatusRequest::TelemetryToCoordinator(id)) => {
                write!(f, " status request {id}")
            }
            Command::StatusRequest(_) => f.write_str(" status request"),
        }
    }
}

impl<B: AsRef<[u8]>> fmt::Display for Report<B> {
    /// The report type and its fields, e.g. `controllers mpc`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.report_type())?;
        match self {
            Report::TelemetryToCoordinator { on, id } => write!(f, " {} {id}", on_off(*on)),
            Report::Landing(s) => write!(f, " {s}"),
            Report::Controllers(c) => write!(f, " {c}"),
            Report::TrajectorySet(w) => write!(f, " {w}"),
            Report::PositionSlaveSet(SlaveAddresses::Single(a)) => write!(f, " {a}"),
            // Labelled as the slot form's command is (`slot 2 ADDR`): four bare
            // addresses do not say which slot is which, nor that empty ones are zeros.
            Report::PositionSlaveSet(SlaveAddresses::Slots(all)) => all
                .iter()
                .enumerate()
                .try_for_each(|(slot, a)| write!(f, " slot {slot} {a}")),
            Report::Time(t) => write!(f, " {t}"),
        }
    }
}

impl<B: AsRef<[u8]>> fmt::Display for Packet<B> {
    /// The category, then the packet's content: `command landing on`,
    /// `telemetry altitude=1.5`, `message "Hello World"` (text escaped as by
    /// [`Text`](crate::Text)'s `Display`, and `"` as `\"`). Floats print in their
    /// shortest round-trip digits, with an exponent when very large or small (`3.4e38`).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.category())?;
        match self {
            Packet::Command(c) => write!(f, " {c}"),
            Packet::Report(r) => write!(f, " {r}"),
            Packet::Telemetry(t) if t.is_empty() => Ok(()),
            Packet::Telemetry(t) => write!(f, " {t}"),
            Packet::Message(t) | Packet::Warning(t) => write!(f, " {}", t.quoted()),
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::string::ToString;

    use crate::parse;

    fn show(bytes: &[u8]) -> std::string::String {
        parse(bytes).unwrap().to_string()
    }

    #[test]
    fn packets_display_on_one_line() {
        assert_eq!(show(b"c\x02\x05"), "command landing on");
        assert_eq!(
            show(b"c\x01\xff\x19"),
            "command telemetry_to_coordinator status request pitch_angle"
        );
        assert_eq!(show(b"c\x03\xff"), "command controllers status request");
        assert_eq!(show(b"r\x02\x04"), "report landing flight");
        assert_eq!(show(b"r\x03\x09"), "report controllers unknown(0x09)");
        assert_eq!(
            show(b"t\x01\x00\x00\xc0\x3f\x19\x00\x00\x80\xbe"),
            "telemetry altitude=1.5 pitch_angle=-0.25"
        );
        assert_eq!(show(b"t"), "telemetry");
        assert_eq!(show(b"m\"hi\"\xff"), r#"message "\"hi\"\xff""#);
        assert_eq!(show(b"ma\"b\\c"), r#"message "a\"b\\c""#);
        assert_eq!(show(b"r\x06\x78\x56\x34\x12"), "report time 305419896");
        assert_eq!(
            show(b"c\x05\x01\x00\x13\xa2\x00\x40\xb5\x99\xb9"),
            "command position_slave_set slot 1 0013a20040b599b9"
        );
        // The firmware's four slots, each labelled.
        let slots = [&b"r\x05\x00\x13\xa2\x00\x40\xb5\x99\xbf"[..], &[0; 24]].concat();
        assert_eq!(
            show(&slots),
            "report position_slave_set slot 0 0013a20040b599bf slot 1 0000000000000000 \
             slot 2 0000000000000000 slot 3 0000000000000000"
        );
        assert_eq!(
            show(b"c\x04\x01\x01\x00\x00\x00\x00\x00\x80\x3f\x00\x00\x00\x40\x00\x00\x40\x40"),
            "command trajectory_set 1 waypoint (time=1 elevator=1 aileron=2 altitude=3)"
        );
        assert_eq!(
            show(b"c\x07\x00\x00\xc0\x3f\x00\x00\x10\xc0"),
            "command position_set elevator=1.5 aileron=-2.25"
        );
    }

    #[test]
    fn very_large_and_small_floats_print_with_an_exponent() {
        use std::format;
        let position = |elevator: f32, aileron: f32| {
            let mut bytes = std::vec![b'c', 0x07];
            bytes.extend_from_slice(&elevator.to_le_bytes());
            bytes.extend_from_slice(&aileron.to_le_bytes());
            show(&bytes)
        };
        assert_eq!(
            position(1e-45, 3.4e38),
            "command position_set elevator=1e-45 aileron=3.4e38"
        );
        assert_eq!(
            position(-f32::MAX, f32::MIN_POSITIVE),
            "command position_set elevator=-3.4028235e38 aileron=1.1754944e-38"
        );
        // Ordinary magnitudes as before, at both ends of the range.
        assert_eq!(
            position(0.0001, 123456790.0),
            "command position_set elevator=0.0001 aileron=123456790"
        );
        assert_eq!(
            position(0.0, -0.0),
            "command position_set elevator=0 aileron=-0"
        );
        assert_eq!(
            position(f32::NAN, f32::NEG_INFINITY),
            "command position_set elevator=NaN aileron=-inf"
        );
        // Shortest digits that read back as the same f32.
        for value in [1e-45f32, 3.4e38, 0.999_999_8, 1.0e9, 9.999999e-5] {
            let text = format!("{}", super::Float(value));
            assert_eq!(text.parse::<f32>().unwrap(), value, "{text}");
        }
        let telemetry = show(b"t\x01\x01\x00\x00\x00");
        assert_eq!(telemetry, "telemetry altitude=1e-45");
    }
}
