//! The ground station's frame codec, `mcp_host::codec::XBeeCodec`, driven through
//! tokio-util's `Decoder` trait as `FramedRead` drives it: bytes arrive in a `BytesMut`
//! in fuzzer-chosen chunks, `decode` is called until it returns `None`, and at the end
//! `decode_eof` until it returns `None`.
//!
//! Input: byte 0 picks the mode (odd: API mode 1, even: mode 2); byte 1 says how many
//! of the next bytes are chunk sizes (0-7); the rest is the stream.
//!
//! Checks: no panic and never `Err` (a corrupt frame is an item and a counter); every
//! byte is taken when `decode` returns `None` (the buffer does not grow); the items are
//! exactly the events of `xbee_api::Decoder` on the whole stream; the counters match
//! the items.
#![no_main]

use bytes::BytesMut;
use libfuzzer_sys::fuzz_target;
use mcp_fuzz::events::{Event, decode_all, event_bound, finish_all};
use mcp_host::codec::{CodecItem, XBeeCodec};
use tokio_util::codec::Decoder as _;
use xbee_api::{ApiMode, DecodeError};

fn owned(item: CodecItem) -> Event {
    match item {
        CodecItem::Frame(frame) => Event::Frame(frame.data().to_vec()),
        CodecItem::Error(error) => Event::Error(error),
    }
}

fuzz_target!(|input: &[u8]| {
    let [mode, n, rest @ ..] = input else {
        return;
    };
    let mode = if mode & 1 == 1 {
        ApiMode::Unescaped
    } else {
        ApiMode::Escaped
    };
    let (sizes, stream) = rest.split_at(usize::from(n % 8).min(rest.len()));
    let bound = event_bound(stream.len());

    let mut expected = Vec::new();
    let mut decoder: xbee_api::Decoder = xbee_api::Decoder::new(mode);
    decode_all(&mut decoder, stream, &mut expected, bound);
    finish_all(&mut decoder, &mut expected, bound);

    let mut codec = XBeeCodec::new(mode);
    let mut buf = BytesMut::new();
    let mut items = Vec::new();
    let mut rest = stream;
    let mut i = 0;
    while !rest.is_empty() {
        let size = match sizes {
            [] => rest.len(),
            _ if sizes.iter().all(|&s| s == 0) => 1,
            _ => usize::from(sizes[i % sizes.len()]),
        };
        i += 1;
        let (chunk, tail) = rest.split_at(size.min(rest.len()));
        rest = tail;
        buf.extend_from_slice(chunk);
        loop {
            match codec.decode(&mut buf) {
                Ok(Some(item)) => items.push(owned(item)),
                Ok(None) => break,
                Err(error) => panic!("decode returned Err: {error}"),
            }
            assert!(items.len() <= bound, "codec stuck in a loop");
        }
        assert!(
            buf.is_empty(),
            "decode returned None with {} bytes left",
            buf.len()
        );
    }
    loop {
        match codec.decode_eof(&mut buf) {
            Ok(Some(item)) => items.push(owned(item)),
            Ok(None) => break,
            Err(error) => panic!("decode_eof returned Err: {error}"),
        }
        assert!(items.len() <= bound, "codec stuck in a loop at eof");
    }
    assert!(buf.is_empty());
    assert_eq!(
        items, expected,
        "codec items differ from the decoder's events"
    );

    let stats = codec.stats();
    let count = |f: fn(&Event) -> bool| items.iter().filter(|e| f(e)).count() as u64;
    assert_eq!(stats.frames, count(|e| matches!(e, Event::Frame(_))));
    assert_eq!(
        stats.bad_checksum,
        count(|e| matches!(e, Event::Error(DecodeError::BadChecksum { .. })))
    );
    assert_eq!(
        stats.oversize,
        count(|e| matches!(e, Event::Error(DecodeError::Oversize { .. })))
    );
    assert_eq!(
        stats.empty,
        count(|e| matches!(e, Event::Error(DecodeError::EmptyFrame)))
    );
    assert_eq!(
        stats.truncated,
        count(|e| matches!(e, Event::Error(DecodeError::Truncated { .. })))
    );
    assert_eq!(
        stats.bad_escape,
        count(|e| matches!(e, Event::Error(DecodeError::BadEscape { .. })))
    );
    assert_eq!(
        stats.bytes_skipped,
        u64::from(decoder.stats().bytes_skipped)
    );
});
