//! `mcp_core::parse` on arbitrary payloads. Whenever a payload parses:
//!
//! - it encodes to `encoded_len()` bytes, which is the payload length (parsing is
//!   strict about lengths), and not into a buffer one byte shorter;
//! - the encoded bytes are the payload's, except that on/off bytes are written 0x01
//!   for any non-zero byte (the one documented normalisation);
//! - they parse again to the same packet, which encodes to the same bytes;
//! - moving the packet to owned storage keeps it, and `Display` does not panic.
//!
//! And whatever the payload, `Command::parse` and `Report::parse` give what `parse`
//! gives for a packet of their category (the packet, or the same error), and an error
//! for any other.
//!
//! Packets are compared through `Debug`: float fields may be NaN, which `==` rejects.
#![no_main]

use libfuzzer_sys::fuzz_target;
use mcp_core::MAX_PAYLOAD;

fuzz_target!(|payload: &[u8]| {
    let whole = mcp_core::parse(payload);
    let (command, report) = (
        mcp_core::Command::parse(payload),
        mcp_core::Report::parse(payload),
    );
    match (payload.first(), &whole) {
        (Some(b'c'), Ok(mcp_core::Packet::Command(c))) => {
            assert_eq!(format!("{command:?}"), format!("{:?}", Ok::<_, ()>(c)));
        }
        (Some(b'r'), Ok(mcp_core::Packet::Report(r))) => {
            assert_eq!(format!("{report:?}"), format!("{:?}", Ok::<_, ()>(r)));
        }
        (Some(b'c'), Err(e)) => assert_eq!(command.as_ref().err(), Some(e)),
        (Some(b'r'), Err(e)) => assert_eq!(report.as_ref().err(), Some(e)),
        _ => {}
    }
    if payload.first() != Some(&b'c') {
        assert!(
            command.is_err(),
            "a command from a packet of another category"
        );
    }
    if payload.first() != Some(&b'r') {
        assert!(
            report.is_err(),
            "a report from a packet of another category"
        );
    }
    let Ok(packet) = whole else {
        return;
    };
    let len = packet.encoded_len();
    assert_eq!(
        len,
        payload.len(),
        "encoded_len differs from the parsed length"
    );

    let mut buf = vec![0u8; len + 8];
    let written = packet
        .encode(&mut buf)
        .expect("buffer larger than encoded_len");
    assert_eq!(written, len, "encode wrote other than encoded_len");
    let encoded = &buf[..written];
    assert!(
        packet.encode(&mut vec![0u8; len - 1]).is_err(),
        "encode into a buffer one byte short succeeded"
    );
    for (i, (&was, &now)) in payload.iter().zip(encoded).enumerate() {
        assert!(
            was == now || (was > 1 && now == 1),
            "byte {i} changed from 0x{was:02X} to 0x{now:02X}"
        );
    }

    let again = mcp_core::parse(encoded).expect("encoded packet parses");
    assert_eq!(
        format!("{again:?}"),
        format!("{packet:?}"),
        "parse(encode(p)) != p"
    );
    let mut buf2 = vec![0u8; MAX_PAYLOAD.max(len)];
    let written2 = again.encode(&mut buf2).expect("buffer of encoded_len");
    assert_eq!(&buf2[..written2], encoded, "encoding is not stable");

    let owned = packet.map_bytes(|s| s.to_vec());
    assert_eq!(format!("{:?}", owned.as_borrowed()), format!("{packet:?}"));
    let _ = format!("{packet}");
});
