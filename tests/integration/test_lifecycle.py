"""Every started motion ends with exactly one final notice naming why, and the reported state
is the arm's real state (docs/state-machine.md "Motion lifecycle"). Each test is one case of
that rule, against the running landscaped with the simulated arm; what the arm really does
comes from the device's telemetry (lifecycle_rig)."""
from __future__ import annotations

import contextlib
import math
import signal
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import can
import pytest
from lifecycle_rig import (
    DRIVES_OFF,
    DRIVES_ON,
    FAR,
    HOME,
    REST_STEP_RAD,
    ArmWatch,
    final_of,
    send_emergency,
    state,
)

from conftest import Controller, open_slcan, start_controller
from landscape import errors
from landscape._generated import landscape_pb2 as pb
from landscape.supervisor import RetVal, Supervisor, notice_data

OTHER = 0xF2


@dataclass
class Rig:
    controller: Controller
    bus: can.BusABC
    sup: Supervisor     # the owner, active at HOME
    other: Supervisor   # a second supervisor, connected, not owner
    watch: ArmWatch


@pytest.fixture
def rig(controller: Controller, bus: can.BusABC, notifier: can.Notifier) -> Iterator[Rig]:
    with Supervisor(bus, notifier=notifier, client_name="owner") as sup, \
            Supervisor(bus, notifier=notifier, client_name="other", source_address=OTHER) as other:
        watch = ArmWatch(sup)
        sup.lock()
        sup.activate()
        sup.wait_complete(sup.move_absolute("home", HOME, speed_pct=50), timeout_s=20)
        list(sup.notices(timeout_s=0))
        yield Rig(controller, bus, sup, other, watch)


def _move_far(r: Rig, speed_pct: float = 50) -> RetVal:
    rv = r.sup.move_absolute("far", FAR, speed_pct=speed_pct)
    assert rv.started, rv
    time.sleep(0.4)
    assert r.watch.moving_after(time.monotonic()) > 10 * REST_STEP_RAD, "the arm should be moving"
    return rv


def _load_path(sup: Supervisor) -> None:
    pts = []
    for k in range(3):
        q = list(HOME)
        q[0] += 0.4 * (k + 1)
        q[2] -= 0.1 * (k + 1)
        pts.append({"joints": q, "tag_name": f"T{k}", "tag_index": k})
    sup.path_load("p", pts)


def _assert_final(n: pb.Notice | None, event_id: str, reason: str) -> dict[str, str]:
    assert n is not None, f"no final notice (expected {event_id} reason={reason})"
    data = notice_data(n)
    assert (n.event_id, data.get("reason")) == (event_id, reason), n
    assert n.kind == (pb.EVENT if event_id.endswith("Complete") else pb.ALARM), n
    return data


def _assert_no_second_final(sup: Supervisor, seq: int, epoch: int) -> None:
    assert final_of(sup, seq, epoch, 0.5) is None, "a second final notice for the same request"


def _deactivate_answers_at_rest(r: Rig) -> float:
    """deactivate; it answers only once the arm is at rest with the drives off."""
    t0 = time.monotonic()
    d = r.sup.deactivate()
    t1 = time.monotonic()
    assert d.ok, d
    # at the moment of the answer: the joints no longer change, the drives are off
    assert r.watch.moving_after(t1) <= REST_STEP_RAD, "deactivate answered while the arm still moved"
    assert r.watch.status_after(t1) == DRIVES_OFF
    return t1 - t0


def test_deactivate_during_a_move_stops_along_the_path_then_answers(rig: Rig) -> None:
    rv = _move_far(rig)
    took = _deactivate_answers_at_rest(rig)
    assert took > 0.05, f"deactivate answered after {took * 1000:.0f} ms: too soon for a moving arm to stop"
    _assert_final(final_of(rig.sup, rv.seq, rv.epoch, 2), "moveAbsoluteAborted", "deactivate")
    st = state(rig.sup)
    assert (st["state"], st["control_mode"], st["motion_control_state"], st["fault"]) == \
        ("LOCKED", "power_off", "robot_stopped_on_command", "")
    _assert_no_second_final(rig.sup, rv.seq, rv.epoch)
    # usable again
    rig.sup.activate()
    rig.sup.wait_complete(rig.sup.move_absolute("home", HOME, speed_pct=50), timeout_s=20)


