"""Benchmark 12: Cartesian motion slowed where the joints must (docs/architecture.md "Path speed
under joint limits") against toppra (PyPI, TOPP-RA: time-optimal path parameterisation under
joint velocity and acceleration limits, acceleration-limited, so a lower bound of a
jerk-limited profile's duration). bench/path_speed.c plans each path with the firmware's
planner, times the planning and runs the plan with the executor at 1 kHz; this script gives
toppra the same joint path (1001 IK points along it) and the same limits."""

from __future__ import annotations

import subprocess
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from common import BIN, BenchError, Row, Section, need

#: The model's joint limits (firmware/model/ls_robot_model.c, as describe publishes them).
QD_MAX = np.array([2.5, 2.5, 3.0, 4.0, 4.0, 6.0])
QDD_MAX = np.array([8.0, 8.0, 10.0, 15.0, 15.0, 20.0])
READY = "0 -0.3 0.6 0 0.9 0"
NEAR_WRIST = "0 0.3 0.3 0.5 0.15 0"


@dataclass(frozen=True)
class Case:
    name: str
    args: str  # bench_pathspeed's arguments


CASES = [
    Case("15 cm line from ready at 90 % (refused before)", f"line {READY} 0.15 0 0 90 100"),
    Case("the same line at 10 %", f"line {READY} 0.15 0 0 10 100"),
    Case("arc from ready at 100 %", f"arc {READY} 0 0.2 0 0.1 0.1 0 100 100"),
    Case("line past a wrist singularity, joint 5 down to 0.1 rad", f"line {NEAR_WRIST} -0.05 0.05 0 50 100"),
    Case("line past a wrist singularity, joint 5 down to 0.01 rad", f"line {NEAR_WRIST} 0 0.11 -0.1 50 100"),
]
#: A stop in the middle of the slowest case, resumed once paused.
STOP_CASE = Case("the last line, stopped half-way and resumed", f"line {NEAR_WRIST} 0 0.11 -0.1 50 100 1.3")


@dataclass
class Result:
    duration_s: float
    requested_s: float
    plan_ns: float
    zones: int
    slow: str
    run_s: float
    qd_ratio: float
    qdd_ratio: float
    toppra_s: float


def run_case(case: Case, with_oracle: bool = True) -> Result:
    exe = need(BIN / "bench_pathspeed", "path speed driver")
    out = subprocess.run([str(exe), *case.args.split()], capture_output=True, text=True, timeout=300, check=False)
    if out.returncode != 0:
        raise BenchError(f"bench_pathspeed {case.args}: {out.stdout.strip() or out.stderr.strip()}")
    info: dict[str, list[str]] = {}
    path: list[list[float]] = []
    for line in out.stdout.splitlines():
        key, _, rest = line.partition(" ")
        if key == "PATH":
            path.append([float(x) for x in rest.split()])
        else:
            info[key] = rest.split() if key != "SLOW" else [rest]
    if "WHY" in info or "RUN" not in info:
        raise BenchError(f"bench_pathspeed {case.args}: {out.stdout.strip()[:300]}")
    plan, run, cart = info["PLAN"], info["RUN"], [float(x) for x in info["CART"]]
    toppra_s = toppra_duration(np.array(path), cart) if with_oracle else float("nan")
    return Result(float(plan[1]), float(plan[2]), float(plan[3]), int(plan[4]), info.get("SLOW", [""])[0],
                  float(run[0]), float(run[1]), float(run[2]), toppra_s)


def toppra_duration(path: np.ndarray, cart: Sequence[float]) -> float:
    """TOPP-RA on the joint path (rows: s, q1..q6) under the joints' limits and the Cartesian
    ones, as extra path coordinates: the tip's distance (s times the length) and turn."""
    try:
        import toppra as ta
        import toppra.algorithm as algo
        import toppra.constraint as tc
    except ImportError:
        raise BenchError("toppra is not installed in the venv (pip install toppra; .ci/setup does)") from None
    length, turn, v_lin, a_lin, v_ang, a_ang = cart
    s, q = path[:, 0], path[:, 1:]
    cols, vlim, alim = [q], [QD_MAX], [QDD_MAX]
    if length > 1e-9:
        cols.append((s * length)[:, None])
        vlim.append(np.array([v_lin]))
        alim.append(np.array([a_lin]))
    if turn > 1e-9:
        cols.append((s * turn)[:, None])
        vlim.append(np.array([v_ang]))
        alim.append(np.array([a_ang]))
    v, a = np.concatenate(vlim), np.concatenate(alim)
    inst = algo.TOPPRA([tc.JointVelocityConstraint(np.vstack([-v, v]).T),
                        tc.JointAccelerationConstraint(np.vstack([-a, a]).T)],
                       ta.SplineInterpolator(s, np.hstack(cols)), gridpoints=np.linspace(0.0, 1.0, 1001),
                       parametrizer="ParametrizeConstAccel")
    traj = inst.compute_trajectory()
    if traj is None:
        raise BenchError("toppra found no parameterisation of a benchmark path")
    return float(traj.duration)


