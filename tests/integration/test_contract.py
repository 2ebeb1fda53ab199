"""The session's contract (docs/protocol.md "Envelope and sessions", "RSVP") through the host
library against the running landscaped: RSVP
answers decide and are acknowledged, units belong to the session, the disconnect
handler's action is configured and narrowed per session, liveness follows the
heartbeat period stated at connect (docs/protocol.md "RSVP", "Disconnect handler",
"Liveness"; docs/conformance.md)."""
from __future__ import annotations

import math
import time
from collections.abc import Iterator
from pathlib import Path

import can
import pytest

from conftest import Controller, open_slcan, start_controller
from landscape import errors
from landscape._generated import landscape_pb2 as pb
from landscape.notices import undeclared
from landscape.supervisor import Supervisor, notice_data

HOME = [0.0, 0.3, 0.3, 0.0, 0.9, 0.0]
OWNER, OTHER = 0xF1, 0xF2


def _events(sup: Supervisor) -> str:
    return str(sup.send_command("events").result["result"])


def _status_line(sup: Supervisor, addr: int) -> str:
    text = str(sup.send_command("status").result["result"])
    return next(line for line in text.splitlines() if line.startswith(f"session 0x{addr:02X} "))


#: The names these tests' paths give their own `rsvp NAME` (no schema declares them).
PATH_EVENTS = {"goOn"}


@pytest.fixture
def owner(bus: can.BusABC) -> Iterator[Supervisor]:
    seen: list[pb.Notice] = []
    with Supervisor(bus, source_address=OWNER, client_name="contract") as s:
        s.on_notice(seen.append)
        s.lock()
        s.activate()
        s.wait_complete(s.move_absolute("home", HOME, speed_pct=50), timeout_s=20)
        yield s
    # every notice the firmware sent carries an event id and data keys of enum ls.EventId
    assert seen and any(n.final for n in seen)
    problems = [undeclared(n.event_id, n.data, path_event=n.event_id in PATH_EVENTS) for n in seen]
    assert [p for p in problems if p is not None] == []


def test_a_declined_path_rsvp_drops_the_path_and_is_acknowledged(owner: Supervisor) -> None:
    q = list(HOME)
    q[0] += 0.2
    owner.path_load("asked", [{"joints": q, "aux_commands": ["rsvp goOn 5"]}, {"joints": HOME}])
    list(owner.notices(timeout_s=0.1))
    rv = owner.path_move("asked")
    ask = next((n for n in owner.notices(timeout_s=20) if n.event_id == "goOn"), None)
    assert ask is not None and ask.kind == pb.EVENT_RSVP
    # the RSVP names the request that armed it, like every other notice about it
    assert (ask.ref_seq, ask.session_epoch) == (rv.seq, rv.epoch)
    assert ask.rsvp_default == "continue"
    ack = owner.decline_rsvp(ask, ["operator=stop here"])
    assert (ack.rsvp_id, ack.ret_code, ack.action) == (ask.rsvp_id, pb.CMD_EXEC_OK, "abort")
    assert (ack.ref_seq, ack.session_epoch) == (rv.seq, rv.epoch)
    with pytest.raises(errors.AlarmError) as ei:
        owner.wait_complete(rv, timeout_s=10)
    d = notice_data(ei.value.notice)
    assert ei.value.notice.event_id == "pathMoveAborted" and d["reason"] == "rsvpDeclined"
    assert d["answer"] == str(pb.CMD_ERR)
    st = owner.get_motion_control_state().result
    assert st["state"] == "RESTING" and st["motion_control_state"] == "robot_stopped_on_command"
    # the reply's data reached the event log
    assert f"rsvp {ask.rsvp_id} goOn (seq {rv.seq}) from 0xF1: declined -1, action abort, " \
           f"data [operator=stop here]" in _events(owner)
    # a second answer and an unknown id are refused, naming why
    with pytest.raises(errors.ParamError, match="already answered"):
        owner.accept_rsvp(ask)
    refused = owner.answer_rsvp(99999, check=False)
    assert refused.ret_code == pb.CMD_PARAM_ERR and "no RSVP with this id" in refused.ret_msg


def test_an_accepted_path_rsvp_goes_on(owner: Supervisor) -> None:
    q = list(HOME)
    q[0] += 0.2
    owner.path_load("accepted", [{"joints": q, "aux_commands": ["rsvp goOn 5"]}, {"joints": HOME}])
    list(owner.notices(timeout_s=0.1))
    rv = owner.path_move("accepted")
    ask = next((n for n in owner.notices(timeout_s=20) if n.event_id == "goOn"), None)
    assert ask is not None
    assert owner.accept_rsvp(ask, ["checked=yes"]).action == "continue"
    assert owner.wait_complete(rv, timeout_s=20).event_id == "pathMoveComplete"


