#!/usr/bin/env bash
# Instructions per input byte of the XBee decoders on a Cortex-M3: the host benchmarks'
# measured loops (`perf::run`, the same code) built for thumbv7m-none-eabi as a firmware
# is (opt-level "s", LTO), run in QEMU's LM3S6965 model one instruction a translation
# block (`-singlestep -d exec,nochain`), every executed instruction logged and counted.
# Each case less `base` (start-up and exit alone) is its measured loop, the caller's
# loop included, as `perf/callgrind.sh` counts on the host. Each case checks the frames
# it found and fails otherwise.
#
# Needs the thumbv7m-none-eabi target and qemu-system-arm (Debian: qemu-system-arm).
#
# Usage: perf/cortex-m/count.sh [case...]   (push1 push2 fifo1 fifo2 slice1 slice2
#                                            calls1 calls2 floor1 floor2; all by default)
set -euo pipefail
cd "$(dirname "$0")"
unset CARGO_TARGET_DIR

cases=("$@")
if [ ${#cases[@]} -eq 0 ]; then
    cases=(push2 push1 fifo2 fifo1 slice2 slice1 calls2 calls1 floor2 floor1)
fi
cargo build --release --quiet
dir=target/thumbv7m-none-eabi/release
# The newest build script output (older ones stay behind after rebuilds).
out=$(ls -td target/thumbv7m-none-eabi/release/build/perf-cortex-m-*/out | head -1)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# Instructions a run of binary $1 executes.
instructions() {
    timeout 600 qemu-system-arm -machine lm3s6965evb -nographic -monitor none \
        -semihosting-config enable=on,target=native -singlestep -d exec,nochain \
        -D "$work/log" -kernel "$dir/$1" >/dev/null 2>&1 || {
        echo "count.sh: $1 failed (wrong totals, or QEMU could not run it)" >&2
        exit 1
    }
    grep -c '^Trace' "$work/log"
}

base=$(instructions base)
printf "%-8s %12s %7s %9s\n" case instructions bytes "per byte"
for case in "${cases[@]}"; do
    n=$(($(instructions "$case") - base))
    bytes=$(stat -c %s "$out/stream${case: -1}.bin")
    awk -v c="$case" -v n="$n" -v b="$bytes" \
        'BEGIN { printf "%-8s %12d %7d %9.2f\n", c, n, b, n / b }'
done
