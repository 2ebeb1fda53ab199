"""Motion as the seed specifies it (issue 18), against the running landscaped
with the simulated arm: PERCENT_SPEED and PERCENT_ACCEL scale Cartesian moves
(seed 3.2.1), the tag_struct's 24 jointvals on the wire and the refusals that
name the field and its limit, comply's valid states, and every MotionType in
a path (seed section 6). docs/protocol.md "Speed and acceleration",
docs/conformance.md."""
from __future__ import annotations

import time
from collections.abc import Iterator

import can
import pytest
from conftest import Controller
from landscape import errors
from landscape._generated import landscape_pb2 as pb
from landscape.registry import lookup
from landscape.supervisor import Supervisor
from test_motion import HOME, WATCH, JointWatch, _rpy, fk

LINE = [0.0, 0.15, 0.0, 0.0, 0.0, 0.0]  # 15 cm along base y, no turn


@pytest.fixture
def sup(controller: Controller) -> Iterator[Supervisor]:
    bus = can.Bus(interface="slcan", channel=controller.pty, bitrate=1000000, sleep_after_open=0)
    try:
        with Supervisor(bus, client_name="motion18") as s:
            WATCH[id(s)] = JointWatch(s)
            s.lock()
            s.activate()  # metres and radians
            rv = s.move_absolute("home", HOME, speed_pct=50)
            s.wait_complete(rv, timeout_s=20)
            yield s
    finally:
        bus.shutdown()


def _timed_line(sup: Supervisor, values: list[float]) -> float:
    """Seconds from the start of a Cartesian relative move to its completion (then back)."""
    t0 = time.monotonic()
    rv = sup.move_relative("line", values, frame=pb.BASE_CARTESIAN_FRAME)
    sup.wait_complete(rv, timeout_s=30)
    took = time.monotonic() - t0
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
    assert slow / fast > 3.0, f"15 cm line: {slow:.3f} s at 10 %, {fast:.3f} s at 90 %"
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
        t0 = time.monotonic()
        sup.wait_complete(sup.path_move(f"s{pct:.0f}", number_of_cycles=1), timeout_s=30)
        took[pct] = time.monotonic() - t0
    assert took[10.0] / took[90.0] > 3.0, took


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
