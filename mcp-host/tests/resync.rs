//! The stream survives garbage, corrupt and cut-off frames between valid ones, in both
//! API modes, over a real pseudo-terminal.

mod common;

use common::*;
use mcp_core::{Packet, TelemetryBuilder, TelemetryId};
use mcp_host::Event;
use xbee_api::{ApiMode, DecodeError};

fn telemetry(k: u32) -> Vec<u8> {
    let mut buf = [0u8; 32];
    let mut t = TelemetryBuilder::new(&mut buf).unwrap();
    t.push(TelemetryId::Altitude, k as f32).unwrap();
    // A value whose bytes need escaping in mode 2 (0x7E, 0x7D, 0x11, 0x13).
    t.push(
        TelemetryId::Unknown(0x7E),
        f32::from_le_bytes([0x7E, 0x7D, 0x11, 0x13]),
    )
    .unwrap();
    let len = t.finish();
    buf[..len].to_vec()
}

/// Garbage without start delimiters.
fn garbage(seed: u32, len: usize) -> Vec<u8> {
    let mut x = seed.wrapping_mul(2_654_435_761).wrapping_add(1);
    (0..len)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            match (x & 0xFF) as u8 {
                0x7E => 0x00,
                b => b,
            }
        })
        .collect()
}

async fn survives(mode: ApiMode) {
    let (mut stream, _sender, mut fake) = pty_link(mode).await;

    const N: u32 = 40;
    let mut bytes = Vec::new();
    for k in 0..N {
        let frame = fake.encode(&rx(MAV, &telemetry(k)));
        if k < 30 {
            match k % 5 {
                0 => bytes.extend(garbage(k, 1 + k as usize)),
                1 => {
                    // The same frame with a corrupted payload byte: bad checksum.
                    let mut bad = frame.clone();
                    let i = bad.len() - 3;
                    bad[i] ^= 0x01;
                    bytes.extend(bad);
                }
                2 => {
                    // The first half of a frame, cut off.
                    bytes.extend(&frame[..frame.len() / 2]);
                }
                3 => {
                    // A lone start delimiter and a bogus length in the noise.
                    bytes.extend([0x7E, 0x00, 0x30]);
                    bytes.extend(garbage(k, 5));
                }
                _ => {}
            }
        }
        bytes.extend(frame);
    }
    // Trailing valid frames flush any candidate still waiting for its length in mode 1.
    fake.write_raw(&bytes).await;

    let mut values = Vec::new();
    let mut errors = Vec::new();
    while values.len() < N as usize {
        match next_event(&mut stream).await {
            Event::Packet(rx) => {
                let Packet::Telemetry(t) = rx.packet else {
                    panic!("{:?}", rx.packet)
                };
                values.push(t.value(TelemetryId::Altitude).unwrap() as u32);
            }
            Event::DecodeError(e) => errors.push(e),
            other => panic!("unexpected {other:?}"),
        }
    }
    assert_eq!(
        values,
        (0..N).collect::<Vec<_>>(),
        "every valid frame, in order"
    );
    assert!(
        errors
            .iter()
            .any(|e| matches!(e, DecodeError::BadChecksum { .. })),
        "{errors:?}"
    );
    if mode == ApiMode::Escaped {
        // A raw 0x7E cuts a partial frame off.
        assert!(
            errors
                .iter()
                .any(|e| matches!(e, DecodeError::Truncated { .. })),
            "{errors:?}"
        );
    }
    let stats = stream.stats();
    assert_eq!(stats.frames, u64::from(N));
    assert!(stats.decode_errors() >= errors.len() as u64);
    assert!(stats.bytes_skipped > 0);
}

#[tokio::test]
async fn survives_garbage_and_corrupt_frames_in_api_mode_1() {
    survives(ApiMode::Unescaped).await;
}

#[tokio::test]
async fn survives_garbage_and_corrupt_frames_in_api_mode_2() {
    survives(ApiMode::Escaped).await;
}

/// A frame over `LinkOptions::max_frame_len` is dropped at its length field: in mode 1
/// a valid frame inside it still comes out, and one with a bad checksum is oversize too.
#[tokio::test]
async fn a_frame_over_the_length_limit_hides_no_frame_inside_it() {
    let mode = ApiMode::Unescaped;
    let (mut stream, _sender, mut fake) = pty_link_with(mcp_host::LinkOptions {
        api_mode: mode,
        max_frame_len: 20,
        ..mcp_host::LinkOptions::default()
    })
    .await;
    // A 30-byte frame (an unknown type) whose data holds a whole Receive Packet.
    let inner = fake.encode(&rx(MAV, b"m1"));
    let mut outer_data = vec![0x23];
    outer_data.extend(&inner);
    outer_data.resize(30, 0);
    let outer = fake.encode(&xbee_api::RawFrame::new(&outer_data).unwrap());
    let mut corrupt = outer.clone();
    *corrupt.last_mut().unwrap() ^= 0x01;
    let mut bytes = outer;
    bytes.extend(corrupt);
    bytes.extend(fake.encode(&rx(MAV, b"m2")));
    fake.write_raw(&bytes).await;

    let oversize = DecodeError::Oversize {
        length: 30,
        capacity: 20,
    };
    let mut texts = Vec::new();
    for _ in 0..5 {
        match next_event(&mut stream).await {
            Event::DecodeError(e) => assert_eq!(e, oversize),
            Event::Packet(rx) => texts.push(rx.payload.to_vec()),
            other => panic!("unexpected {other:?}"),
        }
    }
    assert_eq!(texts, [b"m1".to_vec(), b"m1".to_vec(), b"m2".to_vec()]);
    let stats = stream.stats();
    assert_eq!((stats.frames, stats.oversize), (3, 2));
}

/// API mode 1 on a quiet link: a stray 0x7E and a long length before a frame would
/// hold the frame back until 255 more bytes came; the partial frame is given up once
/// no byte has come for `partial_frame_timeout`, and the frame behind it comes out.
#[tokio::test]
async fn a_stray_delimiter_on_a_quiet_link_holds_back_no_frame() {
    let (mut stream, _sender, mut fake) = pty_link_with(mcp_host::LinkOptions {
        api_mode: ApiMode::Unescaped,
        partial_frame_timeout: Some(std::time::Duration::from_millis(50)),
        ..mcp_host::LinkOptions::default()
    })
    .await;
    let mut bytes = vec![0x7E, 0x00, 0xFF];
    bytes.extend(fake.encode(&rx(MAV, b"m1")));
    fake.write_raw(&bytes).await;
    assert!(matches!(
        next_event(&mut stream).await,
        Event::DecodeError(DecodeError::Truncated {
            length: Some(255),
            ..
        })
    ));
    match next_event(&mut stream).await {
        Event::Packet(rx) => assert_eq!(&rx.payload[..], b"m1"),
        other => panic!("unexpected {other:?}"),
    }
    // The link goes on as before.
    fake.write_raw(&fake.encode(&rx(MAV, b"m2"))).await;
    match next_event(&mut stream).await {
        Event::Packet(rx) => assert_eq!(&rx.payload[..], b"m2"),
        other => panic!("unexpected {other:?}"),
    }
}
