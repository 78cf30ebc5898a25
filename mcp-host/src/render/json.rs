//! The JSON Lines form of frames and packets (`mcp-gs --format json`).
//!
//! One JSON object per frame; the schema is documented in the README and is stable:
//! fields are only ever added. Addresses and hex data are lowercase hex; identifiers
//! and codes are numbers, with their names beside them (`*_name`) where the protocol
//! or Digi names them; non-finite floats are the strings `"NaN"`, `"Infinity"` and
//! `"-Infinity"`; message and warning text (and a node identifier) keeps printable
//! ASCII and writes any other byte as `\xNN` (a backslash as `\\`), so the original
//! bytes can always be recovered.

use mcp_core::{
    Command, Packet, Report, SlaveAddresses, StatusRequest, Telemetry, Text, Waypoint, Waypoints,
};
use serde_json::{Map, Value, json};
use xbee_api::{DecodeError, Frame};

use super::text::at_name;
use crate::{Event, LinkEvent, Origin};

/// Lowercase hex of `bytes`, no separators.
pub fn hex(bytes: &[u8]) -> String {
    use std::fmt::Write;
    bytes
        .iter()
        .fold(String::with_capacity(bytes.len() * 2), |mut s, b| {
            let _ = write!(s, "{b:02x}");
            s
        })
}

/// A float as JSON: a number in the shortest digits that read back as the same `f32`
/// (`0.9999998`, not the `0.9999998211860657` of the `f64` it widens to), or `"NaN"`,
/// `"Infinity"`, `"-Infinity"`. A subnormal (below 1.2e-38 in size) is written as the
/// `f64` it widens to: its shortest digits can be far from it in relative terms (`1e-45`
/// for 1.401298464324817e-45), and a reader that takes the number as an `f64`, not back
/// to an `f32`, gets its value within a millionth then too.
pub fn float(value: f32) -> Value {
    if value.is_nan() {
        Value::from("NaN")
    } else if value.is_infinite() {
        Value::from(if value > 0.0 { "Infinity" } else { "-Infinity" })
    } else if value.is_subnormal() {
        Value::from(f64::from(value))
    } else {
        // The f64 nearest the f32's shortest decimal, which serde_json writes in those
        // same digits (an f64 has more than enough to keep them).
        let shortest = value.to_string().parse::<f64>().unwrap_or(f64::from(value));
        Value::from(shortest)
    }
}

/// Inserts `key: number` and, when `name` is known, `key_name: name`.
fn named(map: &mut Map<String, Value>, key: &str, code: u8, name: Option<&str>) {
    map.insert(key.into(), code.into());
    if let Some(name) = name {
        map.insert(format!("{key}_name"), name.into());
    }
}