def test_deactivate_of_a_paused_move_ends_it(rig: Rig) -> None:
    rv = _move_far(rig)
    assert rig.sup.stop_motion().ok
    st = state(rig.sup)
    assert (st["state"], st["motion_control_state"]) == ("PAUSED", "robot_paused")
    assert rig.watch.moving_after(time.monotonic()) <= REST_STEP_RAD
    _deactivate_answers_at_rest(rig)
    _assert_final(final_of(rig.sup, rv.seq, rv.epoch, 2), "moveAbsoluteAborted", "deactivate")
    st = state(rig.sup)
    assert (st["state"], st["control_mode"], st["motion_control_state"]) == \
        ("LOCKED", "power_off", "robot_stopped_on_command")


def test_deactivate_during_a_path_ends_it_and_releases_the_path(rig: Rig) -> None:
    _load_path(rig.sup)
    rv = rig.sup.path_move("p")
    assert rv.started
    time.sleep(0.5)
    _deactivate_answers_at_rest(rig)
    _assert_final(final_of(rig.sup, rv.seq, rv.epoch, 2), "pathMoveAborted", "deactivate")
    assert state(rig.sup)["state"] == "LOCKED"
    # nothing left behind: the path is free again
    assert rig.sup.path_clear_path("p").ok


def test_emergency_frame_fails_the_move_after_stopping_it(rig: Rig) -> None:
    rv = _move_far(rig)
    t0 = time.monotonic()
    send_emergency(rig.bus)
    final = final_of(rig.sup, rv.seq, rv.epoch, 3)
    t_final = time.monotonic()
    data = _assert_final(final, "moveAbsoluteFailed", "emergency")
    assert "emergency" in data["fault"]
    # the notice comes once the arm is at rest with the drives off
    assert rig.watch.moving_after(t_final) <= REST_STEP_RAD
    assert rig.watch.status_after(t_final) != DRIVES_ON
    st = state(rig.sup)
    assert (st["state"], st["control_mode"], st["motion_control_state"]) == \
        ("LOCKED", "controller_error", "robot_stopped_on_error")
    assert "emergency" in str(st["fault"])
    print(f"\nemergency: final notice after {(t_final - t0) * 1000:.0f} ms")
    _assert_no_second_final(rig.sup, rv.seq, rv.epoch)
    # activate acknowledges the fault; the device moves again
    rig.sup.activate()
    rig.sup.wait_complete(rig.sup.move_absolute("home", HOME, speed_pct=50), timeout_s=20)


def test_following_error_fails_the_move(rig: Rig) -> None:
    """A fault raised inside the loop (a following error: the simulated table stops the
    tool) ends the move with its own final alarm, not only the general `fault`."""
    down = [math.pi, 0.0, 0.0]
    rig.sup.wait_complete(rig.sup.move_absolute("over", [0.45, -0.1, 0.20, *down],
                                                frame=pb.BASE_CARTESIAN_FRAME), timeout_s=20)
    list(rig.sup.notices(timeout_s=0))
    # straight down through the table top (z = 0.10 m)
    rv = rig.sup.move_absolute("through", [0.45, -0.1, 0.02, *down], frame=pb.BASE_CARTESIAN_FRAME)
    assert rv.started, rv
    final = final_of(rig.sup, rv.seq, rv.epoch, 15)
    data = _assert_final(final, "moveAbsoluteFailed", "fault")
    assert "following error" in data["fault"], data
    st = state(rig.sup)
    assert (st["state"], st["control_mode"], st["motion_control_state"]) == \
        ("LOCKED", "controller_error", "robot_stopped_on_error")


def test_owner_lost_during_a_move_reports_the_arm_not_the_motion(rig: Rig) -> None:
    rv = _move_far(rig, speed_pct=10)  # still moving when the heartbeat time-out (1 s) runs out
    list(rig.other.notices(timeout_s=0))
    rig.sup._stop_heartbeat()  # the owner goes silent
    lost = next((n for n in rig.other.notices(timeout_s=4) if n.event_id == "ownerLost"), None)
    t_lost = time.monotonic()
    assert lost is not None, "no ownerLost alarm"
    # the alarm comes once the arm stopped and the drives are off
    assert rig.watch.moving_after(t_lost) <= REST_STEP_RAD
    st = state(rig.other)
    assert (st["state"], st["control_mode"], st["motion_control_state"]) == \
        ("UNLOCKED", "power_off", "robot_stopped_on_error")
    # the lost owner still hears its move's one final notice
    _assert_final(final_of(rig.sup, rv.seq, rv.epoch, 2), "moveAbsoluteAborted", "ownerLost")


