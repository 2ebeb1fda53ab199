"""Settings, units, queries, sensors, digital I/O and signalDigitalIO through
the host library against the running landscaped (sim HAL), and the seed 2.2
disconnect handler when the owner's process is killed."""
from __future__ import annotations

import math
import os
import re
import signal
import socket
import subprocess
import sys
import textwrap
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

import can
import pytest

from conftest import ROOT, Controller, start_controller, wait_for_path
from landscape import errors
from landscape._generated import landscape_pb2 as pb
from landscape.registry import lookup
from landscape.supervisor import Supervisor, notice_data

# ls_robot_model_default (firmware/model/ls_robot_model.c)
QD_MAX = [2.5, 2.5, 3.0, 4.0, 4.0, 6.0]
QDD_MAX = [8.0, 8.0, 10.0, 15.0, 15.0, 20.0]
MAX_LINEAR_SPEED = 1.0
MAX_ANGULAR_SPEED = 3.0
MAX_LINEAR_ACCEL = 4.0
MAX_ANGULAR_ACCEL = 12.0
HEARTBEAT_TIMEOUT_S = 1.0  # landscaped's default
OWNER, OBSERVER, VICTIM = 0xF1, 0xF2, 0xF3


@dataclass
class Sim:
    controller: Controller
    dio_socket: Path
    second_pty: str

    def inputs(self, on: int, off: int = 0) -> None:
        """Drive the simulated inputs through the sim world's control socket."""
        with socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM) as s:
            s.sendto(f"in {on:x} {off:x}".encode(), str(self.dio_socket))



@pytest.fixture
def sim(tmp_path: Path) -> Iterator[Sim]:
    sock = tmp_path / "dio.sock"
    second = tmp_path / "ls1"
    c = start_controller(tmp_path / "ls0", "--link", f"slcan:pty:{second}", "--dio-socket", str(sock))
    try:
        wait_for_path(sock, c.proc)
        wait_for_path(second, c.proc)
        yield Sim(c, sock, str(second))
    finally:
        c.stop()


@pytest.fixture
def bus(sim: Sim) -> Iterator[can.BusABC]:
    b = can.Bus(interface="slcan", channel=sim.controller.pty, bitrate=1000000, sleep_after_open=0)
    try:
        yield b
    finally:
        b.shutdown()


@pytest.fixture
def two(bus: can.BusABC) -> Iterator[tuple[Supervisor, Supervisor]]:
    """The owner (locked) and an observer on one bus."""
    notifier = can.Notifier(bus, [])
    try:
        with Supervisor(bus, notifier=notifier, source_address=OWNER, client_name="owner") as a, \
             Supervisor(bus, notifier=notifier, source_address=OBSERVER, client_name="observer") as b:
            a.lock()
            yield a, b
    finally:
        notifier.stop()


def _raw(sup: Supervisor, command: str, **fields: object) -> pb.Response:
    """Send a request the host library would refuse to build (an enum value
    outside the schema), through the library's own transaction path."""
    cmd = lookup(command)
    req = pb.Request()
    sub = getattr(req, cmd.field)
    sub.SetInParent()
    for k, v in fields.items():
        setattr(sub, k, v)
    with sup._req_lock:
        sup._seq += 1
        req.seq = sup._seq
        return sup._transact(cmd, req, 2.0)


def _wait_notice(sup: Supervisor, match: Callable[[pb.Notice], bool], timeout_s: float) -> pb.Notice | None:
    for n in sup.notices(timeout_s=timeout_s):
        if match(n):
            return n
    return None


# ---------------------------------------------------------------- settings and units

