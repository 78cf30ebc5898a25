//! Digi's xbee-python streams (testdata/ap1.bin, ap2.bin) through a real pseudo-terminal:
//! the stream yields exactly the frames of the expected files, in order.

mod common;

use common::*;
use mcp_host::Event;
use xbee_api::ApiMode;

fn expected(name: &str) -> Vec<serde_json::Value> {
    let path = format!("{}/../testdata/{name}", env!("CARGO_MANIFEST_DIR"));
    std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("{path}: {e}"))
        .lines()
        .map(|line| serde_json::from_str(line).unwrap())
        .collect()
}

fn frame_kind(frame_type: u8) -> &'static str {
    match frame_type {
        0x10 => "transmit",
        0x8B => "transmit_status",
        0x8A => "modem_status",
        0x88 => "at_response",
        _ => "unknown",
    }
}

async fn replay(mode: ApiMode, bin: &str, jsonl: &str) {
    let (mut stream, _sender, mut fake) = pty_link(mode).await;
    let bytes = std::fs::read(format!("{}/../testdata/{bin}", env!("CARGO_MANIFEST_DIR"))).unwrap();
    fake.write_raw(&bytes).await;

    for (n, want) in expected(jsonl).iter().enumerate() {
        let event = next_event(&mut stream).await;
        let kind = want["frame"].as_str().unwrap();
        match event {
            Event::Packet(rx) => {
                assert_eq!(kind, "receive", "#{n}");
                assert_eq!(rx.origin.src64.to_string(), want["src64"], "#{n}");
                assert_eq!(rx.origin.src16.to_string(), want["src16"], "#{n}");
                assert_eq!(u64::from(rx.origin.options), want["options"], "#{n}");
                let category = rx.packet.category().name().unwrap();
                assert_eq!(category, want["mcp"]["category"], "#{n}");
            }
            Event::InvalidPacket(p) => {
                assert_eq!(kind, "receive", "#{n}");
                assert_eq!(p.origin.src64.to_string(), want["src64"], "#{n}");
                assert_eq!(want["mcp"]["category"], "invalid", "#{n}");
            }
            Event::Frame(frame) => {
                assert_eq!(frame_kind(frame.frame_type()), kind, "#{n}: {frame:?}");
                if let Some(id) = want.get("id") {
                    assert_eq!(frame.frame_id().map(u64::from), id.as_u64(), "#{n}");
                }
            }
            other => panic!("#{n}: unexpected {other:?}, want {want}"),
        }
    }
    let stats = stream.stats();
    assert_eq!(stats.decode_errors(), 0);
    assert_eq!(stats.frames, expected(jsonl).len() as u64);
}

#[tokio::test]
async fn api_mode_1_stream_matches_its_expected_frames() {
    replay(ApiMode::Unescaped, "ap1.bin", "ap1.expected.jsonl").await;
}

#[tokio::test]
async fn api_mode_2_stream_matches_its_expected_frames() {
    replay(ApiMode::Escaped, "ap2.bin", "ap2.expected.jsonl").await;
}
