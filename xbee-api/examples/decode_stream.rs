//! Decodes the benchmark stream with one decoder path, for instruction counts under
//! callgrind (see `benches/callgrind.sh`) and quick timings.
//!
//! `cargo run --release -p xbee-api --example decode_stream -- <slice|push> <1|2> [bytes] [runs]`

use std::hint::black_box;
use std::time::Instant;

use xbee_api::{ApiMode, Decoder};

#[path = "../benches/common/mod.rs"]
mod common;

/// Decodes `stream` a slice at a time; the frame data bytes seen.
#[inline(never)]
fn run_slice(stream: &[u8], mode: ApiMode) -> (usize, u32) {
    let mut decoder: Decoder = Decoder::new(mode);
    let mut input = stream;
    let mut count = 0;
    loop {
        let (consumed, event) = decoder.decode(input);
        input = &input[consumed..];
        match event {
            Some(Ok(frame)) => count += black_box(frame.data()).len(),
            Some(Err(e)) => panic!("{e}"),
            None => break,
        }
    }
    (count, decoder.stats().frames_ok)
}

/// Decodes `stream` a byte at a time; the frame data bytes seen.
#[inline(never)]
fn run_push(stream: &[u8], mode: ApiMode) -> (usize, u32) {
    let mut decoder: Decoder = Decoder::new(mode);
    let mut count = 0;
    for &byte in stream {
        if let Some(Ok(frame)) = decoder.push(byte) {
            count += black_box(frame.data()).len();
        }
    }
    (count, decoder.stats().frames_ok)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let arg = |i: usize, default: &str| args.get(i).cloned().unwrap_or_else(|| default.into());
    let path = arg(0, "slice");
    let mode = match arg(1, "2").as_str() {
        "1" => ApiMode::Unescaped,
        _ => ApiMode::Escaped,
    };
    let bytes: usize = arg(2, "1048576").parse().expect("bytes");
    let runs: usize = arg(3, "1").parse().expect("runs");
    let (stream, frames) = common::stream(mode, bytes);
    let run = match path.as_str() {
        "push" => run_push,
        _ => run_slice,
    };
    let mut best = f64::INFINITY;
    for _ in 0..runs {
        let t = Instant::now();
        let (_, ok) = run(black_box(&stream), mode);
        best = best.min(t.elapsed().as_secs_f64());
        assert_eq!(ok as usize, frames);
    }
    println!(
        "{path} mode {}: {} bytes, {frames} frames, best {:.0} MiB/s",
        u8::from(mode),
        stream.len(),
        stream.len() as f64 / best / 1048576.0
    );
}
