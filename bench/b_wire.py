"""Benchmark 6: bytes on the wire per path point for a typical 6-DOF
Cartesian path, encoded by the host library and carried by ISO-TP."""

from __future__ import annotations

import math

from common import BenchError, Row, Section

POINTS = 100
TAGS_PER_REQUEST = 32          # ls.PathLoadReq.tags max_count (protocol/landscape.options)
MAX_MESSAGE = 4095
BLOCK_SIZE = 8                 # the firmware receiver asks for BS 8 (ls_isotp defaults)
# A classic CAN data frame with a 29-bit id and 8 data bytes, before bit stuffing:
# SOF 1 + id 11 + SRR 1 + IDE 1 + id 18 + RTR 1 + r1 r0 2 + DLC 4 + data 64 + CRC 15
# + CRC delimiter 1 + ACK 2 + EOF 7 + interframe space 3.
BITS_PER_FRAME = 131


def isotp_frames(length: int) -> tuple[int, int]:
    """(frames from the sender, flow controls from the receiver) for one message."""
    if length <= 7:
        return 1, 0
    cfs = -(-(length - 6) // 7)
    return 1 + cfs, 1 + (cfs - 1) // BLOCK_SIZE


def path_points() -> list[dict[str, object]]:
    """A 100-point tool path: a spiral over a work surface, each point tagged, with speeds."""
    pts = []
    for i in range(POINTS):
        a = 2 * math.pi * i / 25
        pose = [0.45 + 0.10 * math.cos(a), 0.05 * i / POINTS + 0.10 * math.sin(a), 0.30 - 0.001 * i,
                math.pi, 0.1 * math.sin(a), 0.3 * math.cos(a)]
        pts.append({"pose": pose, "tag_name": f"p{i:03d}", "tag_index": i, "speed_pct": 50.0,
                    "transition_speed_pct": 20.0 if i % 5 else 0.0})
    return pts


def bench_wire(quick: bool) -> Section:
    del quick
    sec = Section(6, "Bytes on the wire per path point (pathLoad of a 100-point Cartesian path)")
    try:
        from landscape._generated import landscape_pb2 as pb
        from landscape.registry import build_request
    except ImportError as exc:
        raise BenchError(f"the host package `landscape` is not importable ({exc})") from None
    pts = path_points()
    messages: list[bytes] = []
    for start in range(0, POINTS, TAGS_PER_REQUEST):
        chunk = pts[start:start + TAGS_PER_REQUEST]
        req = build_request("path_load", seq=1 + len(messages), path_name="spiral", frame="BASE_CARTESIAN_FRAME",
                            motion_type="STRAIGHT_MOTION", number_of_points=len(chunk), tags=chunk)
        data = pb.Uplink(request=req).SerializeToString()
        if len(data) > MAX_MESSAGE:
            raise BenchError(f"a pathLoad of {len(chunk)} points is {len(data)} B, more than one ISO-TP message")
        messages.append(data)
    payload = sum(len(m) for m in messages)
    data_frames = sum(isotp_frames(len(m))[0] for m in messages)
    fcs = sum(isotp_frames(len(m))[1] for m in messages)
    frames = data_frames + fcs
    wire_bytes = frames * 8
    sec.rows.append(Row(f"6. pathLoad, {POINTS} Cartesian points ({len(messages)} requests)",
                        f"{wire_bytes / POINTS:.1f} B/point on the wire ({frames / POINTS:.2f} frames/point, "
                        f"{frames * BITS_PER_FRAME / POINTS:.0f} bit/point)",
                        "protobuf payload (what must be carried)", f"{payload / POINTS:.1f} B/point",
                        f"{wire_bytes / payload:.2f} (wire / payload)",
                        f"{data_frames} data frames + {fcs} flow controls; answers not counted"))
    one = pb.TagPoint(**{k: v for k, v in pts[1].items()})  # type: ignore[arg-type]
    sec.details.append(
        f"Each point: 6-value pose (packed doubles), tag name `p001`, tag index, speed 50 %, transition speed; "
        f"one TagPoint encodes to {len(one.SerializeToString())} B. Requests of at most {TAGS_PER_REQUEST} points "
        f"(the firmware's nanopb bound), each one `Uplink` message = one ISO-TP transfer: data frames padded to "
        f"8 B + the receiver's flow controls (BS {BLOCK_SIZE}). Bits per frame: 29-bit id, 8 data bytes, "
        f"{BITS_PER_FRAME} bits before stuffing.")
    sec.commands.append("(pure encoding, no device: bench/b_wire.py)")
    return sec