def test_speed_and_acceleration_settings(two: tuple[Supervisor, Supervisor]) -> None:
    owner, observer = two
    owner.set_speed(40.0, attribute="PERCENT_SPEED")
    owner.set_speed(0.5, attribute="LINEAR_SPEED")
    owner.set_speed(1.5, attribute="ANGULAR_SPEED")
    v = observer.get_velocities().result
    assert v["percent_velocity"] == 40.0
    assert v["world_linear_velocity"] == pytest.approx(0.5, abs=1e-12)
    assert v["world_angular_velocity"] == pytest.approx(1.5, abs=1e-12)
    assert v["joint_velocities"] == pytest.approx([0.4 * q for q in QD_MAX], abs=1e-12)

    owner.set_acceleration(25.0, attribute="PERCENT_ACCEL")
    owner.set_acceleration(2.0, attribute="LINEAR_ACCEL")
    owner.set_acceleration(6.0, attribute="ANGULAR_ACCEL")
    a = observer.get_accelerations().result
    assert a["percent_accel"] == 25.0
    assert a["world_linear_accel"] == pytest.approx(2.0, abs=1e-12)
    assert a["world_angular_accel"] == pytest.approx(6.0, abs=1e-12)
    assert a["joint_accels"] == pytest.approx([0.25 * q for q in QDD_MAX], abs=1e-12)

    mv = observer.get_max_velocities().result
    assert mv["max_world_linear_velocity"] == MAX_LINEAR_SPEED
    assert mv["max_world_angular_velocity"] == MAX_ANGULAR_SPEED
    assert mv["max_joint_velocities"] == QD_MAX
    ma = observer.get_max_accelerations().result
    assert ma["max_world_linear_accel"] == MAX_LINEAR_ACCEL
    assert ma["max_world_angular_accel"] == MAX_ANGULAR_ACCEL
    assert ma["max_joint_accels"] == QDD_MAX

    # refusals name the value and the range in the current units, and change nothing
    with pytest.raises(errors.ParamOutOfRangeError) as ei:
        owner.set_speed(150.0, attribute="PERCENT_SPEED")
    assert "PERCENT_SPEED 150 %: allowed [0.1, 100]" in str(ei.value)
    owner.set_units(linear="MILLIMETERS", angular="DEGREES")
    with pytest.raises(errors.ParamOutOfRangeError) as ei:
        owner.set_speed(2000.0, attribute="LINEAR_SPEED")
    assert "LINEAR_SPEED 2000 millimeters/s: allowed [1, 1000]" in str(ei.value)
    with pytest.raises(errors.ParamOutOfRangeError) as ei:
        owner.set_acceleration(-1.0, attribute="ANGULAR_ACCEL")
    assert "ANGULAR_ACCEL -1 degrees/s^2: allowed [0.687549, 687.549]" in str(ei.value)
    with pytest.raises(errors.ParamError):
        owner.set_speed(math.nan, attribute="PERCENT_SPEED")
    rsp = _raw(owner, "setSpeed", speed=10.0, attribute=7)
    assert rsp.ret_code == pb.CMD_PARAM_ERR and "attribute 7 is not a SpeedType" in rsp.ret_msg
    v = owner.get_velocities().result  # in the owner's session's units
    assert v["percent_velocity"] == 40.0
    assert v["world_linear_velocity"] == pytest.approx(500.0, abs=1e-9)
    assert v["world_angular_velocity"] == pytest.approx(math.degrees(1.5), abs=1e-9)
    assert v["joint_velocities"] == pytest.approx([math.degrees(0.4 * q) for q in QD_MAX], abs=1e-9)
    v = observer.get_velocities().result  # the observer's session is still in SI
    assert v["world_linear_velocity"] == pytest.approx(0.5, abs=1e-12)
    assert v["world_angular_velocity"] == pytest.approx(1.5, abs=1e-12)

    # only the owner sets; queries work for everyone
    with pytest.raises(errors.NotOwnerError):
        observer.set_speed(10.0, attribute="PERCENT_SPEED")


