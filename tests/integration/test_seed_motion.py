"""Motion as the seed specifies it, against the running landscaped
with the simulated arm: PERCENT_SPEED and PERCENT_ACCEL scale Cartesian moves
(seed 3.2.1), the tag_struct's 24 jointvals on the wire and the refusals that
name the field and its limit, comply's valid states, and every MotionType in
a path (seed section 6). docs/protocol.md "Speed and acceleration",
docs/conformance.md."""
from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterator

import can
import numpy as np
import pytest
from test_motion import HOME, WATCH, JointWatch, _rpy, fk, joints, tip

from conftest import Controller
from landscape import errors
from landscape._generated import landscape_pb2 as pb
from landscape.registry import lookup
from landscape.supervisor import Supervisor, notice_data

SETPOINTS: dict[int, SetpointWatch] = {}
LINE = [0.0, 0.15, 0.0, 0.0, 0.0, 0.0]  # 15 cm along base y, no turn


@pytest.fixture
def sup(controller: Controller) -> Iterator[Supervisor]:
    bus = can.Bus(interface="slcan", channel=controller.pty, bitrate=1000000, sleep_after_open=0)
    try:
        with Supervisor(bus, client_name="motion18") as s:
            WATCH[id(s)] = JointWatch(s)
            SETPOINTS[id(s)] = SetpointWatch(s)
            s.lock()
            s.activate()  # metres and radians
            rv = s.move_absolute("home", HOME, speed_pct=50)
            s.wait_complete(rv, timeout_s=20)
            yield s
    finally:
        bus.shutdown()


class SetpointWatch:
    """The commanded joint positions of every telemetry cycle (JOINTS_CMD_12/34/56) with
    that cycle's device time stamp (TOOL_POS `tool_time_ms`, sent after them: the control
    loop's clock modulo 65.536 s), so that a test times a motion's set-point by the
    device's clock. The host's wall clock would add the request's and the completion
    notice's latency, which grows under load and sanitizers, and the measured joints
    would add the servo's lag."""

    def __init__(self, sup: Supervisor) -> None:
        self._lock = threading.Lock()
        self._cmd: dict[str, float] = {}
        self._samples: list[tuple[int, tuple[float, ...]]] = []
        sup.on_telemetry(self._on)

    def _on(self, b: object) -> None:
        name = getattr(b, "name", "")
        sg = getattr(b, "signals", {})
        with self._lock:
            if name.startswith("JOINTS_CMD_"):
                self._cmd.update(sg)
            elif name == "TOOL_POS" and len(self._cmd) == 6:
                self._samples.append((int(sg["tool_time_ms"]),
                                      tuple(float(self._cmd[f"j{i}_cmd"]) for i in range(1, 7))))
                self._cmd = {}

    def mark(self) -> int:
        with self._lock:
            return len(self._samples)

    def wait_samples(self, mark: int, count: int, timeout_s: float = 2.0) -> list[tuple[int, tuple[float, ...]]]:
        deadline = time.monotonic() + timeout_s
        while True:
            with self._lock:
                got = list(self._samples[mark:])
            if len(got) >= count:
                return got
            if time.monotonic() > deadline:
                raise AssertionError(f"{len(got)} telemetry cycles within {timeout_s} s, wanted {count}")
            time.sleep(0.01)


def _device_timed(watch: SetpointWatch, run: Callable[[], None]) -> float:
    """Device seconds the set-point moved while `run` started a motion and waited for its
    end: from the last telemetry cycle at the start joints to the first that stays at the
    end joints. At 50 cycles/s this overstates the motion by at most two periods (40 ms)."""
    m = watch.mark()
    before = watch.wait_samples(m, 2)[-1]  # at rest: a cycle sent after the previous motion ended
    m = watch.mark()
    run()
    after = watch.mark()
    samples = [before, *watch.wait_samples(m, after - m + 3)]  # and 3 after the end, at rest
    start, end = samples[0][1], samples[-1][1]
    away = [i for i, (_, p) in enumerate(samples) if p != start]
    assert away, "the tool did not move"
    i_start = away[0] - 1
    i_end = max(i for i, (_, p) in enumerate(samples) if p != end) + 1
    return ((samples[i_end][0] - samples[i_start][0]) % 65536) / 1000.0


