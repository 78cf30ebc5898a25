#!/usr/bin/env bash
# Builds the static library of src/lib.rs for a Cortex-M3 and a Cortex-M4F (release:
# opt-level "s", LTO, as a firmware is built) and fails if any panic path is left in it: its panic
# handler calls `no_panic_path_may_remain`, which nothing defines, so the library
# refers to that symbol exactly when a panic is still reachable from an entry point.
#
# Needs the thumbv7m-none-eabi and thumbv7em-none-eabihf targets and llvm-nm (Debian: llvm) or arm-none-eabi-nm
# (Debian: binutils-arm-none-eabi); NM overrides the tool.
#
# To find a panic path the check reports: build with `debug = true` in the release
# profile and look for the calls to the panic handler in
# `llvm-objdump -dS --demangle target/<target>/release/libno_panic.a`.
set -euo pipefail
cd "$(dirname "$0")"
unset CARGO_TARGET_DIR

NM=${NM:-$(command -v llvm-nm || command -v arm-none-eabi-nm || true)}
if [[ -z $NM ]]; then
    echo "check.sh: needs llvm-nm or arm-none-eabi-nm" >&2
    exit 1
fi

for target in thumbv7m-none-eabi thumbv7em-none-eabihf; do
    cargo build --release --quiet --target "$target"
    lib=target/$target/release/libno_panic.a
    # The library also holds core's and compiler-builtins' objects, which an older nm
    # may not read (LLVM bitcode); ours is machine code after LTO. The entry points must
    # be found, or the check would pass on a library it could not read.
    symbols=$("$NM" "$lib" 2>/dev/null || true)
    entries=$(grep -cE ' T mav_(init|rx_byte|rx_chunk|rx_frames|tick|encode|telemetry_in_place|uart|inbox_init|inbox)$' <<<"$symbols" || true)
    if [[ $entries -ne 10 ]]; then
        echo "check.sh: found $entries of the 10 entry points in $lib; cannot check it" >&2
        exit 1
    fi
    if grep -q ' U no_panic_path_may_remain$' <<<"$symbols"; then
        echo "check.sh: $target: a panic path remains in the firmware paths of xbee-api or mcp-core" >&2
        exit 1
    fi
    echo "$target: no panic path from the 10 entry points (opt-level s, LTO)"
    # A new decoder of a fixed mode is all zeros, so its static takes no flash.
    if ! grep -qE ' [Bb] MAV_MODE2_DECODER$' <<<"$symbols"; then
        echo "check.sh: $target: the static Decoder<64, Mode2>::fixed() is not in .bss: $(grep MAV_MODE2_DECODER <<<"$symbols" || echo absent)" >&2
        exit 1
    fi
    echo "$target: a static decoder of a fixed mode 2 is in .bss"
done
