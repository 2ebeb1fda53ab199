"""Benchmark 3: a small blocking command through the whole stack (host
library -> SLCAN pty -> landscaped -> back) against the floor of the same
link (a C peer echoing every frame)."""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import can
import isotp

from common import BIN, BUILD, BenchError, Row, Section, fmt_ratio, median, need, percentile, pty_peer
from landscape._generated import landscape_pb2 as pb

# The ids of one request frame and its echo: ISO-TP normal fixed addressing
# between the default host and device addresses (protocol/landscape.proto).
TO_DEVICE = pb.ISOTP_PHYSICAL_BASE | pb.DEFAULT_DEVICE_ADDRESS << 8 | pb.DEFAULT_HOST_ADDRESS
FROM_DEVICE = pb.ISOTP_PHYSICAL_BASE | pb.DEFAULT_HOST_ADDRESS << 8 | pb.DEFAULT_DEVICE_ADDRESS


def slcan_bus(link: Path) -> can.BusABC:
    return can.Bus(interface="slcan", channel=str(link), bitrate=1000000, sleep_after_open=0)


def command_round_trips(link: Path, runs: int) -> list[float]:
    try:
        from landscape.supervisor import Supervisor
    except ImportError as exc:
        raise BenchError(f"the host package `landscape` is not importable ({exc}): run .ci/setup") from None
    sup = Supervisor(slcan_bus(link), owns_bus=True)
    with sup:
        for _ in range(5):
            sup.get_motion_control_state()
        out = []
        for _ in range(runs):
            t0 = time.perf_counter()
            sup.get_motion_control_state()
            out.append(time.perf_counter() - t0)
        return out


def frame_round_trips(link: Path, runs: int) -> list[float]:
    """Raw python-can: send one 8-byte frame, wait for its echo."""
    bus = slcan_bus(link)
    try:
        out = []
        for k in range(runs + 5):
            msg = can.Message(arbitration_id=TO_DEVICE, is_extended_id=True, data=bytes([1, k & 0xFF] + [0xCC] * 6))
            t0 = time.perf_counter()
            bus.send(msg)
            while True:
                got = bus.recv(timeout=2.0)
                if got is None:
                    raise BenchError(f"no echo of a frame from bench_frame_echo on {link} within 2 s")
                if got.arbitration_id == FROM_DEVICE and got.data[1] == (k & 0xFF):
                    break
            if k >= 5:
                out.append(time.perf_counter() - t0)
        return out
    finally:
        bus.shutdown()


def isotp_sf_round_trips(link: Path, runs: int) -> list[float]:
    """python can-isotp (as the host library uses it): one single frame out, its echo back."""
    bus = slcan_bus(link)
    notifier = can.Notifier(bus, [], timeout=0.05)
    address = isotp.Address(isotp.AddressingMode.NormalFixed_29bits, source_address=0xF1, target_address=0x10)
    stack = isotp.NotifierBasedCanStack(bus, notifier, address=address,
                                        params={"blocksize": 8, "stmin": 0, "tx_padding": 0xCC,
                                                "tx_data_min_length": 8})
    stack.start()
    try:
        out = []
        for k in range(runs + 5):
            data = bytes([k & 0xFF, 2, 3, 4, 5, 6])
            t0 = time.perf_counter()
            stack.send(data)
            got = stack.recv(block=True, timeout=2.0)
            if got != data:
                raise BenchError(f"no ISO-TP single-frame echo from bench_frame_echo on {link}")
            if k >= 5:
                out.append(time.perf_counter() - t0)
        return out
    finally:
        stack.stop()
        notifier.stop()
        bus.shutdown()


def fig(xs: list[float]) -> str:
    return f"median {median(xs) * 1e3:.3f} ms, p99 {percentile(xs, 99) * 1e3:.3f} ms"


def bench_command(quick: bool) -> Section:
    sec = Section(3, "Command round trip: getMotionControlState through the whole stack vs the link's floor")
    runs = 100 if quick else 500
    landscaped = need(BUILD / "bin" / "landscaped", "the firmware")
    echo = need(BIN / "bench_frame_echo", "the SLCAN frame echo")
    with tempfile.TemporaryDirectory(prefix="lsbench-") as tmp:
        link = Path(tmp) / "ls0"
        with pty_peer([str(landscaped), "--hal", "sim", "--link", f"slcan:pty:{link}"], link):
            cmd = command_round_trips(link, runs)
        with pty_peer([str(echo), str(link)], link):
            raw = frame_round_trips(link, runs)
            sf = isotp_sf_round_trips(link, runs)
    sec.rows.append(Row("3a. getMotionControlState round trip (Supervisor -> landscaped)", fig(cmd),
                        "raw frame echo, same pty (python-can send/recv, C echo peer)", fig(raw),
                        f"{fmt_ratio(median(cmd) / median(raw))} (median), "
                        f"{fmt_ratio(percentile(cmd, 99) / percentile(raw, 99))} (p99)", f"{runs} runs each"))
    sec.rows.append(Row("3b. same command", fig(cmd), "ISO-TP single-frame echo (python can-isotp host stack)",
                        fig(sf), f"{fmt_ratio(median(cmd) / median(sf))} (median), "
                        f"{fmt_ratio(percentile(cmd, 99) / percentile(sf, 99))} (p99)",
                        "the floor of any ISO-TP request/answer with the host's stack"))
    sec.details.append(
        "The command goes through `landscape.Supervisor` (protobuf request, can-isotp, python-can slcan) to "
        "`build-bench/bin/landscaped --hal sim` and back (its answer is a multi-frame ISO-TP message). Floors "
        "on the same pty type, answered by `bench/frame_echo.c` (echoes every frame, swapping the two "
        "address bytes of the 29-bit id): (a) one raw CAN frame out and back through python-can; (b) one "
        "ISO-TP single frame out and back through the same can-isotp stack the host library uses.")
    sec.commands.append("build-bench/bin/landscaped --hal sim --link slcan:pty:/tmp/ls0 &")
    sec.commands.append("build-bench/bench/bench_frame_echo /tmp/ls0 &")
    return sec
