"""Cartesian motion slows down where the joints must (docs/protocol.md "Speed and
acceleration", docs/architecture.md "Path speed under joint limits"), checked from outside:
landscaped records every cycle's commanded joints (`--setpoint-trace`), and each joint's
velocity and acceleration are the first and second differences of that record over the
control period (each a mean of the true value, so never above its peak).

- From the README's `ready` pose, a 15 cm line at 90 % speed (which the joints could not
  follow at that speed all along) runs, slower than requested by what its answer says, with
  every joint within its limits; the same line at 10 % runs too, and the 90 % one is faster;
  toppra (TOPP-RA, time-optimal under the same joint velocity and acceleration limits and
  the same Cartesian ones, without a jerk limit) on the recorded joint path is the lower
  bound of its duration.
- A square with the tool level (pitch 1.57) from `ready` is refused (docs/host-tool.md's
  square, with the tool pointing down, runs: tests/integration/test_docs_examples.py):
  joint 4 reaches its limit, where only a jump to another arm configuration would go on,
  which no speed avoids; the answer says what to do, whole (never cut mid-word: describe
  publishes the answer text's limit).
- A stop during a slowed line pauses on the line and resumes on it, every joint within
  its limits throughout; a path with a slowed segment says so in its answer and in a
  slowedDown notice."""
from __future__ import annotations

import re
import time
from pathlib import Path

import numpy as np
import pytest
from setpoint_trace import Trace, derivatives, read_trace, traced
from test_motion import _finals, fk
from test_setpoint_trace import moving_stretches

from landscape import errors
from landscape._generated import landscape_pb2 as pb
from landscape.supervisor import Supervisor, notice_data

READY = [0.0, -0.3, 0.6, 0.0, 0.9, 0.0]  # README: `landscape move-absolute ready JOINT_FRAME ...`
#: Finite differences of set-points computed in doubles: within 0.1 % of a limit.
MARGIN = 1.001
#: "(0.564 s instead of 0.5 s)" in an answer or a notice.
DURATIONS = re.compile(r"\(([0-9.e+-]+) s instead of ([0-9.e+-]+) s\)")
#: A square with the tool level: its second line would turn joint 4 past its limit.
SQUARE = [[0.45, 0.00, 0.50, 0, 1.57, 0], [0.45, 0.10, 0.50, 0, 1.57, 0], [0.35, 0.10, 0.50, 0, 1.57, 0]]
#: A line from a pose near a wrist singularity that joint 4 must swing through fast (q5 from
#: 0.15 rad down to about 0.01 and back): slowed to a few percent in the middle.
NEAR_WRIST = [0.0, 0.3, 0.3, 0.5, 0.15, 0.0]
NEAR_WRIST_MOVE = [0.0, 0.11, -0.1, 0.0, 0.0, 0.0]


def limits(sup: Supervisor) -> tuple[np.ndarray, np.ndarray]:
    """The device's joint velocity and acceleration limits (describe)."""
    assert sup.description is not None
    joints = sup.description.res.joints
    return (np.array([j.max_velocity_rad_s for j in joints]), np.array([j.max_accel_rad_s2 for j in joints]))


def ratios(trace: Trace, first: int, last: int, qd_max: np.ndarray, qdd_max: np.ndarray) -> tuple[float, float]:
    """The largest joint velocity and acceleration over their limits between two samples."""
    part = Trace(trace.rate_hz, trace.dropped, trace.t_s[first:last + 2], trace.q_rad[first:last + 2])
    d = derivatives(part)
    return float(np.max(np.abs(d.velocity) / qd_max)), float(np.max(np.abs(d.acceleration) / qdd_max))


def toppra_duration(q: np.ndarray, tip: np.ndarray, qd_max: np.ndarray, qdd_max: np.ndarray, v_lin: float,
                    a_lin: float) -> float:
    """TOPP-RA's time-optimal duration along the joint path q (rows: set-points) under the joints'
    velocity and acceleration limits and the tool tip's linear ones (tip: its positions), with
    the path parameter the tip's arc length over the whole."""
    try:
        import toppra as ta
    except ImportError:
        pytest.fail("toppra, this test's oracle, is missing from the venv: run bash .ci/setup (the dev extra)")
    import toppra.algorithm as algo
    import toppra.constraint as tc
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(tip, axis=0), axis=1))])
    keep = np.concatenate([[True], np.diff(arc) > 1e-9])  # one point per place: the spline needs them increasing
    s = arc[keep] / arc[keep][-1]
    way = np.hstack([q[keep], arc[keep, None]])
    vlim = np.concatenate([qd_max, [v_lin]])
    alim = np.concatenate([qdd_max, [a_lin]])
    inst = algo.TOPPRA([tc.JointVelocityConstraint(np.vstack([-vlim, vlim]).T),
                        tc.JointAccelerationConstraint(np.vstack([-alim, alim]).T)],
                       ta.SplineInterpolator(s, way), gridpoints=np.linspace(0, 1, 1001),
                       parametrizer="ParametrizeConstAccel")
    traj = inst.compute_trajectory()
    assert traj is not None, "toppra found no parameterisation"
    return float(traj.duration)


