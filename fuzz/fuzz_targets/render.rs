//! What `mcp-gs decode`, `monitor` and `nodes` print of untrusted frames: the text and
//! JSON forms of any frame data (`render::text::frame`, `render::json::frame`), of any
//! MCP payload (`render::*::mcp`) and of any node discovery answer (`NodeInfo::parse`,
//! `discovery::Node`); and the driver's taking of a Receive Packet's payload and of its
//! packet out of the frame's `Bytes` (`Bytes::slice_ref`, which panics on a slice that
//! is not inside them).
//!
//! Checks: no panic; the text, and the JSON as written, hold no control character and no
//! bidirectional override (a peer's bytes cannot reach a terminal as its escape
//! sequences, nor reorder what it shows).
#![no_main]

use bytes::Bytes;
use libfuzzer_sys::fuzz_target;
use mcp_host::discovery::Node;
use mcp_host::render::{json, text};
use xbee_api::{Frame, NodeInfo};

fn check_text(what: &str, s: &str, data: &[u8]) {
    if let Some(c) = s
        .chars()
        .find(|&c| c.is_control() || matches!(c, '\u{202A}'..='\u{202E}' | '\u{2066}'..='\u{2069}'))
    {
        panic!("{what} of {data:02x?} holds {c:?}: {s:?}");
    }
}

fuzz_target!(|data: &[u8]| {
    // As `driver::dispatch` and `on_payload` take them.
    let frame = Bytes::copy_from_slice(data);
    if let Ok(rx) = xbee_api::ReceivePacketRepr::parse_bytes(&frame) {
        let _ = frame.slice_ref(rx.data);
    }
    if let Ok(rx) = xbee_api::ExplicitRxIndicatorRepr::parse_bytes(&frame) {
        let _ = frame.slice_ref(rx.data);
    }
    if let Ok(packet) = mcp_core::parse(&frame) {
        let _ = packet.map_bytes(|s| frame.slice_ref(s));
    }
    check_text("text::mcp", &text::mcp(data), data);
    check_text("json::mcp", &json::mcp(data).to_string(), data);
    if let Ok(frame) = Frame::parse_bytes(data) {
        check_text("text::frame", &text::frame(&frame), data);
        check_text("json::frame", &json::frame(&frame).to_string(), data);
    }
    if let Ok(info) = NodeInfo::parse(data) {
        let node = Node::from(&info);
        check_text("Node", &node.to_string(), data);
        check_text("json::node", &json::node(&node).to_string(), data);
    }
});
