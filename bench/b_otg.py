"""Benchmark 10: ls_otg (ruckig's C++ behind a C API) against ruckig (PyPI) on
random state-to-state 6-DOF problems: duration ratio, limit violations from
1 kHz sampling, planning time, all timed in this run."""

from __future__ import annotations

import subprocess

from otg_problems import Problem, make_problems, ruckig_plan

from common import BIN, BenchError, Row, Section, fmt_ratio, median, need, percentile

SEED = 20261124
LIMIT_TOL = 1e-9


def c_plan(problems: list[Problem]) -> list[list[float]]:
    exe = need(BIN / "bench_otg", "state-to-state trajectory driver")
    text = "\n".join(p.line() for p in problems) + "\n"
    out = subprocess.run([str(exe)], input=text, capture_output=True, text=True, timeout=600, check=False)
    if out.returncode != 0:
        raise BenchError(f"bench_otg failed: {out.stderr.strip()}")
    rows: list[list[float]] = []
    for k, line in enumerate(out.stdout.splitlines()):
        parts = line.split()
        if parts[0] != "OK":
            raise BenchError(f"ls_otg_plan_position refused problem {k}: {line}")
        rows.append([float(x) for x in parts[1:]])
    if len(rows) != len(problems):
        raise BenchError("bench_otg answered fewer problems than it was given")
    return rows


def bench_otg(quick: bool) -> Section:
    sec = Section(10, "State-to-state trajectories vs ruckig: random 6-DOF problems, moving at both ends")
    count = 1000 if quick else 10000
    problems = make_problems(count, SEED)
    ours = c_plan(problems)
    try:
        ref_d, ref_t = ruckig_plan(problems)
    except ImportError:
        raise BenchError("ruckig is not installed in the venv (pip install ruckig; .ci/setup does)") from None
    except RuntimeError as exc:
        raise BenchError(str(exc)) from None
    ours_d = [r[0] for r in ours]
    ours_t = [r[1] for r in ours]
    ratios = [o / r if r > 0 else 1.0 for o, r in zip(ours_d, ref_d, strict=True)]
    violations = sum(1 for r in ours if max(r[2], r[3], r[4]) > 1 + LIMIT_TOL)
    worst = [max(r[i] for r in ours) for i in (2, 3, 4)]
    end_err = max(r[5] for r in ours)
    sec.rows.append(Row(f"10a. trajectory duration, {count} problems",
                        f"ls_otg_plan_position: mean {sum(ours_d) / count:.4f} s",
                        "ruckig (PyPI) calculate(), time-optimal", f"mean {sum(ref_d) / count:.4f} s",
                        f"min {min(ratios):.6f} / mean {sum(ratios) / len(ratios):.6f} / max {max(ratios):.6f}",
                        "ours / ruckig per problem; 1.0 = time-optimal; max |ratio - 1| = "
                        f"{max(abs(r - 1) for r in ratios):.1e}"))
    sec.rows.append(Row("10b. limit violations sampled at 1 kHz", f"{violations} of {count} trajectories",
                        "the limits", "0", "-",
                        f"largest |v|/v_max {worst[0]:.9f}, |a|/a_max {worst[1]:.9f}, |j|/j_max {worst[2]:.9f}; "
                        f"state at T within {end_err:.1e} of the target"))
    sec.rows.append(Row("10c. planning time per 6-DOF problem", f"median {median(ours_t) / 1000:.2f} us, "
                        f"p99 {percentile(ours_t, 99) / 1000:.2f} us", "ruckig calculate() via its Python binding",
                        f"median {median(ref_t) / 1000:.2f} us, p99 {percentile(ref_t, 99) / 1000:.2f} us",
                        f"{fmt_ratio(median(ours_t) / median(ref_t))} (median, lower is better)",
                        "ours: C, 20 back-to-back plans per problem, input checks and the copy of the trajectory "
                        "into the caller's ls_otg_t included; ruckig's: one call each, the Python binding's "
                        "conversions included"))
    sec.details.append(
        "Problems from `bench/otg_problems.py` (seed 20261124; the CI oracle test "
        "`tests/unit/otg/test_otg_oracle.py` runs 1,000 of the same generator): positions in [-3, 3], "
        "v_max 0.2-4, a_max 0.5-20, j_max 2-200 per axis; every axis starts and ends with non-zero velocity "
        "and acceleration, within what the limits can hold (|a| <= 0.9 a_max, |v| + a^2/2j <= 0.9 v_max). "
        "`tests/unit/otg/otg_oracle.c` (built as bench_otg) reads them all, times 20 back-to-back "
        "`ls_otg_plan_position` calls per problem with CLOCK_MONOTONIC, then samples the trajectory every "
        "1 ms and at T; ruckig's `calculate` is timed per call with `perf_counter_ns` in the same script run. "
        "ls_otg is ruckig 0.19.4's own C++ (the version the venv pins), so ratio 1 is expected; the row "
        "shows that the C API, its fixed-size types and the build reproduce it.")
    sec.commands.append("build-bench/bench/bench_otg < problems.txt   "
                        "# 'OK <T_s> <ns per plan> <v> <a> <j ratios> <end error>' per line")
    return sec
