"""Stops keep the jerk limit (docs/architecture.md "Stopping and resuming"), checked from outside:
landscaped records every
cycle's commanded joints (`--setpoint-trace`), and the jerk is the third difference of that
record over the control period (a weighted mean of the true jerk over three cycles, so never
above its peak), including the cycles where a stop and a resume begin.

- A stop while a joint path blends from one point into the next: the device says where it
  paused (stopMotion's answer), so the test knows the stop came inside a blend; every joint's
  jerk stays within the model's limit through the stop, the pause, the resume and the rest of
  the path.
- moveReact: its brake after the threshold and a stopMotion during its travel keep the tool
  tip's jerk within the model's Cartesian jerk limit.

The device publishes velocity and acceleration limits, not jerk limits; those are read from the
default arm's model file, as test_setpoint_trace does."""
from __future__ import annotations

import math
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest
from setpoint_trace import Trace, derivatives, model_values, read_trace, traced
from test_motion import fk
from test_setpoint_trace import model_jerk_limits

from landscape._generated import landscape_pb2 as pb
from landscape.supervisor import Supervisor, notice_data
from sensor_fixtures import Q_OVER_TABLE

#: Third differences of set-points computed in doubles: within 0.1 % of the limit (the
#: profiles run at it, and rounding of 1e-16 rad is 1e-6 rad/s^3 after dividing by dt^3).
MARGIN = 1.001
IN_BLEND = "(inside the blend of two points)"
#: Where the stop is aimed: this long before the next point's expected tag (s). The blend
#: into a point ends at its tag; the overlap of these moves is about 0.1 to 0.2 s.
AIMS_S = (0.05, 0.09, 0.03, 0.12, 0.07, 0.02, 0.15, 0.04)


def model_linear_jerk_limit() -> float:
    """max_linear_jerk of the model file (m/s^3)."""
    return model_values("max_linear_jerk")[0]


@contextmanager
def active(tmp_path: Path, name: str) -> Iterator[tuple[Supervisor, Path]]:
    """A traced landscaped with one owner that locked and activated (m, rad) at 100 %
    acceleration; the trace file once it has exited cleanly."""
    with traced(tmp_path, name) as (sup, trace_path):
        sup.lock()
        sup.activate()
        sup.set_acceleration(100)
        yield sup, trace_path


def joint_jerk_ratio(trace: Trace) -> np.ndarray:
    """Per joint: the largest |third difference| over the model's jerk limit."""
    assert trace.dropped == 0
    return np.max(np.abs(derivatives(trace).jerk), axis=0) / model_jerk_limits()


def tip_jerk(trace: Trace) -> np.ndarray:
    """The flange position's jerk (m/s^3) from FK of every set-point: for a tool tip moving on
    a line with its orientation held, the same as the tip's."""
    p = np.array([fk(q)[:3, 3] for q in trace.q_rad])
    return np.linalg.norm(np.diff(p, 3, axis=0), axis=1) / trace.period_s**3


# ------------------------------------------------------------------ a stop while blending

def joint_zigzag() -> list[list[float]]:
    """Six joint points from Q_OVER_TABLE: joint 1 turning on the same way, joint 3 to and fro,
    so every segment is alike and blends into the next."""
    q = list(Q_OVER_TABLE)
    pts = []
    for k in range(6):
        q = [q[0] + 0.15, q[1], q[2] + (0.12 if k % 2 == 0 else -0.12), *q[3:]]
        pts.append(list(q))
    return pts


def stop_in_a_blend(sup: Supervisor, name: str, aim_s: float) -> str:
    """Run path `name`; from the period of its tags J1 -> J2, stop `aim_s` before J3's tag is
    due; resume once paused and run it to the end. stopMotion's answer (where it paused)."""
    list(sup.notices(timeout_s=0))
    rv = sup.path_move(name, number_of_cycles=1)
    tags: dict[str, float] = {}
    answer = ""
    for n in sup.notices(timeout_s=60):
        if n.ref_seq != rv.seq:
            continue
        if n.event_id == "tag":
            tags[notice_data(n)["tag"]] = time.monotonic()
            if set(tags) >= {"J1", "J2"} and not answer:
                due = tags["J2"] + (tags["J2"] - tags["J1"])
                time.sleep(max(0.0, due - aim_s - time.monotonic()))
                answer = sup.stop_motion().ret_msg
                sup.resume_motion()
        if n.final:
            assert n.event_id == "pathMoveComplete", n
            break
    assert answer, f"no stop: tags {sorted(tags)}"
    return answer