def test_units_belong_to_the_session(bus: can.BusABC) -> None:
    notifier = can.Notifier(bus, [])
    try:
        with Supervisor(bus, notifier=notifier, source_address=OWNER, client_name="mm") as a, \
             Supervisor(bus, notifier=notifier, source_address=OTHER, client_name="si") as b:
            a.lock()
            a.set_units(linear="MILLIMETERS", angular="DEGREES")
            assert a.get_units().result == {"linear_units": "millimeters", "angular_units": "degrees"}
            assert b.get_units().result == {"linear_units": "meters", "angular_units": "radians"}
            qa = a.get_robot_position().result["joints"]
            qb = b.get_robot_position().result["joints"]
            assert qa == pytest.approx([math.degrees(v) for v in qb], abs=1e-3)
            assert "units=millimeters,degrees" in _status_line(b, OWNER)
            assert "units=meters,radians" in _status_line(b, OTHER)
        # the next session of the same supervisor starts in SI (docs/conformance.md, setUnits: `landscape demo`
        # once failed after a previous session had left degrees set)
        with Supervisor(bus, notifier=notifier, source_address=OWNER, client_name="next") as c:
            assert c.connect_result is not None and c.connect_result.units == ("METERS", "RADIANS")
            assert c.get_units().result == {"linear_units": "meters", "angular_units": "radians"}
    finally:
        notifier.stop()


def test_liveness_follows_the_stated_heartbeat_period(bus: can.BusABC) -> None:
    notifier = can.Notifier(bus, [])
    try:
        with Supervisor(bus, notifier=notifier, source_address=OWNER, heartbeat_period_ms=400) as slow, \
             Supervisor(bus, notifier=notifier, source_address=OTHER, heartbeat_period_ms=100) as fast:
            assert slow.device_info is not None and fast.device_info is not None
            assert slow.device_info.heartbeat_timeout_ms == 2000  # 5 periods, above the configured 1000
            assert fast.device_info.heartbeat_timeout_ms == 1000  # never below the configured time-out
            assert "heartbeat_timeout_ms=2000" in _status_line(fast, OWNER)
            # requests alone do not keep a session: only HEARTBEAT frames do
            slow._stop_heartbeat()
            t0 = time.monotonic()
            while time.monotonic() - t0 < 1.5:
                slow.get_units()  # still alive within its 2 s
                time.sleep(0.1)
            deadline = t0 + 4.0
            while "session 0xF1 " in str(fast.send_command("status").result["result"]):
                assert time.monotonic() < deadline, "the silent session was not dropped"
                time.sleep(0.1)
            assert time.monotonic() - t0 > 1.5
        with pytest.raises(errors.ParamOutOfRangeError, match="heartbeat_period_ms 5000: allowed 10..2000"):
            with Supervisor(bus, notifier=notifier, source_address=OWNER, heartbeat_period_ms=5000):
                pass
    finally:
        notifier.stop()


@pytest.fixture
def narrow_ctl(tmp_path: Path) -> Iterator[Controller]:
    c = start_controller(tmp_path / "ls0", "--disconnect-action", "stop_deactivate")
    try:
        yield c
    finally:
        assert c.stop() == 0


def test_the_configured_disconnect_action_and_a_narrower_session(narrow_ctl: Controller) -> None:
    bus = open_slcan(narrow_ctl.pty)
    notifier = can.Notifier(bus, [])
    try:
        with Supervisor(bus, notifier=notifier, source_address=OTHER, client_name="watcher") as watcher:
            assert "disconnect_action=stop_deactivate" in str(watcher.send_command("config").result["result"])
            # a session may not widen the configured action
            with pytest.raises(errors.ParamOutOfRangeError, match="wider than the configured stop_deactivate"):
                with Supervisor(bus, notifier=notifier, source_address=OWNER,
                                disconnect_action="DISCONNECT_STOP_DEACTIVATE_RELEASE"):
                    pass
            # narrowed to `stop`: the arm stops, the drives stay on, the lock waits for the owner
            owner = Supervisor(bus, notifier=notifier, source_address=OWNER, client_name="narrow",
                               disconnect_action="DISCONNECT_STOP")
            res = owner.open()
            assert res.disconnect_action == "DISCONNECT_STOP"
            owner.lock()
            owner.activate()
            list(watcher.notices(timeout_s=0.0))
            rv = owner.move_absolute("far", [0.8, 0.3, 0.3, 0.0, 0.9, 0.0], speed_pct=20)
            owner._stop_heartbeat()  # the owner vanishes mid-motion
            lost = next((n for n in watcher.notices(timeout_s=4.0) if n.event_id == "ownerLost"), None)
            assert lost is not None
            assert notice_data(lost)["action"] == "stop" and notice_data(lost)["reason"] == "heartbeat lost"
            st = watcher.get_motion_control_state().result
            assert st["state"] == "RESTING" and st["control_mode"] == "power_on"
            with pytest.raises(errors.NotOwnerError, match="keeps the lock"):
                watcher.set_speed(10.0, attribute="PERCENT_SPEED")
            assert "owner 0xF1 lost (heartbeat lost): action stop" in \
                str(watcher.send_command("faults").result["result"])
            with pytest.raises(errors.AlarmError) as ei:  # the motion's one final notice reached its address
                owner.wait_complete(rv, timeout_s=2.0)
            assert notice_data(ei.value.notice)["reason"] == "ownerLost"
            # the owner's address connects again: the lock is its own again, drives still on
            res = owner.connect()
            assert res.device.owner and res.device.state == pb.RESTING
            owner.set_speed(10.0, attribute="PERCENT_SPEED")
            owner.close()
    finally:
        notifier.stop()
        bus.shutdown()