def test_a_line_the_joints_must_slow_runs_slower_within_every_joint_limit(tmp_path: Path) -> None:
    answers = {}
    with traced(tmp_path, "line") as (sup, trace_path):
        qd_max, qdd_max = limits(sup)
        assert sup.description is not None
        v_max = sup.description.res.max_linear_speed_m_s
        a_max = sup.description.res.max_linear_accel_m_s2
        sup.lock()
        sup.activate()
        sup.set_acceleration(100)
        for pct in (90, 10):
            sup.wait_complete(sup.move_absolute("ready", READY), timeout_s=30)
            sup.set_speed(pct, attribute=pb.PERCENT_SPEED)
            rv = sup.move_relative("line", [0.15, 0, 0, 0, 0, 0], frame=pb.BASE_CARTESIAN_FRAME)
            answers[pct] = rv.ret_msg
            sup.wait_complete(rv, timeout_s=30)
    trace = read_trace(trace_path)
    assert trace.dropped == 0
    moves = moving_stretches(trace)
    fast, slow = moves[1], moves[3]  # ready, the 90 % line, ready, the 10 % line
    took = {90: (fast[1] - fast[0]) * trace.period_s, 10: (slow[1] - slow[0]) * trace.period_s}
    print(f"\n  90 %: {answers[90]!r}, took {took[90]:.3f} s\n  10 %: {answers[10]!r}, took {took[10]:.3f} s")

    # the 90 % line says it runs slower, and how long it takes; it does
    m = DURATIONS.search(answers[90])
    assert m, answers[90]
    planned, requested = float(m[1]), float(m[2])
    assert "slower" not in answers[10] and DURATIONS.search(answers[10]) is None, answers[10]
    assert planned > requested * 1.01, answers[90]
    assert took[90] == pytest.approx(planned, abs=2.5e-3)
    assert took[90] < took[10]  # the bar's percent-speed probe: faster at 90 %

    # every joint within its limits, on both lines
    for first, last in (fast, slow):
        qd, qdd = ratios(trace, first, last, qd_max, qdd_max)
        print(f"  samples {first}..{last}: joint speed <= {qd:.4f}, acceleration <= {qdd:.4f} of the limits")
        assert qd <= MARGIN and qdd <= MARGIN, (qd, qdd)

    # toppra, acceleration-limited on the recorded joint path, is a lower bound of its duration
    q = trace.q_rad[fast[0]:fast[1] + 1]
    tip = np.array([fk(list(x))[:3, 3] for x in q])
    bound = toppra_duration(q, tip, qd_max, qdd_max, 0.9 * v_max, a_max)
    print(f"  toppra: {bound:.3f} s; ours / toppra {took[90] / bound:.3f}")
    assert bound <= took[90] <= 1.3 * bound


def test_a_level_square_from_ready_is_refused_with_what_to_do_instead(tmp_path: Path) -> None:
    with traced(tmp_path, "square") as (sup, _):
        assert sup.description is not None
        max_answer = sup.description.res.max_answer_bytes
        assert max_answer == 335 and sup.description.res.max_notice_datum_bytes == 95
        sup.lock()
        sup.activate()
        sup.wait_complete(sup.move_absolute("ready", READY), timeout_s=30)
        sup.path_load("square", [{"pose": p, "speed_pct": 40.0} for p in SQUARE], frame=pb.BASE_CARTESIAN_FRAME,
                      motion_type=pb.STRAIGHT_MOTION)
        for speed in (40.0, 2.0):  # no speed helps
            sup.set_speed(speed, attribute=pb.PERCENT_SPEED)
            with pytest.raises(errors.ParamOutOfRangeError) as exc:
                sup.path_move("square", number_of_cycles=1)
            msg = str(exc.value)
            print(f"\n  {msg}")
            assert "pathMove refused, nothing moved: point 1: joint 4 reaches its limit 3.229 rad at " in msg
            assert "a jump no speed allows: use a joint move, or start with joint 4 turned the other way" in msg
        assert sup.get_motion_control_state().result["state"] == "RESTING"


