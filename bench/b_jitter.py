"""Benchmark 8: wake-up latency of the Linux backend's 1 kHz loop
(hal/linux/hal_linux_rt) against a bare clock_nanosleep loop, back to back
in one process."""

from __future__ import annotations

import platform
import subprocess

from common import BIN, BenchError, Row, Section, fmt_ratio, need


def parse(line: str) -> dict[str, int]:
    parts = line.split()
    return {parts[i]: int(parts[i + 1]) for i in range(1, len(parts) - 1, 2)}


def bench_jitter(quick: bool) -> Section:
    sec = Section(8, "Real-time jitter at 1 kHz: hal_linux_rt vs a bare clock_nanosleep loop")
    exe = need(BIN / "bench_rt_jitter", "jitter driver")
    seconds = 2 if quick else 10
    out = subprocess.run([str(exe), str(seconds), "1000", "80"], capture_output=True, text=True,
                         timeout=4 * seconds + 30)
    if out.returncode != 0:
        raise BenchError(f"bench_rt_jitter failed: {out.stderr.strip()}")
    lines = {line.split()[0]: line for line in out.stdout.splitlines()}
    hal, bare = parse(lines["hal_linux_rt"]), parse(lines["bare_loop"])

    def fig(d: dict[str, int]) -> str:
        return (f"p50 {d['p50'] / 1000:.1f} / p99 {d['p99'] / 1000:.1f} / p99.9 {d['p999'] / 1000:.1f} / "
                f"max {d['max'] / 1000:.1f} us; {d['overruns']} overruns")

    sched = "SCHED_FIFO 80" if hal["realtime"] else "normal thread (no SCHED_FIFO granted)"
    sec.rows.append(Row(f"8. wake-up latency, 1 kHz, {seconds} s each", fig(hal), "bare clock_nanosleep loop",
                        fig(bare), f"{fmt_ratio(hal['p99'] / max(bare['p99'], 1))} (p99), "
                        f"{fmt_ratio(hal['max'] / max(bare['max'], 1))} (max)",
                        f"{sched}, memory locked; kernel {platform.release()}"))
    if out.stderr.strip():
        sec.details.append("Runner warnings: `" + out.stderr.strip().replace("\n", "; ") + "`")
    sec.details.append(
        "`bench/rt_jitter.c`: the runner (`hal_linux_rt_start`, priority 80, memory locked) runs until it has "
        f"{seconds * 1000} cycles, then a bare thread with the same scheduling sleeps to absolute deadlines "
        "(`clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME)`) as long. Both cycle bodies only read the clock: "
        "latency_k = t_k - (t_0 + k * 1 ms), re-based after an overrun (a wake-up more than a period late). "
        "This kernel is not PREEMPT_RT, and the machine runs other work: the figures are this host's, the "
        "ratio is what the runner adds.")
    sec.commands.append(f"build-bench/bench/bench_rt_jitter {seconds} 1000 80")
    return sec
