#!/usr/bin/env bash
# Builds the firmware (release profile: opt-level "s", LTO) and prints its footprint
# and that of the receive path alone (rx_path minus baseline), and, for comparison, of
# the receive path on the slice decoder (rx_slice minus baseline).
#
# Needs the thumbv7m-none-eabi target and llvm-size/llvm-nm (Debian: llvm) or
# arm-none-eabi-size/arm-none-eabi-nm (Debian: binutils-arm-none-eabi); SIZE and NM
# override the tools.
#
# Fails when the receive path takes more flash than its budget, RX_FLASH_BUDGET bytes
# (default 4096: the 4 KiB the receive path is held to), and when a binary keeps a panic
# path (its panic handler, panic-halt's, is then reached through core::panicking).
set -euo pipefail
cd "$(dirname "$0")"
unset CARGO_TARGET_DIR

cargo build --release --bins --quiet

SIZE=${SIZE:-$(command -v llvm-size || command -v arm-none-eabi-size || true)}
NM=${NM:-$(command -v llvm-nm || command -v arm-none-eabi-nm || true)}
if [[ -z $SIZE || -z $NM ]]; then
    echo "size.sh: needs llvm-size and llvm-nm, or arm-none-eabi-size and arm-none-eabi-nm" >&2
    exit 1
fi
dir=target/thumbv7m-none-eabi/release

# Size of one section of a binary (0 if absent).
section() {
    "$SIZE" -A "$dir/$1" | awk -v s="$2" '$1 == s { n = $2 } END { print n + 0 }'
}
# Flash: what is loaded into flash (vector table, code, constants, .data's initial values).
flash() {
    echo $(($(section "$1" .vector_table) + $(section "$1" .text) + $(section "$1" .rodata) + $(section "$1" .data)))
}
# Static RAM: .data + .bss (+ .uninit). The stack takes the rest of the 64 KiB.
ram() {
    echo $(($(section "$1" .data) + $(section "$1" .bss) + $(section "$1" .uninit)))
}
# Total size of the symbols of a binary whose demangled name matches an ERE.
symbols() {
    local total=0 size
    while read -r size; do
        total=$((total + 16#$size))
    done < <("$NM" -C -S "$dir/$1" | grep -E "$2" | awk 'NF >= 4 { print $2 }')
    echo "$total"
}

printf '%-14s %8s %8s %8s %8s %8s %10s %8s\n' binary .vectors .text .rodata .data .bss flash "RAM"
for bin in mav-firmware rx_path rx_slice baseline; do
    printf '%-14s %8d %8d %8d %8d %8d %10d %8d\n' "$bin" \
        "$(section $bin .vector_table)" "$(section $bin .text)" "$(section $bin .rodata)" \
        "$(section $bin .data)" "$(section $bin .bss)" "$(flash $bin)" "$(ram $bin)"
done

mem_re='compiler_builtins::mem::|__aeabi_mem(cpy|move|set|clr)'
rx_flash=$(($(flash rx_path) - $(flash baseline)))
rx_mem=$(($(symbols rx_path "$mem_re") - $(symbols baseline "$mem_re")))
rx_ram=$(($(ram rx_path) - $(ram baseline)))
inbox=$(symbols rx_path 'mav_firmware::rx::INBOX')
echo
echo "receive path (rx_path - baseline):"
echo "  flash                           $rx_flash bytes"
echo "    of which memcpy/memmove       $rx_mem bytes (compiler-builtins; every firmware that copies links them)"
echo "    receive path's own code       $((rx_flash - rx_mem)) bytes"
echo "  static RAM                      $rx_ram bytes"
echo "    inbox (RefCell<Inbox<100, Mode1, 84, 4>>: the decoder, 4 payloads, counters)  $inbox bytes"

budget=${RX_FLASH_BUDGET:-4096}
if ((rx_flash > budget)); then
    echo "size.sh: the receive path takes $rx_flash bytes of flash, over its budget of $budget" >&2
    exit 1
fi
echo "  within the flash budget of $budget bytes ($((budget - rx_flash)) to spare)"
echo
echo "receive path on the slice decoder, decode_each per FIFO's worth (rx_slice - baseline):"
echo "  flash                           $(($(flash rx_slice) - $(flash baseline))) bytes"

# No panic path: a reachable panic links core::panicking (a `RefCell::borrow_mut` or a
# `&buf[..len]` the compiler cannot prove in bounds is enough).
for bin in mav-firmware rx_path rx_slice baseline; do
    if "$NM" -C "$dir/$bin" | grep -q ' core::panicking::'; then
        echo "size.sh: $bin keeps a panic path: $("$NM" -C "$dir/$bin" | grep -E ' core::(panicking|cell|slice|option|result)::' | awk '{ $1 = $2 = ""; print }' | tr '\n' ';')" >&2
        exit 1
    fi
done
echo
echo "no panic path in mav-firmware, rx_path, rx_slice or baseline"
