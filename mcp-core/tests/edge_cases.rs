//! What the specification leaves open, as settled for this crate: strict lengths,
//! unknown identifiers, both slave set forms, on/off bytes, empty packets.

use mcp_core::{
    Address, Category, Command, CommandType, Controller, Error, ErrorKind, Expected, LandingState,
    Packet, Report, SlaveAddresses, Slot, StatusRequest, TelemetryId, parse,
};

fn err(bytes: &[u8]) -> Error {
    match parse(bytes) {
        Ok(p) => panic!("{bytes:02x?} parsed as {p:?}"),
        Err(e) => e,
    }
}

fn encode(p: &Packet<&[u8]>) -> Vec<u8> {
    let mut buf = vec![0; p.encoded_len()];
    let len = p.encode(&mut buf).unwrap();
    buf.truncate(len);
    buf
}

#[test]
fn empty_input_is_an_error() {
    let e = err(&[]);
    assert_eq!(*e.kind(), ErrorKind::Empty);
    assert_eq!(e.offset(), 0);
}

#[test]
fn unknown_category_is_an_error() {
    for byte in [0x00, b'C', b'x', 0xFF] {
        let e = err(&[byte, 0x01, 0x02]);
        assert_eq!(*e.kind(), ErrorKind::UnknownCategory(byte));
        assert_eq!(e.offset(), 0);
    }
}

#[test]
fn unknown_command_and_report_types_are_errors() {
    for t in [0x00, 0x08, 0x63, 0xFF] {
        let e = err(&[b'c', t, 0x00]);
        assert_eq!(
            *e.kind(),
            ErrorKind::UnknownType {
                category: Category::Command,
                value: t
            }
        );
        assert_eq!(e.offset(), 1);
    }
    // Reports have no position set type (table 17).
    for t in [0x00, 0x07, 0x08] {
        let e = err(&[b'r', t, 0, 0, 0, 0, 0, 0, 0, 0]);
        assert_eq!(
            *e.kind(),
            ErrorKind::UnknownType {
                category: Category::Report,
                value: t
            }
        );
    }
}

#[test]
fn missing_type_byte_is_an_error() {
    assert_eq!(*err(b"c").kind(), ErrorKind::MissingType(Category::Command));
    assert_eq!(*err(b"r").kind(), ErrorKind::MissingType(Category::Report));
    assert_eq!(err(b"r").offset(), 1);
}

#[test]
fn non_zero_on_off_bytes_decode_as_on_and_encode_as_one() {
    for byte in [0x01, 0x02, 0x80, 0xFE] {
        let bytes = [b'c', 0x02, byte];
        let p = parse(&bytes).unwrap();
        assert_eq!(p, Packet::Command(Command::Landing { on: true }));
        assert_eq!(encode(&p), [b'c', 0x02, 0x01]);

        let bytes = [b'c', 0x01, byte, 0x05];
        let p = parse(&bytes).unwrap();
        assert_eq!(
            p,
            Packet::Command(Command::TelemetryToCoordinator {
                on: true,
                id: TelemetryId::EstimatedAileronSpeed
            })
        );
        assert_eq!(encode(&p), [b'c', 0x01, 0x01, 0x05]);

        let bytes = [b'r', 0x01, byte, 0x05];
        let p = parse(&bytes).unwrap();
        assert_eq!(encode(&p), [b'r', 0x01, 0x01, 0x05]);
    }
    // 0xFF in the on/off position is the status request, not "on".
    assert_eq!(
        parse(&[b'c', 0x02, 0xFF]).unwrap(),
        Packet::Command(Command::StatusRequest(StatusRequest::Landing))
    );
}

