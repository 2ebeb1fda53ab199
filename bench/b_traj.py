"""Benchmark 4: ls_traj against ruckig on random 6-DOF rest-to-rest problems:
duration ratio (ours / ruckig's time-optimal synchronised duration) and
planning time, both timed in this run."""

from __future__ import annotations

import random
import subprocess
import time

from common import BIN, BenchError, Row, Section, fmt_ratio, median, need, percentile

DOFS = 6
SEED = 20261123


def make_problems(count: int) -> list[tuple[list[float], ...]]:
    """The distribution of tests/unit/traj/test_ruckig_oracle.py (every profile shape occurs)."""
    rng = random.Random(SEED)
    out: list[tuple[list[float], ...]] = []
    for k in range(count):
        p0 = [rng.uniform(-3.0, 3.0) for _ in range(DOFS)]
        p1 = [rng.uniform(-3.0, 3.0) for _ in range(DOFS)]
        if k % 10 == 0:
            p1[k % DOFS] = p0[k % DOFS]
        if k % 7 == 0:
            p1[(k + 1) % DOFS] = p0[(k + 1) % DOFS] + rng.uniform(-1e-3, 1e-3)
        v = [rng.uniform(0.1, 4.0) for _ in range(DOFS)]
        a = [rng.uniform(0.2, 20.0) for _ in range(DOFS)]
        j = [rng.uniform(0.5, 200.0) for _ in range(DOFS)]
        out.append((p0, p1, v, a, j))
    return out


def ruckig_plan(problems: list[tuple[list[float], ...]]) -> tuple[list[float], list[float]]:
    try:
        from ruckig import InputParameter, Result, Ruckig, Trajectory
    except ImportError:
        raise BenchError("ruckig is not installed in the venv (pip install ruckig; .ci/setup does)") from None
    otg = Ruckig(DOFS)
    traj = Trajectory(DOFS)
    durations, times = [], []
    inp = InputParameter(DOFS)
    for p0, p1, v, a, j in problems:
        inp.current_position, inp.target_position = p0, p1
        inp.current_velocity = inp.current_acceleration = [0.0] * DOFS
        inp.target_velocity = inp.target_acceleration = [0.0] * DOFS
        inp.max_velocity, inp.max_acceleration, inp.max_jerk = v, a, j
        t0 = time.perf_counter_ns()
        res = otg.calculate(inp, traj)
        times.append(float(time.perf_counter_ns() - t0))
        if res not in (Result.Working, Result.Finished):
            raise BenchError(f"ruckig refused a problem: {res}")
        durations.append(traj.duration)
    return durations, times


def python_call_overhead_ns(samples: int = 2000) -> float:
    """Median cost of the timer pair around a trivial call into a pybind11 object."""
    from ruckig import Trajectory

    traj = Trajectory(DOFS)
    out = []
    for _ in range(samples):
        t0 = time.perf_counter_ns()
        _ = traj.duration
        out.append(float(time.perf_counter_ns() - t0))
    return median(out)


def c_plan(problems: list[tuple[list[float], ...]]) -> tuple[list[float], list[float]]:
    exe = need(BIN / "bench_traj", "trajectory driver")
    text = "\n".join(" ".join(repr(x) for x in [DOFS, *p0, *p1, *v, *a, *j]) for p0, p1, v, a, j in problems)
    out = subprocess.run([str(exe)], input=text + "\n", capture_output=True, text=True, timeout=300)
    if out.returncode != 0:
        raise BenchError(f"bench_traj failed: {out.stderr.strip()}")
    durations, times = [], []
    for line in out.stdout.splitlines():
        parts = line.split()
        if parts[0] != "OK":
            raise BenchError(f"ls_traj_plan refused a problem: {line}")
        durations.append(float(parts[1]))
        times.append(float(parts[2]))
    if len(durations) != len(problems):
        raise BenchError("bench_traj answered fewer problems than it was given")
    return durations, times


def bench_traj(quick: bool) -> Section:
    sec = Section(4, "Trajectories vs ruckig: random 6-DOF rest-to-rest problems")
    count = 1000 if quick else 10000
    problems = make_problems(count)
    ours_d, ours_t = c_plan(problems)
    ref_d, ref_t = ruckig_plan(problems)
    overhead = python_call_overhead_ns()
    ratios = [o / r if r > 0 else 1.0 for o, r in zip(ours_d, ref_d, strict=True)]
    sec.rows.append(Row(f"4a. trajectory duration, {count} problems",
                        f"ls_traj_plan: mean {sum(ours_d) / count:.4f} s", "ruckig (PyPI) calculate(), time-optimal",
                        f"mean {sum(ref_d) / count:.4f} s",
                        f"min {min(ratios):.6f} / mean {sum(ratios) / len(ratios):.6f} / max {max(ratios):.6f}",
                        "ours / ruckig per problem; 1.0 = time-optimal; max |ratio - 1| = "
                        f"{max(abs(r - 1) for r in ratios):.1e}"))
    sec.rows.append(Row("4b. planning time per 6-DOF problem", f"median {median(ours_t) / 1000:.2f} us, "
                        f"p99 {percentile(ours_t, 99) / 1000:.2f} us", "ruckig calculate() via its Python binding",
                        f"median {median(ref_t) / 1000:.2f} us, p99 {percentile(ref_t, 99) / 1000:.2f} us",
                        f"{fmt_ratio(median(ours_t) / median(ref_t))} (median, lower is better)",
                        f"ruckig's figure includes the Python call: a trivial "
                        f"binding call + timer measures {overhead / 1000:.2f} us here"))
    sec.details.append(
        "Problems as in tests/unit/traj/test_ruckig_oracle.py (positions in [-3, 3], v 0.1-4, a 0.2-20, "
        "j 0.5-200, some axes still or moving by < 1e-3; seed 20261123). `bench/traj_plan.c` reads them all, "
        "then times 20 back-to-back `ls_traj_plan` calls per problem with CLOCK_MONOTONIC; ruckig's "
        "`calculate` is timed per call with `perf_counter_ns` in the same script run.")
    sec.commands.append("build-bench/bench/bench_traj < problems.txt   # 'OK <duration_s> <ns per plan>' per line")
    return sec
