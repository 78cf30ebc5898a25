#!/usr/bin/env bash
# Instructions per byte of the slice decoder (`Decoder::decode`) and the byte-at-a-time
# decoder (`Decoder::push`) in API modes 2 and 1, counted by valgrind's callgrind on the
# benchmark stream (Receive Packets carrying MCP telemetry; 1 MiB unless given), only
# inside the decoding loops of `examples/decode_stream.rs`.
#
# Then, if the thumbv7em-none-eabihf target and an ARM objdump are installed, the
# Cortex-M4 code of `push` as a UART receive interrupt handler would call it.
#
# Usage: xbee-api/benches/callgrind.sh [bytes]
set -euo pipefail

crate=$(cd "$(dirname "$0")/.." && pwd)
bytes=${1:-1048576}
target=${CARGO_TARGET_DIR:-$crate/../target}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

cargo build --quiet --release -p xbee-api --example decode_stream \
    --manifest-path "$crate/Cargo.toml"
bin=$target/release/examples/decode_stream
for path in slice push; do
    for mode in 2 1; do
        valgrind --tool=callgrind --callgrind-out-file="$work/callgrind.out" \
            --toggle-collect="*run_$path*" "$bin" "$path" "$mode" "$bytes" 1 \
            >"$work/stdout" 2>"$work/stderr"
        ir=$(sed -n 's/.*Collected : \([0-9]*\).*/\1/p' "$work/stderr")
        n=$(sed -n 's/.*: \([0-9]*\) bytes,.*/\1/p' "$work/stdout")
        awk -v p="$path" -v m="$mode" -v ir="$ir" -v n="$n" \
            'BEGIN { printf "%-5s mode %s: %10d instructions, %8d bytes, %5.2f per byte\n", p, m, ir, n, ir / n }'
    done
done

objdump=$(command -v arm-none-eabi-objdump || command -v llvm-objdump || true)
if [ -z "$objdump" ] || ! rustup target list --installed 2>/dev/null | grep -q thumbv7em-none-eabihf; then
    exit 0
fi
mkdir -p "$work/isr/src"
cat >"$work/isr/Cargo.toml" <<TOML
[package]
name = "isr"
version = "0.0.0"
edition = "2024"

[lib]
crate-type = ["staticlib"]

[dependencies]
xbee-api = { path = "$crate" }

[profile.release]
opt-level = "s"
panic = "abort"
codegen-units = 1
lto = true

[workspace]
TOML
cat >"$work/isr/src/lib.rs" <<'RS'
#![no_std]
use xbee_api::{Decoder, Event};

/// What a UART receive interrupt does with each byte: push it, hand any event on.
#[unsafe(no_mangle)]
pub fn uart_rx(decoder: &mut Decoder, byte: u8, sink: fn(Event<'_>)) {
    if let Some(event) = decoder.push(byte) {
        sink(event);
    }
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo<'_>) -> ! {
    loop {}
}
RS
cp "$crate/../Cargo.lock" "$work/isr/" 2>/dev/null || true
CARGO_TARGET_DIR="$work/isr/target" cargo build --quiet --offline --release \
    --target thumbv7em-none-eabihf --manifest-path "$work/isr/Cargo.toml"
echo
echo "thumbv7em: push in a UART interrupt handler (Decoder<512>, mode 1 or 2)"
"$objdump" -d --no-show-raw-insn "$work/isr/target/thumbv7em-none-eabihf/release/libisr.a" |
    awk '/<uart_rx>:/,/^$/'
