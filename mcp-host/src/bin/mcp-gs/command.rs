//! The COMMAND words of `send` and `encode`: every MCP command, as an operator types it.

use std::time::{SystemTime, UNIX_EPOCH};

use clap::{Subcommand, ValueEnum};
use mcp_core::{
    Address, Command, CommandType, Controller, MAX_PAYLOAD, Packet, Slot, StatusRequest,
    TelemetryId, Text, TrajectoryBuilder, Waypoint,
};

/// On or off.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum OnOff {
    /// Turn on.
    On,
    /// Turn off.
    Off,
}

impl OnOff {
    fn is_on(self) -> bool {
        self == Self::On
    }
}

/// A time value for the MAV's clock: `now`, `+N` (N seconds from now) or seconds since
/// the Unix epoch, as a waypoint's TIME takes them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum TimeArg {
    /// This machine's clock, read when the command is built.
    Now,
    /// This many seconds after this machine's clock, read when the command is built.
    FromNow(u32),
    /// Seconds since 1970-01-01 00:00:00 UTC.
    Seconds(u32),
}

impl TimeArg {
    /// The time to send, seconds since 1970; `what` names it in messages. An absolute
    /// time before 2000 is sent as given, with a warning (most likely meant as seconds
    /// from now).
    fn resolve(self, what: &str) -> Result<u32, String> {
        match self {
            Self::Now => now(),
            Self::FromNow(seconds) => now()?
                .checked_add(seconds)
                .ok_or_else(|| format!("{what} +{seconds} is past 2106: it does not fit u32")),
            Self::Seconds(time) => {
                // Once, for the first of them: a trajectory's waypoints are read one by one.
                static WARNED: std::sync::atomic::AtomicBool =
                    std::sync::atomic::AtomicBool::new(false);
                if time < Y2000 && !WARNED.swap(true, std::sync::atomic::Ordering::Relaxed) {
                    err!(
                        "mcp-gs: warning: {what} {time} is {time} s after 1970-01-01 00:00 UTC: \
                         the MAV's clock counts seconds since 1970; for {time} s from now, \
                         give +{time}"
                    );
                }
                Ok(time)
            }
        }
    }
}

impl std::str::FromStr for TimeArg {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        if s.eq_ignore_ascii_case("now") {
            return Ok(Self::Now);
        }
        let (digits, time): (_, fn(u32) -> Self) = match s.strip_prefix('+') {
            Some(digits) => (digits, Self::FromNow),
            None => (s, Self::Seconds),
        };
        // Digits alone: `u32::from_str` would also take a sign.
        match digits.parse() {
            Ok(seconds) if digits.bytes().all(|b| b.is_ascii_digit()) => Ok(time(seconds)),
            _ => Err(format!(
                "expected `now`, `+N` (N seconds from now) or seconds since 1970 (0 to {}), \
                 got `{s}`",
                u32::MAX
            )),
        }
    }
}

/// Parses `TIME,ELEVATOR,AILERON,ALTITUDE`.
fn parse_waypoint(s: &str) -> Result<Waypoint, String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let [time, elevator, aileron, altitude] = parts[..] else {
        return Err(format!(
            "expected TIME,ELEVATOR,AILERON,ALTITUDE (4 values), got {} in `{s}`",
            parts.len()
        ));
    };
    let float = |name: &str, v: &str| parse_finite(v).map_err(|e| format!("{name} {e}"));
    Ok(Waypoint {
        // The MAV's clock time, seconds since 1970.
        time: time
            .parse::<TimeArg>()
            .map_err(|e| format!("waypoint TIME: {e}"))?
            .resolve("waypoint time")?,
        elevator: float("elevator", elevator)?,
        aileron: float("aileron", aileron)?,
        altitude: float("altitude", altitude)?,
    })
}

/// Before this time (2000-01-01 00:00:00 UTC), an absolute time for the MAV's clock is
/// most likely meant as seconds from now.
const Y2000: u32 = 946_684_800;

