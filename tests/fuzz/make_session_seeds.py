#!/usr/bin/env python3
"""Write the seed corpus of tests/fuzz/fuzz_session.c: a few whole sessions.

The harness reads steps [op][n][n argument bytes]; a request step's arguments
are the supervisor, the command's field number in ls.Request, the seq policy,
then one value per field of the command's message in field-number order (the
order nanopb's iterator walks), encoded as fill() in fuzz_session.c reads them.
This script mirrors that encoding from the schema, so the seeds follow the
schema when it changes:

    python3 tests/fuzz/make_session_seeds.py tests/fuzz/seeds/fuzz_session
"""
from __future__ import annotations

import struct
import sys
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "host_tools" / "src"))
from google.protobuf.descriptor import Descriptor, FieldDescriptor  # noqa: E402

from landscape._generated import landscape_pb2 as pb  # noqa: E402
from landscape.limits import max_count  # noqa: E402
from landscape.registry import is_repeated  # noqa: E402

# fuzz_session.c: k_names, take_double's table, op numbers
NAMES = ["p0", "p1", "p2", "tag", "", "force_sensor", "wait 0.1", "dio 8 on", "0123456789" * 6 + "012",
         "\u00e9t\u00e9", "(not UTF-8)", "status", "digital"]
DOUBLES = [0.0, 0.1, -0.1, 0.5, 1.0, -1.0, 2.0, 10.0, 50.0, 100.0]
OP_REQUEST, OP_50MS, OP_RSVP, OP_DIO, OP_EMERGENCY = 0, 9, 10, 11, 13
WITH_HEARTBEATS = 0x10
JOINTS = 6


def double(v: float) -> bytes:
    if v in DOUBLES:
        return bytes([DOUBLES.index(v)])
    return bytes([200]) + struct.pack(">i", round(v * 65536))


def uint(v: int) -> bytes:
    if v < 8:
        out = bytes([v])
    elif 128 <= v < 250:
        out = bytes([v])
    else:
        out = bytes([250]) + struct.pack(">I", v & 0xFFFFFFFF)
    return out


def count(c: int, array_size: int) -> bytes:
    if c == min(JOINTS, array_size):
        return b"\x00"
    if 0 < c < 4:
        return bytes([c])
    if c == 0:
        return b"\x04"
    b = next(b for b in range(200, 256) if b % (array_size + 1) == c)
    return bytes([b])


def array_size(fd: FieldDescriptor) -> int:
    return max_count(fd.containing_type.name, fd.name) or 64


def scalar(fd: FieldDescriptor, v: Any) -> bytes:
    t = fd.type
    if t == FieldDescriptor.TYPE_BOOL:
        return bytes([1 if v else 0])
    if t in (FieldDescriptor.TYPE_DOUBLE, FieldDescriptor.TYPE_FLOAT):
        return double(float(v or 0.0))
    if t == FieldDescriptor.TYPE_STRING:
        return bytes([NAMES.index(v or "p0")])
    if t == FieldDescriptor.TYPE_MESSAGE:
        return fields(fd.message_type, v or {})
    size64 = t in (FieldDescriptor.TYPE_INT64, FieldDescriptor.TYPE_UINT64, FieldDescriptor.TYPE_SINT64,
                   FieldDescriptor.TYPE_FIXED64, FieldDescriptor.TYPE_SFIXED64)
    out = uint(int(v or 0))
    return out if size64 else out + b"\x01"  # 32-bit values: the byte that could negate them


def fields(desc: Descriptor, values: dict[str, Any]) -> bytes:
    out = b""
    for fd in sorted(desc.fields, key=lambda f: f.number):
        v = values.get(fd.name)
        if is_repeated(fd):
            items = list(v or [])
            out += count(len(items), array_size(fd))
            for item in items:
                out += scalar(fd, item)
            continue
        if fd.has_presence and fd.type != FieldDescriptor.TYPE_MESSAGE:
            # proto3 `optional` (a has_ flag in nanopb): present unless the seed says None
            if fd.name in values and v is None:
                out += b"\x03"
                continue
            out += b"\x00"
        out += scalar(fd, v)
    return out


def step(op: int, args: bytes) -> bytes:
    return bytes([op, len(args)]) + args


def request(sup: int, command: str, how: int = 0, **values: Any) -> bytes:
    fd = pb.Request.DESCRIPTOR.fields_by_name[command]
    args = bytes([sup, fd.number, how]) + fields(fd.message_type, values)
    if command == "connect":
        args += b"\x00\x00\x00"  # right version and schema, heartbeat period 100 ms, its own nonce
    return step(OP_REQUEST, args)


def wait(ms50: int) -> bytes:
    return step(OP_50MS | WITH_HEARTBEATS, bytes([ms50]))


def seeds() -> dict[str, bytes]:
    up = [0.5, -0.1, 0.5, 0.1, 0.5, 0.1]
    start = request(0, "connect", client_name="p0") + request(0, "lock") + request(0, "activate")
    path = [{"joints": [0.1 * (i + 1)] * JOINTS, "tag_name": "tag", "tag_index": i} for i in range(3)]
    return {
        "move": start + request(0, "move_absolute", point_name="p0", values=up, speed_pct=50.0) + wait(40)
        + request(0, "deactivate") + wait(20) + request(0, "release") + request(0, "disconnect"),
        "stop-resume-abort": start + request(0, "move_absolute", point_name="p1", values=up, speed_pct=10.0)
        + wait(4) + request(0, "stop_motion") + wait(10) + request(0, "resume_motion") + wait(4)
        + request(0, "stop_motion") + wait(10) + request(0, "abort_motion") + wait(4),
        "path": start + request(0, "path_load", path_name="p2", tags=path, number_of_points=3)
        + request(0, "path_move", path_name="p2", number_of_cycles=2) + wait(100),
        "owner-lost": start + request(1, "connect", client_name="p1")
        + request(0, "move_absolute", point_name="p0", values=up) + wait(2)
        + step(OP_50MS, bytes([30])) + request(1, "get_motion_control_state"),
        "emergency": start + request(0, "move_relative", point_name="p0", values=[0.2] * JOINTS)
        + wait(2) + step(OP_EMERGENCY, b"") + wait(20) + request(0, "activate"),
        "retransmit-and-reuse": start + request(0, "set_speed", speed=50.0)
        + request(0, "set_speed", how=210) + request(0, "get_units", how=240) + request(0, "lock", how=252),
        "dio": start + request(0, "set_digital_io", type="digital", unit_id=0, bits_on=0x100)
        + request(0, "signal_digital_io", type="digital", unit_id=0, bit_string=1)
        + step(OP_DIO, b"\x01") + wait(4) + step(OP_RSVP, b"\x00\x00\x01") + wait(4),
    }


def main() -> int:
    out = Path(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).parent / "seeds" / "fuzz_session")
    out.mkdir(parents=True, exist_ok=True)
    for name, data in seeds().items():
        (out / name).write_bytes(data)
    print(f"wrote {len(seeds())} seeds to {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
