#!/usr/bin/env python3
"""Writes the seed corpus of every fuzz target into fuzz/corpus/<target>/.

Sources: the MCP packets of the specification's tables 3-24 (written out below) and
the XBee vectors under testdata/ (Digi's manual frames, the ap1.bin/ap2.bin streams).
Only the standard library; deterministic; run from anywhere:

    python3 fuzz/seed-corpus.py

Each target's directory is emptied and written again. Input formats:

- xbee_decoder_mode1/2, host_codec: one byte N (chunk-size count, N % 8), N chunk
  sizes, then the stream bytes.
- mcp_parse: one MCP payload.
- frame_roundtrip: structured input read by `arbitrary`; seeded with frame data and
  payloads (padded with zeros to 64 bytes, which `arbitrary` needs at least) so that
  its first inputs are not all zeros.
- hub_client_codec: host_codec's seeds (the same layout: a byte of mode, here also of
  frame size limit, then host_codec's).
- the other targets start from no seed.
"""

import pathlib
import shutil

ROOT = pathlib.Path(__file__).resolve().parent.parent
TESTDATA = ROOT / "testdata"
CORPUS = ROOT / "fuzz" / "corpus"

START, ESCAPE = 0x7E, 0x7D
SPECIAL = {0x7E, 0x7D, 0x11, 0x13}


def f32(value):
    import struct

    return struct.pack("<f", value)


def u32(value):
    return value.to_bytes(4, "little")


WAYPOINT = u32(1_700_000_000) + f32(1.5) + f32(-2.25) + f32(10.0)
WAYPOINT2 = u32(1_700_000_060) + f32(0.0) + f32(3.0) + f32(12.5)
SLAVE = bytes.fromhex("0013A20040522BAA")

# Every packet of the specification's tables 3-24, with the table it comes from.
TABLES = {
    "t03-telemetry-to-coordinator-on": b"c\x01\x01\x19",
    "t03-telemetry-to-coordinator-off": b"c\x01\x00\x01",
    "t04-telemetry-to-coordinator-status": b"c\x01\xff\x19",
    "t05-landing-on": b"c\x02\x01",
    "t05-landing-off": b"c\x02\x00",
    "t06-landing-status": b"c\x02\xff",
    "t07-controllers": b"c\x03\x02",
    "t08-controllers-status": b"c\x03\xff",
    "t09-trajectory-set-2": b"c\x04\x02" + WAYPOINT + WAYPOINT2,
    "t09-trajectory-set-0": b"c\x04\x00",
    "t10-trajectory-set-status": b"c\x04\xff",
    "t11-position-slave-set": b"c\x05" + SLAVE,
    "t11-position-slave-set-slot": b"c\x05\x02" + SLAVE,
    "t12-position-slave-set-status": b"c\x05\xff",
    "t13-time": b"c\x06" + u32(1_700_000_000),
    "t14-time-status": b"c\x06\xff",
    "t15-position-set": b"c\x07" + f32(1.25) + f32(-0.5),
    "t16-telemetry-2": b"t\x01" + f32(1.5) + b"\x19" + f32(-3.0),
    "t16-telemetry-0": b"t",
    "t18-report-telemetry-to-coordinator": b"r\x01\x01\x19",
    "t19-report-landing": b"r\x02\x04",
    "t20-report-controllers": b"r\x03\x03",
    "t21-report-trajectory-set": b"r\x04\x01" + WAYPOINT,
    "t22-report-position-slave-set": b"r\x05" + SLAVE,
    "t22-report-position-slave-set-slots": b"r\x05" + SLAVE * 4,
    "t23-report-time": b"r\x06" + u32(1_700_000_000),
    "t24-message": b"mHello World",
    "t24-warning": b"wlow battery",
}


