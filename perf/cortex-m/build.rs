//! Puts `memory.x` on the linker search path, and writes the streams the cases decode:
//! the host benchmarks' seeded streams of XBee Receive Packets, each an MCP telemetry
//! packet of 8 values, in API modes 1 and 2, small enough for the LM3S6965's flash.

use std::{env, fs, path::PathBuf};

use xbee_api::ApiMode;

/// Bytes of each stream: about 100 frames.
const STREAM_BYTES: usize = 6_000;

fn main() {
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    fs::copy("memory.x", out.join("memory.x")).expect("copy memory.x");
    println!("cargo:rustc-link-search={}", out.display());
    let mut totals = String::new();
    for (mode, name) in [(ApiMode::Unescaped, "1"), (ApiMode::Escaped, "2")] {
        let stream = perf::mcp_stream(mode, STREAM_BYTES);
        fs::write(out.join(format!("stream{name}.bin")), &stream.bytes).expect("write stream");
        totals += &format!(
            "/// Frames and values of the mode {name} stream.\npub const TOTALS{name}: (usize, usize) = ({}, {});\n",
            stream.totals.frames, stream.totals.values
        );
    }
    fs::write(out.join("totals.rs"), totals).expect("write totals");
    println!("cargo:rerun-if-changed=memory.x");
    println!("cargo:rerun-if-changed=build.rs");
}
