"""When drives fail (docs/deploy.md "Drives", docs/protocol.md "Drives"): landscaped as
the CiA 402 master of ls-simdrives, whose drives misbehave on command through its
control socket (docs/simulated-drives.md). One test per defect class: an EMCY during a
motion, a drive that stops answering, a frozen feedback, a fault a reset does not clear,
a drive bus gone quiet (bus-off), the drive link's device vanishing;
each asserts the final notice, the alarm, the state, that the healthy joints stopped
along the path, that nothing resumes by itself, and that activate recovers the arm."""
from __future__ import annotations

import contextlib
import socket
import time
from collections.abc import Iterator
from pathlib import Path

import can
import pytest

from conftest import BroadcastMotion, Controller, final_notice, start_controller
from landscape import errors
from landscape._generated import landscape_pb2 as pb
from landscape.supervisor import Supervisor, notice_data

START = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
TARGET = [1.0, -0.6, 0.8, 1.2, 1.0, -1.5]  # every joint moves: a stop shows on each


def _send(ctl: Path, command: str) -> float:
    """Send a misbehaviour command; its CLOCK_MONOTONIC time (the device's clock too)."""
    with socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM) as s:
        s.sendto(command.encode(), str(ctl))
    return time.monotonic()


class Joint1:
    """Joint 1's measured angle from every JOINTS_12 broadcast, with its arrival time."""

    def __init__(self, sup: Supervisor) -> None:
        self.samples: list[tuple[float, float]] = []
        sup.on_telemetry(self._on)

    def _on(self, b: object) -> None:
        if getattr(b, "name", "") == "JOINTS_12":
            self.samples.append((time.monotonic(), float(b.signals["j1"])))  # type: ignore[attr-defined]

    def stop_after(self, t0: float) -> tuple[float, float, float]:
        """(speed at t0, distance travelled after t0, time until it rests: within 2e-4 rad for 0.1 s)."""
        s = self.samples
        i0 = next(i for i, (t, _) in enumerate(s) if t >= t0)
        v0 = (s[i0][1] - s[i0 - 2][1]) / (s[i0][0] - s[i0 - 2][0])
        q_end = s[-1][1]
        rest = next(i for i in range(i0, len(s)) if all(abs(q - s[i][1]) < 2e-4 for t, q in s[i:] if t < s[i][0] + 0.1))
        return v0, abs(q_end - s[i0 - 1][1]), s[rest][0] - t0


def _detected(sup: Supervisor, t0: float, needle: str) -> float:
    """How long after t0 the device logged the fault whose text starts with `needle`."""
    for line in str(sup.send_command("faults").result["result"]).splitlines():
        at, _, text = line.partition(" ")
        if text.startswith(needle):
            return float(at) - t0
    raise AssertionError(f"no fault log entry {needle!r}")


def _report(what: str, sup: Supervisor, watch: Joint1, t0: float, needle: str) -> None:
    v0, dist, took = watch.stop_after(t0)
    print(f"\nFIGURE drive fault | {what} | detected after {_detected(sup, t0, needle) * 1e3:.0f} ms | joint 1 at "
          f"{v0:.2f} rad/s stopped in {dist:.3f} rad, {took:.2f} s")


