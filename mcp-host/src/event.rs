//! What a [`crate::PacketStream`] yields.

use std::fmt;
use std::time::SystemTime;

use bytes::Bytes;
use xbee_api::{Address16, Address64};

/// The byte storage of owned MCP packets: slices of the received frame, no copy.
pub type OwnedPacket = mcp_core::Packet<Bytes>;

/// Something that happened on the link.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Event {
    /// A valid MCP packet arrived.
    Packet(Received),
    /// A Receive Packet whose payload is not a valid MCP packet.
    InvalidPacket(InvalidPacket),
    /// Any other frame: modem status, a transmit status or response that no request in
    /// flight claimed, AT responses, unknown frame types.
    Frame(OwnedFrame),
    /// The transport went down, came up, or the link ended.
    Link(LinkEvent),
    /// A frame was dropped by the framing layer (bad checksum, cut off, ...); the stream
    /// resynchronises on the next start delimiter.
    DecodeError(xbee_api::DecodeError),
}

impl Event {
    /// The MCP packet, if this is one.
    pub fn packet(&self) -> Option<&Received> {
        match self {
            Event::Packet(rx) => Some(rx),
            _ => None,
        }
    }

    /// The MCP packet, if this is one, owned: for `filter_map` over a stream of events.
    ///
    /// ```
    /// # async fn run(stream: mcp_host::PacketStream) {
    /// use futures::{StreamExt, future::ready};
    /// use mcp_host::Event;
    ///
    /// let mut packets = stream.filter_map(|event| ready(event.into_packet()));
    /// while let Some(rx) = packets.next().await {
    ///     println!("{} {}", rx.origin.src64, rx.packet);
    /// }
    /// # }
    /// ```
    pub fn into_packet(self) -> Option<Received> {
        match self {
            Event::Packet(rx) => Some(rx),
            _ => None,
        }
    }

    /// Where and when the radio frame came from, for an MCP packet, valid or not.
    pub fn origin(&self) -> Option<&Origin> {
        match self {
            Event::Packet(rx) => Some(&rx.origin),
            Event::InvalidPacket(invalid) => Some(&invalid.origin),
            _ => None,
        }
    }
}

/// One line of text, as `mcp-gs monitor` prints it (without its time of day):
/// [`render::text::event`](crate::render::text::event).
///
/// ```
/// use mcp_host::xbee_api::DecodeError;
/// use mcp_host::Event;
///
/// let event = Event::DecodeError(DecodeError::EmptyFrame);
/// assert_eq!(event.to_string(), "error: frame length 0");
/// ```
impl fmt::Display for Event {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&crate::render::text::event(self))
    }
}

/// Where and when a radio frame came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Origin {
    /// 64-bit source address.
    pub src64: Address64,
    /// 16-bit source network address.
    pub src16: Address16,
    /// Receive options byte of the frame (0x01 acknowledged, 0x02 broadcast, ...).
    pub options: u8,
    /// When the frame was decoded.
    pub received_at: SystemTime,
}

/// A valid MCP packet, with where it came from.
#[derive(Debug, Clone, PartialEq)]
pub struct Received {
    /// Source and time.
    pub origin: Origin,
    /// The packet; its byte views share the frame's storage.
    pub packet: OwnedPacket,
    /// The raw MCP payload.
    pub payload: Bytes,
    /// The API frame it came in, as received: its frame data, type byte first (a
    /// Receive Packet, 0x90, or an Explicit Rx Indicator, 0x91). `payload` is part of it.
    pub frame: Bytes,
}

/// The line [`Event::Packet`] shows: `rx  0013a20040522baa/7d84 opt 01: telemetry
/// altitude=1.5` ([`render::text::received`](crate::render::text::received)).
impl fmt::Display for Received {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&crate::render::text::received(self))
    }
}

/// A Receive Packet whose payload failed to parse as MCP.
#[derive(Debug, Clone, PartialEq)]
pub struct InvalidPacket {
    /// Source and time.
    pub origin: Origin,
    /// What was wrong, and at which byte.
    pub error: mcp_core::Error,
    /// The payload as received.
    pub payload: Bytes,
    /// The API frame it came in, as received: its frame data, type byte first (0x90 or
    /// 0x91). `payload` is part of it.
    pub frame: Bytes,
}

/// Where a link is, as [`CommandSender::link_state`](crate::CommandSender::link_state)
/// and [`PacketStream::link_state`](crate::PacketStream::link_state) tell at any time
/// (the [`LinkEvent`]s tell each change).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum LinkState {
    /// Not connected yet: a `tcp-listen` or `pty` link waiting for its first peer, or a
    /// `serial` or `tcp` one waiting for its device
    /// ([`LinkOptions::wait_for_link`](crate::LinkOptions::wait_for_link)).
    Connecting,
    /// The transport is up. Over `tcp:`, that the peer took the connection, not that
    /// it serves it: a peer that serves one connection at a time (`mcp-gs sim` and
    /// `radio`, many serial-to-TCP bridges) lets the next wait its turn, saying
    /// nothing, and carries out what it was sent meanwhile once its turn comes, even a
    /// command whose send timed out here. Share a radio through
    /// [`hub`](crate::hub) instead.
    Connected,
    /// The transport went away; the link is reconnecting.
    Reconnecting,
    /// The link ended for good; its transport is closed.
    Closed,
}