def test_units_round_trip_of_the_tool_offset(two: tuple[Supervisor, Supervisor]) -> None:
    """Units belong to the session that set them (docs/conformance.md, setUnits)."""
    owner, observer = two
    assert owner.connect_result is not None and owner.connect_result.units == ("METERS", "RADIANS")
    assert observer.get_units().result == {"linear_units": "meters", "angular_units": "radians"}
    owner.set_units(linear="MILLIMETERS", angular="DEGREES")
    assert owner.get_units().result == {"linear_units": "millimeters", "angular_units": "degrees"}
    assert observer.get_units().result == {"linear_units": "meters", "angular_units": "radians"}
    offset = [10.0, -20.0, 150.0, 90.0, 0.0, -30.0]
    owner.set_tool_offset(offset)
    assert owner.get_tool_offsets().result["offset"] == pytest.approx(offset, abs=1e-9)
    si = [0.01, -0.02, 0.15, math.pi / 2, 0.0, -math.pi / 6]
    assert observer.get_tool_offsets().result["offset"] == pytest.approx(si, abs=1e-12)
    owner.set_units(linear="INCHES", angular="RADIANS")
    got = owner.get_tool_offsets().result["offset"]
    assert got == pytest.approx([10 / 25.4, -20 / 25.4, 150 / 25.4, math.pi / 2, 0.0, -math.pi / 6], abs=1e-9)
    owner.set_units(linear="FEET", angular="DEGREES")
    assert owner.get_tool_offsets().result["offset"][2] == pytest.approx(0.15 / 0.3048, abs=1e-12)

    with pytest.raises(errors.ParamError) as ei:
        owner.set_tool_offset([1.0, 2.0, 3.0, 4.0, 5.0])
    assert "takes 6 values" in str(ei.value)
    with pytest.raises(errors.ParamError):
        owner.set_world_cartesian_frame([0.0, 0.0, math.inf, 0.0, 0.0, 0.0])
    rsp = _raw(owner, "setUnits", linear=9, angular=0)
    assert rsp.ret_code == pb.CMD_PARAM_ERR and "linear unit 9" in rsp.ret_msg
    assert owner.get_units().result == {"linear_units": "feet", "angular_units": "degrees"}

    owner.activate()  # set commands are valid at rest too
    owner.set_units(linear="METERS", angular="RADIANS")
    assert owner.get_tool_offsets().result["offset"] == pytest.approx(si, abs=1e-12)
    owner.deactivate()

    # a new session starts in SI whatever the last one set, and the connect answer says so
    owner.set_units(linear="MILLIMETERS", angular="DEGREES")
    res = owner.connect()
    assert res.units == ("METERS", "RADIANS")
    assert owner.get_units().result == {"linear_units": "meters", "angular_units": "radians"}


def _norm(v: list[float]) -> float:
    return math.sqrt(sum(x * x for x in v))


def _rot(rpy: list[float]) -> list[float]:
    """R = Rz(yaw) Ry(pitch) Rx(roll), row-major: orientations compared as
    matrices, since at pitch +-90 deg (the arm's rest pose) roll and yaw alone
    are not defined."""
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr,
            sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr,
            -sp, cp * sr, cp * cr]


def test_robot_position_follows_world_frame_and_tool(two: tuple[Supervisor, Supervisor]) -> None:
    owner, observer = two
    p0 = observer.get_robot_position().result
    assert len(p0["joints"]) == 6 and len(p0["world_pose"]) == 6
    owner.set_world_cartesian_frame([0.5, 0.0, 0.0, 0.0, 0.0, 0.0])
    p1 = observer.get_robot_position().result
    assert p1["joints"] == pytest.approx(p0["joints"], abs=1e-6)  # the arm rests
    assert p1["world_pose"][:3] == pytest.approx([p0["world_pose"][0] - 0.5, *p0["world_pose"][1:3]], abs=1e-6)
    assert _rot(p1["world_pose"][3:]) == pytest.approx(_rot(p0["world_pose"][3:]), abs=1e-5)
    owner.set_world_cartesian_frame([0.0, 0.0, 0.0, 0.0, 0.0, math.pi / 2])  # base +y is world -x
    p1 = observer.get_robot_position().result
    assert p1["world_pose"][:3] == pytest.approx([p0["world_pose"][1], -p0["world_pose"][0], p0["world_pose"][2]],
                                                 abs=1e-6)
    owner.set_world_cartesian_frame([0.0] * 6)
    owner.set_tool_offset([0.0, 0.0, 0.1, 0.0, 0.0, 0.0])
    p2 = observer.get_robot_position().result
    z_axis = _rot(p0["world_pose"][3:])[2::3]  # the flange z axis in the base frame
    want = [a + 0.1 * z for a, z in zip(p0["world_pose"][:3], z_axis, strict=True)]
    assert p2["world_pose"][:3] == pytest.approx(want, abs=1e-5)
    owner.set_units(linear="MILLIMETERS", angular="DEGREES")
    p3 = owner.get_robot_position().result
    assert p3["joints"] == pytest.approx([math.degrees(q) for q in p2["joints"]], abs=1e-4)
    assert p3["world_pose"][:3] == pytest.approx([1000 * x for x in p2["world_pose"][:3]], abs=1e-3)
    assert _rot([math.radians(a) for a in p3["world_pose"][3:]]) == pytest.approx(_rot(p2["world_pose"][3:]),
                                                                               abs=1e-5)


