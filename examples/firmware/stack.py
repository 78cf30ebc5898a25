#!/usr/bin/env python3
"""Stack high-water mark of a firmware ELF, measured in QEMU.

Boots the ELF in qemu-system-arm (lm3s6965evb) with UART0 and the QEMU monitor on
local TCP sockets, drives it with every MCP command type, status requests, a
5-waypoint trajectory, 40 telemetry ids, landing and take-off, garbage and an
oversize frame, then reads the top 8 KiB of RAM through the monitor. QEMU's RAM
starts zeroed and the stack grows down from the top of RAM, so the lowest non-zero
word marks (a lower bound of) the deepest stack use.

Usage: ./stack.py [ELF]   (default: the release build of mav-firmware)
"""

import re
import socket
import struct
import subprocess
import sys
import time

RAM_END = 0x2001_0000
WINDOW = 8 * 1024


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def frame(data):
    return bytes([0x7E, len(data) >> 8, len(data) & 0xFF]) + data + bytes([0xFF - (sum(data) & 0xFF)])


def receive_packet(payload):
    # From the coordinator: 64-bit 0, 16-bit 0, options 0x01.
    return frame(b"\x90" + bytes(8) + b"\x00\x00\x01" + payload)


def drain(sock, seconds):
    end = time.time() + seconds
    while time.time() < end:
        try:
            if not sock.recv(65536):
                return
        except socket.timeout:
            pass


def main():
    elf = sys.argv[1] if len(sys.argv) > 1 else "target/thumbv7m-none-eabi/release/mav-firmware"
    serial_port, monitor_port = free_port(), free_port()
    qemu = subprocess.Popen(
        ["qemu-system-arm", "-machine", "lm3s6965evb", "-nographic",
         "-monitor", f"tcp:127.0.0.1:{monitor_port},server,nowait",
         "-serial", f"tcp:127.0.0.1:{serial_port},server,wait=on", "-kernel", elf],
        stderr=subprocess.PIPE)
    try:
        qemu.stderr.readline()  # "QEMU waiting for connection on: ..."
        uart = socket.create_connection(("127.0.0.1", serial_port))
        uart.settimeout(0.2)
        drain(uart, 0.5)
        waypoints = b"".join(struct.pack("<Ifff", 4_000_000_000 + i, i, -i, 1 + i) for i in range(5))
        packets = [b"c\x01\x01" + bytes([i]) for i in range(40)] + [
            b"c\x04\x05" + waypoints, b"c\x04\xff", b"c\x05" + bytes(8), b"c\x05\x02" + bytes(range(8)),
            b"c\x05\xff", b"c\x06\x00\x00\x00\x10", b"c\x06\xff", b"c\x07" + struct.pack("<ff", 1, 2),
            b"c\x03\x03", b"c\x03\xff", b"c\x02\xff", b"c\x01\xff\x05", b"mhello", b"x"]
        burst = b"".join(receive_packet(p) for p in packets)
        uart.sendall(burst)
        drain(uart, 1.0)
        uart.sendall(receive_packet(b"c\x02\x01"))  # land
        drain(uart, 3.0)
        uart.sendall(receive_packet(b"c\x02\x00"))  # take off
        drain(uart, 3.0)
        uart.sendall(b"\x7e\xff\xff" + bytes(300) + burst)  # oversize frame, then the burst again
        drain(uart, 1.0)

        monitor = socket.create_connection(("127.0.0.1", monitor_port))
        monitor.settimeout(1.0)
        words = WINDOW // 4
        monitor.sendall(f"xp /{words}xw {RAM_END - WINDOW:#x}\n".encode())
        out = b""
        end = time.time() + 5
        while time.time() < end and out.count(b"\n") < words // 4 + 2:
            try:
                data = monitor.recv(1 << 20)
            except socket.timeout:
                continue
            if not data:
                break
            out += data
        lowest = None
        for line in out.decode(errors="replace").splitlines():
            m = re.match(r"\s*([0-9a-f]+):\s+(.*)", line)
            if not m:
                continue
            address = int(m.group(1), 16)
            for i, word in enumerate(m.group(2).split()):
                if int(word, 16) != 0:
                    lowest = min(lowest or RAM_END, address + 4 * i)
        if lowest is None:
            sys.exit("stack.py: no stack use found (monitor output not read?)")
        print(f"{elf}: stack high-water mark about {RAM_END - lowest} bytes (lowest used word {lowest:#010x})")
    finally:
        qemu.kill()
        qemu.wait()


if __name__ == "__main__":
    main()
