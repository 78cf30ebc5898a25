#!/usr/bin/env bash
# The Cortex-M4 code of xbee-api's byte-at-a-time decoder (`Decoder::push`) as a UART
# receive interrupt handler would call it: builds a tiny static library for
# thumbv7em-none-eabihf and disassembles its handler. Needs that rustup target and an
# ARM objdump (arm-none-eabi-objdump or llvm-objdump). Instructions per byte on the
# host are counted by callgrind.sh beside this script.
#
# Usage: perf/push-thumbv7em.sh
set -euo pipefail

crate=$(cd "$(dirname "$0")/../xbee-api" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

objdump=$(command -v arm-none-eabi-objdump || command -v llvm-objdump || true)
if [ -z "$objdump" ] || ! rustup target list --installed 2>/dev/null | grep -q thumbv7em-none-eabihf; then
    echo "push-thumbv7em.sh: needs the thumbv7em-none-eabihf target and an ARM objdump" >&2
    exit 1
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
use xbee_api::{DecodeEvent, Decoder};

/// What a UART receive interrupt does with each byte: push it, hand any event on.
#[unsafe(no_mangle)]
pub fn uart_rx(decoder: &mut Decoder, byte: u8, sink: fn(DecodeEvent<'_>)) {
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
echo "thumbv7em: push in a UART interrupt handler (Decoder<512>, mode 1 or 2)"
"$objdump" -d --no-show-raw-insn "$work/isr/target/thumbv7em-none-eabihf/release/libisr.a" |
    awk '/<uart_rx>:/,/^$/'
