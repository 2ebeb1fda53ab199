"""ls_traj against ruckig: synchronised time-optimal durations and limits.

1,000 seeded random 6-DOF rest-to-rest problems are planned by the C driver
``traj_oracle`` (path in ``LS_TRAJ_ORACLE``) and by ruckig (Synchronization.Time,
its default). For rest-to-rest motion ruckig's synchronised duration is the
largest per-axis minimum time, which is what ls_traj_plan must produce; the
driver also reports the largest velocity, acceleration and jerk ratios over
1 kHz samples, which must stay within the limits.
"""

from __future__ import annotations

import os
import random
import subprocess
from dataclasses import dataclass
from pathlib import Path

import pytest
from ruckig import InputParameter, Result, Ruckig, Trajectory

DOFS = 6
PROBLEMS = 1000
SEED = 20261122
DURATION_REL_TOL = 1e-6
LIMIT_TOL = 1e-6


@dataclass(frozen=True)
class Problem:
    p0: list[float]
    p1: list[float]
    v_max: list[float]
    a_max: list[float]
    j_max: list[float]

    def line(self) -> str:
        values = [DOFS, *self.p0, *self.p1, *self.v_max, *self.a_max, *self.j_max]
        return " ".join(repr(x) for x in values)


@dataclass(frozen=True)
class Report:
    duration_s: float
    v_ratio: float
    a_ratio: float
    j_ratio: float
    sync_err_s: float
    end_err: float


def oracle_path() -> Path:
    path = os.environ.get("LS_TRAJ_ORACLE")
    if not path:
        pytest.fail("LS_TRAJ_ORACLE is not set: run this through ctest, or set it to the built traj_oracle")
    if not Path(path).is_file():
        pytest.fail(f"traj_oracle not found at {path}: build the traj_oracle target first")
    return Path(path)


def make_problems() -> list[Problem]:
    rng = random.Random(SEED)
    problems: list[Problem] = []
    for k in range(PROBLEMS):
        p0 = [rng.uniform(-3.0, 3.0) for _ in range(DOFS)]
        p1 = [rng.uniform(-3.0, 3.0) for _ in range(DOFS)]
        if k % 10 == 0:
            p1[k % DOFS] = p0[k % DOFS]  # some axes do not move
        if k % 7 == 0:
            p1[(k + 1) % DOFS] = p0[(k + 1) % DOFS] + rng.uniform(-1e-3, 1e-3)  # tiny moves
        # Wide ranges so that every profile shape occurs: cruise or not, a_max reached or not.
        v_max = [rng.uniform(0.1, 4.0) for _ in range(DOFS)]
        a_max = [rng.uniform(0.2, 20.0) for _ in range(DOFS)]
        j_max = [rng.uniform(0.5, 200.0) for _ in range(DOFS)]
        problems.append(Problem(p0, p1, v_max, a_max, j_max))
    return problems


def ruckig_duration(problem: Problem) -> float:
    inp = InputParameter(DOFS)
    inp.current_position = problem.p0
    inp.current_velocity = [0.0] * DOFS
    inp.current_acceleration = [0.0] * DOFS
    inp.target_position = problem.p1
    inp.target_velocity = [0.0] * DOFS
    inp.target_acceleration = [0.0] * DOFS
    inp.max_velocity = problem.v_max
    inp.max_acceleration = problem.a_max
    inp.max_jerk = problem.j_max
    trajectory = Trajectory(DOFS)
    result = Ruckig(DOFS).calculate(inp, trajectory)
    assert result == Result.Working, f"ruckig failed on {problem}: {result}"
    return float(trajectory.duration)


def run_oracle(problems: list[Problem]) -> list[Report]:
    stdin = "\n".join(p.line() for p in problems) + "\n"
    done = subprocess.run(
        [str(oracle_path())], input=stdin, capture_output=True, text=True, timeout=300, check=False
    )
    assert done.returncode == 0, f"traj_oracle exited {done.returncode}: {done.stderr}"
    reports: list[Report] = []
    for line, problem in zip(done.stdout.splitlines(), problems, strict=True):
        fields = line.split()
        assert fields[0] == "OK", f"ls_traj_plan rejected {problem}: {line}"
        reports.append(Report(*(float(x) for x in fields[1:])))
    return reports


@pytest.fixture(scope="module")
def results() -> list[tuple[Problem, Report, float]]:
    problems = make_problems()
    reports = run_oracle(problems)
    return [(p, r, ruckig_duration(p)) for p, r in zip(problems, reports, strict=True)]


def test_duration_matches_ruckig(results: list[tuple[Problem, Report, float]]) -> None:
    worst = max(results, key=lambda x: abs(x[1].duration_s - x[2]) / x[2])
    problem, report, expected = worst
    rel = abs(report.duration_s - expected) / expected
    assert rel <= DURATION_REL_TOL, (
        f"duration {report.duration_s!r} vs ruckig {expected!r} (relative {rel:.3g}) for {problem}"
    )


def test_limits_respected(results: list[tuple[Problem, Report, float]]) -> None:
    for problem, report, _ in results:
        assert report.v_ratio <= 1.0 + LIMIT_TOL, f"|v|/v_max = {report.v_ratio!r} for {problem}"
        assert report.a_ratio <= 1.0 + LIMIT_TOL, f"|a|/a_max = {report.a_ratio!r} for {problem}"
        assert report.j_ratio <= 1.0 + LIMIT_TOL, f"|jerk|/j_max = {report.j_ratio!r} for {problem}"


def test_axes_synchronised_and_exact_at_end(results: list[tuple[Problem, Report, float]]) -> None:
    for problem, report, _ in results:
        assert report.sync_err_s <= 1e-12 * report.duration_s, f"axes end apart for {problem}: {report}"
        assert report.end_err == 0.0, f"end position not exactly p1 for {problem}: {report}"