#[test]
fn unknown_identifiers_are_valid() {
    assert_eq!(
        parse(&[b'c', 0x01, 0x01, 0x21]).unwrap(),
        Packet::Command(Command::TelemetryToCoordinator {
            on: true,
            id: TelemetryId::Unknown(0x21)
        })
    );
    assert_eq!(
        parse(&[b'c', 0x01, 0xFF, 0xFF]).unwrap(),
        Packet::Command(Command::StatusRequest(
            StatusRequest::TelemetryToCoordinator(TelemetryId::Unknown(0xFF))
        ))
    );
    for c in [0x00, 0x04, 0x7F, 0xFE] {
        assert_eq!(
            parse(&[b'c', 0x03, c]).unwrap(),
            Packet::Command(Command::Controllers(Controller::Unknown(c)))
        );
        assert_eq!(
            parse(&[b'r', 0x03, c]).unwrap(),
            Packet::Report(Report::Controllers(Controller::Unknown(c)))
        );
    }
    for s in [0x05, 0x80, 0xFF] {
        assert_eq!(
            parse(&[b'r', 0x02, s]).unwrap(),
            Packet::Report(Report::Landing(LandingState::Unknown(s)))
        );
    }
    let t = [b't', 0xF0, 0, 0, 0x80, 0x3F];
    let Ok(Packet::Telemetry(t)) = parse(&t) else {
        panic!("not telemetry")
    };
    let r = t.iter().next().unwrap();
    assert_eq!((r.id, r.value), (TelemetryId::Unknown(0xF0), 1.0));
}

#[test]
fn a_controllers_report_of_0xff_is_no_controller() {
    // Table 20: 0x00-0xFE; in a command 0xFF is the status request.
    let e = err(b"r\x03\xff");
    assert_eq!(*e.kind(), ErrorKind::InvalidController(0xFF));
    assert_eq!((e.offset(), e.code()), (2, 0x4A));
    assert_eq!(
        e.to_string(),
        "controller 0xff is not 0x00-0xfe (0xff is no controller) (at offset 2)"
    );
    assert_eq!(
        Report::parse(b"r\x03\xff").unwrap_err().kind(),
        &ErrorKind::InvalidController(0xFF)
    );
    // A length error first.
    assert!(matches!(
        err(b"r\x03\xff\x00").kind(),
        ErrorKind::WrongLength { .. }
    ));
    assert_eq!(
        parse(b"c\x03\xff").unwrap(),
        Packet::Command(Command::StatusRequest(StatusRequest::Controllers))
    );
}

const A: [u8; 8] = [0x00, 0x13, 0xA2, 0x00, 0x40, 0xB5, 0x99, 0xBF];

#[test]
fn position_slave_set_spec_form() {
    let mut bytes = vec![b'c', 0x05];
    bytes.extend_from_slice(&A);
    let p = parse(&bytes).unwrap();
    assert_eq!(
        p,
        Packet::Command(Command::PositionSlaveSet {
            slot: None,
            address: Address(A)
        })
    );
    assert_eq!(encode(&p), bytes);
    // An address starting with 0xFF is still a set, not a status request.
    let mut ff = bytes.clone();
    ff[2] = 0xFF;
    assert!(matches!(
        parse(&ff).unwrap(),
        Packet::Command(Command::PositionSlaveSet { slot: None, .. })
    ));
}

#[test]
fn position_slave_set_firmware_form() {
    for slot in 0..4 {
        let mut bytes = vec![b'c', 0x05, slot];
        bytes.extend_from_slice(&A);
        let p = parse(&bytes).unwrap();
        assert_eq!(
            p,
            Packet::Command(Command::PositionSlaveSet {
                slot: Slot::new(slot),
                address: Address(A)
            })
        );
        assert_eq!(encode(&p), bytes);
    }
    for slot in [4, 0x10, 0xFF] {
        let mut bytes = vec![b'c', 0x05, slot];
        bytes.extend_from_slice(&A);
        let e = err(&bytes);
        assert_eq!(*e.kind(), ErrorKind::InvalidSlot(slot));
        assert_eq!(e.offset(), 2);
    }
}

