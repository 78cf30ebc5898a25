//! The one-line text form of frames and packets (`mcp-gs --format text`).

use std::fmt::Write;
use std::time::{SystemTime, UNIX_EPOCH};

use xbee_api::{AtStatus, DecodeError, Frame};

use super::json::hex;

/// An MCP payload as text: the packet, or why it is invalid and its bytes.
pub fn mcp(payload: &[u8]) -> String {
    match mcp_core::parse(payload) {
        Ok(packet) => packet.to_string(),
        Err(error) => invalid_mcp(&error, payload),
    }
}

/// An invalid MCP payload: why, and its bytes (none to show for an empty one).
fn invalid_mcp(error: &impl std::fmt::Display, payload: &[u8]) -> String {
    if payload.is_empty() {
        format!("invalid MCP packet ({error})")
    } else {
        format!("invalid MCP packet ({error}): {}", hex(payload))
    }
}

/// One frame as a line of text (no newline).
pub fn frame(frame: &Frame<'_>) -> String {
    let mut s = String::new();
    let _ = match frame {
        Frame::ReceivePacket(rx) => write!(
            s,
            "rx  {}/{} opt {:02x}: {}",
            rx.src64,
            rx.src16,
            rx.options,
            mcp(rx.data)
        ),
        Frame::TransmitRequest(tx) => write!(
            s,
            "tx  {}/{} id {} radius {} opt {:02x}: {}",
            tx.dst64,
            tx.dst16,
            tx.frame_id,
            tx.radius,
            tx.options,
            mcp(tx.data)
        ),
        Frame::TransmitStatus(st) => write!(
            s,
            "transmit status id {} to {}: delivery {} (0x{:02x}), retries {}, discovery {} (0x{:02x})",
            st.frame_id,
            st.dst16,
            st.delivery,
            u8::from(st.delivery),
            st.retries,
            st.discovery,
            u8::from(st.discovery)
        ),
        Frame::ModemStatus(ms) => write!(
            s,
            "modem status {} (0x{:02x})",
            ms.status,
            u8::from(ms.status)
        ),
        Frame::AtCommand(at) => write!(
            s,
            "at{} id {} {}{}",
            if at.queued { " queued" } else { "" },
            at.frame_id,
            at_name(at.command),
            data_suffix(at.parameter)
        ),
        Frame::AtCommandResponse(at) => write!(
            s,
            "at response id {} {} {}{}",
            at.frame_id,
            at_name(at.command),
            at_status(at.status),
            data_suffix(at.data)
        ),
        Frame::RemoteAtCommand(at) => write!(
            s,
            "remote at id {} to {}/{} opt {:02x} {}{}",
            at.frame_id,
            at.dst64,
            at.dst16,
            at.options,
            at_name(at.command),
            data_suffix(at.parameter)
        ),
        Frame::RemoteAtResponse(at) => write!(
            s,
            "remote at response id {} from {}/{} {} {}{}",
            at.frame_id,
            at.src64,
            at.src16,
            at_name(at.command),
            at_status(at.status),
            data_suffix(at.data)
        ),
        Frame::ExplicitAddressingCommand(tx) => write!(
            s,
            "explicit tx {}/{} id {} ep {:02x}->{:02x} cluster {:04x} profile {:04x}: {}",
            tx.dst64,
            tx.dst16,
            tx.frame_id,
            tx.src_endpoint,
            tx.dst_endpoint,
            tx.cluster_id,
            tx.profile_id,
            mcp(tx.data)
        ),
        Frame::ExplicitRxIndicator(rx) => write!(
            s,
            "explicit rx {}/{} ep {:02x}->{:02x} cluster {:04x} profile {:04x} opt {:02x}: {}",
            rx.src64,
            rx.src16,
            rx.src_endpoint,
            rx.dst_endpoint,
            rx.cluster_id,
            rx.profile_id,
            rx.options,
            mcp(rx.data)
        ),
        Frame::NodeIdentificationIndicator(ni) => write!(
            s,
            "node identification {}/{} {} {} parent {}: {} (0x{:02x}), from {}/{} opt {:02x}",
            ni.node.addr64,
            ni.node.addr16,
            ni.node.device_type,
            mcp_core::Text::new(ni.node.identifier).quoted(),
            ni.node.parent,
            ni.source_event(),
            u8::from(ni.source_event()),
            ni.src64,
            ni.src16,
            ni.options
        ),
        Frame::Unknown { frame_type, data } => {
            write!(s, "frame type 0x{frame_type:02x}{}", data_suffix(data))
        }
        // A frame type that xbee-api learned to read after this renderer was written.
        other => write!(s, "frame type 0x{:02x}", other.frame_type()),
    };
    s
}