def test_sensor_readings(two: tuple[Supervisor, Supervisor]) -> None:
    owner, observer = two
    ft = observer.get_sensor_reading("force_sensor").result["current_data"]
    assert len(ft) == 6
    laser_m = observer.get_sensor_reading("laser_standoff_sensor").result["current_data"]
    assert len(laser_m) == 1 and 0.0 <= laser_m[0] <= 0.5
    owner.set_units(linear="MILLIMETERS", angular="DEGREES")
    laser_mm = owner.get_sensor_reading("laser_standoff_sensor").result["current_data"]
    assert laser_mm[0] == pytest.approx(1000 * laser_m[0], abs=1e-3)
    ft_after = observer.get_sensor_reading("force_sensor").result["current_data"]
    assert ft_after == pytest.approx(ft, abs=0.5)  # N and Nm: not scaled by setUnits
    with pytest.raises(errors.UnsupportedError) as ei:
        observer.get_sensor_reading("sonar")
    assert "force_sensor, laser_standoff_sensor" in str(ei.value)


def _comms_wakeups(sup: Supervisor) -> int:
    text = sup.send_command("rtstats").result["result"]
    m = re.search(r"^comms_wakeups=([0-9]+)$", text, re.M)
    assert m is not None, f"sendCommand rtstats: no comms_wakeups line in {text!r}"
    return int(m[1])


def test_the_comms_thread_sleeps_until_a_frame_an_event_or_a_deadline(two: tuple[Supervisor, Supervisor]) -> None:
    """Idle, the comms thread wakes for the frames it gets and sends (telemetry at 50 Hz, its
    heartbeat at 5 Hz, two supervisors' heartbeats) and the rtstats requests: well under
    100 turns/s (66/s measured). A fixed 1 ms poll makes 780-890/s (docs/architecture.md "Threads")."""
    _, observer = two
    n0, t0 = _comms_wakeups(observer), time.monotonic()
    time.sleep(2.0)
    n1, t1 = _comms_wakeups(observer), time.monotonic()
    rate = (n1 - n0) / (t1 - t0)
    assert 40 <= rate <= 250, f"{rate:.0f} comms turns/s while idle ({n1 - n0} in {t1 - t0:.2f} s)"


# ---------------------------------------------------------------- digital I/O

def test_dio_outputs_set_and_read_back(two: tuple[Supervisor, Supervisor]) -> None:
    owner, observer = two
    owner.set_digital_io("digital", 0, bits_on=0x00050000, description="lamp and valve")
    assert observer.get_digital_io("digital", 0).result["bits_on"] & 0xFFFF0000 == 0x00050000
    owner.set_digital_io("digital", 0, bits_on=0x00020000, bits_off=0x00010000)
    assert observer.get_digital_io("digital", 0).result["bits_on"] & 0xFFFF0000 == 0x00060000
    with pytest.raises(errors.ParamOutOfRangeError) as ei:
        owner.set_digital_io("digital", 0, bits_on=0x00000001)
    assert "bits 0x1 of unit 0 are not outputs" in str(ei.value)
    with pytest.raises(errors.ParamOutOfRangeError):
        owner.set_digital_io("digital", 1, bits_on=0x00010000)
    with pytest.raises(errors.ParamError) as ei:
        owner.set_digital_io("analog", 0, bits_on=0x00010000)
    assert "'digital'" in str(ei.value)
    with pytest.raises(errors.ParamError):
        owner.set_digital_io("digital", 0, bits_on=0x00010000, bits_off=0x00010000)
    with pytest.raises(errors.NotOwnerError):
        observer.set_digital_io("digital", 0, bits_on=0x00010000)
    assert observer.get_digital_io("digital", 0).result["bits_on"] & 0xFFFF0000 == 0x00060000


def test_simulated_inputs_read_back(sim: Sim, two: tuple[Supervisor, Supervisor]) -> None:
    _, observer = two
    sim.inputs(0x0009)
    deadline = time.monotonic() + 2
    while observer.get_digital_io("digital", 0).result["bits_on"] & 0xFFFF != 0x0009:
        assert time.monotonic() < deadline, "the sim inputs did not reach getDigitalIO within 2 s"
        time.sleep(0.02)
    sim.inputs(0, 0x0001)
    deadline = time.monotonic() + 2
    while observer.get_digital_io("digital", 0).result["bits_on"] & 0xFFFF != 0x0008:
        assert time.monotonic() < deadline
        time.sleep(0.02)