/// One frame as a JSON object.
pub fn frame(frame: &Frame<'_>) -> Value {
    let mut m = Map::new();
    match frame {
        Frame::ReceivePacket(rx) => {
            m.insert("frame".into(), "receive".into());
            m.insert("src64".into(), rx.src64.to_string().into());
            m.insert("src16".into(), rx.src16.to_string().into());
            m.insert("options".into(), rx.options.into());
            m.insert("mcp".into(), mcp(rx.data));
        }
        Frame::TransmitRequest(tx) => {
            m.insert("frame".into(), "transmit".into());
            m.insert("id".into(), tx.frame_id.into());
            m.insert("dst64".into(), tx.dst64.to_string().into());
            m.insert("dst16".into(), tx.dst16.to_string().into());
            m.insert("radius".into(), tx.radius.into());
            m.insert("options".into(), tx.options.into());
            m.insert("mcp".into(), mcp(tx.data));
        }
        Frame::TransmitStatus(st) => {
            m.insert("frame".into(), "transmit_status".into());
            m.insert("id".into(), st.frame_id.into());
            m.insert("dst16".into(), st.dst16.to_string().into());
            m.insert("retries".into(), st.retries.into());
            named(&mut m, "delivery", st.delivery.into(), st.delivery.name());
            named(
                &mut m,
                "discovery",
                st.discovery.into(),
                st.discovery.name(),
            );
        }
        Frame::ModemStatus(ms) => {
            m.insert("frame".into(), "modem_status".into());
            named(&mut m, "status", ms.status.into(), ms.status.name());
        }
        Frame::AtCommand(at) => {
            m.insert("frame".into(), "at".into());
            if at.queued {
                m.insert("queued".into(), true.into());
            }
            m.insert("id".into(), at.frame_id.into());
            m.insert("command".into(), at_name(at.command).into());
            m.insert("parameter".into(), hex(at.parameter).into());
        }
        Frame::AtCommandResponse(at) => {
            m.insert("frame".into(), "at_response".into());
            m.insert("id".into(), at.frame_id.into());
            m.insert("command".into(), at_name(at.command).into());
            named(
                &mut m,
                "status",
                at.status.into(),
                at.status.meaning().name(),
            );
            m.insert("data".into(), hex(at.data).into());
        }
        Frame::RemoteAtCommand(at) => {
            m.insert("frame".into(), "remote_at".into());
            m.insert("id".into(), at.frame_id.into());
            m.insert("dst64".into(), at.dst64.to_string().into());
            m.insert("dst16".into(), at.dst16.to_string().into());
            m.insert("options".into(), at.options.into());
            m.insert("command".into(), at_name(at.command).into());
            m.insert("parameter".into(), hex(at.parameter).into());
        }
        Frame::RemoteAtResponse(at) => {
            m.insert("frame".into(), "remote_at_response".into());
            m.insert("id".into(), at.frame_id.into());
            m.insert("src64".into(), at.src64.to_string().into());
            m.insert("src16".into(), at.src16.to_string().into());
            m.insert("command".into(), at_name(at.command).into());
            named(
                &mut m,
                "status",
                at.status.into(),
                at.status.meaning().name(),
            );
            m.insert("data".into(), hex(at.data).into());
        }
        Frame::ExplicitAddressingCommand(tx) => {
            m.insert("frame".into(), "explicit_transmit".into());
            m.insert("id".into(), tx.frame_id.into());
            m.insert("dst64".into(), tx.dst64.to_string().into());
            m.insert("dst16".into(), tx.dst16.to_string().into());
            m.insert("src_endpoint".into(), tx.src_endpoint.into());
            m.insert("dst_endpoint".into(), tx.dst_endpoint.into());
            m.insert("cluster".into(), tx.cluster_id.into());
            m.insert("profile".into(), tx.profile_id.into());
            m.insert("radius".into(), tx.radius.into());
            m.insert("options".into(), tx.options.into());
            m.insert("data".into(), hex(tx.data).into());
            m.insert("mcp".into(), mcp(tx.data));
        }
        Frame::ExplicitRxIndicator(rx) => {
            m.insert("frame".into(), "explicit_receive".into());
            m.insert("src64".into(), rx.src64.to_string().into());
            m.insert("src16".into(), rx.src16.to_string().into());
            m.insert("src_endpoint".into(), rx.src_endpoint.into());
            m.insert("dst_endpoint".into(), rx.dst_endpoint.into());
            m.insert("cluster".into(), rx.cluster_id.into());
            m.insert("profile".into(), rx.profile_id.into());
            m.insert("options".into(), rx.options.into());
            m.insert("data".into(), hex(rx.data).into());
            m.insert("mcp".into(), mcp(rx.data));
        }
        Frame::NodeIdentificationIndicator(ni) => {
            let node = &ni.node;
            m.insert("frame".into(), "node_identification".into());
            m.insert("src64".into(), ni.src64.to_string().into());
            m.insert("src16".into(), ni.src16.to_string().into());
            m.insert("options".into(), ni.options.into());
            node_fields(
                &mut m,
                (node.addr64, node.addr16, node.parent),
                node.identifier,
                node.device_type,
            );
            named(
                &mut m,
                "event",
                ni.source_event().into(),
                ni.source_event().name(),
            );
            m.insert("profile".into(), node.profile_id.into());
            m.insert("manufacturer".into(), node.manufacturer_id.into());
            if let Some(dd) = node.device_type_identifier {
                m.insert("device_type_identifier".into(), dd.into());
            }
            if let Some(rssi) = node.rssi {
                m.insert("rssi_dbm".into(), (-i16::from(rssi)).into());
            }
        }
        Frame::Unknown { frame_type, data } => {
            m.insert("frame".into(), "unknown".into());
            m.insert("type".into(), (*frame_type).into());
            m.insert("data".into(), hex(data).into());
        }
        // A frame type that xbee-api learned to read after this renderer was written.
        other => {
            m.insert("frame".into(), "other".into());
            m.insert("type".into(), other.frame_type().into());
        }
    }
    Value::Object(m)
}