#[test]
fn position_slave_set_report_forms() {
    let mut bytes = vec![b'r', 0x05];
    for i in 0..4u8 {
        let mut a = A;
        a[7] = i;
        bytes.extend_from_slice(&a);
    }
    let p = parse(&bytes).unwrap();
    let Packet::Report(Report::PositionSlaveSet(SlaveAddresses::Slots(all))) = p else {
        panic!("not the four-address form: {p:?}");
    };
    assert_eq!(all[3].0[7], 3);
    assert_eq!(encode(&p), bytes);
    assert_eq!(
        parse(&bytes[..10]).unwrap(),
        Packet::Report(Report::PositionSlaveSet(SlaveAddresses::Single(Address([
            A[0], A[1], A[2], A[3], A[4], A[5], A[6], 0
        ]))))
    );
    let e = err(&bytes[..11]);
    assert!(matches!(
        e.kind(),
        ErrorKind::WrongLength {
            expected: Expected::Either(10, 34),
            got: 11,
            ..
        }
    ));
}

#[test]
fn trajectory_size_must_match_the_length() {
    let mut bytes = vec![b'c', 0x04, 0x02];
    bytes.extend_from_slice(&[0; 16]);
    let e = err(&bytes);
    assert_eq!(
        *e.kind(),
        ErrorKind::SizeMismatch {
            size: 2,
            waypoints: 1
        }
    );
    assert_eq!(e.offset(), 2);
    bytes[0] = b'r';
    bytes[2] = 0;
    assert_eq!(
        *err(&bytes).kind(),
        ErrorKind::SizeMismatch {
            size: 0,
            waypoints: 1
        }
    );
    // Size 1 but not a whole waypoint.
    let e = err(&[b'c', 0x04, 0x01, 0, 0, 0, 0, 0]);
    assert!(matches!(
        e.kind(),
        ErrorKind::WrongLength {
            packet_type: Some(CommandType::TrajectorySet),
            expected: Expected::Multiple {
                base: 3,
                stride: 16
            },
            got: 8,
            ..
        }
    ));
    assert_eq!(e.offset(), 3);
    // Command with size 0xFF is a status request: exactly 3 bytes.
    let mut status = vec![b'c', 0x04, 0xFF];
    status.extend_from_slice(&[0; 16]);
    assert!(matches!(
        err(&status).kind(),
        ErrorKind::WrongLength {
            status_request: true,
            expected: Expected::Exactly(3),
            ..
        }
    ));
    // Trajectory packets without the size byte.
    assert!(matches!(
        err(b"c\x04").kind(),
        ErrorKind::WrongLength { got: 2, .. }
    ));
}

#[test]
fn empty_trajectory_and_empty_telemetry_are_valid() {
    let Ok(Packet::Command(Command::TrajectorySet(w))) = parse(b"c\x04\x00") else {
        panic!("not an empty trajectory");
    };
    assert!(w.is_empty());
    let Ok(Packet::Telemetry(t)) = parse(b"t") else {
        panic!("not an empty telemetry packet");
    };
    assert!(t.is_empty());
    assert_eq!(t.iter().count(), 0);
    assert_eq!(encode(&Packet::Telemetry(t)), b"t");
}

#[test]
fn telemetry_length_must_be_one_plus_five_k() {
    for len in [2usize, 5, 7, 10, 12] {
        let bytes = vec![b't'; len];
        let e = err(&bytes);
        assert_eq!(
            *e.kind(),
            ErrorKind::WrongLength {
                category: Category::Telemetry,
                packet_type: None,
                status_request: false,
                expected: Expected::Multiple { base: 1, stride: 5 },
                got: len
            }
        );
        // Points at the start of the partial record.
        assert_eq!(e.offset(), len - (len - 1) % 5);
    }
}