@pytest.mark.parametrize("callback,kind", [
    ("CB_EVENT", pb.EVENT), ("CB_ALARM", pb.ALARM), ("CB_EVENT_RSVP", pb.EVENT_RSVP),
    ("CB_ALARM_RSVP", pb.ALARM_RSVP)])
def test_signal_callbacks_on_a_simulated_input(sim: Sim, two: tuple[Supervisor, Supervisor], callback: str,
                                               kind: int) -> None:
    _, observer = two  # any connected supervisor may watch
    answered: list[int] = []
    observer.on_rsvp("dioSignal", lambda n: answered.append(n.rsvp_id) or pb.CMD_EXEC_OK)
    sim.inputs(0, 0xFFFF)
    time.sleep(0.05)
    watch_rv = observer.signal_digital_io("digital", 0, 0x0006, callback_type=callback)
    watch = watch_rv.result["watch_id"]
    assert watch > 0
    sim.inputs(0x0002)
    assert _wait_notice(observer, lambda n: n.event_id == "dioSignal", 0.3) is None  # one of two bits
    sim.inputs(0x0004)
    n = _wait_notice(observer, lambda n: n.event_id == "dioSignal", 2.0)
    assert n is not None, f"no dioSignal for {callback}"
    assert n.kind == kind
    d = notice_data(n)
    assert d["unit"] == "0" and d["bits"] == "0x6" and d["watch"] == str(watch)
    assert int(d["levels"], 16) & 0x6 == 0x6
    if kind in (pb.EVENT_RSVP, pb.ALARM_RSVP):
        assert n.rsvp_default == "cancel" and n.rsvp_timeout_ms == 2000
        assert n.ref_seq == watch_rv.seq and n.session_epoch == watch_rv.epoch  # the request that armed it
        deadline = time.monotonic() + 2
        while not answered:
            assert time.monotonic() < deadline, "the RSVP handler did not run"
            time.sleep(0.01)
        assert answered == [n.rsvp_id]
        ack = observer.wait_rsvp_ack(n.rsvp_id, timeout_s=2.0)
        assert (ack.ret_code, ack.action) == (pb.CMD_EXEC_OK, "rearm")  # accepted: the watch is armed again
        # answered: no default action follows
        assert _wait_notice(observer, lambda n: n.event_id == "dioSignalRsvpTimeout", 2.5) is None
        # re-armed: it fires again on the bits' next rising
        sim.inputs(0, 0x0006)
        time.sleep(0.05)
        sim.inputs(0x0006)
        again = _wait_notice(observer, lambda n: n.event_id == "dioSignal", 2.0)
        assert again is not None and again.kind == kind and again.ref_seq == watch_rv.seq
        return
    # once only
    sim.inputs(0, 0x0006)
    time.sleep(0.05)
    sim.inputs(0x0006)
    assert _wait_notice(observer, lambda n: n.event_id == "dioSignal", 0.5) is None


def test_unanswered_rsvp_takes_its_default_after_the_timeout(sim: Sim, two: tuple[Supervisor, Supervisor]) -> None:
    owner, _ = two
    sim.inputs(0, 0xFFFF)
    time.sleep(0.05)
    watch = owner.signal_digital_io("digital", 0, 0x0010, callback_type="CB_ALARM_RSVP").result["watch_id"]
    sim.inputs(0x0010)
    n = _wait_notice(owner, lambda n: n.event_id == "dioSignal", 2.0)
    assert n is not None and n.kind == pb.ALARM_RSVP  # no handler: nobody answers
    t0 = time.monotonic()
    done = _wait_notice(owner, lambda n: n.event_id == "dioSignalRsvpTimeout", 4.0)
    elapsed = time.monotonic() - t0
    assert done is not None
    assert notice_data(done) == {"watch": str(watch), "action": "cancel"}
    assert 1.5 < elapsed < 3.0  # the 2000 ms the notice announced
    # the watch ended: its slot is free again, and the bits firing again say nothing
    sim.inputs(0, 0x0010)
    time.sleep(0.05)
    sim.inputs(0x0010)
    assert _wait_notice(owner, lambda n: n.event_id == "dioSignal", 0.5) is None


