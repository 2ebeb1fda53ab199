"""Under fault injection (landscaped --link-faults SPEC, hal/sim/faulty_link.h):
commands complete exactly once or fail with a clear ControllerTimeoutError,
retransmissions never execute twice, a path is never half loaded, heartbeat
loss ends in the safe stop, and an e-stop input stops motion and raises the
fault alarm.

Parts that need firmware features not built yet (setSpeed/getVelocities,
pathLoad, motion, --estop-input) skip with the reason while the device
answers CMD_NOT_IMPLEMENTED_ERR or the option is missing; they run as soon as
the feature lands. docs/reliability.md records the figures."""
from __future__ import annotations

import logging
import os
import socket
import subprocess
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import can
import pytest

from conftest import LANDSCAPED, Controller, start_controller
from landscape import errors
from landscape._generated import landscape_pb2 as pb
from landscape.supervisor import RetVal, Supervisor, notice_data

LOSS_RATES = [0.01, 0.05, 0.20]
# The supervisor beats every 100 ms against the device's 1 s time-out, so a
# session survives 9 lost heartbeats in a row (at 20 % loss: 0.2^10 = 1e-7
# per beat); the owner-lost test below stops beating on purpose.
HB_MS = 100
RETRIES = 8
PER_TRY_S = float(os.environ.get("LS_FAULT_PER_TRY_S", "0.4"))


class RetransmitCounter(logging.Handler):
    """Counts the host library's 'retransmitting' log records."""

    def __init__(self) -> None:
        super().__init__(logging.INFO)
        self.count = 0

    def emit(self, record: logging.LogRecord) -> None:
        if "retransmitting" in record.getMessage():
            self.count += 1


@pytest.fixture
def retransmits() -> Iterator[RetransmitCounter]:
    h = RetransmitCounter()
    lg = logging.getLogger("landscape")
    old = lg.level
    lg.setLevel(logging.INFO)
    lg.addHandler(h)
    try:
        yield h
    finally:
        lg.removeHandler(h)
        lg.setLevel(old)


def faulty(tmp_path: Path, spec: str, *extra: str) -> Controller:
    return start_controller(tmp_path / "ls0", "--link-faults", spec, *extra)


def open_bus(c: Controller) -> can.BusABC:
    return can.Bus(interface="slcan", channel=c.pty, bitrate=1000000, sleep_after_open=0)


def sup_on(bus: can.BusABC, addr: int = 0xF1, **kw: Any) -> Supervisor:
    kw.setdefault("retries", RETRIES)
    kw.setdefault("timeout_s", PER_TRY_S)
    kw.setdefault("heartbeat_period_ms", HB_MS)
    return Supervisor(bus, source_address=addr, client_name=f"faults-{addr:02x}", **kw)


def executed(sup: Supervisor) -> int:
    """This session's executed counter (sendCommand status; the status request counts itself)."""
    text = sup.send_command("status").result["result"]
    for line in text.splitlines():
        if line.startswith(f"session 0x{sup.source_address:02X} "):
            return int(line.split("executed=")[1].split()[0])
    raise AssertionError(f"no session line for 0x{sup.source_address:02X} in:\n{text}")


@dataclass
class Tally:
    ok: int = 0
    timeouts: int = 0
    by_code: dict[str, int] = field(default_factory=dict)

    def run(self, fn: Callable[[], RetVal]) -> RetVal | None:
        try:
            rv = fn()
        except errors.ControllerTimeoutError as exc:
            msg = str(exc)
            assert "no answer from the controller" in msg and "tries" in msg, msg  # clear, actionable
            self.timeouts += 1
            return None
        self.ok += 1
        self.by_code[rv.ret_name] = self.by_code.get(rv.ret_name, 0) + 1
        return rv


def retry_until_answered(fn: Callable[[], RetVal], attempts: int = 5) -> RetVal:
    for _ in range(attempts - 1):
        try:
            return fn()
        except errors.ControllerTimeoutError:
            continue
    return fn()