/// An AT command name as it may be shown: its two characters, or their hex when either
/// is not a printable ASCII character (a name from a peer may hold a terminal's escape
/// byte).
///
/// ```
/// use mcp_host::render::text::at_name;
/// assert_eq!(at_name(*b"AP"), "AP");
/// assert_eq!(at_name(*b"\x1bc"), "1b63");
/// ```
pub fn at_name(command: [u8; 2]) -> String {
    if command.iter().all(|b| b.is_ascii_graphic()) {
        command.iter().map(|&b| char::from(b)).collect()
    } else {
        hex(&command)
    }
}

fn data_suffix(data: &[u8]) -> String {
    if data.is_empty() {
        String::new()
    } else {
        format!(" {}", hex(data))
    }
}

/// A dropped frame as a line of text, with the input offset at which the decoder
/// dropped it when known (the frame started before it).
pub fn decode_error(error: &DecodeError, offset: Option<u64>) -> String {
    match offset {
        Some(offset) => format!("error, found at input offset {offset}: {error}"),
        None => format!("error: {error}"),
    }
}

/// A valid packet received, as a line of text: `rx  SRC64/SRC16 opt OPTIONS: PACKET`.
pub fn received(rx: &crate::Received) -> String {
    format!(
        "rx  {}/{} opt {:02x}: {}",
        rx.origin.src64,
        rx.origin.src16,
        rx.origin.options,
        rx.packet.as_borrowed()
    )
}

/// An event of a [`crate::PacketStream`] as a line of text (no time stamp: see
/// [`time()`]).
pub fn event(event: &crate::Event) -> String {
    use crate::Event;
    match event {
        Event::Packet(rx) => received(rx),
        Event::InvalidPacket(rx) => format!(
            "rx  {}/{} opt {:02x}: {}",
            rx.origin.src64,
            rx.origin.src16,
            rx.origin.options,
            invalid_mcp(&rx.error, &rx.payload)
        ),
        Event::Frame(owned) => match owned.parse() {
            Ok(parsed) => frame(&parsed),
            Err(error) => format!("error: {error}: {}", hex(owned.data())),
        },
        Event::DecodeError(error) => decode_error(error, None),
        Event::Link(event) => event.to_string(),
    }
}

/// An AT status: its name, or for a code with upper bits set, what its low four bits
/// say and the code (`ok (0x40)`).
fn at_status(status: AtStatus) -> String {
    let meaning = status.meaning();
    if meaning == status {
        status.to_string()
    } else {
        format!("{meaning} (0x{:02x})", u8::from(status))
    }
}

/// `rx` or `tx`.
pub fn direction(direction: crate::record::Direction) -> &'static str {
    match direction {
        crate::record::Direction::Received => "rx",
        crate::record::Direction::Sent => "tx",
    }
}

/// A time as UTC `HH:MM:SS.mmm` (its date: [`DateLines`]).
pub fn time(time: SystemTime) -> String {
    let of_day = unix_millis(time).rem_euclid(DAY_MILLIS);
    format!(
        "{:02}:{:02}:{:02}.{:03}",
        of_day / 3_600_000,
        of_day / 60_000 % 60,
        of_day / 1000 % 60,
        of_day % 1000
    )
}

/// Milliseconds in a day.
const DAY_MILLIS: i128 = 86_400_000;

/// Milliseconds since 1970-01-01 00:00:00 UTC, rounded down: negative before it, the
/// last instant of 1969 in 1969.
fn unix_millis(time: SystemTime) -> i128 {
    match time.duration_since(UNIX_EPOCH) {
        Ok(after) => i128::try_from(after.as_millis()).unwrap_or(i128::MAX),
        Err(before) => {
            // At most about 1.8e28: no overflow below.
            let nanos = i128::try_from(before.duration().as_nanos()).unwrap_or(i128::MAX / 2);
            -((nanos + 999_999) / 1_000_000)
        }
    }
}

/// A time's UTC calendar date, `YYYY-MM-DD`; `None` for a time out of the years -9999
/// to 9999 (a damaged recording's, say).
pub fn date(time: SystemTime) -> Option<String> {
    let seconds = i64::try_from(unix_millis(time).div_euclid(1000)).ok()?;
    let stamp = ::time::OffsetDateTime::from_unix_timestamp(seconds).ok()?;
    Some(stamp.date().to_string())
}