def test_signal_polling_time_out_and_cycle(sim: Sim, two: tuple[Supervisor, Supervisor]) -> None:
    owner, _ = two
    sim.inputs(0, 0xFFFF)
    time.sleep(0.05)
    watch = owner.signal_digital_io("digital", 0, 0x0100, polling_timeout_ms=300,
                                    callback_type="CB_ALARM").result["watch_id"]
    t0 = time.monotonic()
    n = _wait_notice(owner, lambda n: n.event_id.startswith("dioSignal"), 2.0)
    assert n is not None and n.event_id == "dioSignalTimeout" and n.kind == pb.ALARM
    assert notice_data(n)["watch"] == str(watch)
    assert 0.2 < time.monotonic() - t0 < 1.0
    # sampled every 200 ms: fires at a sample after the input rose
    watch = owner.signal_digital_io("digital", 0, 0x0100, polling_cycle_time_ms=200).result["watch_id"]
    sim.inputs(0x0100)
    n = _wait_notice(owner, lambda n: n.event_id == "dioSignal", 2.0)
    assert n is not None and n.kind == pb.EVENT and notice_data(n)["watch"] == str(watch)
    with pytest.raises(errors.ParamError):
        owner.signal_digital_io("digital", 0, 0)
    with pytest.raises(errors.ParamOutOfRangeError):
        owner.signal_digital_io("digital", 0, 1, polling_timeout_ms=-1)


def test_watch_table_is_bounded(sim: Sim, two: tuple[Supervisor, Supervisor]) -> None:
    owner, observer = two
    sim.inputs(0, 0xFFFF)
    time.sleep(0.05)
    ids = [owner.signal_digital_io("digital", 0, 0x8000).result["watch_id"] for _ in range(8)]
    assert len(set(ids)) == 8
    with pytest.raises(errors.NoResourcesError):
        observer.signal_digital_io("digital", 0, 0x8000)
    sim.inputs(0x8000)
    fired = set()
    for n in owner.notices(timeout_s=2.0):
        if n.event_id == "dioSignal":
            fired.add(int(notice_data(n)["watch"]))
            if len(fired) == 8:
                break
    assert fired == set(ids)
    assert observer.signal_digital_io("digital", 0, 0x8000).result["watch_id"] > 0


# ---------------------------------------------------------------- seed 2.2: the owner's process dies

VICTIM_SCRIPT = textwrap.dedent("""
    import sys, time
    import can
    from landscape.supervisor import Supervisor
    bus = can.Bus(interface="slcan", channel=sys.argv[1], bitrate=1000000, sleep_after_open=0)
    sup = Supervisor(bus, source_address=int(sys.argv[2]), client_name="victim")
    sup.__enter__()
    sup.lock()
    sup.activate()
    print("ready", flush=True)
    while True:
        time.sleep(1)
""")


def test_killed_owner_process_is_deactivated_and_released(sim: Sim, bus: can.BusABC) -> None:
    with Supervisor(bus, source_address=OBSERVER, client_name="watcher") as watcher:
        env = dict(os.environ, PYTHONPATH=str(ROOT / "host_tools" / "src"))
        victim = subprocess.Popen([sys.executable, "-c", VICTIM_SCRIPT, sim.second_pty, str(VICTIM)],
                                  stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env)
        try:
            assert victim.stdout is not None
            line = victim.stdout.readline()
            assert line == b"ready\n", victim.stderr.read().decode() if victim.stderr else ""
            state = watcher.get_motion_control_state().result
            assert state["state"] == "RESTING" and state["control_mode"] == "power_on"
            list(watcher.notices(timeout_s=0.0))  # drop what came before
            victim.send_signal(signal.SIGKILL)
            t0 = time.monotonic()
            alarm = _wait_notice(watcher, lambda n: n.event_id == "ownerLost", HEARTBEAT_TIMEOUT_S + 2.0)
            elapsed = time.monotonic() - t0
        finally:
            victim.kill()
            victim.wait(timeout=10)
        assert alarm is not None and alarm.kind == pb.ALARM
        assert notice_data(alarm)["supervisor"] == f"0x{VICTIM:02X}"
        assert notice_data(alarm)["action"] == "stop_deactivate_release"  # the configured default
        assert elapsed < HEARTBEAT_TIMEOUT_S + 0.5  # the time-out plus a scheduling margin
        state = watcher.get_motion_control_state().result
        assert state["state"] == "UNLOCKED" and state["control_mode"] == "power_off"
        watcher.lock()  # the device is free for the next owner
