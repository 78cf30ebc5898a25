//! Writes a generated stream to a file, e.g. a capture for `mcp-gs decode`.
//!
//! `cargo run --release -p perf --example write_stream -- <xbee1|xbee2|mavlink> <bytes> <path>`

use perf::{mavlink_stream, mcp_stream};
use xbee_api::ApiMode;

fn main() -> std::io::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [kind, bytes, path] = &args[..] else {
        eprintln!("usage: write_stream <xbee1|xbee2|mavlink> <bytes> <path>");
        std::process::exit(2);
    };
    let bytes: usize = bytes.parse().expect("bytes");
    let stream = match kind.as_str() {
        "xbee1" => mcp_stream(ApiMode::Unescaped, bytes),
        "xbee2" => mcp_stream(ApiMode::Escaped, bytes),
        "mavlink" => mavlink_stream(mcp_stream(ApiMode::Escaped, bytes).totals.values),
        other => panic!("unknown stream {other}"),
    };
    std::fs::write(path, &stream.bytes)?;
    let t = stream.totals;
    println!(
        "{path}: {} bytes, {} frames, {} values",
        stream.bytes.len(),
        t.frames,
        t.values
    );
    Ok(())
}