/// Shown as `connecting`, `connected`, `reconnecting` or `closed`.
impl fmt::Display for LinkState {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            LinkState::Connecting => "connecting",
            LinkState::Connected => "connected",
            LinkState::Reconnecting => "reconnecting",
            LinkState::Closed => "closed",
        })
    }
}

/// A transport state change.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub enum LinkEvent {
    /// The transport is up for the first time (for `tcp-listen`: the first peer arrived).
    /// Over `tcp:`, the peer may still let the connection wait its turn: see
    /// [`LinkState::Connected`].
    ///
    /// It comes first on the stream of every link, also of one that
    /// [`connect`](crate::connect) opened before it returned (a `serial:` or `tcp:` link
    /// without [`wait_for_link`](crate::LinkOptions::wait_for_link)), where it waits to
    /// be read: a program that sends right after `connect` reads it after those sends
    /// were answered. A program that sets its MAV up once a connection (turns its
    /// telemetry on) does so either on this event and on [`Reconnected`](Self::Reconnected),
    /// which works whenever the link comes up, or right after `connect` and on
    /// `Reconnected` (the `telemetry` example), not on both this event and after
    /// `connect`, which would do it twice.
    #[non_exhaustive]
    Connected {
        /// What is at the other end.
        peer: String,
    },
    /// The transport went away; requests in flight failed. Reconnection follows unless
    /// disabled.
    #[non_exhaustive]
    Disconnected {
        /// Why.
        reason: String,
    },
    /// The transport is up again after a disconnection.
    #[non_exhaustive]
    Reconnected {
        /// What is at the other end now.
        peer: String,
    },
    /// The link ended for good (reconnection disabled or impossible, or
    /// [`CommandSender::close`](crate::CommandSender::close)); the stream ends after this
    /// event.
    #[non_exhaustive]
    Closed {
        /// Why.
        reason: String,
    },
}

/// The line [`Event::Link`] shows too: `link disconnected: REASON`.
impl fmt::Display for LinkEvent {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LinkEvent::Connected { peer } => write!(f, "link connected: {peer}"),
            LinkEvent::Disconnected { reason } => write!(f, "link disconnected: {reason}"),
            LinkEvent::Reconnected { peer } => write!(f, "link reconnected: {peer}"),
            LinkEvent::Closed { reason } => write!(f, "link closed: {reason}"),
        }
    }
}

/// An XBee API frame, owned: the frame data (frame type byte first) without delimiter,
/// length or checksum.
#[derive(Clone, PartialEq, Eq)]
pub struct OwnedFrame {
    data: Bytes,
}

impl OwnedFrame {
    /// Wraps frame data (frame type first). Returns `None` for empty data.
    pub fn new(data: Bytes) -> Option<Self> {
        (!data.is_empty()).then_some(OwnedFrame { data })
    }

    /// The frame type byte.
    pub fn frame_type(&self) -> u8 {
        self.data.first().copied().unwrap_or(0)
    }

    /// The frame id, for frame types that carry one in their second byte (requests and
    /// their responses: 0x00, 0x01, 0x08, 0x09, 0x10, 0x11, 0x17, 0x20, 0x24, 0x88,
    /// 0x89, 0x8B, 0x97, 0xA4).
    pub fn frame_id(&self) -> Option<u8> {
        if xbee_api::frame::frame_type::carries_frame_id(self.frame_type()) {
            self.data.get(1).copied()
        } else {
            None
        }
    }

    /// The frame data, frame type byte first.
    pub fn data(&self) -> &Bytes {
        &self.data
    }

    /// The typed view (fails when the data is too short for its frame type).
    pub fn parse(&self) -> Result<xbee_api::Frame<'_>, xbee_api::FrameError> {
        xbee_api::Frame::parse_bytes(&self.data)
    }
}

impl fmt::Debug for OwnedFrame {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "OwnedFrame(0x{:02X}:", self.frame_type())?;
        for b in self.data.iter().skip(1) {
            write!(f, " {b:02X}")?;
        }
        f.write_str(")")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn link_states_and_events_show_as_the_event_lines_do() {
        let states = [
            LinkState::Connecting,
            LinkState::Connected,
            LinkState::Reconnecting,
            LinkState::Closed,
        ];
        let shown: Vec<String> = states.iter().map(ToString::to_string).collect();
        assert_eq!(shown, ["connecting", "connected", "reconnecting", "closed"]);
        let down = LinkEvent::Disconnected {
            reason: "read: connection reset".into(),
        };
        assert_eq!(
            down.to_string(),
            "link disconnected: read: connection reset"
        );
        assert_eq!(Event::Link(down.clone()).to_string(), down.to_string());
        let up = LinkEvent::Reconnected {
            peer: "127.0.0.1:9750".into(),
        };
        assert_eq!(up.to_string(), "link reconnected: 127.0.0.1:9750");
    }
}