/// The name [`frame`] gives a frame of type `frame_type` as its `"frame"`, for a type
/// xbee-api reads (`transmit_status` for 0x8B); `None` for another. A queued AT command
/// (0x09) is an `at` frame too, with `"queued":true`.
pub fn frame_type_name(frame_type: u8) -> Option<&'static str> {
    use xbee_api::frame::frame_type::*;
    Some(match frame_type {
        AT_COMMAND | AT_COMMAND_QUEUE => "at",
        TRANSMIT_REQUEST => "transmit",
        EXPLICIT_ADDRESSING_COMMAND => "explicit_transmit",
        REMOTE_AT_COMMAND => "remote_at",
        AT_COMMAND_RESPONSE => "at_response",
        MODEM_STATUS => "modem_status",
        TRANSMIT_STATUS => "transmit_status",
        RECEIVE_PACKET => "receive",
        EXPLICIT_RX_INDICATOR => "explicit_receive",
        NODE_IDENTIFICATION_INDICATOR => "node_identification",
        REMOTE_AT_RESPONSE => "remote_at_response",
        _ => return None,
    })
}

/// A frame the decoder dropped, at byte `offset` of the input when known.
pub fn decode_error(error: &DecodeError, offset: Option<u64>) -> Value {
    let mut m = Map::new();
    m.insert("error".into(), decode_error_kind(error).into());
    if let Some(offset) = offset {
        m.insert("offset".into(), offset.into());
    }
    match *error {
        DecodeError::BadChecksum { expected, got } => {
            m.insert("expected".into(), expected.into());
            m.insert("got".into(), got.into());
        }
        DecodeError::Oversize { length, capacity } => {
            m.insert("length".into(), length.into());
            m.insert("capacity".into(), capacity.into());
        }
        DecodeError::EmptyFrame => {}
        DecodeError::Truncated { length, received } => {
            m.insert("length".into(), length.map_or(Value::Null, Value::from));
            m.insert("received".into(), received.into());
        }
        DecodeError::BadEscape { byte, received } => {
            m.insert("byte".into(), byte.into());
            m.insert("received".into(), received.into());
        }
        // A kind of error newer than this renderer: its message says what it is.
        _ => {}
    }
    m.insert("message".into(), error.to_string().into());
    Value::Object(m)
}

/// The stable name of a decode error kind.
pub fn decode_error_kind(error: &DecodeError) -> &'static str {
    match error {
        DecodeError::BadChecksum { .. } => "checksum",
        DecodeError::Oversize { .. } => "oversize",
        DecodeError::EmptyFrame => "empty_frame",
        DecodeError::Truncated { .. } => "truncated",
        DecodeError::BadEscape { .. } => "bad_escape",
        _ => "other",
    }
}

/// An MCP payload as a JSON object: the packet, or `{"category":"invalid",...}`.
pub fn mcp(payload: &[u8]) -> Value {
    match mcp_core::parse(payload) {
        Ok(packet) => packet_json(&packet),
        Err(error) => json!({
            "category": "invalid",
            "error": error.to_string(),
            "offset": error.offset(),
            "data": hex(payload),
        }),
    }
}

/// A parsed MCP packet as a JSON object.
pub fn packet_json<B: AsRef<[u8]>>(packet: &Packet<B>) -> Value {
    let mut m = Map::new();
    m.insert("category".into(), packet.category().to_string().into());
    match packet {
        Packet::Command(command) => command_fields(&mut m, command),
        Packet::Report(report) => report_fields(&mut m, report),
        Packet::Telemetry(telemetry) => {
            m.insert("values".into(), telemetry_values(telemetry));
        }
        Packet::Message(text) | Packet::Warning(text) => {
            m.insert("text".into(), text_json(text));
        }
    }
    Value::Object(m)
}

fn text_json<B: AsRef<[u8]>>(text: &Text<B>) -> Value {
    text.as_borrowed().to_string().into()
}

/// Text from a radio (a node identifier, an AT parameter's text) as message text is
/// written: printable ASCII as it is, any other byte as `\xNN`, a backslash as `\\`.
///
/// ```
/// use mcp_host::render::json::text;
/// assert_eq!(text(b"MAV \"1\"\\"), r#"MAV "1"\\"#);
/// assert_eq!(text("h\u{e9}".as_bytes()), r"h\xc3\xa9");
/// ```
pub fn text(bytes: &[u8]) -> Value {
    text_json(&Text::new(bytes))
}

/// A radio found by node discovery ([`crate::discovery::Node`]), with the fields and
/// names a node identification frame has: `addr64`, `addr16`, `identifier` (as
/// [`text`] writes it), `parent`, `device_type` and `device_type_name`, and `rssi_dbm`
/// when the radio's `NO` asks for it.
pub fn node(node: &crate::discovery::Node) -> Value {
    let mut m = Map::new();
    node_fields(
        &mut m,
        (node.addr64, node.addr16, node.parent),
        &node.identifier,
        node.device_type,
    );
    if let Some(rssi) = node.rssi {
        m.insert("rssi_dbm".into(), (-i16::from(rssi)).into());
    }
    Value::Object(m)
}

