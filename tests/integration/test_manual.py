"""manualControl: jogging from the sim world's manual device (the control
socket's `jog` datagrams) moves the arm within the jog speed limit; motion
commands are refused while it is on."""
from __future__ import annotations

import math
import time

import pytest

from landscape import errors
from sensor_fixtures import MAX_LINEAR_SPEED, Rig, rig  # noqa: F401 (fixture)


def _track(rig: Rig, seconds: float) -> list[tuple[float, list[float]]]:
    out = []
    t0 = time.monotonic()
    while time.monotonic() - t0 < seconds:
        out.append((time.monotonic(), rig.sup.get_robot_position().result["world_pose"][:3]))
    return out


def _window_speeds(track: list[tuple[float, list[float]]], window_s: float) -> list[float]:
    """Speeds over windows of at least window_s (the host's timestamps jitter)."""
    speeds = []
    j = 0
    for i in range(len(track)):
        while j < len(track) and track[j][0] - track[i][0] < window_s:
            j += 1
        if j == len(track):
            break
        speeds.append(math.dist(track[i][1], track[j][1]) / (track[j][0] - track[i][0]))
    return speeds


@pytest.mark.parametrize(("kind", "fraction"), [("teachpendant", 0.10), ("spaceball", 0.25)])
def test_jog_moves_the_arm_within_the_speed_limit(rig: Rig, kind: str, fraction: float) -> None:
    sup = rig.sup
    assert sup.manual_control(kind).ok
    assert sup.get_motion_control_state().result["motion_control_state"] == f"manual_{kind}"
    p0 = sup.get_robot_position().result["world_pose"]
    rig.send("jog 1 0 0 0 0 0")
    track = _track(rig, 1.0)
    rig.send("jog-stop")
    time.sleep(0.5)
    p1 = sup.get_robot_position().result["world_pose"]
    limit = fraction * MAX_LINEAR_SPEED
    speeds = _window_speeds(track, 0.25)
    moved = math.dist(p0[:3], p1[:3])
    print(f"\n{kind}: moved {1000 * moved:.1f} mm in about 1 s, highest speed over 0.25 s windows "
          f"{max(speeds):.4f} m/s (limit {limit:g} m/s)")
    assert max(speeds) <= 1.05 * limit
    assert moved >= 0.7 * limit  # it did move, at about the jog speed
    # a pure translation keeps the orientation (angles compared modulo 2 pi: roll sits at +-pi)
    assert all(abs(math.remainder(a - b, 2 * math.pi)) < 1e-3 for a, b in zip(p1[3:], p0[3:], strict=False))
    still_q = sup.get_robot_position().result["joints"]
    time.sleep(0.2)
    assert sup.get_robot_position().result["joints"] == pytest.approx(still_q, abs=1e-6)  # released: at rest
    assert sup.manual_control("off").ok
    assert sup.get_motion_control_state().result["motion_control_state"] == "robot_at_rest"


def test_motion_commands_are_refused_while_jogging(rig: Rig) -> None:
    sup = rig.sup
    sup.manual_control("teachpendant")
    with pytest.raises(errors.BusyError):
        sup.move_relative("x", [0.1, 0, 0, 0, 0, 0])
    with pytest.raises(errors.BusyError) as ei:
        sup.move_react("force_sensor", [0.0, 0.0, 0.05], thresholds=[0.0, 0.0, 5.0])
    assert "manualControl" in str(ei.value)
    with pytest.raises(errors.BusyError) as ei:
        sup.get_tool("gripper")
    assert "manualControl" in str(ei.value)
    sup.manual_control("off")
    rv = sup.move_relative("x", [0.05, 0, 0, 0, 0, 0])
    sup.wait_complete(rv, timeout_s=20)


def test_manual_control_set_while_locked_jogs_once_active(rig: Rig) -> None:
    sup = rig.sup
    sup.deactivate()
    assert sup.manual_control("spaceball").ok
    p0 = sup.get_robot_position().result["world_pose"]
    rig.send("jog 0 0 1 0 0 0")
    time.sleep(0.3)
    assert sup.get_robot_position().result["world_pose"] == pytest.approx(p0, abs=1e-4)  # drives off
    sup.activate()
    time.sleep(0.5)
    rig.send("jog-stop")
    time.sleep(0.3)
    assert sup.get_motion_control_state().result["motion_control_state"] == "manual_spaceball"
    p1 = sup.get_robot_position().result["world_pose"]
    assert math.dist(p0[:3], p1[:3]) > 0.05
    sup.manual_control("off")


def test_unknown_manual_type(rig: Rig) -> None:
    with pytest.raises(errors.ParamError) as ei:
        rig.sup.manual_control("joystick")
    assert "teachpendant, spaceball or off" in str(ei.value)


def test_manual_control_ends_with_the_owners_control(rig: Rig) -> None:
    """release ends jogging: the next owner must switch it on itself."""
    sup = rig.sup
    sup.manual_control("teachpendant")
    assert sup.get_motion_control_state().result["motion_control_state"] == "manual_teachpendant"
    sup.deactivate()
    sup.release()
    assert sup.get_motion_control_state().result["motion_control_state"] == "robot_at_rest"
    sup.lock()
    sup.activate()
    p0 = sup.get_robot_position().result["world_pose"]
    rig.send("jog 0 0 1 0 0 0")
    time.sleep(0.4)
    rig.send("jog-stop")
    assert sup.get_robot_position().result["world_pose"] == pytest.approx(p0, abs=1e-4)  # nothing jogged
    rv = sup.move_relative("x", [0.02, 0, 0, 0, 0, 0])  # and motion commands are accepted again
    sup.wait_complete(rv, timeout_s=20)