def executed_retry(sup: Supervisor) -> tuple[int, int]:
    """(executed counter, status tries lost on the way): every lost try may have
    executed on the device without us seeing its answer."""
    lost = 0
    for _ in range(5):
        try:
            return executed(sup), lost
        except errors.ControllerTimeoutError:
            lost += 1
    raise AssertionError("sendCommand status timed out 5 times in a row")


def check_executed(sup: Supervisor, e0: int, t: Tally) -> int:
    """Between e0 and now, the device executed each answered command once, and at
    most once each command that timed out: never a retransmission twice."""
    e1, lost = executed_retry(sup)
    delta = e1 - e0 - 1  # the status request that read e1 counts itself
    assert t.ok <= delta <= t.ok + t.timeouts + lost, (t, e0, e1, lost)
    if t.timeouts == 0 and lost == 0:
        assert delta == t.ok
    return delta


# ------------------------------------------------------------------ exactly once


class FaultWindow:
    """Frame faults only in a window (window=AFTER+FOR): connect and read the
    counters on a clean bus, run the commands under faults. At 20 % loss an
    n-frame ISO-TP message gets through with probability 0.8^(n+1), so the
    handshake (about 15 frames) and the status report (about 30) would almost
    never arrive; the commands under test are the short ones."""

    AFTER_S = 1.5
    LAST_COMMAND_MARGIN_S = (RETRIES + 1) * PER_TRY_S + 0.5  # a command started before it ends in the window

    def __init__(self, for_s: float) -> None:
        self.for_s = for_s
        self.t0 = 0.0

    def spec(self) -> str:
        return f"window={int(self.AFTER_S * 1000)}ms+{int(self.for_s * 1000)}ms"

    def started(self) -> None:
        self.t0 = time.monotonic()  # just after landscaped wrapped its links (its pty exists)

    def wait_open(self) -> None:
        time.sleep(max(0.0, self.t0 + self.AFTER_S + 0.1 - time.monotonic()))

    def more(self) -> bool:
        return time.monotonic() < self.t0 + self.AFTER_S + self.for_s - self.LAST_COMMAND_MARGIN_S

    def wait_closed(self) -> None:
        time.sleep(max(0.0, self.t0 + self.AFTER_S + self.for_s + 0.2 - time.monotonic()))


@pytest.mark.parametrize("loss", LOSS_RATES, ids=lambda p: f"loss{int(p * 100)}pct")
def test_commands_execute_exactly_once_under_loss(tmp_path: Path, loss: float,
                                                  retransmits: RetransmitCounter) -> None:
    w = FaultWindow(for_s={0.01: 12.0, 0.05: 20.0}.get(loss, 30.0))
    c = faulty(tmp_path, f"drop={loss},{w.spec()},seed=7")
    w.started()
    bus = open_bus(c)
    try:
        with sup_on(bus) as sup:
            e0, _ = executed_retry(sup)
            w.wait_open()
            t = Tally()
            n = 0
            locked = None  # unknown after a time-out
            while n < 90 and w.more():
                if n % 3 == 0:
                    rv = t.run(lambda: sup.get_motion_control_state())
                    if rv is not None:
                        assert rv.result["state"] in ("UNLOCKED", "LOCKED"), rv
                        locked = rv.result["state"] == "LOCKED"
                elif n % 3 == 1:
                    rv = t.run(lambda: sup.lock(check=False))
                    if rv is not None and locked is False:
                        # a lock executed twice would answer WRONG_STATE to its own retransmission
                        assert rv.ret_code == pb.CMD_EXEC_OK, rv
                    locked = True if rv is not None and rv.ok else None
                else:
                    rv = t.run(lambda: sup.release(check=False))
                    locked = False if rv is not None and rv.ok else None
                n += 1
            w.wait_closed()
            delta = check_executed(sup, e0, t)
            assert set(t.by_code) <= {"CMD_EXEC_OK", "CMD_WRONG_STATE_ERR"}, t.by_code
        print(f"\nloss {loss:.0%}: {n} commands, ok {t.ok}, timeouts {t.timeouts}, "
              f"retransmissions {retransmits.count}, executed {delta}")
        # The acceptance is "exactly once, or a clear time-out" (checked above);
        # how many time out depends on which frames the loss hits, which
        # depends on timing on a shared machine: it is a printed figure, with
        # only a floor that shows the run was meaningful.
        assert n >= 5, f"only {n} commands fitted in the fault window"
        if loss <= 0.05:
            assert t.ok * 2 >= n, f"fewer than half of {n} commands were answered at {loss:.0%} loss: {t}"
        else:
            # 20 %: a lost flow control stalls the device's sender for N_Bs (1 s) while the
            # host retries (docs/reliability.md, finding 3): few answers, but some.
            assert t.ok >= 1, f"no command was answered at {loss:.0%} loss: {t}"
        if loss >= 0.05:
            assert retransmits.count > 0, "no retransmission at this loss: were faults injected at all?"
    finally:
        bus.shutdown()
        c.stop()


