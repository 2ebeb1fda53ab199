"""Benchmark 11: the device heartbeat's period as a supervisor receives it
(landscaped --hal sim -> SLCAN pty -> the host library's bus), against the
period the device keeps (200 ms, each frame 200 ms after the previous one).

What this measures is the device's comms thread waking on time plus this
process's reader thread getting the frame: the integration tests judge the
median period and the frame counters, and this figure shows the spread that a
shared machine adds (tests/integration/test_broadcasts.py)."""

from __future__ import annotations

import tempfile
import threading
import time
from pathlib import Path

import can

from common import BUILD, BenchError, Row, Section, fmt_ratio, median, need, percentile, pty_peer
from landscape import telemetry
from landscape._generated import landscape_pb2 as pb
from landscape.bus import BusSpec, open_bus, release_bus

PERIOD_S = telemetry.cycle_time_s("HEARTBEAT")  # the DBC's GenMsgCycleTime, which landscaped.c sends at


class Beats(can.Listener):
    """(arrival time, hb_counter) of every HEARTBEAT the device at `device` sends."""

    def __init__(self, device: int) -> None:
        self.device = device
        self.lock = threading.Lock()
        self.seen: list[tuple[float, int]] = []

    def on_message_received(self, msg: can.Message) -> None:
        b = telemetry.decode(msg)
        if b is not None and b.name == "HEARTBEAT" and b.sender == self.device:
            with self.lock:
                self.seen.append((time.monotonic(), int(b.signals["hb_counter"])))


def capture(link: Path, seconds: float) -> list[tuple[float, int]]:
    beats = Beats(pb.DEFAULT_DEVICE_ADDRESS)
    bus = open_bus(BusSpec(interface="slcan", channel=str(link)))
    notifier = can.Notifier(bus, [beats], timeout=0.05)
    try:
        time.sleep(seconds)
    finally:
        notifier.stop()
        bus.shutdown()
        release_bus(bus)
    with beats.lock:
        return list(beats.seen)


def bench_heartbeat(quick: bool) -> Section:
    sec = Section(11, "Heartbeat period as a supervisor receives it")
    landscaped = need(BUILD / "bin" / "landscaped", "the firmware")
    seconds = 4.0 if quick else 30.0
    with tempfile.TemporaryDirectory(prefix="ls-bench-hb-") as tmp:
        link = Path(tmp) / "can0"
        with pty_peer([str(landscaped), "--hal", "sim", "--link", f"slcan:pty:{link}"], link):
            seen = capture(link, seconds)
    if len(seen) < 3:
        raise BenchError(f"{len(seen)} heartbeats in {seconds:g} s from landscaped on {link}: expected about "
                         f"{seconds / PERIOD_S:.0f}")
    gaps = [tb - ta for (ta, _), (tb, _) in zip(seen, seen[1:], strict=False)]
    lost = sum((b - a - 1) % 256 for (_, a), (_, b) in zip(seen, seen[1:], strict=False))
    fig = (f"median {median(gaps) * 1000:.1f} / p99 {percentile(gaps, 99) * 1000:.1f} / "
           f"min {min(gaps) * 1000:.1f} / max {max(gaps) * 1000:.1f} ms; {lost} lost")
    sec.rows.append(Row(f"11. heartbeat period received, {len(gaps)} gaps", fig, "the device's period",
                        f"{PERIOD_S * 1000:.0f} ms", f"{fmt_ratio(median(gaps) / PERIOD_S)} (median), "
                        f"{fmt_ratio(max(gaps) / PERIOD_S)} (max)",
                        "lost: counter gaps (hb_counter, protocol/landscape.dbc)"))
    sec.details.append(
        f"`bench/b_heartbeat.py`: landscaped --hal sim on an SLCAN pty, the host library's bus "
        f"(`landscape.bus.open_bus`, its chunked reader) for {seconds:g} s; a gap is the time between two "
        "HEARTBEAT frames reaching the listener. The device sends each 200 ms after the previous one, so a gap "
        "beyond that is the device's comms thread or this reader waking late, and a short gap after a long one is "
        "this reader catching up. The integration tests judge the median and the counters, not single gaps "
        "(tests/integration/test_broadcasts.py).")
    sec.commands.append(f"build-bench/bin/landscaped --hal sim --link slcan:pty:/tmp/hb0 &   # then {seconds:g} s "
                        "of HEARTBEAT through landscape.bus.open_bus")
    return sec