def rpy(T: np.ndarray) -> list[float]:
    R = T[:3, :3]
    pitch = float(np.arctan2(-R[2, 0], np.hypot(R[0, 0], R[1, 0])))
    return [float(np.arctan2(R[2, 1], R[2, 2])), pitch, float(np.arctan2(R[1, 0], R[0, 0]))]


def test_a_stop_during_a_slowed_line_pauses_and_resumes_on_it(tmp_path: Path) -> None:
    with traced(tmp_path, "stop") as (sup, trace_path):
        qd_max, qdd_max = limits(sup)
        sup.lock()
        sup.activate()
        sup.set_acceleration(100)
        sup.wait_complete(sup.move_absolute("near", NEAR_WRIST), timeout_s=30)
        start = fk(NEAR_WRIST)[:3, 3]
        rv = sup.move_relative("swing", NEAR_WRIST_MOVE, frame=pb.BASE_CARTESIAN_FRAME, speed_pct=50)
        m = DURATIONS.search(rv.ret_msg)
        assert m and "running at" in rv.ret_msg and "joint 4 at its" in rv.ret_msg, rv.ret_msg
        time.sleep(0.45 * float(m[1]))  # into the slow middle
        answer = sup.stop_motion().ret_msg
        assert answer.startswith("paused on the planned path"), answer
        assert sup.get_motion_control_state().result["state"] == "PAUSED"
        time.sleep(0.2)
        sup.resume_motion()
        sup.wait_complete(rv, timeout_s=60)
    trace = read_trace(trace_path)
    moves = moving_stretches(trace)
    assert len(moves) >= 3, moves  # to the start; the line up to the stop; the rest after the resume
    goal = start + np.array(NEAR_WRIST_MOVE[:3])
    line = trace.q_rad[moves[1][0]:]
    tips = np.array([fk(list(q))[:3, 3] for q in line])
    u = (goal - start) / np.linalg.norm(goal - start)
    off = np.linalg.norm((tips - start) - np.outer((tips - start) @ u, u), axis=1)
    assert np.max(off) < 1e-6, f"the tip left the line by {np.max(off):.3g} m"
    assert np.linalg.norm(tips[-1] - goal) < 1e-6
    paused_at = (tips[moves[1][1] - moves[1][0]] - start) @ u / np.linalg.norm(goal - start)
    assert 0.1 < paused_at < 0.9, paused_at
    for first, last in moves[1:]:
        qd, qdd = ratios(trace, first, last, qd_max, qdd_max)
        assert qd <= MARGIN and qdd <= MARGIN, (first, last, qd, qdd)
    qd, _ = ratios(trace, moves[1][0], moves[-1][1], qd_max, qdd_max)
    assert qd > 0.9  # joint 4 runs at its velocity limit in the middle: the check is not vacuous


def test_a_path_says_which_segment_runs_slower(tmp_path: Path) -> None:
    with traced(tmp_path, "path") as (sup, _):
        sup.lock()
        sup.activate()
        sup.wait_complete(sup.move_absolute("near", NEAR_WRIST), timeout_s=30)
        start = fk(NEAR_WRIST)
        r = rpy(start)
        middle = [*(start[:3, 3] + [0.02, 0.0, 0.0]), *r]
        far = [*(start[:3, 3] + np.array([0.02, 0.0, 0.0]) + NEAR_WRIST_MOVE[:3]), *r]
        sup.path_load("swing", [{"pose": middle, "tag_name": "m"}, {"pose": far, "tag_name": "f"}],
                      frame=pb.BASE_CARTESIAN_FRAME, motion_type=pb.STRAIGHT_MOTION)
        list(sup.notices(timeout_s=0.1))
        rv = sup.path_move("swing")
        assert "1 of 2 segments run slower where the joints need it (slowedDown notices)" in rv.ret_msg, rv.ret_msg
        got = _finals(sup, rv.seq, 60)
    events = [n.event_id for n in got]
    assert events == ["tag", "slowedDown", "tag", "pathMoveComplete"], events
    d = notice_data(got[1])
    assert d["path"] == "swing" and d["point"] == "1" and d["joint"] == "4"
    assert d["limit"] in ("velocity", "acceleration")
    assert 0 < float(d["speed_pct"]) < 100 and 0 <= float(d["from_pct"]) < float(d["to_pct"]) <= 100
    assert float(d["duration_s"]) > float(d["requested_s"])
