//! Property tests: encode then parse gives the value back; arbitrary bytes never
//! panic; whatever parses encodes back to the same bytes (on/off bytes normalised).

use mcp_core::{
    Address, Command, ErrorKind, Packet, Report, SlaveAddresses, Slot, StatusRequest, Telemetry,
    Text, Waypoint, Waypoints, parse,
};
use proptest::prelude::*;

/// An owned packet and the storage its views borrow.
type Owned = Packet<Vec<u8>>;

fn float() -> impl Strategy<Value = f32> {
    // Every bit pattern, NaNs included.
    any::<u32>().prop_map(f32::from_bits)
}

fn waypoint() -> impl Strategy<Value = Waypoint> {
    (any::<u32>(), float(), float(), float()).prop_map(|(time, elevator, aileron, altitude)| {
        Waypoint {
            time,
            elevator,
            aileron,
            altitude,
        }
    })
}

fn waypoints() -> impl Strategy<Value = Waypoints<Vec<u8>>> {
    prop::collection::vec(waypoint(), 0..=254).prop_map(|ws| {
        Waypoints::new_checked(ws.iter().flat_map(|w| w.to_bytes()).collect()).unwrap()
    })
}

fn address() -> impl Strategy<Value = Address> {
    any::<[u8; 8]>().prop_map(Address)
}

fn slot() -> impl Strategy<Value = Slot> {
    (0u8..4).prop_map(|n| Slot::new(n).unwrap())
}

fn status_request() -> impl Strategy<Value = StatusRequest> {
    prop_oneof![
        any::<u8>().prop_map(|id| StatusRequest::TelemetryToCoordinator(id.into())),
        Just(StatusRequest::Landing),
        Just(StatusRequest::Controllers),
        Just(StatusRequest::TrajectorySet),
        Just(StatusRequest::PositionSlaveSet),
        Just(StatusRequest::Time),
    ]
}

fn command() -> impl Strategy<Value = Command<Vec<u8>>> {
    prop_oneof![
        (any::<bool>(), any::<u8>())
            .prop_map(|(on, id)| Command::TelemetryToCoordinator { on, id: id.into() }),
        any::<bool>().prop_map(|on| Command::Landing { on }),
        // 0xFF would be the status request.
        (0u8..0xFF).prop_map(|c| Command::Controllers(c.into())),
        waypoints().prop_map(Command::TrajectorySet),
        (prop::option::of(slot()), address())
            .prop_map(|(slot, address)| Command::PositionSlaveSet { slot, address }),
        any::<u32>().prop_map(Command::Time),
        (float(), float())
            .prop_map(|(elevator, aileron)| Command::PositionSet { elevator, aileron }),
        status_request().prop_map(Command::StatusRequest),
    ]
}

fn report() -> impl Strategy<Value = Report<Vec<u8>>> {
    prop_oneof![
        (any::<bool>(), any::<u8>())
            .prop_map(|(on, id)| Report::TelemetryToCoordinator { on, id: id.into() }),
        any::<u8>().prop_map(|s| Report::Landing(s.into())),
        // 0xFF is no controller.
        (0u8..0xFF).prop_map(|c| Report::Controllers(c.into())),
        waypoints().prop_map(Report::TrajectorySet),
        address().prop_map(|a| Report::PositionSlaveSet(SlaveAddresses::Single(a))),
        prop::array::uniform4(address())
            .prop_map(|a| Report::PositionSlaveSet(SlaveAddresses::Slots(a))),
        any::<u32>().prop_map(Report::Time),
    ]
}

fn telemetry() -> impl Strategy<Value = Telemetry<Vec<u8>>> {
    prop::collection::vec((any::<u8>(), float()), 0..60).prop_map(|records| {
        let mut bytes = Vec::new();
        for (id, value) in records {
            bytes.push(id);
            bytes.extend_from_slice(&value.to_le_bytes());
        }
        Telemetry::new_checked(bytes).unwrap()
    })
}

fn packet() -> impl Strategy<Value = Owned> {
    let text = || prop::collection::vec(any::<u8>(), 0..300).prop_map(Text::new);
    prop_oneof![
        command().prop_map(Packet::Command),
        report().prop_map(Packet::Report),
        telemetry().prop_map(Packet::Telemetry),
        text().prop_map(Packet::Message),
        text().prop_map(Packet::Warning),
    ]
}

fn encode<B: AsRef<[u8]>>(p: &Packet<B>) -> Vec<u8> {
    let mut buf = vec![0; p.encoded_len()];
    let len = p.encode(&mut buf).unwrap();
    assert_eq!(len, buf.len());
    buf
}

/// Equality that compares floats by bit pattern (NaN payloads included).
fn same_bits(a: &Packet<&[u8]>, b: &Packet<&[u8]>) -> bool {
    match (a, b) {
        (
            Packet::Command(Command::PositionSet {
                elevator: e1,
                aileron: a1,
            }),
            Packet::Command(Command::PositionSet {
                elevator: e2,
                aileron: a2,
            }),
        ) => e1.to_bits() == e2.to_bits() && a1.to_bits() == a2.to_bits(),
        // Every other float lives in the byte views, compared byte by byte.
        _ => a == b,
    }
}

/// The input with its on/off byte (if the packet has one) written as 0x00/0x01.
fn normalise_on_off(bytes: &[u8], parsed: &Packet<&[u8]>) -> Vec<u8> {
    let mut out = bytes.to_vec();
    let on = match parsed {
        Packet::Command(Command::TelemetryToCoordinator { on, .. })
        | Packet::Command(Command::Landing { on })
        | Packet::Report(Report::TelemetryToCoordinator { on, .. }) => Some(*on),
        _ => None,
    };
    if let Some(on) = on {
        out[2] = u8::from(on);
    }
    out
}