/// A finite `f32`: NaN and infinities are no position a MAV can fly to, nor is a number
/// beyond the range of an `f32`, which would be sent as an infinity (`raw` sends any
/// bytes, for testing firmware). A number too small for an `f32` is sent as 0, with a
/// warning.
pub(crate) fn parse_finite(s: &str) -> Result<f32, String> {
    let Ok(v) = s.parse::<f32>() else {
        return Err(format!("`{s}` is not a number"));
    };
    let word = s.trim().trim_start_matches(['+', '-']).to_ascii_lowercase();
    if v.is_nan() || ["inf", "infinity"].contains(&word.as_str()) {
        return Err(format!(
            "`{s}` is not a finite number (to send any bytes, use `raw`)"
        ));
    }
    if v.is_infinite() {
        return Err(format!(
            "`{s}` is outside the range of a 32-bit float (-{max:e} to {max:e}; to send \
             any bytes, use `raw`)",
            max = f32::MAX
        ));
    }
    if v == 0.0 && s.parse::<f64>().is_ok_and(|wide| wide != 0.0) {
        err!("mcp-gs: warning: `{s}` is closer to 0 than a 32-bit float can hold: it is sent as 0");
    }
    Ok(v)
}

/// A name or number of an identifier (a telemetry id, a controller): names in any case,
/// as every name on the command line.
fn parse_id<T>(s: &str) -> Result<T, mcp_core::ParseIdError>
where
    T: std::str::FromStr<Err = mcp_core::ParseIdError>,
{
    s.to_ascii_lowercase().parse()
}

/// The long help of a telemetry id argument: every name, with its number.
pub(crate) fn telemetry_id_help() -> String {
    let names: Vec<String> = TelemetryId::iter()
        .filter_map(|id| Some(format!("{} ({})", id.name()?, u8::from(id))))
        .collect();
    format!(
        "Telemetry id: a name, in any case, or a number from 0 to 255 (decimal or 0x-hex). \
         The names and numbers: {}",
        names.join(", ")
    )
}

/// A telemetry id: a name in any case, or a number.
pub(crate) fn parse_telemetry_id(s: &str) -> Result<TelemetryId, String> {
    parse_id(s).map_err(|e| e.to_string())
}

/// A controller of a controllers command: a name in any case, or a number from 0 to 254
/// (255 is the status request byte).
fn parse_controller(s: &str) -> Result<Controller, String> {
    match parse_id::<Controller>(s) {
        Ok(c) if u8::from(c) != 0xFF => Ok(c),
        Ok(_) => Err(
            "controller 255 (0xFF) is the status request byte: give 0 to 254, or ask with \
             `status controllers`"
                .into(),
        ),
        Err(e) => Err(format!(
            "not a controller: give a name ({}) or a number from 0 to 254 (decimal or 0x-hex)",
            e.names().join(", ")
        )),
    }
}

/// A byte: decimal or `0x` hex.
pub(crate) fn parse_byte(s: &str) -> Result<u8, String> {
    let t = s.trim();
    match t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
        Some(hex) => u8::from_str_radix(hex, 16),
        None => t.parse(),
    }
    .map_err(|_| format!("expected a byte, 0 to 255 (decimal or 0x-hex), got `{s}`"))
}

/// The KIND of a status request: a command type with a status request, by its name,
/// by the word `send` uses for the command, or by its number.
pub(crate) fn parse_status_kind(s: &str) -> Result<CommandType, String> {
    let kind = match s.trim().to_ascii_lowercase().replace('-', "_").as_str() {
        "telemetry" => CommandType::TelemetryToCoordinator,
        "controller" => CommandType::Controllers,
        "trajectory" => CommandType::TrajectorySet,
        "slave_set" => CommandType::PositionSlaveSet,
        other => other
            .parse::<CommandType>()
            .map_err(|_| format!("not a status request kind: {STATUS_KINDS}"))?,
    };
    no_status_request(kind).map_or(Ok(kind), Err)
}