/// The fields every object of a radio's node information has, in order: `addr64`,
/// `addr16`, `identifier` (its bytes as [`text`] writes them), `parent`,
/// `device_type` and `device_type_name`.
fn node_fields(
    m: &mut Map<String, Value>,
    (addr64, addr16, parent): (
        xbee_api::Address64,
        xbee_api::Address16,
        xbee_api::Address16,
    ),
    identifier: &[u8],
    device_type: xbee_api::DeviceType,
) {
    m.insert("addr64".into(), addr64.to_string().into());
    m.insert("addr16".into(), addr16.to_string().into());
    m.insert("identifier".into(), text(identifier));
    m.insert("parent".into(), parent.to_string().into());
    named(m, "device_type", device_type.into(), device_type.name());
}

fn telemetry_values<B: AsRef<[u8]>>(telemetry: &Telemetry<B>) -> Value {
    telemetry
        .as_borrowed()
        .iter()
        .map(|record| {
            let mut v = Map::new();
            v.insert("id".into(), u8::from(record.id).into());
            if let Some(name) = record.id.name() {
                v.insert("name".into(), name.into());
            }
            v.insert("value".into(), float(record.value));
            Value::Object(v)
        })
        .collect()
}

fn waypoints_json<B: AsRef<[u8]>>(waypoints: &Waypoints<B>) -> Value {
    waypoints
        .as_borrowed()
        .iter()
        .map(|w| waypoint(&w))
        .collect()
}

/// One waypoint as a JSON object, as a trajectory's `waypoints` list has them:
/// `{"time":...,"elevator":...,"aileron":...,"altitude":...}`.
pub fn waypoint(w: &Waypoint) -> Value {
    json!({
        "time": w.time,
        "elevator": float(w.elevator),
        "aileron": float(w.aileron),
        "altitude": float(w.altitude),
    })
}

fn address(address: mcp_core::Address) -> Value {
    hex(&address.0).into()
}

fn command_fields<B: AsRef<[u8]>>(m: &mut Map<String, Value>, command: &Command<B>) {
    let ty = command.command_type();
    m.insert("type".into(), ty.to_string().into());
    match command {
        Command::StatusRequest(request) => {
            m.insert("status_request".into(), true.into());
            if let StatusRequest::TelemetryToCoordinator(id) = request {
                named(m, "telemetry", u8::from(*id), id.name());
            }
        }
        Command::TelemetryToCoordinator { on, id } => {
            m.insert("on".into(), (*on).into());
            named(m, "telemetry", u8::from(*id), id.name());
        }
        Command::Landing { on } => {
            m.insert("on".into(), (*on).into());
        }
        Command::Controllers(controller) => {
            named(m, "controller", u8::from(*controller), controller.name());
        }
        Command::TrajectorySet(waypoints) => {
            m.insert("waypoints".into(), waypoints_json(waypoints));
        }
        Command::PositionSlaveSet { slot, address: a } => {
            m.insert("address".into(), address(*a));
            if let Some(slot) = slot {
                m.insert("slot".into(), slot.get().into());
            }
        }
        Command::Time(time) => {
            m.insert("time".into(), (*time).into());
        }
        Command::PositionSet { elevator, aileron } => {
            m.insert("elevator".into(), float(*elevator));
            m.insert("aileron".into(), float(*aileron));
        }
    }
}

fn report_fields<B: AsRef<[u8]>>(m: &mut Map<String, Value>, report: &Report<B>) {
    m.insert("type".into(), report.report_type().to_string().into());
    match report {
        Report::TelemetryToCoordinator { on, id } => {
            m.insert("on".into(), (*on).into());
            named(m, "telemetry", u8::from(*id), id.name());
        }
        Report::Landing(state) => named(m, "state", u8::from(*state), state.name()),
        Report::Controllers(controller) => {
            named(m, "controller", u8::from(*controller), controller.name());
        }
        Report::TrajectorySet(waypoints) => {
            m.insert("waypoints".into(), waypoints_json(waypoints));
        }
        Report::PositionSlaveSet(SlaveAddresses::Single(a)) => {
            m.insert("address".into(), address(*a));
        }
        Report::PositionSlaveSet(SlaveAddresses::Slots(all)) => {
            m.insert(
                "addresses".into(),
                all.iter().map(|a| address(*a)).collect(),
            );
        }
        Report::Time(time) => {
            m.insert("time".into(), (*time).into());
        }
    }
}

