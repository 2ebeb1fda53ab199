"""ls_otg against ruckig (PyPI): state-to-state durations and limits.

1,000 seeded random 6-DOF problems that start and end moving (bench/otg_problems.py,
the generator of bench 10) are planned by the C driver ``otg_oracle`` (path in
``LS_OTG_ORACLE``) and by ruckig's Python binding. ls_otg is ruckig's own C++ at the
same version (0.19.4), so the synchronised durations must agree to 1e-6 relative;
the driver also reports the largest velocity, acceleration and jerk ratios over 1 kHz
samples (must stay within the limits) and the distance from the target at T.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[3] / "bench"))

from otg_problems import Problem, make_problems, ruckig_plan  # noqa: E402

PROBLEMS = 1000
SEED = 20261124
DURATION_REL_TOL = 1e-6
LIMIT_TOL = 1e-9
END_TOL = 1e-9


def oracle_path() -> Path:
    path = os.environ.get("LS_OTG_ORACLE")
    if not path:
        pytest.fail("LS_OTG_ORACLE is not set: run this through ctest, or set it to the built otg_oracle")
    if not Path(path).is_file():
        pytest.fail(f"otg_oracle not found at {path}: build the otg_oracle target first")
    return Path(path)


def run_oracle(problems: list[Problem]) -> list[list[str]]:
    text = "\n".join(p.line() for p in problems) + "\n"
    out = subprocess.run([str(oracle_path())], input=text, capture_output=True, text=True, timeout=300, check=False)
    assert out.returncode == 0, f"otg_oracle failed: {out.stderr.strip()}"
    lines = [line.split() for line in out.stdout.splitlines()]
    assert len(lines) == len(problems), "otg_oracle answered a different number of problems"
    return lines


def test_problems_start_and_end_moving() -> None:
    for p in make_problems(PROBLEMS, SEED):
        for values in (p.v0, p.a0, p.v1, p.a1):
            assert all(x != 0.0 for x in values)


def test_durations_and_limits_match_ruckig() -> None:
    problems = make_problems(PROBLEMS, SEED)
    ref, _ = ruckig_plan(problems)
    worst = 0.0
    for k, (fields, want) in enumerate(zip(run_oracle(problems), ref, strict=True)):
        assert fields[0] == "OK", f"problem {k}: ls_otg refused it ({' '.join(fields)}): {problems[k].line()}"
        duration, v_ratio, a_ratio, j_ratio, end_err = (float(fields[i]) for i in (1, 3, 4, 5, 6))
        rel = abs(duration - want) / max(want, 1e-9)
        worst = max(worst, rel)
        assert rel <= DURATION_REL_TOL, f"problem {k}: ls_otg {duration!r} s, ruckig {want!r} s"
        assert v_ratio <= 1 + LIMIT_TOL, f"problem {k}: velocity {v_ratio:.12f} x v_max"
        assert a_ratio <= 1 + LIMIT_TOL, f"problem {k}: acceleration {a_ratio:.12f} x a_max"
        assert j_ratio <= 1 + LIMIT_TOL, f"problem {k}: jerk {j_ratio:.12f} x j_max"
        assert end_err <= END_TOL, f"problem {k}: {end_err:.3e} from the target state at T"
    print(f"max relative duration difference {worst:.2e}")