/// Why `kind` has no status request, if it has none.
fn no_status_request(kind: CommandType) -> Option<String> {
    if StatusRequest::for_type(kind, TelemetryId::from(0)).is_some() {
        return None;
    }
    Some(match kind {
        CommandType::PositionSet => format!(
            "{kind} has no status request (the position is in the telemetry): {STATUS_KINDS}"
        ),
        _ => format!(
            "{} is not a command type with a status request: {STATUS_KINDS}",
            u8::from(kind)
        ),
    })
}

/// The kinds [`parse_status_kind`] takes, for its errors.
const STATUS_KINDS: &str = "give telemetry_to_coordinator (or telemetry), landing, \
    controllers (controller), trajectory_set (trajectory), position_slave_set (slave-set), \
    time, or the number of one of them (1 to 6)";

fn parse_slot(s: &str) -> Result<Slot, String> {
    s.parse::<u8>()
        .ok()
        .and_then(Slot::new)
        .ok_or_else(|| format!("slot must be 0, 1, 2 or 3, got `{s}`"))
}

/// An MCP command (or message) to send. Identifiers take a name or a number.
#[derive(Debug, Clone, PartialEq, Subcommand)]
pub(crate) enum CommandArgs {
    /// Telemetry to coordinator: turn sending of one telemetry id on or off
    /// (e.g. `telemetry on altitude`, `telemetry off 0x11`).
    Telemetry {
        /// on or off.
        #[arg(ignore_case = true, value_name = "on|off")]
        state: OnOff,
        /// Telemetry id: a name (e.g. `estimated_altitude`) or a number (0-255).
        #[arg(value_parser = parse_telemetry_id, long_help = telemetry_id_help())]
        id: TelemetryId,
    },
    /// Landing: turn autonomous landing on or off.
    Landing {
        /// on or off.
        #[arg(ignore_case = true, value_name = "on|off")]
        state: OnOff,
    },
    /// Controllers: switch the active controller (`manual`, `altitude`, `mpc` or a number).
    Controller {
        /// Controller: a name or a number (0-254).
        #[arg(value_parser = parse_controller)]
        id: Controller,
    },
    /// Trajectory set: send the waypoints, in order (none clears the trajectory).
    Trajectory {
        /// A waypoint as TIME,ELEVATOR,AILERON,ALTITUDE; repeat for more. TIME is the
        /// MAV's clock time in seconds since 1970 (POSIX time, as `time` sets it): an
        /// absolute time (e.g. 1763683210), `+N` for N seconds from now or `now`, both by
        /// this machine's clock (set the MAV's with `time now` first).
        #[arg(long = "waypoint", value_name = "TIME,ELEV,AIL,ALT", value_parser = parse_waypoint, allow_hyphen_values = true)]
        waypoints: Vec<Waypoint>,
    },
    /// Position slave set: the slave MAV for coordinate system distribution.
    SlaveSet {
        /// The slave's 64-bit address (16 hex digits).
        #[arg(value_parser = parse_slave_address)]
        address: Address,
        /// Use the deployed firmware's form, with this slot (0-3). Without it, the
        /// specification's form, which names one slave: the simulator's MAVs, which
        /// keep four as the deployed firmware does, take it as slot 0's.
        #[arg(long, value_parser = parse_slot)]
        slot: Option<Slot>,
    },
    /// Time: set the MAV's clock.
    Time {
        /// `now`, `+N` (N seconds from now, by this machine's clock) or seconds since
        /// 1970-01-01 UTC.
        time: TimeArg,
    },
    /// Position set: the MAV's position in the new coordinate system.
    #[command(allow_negative_numbers = true)]
    PositionSet {
        /// New elevator position.
        #[arg(value_parser = parse_finite)]
        elevator: f32,
        /// New aileron position.
        #[arg(value_parser = parse_finite)]
        aileron: f32,
    },
    /// A status request (the MAV answers with the matching report).
    Status {
        /// What to ask: `telemetry_to_coordinator` (or `telemetry`), `landing`,
        /// `controllers` (`controller`), `trajectory_set` (`trajectory`),
        /// `position_slave_set` (`slave-set`), `time`, or a number.
        #[arg(value_parser = parse_status_kind)]
        kind: CommandType,
        /// For `telemetry_to_coordinator`: the telemetry id (a name or a number).
        // Parsed once the kind is known: another kind takes no id at all, which is what a
        // wrong one should hear.
        #[arg(long_help = telemetry_id_help())]
        id: Option<String>,
    },
    /// A text message (category `m`).
    Message {
        /// The text, at most 254 bytes of 8-bit ASCII, as `monitor` prints it: a byte
        /// that is not ASCII as `\xNN` (`\xe9`), a backslash as `\\`, a quote as `\"`
        /// or as it is.
        /// Several words are joined with one space between them, as `echo` does.
        #[arg(value_parser = parse_message_text, num_args = 1.., required = true)]
        text: Vec<MessageText>,
    },
    /// Any payload, as hex (not checked: for testing radios and MAV firmware).
    Raw {
        /// The payload bytes in hex, e.g. `630201`.
        #[arg(value_parser = parse_hex_payload)]
        payload: HexPayload,
    },
}