# A node discovery answer, as an AT Command Response to ND (frame id 1, status ok): MY,
# SH and SL, the node identifier and its 0x00, the parent, device type (router),
# status, profile id, manufacturer id, then the device type identifier and the RSSI
# that a radio whose NO asks for them adds.
ND_ANSWER = (
    bytes.fromhex("88014E4400" "7D84" "0013A20040B599B9")
    + b"MAV 1\x00"
    + bytes.fromhex("FFFE" "01" "00" "C105" "101E" "000B0000" "28")
)


def checksum(data):
    return 0xFF - (sum(data) & 0xFF)


def encode(data, mode):
    """Frame data (type byte first) to an API frame in mode 1 or 2."""
    body = len(data).to_bytes(2, "big") + data + bytes([checksum(data)])
    if mode == 2:
        out = bytearray()
        for b in body:
            if b in SPECIAL:
                out += bytes([ESCAPE, b ^ 0x20])
            else:
                out.append(b)
        body = bytes(out)
    return bytes([START]) + body


def unescape(stream):
    out, i = bytearray(), 0
    while i < len(stream):
        b = stream[i]
        if b == ESCAPE and i + 1 < len(stream):
            out.append(stream[i + 1] ^ 0x20)
            i += 2
        else:
            out.append(b)
            i += 1
    return bytes(out)


def frames(stream, mode):
    """Frame data of every frame of a stream of valid frames, checksums checked."""
    if mode == 2:
        # A raw 0x7E only ever starts a frame in mode 2: split there, then unescape.
        bodies = [unescape(c) for c in stream.split(bytes([START]))[1:]]
    else:
        bodies, i = [], 0
        while i < len(stream):
            assert stream[i] == START, f"no delimiter at {i}"
            n = int.from_bytes(stream[i + 1 : i + 3], "big")
            bodies.append(stream[i + 1 : i + 4 + n])
            i += n + 4
    out = []
    for body in bodies:
        n = int.from_bytes(body[:2], "big")
        data = body[2 : 2 + n]
        assert len(body) == n + 3 and body[-1] == checksum(data), "bad frame in stream"
        out.append(data)
    return out


def receive_packet(payload):
    return bytes([0x90]) + SLAVE + bytes([0xFF, 0xFE, 0x41]) + payload


def digi_frames():
    """(name, mode, wire bytes) of every frame of digi-manual.txt."""
    out = []
    for line in (TESTDATA / "digi-manual.txt").read_text().splitlines():
        if not line.strip() or line.startswith("#"):
            continue
        frame_type, mode, *hexbytes = line.split()
        wire = bytes.fromhex("".join(hexbytes))
        out.append((f"digi-{frame_type.lower()}", int(mode), wire))
    return out


def stream_seed(stream, sizes=()):
    return bytes([len(sizes)]) + bytes(sizes) + stream


# libFuzzer skips inputs shorter than `arbitrary`'s least size of frame_roundtrip's
# `Input`; its seeds are padded with zeros to this length so that all of them are read.
ROUNDTRIP_MIN_LEN = 64


def write(target, name, data, seen):
    # The hub's client codec reads the host codec's layout (its first byte picks the
    # frame size limit too): the same streams, read as a client's.
    if target == "host_codec":
        write("hub_client_codec", name, data, seen)
    if target == "frame_roundtrip":
        data = data + bytes(max(0, ROUNDTRIP_MIN_LEN - len(data)))
    if data in seen[target]:
        return
    seen[target].add(data)
    path = CORPUS / target / name
    n = 1
    while path.exists():
        n += 1
        path = CORPUS / target / f"{name}-{n}"
    path.write_bytes(data)