#[test]
fn position_set_has_no_status_request() {
    let bytes = [b'c', 0x07, 0xFF, 0xFF, 0xFF, 0xFF, 0x00, 0x00, 0x80, 0x3F];
    let Ok(Packet::Command(Command::PositionSet { elevator, aileron })) = parse(&bytes) else {
        panic!("not a position set");
    };
    assert_eq!(elevator.to_bits(), 0xFFFF_FFFF);
    assert!(elevator.is_nan());
    assert_eq!(aileron, 1.0);
    let p = parse(&bytes).unwrap();
    assert_eq!(encode(&p), bytes);
    // A 3-byte `c 07 FF` is a position set of the wrong length.
    assert!(matches!(
        err(&[b'c', 0x07, 0xFF]).kind(),
        ErrorKind::WrongLength {
            expected: Expected::Exactly(10),
            got: 3,
            ..
        }
    ));
}

#[test]
fn time_with_0xff_first_byte_is_a_set() {
    let bytes = [b'c', 0x06, 0xFF, 0x00, 0x00, 0x00];
    assert_eq!(parse(&bytes).unwrap(), Packet::Command(Command::Time(255)));
}

#[test]
fn wrong_lengths_are_errors_with_offsets() {
    // A slaves report one byte longer than its longer form.
    const LONG_SLAVES: [u8; 35] = {
        let mut b = [0x42u8; 35];
        (b[0], b[1], b[2]) = (b'r', 5, 0);
        b
    };
    // (packet, expected, status request, offset)
    let cases: &[(&[u8], Expected, bool, usize)] = &[
        (b"c\x01\x01", Expected::Exactly(4), false, 3),
        (b"c\x01\x01\x01\x01", Expected::Exactly(4), false, 4),
        (b"c\x01\xff", Expected::Exactly(4), true, 3),
        (b"c\x02", Expected::Exactly(3), false, 2),
        (b"c\x02\x01\x00", Expected::Exactly(3), false, 3),
        (b"c\x02\xff\x00", Expected::Exactly(3), true, 3),
        (b"c\x03\x01\x00", Expected::Exactly(3), false, 3),
        (b"c\x05\x01", Expected::Either(10, 11), false, 3),
        // Byte 3 0xFF: a status request (3 bytes) or, for the types whose set command
        // may hold 0xFF there, that command (position slave set's spec form, time).
        (b"c\x05\xff\x00", Expected::Either(3, 10), true, 4),
        (
            b"c\x05\xff\x00\x00\x00\x00\x00\x00\x00\x00\x00",
            Expected::Either(3, 10),
            true,
            10,
        ),
        (b"c\x06\xff\x00", Expected::Either(3, 6), true, 4),
        (
            b"c\x06\xff\x00\x00\x00\x00",
            Expected::Either(3, 6),
            true,
            6,
        ),
        (b"c\x01\xff\x00\x00", Expected::Exactly(4), true, 4),
        (b"c\x03\xff\x00", Expected::Exactly(3), true, 3),
        (b"c\x04\xff\x00", Expected::Exactly(3), true, 3),
        // Longer than both forms: the first byte past the longer one.
        (
            b"c\x05\x00\x13\xa2\x00\x40\xb5\x99\xbf\x00\x00",
            Expected::Either(10, 11),
            false,
            11,
        ),
        (&LONG_SLAVES, Expected::Either(10, 34), false, 34),
        (b"c\x06\x01\x02\x03", Expected::Exactly(6), false, 5),
        (b"c\x06\x01\x02\x03\x04\x05", Expected::Exactly(6), false, 6),
        (b"c\x07\x00\x00\x00\x00", Expected::Exactly(10), false, 6),
        (b"r\x01\x01", Expected::Exactly(4), false, 3),
        (b"r\x02", Expected::Exactly(3), false, 2),
        (b"r\x02\x01\x01", Expected::Exactly(3), false, 3),
        (b"r\x03\x01\x01", Expected::Exactly(3), false, 3),
        (b"r\x06\x01\x02\x03", Expected::Exactly(6), false, 5),
        (b"r\x06\xff", Expected::Exactly(6), false, 3),
    ];
    for &(bytes, expected, status_request, offset) in cases {
        let e = err(bytes);
        match *e.kind() {
            ErrorKind::WrongLength {
                expected: x,
                status_request: s,
                got,
                ..
            } => {
                assert_eq!(x, expected, "{bytes:02x?}");
                assert_eq!(s, status_request, "{bytes:02x?}");
                assert_eq!(got, bytes.len());
            }
            other => panic!("{bytes:02x?}: {other:?}"),
        }
        assert_eq!(e.offset(), offset, "{bytes:02x?}");
        // Display names the packet and both lengths.
        let text = e.to_string();
        assert!(text.contains(&format!("got {}", bytes.len())), "{text}");
    }
}