/// Payload bytes given as hex on the command line.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct HexPayload(pub(crate) Vec<u8>);

fn parse_hex_payload(s: &str) -> Result<HexPayload, String> {
    let digits: String = s
        .chars()
        .filter(|c| !c.is_whitespace() && *c != ':')
        .collect();
    let digits = digits.strip_prefix("0x").unwrap_or(&digits);
    if !digits.len().is_multiple_of(2) {
        return Err("hex payload needs an even number of digits".into());
    }
    let bytes = (0..digits.len())
        .step_by(2)
        .map(|i| {
            digits
                .get(i..i + 2)
                .and_then(|pair| u8::from_str_radix(pair, 16).ok())
                .ok_or_else(|| format!("`{}` is not hex", &digits[i..]))
        })
        .collect::<Result<Vec<u8>, String>>()?;
    if bytes.len() > MAX_PAYLOAD {
        return Err(format!(
            "payload of {} bytes exceeds {MAX_PAYLOAD}",
            bytes.len()
        ));
    }
    Ok(HexPayload(bytes))
}

/// A message's bytes given on the command line.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct MessageText(pub(crate) Vec<u8>);

/// A message's text as `monitor` and `decode` print it, back to its bytes
/// ([`unescape_text`]).
fn parse_message_text(s: &str) -> Result<MessageText, String> {
    unescape_text(s, "the protocol's messages are 8-bit ASCII").map(MessageText)
}

/// Text as this program prints it (a message, a radio's node identifier), back to its
/// bytes: ASCII as it is, `\xNN` for any byte, `\\` and `\"` for a backslash and a
/// quote. The text is 8-bit ASCII (`why` says whose), so a character that is not ASCII
/// is refused rather than sent as its UTF-8 bytes, which the other end would show as
/// two or three others.
pub(crate) fn unescape_text(s: &str, why: &str) -> Result<Vec<u8>, String> {
    let mut bytes = Vec::with_capacity(s.len());
    let mut chars = s.char_indices();
    while let Some((at, c)) = chars.next() {
        match c {
            '\\' => match chars.next().map(|(_, c)| c) {
                Some('\\') => bytes.push(b'\\'),
                Some('"') => bytes.push(b'"'),
                Some('x') => {
                    let digits = s
                        .get(at + 2..at + 4)
                        .filter(|d| d.bytes().all(|b| b.is_ascii_hexdigit()));
                    let Some(byte) = digits.and_then(|d| u8::from_str_radix(d, 16).ok()) else {
                        return Err(format!(
                            "`{}` at byte {at}: `\\x` takes two hex digits (`\\x41` is `A`)",
                            s.get(at..)
                                .unwrap_or_default()
                                .chars()
                                .take(4)
                                .collect::<String>()
                        ));
                    };
                    bytes.push(byte);
                    chars.nth(1);
                }
                _ => {
                    return Err(format!(
                        "a backslash (at byte {at}) starts `\\xNN` (a byte in hex), `\\\\` (a \
                         backslash) or `\\\"` (a quote)"
                    ));
                }
            },
            c if c.is_ascii() => bytes.push(c as u8),
            c => {
                return Err(format!(
                    "`{c}` is not ASCII: {why}; give a byte above 0x7F as `\\xNN` (for \
                     example `\\xe9`, `é` in Latin-1), as it is printed"
                ));
            }
        }
    }
    Ok(bytes)
}