/// The dates of text output whose lines carry only the time of day ([`time()`]): a line
/// `-- YYYY-MM-DD (UTC) --` before the first line and before each line on another UTC
/// day than the line before it, as a recording that spans midnight or a monitor left
/// running for days has.
///
/// ```
/// use std::time::{Duration, UNIX_EPOCH};
/// use mcp_host::render::text::DateLines;
///
/// let mut dates = DateLines::new();
/// let evening = UNIX_EPOCH + Duration::from_secs(1_700_000_000); // 22:13:20 UTC
/// assert_eq!(dates.before(evening).as_deref(), Some("-- 2023-11-14 (UTC) --"));
/// assert_eq!(dates.before(evening + Duration::from_secs(3600)), None);
/// let after_midnight = evening + Duration::from_secs(7200);
/// assert_eq!(dates.before(after_midnight).as_deref(), Some("-- 2023-11-15 (UTC) --"));
/// ```
#[derive(Debug, Clone, Default)]
pub struct DateLines {
    /// The UTC day (days since 1970) of the line before, once there is one.
    day: Option<i128>,
}

impl DateLines {
    /// No line shown yet: the first one gets its date.
    pub const fn new() -> Self {
        Self { day: None }
    }

    /// The line to print before a line stamped `time`, if it is on another day than the
    /// line before it (or is the first). A time with no calendar date ([`date`]) is
    /// shown as `-- no date (UTC) --`.
    pub fn before(&mut self, time: SystemTime) -> Option<String> {
        let day = unix_millis(time).div_euclid(DAY_MILLIS);
        if self.day == Some(day) {
            return None;
        }
        self.day = Some(day);
        let date = date(time).unwrap_or_else(|| "no date".to_owned());
        Some(format!("-- {date} (UTC) --"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn an_empty_invalid_packet_shows_no_bytes() {
        assert_eq!(mcp(b""), "invalid MCP packet (empty packet (at offset 0))");
        assert_eq!(
            mcp(b"c\x09"),
            "invalid MCP packet (unknown command type 0x09 (at offset 1)): 6309"
        );
    }

    #[test]
    fn dates_around_1970_midnights_and_out_of_range() {
        let at = |secs: i64| {
            let d = Duration::from_secs(secs.unsigned_abs());
            if secs < 0 {
                UNIX_EPOCH - d
            } else {
                UNIX_EPOCH + d
            }
        };
        assert_eq!(time(at(0)), "00:00:00.000");
        assert_eq!(
            time(at(86_399) + Duration::from_micros(999_999)),
            "23:59:59.999"
        );
        assert_eq!(time(UNIX_EPOCH - Duration::from_micros(1)), "23:59:59.999");
        assert_eq!(time(at(-86_400)), "00:00:00.000");
        assert_eq!(date(at(0)).as_deref(), Some("1970-01-01"));
        assert_eq!(date(at(-1)).as_deref(), Some("1969-12-31"));
        assert_eq!(
            date(UNIX_EPOCH - Duration::from_nanos(1)).as_deref(),
            Some("1969-12-31")
        );
        assert_eq!(date(at(86_399)).as_deref(), Some("1970-01-01"));
        assert_eq!(date(at(86_400)).as_deref(), Some("1970-01-02"));
        assert_eq!(date(at(951_782_400)).as_deref(), Some("2000-02-29"));
        assert_eq!(date(at(253_402_300_799)).as_deref(), Some("9999-12-31"));
        assert_eq!(date(at(253_402_300_800)), None);
        // The latest time a recording can hold (`u64` microseconds).
        let latest = UNIX_EPOCH + Duration::from_micros(u64::MAX);
        assert_eq!(date(latest), None);

        let mut dates = DateLines::new();
        assert_eq!(
            dates.before(at(-1)).as_deref(),
            Some("-- 1969-12-31 (UTC) --")
        );
        assert_eq!(
            dates.before(at(0)).as_deref(),
            Some("-- 1970-01-01 (UTC) --")
        );
        assert_eq!(dates.before(at(86_399)), None);
        assert_eq!(dates.before(latest).as_deref(), Some("-- no date (UTC) --"));
        assert_eq!(dates.before(latest), None);
        // Back in time (a clock set back): the date again.
        assert_eq!(
            dates.before(at(0)).as_deref(),
            Some("-- 1970-01-01 (UTC) --")
        );
    }

    #[test]
    fn an_at_status_with_upper_bits_shows_what_its_low_bits_say_and_the_code() {
        assert_eq!(at_status(AtStatus::Ok), "ok");
        assert_eq!(at_status(AtStatus::from(0x40)), "ok (0x40)");
        assert_eq!(at_status(AtStatus::from(0x44)), "tx_failure (0x44)");
        assert_eq!(at_status(AtStatus::from(0x0E)), "unknown(0x0E)");
        let frame = Frame::parse_bytes(&[0x88, 0x01, 0x42, 0x44, 0x40]).unwrap();
        assert_eq!(super::frame(&frame), "at response id 1 BD ok (0x40)");
        let json = super::super::json::frame(&frame);
        assert_eq!(json["status"], 0x40);
        assert_eq!(json["status_name"], "ok");
    }
}
