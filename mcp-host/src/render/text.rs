//! The one-line text form of frames and packets (`mcp-gs --format text`).

use std::fmt::Write;

use xbee_api::{AtStatus, DecodeError, Frame};

use super::json::hex;

/// An MCP payload as text: the packet, or why it is invalid and its bytes.
pub fn mcp(payload: &[u8]) -> String {
    match mcp_core::parse(payload) {
        Ok(packet) => packet.to_string(),
        Err(error) => format!("invalid MCP packet ({error}): {}", hex(payload)),
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
            hex(tx.data)
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
            hex(rx.data)
        ),
        Frame::Unknown { frame_type, data } => {
            write!(s, "frame type 0x{frame_type:02x}{}", data_suffix(data))
        }
        // A frame type that xbee-api learned to read after this renderer was written.
        other => write!(s, "frame type 0x{:02x}", other.frame_type()),
    };
    s
}

fn at_name(command: [u8; 2]) -> String {
    super::json::at_name(command)
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

/// An event of a [`crate::PacketStream`] as a line of text (no time stamp: see
/// [`time`]).
pub fn event(event: &crate::Event) -> String {
    use crate::{Event, LinkEvent};
    match event {
        Event::Packet(rx) => format!(
            "rx  {}/{} opt {:02x}: {}",
            rx.origin.src64,
            rx.origin.src16,
            rx.origin.options,
            rx.packet.as_borrowed()
        ),
        Event::InvalidPacket(rx) => format!(
            "rx  {}/{} opt {:02x}: invalid MCP packet ({}): {}",
            rx.origin.src64,
            rx.origin.src16,
            rx.origin.options,
            rx.error,
            hex(&rx.payload)
        ),
        Event::Frame(owned) => match owned.parse() {
            Ok(parsed) => frame(&parsed),
            Err(error) => format!("error: {error}: {}", hex(owned.data())),
        },
        Event::DecodeError(error) => decode_error(error, None),
        Event::Link(LinkEvent::Connected { peer }) => format!("link connected: {peer}"),
        Event::Link(LinkEvent::Disconnected { reason }) => format!("link disconnected: {reason}"),
        Event::Link(LinkEvent::Reconnected { peer }) => format!("link reconnected: {peer}"),
        Event::Link(LinkEvent::Closed { reason }) => format!("link closed: {reason}"),
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

/// A time as UTC `HH:MM:SS.mmm`.
pub fn time(time: std::time::SystemTime) -> String {
    let d = time
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap_or_default();
    let secs = d.as_secs();
    format!(
        "{:02}:{:02}:{:02}.{:03}",
        secs / 3600 % 24,
        secs / 60 % 60,
        secs % 60,
        d.subsec_millis()
    )
}

#[cfg(test)]
mod tests {
    use super::*;

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