def test_disconnect_during_a_path_leaves_nothing_behind(rig: Rig) -> None:
    _load_path(rig.sup)
    old = rig.sup.path_move("p")
    assert old.started
    time.sleep(0.5)
    list(rig.other.notices(timeout_s=0))
    assert rig.sup.disconnect().ok
    lost = next((n for n in rig.other.notices(timeout_s=4) if n.event_id == "ownerLost"), None)
    assert lost is not None and notice_data(lost)["reason"] == "disconnect"
    st = state(rig.other)
    assert (st["state"], st["control_mode"], st["motion_control_state"]) == \
        ("UNLOCKED", "power_off", "robot_stopped_on_command")
    _assert_final(final_of(rig.sup, old.seq, old.epoch, 2), "pathMoveAborted", "disconnect")

    # the next session: the path is free, and a request that reuses the old seq is
    # never ended by the old notice
    rig.sup.connect()
    rig.sup.lock()
    rig.sup.activate()
    assert rig.sup.path_clear_path("p").ok
    with pytest.raises(errors.WrongStateError):
        rig.sup.abort_motion()
    while rig.sup._seq + 1 < old.seq:
        rig.sup.get_motion_control_state()
    new = rig.sup.move_absolute("home", HOME, speed_pct=50)
    assert new.seq == old.seq and new.epoch != old.epoch, (old, new)
    done = rig.sup.wait_complete(new, timeout_s=20)
    assert done.event_id == "moveAbsoluteComplete" and done.session_epoch == new.epoch


@pytest.mark.sim_world
def test_path_load_checks_aux_io(rig: Rig) -> None:
    pts = [{"joints": HOME, "aux_commands": ["dio 0 0x1 0"]}]  # bit 0 of the simulated unit is an input
    with pytest.raises(errors.ParamError, match="not outputs"):
        rig.sup.path_load("bad", pts)
    pts = [{"joints": HOME, "aux_commands": ["dio 3 0x10000 0"]}]
    with pytest.raises(errors.ParamError, match="does not exist"):
        rig.sup.path_load("bad", pts)
    pts = [{"joints": HOME, "aux_commands": ["wait 0 0x10000 1"]}]
    with pytest.raises(errors.ParamError, match="not inputs"):
        rig.sup.path_load("bad", pts)
    # an output bit is fine, and the path runs through it
    pts = [{"joints": HOME, "aux_commands": ["dio 0 0x10000 0"]}]
    rig.sup.path_load("good", pts)
    done = rig.sup.wait_complete(rig.sup.path_move("good"), timeout_s=20)
    assert done.event_id == "pathMoveComplete"
    assert state(rig.sup)["state"] == "RESTING"


def test_sigterm_during_a_move_stops_it_then_notifies_then_exits(tmp_path: Path) -> None:
    c = start_controller(tmp_path / "ls0")
    bus = open_slcan(c.pty)
    sup = Supervisor(bus, client_name="owner")
    try:
        sup.open()
        watch = ArmWatch(sup)
        sup.lock()
        sup.activate()
        rv = sup.move_absolute("far", FAR, speed_pct=50)
        assert rv.started, rv
        time.sleep(0.4)
        assert watch.moving_after(time.monotonic()) > 10 * REST_STEP_RAD
        t0 = time.monotonic()
        c.proc.send_signal(signal.SIGTERM)
        final = final_of(sup, rv.seq, rv.epoch, 5)
        t_final = time.monotonic()
        _assert_final(final, "moveAbsoluteAborted", "shutdown")
        assert c.proc.wait(timeout=5) == 0
        # at rest when the notice went out: the joints broadcast from then until the exit are still
        after = watch.sets_between(t_final - 0.005, time.monotonic())
        assert len(after) >= 2 and watch.max_step(after) <= REST_STEP_RAD, after
        print(f"\nshutdown: final notice {(t_final - t0) * 1000:.0f} ms after SIGTERM")
    finally:
        sup._running = False  # the device is gone: no disconnect on close
        with contextlib.suppress(Exception):
            sup.close()
        with contextlib.suppress(Exception):
            bus.shutdown()
        c.stop()
