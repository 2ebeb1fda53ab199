"""manualControl: jogging from the sim world's manual device (the control
socket's `jog`, `buttons`, `unplug` and `plug` datagrams) moves the arm
within the jog speed limit, the teach pendant only while its enabling switch
is held; a lost device stops the jog with an alarm; the operator's buttons
are reported; motion commands are refused while it is on. The same on real
input devices (evdev) runs in the VM tier (tests/vm/test_guest.py)."""
from __future__ import annotations

import math
import time

import pytest

from conftest import BroadcastMotion
from landscape import errors
from landscape._generated import landscape_pb2 as pb
from landscape.supervisor import notice_data
from sensor_fixtures import MAX_LINEAR_SPEED, Rig, rig  # noqa: F401 (fixture)

# The simulated world's manual device (its control socket) stands in for the operator's.
pytestmark = pytest.mark.sim_world

ENABLE, SPEED_DOWN, FRAME = 0x1, 0x8, 0x10  # hal/hal_manual.h HAL_MANUAL_BTN_*


def _wait_notice(rig: Rig, event_id: str, timeout_s: float = 5.0, **data: str) -> pb.Notice:
    """The next notice `event_id` whose data has these key=value pairs."""
    for n in rig.sup.notices(timeout_s=timeout_s):
        if n.event_id == event_id and all(notice_data(n).get(k) == v for k, v in data.items()):
            return n
    raise AssertionError(f"no {event_id} {data} within {timeout_s} s")


def _press_enable(rig: Rig) -> None:
    """Release the enabling switch, then press it (two control cycles apart
    at least: one drain of the socket would merge them)."""
    rig.send("buttons 0")
    time.sleep(0.05)
    rig.send(f"buttons {ENABLE:x}")
    _wait_notice(rig, "manualSwitch", switch="enabled")


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
    if kind == "teachpendant":
        _press_enable(rig)
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
    broadcast = BroadcastMotion(sup)
    sup.deactivate()
    assert sup.manual_control("spaceball").ok
    p0 = sup.get_robot_position().result["world_pose"]
    rig.send("jog 0 0 1 0 0 0")
    time.sleep(0.3)
    assert sup.get_robot_position().result["world_pose"] == pytest.approx(p0, abs=1e-4)  # drives off
    sup.activate()
    time.sleep(0.3)  # deflected through the activation: it waits for the device at rest
    assert sup.get_robot_position().result["world_pose"] == pytest.approx(p0, abs=1e-4)
    rig.send("jog-stop")
    time.sleep(0.05)
    rig.send("jog 0 0 1 0 0 0")
    time.sleep(0.5)
    rig.send("jog-stop")
    time.sleep(0.3)
    assert sup.get_motion_control_state().result["motion_control_state"] == "manual_spaceball"
    assert broadcast.now() == "manual_spaceball"  # the broadcast says what the query says
    p1 = sup.get_robot_position().result["world_pose"]
    assert math.dist(p0[:3], p1[:3]) > 0.05
    sup.manual_control("off")
    assert broadcast.now() == sup.get_motion_control_state().result["motion_control_state"] == "robot_at_rest"


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


def _still_for(rig: Rig, seconds: float) -> list[float]:
    """The joints, after checking they did not change for `seconds`."""
    q0 = rig.sup.get_robot_position().result["joints"]
    time.sleep(seconds)
    q1 = rig.sup.get_robot_position().result["joints"]
    assert q1 == pytest.approx(q0, abs=1e-6)
    return list(q1)


def test_the_pendant_jogs_only_while_its_enabling_switch_is_held(rig: Rig) -> None:
    sup = rig.sup
    assert sup.manual_control("teachpendant").ok
    rig.send("jog 0 0 1 0 0 0")
    _still_for(rig, 0.3)  # deflected, switch released: nothing
    _press_enable(rig)
    time.sleep(0.3)
    p1 = sup.get_robot_position().result["world_pose"]
    rig.send("buttons 0")  # released: the jog brakes on its ramp
    _wait_notice(rig, "manualSwitch", switch="released")
    time.sleep(0.5)
    p2 = _still_for(rig, 0.3)
    assert p2 != pytest.approx(p1, abs=1e-4)  # it did move while held
    rig.send("jog-stop")
    sup.manual_control("off")


def test_a_lost_device_stops_the_jog_with_an_alarm_and_a_new_one_jogs(rig: Rig) -> None:
    sup = rig.sup
    assert sup.manual_control("spaceball").ok
    rig.send("jog 0 0 1 0 0 0")
    time.sleep(0.3)
    rig.send("unplug")
    alarm = _wait_notice(rig, "manualDeviceLost")
    assert alarm.kind == pb.ALARM
    assert notice_data(alarm) == {"device": "spaceball", "reason": "unplugged", "path": "sim"}
    time.sleep(0.5)  # the ramp down
    q_stopped = _still_for(rig, 0.3)
    rig.send("plug")
    _wait_notice(rig, "manualDeviceFound", device="spaceball", path="sim")
    rig.send("jog 0 0 -1 0 0 0")
    time.sleep(0.3)
    rig.send("jog-stop")
    assert sup.get_robot_position().result["joints"] != pytest.approx(q_stopped, abs=1e-4)
    sup.manual_control("off")


def test_the_operators_buttons_are_reported_as_events(rig: Rig) -> None:
    sup = rig.sup
    assert sup.manual_control("teachpendant").ok
    rig.send(f"buttons {SPEED_DOWN:x}")
    _wait_notice(rig, "manualOverride", device="teachpendant", percent="50")
    rig.send("buttons 0")
    time.sleep(0.05)
    rig.send(f"buttons {FRAME:x}")
    _wait_notice(rig, "manualFrame", device="teachpendant", frame="base")
    rig.send("buttons 0")
    sup.manual_control("off")