def test_a_stop_while_blending_keeps_every_joints_jerk_limit(tmp_path: Path) -> None:
    pts = joint_zigzag()
    answers = []
    with active(tmp_path, "blend") as (sup, trace_path):
        sup.wait_complete(sup.move_absolute("start", Q_OVER_TABLE, speed_pct=50), timeout_s=20)
        sup.path_load("zig", [{"joints": p, "tag_name": f"J{k}", "speed_pct": 100.0, "accel_pct": 100.0,
                               "transition_speed_pct": 100.0} for k, p in enumerate(pts)])
        for aim in AIMS_S:
            answers.append(stop_in_a_blend(sup, "zig", aim))
            sup.wait_complete(sup.move_absolute("start", Q_OVER_TABLE, speed_pct=50), timeout_s=20)
            if sum(IN_BLEND in a for a in answers) >= 2:
                break
    ratio = joint_jerk_ratio(read_trace(trace_path))
    inside = sum(IN_BLEND in a for a in answers)
    print(f"\n  {len(answers)} stops, {inside} inside a blend; max |joint jerk| / limit: "
          + " ".join(f"{r:.4f}" for r in ratio))
    assert inside >= 1, f"no stop came inside a blend: {answers}"
    assert all(a.startswith("paused on the planned path (") for a in answers), answers
    assert np.all(ratio <= MARGIN), f"joint jerk beyond {MARGIN} x its limit: {ratio}"
    assert np.max(ratio) > 0.5, ratio  # the path runs near its limits: the check is not vacuous


# ------------------------------------------------------------------ moveReact

OVER = [0.5, -0.1, 0.35, math.pi, 0.0, 0.0]  # tool pointing down, 0.25 m above the table top


def test_move_react_brakes_and_stops_within_the_cartesian_jerk_limit(tmp_path: Path) -> None:
    with active(tmp_path, "react") as (sup, trace_path):
        sup.wait_complete(sup.move_absolute("over_table", Q_OVER_TABLE), timeout_s=20)
        sup.wait_complete(sup.move_absolute("over", OVER, frame=pb.BASE_CARTESIAN_FRAME), timeout_s=20)
        # stopMotion during the travel of a move that meets nothing, then the rest of it
        rv = sup.move_react("force_sensor", [0.0, 0.0, 0.1], motion_speed_pct=15.0, thresholds=[0.0, 0.0, 5.0])
        time.sleep(0.4)
        answer = sup.stop_motion().ret_msg
        sup.resume_motion()
        d = notice_data(sup.wait_complete(rv, timeout_s=20))
        assert d["reason"] == "max_distance"
        assert float(d["travelled"]) == pytest.approx(0.1, abs=1e-9)
        # the brake after the threshold, at 0.15 m/s onto the table 0.15 m below
        rv = sup.move_react("force_sensor", [0.0, 0.0, 0.2], motion_speed_pct=15.0, thresholds=[0.0, 0.0, 5.0])
        assert notice_data(sup.wait_complete(rv, timeout_s=20))["reason"] == "threshold"
    trace = read_trace(trace_path)
    # from the arrival at OVER on: straight lines of the tip only (the moves before are not)
    p = np.array([fk(q)[:3, 3] for q in trace.q_rad])
    at_over = np.flatnonzero(np.linalg.norm(p - OVER[:3], axis=1) < 1e-7)
    assert at_over.size, "the trace never reaches OVER"
    j = tip_jerk(Trace(trace.rate_hz, trace.dropped, trace.t_s[at_over[0]:], trace.q_rad[at_over[0]:]))
    limit = model_linear_jerk_limit()
    # how far the brake ran past the crossing: the lowest set-point below where it came back to
    overshoot_mm = 1e3 * (p[-1, 2] - np.min(p[at_over[0]:, 2]))
    print(f"\n  stopMotion: {answer!r}; max tip jerk {np.max(j):.3f} m/s^3 (limit {limit:g}); "
          f"the brake from 0.15 m/s ran {overshoot_mm:.2f} mm past the crossing")
    assert answer.startswith("paused on the planned path (on the move's line)"), answer
    assert np.max(j) <= limit * MARGIN, f"tip jerk {np.max(j):.4g} m/s^3 beyond {limit} m/s^3"
    assert np.max(j) > 0.5 * limit  # the brake runs at it: the check is not vacuous
