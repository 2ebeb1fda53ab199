"""Benchmark 9: blended paths. A 20-point Cartesian zig-zag run by the motion executor
(bench/blend_zigzag.c: the firmware's planners and ls_motion_prog_blend, an ideal arm at
1 ms), with transitionSpeed 100 % against the same path stopping at every point (0 %):
duration ratio, how far the tool misses the points and leaves the polyline against the
documented bound, and the largest limit ratio (used / allowed, from the set-points)."""

from __future__ import annotations

import subprocess
from dataclasses import dataclass

from common import BIN, BenchError, Row, Section, need

N_POINTS = 20
STEP_M = 0.02  # along base y per point
ZIG_M = 0.05  # along base x, every other point: legs of 5.4 cm turning by 136 degrees
SPEED_PCT = 25.0
ACCEL_PCT = 100.0


@dataclass(frozen=True)
class Run:
    duration_s: float
    miss_m: float
    off_m: float
    bound_m: float
    v_ratio: float
    a_ratio: float
    j_ratio: float
    qd_ratio: float
    min_speed_m_s: float
    tags: int

    @property
    def limit_ratio(self) -> float:
        return max(self.v_ratio, self.a_ratio, self.j_ratio)


def run_zigzag(transition_pct: float) -> Run:
    exe = need(BIN / "bench_blend", "blend driver")
    argv = [str(exe), str(N_POINTS), repr(STEP_M), repr(ZIG_M), repr(SPEED_PCT), repr(ACCEL_PCT),
            repr(transition_pct)]
    out = subprocess.run(argv, capture_output=True, text=True, timeout=300)
    line = out.stdout.strip()
    if out.returncode != 0 or not line.startswith("OK "):
        raise BenchError(f"bench_blend at transition {transition_pct:g} %: {line or out.stderr.strip()}")
    f = line.split()[1:]
    return Run(*(float(x) for x in f[:9]), tags=int(f[9]))


def bench_blend(quick: bool) -> Section:
    sec = Section(9, "Blended paths: a 20-point Cartesian zig-zag")
    stop = run_zigzag(0.0)
    levels = [100.0] if quick else [25.0, 50.0, 100.0]
    runs = {t: run_zigzag(t) for t in levels}
    for run in (stop, *runs.values()):
        if run.tags != N_POINTS:
            raise BenchError(f"bench_blend reported {run.tags} tag events for {N_POINTS} tagged points")
    full = runs[100.0]
    sec.rows.append(Row("9a. zig-zag duration, blended (transitionSpeed 100 %)", f"{full.duration_s:.3f} s",
                        "the same path stopping at every point (0 %)", f"{stop.duration_s:.3f} s",
                        f"{full.duration_s / stop.duration_s:.3f}",
                        f"lowest tip speed between the first and the last point {full.min_speed_m_s:.4f} m/s "
                        f"(stopping: {stop.min_speed_m_s:.1e})"))
    sec.rows.append(Row("9b. largest corner deviation (100 %)",
                        f"misses a point by {full.miss_m * 1e3:.3f} mm at most; "
                        f"{full.off_m * 1e3:.3f} mm from the polyline at most",
                        "documented bound max(Ja, Jb) T_o^3 / 6", f"{full.bound_m * 1e3:.3f} mm",
                        f"{full.off_m / full.bound_m:.3f}", "off-polyline distance / bound (<= 1)"))
    sec.rows.append(Row("9c. largest limit ratio (100 %)",
                        f"{full.limit_ratio:.6f} (speed {full.v_ratio:.6f}, accel {full.a_ratio:.6f}, "
                        f"jerk {full.j_ratio:.6f})", "the Cartesian limits in use",
                        f"{SPEED_PCT:g} % speed, {ACCEL_PCT:g} % accel", f"{full.limit_ratio:.6f}",
                        f"used / allowed (<= 1); stopping: {stop.limit_ratio:.6f}; joint speed "
                        f"{full.qd_ratio:.3f} of its limit"))
    for t, run in runs.items():
        if t == 100.0:
            continue
        sec.rows.append(Row(f"9d. transitionSpeed {t:g} %", f"{run.duration_s:.3f} s, misses by "
                            f"{run.miss_m * 1e3:.3f} mm, bound {run.bound_m * 1e3:.3f} mm",
                            "stopping (0 %)", f"{stop.duration_s:.3f} s", f"{run.duration_s / stop.duration_s:.3f}",
                            f"limit ratio {run.limit_ratio:.6f}"))
    sec.details.append(
        f"`bench/blend_zigzag.c` plans {N_POINTS} STRAIGHT_MOTION points from the tool tip at q = (0, 0.3, 0.3, 0, "
        f"0.9, 0): point k at (+{ZIG_M * 100:g} cm for even k, {STEP_M * 100:g} cm x (k + 1), 0), legs of 5.4 cm "
        f"turning by 136 degrees, at {SPEED_PCT:g} % speed and {ACCEL_PCT:g} % acceleration of the model's "
        "Cartesian maxima, as the program builder does (`ls_motion_seg_line`, then `ls_motion_prog_blend`), and "
        "runs it with the executor at 1 ms and an ideal arm. Speed, acceleration and jerk are finite differences "
        "of the set-points' tool tip (each a weighted mean of the true value, never above its peak; their rounding "
        "is about 1e-7 of a limit: the jerk of the time-optimal segments, at its limit, reads 1.00000004); "
        "the miss is "
        "the tip's closest approach to each point passed; the bound is docs/architecture.md \"Blended paths\". "
        "The figures are computed, not timed: they do not depend on the machine's load.")
    sec.commands.append(f"build-bench/bench/bench_blend {N_POINTS} {STEP_M} {ZIG_M} {SPEED_PCT:g} {ACCEL_PCT:g} 100"
                        "   # and 0: 'OK duration miss off bound v a j qd min_speed tags'")
    return sec