def _timed_line(sup: Supervisor, values: list[float]) -> float:
    """Device seconds of a Cartesian relative move (then back, untimed)."""
    def line() -> None:
        sup.wait_complete(sup.move_relative("line", values, frame=pb.BASE_CARTESIAN_FRAME), timeout_s=30)
    took = _device_timed(SETPOINTS[id(sup)], line)
    back = sup.move_relative("back", [-v for v in values], frame=pb.BASE_CARTESIAN_FRAME)
    sup.wait_complete(back, timeout_s=30)
    return took


# ---------------------------------------------------------------- 1. percent speed and acceleration

def test_percent_speed_scales_cartesian_moves(sup: Supervisor) -> None:
    sup.set_acceleration(100)  # PERCENT_ACCEL: the model's maxima, so that speed dominates
    sup.set_speed(10)
    slow = _timed_line(sup, LINE)
    sup.set_speed(90)
    fast = _timed_line(sup, LINE)
    # Planned: 1.5 s cruise + ~0.1 s ramps at 10 %, 0.17 s + ~0.33 s ramps at 90 % (about 3.1);
    # without the percent applied both took the same (0.96 s each).
    assert slow / fast > 2.5, f"15 cm line: {slow:.3f} s at 10 %, {fast:.3f} s at 90 %"
    # LINEAR_SPEED after PERCENT_SPEED: the most recent call's kind wins
    sup.set_speed(0.05, attribute=pb.LINEAR_SPEED)
    linear = _timed_line(sup, LINE)
    assert linear > 0.15 / 0.05, f"15 cm at LINEAR_SPEED 0.05 m/s took {linear:.3f} s"
    sup.set_speed(90)
    assert _timed_line(sup, LINE) < linear / 3.0


def test_percent_accel_scales_cartesian_moves(sup: Supervisor) -> None:
    short = [0.0, 0.04, 0.0, 0.0, 0.0, 0.0]  # 4 cm at full speed: acceleration dominates
    sup.set_speed(100)
    sup.set_acceleration(5)
    slow = _timed_line(sup, short)
    sup.set_acceleration(100)
    fast = _timed_line(sup, short)
    assert slow / fast > 2.5, f"4 cm line: {slow:.3f} s at 5 % accel, {fast:.3f} s at 100 %"
    # LINEAR_ACCEL after PERCENT_ACCEL: the LINEAR_/ANGULAR_ values again
    sup.set_acceleration(0.2, attribute=pb.LINEAR_ACCEL)
    assert _timed_line(sup, short) > 0.8 * slow


def test_point_percents_scale_straight_path_segments(sup: Supervisor) -> None:
    start = fk(HOME)
    rpy = _rpy(start)
    a = [*(start[:3, 3] + [0.0, 0.15, 0.0]), *rpy]
    b = [*start[:3, 3], *rpy]
    took = {}
    for pct in (10.0, 90.0):
        sup.path_load(f"s{pct:.0f}", [{"pose": a, "speed_pct": pct, "accel_pct": 100.0},
                                      {"pose": b, "speed_pct": pct, "accel_pct": 100.0}],
                      frame=pb.BASE_CARTESIAN_FRAME, motion_type=pb.STRAIGHT_MOTION)
        def run(name: str = f"s{pct:.0f}") -> None:
            sup.wait_complete(sup.path_move(name, number_of_cycles=1), timeout_s=30)
        took[pct] = _device_timed(SETPOINTS[id(sup)], run)
    assert took[10.0] / took[90.0] > 2.5, took  # planned about 3.1, as for the single line


# ---------------------------------------------------------------- 2. tag_struct's jointvals

def test_24_jointvals_decode_and_the_arm_names_its_joint_count(sup: Supervisor) -> None:
    vals = [0.1] * 24
    with pytest.raises(errors.ParamError) as ei:
        sup.path_load("j24", [{"joints": vals}])
    msg = str(ei.value)
    assert "did not decode" not in msg
    assert "`joints` has 24 values, this arm has 6 joints" in msg


def test_25_jointvals_are_refused_naming_the_field_and_its_limit(sup: Supervisor) -> None:
    # The library refuses it before sending (the device's published limit) ...
    with pytest.raises(errors.ArgumentError, match="joints"):
        sup.path_load("j25", [{"joints": [0.1] * 25}])
    # ... and the firmware names the field and the limit when it gets it anyway.
    desc, sup.description = sup.description, None
    try:
        rv = sup.path_load("j25", [{"joints": list(HOME)}, {"joints": [0.1] * 25}], check=False)
    finally:
        sup.description = desc
    assert rv.ret_code == pb.CMD_PARAM_ERR
    assert "path_load.tags[1].joints has 25 values, at most 24" in rv.ret_msg, rv.ret_msg
    assert sup.get_motion_control_state().ok  # and it serves on