def test_connect_and_status_survive_moderate_loss(tmp_path: Path) -> None:
    """Without a window: the handshake and the long status report (20 frames) get
    through 1 % loss; at 5 % a 20-frame message needs about 3 tries on average."""
    c = faulty(tmp_path, "drop=0.01,seed=17")
    bus = open_bus(c)
    try:
        with sup_on(bus) as sup:
            e0, _ = executed_retry(sup)
            t = Tally()
            for _ in range(10):
                t.run(lambda: sup.get_motion_control_state())
            check_executed(sup, e0, t)
            assert t.timeouts == 0, t
    finally:
        bus.shutdown()
        c.stop()


@pytest.mark.parametrize("loss", LOSS_RATES, ids=lambda p: f"loss{int(p * 100)}pct")
def test_set_speed_takes_effect_once_under_loss(tmp_path: Path, loss: float) -> None:
    w = FaultWindow(for_s=20.0)
    c = faulty(tmp_path, f"drop={loss},{w.spec()},seed=11")
    w.started()
    bus = open_bus(c)
    try:
        with sup_on(bus) as sup:
            sup.lock()
            sup.set_speed(10.0)
            sup.get_velocities()
            e0, _ = executed_retry(sup)
            w.wait_open()
            t = Tally()
            last_set: float | None = 10.0
            i = 0
            while i < 30 and w.more():
                i += 1
                v = 5.0 + i
                rv = t.run(lambda v=v: sup.set_speed(v))
                last_set = v if rv is not None else None  # a timed-out set may or may not have run
                got = t.run(lambda: sup.get_velocities())
                if got is not None:
                    pv = got.result.get("percent_velocity", 0.0)
                    if last_set is not None:
                        assert pv == pytest.approx(last_set), (i, got)
                    else:
                        assert pv in (pytest.approx(v), pytest.approx(v - 1.0), pytest.approx(10.0)), (i, got)
            w.wait_closed()
            check_executed(sup, e0, t)
    finally:
        bus.shutdown()
        c.stop()


POINTS = 7  # per pathLoad: a multi-frame ISO-TP message that loss can cut in the middle


def _tags(k: int) -> list[dict[str, Any]]:
    return [{"joints": [0.01 * (k + j)] * 6, "tag_name": f"t{k}_{j}"} for j in range(POINTS)]


@pytest.mark.parametrize("loss", LOSS_RATES, ids=lambda p: f"loss{int(p * 100)}pct")
def test_path_is_never_half_loaded(tmp_path: Path, loss: float) -> None:
    w = FaultWindow(for_s=20.0)
    c = faulty(tmp_path, f"drop={loss},{w.spec()},seed=13")
    w.started()
    bus = open_bus(c)
    try:
        with sup_on(bus) as sup:
            sup.lock()
            sup.path_clear_path("soak", check=False)
            w.wait_open()
            t = Tally()
            prev: int | None = 0
            lost_since = 0
            k = -1
            while k < 20 and w.more():
                k += 1
                rv = t.run(lambda k=k: sup.path_load("soak", _tags(k)))
                if rv is None:
                    lost_since += 1
                    continue
                n = rv.result.get("points_in_path", 0)
                assert n % POINTS == 0, f"path holds {n} points: a pathLoad was cut in the middle"
                if prev is not None:
                    # this load, plus at most every timed-out one since the last answer; never twice
                    assert prev + POINTS <= n <= prev + POINTS * (1 + lost_since), (k, prev, n, lost_since)
                prev, lost_since = n, 0
            tag = t.run(lambda: sup.get_tag_id())
            if tag is not None:
                assert tag.result.get("path_name", "") in ("", "soak"), tag
    finally:
        bus.shutdown()
        c.stop()