#[test]
fn status_request_length_errors_name_the_status_request() {
    // Every command type with a status request, its byte 3 0xFF and one byte too many.
    let cases: &[(&[u8], &str)] = &[
        (
            b"c\x01\xff\x00\x00",
            "telemetry_to_coordinator command status request: expected 4 bytes, got 5 (at \
             offset 4)",
        ),
        (
            b"c\x02\xff\x00",
            "landing command status request: expected 3 bytes, got 4 (at offset 3)",
        ),
        (
            b"c\x03\xff\x00",
            "controllers command status request: expected 3 bytes, got 4 (at offset 3)",
        ),
        (
            b"c\x04\xff\x00",
            "trajectory_set command status request: expected 3 bytes, got 4 (at offset 3)",
        ),
        (
            b"c\x05\xff\x00",
            "position_slave_set command or its status request: expected 3 or 10 bytes, got 4 \
             (at offset 4)",
        ),
        (
            b"c\x06\xff\x00",
            "time command or its status request: expected 3 or 6 bytes, got 4 (at offset 4)",
        ),
    ];
    for &(bytes, message) in cases {
        assert_eq!(
            err(bytes).to_string(),
            format!("wrong length for {message}"),
            "{bytes:02x?}"
        );
        // The status request itself parses.
        let t = CommandType::from(bytes[1]);
        let request = StatusRequest::for_type(t, TelemetryId::from(0)).unwrap();
        let len = if t == CommandType::TelemetryToCoordinator {
            4
        } else {
            3
        };
        assert_eq!(
            parse(&bytes[..len]).unwrap(),
            Packet::Command(Command::StatusRequest(request))
        );
    }
    // The set commands that may hold 0xFF in byte 3 still parse at their own length.
    let mut slave = [0u8; 10];
    (slave[0], slave[1], slave[2]) = (b'c', 0x05, 0xFF);
    assert!(matches!(
        parse(&slave),
        Ok(Packet::Command(Command::PositionSlaveSet {
            slot: None,
            ..
        }))
    ));
    let mut slot_slave = [0u8; 11];
    (slot_slave[0], slot_slave[1], slot_slave[2]) = (b'c', 0x05, 0xFF);
    assert_eq!(*err(&slot_slave).kind(), ErrorKind::InvalidSlot(0xFF));
    // Without 0xFF in byte 3 the set command's lengths alone are expected.
    assert_eq!(
        err(b"c\x05\x00\x00").to_string(),
        "wrong length for position_slave_set command: expected 10 or 11 bytes, got 4 (at \
         offset 4)"
    );
    assert_eq!(
        err(b"c\x06\x00\x00").to_string(),
        "wrong length for time command: expected 6 bytes, got 4 (at offset 4)"
    );
}