/// Adds a recording's `time` (seconds since 1970, with microseconds) and `direction`
/// (`"rx"`/`"tx"`) to a frame object.
pub fn add_record_fields(
    value: &mut Value,
    direction: crate::record::Direction,
    time: std::time::SystemTime,
) {
    if let Value::Object(map) = value {
        map.insert("time".into(), seconds(time).into());
        map.insert("direction".into(), super::text::direction(direction).into());
    }
}

/// An event of a [`crate::PacketStream`] as a JSON object: received packets as
/// `receive` frames, other frames as [`frame`] writes them, decode errors as
/// [`decode_error`] does (without offset), link changes as
/// `{"link":"disconnected","reason":"..."}`. Every object has a `time`, seconds since
/// 1970 (as [`seconds`] writes it): when a packet was received, and for other events
/// (which carry no time) when this function renders them, as they arrive.
pub fn event(event: &Event) -> Value {
    let mut value = match event {
        Event::Packet(rx) => return receive(&rx.origin, packet_json(&rx.packet)),
        Event::InvalidPacket(rx) => return receive(&rx.origin, mcp(&rx.payload)),
        Event::Frame(frame) => match frame.parse() {
            Ok(parsed) => self::frame(&parsed),
            Err(error) => json!({
                "error": "frame",
                "message": error.to_string(),
                "data": hex(frame.data()),
            }),
        },
        Event::DecodeError(error) => decode_error(error, None),
        Event::Link(link) => link_event(link),
    };
    if let Value::Object(map) = &mut value {
        map.insert("time".into(), seconds(std::time::SystemTime::now()).into());
    }
    value
}

/// A time as the JSON objects carry it: seconds since 1970, to the microsecond, as a
/// recording keeps it (0 for a time before 1970).
pub fn seconds(time: std::time::SystemTime) -> f64 {
    time.duration_since(std::time::UNIX_EPOCH).map_or(0.0, |d| {
        let micros = u64::try_from(d.as_micros()).unwrap_or(u64::MAX);
        std::time::Duration::from_micros(micros).as_secs_f64()
    })
}

fn receive(origin: &Origin, mcp: Value) -> Value {
    let time = seconds(origin.received_at);
    json!({
        "frame": "receive",
        "src64": origin.src64.to_string(),
        "src16": origin.src16.to_string(),
        "options": origin.options,
        "mcp": mcp,
        "time": time,
    })
}

fn link_event(link: &LinkEvent) -> Value {
    match link {
        LinkEvent::Connected { peer } => json!({"link": "connected", "peer": peer}),
        LinkEvent::Disconnected { reason } => json!({"link": "disconnected", "reason": reason}),
        LinkEvent::Reconnected { peer } => json!({"link": "reconnected", "peer": peer}),
        LinkEvent::Closed { reason } => json!({"link": "closed", "reason": reason}),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_frame_types_name_is_its_frames_name() {
        for data in [
            &[0x8A, 0x06][..],
            &[0x8B, 1, 0xFF, 0xFE, 0, 0, 0],
            &[0x88, 1, b'A', b'P', 0],
            &[0x08, 1, b'A', b'P'],
            &[0x09, 1, b'A', b'P'],
            &[
                0x90, 0, 0x13, 0xA2, 0, 0x40, 0xB5, 0x99, 0xB9, 0xFF, 0xFE, 0x01,
            ],
        ] {
            let parsed = Frame::parse_bytes(data).unwrap();
            assert_eq!(
                frame_type_name(data[0]),
                frame(&parsed)["frame"].as_str(),
                "{data:02x?}"
            );
        }
        assert_eq!(frame_type_name(0x23), None);
    }

    #[test]
    fn floats_keep_the_shortest_digits_of_their_f32() {
        for (value, text) in [
            (0.999_999_8_f32, "0.9999998"),
            (1.5, "1.5"),
            (-0.1, "-0.1"),
            (f32::MAX, "3.4028235e+38"),
            (f32::MIN_POSITIVE, "1.1754944e-38"),
            (0.0, "0.0"),
            // Subnormals: the f64 they widen to.
            (1e-45, "1.401298464324817e-45"),
            (1e-40, "9.99994610111476e-41"),
            (-1e-39, "-1.0000002153053333e-39"),
        ] {
            let json = float(value).to_string();
            assert_eq!(json, text, "{value}");
            let back: f64 = serde_json::from_str(&json).unwrap();
            assert_eq!(back as f32, value, "{json}");
            // Within a millionth of the exact value, relative, read as an f64.
            let exact = f64::from(value);
            assert!((back - exact).abs() <= 1e-6 * exact.abs(), "{json}");
        }
        assert_eq!(float(f32::NAN), "NaN");
        assert_eq!(float(f32::NEG_INFINITY), "-Infinity");
    }
}