def bench_pathspeed(quick: bool) -> Section:
    sec = Section(12, "Path speed under joint limits vs toppra: Cartesian lines and an arc the joints slow down")
    results = [(c, run_case(c)) for c in CASES]
    for k, (case, r) in enumerate(results):
        sec.rows.append(Row(f"12{'abcdefgh'[k]}. {case.name}",
                            f"{r.duration_s:.3f} s (requested {r.requested_s:.3f} s)",
                            "toppra, acceleration-limited", f"{r.toppra_s:.3f} s",
                            f"{r.duration_s / r.toppra_s:.3f}",
                            f"ours / toppra (goal <= 1.3); joint speed <= {r.qd_ratio:.3f}, acceleration <= "
                            f"{r.qdd_ratio:.3f} of the limits at 1 kHz; {r.slow or 'not slowed'}"))
    worst_qd = max(r.qd_ratio for _, r in results)
    worst_qdd = max(r.qdd_ratio for _, r in results)
    stop_note = "not run in --quick"
    if not quick:
        s = run_case(STOP_CASE, with_oracle=False)
        worst_qd, worst_qdd = max(worst_qd, s.qd_ratio), max(worst_qdd, s.qdd_ratio)
        stop_note = (f"{STOP_CASE.name}: joint speed <= {s.qd_ratio:.3f}, acceleration <= {s.qdd_ratio:.3f}, "
                     f"{s.run_s:.3f} s in all")
    sec.rows.append(Row("12f. largest joint speed and acceleration / limit, sampled at 1 kHz",
                        f"speed {worst_qd:.4f}, acceleration {worst_qdd:.4f}", "the joint limits", "1.0",
                        f"{max(worst_qd, worst_qdd):.4f}", f"goal <= 1.0; {stop_note}"))
    plan_us = [r.plan_ns / 1000 for _, r in results]
    sec.rows.append(Row("12g. planning time per segment (comms thread, at request time)",
                        f"{min(plan_us):.0f} to {max(plan_us):.0f} us", "", "", "",
                        "mean of 20 back-to-back ls_motion_plan_line/_arc calls per path: sampling and IK every "
                        "1 mm / 0.5 deg / 10 ms (finer where a joint turns fast), the speed-limit curve, the "
                        f"profile; {', '.join(str(r.zones) for _, r in results)} zones"))
    sec.details.append(
        "`bench/path_speed.c` (built as bench_pathspeed) moves the flange from the given joints by the given "
        "offset in the base frame, orientation kept (an arc through the via offset), at SPEED_PCT of the "
        "model's Cartesian speed and its full acceleration and jerk, planned with `ls_motion_plan_line` / "
        "`_arc` as the firmware does, timed over 20 back-to-back calls with CLOCK_MONOTONIC, and run with the "
        "executor at 1 ms on an ideal arm (the set-point is the position); the joint speed and acceleration "
        "are the first and second differences of the set-points. toppra 0.6 (`host_tools/constraints.txt`) "
        "gets the joint path at 1001 points of the path parameter (IK as the executor does it) as a cubic "
        "spline, 1001 grid points, the joints' velocity and acceleration limits and the Cartesian speed and "
        "acceleration as limits of two more path coordinates (distance and turn); its duration is "
        "acceleration-limited and so a lower bound: ours adds the jerk limit's ramps, and keeps a zone's "
        "worst joint bounds along the zone (docs/architecture.md \"Path speed under joint limits\" says why "
        "the lines that pass close to a singularity stay well above the goal). Joint paths, limits and "
        "durations are computed, not timed: they do not depend on the machine's load; the planning time is.")
    sec.commands.append("build-bench/bench/bench_pathspeed line 0 -0.3 0.6 0 0.9 0 0.15 0 0 90 100   "
                        "# PLAN/SLOW/CART/PATH/RUN lines (bench/path_speed.c)")
    return sec