/// Builds the status request for `kind` (and `id` for telemetry-to-coordinator).
pub(crate) fn status_request(kind: CommandType, id: Option<&str>) -> Result<StatusRequest, String> {
    match (kind, id) {
        (CommandType::TelemetryToCoordinator, None) => Err(
            "a telemetry_to_coordinator status request needs a telemetry id (e.g. `altitude`)"
                .into(),
        ),
        (CommandType::TelemetryToCoordinator, Some(id)) => parse_telemetry_id(id)
            .map(StatusRequest::TelemetryToCoordinator)
            .map_err(|e| format!("`{id}` is {e}")),
        (_, Some(_)) => Err(format!("a {kind} status request takes no telemetry id")),
        (kind, None) => StatusRequest::for_type(kind, TelemetryId::from(0))
            .ok_or_else(|| no_status_request(kind).unwrap_or_default()),
    }
}

impl CommandArgs {
    /// The MCP payload bytes.
    pub(crate) fn payload(&self) -> Result<Vec<u8>, String> {
        if let Self::Raw { payload } = self {
            return Ok(payload.0.clone());
        }
        let mut buf = [0u8; MAX_PAYLOAD];
        let len = match self {
            Self::Trajectory { waypoints } => {
                let mut builder =
                    TrajectoryBuilder::command(&mut buf).map_err(|e| e.to_string())?;
                for (i, waypoint) in waypoints.iter().enumerate() {
                    builder.push(*waypoint).map_err(|_| {
                        format!(
                            "too many waypoints: {} fit in one packet, got {}",
                            i,
                            waypoints.len()
                        )
                    })?;
                }
                builder.finish()
            }
            other => {
                let text;
                let packet: Packet<&[u8]> = match other {
                    Self::Telemetry { state, id } => Command::TelemetryToCoordinator {
                        on: state.is_on(),
                        id: *id,
                    }
                    .into(),
                    Self::Landing { state } => Command::Landing { on: state.is_on() }.into(),
                    Self::Controller { id } => {
                        if u8::from(*id) == 0xFF {
                            return Err("controller 255 (0xFF) is the status request byte: use `status controllers`".into());
                        }
                        Command::Controllers(*id).into()
                    }
                    Self::SlaveSet { address, slot } => Command::PositionSlaveSet {
                        slot: *slot,
                        address: *address,
                    }
                    .into(),
                    Self::Time { time } => Command::Time(time.resolve("time")?).into(),
                    Self::PositionSet { elevator, aileron } => Command::PositionSet {
                        elevator: *elevator,
                        aileron: *aileron,
                    }
                    .into(),
                    Self::Status { kind, id } => {
                        Command::StatusRequest(status_request(*kind, id.as_deref())?).into()
                    }
                    Self::Message { text: words } => {
                        let words: Vec<&[u8]> = words.iter().map(|w| w.0.as_slice()).collect();
                        text = words.join(&b' ');
                        Packet::Message(Text::new(text.as_slice()))
                    }
                    Self::Trajectory { .. } | Self::Raw { .. } => unreachable!("handled above"),
                };
                packet.encode(&mut buf).map_err(|e| match packet {
                    Packet::Message(_) => format!(
                        "message too long: {} bytes, at most {} fit",
                        e.needed - 1,
                        MAX_PAYLOAD - 1
                    ),
                    _ => e.to_string(),
                })?
            }
        };
        Ok(buf[..len].to_vec())
    }
}

fn now() -> Result<u32, String> {
    let secs = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_err(|_| "this machine's clock is before 1970".to_string())?
        .as_secs();
    u32::try_from(secs)
        .map_err(|_| "this machine's clock is past 2106: time does not fit u32".into())
}

/// The slave address of `slave-set`: 16 hex digits, as every 64-bit address here.
fn parse_slave_address(s: &str) -> Result<Address, String> {
    crate::link_args::parse_address64(s).map(|a| Address::from(a.0))
}
