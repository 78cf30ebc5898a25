//! The incremental builders stop cleanly at the buffer and the payload limit.

use mcp_core::{
    Command, Full, MAX_PAYLOAD, Packet, Report, TelemetryBuilder, TelemetryId, TextBuilder,
    TrajectoryBuilder, Waypoint, parse,
};

fn wp(n: u32) -> Waypoint {
    Waypoint {
        time: n,
        elevator: n as f32,
        aileron: -(n as f32),
        altitude: 0.5,
    }
}

#[test]
fn telemetry_builder_stops_at_the_payload_limit() {
    let mut buf = [0u8; 1024];
    let mut b = TelemetryBuilder::new(&mut buf).unwrap();
    let mut pushed = 0u8;
    while b.push(TelemetryId::from(pushed), f32::from(pushed)).is_ok() {
        pushed += 1;
    }
    assert_eq!(pushed, 50);
    assert_eq!(b.push(TelemetryId::Altitude, 1.0), Err(Full));
    assert_eq!(b.count(), 50);
    let len = b.finish();
    assert_eq!(len, 251);
    assert!(len <= MAX_PAYLOAD);
    let Ok(Packet::Telemetry(t)) = parse(&buf[..len]) else {
        panic!("not telemetry");
    };
    assert_eq!(t.len(), 50);
    assert_eq!(t.get(49).unwrap().value, 49.0);
    assert!(t.get(50).is_none());
}

#[test]
fn telemetry_builder_stops_at_the_buffer_and_keeps_the_packet() {
    let mut buf = [0u8; 13];
    let mut b = TelemetryBuilder::new(&mut buf).unwrap();
    assert_eq!(b.push(TelemetryId::Altitude, 1.0), Ok(()));
    assert_eq!(b.push(TelemetryId::RollAngle, 2.0), Ok(()));
    assert_eq!(b.push(TelemetryId::PitchAngle, 3.0), Err(Full));
    assert_eq!(b.as_bytes().len(), 11);
    let len = b.finish();
    assert_eq!(len, 11);
    // Nothing was written past the packet.
    assert_eq!(&buf[11..], [0, 0]);
    let Ok(Packet::Telemetry(t)) = parse(&buf[..len]) else {
        panic!("not telemetry");
    };
    let ids: Vec<_> = t.iter().map(|r| r.id).collect();
    assert_eq!(ids, [TelemetryId::Altitude, TelemetryId::RollAngle]);
}

#[test]
fn telemetry_builder_needs_one_byte() {
    assert!(TelemetryBuilder::new(&mut []).is_err());
    let mut one = [0u8; 1];
    let mut b = TelemetryBuilder::new(&mut one).unwrap();
    assert_eq!(b.push(TelemetryId::Altitude, 0.0), Err(Full));
    assert_eq!(b.finish(), 1);
    assert_eq!(one, *b"t");
}

#[test]
fn trajectory_builder_stops_at_the_payload_limit() {
    let mut buf = [0u8; 4096];
    let mut b = TrajectoryBuilder::command(&mut buf).unwrap();
    let mut n = 0;
    while b.push(wp(n)).is_ok() {
        n += 1;
    }
    assert_eq!(n, 15);
    let len = b.finish();
    assert_eq!(len, 3 + 15 * 16);
    let Ok(Packet::Command(Command::TrajectorySet(w))) = parse(&buf[..len]) else {
        panic!("not a trajectory set");
    };
    assert_eq!(w.size(), 15);
    assert_eq!(
        w.iter().collect::<Vec<_>>(),
        (0..15).map(wp).collect::<Vec<_>>()
    );
}

#[test]
fn trajectory_builder_stops_at_the_buffer() {
    let mut buf = [0u8; 40];
    let mut b = TrajectoryBuilder::report(&mut buf).unwrap();
    assert_eq!(b.push(wp(1)), Ok(()));
    assert_eq!(b.push(wp(2)), Ok(()));
    assert_eq!(b.push(wp(3)), Err(Full));
    assert_eq!(b.count(), 2);
    let len = b.finish();
    assert_eq!(len, 35);
    let Ok(Packet::Report(Report::TrajectorySet(w))) = parse(&buf[..len]) else {
        panic!("not a trajectory report");
    };
    assert_eq!(w.len(), 2);
}

#[test]
fn trajectory_builder_empty_and_too_small() {
    let mut buf = [0u8; 3];
    let b = TrajectoryBuilder::command(&mut buf).unwrap();
    assert_eq!(b.as_bytes(), b"c\x04\x00");
    assert_eq!(b.finish(), 3);
    assert!(parse(&buf).is_ok());
    assert!(TrajectoryBuilder::report(&mut [0u8; 2]).is_err());
}

#[test]
fn text_builder_writes_formatted_text_and_stops_at_the_payload_limit() {
    use core::fmt::Write as _;
    let mut buf = [0xAAu8; 1024];
    let mut text = TextBuilder::warning(&mut buf).unwrap();
    write!(text, "slot {} of {}", 5, 4).unwrap();
    assert_eq!(text.as_bytes(), b"wslot 5 of 4");
    // 300 more bytes: what fits the 255-byte payload is written, and `write!` fails.
    assert!(write!(text, "{:300}", "").is_err());
    assert_eq!(text.text_len(), MAX_PAYLOAD - 1);
    assert_eq!(text.push(b"x"), Err(Full));
    let len = text.finish();
    assert_eq!(len, MAX_PAYLOAD);
    assert_eq!(buf[MAX_PAYLOAD], 0xAA, "nothing past the payload");
    let Ok(Packet::Warning(w)) = parse(&buf[..len]) else {
        panic!("not a warning");
    };
    assert!(w.as_bytes().starts_with(b"slot 5 of 4   "));
}

#[test]
fn text_builder_needs_one_byte() {
    assert!(TextBuilder::message(&mut []).is_err());
    let mut one = [0u8; 1];
    let mut text = TextBuilder::message(&mut one).unwrap();
    assert_eq!(text.push(b""), Ok(()));
    assert_eq!(text.push(b"a"), Err(Full));
    assert_eq!(text.finish(), 1);
    assert_eq!(one, *b"m");
}

proptest::proptest! {
    /// Pushed in any pieces into any buffer, the packet holds the longest prefix of the
    /// text that fits, and parses back as that text; `Full` exactly when a byte was cut.
    #[test]
    fn text_builder_keeps_the_prefix_that_fits(
        pieces in proptest::collection::vec(
            proptest::collection::vec(proptest::num::u8::ANY, 0..40),
            0..12,
        ),
        room in 1usize..300,
        warning in proptest::bool::ANY,
    ) {
        let mut buf = vec![0u8; room];
        let mut text = if warning {
            TextBuilder::warning(&mut buf)
        } else {
            TextBuilder::message(&mut buf)
        }
        .unwrap();
        let cap = room.min(MAX_PAYLOAD) - 1;
        let mut all = Vec::new();
        for piece in &pieces {
            let fits = piece.is_empty() || all.len() + piece.len() <= cap;
            all.extend_from_slice(piece);
            proptest::prop_assert_eq!(text.push(piece).is_ok(), fits);
        }
        let len = text.finish();
        let kept = &all[..all.len().min(cap)];
        proptest::prop_assert_eq!(len, 1 + kept.len());
        let expected = if warning { Packet::warning(kept) } else { Packet::message(kept) };
        proptest::prop_assert_eq!(parse(&buf[..len]), Ok(expected));
    }
}