def main():
    targets = [
        "xbee_decoder_mode1",
        "xbee_decoder_mode2",
        "mcp_parse",
        "frame_roundtrip",
        "host_codec",
        "hub_client_codec",
    ]
    for t in targets:
        shutil.rmtree(CORPUS / t, ignore_errors=True)
        (CORPUS / t).mkdir(parents=True)
    seen = {t: set() for t in targets}

    ap = {
        1: (TESTDATA / "ap1.bin").read_bytes(),
        2: (TESTDATA / "ap2.bin").read_bytes(),
    }
    ap_frames = {m: frames(ap[m], m) for m in (1, 2)}

    # MCP payloads: the tables, and every distinct one the streams carry (receive and
    # transmit frames), a few per category.
    for name, payload in TABLES.items():
        write("mcp_parse", name, payload, seen)
        write("frame_roundtrip", name, payload, seen)
    per_category = {}
    for data in ap_frames[1] + ap_frames[2]:
        header = {0x90: 12, 0x10: 14}.get(data[0])
        if header is None or len(data) <= header:
            continue
        payload = data[header:]
        k = per_category.get(payload[0], 0)
        if k < 4 and payload not in seen["mcp_parse"]:
            per_category[payload[0]] = k + 1
            write("mcp_parse", f"ap-{chr(payload[0]) if payload[0] < 128 else 'x'}-{k}",
                  payload, seen)

    for mode in (1, 2):
        decoder = f"xbee_decoder_mode{mode}"
        # Digi's frames, each alone, and all of a mode back to back.
        digi = [(n, w) for n, m, w in digi_frames() if m == mode]
        for name, wire in digi:
            write(decoder, name, stream_seed(wire), seen)
            write("host_codec", f"m{mode}-{name}", bytes([mode]) + stream_seed(wire), seen)
            if mode == 1:
                write("frame_roundtrip", name, wire[3:-1], seen)
        write(decoder, "digi-all", stream_seed(b"".join(w for _, w in digi), (1, 5, 64)), seen)
        # The whole xbee-python stream, split three ways, and its first frames alone.
        stream = ap[mode]
        write(decoder, "ap-whole", stream_seed(stream), seen)
        write(decoder, "ap-whole-split", stream_seed(stream, (1, 2, 3, 250, 0, 17, 64)), seen)
        write("host_codec", f"m{mode}-ap-whole-split", bytes([mode]) + stream_seed(stream, (7, 64, 1)), seen)
        for i, data in enumerate(ap_frames[mode][:12]):
            write(decoder, f"ap-frame-{i:02}", stream_seed(encode(data, mode)), seen)
        # A node discovery answer.
        write(decoder, "nd-answer", stream_seed(encode(ND_ANSWER, mode)), seen)
        if mode == 1:
            write("frame_roundtrip", "nd-answer", ND_ANSWER, seen)
        # Every table packet in a Receive Packet, back to back.
        rx = b"".join(encode(receive_packet(p), mode) for p in TABLES.values())
        write(decoder, "tables-in-receive-packets", stream_seed(rx, (3,)), seen)
        write("host_codec", f"m{mode}-tables-in-receive-packets", bytes([mode]) + stream_seed(rx, (3,)), seen)
        # Damage: garbage with delimiters before a frame, a cut-off frame, a bad
        # checksum, an empty and an oversize length, a bad escape.
        good = encode(receive_packet(TABLES["t13-time"]), mode)
        damaged = {
            "garbage-then-frame": b"\x00\x7e\x00\x7e\x00\x05\x90" + good,
            "cut-then-frame": good[:9] + good,
            "bad-checksum-then-frame": good[:-1] + bytes([good[-1] ^ 1]) + good,
            "empty-then-frame": b"\x7e\x00\x00" + good,
            "oversize-then-frame": b"\x7e\xff\xff" + good,
            "frame-inside-candidate": b"\x7e\x00\x20" + good + b"\x00" * 20 + good,
            "bad-escape-then-frame": b"\x7e\x00\x7d\x00" + good,
            "cut-at-end": good + good[:-2],
        }
        for name, stream in damaged.items():
            write(decoder, name, stream_seed(stream, (2, 1)), seen)
            write("host_codec", f"m{mode}-{name}", bytes([mode]) + stream_seed(stream, (2, 1)), seen)

    total = sum(len(s) for s in seen.values())
    size = sum(p.stat().st_size for p in CORPUS.rglob("*") if p.is_file())
    print(f"{total} files, {size} bytes under {CORPUS.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
