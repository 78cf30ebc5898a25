//! The xbee-python streams (testdata/ap1.bin in mode 1, ap2.bin in mode 2) decode to
//! exactly the frames of their expected JSONL files, in order, without decode errors,
//! whatever the read sizes.

mod common;

use common::{Owned, decode_bytes, decode_slices, frames, testdata, to_hex};
use serde_json::{Value, json};
use xbee_api::{ApiMode, Frame};

/// The frame-level fields of `frame`, in the schema of the expected files (no `mcp`).
fn frame_json(frame: &Frame<'_>) -> Value {
    match frame {
        Frame::ReceivePacket(rx) => json!({
            "frame": "receive",
            "src64": rx.src64.to_string(),
            "src16": rx.src16.to_string(),
            "options": rx.options,
        }),
        Frame::TransmitRequest(tx) => json!({
            "frame": "transmit",
            "id": tx.frame_id,
            "dst64": tx.dst64.to_string(),
            "dst16": tx.dst16.to_string(),
            "radius": tx.radius,
            "options": tx.options,
        }),
        Frame::TransmitStatus(st) => json!({
            "frame": "transmit_status",
            "id": st.frame_id,
            "dst16": st.dst16.to_string(),
            "retries": st.retries,
            "delivery": u8::from(st.delivery),
            "discovery": u8::from(st.discovery),
        }),
        Frame::ModemStatus(ms) => json!({
            "frame": "modem_status",
            "status": u8::from(ms.status),
        }),
        Frame::AtCommandResponse(at) => json!({
            "frame": "at_response",
            "id": at.frame_id,
            "command": String::from_utf8_lossy(&at.command),
            "status": u8::from(at.status),
            "data": to_hex(at.data),
        }),
        Frame::Unknown { frame_type, data } => json!({
            "frame": "unknown",
            "type": frame_type,
            "data": to_hex(data),
        }),
        other => panic!("frame kind not in the expected files: {other:?}"),
    }
}

fn expected(name: &str) -> Vec<Value> {
    String::from_utf8(testdata(name))
        .unwrap()
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(|line| {
            let mut v: Value = serde_json::from_str(line).unwrap();
            v.as_object_mut().unwrap().remove("mcp");
            v
        })
        .collect()
}

fn check(mode: ApiMode, events: &[Owned], expected: &[Value]) {
    let errors: Vec<_> = events
        .iter()
        .filter(|e| matches!(e, Owned::Error(_)))
        .collect();
    assert!(errors.is_empty(), "{mode}: decode errors {errors:?}");
    let got: Vec<Value> = frames(events)
        .iter()
        .map(|data| frame_json(&Frame::parse_bytes(data).unwrap()))
        .collect();
    assert_eq!(got.len(), expected.len(), "{mode}: frame count");
    for (i, (g, e)) in got.iter().zip(expected).enumerate() {
        assert_eq!(g, e, "{mode}: frame {i}");
    }
}

fn check_stream(mode: ApiMode, bin: &str, jsonl: &str) {
    let stream = testdata(bin);
    let expected = expected(jsonl);
    for reads in [&[stream.len()][..], &[1], &[7, 1, 64, 3], &[4096]] {
        let (events, stats) = decode_slices::<512>(mode, &stream, reads);
        check(mode, &events, &expected);
        assert_eq!(stats.frames_ok as usize, expected.len());
        assert_eq!(stats.errors(), 0);
        assert_eq!(stats.bytes_skipped, 0);
    }
    let (events, _) = decode_bytes::<512>(mode, &stream);
    check(mode, &events, &expected);
}

#[test]
fn ap1_mode1_stream_matches_expected() {
    check_stream(ApiMode::Unescaped, "ap1.bin", "ap1.expected.jsonl");
}

#[test]
fn ap2_mode2_stream_matches_expected() {
    check_stream(ApiMode::Escaped, "ap2.bin", "ap2.expected.jsonl");
}

#[test]
fn streams_reencode_to_the_same_bytes() {
    use xbee_api::EncodeFrame;
    for (mode, bin) in [
        (ApiMode::Unescaped, "ap1.bin"),
        (ApiMode::Escaped, "ap2.bin"),
    ] {
        let stream = testdata(bin);
        let (events, _) = decode_slices::<512>(mode, &stream, &[stream.len()]);
        let mut out = Vec::new();
        for data in frames(&events) {
            let frame = Frame::parse_bytes(&data).unwrap();
            let mut buf = vec![0u8; frame.encoded_len(mode)];
            let n = frame.encode(mode, &mut buf).unwrap();
            out.extend_from_slice(&buf[..n]);
        }
        assert_eq!(out, stream, "{mode}");
    }
}