@pytest.fixture
def rig(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[tuple[Controller, Supervisor]]:
    monkeypatch.setattr("conftest.ARM", "cia402")
    # the defaults of docs/deploy.md: a drive whose feedback misses 5 drive cycles is lost
    c = start_controller(tmp_path / "ls0", drive_keys={"stale_cycles": "5"})
    bus = can.Bus(interface="slcan", channel=c.pty, bitrate=1000000, sleep_after_open=0)
    try:
        with Supervisor(bus, client_name="faults") as sup:
            sup.lock()
            sup.activate()
            yield c, sup
    finally:
        bus.shutdown()
        code = c.stop()
        assert code == 0, c.log.read_text()[-4000:]


def _joints(sup: Supervisor) -> list[float]:
    return list(sup.get_robot_position().result["joints"])


_final = final_notice


def _moving(sup: Supervisor) -> int:
    rv = sup.move_absolute("far", TARGET, speed_pct=30)
    time.sleep(0.6)
    state = sup.get_motion_control_state().result["state"]
    if state != "MOVING":  # say why the move ended before the fault was injected
        why = [f"{n.event_id}: {n.text}" for n in sup.notices(timeout_s=0.2) if n.ref_seq == rv.seq]
        raise AssertionError(f"the move is {state} 0.6 s after it started, not MOVING: {why}")
    return rv.seq


def _during_a_move(c: Controller, sup: Supervisor, command: str) -> tuple[Joint1, float, pb.Notice, list[pb.Notice]]:
    """Start a move of every joint and send the simulator `command` while it runs: the watch
    of joint 1, the time it was sent, the move's final notice and every notice until it."""
    watch = Joint1(sup)
    list(sup.notices(timeout_s=0.1))
    seq = _moving(sup)
    assert c.drives_control is not None
    t0 = _send(c.drives_control, command)
    seen: list[pb.Notice] = []
    return watch, t0, _final(sup, seq, seen), seen


def _healthy_stopped_along_the_path(sup: Supervisor, failed: int) -> None:
    q = _joints(sup)
    fr = [(qi - s) / (t - s) for j, (qi, s, t) in enumerate(zip(q, START, TARGET, strict=True)) if j != failed]
    assert 0.0 < min(fr) and max(fr) < 1.0, fr  # stopped on the way, not at either end
    assert max(fr) - min(fr) < 0.03, fr  # on the joint-space line: a synchronised stop
    time.sleep(0.3)
    assert _joints(sup) == pytest.approx(q, abs=1e-3)  # and nothing moves by itself


def test_an_emcy_during_a_move_fails_it_naming_joint_node_and_code(rig: tuple[Controller, Supervisor]) -> None:
    c, sup = rig
    broadcast = BroadcastMotion(sup)
    watch, t0, final, seen = _during_a_move(c, sup, "emcy 0x23 0x8611")
    assert final.event_id == "moveAbsoluteFailed" and final.kind == pb.ALARM
    d = notice_data(final)
    assert d["reason"] == "fault"
    assert d["fault"] == "joint 3 (node 0x23): FAULT, EMCY 0x8611 following error", d
    st = sup.get_motion_control_state().result
    assert st["state"] == "LOCKED" and st["motion_control_state"] == "robot_stopped_on_error", st
    assert broadcast.now() == "robot_stopped_on_error"  # the broadcast says it too
    _healthy_stopped_along_the_path(sup, failed=2)
    # the EMCY itself, to every supervisor, and the drive's error code read back once the drives are off
    seen += list(sup.notices(timeout_s=2.0))
    emcy = [n for n in seen if n.event_id == "driveEmcy"]
    assert emcy and emcy[0].kind == pb.ALARM
    e = notice_data(emcy[0])
    assert (e["joint"], e["node"], e["code"], e["meaning"]) == ("3", "0x23", "0x8611", "following error"), e
    read_back = [notice_data(n) for n in seen if n.event_id == "driveErrorCode"]
    assert read_back and read_back[0]["code"] == "0x8611", seen
    # the drives' notices count on in the session's notice_seq: no gap, no 0
    counted = [n.notice_seq for n in seen]
    assert 0 not in counted and counted == list(range(counted[0], counted[0] + len(counted))), counted
    faults = str(sup.send_command("faults").result["result"])
    assert "joint 3 (node 0x23): EMCY 0x8611 following error" in faults, faults
    _report("EMCY 0x8611 (following error) of joint 3 during a move", sup, watch, t0, "joint 3 (node 0x23): FAULT")
    # recovery: activate resets the drive and the arm moves again, without a restart
    sup.activate()
    rv = sup.move_absolute("back", START, speed_pct=50)
    sup.wait_complete(rv, timeout_s=20)
    assert _joints(sup) == pytest.approx(START, abs=2e-3)


def test_a_drive_that_stops_answering_is_lost_and_stays_lost(rig: tuple[Controller, Supervisor]) -> None:
    c, sup = rig
    watch, t0, final, seen = _during_a_move(c, sup, "silence 0x24")
    took = time.monotonic() - t0
    d = notice_data(final)
    assert final.event_id == "moveAbsoluteFailed" and d["reason"] == "fault"
    assert d["fault"].startswith("joint 4 (node 0x24): "), d
    assert "heartbeat" in d["fault"] or "no feedback" in d["fault"], d
    assert took < 2.0, f"a silent drive was noticed after {took:.2f} s"
    _healthy_stopped_along_the_path(sup, failed=3)
    _report("joint 4's drive goes silent (heartbeat lost) during a move", sup, watch, t0, "joint 4 (node 0x24)")
    # it does not come back by itself: while silent, activate says which drive and why
    rv = sup.activate(check=False)
    assert rv.ret_code != pb.CMD_EXEC_OK
    assert "joint 4 (node 0x24)" in rv.ret_msg, rv.ret_msg
    # once it answers again, activate configures it anew and the arm moves
    _send(c.drives_control, "reset")
    time.sleep(0.2)
    sup.activate()
    rv = sup.move_absolute("back", START, speed_pct=50)
    sup.wait_complete(rv, timeout_s=20)


def test_a_frozen_feedback_is_a_lost_drive(rig: tuple[Controller, Supervisor]) -> None:
    c, sup = rig
    watch, t0, final, seen = _during_a_move(c, sup, "freeze-tpdo 0x25")
    d = notice_data(final)
    assert d["fault"].startswith("joint 5 (node 0x25): no feedback (TPDO1) for "), d
    _healthy_stopped_along_the_path(sup, failed=4)
    _report("joint 5's feedback (TPDO) freezes during a move", sup, watch, t0, "joint 5 (node 0x25)")


def test_a_drive_that_stays_in_fault_refuses_activate_with_what_it_says(rig: tuple[Controller, Supervisor]) -> None:
    c, sup = rig
    assert c.drives_control is not None
    _send(c.drives_control, "sticky-fault 0x22 5")
    _send(c.drives_control, "emcy 0x22 0x2310")
    time.sleep(0.3)
    st = sup.get_motion_control_state().result
    assert st["state"] == "LOCKED", st  # at rest: the drives went off at once
    rv = sup.activate(check=False)
    assert rv.ret_code == pb.CMD_ERR, rv.ret_msg
    assert rv.ret_msg.startswith("activate failed, the drives are off: joint 2 (node 0x22): "), rv.ret_msg
    assert "EMCY 0x2310 continuous over-current" in rv.ret_msg and "stays in FAULT" in rv.ret_msg, rv.ret_msg
    with pytest.raises(errors.WrongStateError):
        sup.move_absolute("no", TARGET)
    _send(c.drives_control, "reset")
    sup.activate()


def test_a_drive_bus_gone_quiet_loses_every_drive_until_activate(rig: tuple[Controller, Supervisor]) -> None:
    """Bus-off as the drives see it: nothing crosses the bus either way for 1.5 s, then
    each node reports EMCY 0x8140. Every axis is lost, the fault names a node and why,
    and nothing resumes when the bus comes back: activate does it."""
    c, sup = rig
    watch, t0, final, seen = _during_a_move(c, sup, "bus-off 1500")
    took = time.monotonic() - t0
    d = notice_data(final)
    assert final.event_id == "moveAbsoluteFailed" and final.kind == pb.ALARM and d["reason"] == "fault", d
    assert d["fault"].startswith("joint ") and " (node 0x2" in d["fault"], d
    assert "no feedback" in d["fault"] or "heartbeat" in d["fault"], d
    assert took < 1.0, f"a silent drive bus was noticed after {took:.2f} s"
    st = sup.get_motion_control_state().result
    assert st["state"] == "LOCKED" and st["motion_control_state"] == "robot_stopped_on_error", st
    _report("the drive bus carries nothing for 1.5 s (bus-off) during a move", sup, watch, t0, "joint ")
    # the bus back: each drive says it recovered from bus-off; the arm stays where it is, off
    time.sleep(max(0.0, t0 + 2.0 - time.monotonic()))
    seen += list(sup.notices(timeout_s=0.5))
    recovered = {notice_data(n)["node"] for n in seen if n.event_id == "driveEmcy"
                 and notice_data(n)["code"] == "0x8140"}
    assert recovered == {"0x21", "0x22", "0x23", "0x24", "0x25", "0x26"}, [notice_data(n) for n in seen]
    q = _joints(sup)
    time.sleep(0.3)
    assert _joints(sup) == pytest.approx(q, abs=1e-3)
    assert sup.get_motion_control_state().result["state"] == "LOCKED"
    sup.activate()
    rv = sup.move_absolute("back", START, speed_pct=50)
    sup.wait_complete(rv, timeout_s=20)
    assert _joints(sup) == pytest.approx(START, abs=2e-3)


def test_the_drive_links_device_vanishing_loses_every_drive_naming_the_link(
        rig: tuple[Controller, Supervisor]) -> None:
    """The drive link's device goes away (an SLCAN adapter unplugged: here the simulator
    holding the pty dies): the move fails naming the link, activate is refused naming it,
    and nothing moves by itself."""
    c, sup = rig
    list(sup.notices(timeout_s=0.1))
    seq = _moving(sup)
    assert c.drives is not None
    c.drives.kill()
    t0 = time.monotonic()
    final = _final(sup, seq, [])
    took = time.monotonic() - t0
    d = notice_data(final)
    assert final.event_id == "moveAbsoluteFailed" and d["reason"] == "fault", d
    assert d["fault"].startswith("the drive bus slcan:tty:") and d["fault"].endswith("every drive is lost"), d
    assert took < 1.0, f"the vanished drive link was noticed after {took:.2f} s"
    print(f"\nFIGURE drive fault | the drive link's device vanishes during a move | move failed after "
          f"{took * 1e3:.0f} ms")
    st = sup.get_motion_control_state().result
    assert st["state"] == "LOCKED" and st["motion_control_state"] == "robot_stopped_on_error", st
    rv = sup.activate(check=False)
    assert rv.ret_code != pb.CMD_EXEC_OK
    assert "the drive bus slcan:tty:" in rv.ret_msg and "every drive is lost" in rv.ret_msg, rv.ret_msg
    assert sup.get_motion_control_state().result["state"] == "LOCKED"


def test_drives_stop_by_themselves_when_landscaped_dies(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """SIGKILL: no stop, no shutdown; each drive sees the controller's heartbeat stop and
    reacts per 0x6007 (quick stop) within [drives] heartbeat_timeout_ms: its EMCY 0x8130."""
    monkeypatch.setattr("conftest.ARM", "cia402")
    c = start_controller(tmp_path / "ls0")
    drv = tmp_path / "ls0-drives"
    try:
        bus = can.Bus(interface="slcan", channel=c.pty, bitrate=1000000, sleep_after_open=0)
        sup = Supervisor(bus, client_name="kill")
        sup.open()
        sup.lock()
        sup.activate()
        sup.move_absolute("far", TARGET, speed_pct=20)
        time.sleep(0.4)
        c.proc.kill()
        t_kill = time.monotonic()
        c.proc.wait(timeout=5)
        with contextlib.suppress(can.CanError, errors.LandscapeError):
            sup.close()  # its pty went with landscaped
        with contextlib.suppress(can.CanError):
            bus.shutdown()
        # listen on the drive bus as landscaped did (the pty stays the simulator's)
        listener = can.Bus(interface="slcan", channel=str(drv), bitrate=1000000, sleep_after_open=0)
        try:
            seen: dict[int, float] = {}
            deadline = t_kill + 3.0
            while time.monotonic() < deadline and len(seen) < 6:
                m = listener.recv(timeout=0.1)
                if m is not None and 0x81 <= m.arbitration_id <= 0xFF and m.data[:2] == b"\x30\x81":
                    seen.setdefault(m.arbitration_id - 0x80, time.monotonic() - t_kill)
        finally:
            listener.shutdown()
        assert sorted(seen) == [0x21, 0x22, 0x23, 0x24, 0x25, 0x26], seen
        print(f"EMCY 0x8130 after SIGKILL: {', '.join(f'{n:#x} {t * 1e3:.0f} ms' for n, t in sorted(seen.items()))}")
        assert max(seen.values()) < 0.35 + 0.25, seen  # heartbeat_timeout_ms 350, and the simulator's own pace
    finally:
        c.stop()
