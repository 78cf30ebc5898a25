//! Runs one measured loop over its stream, for instruction counts under callgrind (see
//! `callgrind.sh`, which collects inside the `run_*` functions only) and quick timings.
//!
//! `cargo run --release -p perf --example receive -- <case> [bytes] [runs]`, where case
//! is `slice2`, `slice1`, `calls2`, `calls1` (one `decode` call a frame), `push2`, `push1`,
//! `fifo2`, `fifo1` (`decode_each` on chunks of `CHUNK` bytes, default 16, as a UART FIFO
//! or DMA buffer hands them over), `pipeline2`, `pipeline1`, `pipeline_push2`, `mavlink`
//! (a MAVLink stream carrying as many values as the mode 2 stream), `floor2` or `floor1`
//! (the least a byte-at-a-time decoder does, `perf::floor`).

use std::hint::black_box;
use std::time::Instant;

use perf::run::{
    run_fifo, run_floor, run_pipeline, run_pipeline_push, run_push, run_slice, run_slice_calls,
};
use perf::{Totals, mavlink_stream, mcp_stream};
use xbee_api::ApiMode;

#[path = "../benches/common/mavlink_run.rs"]
mod mavlink_run;

/// A measured loop over a stream.
type Run = Box<dyn Fn(&[u8], ApiMode) -> Totals>;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let arg = |i: usize, default: &str| args.get(i).cloned().unwrap_or_else(|| default.into());
    let case = arg(0, "pipeline2");
    let bytes: usize = arg(1, "1048576").parse().expect("bytes");
    let runs: usize = arg(2, "1").parse().expect("runs");
    let mode = if case.ends_with('1') {
        ApiMode::Unescaped
    } else {
        ApiMode::Escaped
    };
    let xbee = mcp_stream(mode, bytes);
    let stream = match case.as_str() {
        "mavlink" => mavlink_stream(xbee.totals.values),
        _ => xbee,
    };
    let chunk: usize = std::env::var("CHUNK")
        .map_or(16, |c| c.parse().expect("CHUNK"))
        .max(1);
    let run: Run = match case.as_str() {
        "slice2" | "slice1" => Box::new(run_slice),
        "calls2" | "calls1" => Box::new(run_slice_calls),
        "push2" | "push1" => Box::new(run_push),
        "fifo2" | "fifo1" => Box::new(move |s, m| run_fifo(s, m, chunk)),
        "pipeline2" | "pipeline1" => Box::new(run_pipeline),
        "pipeline_push2" => Box::new(run_pipeline_push),
        "mavlink" => Box::new(|s, _| mavlink_run::run_mavlink(s)),
        "floor1" | "floor2" => Box::new(run_floor),
        other => panic!("unknown case {other}"),
    };
    let mut best = f64::INFINITY;
    for _ in 0..runs {
        let start = Instant::now();
        let totals = run(black_box(&stream.bytes), mode);
        best = best.min(start.elapsed().as_secs_f64());
        assert_eq!(totals.frames, stream.totals.frames);
    }
    println!(
        "{case}: {} bytes, {} frames, {} values, best {:.0} MB/s",
        stream.bytes.len(),
        stream.totals.frames,
        stream.totals.values,
        stream.bytes.len() as f64 / best / 1e6
    );
}
