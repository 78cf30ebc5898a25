//! `mcp_core::parse` on arbitrary payloads. Whenever a payload parses:
//!
//! - it encodes to `encoded_len()` bytes, which is the payload length (parsing is
//!   strict about lengths), and not into a buffer one byte shorter;
//! - the encoded bytes are the payload's, except that on/off bytes are written 0x01
//!   for any non-zero byte (the one documented normalisation);
//! - they parse again to the same packet, which encodes to the same bytes;
//! - moving the packet to owned storage keeps it, and `Display` does not panic.
//!
//! Packets are compared through `Debug`: float fields may be NaN, which `==` rejects.
#![no_main]

use libfuzzer_sys::fuzz_target;
use mcp_core::MAX_PAYLOAD;

fuzz_target!(|payload: &[u8]| {
    let Ok(packet) = mcp_core::parse(payload) else {
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