# ------------------------------------------------------------------ heartbeat loss


def _wait_state(sup: Supervisor, want: str, timeout_s: float) -> dict[str, Any]:
    deadline = time.monotonic() + timeout_s
    st: dict[str, Any] = {}
    while time.monotonic() < deadline:
        try:
            st = sup.get_motion_control_state().result
        except errors.ControllerTimeoutError:
            continue
        if st["state"] == want:
            return st
        time.sleep(0.05)
    raise AssertionError(f"the device did not reach {want} within {timeout_s} s: last {st}")


def _session_counters(sup: Supervisor) -> tuple[int, set[str]]:
    text = retry_until_answered(lambda: sup.send_command("status")).result["result"]
    dropped = int(next(ln for ln in text.splitlines() if ln.startswith("sessions_dropped=")).split("=")[1])
    sessions = {ln.split()[1] for ln in text.splitlines() if ln.startswith("session ")}
    return dropped, sessions


@pytest.mark.parametrize("loss", [0.05, 0.20], ids=lambda p: f"loss{int(p * 100)}pct")
def test_owner_heartbeat_loss_ends_in_the_safe_stop(tmp_path: Path, loss: float) -> None:
    """The owner beats through a lossy phase (no false ownerLost), then vanishes
    just before the loss ends; an observer sees the device stop, deactivate,
    release and raise ownerLost. Notices are not retransmitted, so the alarm is
    timed to leave on a clean bus: the owner stops beating 0.3 s before the
    window closes and the device waits 1 s (7 heartbeats lost in a row would be
    needed to move the alarm into the window: 0.2^7 = 1e-5)."""
    w = FaultWindow(for_s=5.0)
    c = faulty(tmp_path, f"drop={loss},{w.spec()},seed=3")
    w.started()
    bus = open_bus(c)
    notifier = can.Notifier(bus, [], timeout=0.05)
    try:
        with sup_on(bus, 0xF2, notifier=notifier) as watcher:
            owner = sup_on(bus, 0xF1, notifier=notifier)
            owner.open()
            owner.lock()
            act = owner.activate(check=False)
            moving = False
            if act.ok:
                moving = owner.move_absolute("far", [0.5] * 6, check=False).started
            dropped0, _ = _session_counters(watcher)
            w.wait_open()
            time.sleep(max(0.0, w.t0 + w.AFTER_S + w.for_s - 0.3 - time.monotonic()))
            t0 = time.monotonic()
            owner._stop_heartbeat()  # the owner vanishes without a word
            alarm = None
            for n in watcher.notices(timeout_s=4.0):
                if n.event_id == "ownerLost":
                    alarm = n
                    break
            elapsed = time.monotonic() - t0
            assert alarm is not None and alarm.kind in (pb.ALARM, pb.ALARM_RSVP), "no ownerLost alarm"
            assert elapsed < 1.0 + 0.5, elapsed
            st = _wait_state(watcher, "UNLOCKED", 3.0)
            assert st["control_mode"] == "power_off", st
            assert st.get("owner", False) is False
            dropped1, sessions = _session_counters(watcher)
            # exactly the induced drop: the owner's session survived the lossy phase until it stopped beating
            assert dropped1 - dropped0 == 1, (dropped0, dropped1)
            assert "0xF1" not in sessions and "0xF2" in sessions, sessions
            print(f"\nloss {loss:.0%}: ownerLost after {elapsed:.2f} s (moving={moving})")
            owner._running = False
            owner.close()
    finally:
        notifier.stop()
        bus.shutdown()
        c.stop()


# ------------------------------------------------------------------ e-stop input

ESTOP_BIT = 3


