"""Random state-to-state 6-DOF problems for ls_otg against ruckig (PyPI): one
generator for bench 10 (bench/b_otg.py, 10,000) and the CI oracle test
(tests/unit/otg/test_otg_oracle.py, 1,000).

Every problem starts and ends moving (non-zero velocity and acceleration on
every axis) and is reachable within its limits: each state has |a| <= 0.9
a_max and |a| <= sqrt(v_max j_max), and |v| + a^2 / (2 j_max) <= 0.9 v_max,
so the velocity while the acceleration ramps to or from the state stays
within v_max. Limits span wide ranges so that every profile shape occurs.
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass

DOFS = 6


@dataclass(frozen=True)
class Problem:
    p0: list[float]
    v0: list[float]
    a0: list[float]
    p1: list[float]
    v1: list[float]
    a1: list[float]
    v_max: list[float]
    a_max: list[float]
    j_max: list[float]

    def line(self) -> str:
        """One line of the C driver's input (tests/unit/otg/otg_oracle.c)."""
        values = [DOFS, *self.p0, *self.v0, *self.a0, *self.p1, *self.v1, *self.a1, *self.v_max, *self.a_max,
                  *self.j_max]
        return " ".join(repr(x) for x in values)


def _state(rng: random.Random, v_max: float, a_max: float, j_max: float) -> tuple[float, float, float]:
    p = rng.uniform(-3.0, 3.0)
    a_hold = min(0.9 * a_max, math.sqrt(v_max * j_max))
    a = rng.choice((-1.0, 1.0)) * rng.uniform(0.05, 1.0) * a_hold
    span = 0.9 * v_max - a * a / (2.0 * j_max)
    v = rng.choice((-1.0, 1.0)) * rng.uniform(0.05, 1.0) * span
    return p, v, a


def make_problems(count: int, seed: int) -> list[Problem]:
    rng = random.Random(seed)
    out: list[Problem] = []
    for _ in range(count):
        v_max = [rng.uniform(0.2, 4.0) for _ in range(DOFS)]
        a_max = [rng.uniform(0.5, 20.0) for _ in range(DOFS)]
        j_max = [rng.uniform(2.0, 200.0) for _ in range(DOFS)]
        cur = [_state(rng, v_max[i], a_max[i], j_max[i]) for i in range(DOFS)]
        tgt = [_state(rng, v_max[i], a_max[i], j_max[i]) for i in range(DOFS)]
        out.append(Problem([s[0] for s in cur], [s[1] for s in cur], [s[2] for s in cur],
                           [s[0] for s in tgt], [s[1] for s in tgt], [s[2] for s in tgt], v_max, a_max, j_max))
    return out


def ruckig_plan(problems: list[Problem]) -> tuple[list[float], list[float]]:
    """ruckig's synchronised duration per problem and the time of each
    calculate() call (ns, perf_counter_ns around the call: it includes the
    Python binding). Raises RuntimeError when ruckig refuses a problem (the
    generator made one that is not reachable) or ImportError without ruckig."""
    import time

    from ruckig import InputParameter, Result, Ruckig, RuckigError, Trajectory

    otg = Ruckig(DOFS)
    traj = Trajectory(DOFS)
    inp = InputParameter(DOFS)
    durations: list[float] = []
    times: list[float] = []
    for k, pr in enumerate(problems):
        inp.current_position, inp.current_velocity, inp.current_acceleration = pr.p0, pr.v0, pr.a0
        inp.target_position, inp.target_velocity, inp.target_acceleration = pr.p1, pr.v1, pr.a1
        inp.max_velocity, inp.max_acceleration, inp.max_jerk = pr.v_max, pr.a_max, pr.j_max
        try:
            t0 = time.perf_counter_ns()
            res = otg.calculate(inp, traj)
            times.append(float(time.perf_counter_ns() - t0))
        except RuckigError as exc:
            raise RuntimeError(f"ruckig refused problem {k} ({exc}): the generator made an invalid one") from None
        if res not in (Result.Working, Result.Finished):
            raise RuntimeError(f"ruckig refused problem {k} ({res}): the generator made an unreachable one")
        durations.append(traj.duration)
    return durations, times