/// Bytes that look like packets often enough to reach every parser branch.
fn packet_like_bytes() -> impl Strategy<Value = Vec<u8>> {
    let category = prop::sample::select(vec![b'c', b'r', b't', b'm', b'w', 0x00, 0xFF]);
    let arg = prop_oneof![Just(0xFFu8), 0u8..5, any::<u8>()];
    prop_oneof![
        prop::collection::vec(any::<u8>(), 0..64),
        (
            category,
            0u8..9,
            arg,
            prop::collection::vec(any::<u8>(), 0..40)
        )
            .prop_map(|(c, t, a, rest)| {
                let mut v = vec![c, t, a];
                v.extend(rest);
                v
            }),
        // Trajectories whose size byte is right or off by a little.
        (
            prop::sample::select(vec![b'c', b'r']),
            0usize..4,
            -1i8..=1,
            0usize..3
        )
            .prop_map(|(c, n, delta, extra)| {
                let mut v = vec![c, 0x04, (n as i8 + delta).max(0) as u8];
                v.resize(3 + n * 16 + extra, 0x5A);
                v
            }),
    ]
}

/// That a parser of the packets of category `byte` gave `own` for `bytes`, where
/// [`parse`] gave `whole` (the packet if of that category): the same packet, or the same
/// error, for a packet of that category, and for any other an error saying so.
fn own_category<T: PartialEq + std::fmt::Debug>(
    bytes: &[u8],
    byte: u8,
    own: Result<T, mcp_core::Error>,
    whole: Result<Option<T>, mcp_core::Error>,
) -> Result<(), TestCaseError> {
    let ours = bytes.first() == Some(&byte);
    match (own, whole) {
        (Ok(own), Ok(Some(whole))) => prop_assert_eq!(own, whole),
        (Err(e), Err(w)) if ours => prop_assert_eq!(e, w),
        (Err(e), _) if !ours => prop_assert!(
            bytes.is_empty() || matches!(e.kind(), ErrorKind::WrongCategory { .. }),
            "{e}"
        ),
        (own, whole) => prop_assert!(false, "{own:?}, from parse {whole:?}"),
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    /// Any 16 bytes are a waypoint, and give back the same bytes (NaN payloads too).
    #[test]
    fn waypoint_bytes_round_trip(bytes in any::<[u8; 16]>()) {
        let waypoint = mcp_core::Waypoint::from_bytes(bytes);
        prop_assert_eq!(waypoint.to_bytes(), bytes);
        let view = mcp_core::Waypoints::new_checked(&bytes[..]).unwrap();
        let read = view.iter().next().unwrap();
        prop_assert_eq!(read.to_bytes(), bytes);
        prop_assert_eq!(read.time, waypoint.time);
    }

    #[test]
    fn encode_then_parse_gives_the_value_back(p in packet()) {
        let bytes = encode(&p);
        let parsed = parse(&bytes).map_err(|e| TestCaseError::fail(format!("{e}")))?;
        let original = p.as_borrowed();
        prop_assert!(same_bits(&parsed, &original), "{parsed:?} != {original:?}");
        prop_assert_eq!(encode(&parsed), bytes);
    }

    #[test]
    fn arbitrary_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..400)) {
        if let Ok(p) = parse(&bytes) {
            prop_assert_eq!(encode(&p), normalise_on_off(&bytes, &p));
        }
    }

    #[test]
    fn command_and_report_parsers_read_their_own_category_alone(bytes in packet_like_bytes()) {
        // Each agrees with `parse` on a packet of its category, and refuses any other.
        let whole = parse(&bytes);
        own_category(&bytes, b'c', Command::parse(&bytes), whole.map(|p| match p {
            Packet::Command(c) => Some(c),
            _ => None,
        }))?;
        own_category(&bytes, b'r', Report::parse(&bytes), whole.map(|p| match p {
            Packet::Report(r) => Some(r),
            _ => None,
        }))?;
    }

    #[test]
    fn whatever_parses_encodes_to_the_same_bytes(bytes in packet_like_bytes()) {
        match parse(&bytes) {
            Ok(p) => {
                prop_assert_eq!(p.encoded_len(), bytes.len());
                prop_assert_eq!(encode(&p), normalise_on_off(&bytes, &p));
                // The owned copy encodes the same.
                let owned = p.map_bytes(|s| s.to_vec());
                prop_assert_eq!(encode(&owned), normalise_on_off(&bytes, &p));
            }
            Err(e) => {
                // The offset points into the packet or just past its end.
                prop_assert!(e.offset() <= bytes.len().max(1), "{e}");
            }
        }
    }

    #[test]
    fn encoding_into_a_short_buffer_fails_cleanly(p in packet(), cut in 0usize..16) {
        let len = p.encoded_len();
        let mut buf = vec![0; len.saturating_sub(cut + 1)];
        let e = p.encode(&mut buf).unwrap_err();
        prop_assert_eq!(e.needed, len);
        prop_assert_eq!(e.available, buf.len());
    }
}

#[test]
fn the_bias_reaches_valid_packets() {
    // Guards the strategy above: it must produce parseable trajectories too.
    let mut v = vec![b'c', 0x04, 0x01];
    v.resize(19, 0x5A);
    assert!(parse(&v).is_ok());
}
