//! The XBee streaming decoder in API mode 2 on arbitrary bytes, split into reads at
//! fuzzer-chosen points: the first byte says how many of the next bytes are chunk
//! sizes (0-7); the rest is the stream. Checked with the default capacity, with a
//! small one that makes oversize frames and buffer compaction common, and with the
//! default capacity limited to the small one's (`Decoder::with_max_len`), which must
//! decode exactly as the small one.
#![no_main]

use libfuzzer_sys::fuzz_target;
use mcp_fuzz::split::{check_stream, check_stream_limited};
use xbee_api::{ApiMode, DEFAULT_CAPACITY};

fuzz_target!(|input: &[u8]| {
    let Some((&n, rest)) = input.split_first() else {
        return;
    };
    let (sizes, stream) = rest.split_at(usize::from(n % 8).min(rest.len()));
    check_stream::<DEFAULT_CAPACITY>(ApiMode::Escaped, sizes, stream);
    check_stream_limited::<DEFAULT_CAPACITY, 16>(ApiMode::Escaped, sizes, stream);
});
