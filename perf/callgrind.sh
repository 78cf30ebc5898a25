#!/usr/bin/env bash
# Instructions per input byte of each receive-path case, counted by valgrind's
# callgrind inside the measured `run_*` loop only (stream generation is not counted):
# the XBee slice decoder, the byte-at-a-time decoder, the slice decoder fed in chunks
# of CHUNK bytes (fifo2/fifo1; default 16, a UART FIFO or DMA buffer), the pipeline to
# typed MCP telemetry values, and the `mavlink` crate on a MAVLink v2 stream carrying as
# many values; and `floor1`/`floor2`, the least a byte-at-a-time decoder does (perf::floor:
# frames split by their length field, escapes undone in mode 2, one call a byte), the
# floors under push1 and push2.
# Streams are 1 MiB unless given.
#
# Usage: [CHUNK=n] perf/callgrind.sh [bytes] [case...]
set -euo pipefail

crate=$(cd "$(dirname "$0")" && pwd)
bytes=${1:-1048576}
shift || true
cases=("$@")
if [ ${#cases[@]} -eq 0 ]; then
    cases=(slice2 slice1 push2 push1 fifo2 fifo1 pipeline2 pipeline1 pipeline_push2 mavlink floor2 floor1)
fi
target=${CARGO_TARGET_DIR:-$crate/../target}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

cargo build --quiet --release -p perf --example receive --manifest-path "$crate/Cargo.toml"
bin=$target/release/examples/receive
# Collection toggles on entry to and exit from each measured loop. The names are exact
# (no trailing `*`): a closure such as `run_pipeline::{{closure}}` must not match, or
# entering it would toggle collection off and leave its cost out.
toggles=()
for f in run_slice run_slice_calls run_push run_pipeline run_pipeline_push run_fifo run_mavlink run_floor; do
    toggles+=("--toggle-collect=*::$f")
done
printf "%-15s %12s %9s %8s %9s %12s\n" case instructions bytes values "per byte" "per value"
for case in "${cases[@]}"; do
    valgrind --tool=callgrind --callgrind-out-file="$work/callgrind.out" \
        "${toggles[@]}" "$bin" "$case" "$bytes" 1 \
        >"$work/stdout" 2>"$work/stderr"
    ir=$(sed -n 's/.*Collected : \([0-9]*\).*/\1/p' "$work/stderr")
    n=$(sed -n 's/.*: \([0-9]*\) bytes,.*/\1/p' "$work/stdout")
    v=$(sed -n 's/.* \([0-9]*\) values,.*/\1/p' "$work/stdout")
    awk -v c="$case" -v ir="$ir" -v n="$n" -v v="$v" \
        'BEGIN { printf "%-15s %12d %9d %8d %9.2f %12.1f\n", c, ir, n, v, ir / n, ir / v }'
done