# ---------------------------------------------------------------- 3. comply's states

def test_comply_is_valid_at_rest_only(sup: Supervisor) -> None:
    assert [pb.State.Name(s) for s in lookup("comply").states] == ["RESTING"]
    rv = sup.move_absolute("far", [1.0, 0.3, 0.3, 0.0, 0.9, 0.0], speed_pct=10)
    try:
        assert sup.get_motion_control_state().result["state"] == "MOVING"
        with pytest.raises(errors.WrongStateError):
            sup.comply("force_sensor", [0.0, 0.0, 10.0], max_travel=[0.05, 0, 0, 0, 0, 0.05])
    finally:
        sup.wait_complete(rv, timeout_s=30)


# ---------------------------------------------------------------- 4. every MotionType in a path


def _tagged_run(sup: Supervisor, name: str) -> tuple[list[str], list[list[float]]]:
    """Run path `name` once: its tags in order and the joints broadcast meanwhile."""
    w = WATCH[id(sup)]
    m = w.mark()
    list(sup.notices(timeout_s=0.1))
    rv = sup.path_move(name, number_of_cycles=1)
    got = []
    for n in sup.notices(timeout_s=60):
        if n.ref_seq == rv.seq:
            got.append(n)
            if n.final:
                break
    assert [n.event_id for n in got if n.final] == ["pathMoveComplete"], [n.event_id for n in got]
    time.sleep(0.1)
    return [notice_data(n)["tag"] for n in got if n.event_id == "tag"], w.since(m)


def test_slew_path_runs_each_joint_on_its_own(sup: Supervisor) -> None:
    far = list(HOME)
    far[0] += 1.2  # joint 1 travels far, joint 3 a little: a slew does not wait for joint 1
    far[2] -= 0.1
    back = list(HOME)
    sup.path_load("slew", [{"joints": far, "tag_name": "far"}, {"joints": back, "tag_name": "back"}],
                  motion_type=pb.SLEW_MOTION)
    tags, qs = _tagged_run(sup, "slew")
    assert tags == ["far", "back"]
    assert joints(sup) == pytest.approx(back, abs=2e-3)
    first = qs[: len(qs) // 2]
    # joint 3 has arrived while joint 1 is not yet half-way (a synchronised move has them in step)
    assert any(abs(q[2] - far[2]) < 2e-3 and (q[0] - HOME[0]) / 1.2 < 0.5 for q in first)
    # the same points as JOINT_MOTION: synchronised, so never so
    sup.path_load("sync", [{"joints": far}, {"joints": back}])
    _, qs = _tagged_run(sup, "sync")
    assert not any(abs(q[2] - far[2]) < 2e-3 and (q[0] - HOME[0]) / 1.2 < 0.5 for q in qs[: len(qs) // 2])


def test_circular_path_runs_arcs_through_its_points(sup: Supervisor) -> None:
    start = fk(HOME)
    rpy = _rpy(start)
    p0 = start[:3, 3]
    c = p0 + [0.0, 0.1, 0.0]  # centre of the circle the points lie on (radius 0.1 m, horizontal)
    pts = [p0 + [0.1, 0.1, 0.0], p0 + [0.0, 0.2, 0.0], p0 + [-0.1, 0.1, 0.0], p0]  # via, goal, via, goal
    sup.path_load("circ", [{"pose": [*p, *rpy], "tag_name": f"C{k}"} for k, p in enumerate(pts)],
                  frame=pb.BASE_CARTESIAN_FRAME, motion_type=pb.CIRCULAR_MOTION)
    tags, qs = _tagged_run(sup, "circ")
    assert tags == ["C0", "C1", "C2", "C3"]
    assert len(qs) > 20
    for q in qs:
        p = fk(q)[:3, 3]
        assert abs(np.linalg.norm((p - c)[:2]) - 0.1) < 1.5e-3
        assert abs(p[2] - c[2]) < 1.5e-3
    assert np.linalg.norm(tip(sup) - p0) < 1e-3  # ends at its last point
    # an odd count leaves a via point without its goal: refused, naming it
    sup.path_load("odd", [{"pose": [*pts[0], *rpy]}, {"pose": [*pts[1], *rpy]}, {"pose": [*pts[2], *rpy]}],
                  frame=pb.BASE_CARTESIAN_FRAME, motion_type=pb.CIRCULAR_MOTION)
    with pytest.raises(errors.ParamError, match=r"point 2 is a via point with no circular goal after it"):
        sup.path_move("odd", number_of_cycles=1)