#[test]
fn trajectory_length_errors_name_the_category() {
    use mcp_core::Waypoints;
    let partial = [0u8; 17];
    for (category, name) in [(Category::Command, "command"), (Category::Report, "report")] {
        let e = Waypoints::new_checked_for(&partial[..], category).unwrap_err();
        assert_eq!(
            e.to_string(),
            format!(
                "wrong length for trajectory_set {name}: expected 3 + 16k bytes, got 20 (at \
                 offset 19)"
            )
        );
        assert_eq!(
            Waypoints::new_unchecked(&partial[..]).check_len_for(category),
            Err(e)
        );
        // A packet of that category says the same.
        let mut packet = vec![u8::from(category), 0x04, 0x01];
        packet.extend_from_slice(&partial);
        assert_eq!(err(&packet), e);
    }
    // `new_checked` and `check_len` read the bytes as a command's.
    assert_eq!(
        Waypoints::new_checked(&partial[..]).unwrap_err(),
        Waypoints::new_checked_for(&partial[..], Category::Command).unwrap_err()
    );
    assert!(Waypoints::new_checked_for(&[0u8; 32][..], Category::Report).is_ok());
}

#[test]
fn text_with_high_bytes_is_kept_and_escaped() {
    let bytes = [b'm', b'A', 0x80, 0xFF, b'\\', 0x00];
    let Ok(Packet::Message(t)) = parse(&bytes) else {
        panic!("not a message")
    };
    assert_eq!(t.as_bytes(), &bytes[1..]);
    assert_eq!(t.as_str(), None);
    assert_eq!(t.to_string(), r"A\x80\xff\\\x00");
    let p = parse(&bytes).unwrap();
    assert_eq!(encode(&p), bytes);

    let Ok(Packet::Warning(w)) = parse(&[b'w', 0xE9]) else {
        panic!("not a warning")
    };
    assert_eq!(w.to_string(), r"\xe9");
    // Empty message and warning.
    assert!(matches!(parse(b"m"), Ok(Packet::Message(t)) if t.is_empty()));
    assert!(matches!(parse(b"w"), Ok(Packet::Warning(t)) if t.is_empty()));
}

#[test]
fn error_display_says_what_and_where() {
    assert_eq!(err(&[]).to_string(), "empty packet (at offset 0)");
    assert_eq!(
        err(b"c\x09").to_string(),
        "unknown command type 0x09 (at offset 1)"
    );
    assert_eq!(
        err(b"c\x04\x02").to_string(),
        "trajectory size byte 2 does not match the 0 waypoints in the packet length (at offset 2)"
    );
    let one = [&b"c\x04\x02"[..], &[0; 16]].concat();
    assert_eq!(
        err(&one).to_string(),
        "trajectory size byte 2 does not match the 1 waypoint in the packet length (at offset 2)"
    );
    assert_eq!(
        err(b"c\x05\x07\x00\x00\x00\x00\x00\x00\x00\x00").to_string(),
        "position slave slot 7 is not 0-3 (at offset 2)"
    );
    assert_eq!(
        err(b"c\x01\xff").to_string(),
        "wrong length for telemetry_to_coordinator command status request: expected 4 bytes, got 3 (at offset 3)"
    );
    let e: &dyn core::error::Error = &err(b"x");
    assert!(e.to_string().starts_with("unknown packet category 0x78"));
}

#[test]
fn map_bytes_moves_storage_without_reparsing() {
    let bytes = b"t\x01\x00\x00\x80\x3f".to_vec();
    let p = parse(&bytes).unwrap();
    let owned: Packet<Vec<u8>> = p.map_bytes(|s| s.to_vec());
    drop(bytes);
    let Packet::Telemetry(t) = &owned else {
        panic!("not telemetry")
    };
    assert_eq!(t.value(TelemetryId::Altitude), Some(1.0));
    assert_eq!(owned.category(), Category::Telemetry);
    let mut buf = [0u8; 8];
    let len = owned.encode(&mut buf).unwrap();
    assert_eq!(&buf[..len], b"t\x01\x00\x00\x80\x3f");
    assert_eq!(owned.as_borrowed().encoded_len(), 6);
}