def test_estop_input_stops_motion_and_raises_the_fault_alarm(tmp_path: Path) -> None:
    sock_path = tmp_path / "dio.sock"
    c = faulty(tmp_path, "drop=0,seed=5", "--estop-input", str(ESTOP_BIT), "--dio-socket", str(sock_path))
    bus = open_bus(c)
    dgram = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
    try:
        with sup_on(bus) as sup:
            retry_until_answered(lambda: sup.lock())
            retry_until_answered(lambda: sup.activate())
            mv = sup.move_absolute("far", [1.0, -0.5, 0.5, 0.0, 0.5, 0.0], check=False)
            assert mv.started, mv
            time.sleep(0.3)  # well under way
            deadline = time.monotonic() + 5
            while not sock_path.exists():
                assert time.monotonic() < deadline, "landscaped did not create its DIO socket"
                time.sleep(0.02)
            t0 = time.monotonic()
            dgram.sendto(f"in {1 << ESTOP_BIT:x} 0".encode(), str(sock_path))
            alarm = None
            for n in sup.notices(timeout_s=3.0):
                if n.kind in (pb.ALARM, pb.ALARM_RSVP):
                    alarm = n
                    break
            latency = time.monotonic() - t0
            assert alarm is not None, "no alarm after the e-stop input"
            # the arm stops along its path at the model's maximum deceleration, the
            # drives go off, then the move's one final notice names the fault
            final = next((n for n in sup.notices(timeout_s=3.0) if n.final and n.ref_seq == mv.seq), None)
            assert final is not None, "the move got no final notice after the e-stop input"
            assert final.event_id == "moveAbsoluteFailed", final
            assert notice_data(final)["reason"] == "fault", final
            st = sup.get_motion_control_state().result
            assert st["fault"], f"no latched fault: {st}"
            assert st["state"] == "LOCKED" and st["control_mode"] == "controller_error", st
            assert st["motion_control_state"] == "robot_stopped_on_error", st
            # stopped: the position no longer changes (within one cycle plus the deceleration)
            time.sleep(0.5)
            p1 = retry_until_answered(lambda: sup.get_robot_position(check=False))
            time.sleep(0.3)
            p2 = retry_until_answered(lambda: sup.get_robot_position(check=False))
            if p1.ok and p2.ok:
                # 1e-9 rad (m) in 0.3 s is no motion; the simulated arm at rest still moves its
                # last bits (4e-16 rad seen under load), so bit-for-bit equality was no property
                assert p1.result.keys() == p2.result.keys()
                for key, value in p1.result.items():
                    assert value == pytest.approx(p2.result[key], rel=0, abs=1e-9), (key, p1, p2)
            print(f"\ne-stop: alarm {alarm.event_id} after {latency * 1000:.0f} ms, fault {st['fault']!r}")
            assert latency < 0.5, f"the e-stop alarm took {latency:.3f} s"
    finally:
        dgram.close()
        bus.shutdown()
        c.stop()


# ------------------------------------------------------------------ the option itself


def test_bad_fault_spec_is_refused_with_a_clear_message(tmp_path: Path) -> None:
    r = subprocess.run([str(LANDSCAPED), "--hal", "sim", "--link", f"slcan:pty:{tmp_path / 'x'}",
                        "--link-faults", "drop=2"], capture_output=True, text=True, timeout=10)
    assert r.returncode != 0
    assert "--link-faults" in r.stderr and "drop '2'" in r.stderr and "probability 0..1" in r.stderr, r.stderr
    assert not (tmp_path / "x").exists()


def test_faults_are_counted_and_logged_at_shutdown(tmp_path: Path) -> None:
    c = faulty(tmp_path, "drop=0.05,dup=0.01,seed=1")
    bus = open_bus(c)
    try:
        with sup_on(bus) as sup:
            for _ in range(20):
                retry_until_answered(lambda: sup.get_motion_control_state())
    finally:
        bus.shutdown()
        status = c.stop()  # also when the session failed: never leave landscaped behind
    assert status == 0
    err = c.log.read_text(errors="replace")
    line = next((ln for ln in err.splitlines() if " faults: tx frames=" in ln), "")
    assert line, err
    fields = dict(kv.split("=") for kv in line.split(" faults: ", 1)[1].split() if "=" in kv)
    assert int(fields["drop"]) > 0  # tx, first occurrence
