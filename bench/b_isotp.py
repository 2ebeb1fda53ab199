"""Benchmarks 1 and 2: ISO-TP efficiency (frames per transfer against the
ISO 15765-2 minimum) and ISO-TP throughput/latency over an SLCAN pty."""

from __future__ import annotations

import subprocess
import tempfile
import time
import uuid
from pathlib import Path

import can
import isotp

from common import BIN, PYTHON, ROOT, BenchError, Row, Section, fmt_ratio, median, need, percentile, pty_peer

MAX_LEN = 4095
PY_RETRIES: list[int] = []  # lengths whose reference transfer was repeated (see py_frames)


def iso_min_frames(length: int) -> int:
    """ISO 15765-2 minimum on classic CAN: one SF, or one FF + the CFs + one FC (BS 0)."""
    if length <= 7:
        return 1
    return 1 + -(-(length - 6) // 7) + 1


def ratio_stats(frames: dict[int, int]) -> tuple[float, float, float, int]:
    ratios = {n: f / iso_min_frames(n) for n, f in frames.items()}
    worst = max(ratios, key=lambda n: (ratios[n], -n))
    return min(ratios.values()), sum(ratios.values()) / len(ratios), max(ratios.values()), worst


def c_frames(block_size: int) -> dict[int, int]:
    exe = need(BIN / "bench_isotp_frames", "ISO-TP frame counter")
    out = subprocess.run([str(exe), str(block_size)], capture_output=True, text=True, timeout=120)
    if out.returncode != 0:
        raise BenchError(f"bench_isotp_frames failed: {out.stderr.strip()}")
    frames = {int(a): int(b) for a, b in (line.split() for line in out.stdout.splitlines())}
    if sorted(frames) != list(range(1, MAX_LEN + 1)):
        raise BenchError("bench_isotp_frames did not report every length 1..4095")
    return frames


def quick_lengths() -> list[int]:
    """The lengths the reference transfers in --quick: every single-frame length and the first few
    multi-frame ones, then a stride through the rest, and the maximum."""
    return sorted({*range(1, 33), *range(33, MAX_LEN, 97), MAX_LEN})


def py_frames(block_size: int, lengths: list[int]) -> dict[int, int]:
    """python can-isotp, two stacks on a python-can virtual bus, counted by a third bus node."""
    ch = uuid.uuid4().hex
    buses = [can.Bus(interface="virtual", channel=ch) for _ in range(3)]
    a_bus, b_bus, monitor = buses
    params = {"blocksize": block_size, "stmin": 0, "tx_padding": 0xCC}
    a = isotp.CanStack(a_bus, address=isotp.Address(isotp.AddressingMode.NormalFixed_29bits,
                                                    source_address=0xF1, target_address=0x10), params=params)
    b = isotp.CanStack(b_bus, address=isotp.Address(isotp.AddressingMode.NormalFixed_29bits,
                                                    source_address=0x10, target_address=0xF1), params=params)
    frames: dict[int, int] = {}
    retried: list[int] = []

    def attempt(data: bytes) -> int | None:
        """Frames of one transfer, or None when it failed (can-isotp's timers run on wall-clock time:
        a stall of the machine longer than N_Bs/N_Cr, 1 s, aborts a transfer)."""
        a.send(data)
        got = None
        for _ in range(200000):
            a.process()
            b.process()
            if b.available():
                got = b.recv()
                break
        count = 0
        while monitor.recv(0) is not None:
            count += 1
        return count if got == data else None

    try:
        for n in lengths:
            data = bytes((i * 37 + n) & 0xFF for i in range(n))
            for _ in range(3):
                count = attempt(data)
                if count is not None:
                    break
                retried.append(n)
                a.reset()
                b.reset()
                while monitor.recv(0) is not None:
                    pass
            if count is None:
                raise BenchError(f"can-isotp reference: transfer of {n} bytes failed 3 times on the virtual bus")
            frames[n] = count
        if retried:
            PY_RETRIES.extend(retried)
    finally:
        for bus in buses:
            bus.shutdown()
    return frames


def bench_frames(quick: bool) -> Section:
    sec = Section(1, "ISO-TP efficiency: frames per transfer / ISO 15765-2 minimum, lengths 1..4095")
    sec.details.append(
        "Minimum per ISO 15765-2 on classic CAN: 1 single frame (1..7 B), else 1 first frame + "
        "ceil((len-6)/7) consecutive frames + 1 flow control (what a receiver asking for block size 0 "
        "sends). Every frame both directions is counted. Firmware: two `ls_isotp` links back to back in "
        "memory (`bench/isotp_frames.c`). Reference: two python can-isotp 2.x `CanStack`s on a python-can "
        "`virtual` bus, frames counted by a third node. Block size 8 is the default of both stacks and of "
        "the host library; each extra flow control per block is counted against the minimum.")
    for bs in (0, 8):
        ours = c_frames(bs)
        o_min, o_mean, o_max, o_worst = ratio_stats(ours)
        lengths = quick_lengths() if quick else list(range(1, MAX_LEN + 1))
        ref = py_frames(bs, lengths)
        r_min, r_mean, r_max, _ = ratio_stats(ref)
        s_mean = ratio_stats({n: ours[n] for n in lengths})[1]
        same = sum(1 for n in lengths if ours[n] == ref[n])
        ref_txt = "python can-isotp, virtual bus" + (f" ({len(lengths)} lengths: --quick)" if quick else "")
        ref_fig = f"min {r_min:.2f} / mean {r_mean:.3f} / max {r_max:.2f}"
        ratio = f"{s_mean / r_mean:.3f} (mean); same count at {same}/{len(lengths)} lengths"
        sec.rows.append(Row(f"1. ISO-TP frames / minimum, BS {bs}",
                            f"min {o_min:.2f} / mean {o_mean:.3f} / max {o_max:.2f} (max at {o_worst} B)",
                            ref_txt, ref_fig, ratio, "goal 1.00" if bs == 0 else "BS 8: one FC per 8 CFs"))
        sec.details.append(f"BS {bs}: 4095 B takes {ours[4095]} frames (minimum {iso_min_frames(4095)}).")
    if PY_RETRIES:
        sec.details.append(f"The reference repeated {len(PY_RETRIES)} transfer(s) that can-isotp aborted on a "
                           f"wall-clock timeout while the machine stalled (lengths {sorted(set(PY_RETRIES))}); "
                           "the frames of the successful attempt are counted.")
    sec.commands.append("build-bench/bench/bench_isotp_frames 0   # '<len> <frames>' per length")
    return sec


# ---------------------------------------------------------------- 2. pty throughput / latency

HOST_PARAMS = {"blocksize": 8, "stmin": 0, "tx_padding": 0xCC, "tx_data_min_length": 8, "max_frame_size": 4095}


def echo_figures(link: Path, n_small: int, n_big: int) -> tuple[list[float], list[float]]:
    """Round trips (s) of 64 B and of 4095 B messages through the echo peer at `link`."""
    bus = can.Bus(interface="slcan", channel=str(link), bitrate=1000000, sleep_after_open=0)
    notifier = can.Notifier(bus, [], timeout=0.05)
    address = isotp.Address(isotp.AddressingMode.NormalFixed_29bits, source_address=0xF1, target_address=0x10)
    stack = isotp.NotifierBasedCanStack(bus, notifier, address=address, params=dict(HOST_PARAMS))
    stack.start()
    try:
        def round_trip(data: bytes) -> float:
            t0 = time.perf_counter()
            stack.send(data)
            got = stack.recv(block=True, timeout=10.0)
            dt = time.perf_counter() - t0
            if got != data:
                raise BenchError(f"echo of {len(data)} B over {link} failed (got "
                                   f"{'nothing' if got is None else f'{len(got)} B'})")
            return dt

        for _ in range(3):
            round_trip(bytes(range(64)))
        small = [round_trip(bytes((i + k) & 0xFF for i in range(64))) for k in range(n_small)]
        big = [round_trip(bytes((i * 7 + k) & 0xFF for i in range(MAX_LEN))) for k in range(n_big)]
        return small, big
    finally:
        stack.stop()
        notifier.stop()
        bus.shutdown()


def bench_pty(quick: bool) -> Section:
    sec = Section(2, "ISO-TP throughput and latency over the SLCAN pty")
    n_small, n_big = (50, 5) if quick else (300, 20)
    c_echo = need(BIN / "bench_isotp_pty_echo", "firmware ISO-TP echo peer")
    with tempfile.TemporaryDirectory(prefix="lsbench-") as tmp:
        link = Path(tmp) / "echo"
        with pty_peer([str(c_echo), str(link)], link):
            c_small, c_big = echo_figures(link, n_small, n_big)
        with pty_peer([PYTHON, str(ROOT / "bench" / "isotp_py_echo.py"), str(link)], link):
            p_small, p_big = echo_figures(link, n_small, n_big)
    c_rate, p_rate = MAX_LEN / median(c_big), MAX_LEN / median(p_big)
    sec.rows.append(Row("2a. ISO-TP echo 4095 B, goodput (B / round trip)", f"{c_rate / 1000:.1f} kB/s",
                        "python can-isotp echo, same pty", f"{p_rate / 1000:.1f} kB/s",
                        f"{fmt_ratio(c_rate / p_rate)} (higher is better)",
                        f"median of {n_big}; round trip {median(c_big) * 1e3:.1f} vs {median(p_big) * 1e3:.1f} ms"))
    sec.rows.append(Row("2b. ISO-TP echo 64 B, round trip", f"median {median(c_small) * 1e3:.3f} ms, "
                        f"p99 {percentile(c_small, 99) * 1e3:.3f} ms", "python can-isotp echo, same pty",
                        f"median {median(p_small) * 1e3:.3f} ms, p99 {percentile(p_small, 99) * 1e3:.3f} ms",
                        f"{fmt_ratio(median(c_small) / median(p_small))} (lower is better)", f"{n_small} runs"))
    sec.details.append(
        "Host side (the same in both runs): python-can `slcan` on the pty + python can-isotp "
        "`NotifierBasedCanStack` with the host library's parameters (BS 8, STmin 0, padding). Device side: "
        "`bench/isotp_pty_echo.c` (the firmware's `ls_isotp` on `hal/sim/slcan_pty`, firmware defaults) vs "
        "`bench/isotp_py_echo.py` (python can-isotp `TransportLayerLogic` behind a minimal SLCAN device end "
        "on a pty). Each echoes every message; the figure is one message's round trip. Device -> host is "
        "the slow direction: python-can's slcan reader takes one byte per call.")
    sec.commands.append("build-bench/bench/bench_isotp_pty_echo /tmp/echo &   # then python-can slcan on /tmp/echo")
    sec.commands.append(".venv/bin/python bench/isotp_py_echo.py /tmp/echo &")
    return sec