#[test]
fn encode_reports_a_small_buffer() {
    let p: Packet<&[u8]> = Packet::Command(Command::Time(1));
    let mut buf = [0u8; 5];
    let e = p.encode(&mut buf).unwrap_err();
    assert_eq!((e.needed, e.available), (6, 5));
    assert_eq!(buf, [0; 5]);
}

/// `t`, then two records: altitude 1.5 and pitch -0.25.
const TWO_RECORDS: [u8; 11] = [
    b't', 0x01, 0x00, 0x00, 0xC0, 0x3F, 0x19, 0x00, 0x00, 0x80, 0xBE,
];

fn telemetry(bytes: &[u8]) -> mcp_core::Telemetry<&[u8]> {
    let Packet::Telemetry(telemetry) = parse(bytes).unwrap() else {
        panic!("not telemetry")
    };
    telemetry
}

#[test]
fn record_and_waypoint_iterators_count_what_is_left() {
    let telemetry = telemetry(&TWO_RECORDS);
    let mut records = telemetry.iter();
    assert_eq!((records.len(), records.size_hint()), (2, (2, Some(2))));
    records.next();
    assert_eq!((records.len(), records.size_hint()), (1, (1, Some(1))));
    records.next();
    assert_eq!((records.len(), records.next()), (0, None));

    // Three waypoints of 16 bytes each.
    let waypoints = mcp_core::Waypoints::new_checked(&[0u8; 48][..]).unwrap();
    let mut each = waypoints.iter();
    assert_eq!((each.len(), each.size_hint()), (3, (3, Some(3))));
    each.next();
    assert_eq!((each.len(), each.size_hint()), (2, (2, Some(2))));
    assert_eq!(each.count(), 2);
}

#[test]
fn a_record_index_past_any_packet_is_none_not_a_wrapped_one() {
    let telemetry = telemetry(&TWO_RECORDS);
    assert_eq!(
        telemetry.get(1).map(|r| r.id),
        Some(TelemetryId::PitchAngle)
    );
    assert_eq!(telemetry.get(2), None);
    // 5 * (usize::MAX / 5 + 1) wraps to 4 or less: the index must not read a record at
    // the wrapped offset.
    assert_eq!(telemetry.get(usize::MAX / 5 + 1), None);
    assert_eq!(telemetry.get(usize::MAX), None);
}

#[test]
fn a_status_request_is_one_and_a_set_command_is_not() {
    let requests = [
        StatusRequest::TelemetryToCoordinator(TelemetryId::Altitude),
        StatusRequest::Landing,
        StatusRequest::Controllers,
        StatusRequest::TrajectorySet,
        StatusRequest::PositionSlaveSet,
        StatusRequest::Time,
    ];
    for request in requests {
        assert!(Command::<&[u8]>::status_request(request).is_status_request());
    }
    assert!(!Command::<&[u8]>::landing(true).is_status_request());
    assert!(
        !Command::<&[u8]>::telemetry_to_coordinator(true, TelemetryId::Altitude)
            .is_status_request()
    );
    assert!(!Command::<&[u8]>::Time(0).is_status_request());
}

#[test]
fn waypoints_not_whole_are_a_length_error_naming_a_command() {
    let partial = mcp_core::Waypoints::new_unchecked(&[0u8; 17][..]);
    let error = partial.check_len().unwrap_err();
    assert!(
        matches!(
            error.kind(),
            ErrorKind::WrongLength {
                category: Category::Command,
                got: 20,
                ..
            }
        ),
        "{error:?}"
    );
    assert!(
        mcp_core::Waypoints::new_unchecked(&[0u8; 32][..])
            .check_len()
            .is_ok()
    );
}

#[test]
fn text_with_a_byte_is_not_empty() {
    assert!(mcp_core::Text::new(&b""[..]).is_empty());
    assert!(!mcp_core::Text::new(&b"x"[..]).is_empty());
    assert_eq!(mcp_core::Text::new(&b"xy"[..]).len(), 2);
}
