"""docs/protocol.md "Identity", one supervisor per address, against landscaped: a second client on a live
session's address is refused naming the holder; the same client (its nonce) reconnects; only
heartbeats carrying the session's token keep it; supervisors without a pinned address pick
different free ones and the owner stays the owner; `-s` pins; `kill -9` of the owner with a
recorder running stops the arm per the disconnect action within the session's time-out.

landscaped runs with three SLCAN ptys (it bridges frames between its links), so clients on
different ptys hear each other's heartbeats as on one CAN bus."""
from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import textwrap
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import can
import pytest

from conftest import CLI, ROOT, Controller, open_slcan, start_controller, wait_for_path
from landscape import AddressInUseError, Supervisor
from landscape import telemetry as tm
from landscape._generated import landscape_pb2 as pb
from landscape.bus import ADDRESS_LISTEN_S
from landscape.supervisor import notice_data

HEARTBEAT_TIMEOUT_S = 1.0  # landscaped's default session time-out
FIRST, SECOND = pb.DEFAULT_HOST_ADDRESS, pb.DEFAULT_HOST_ADDRESS + 1


@dataclass
class Rig:
    controller: Controller
    ptys: list[str]  # three links of one landscaped



@pytest.fixture
def rig(tmp_path: Path) -> Iterator[Rig]:
    extra = [tmp_path / "ls1", tmp_path / "ls2"]
    c = start_controller(tmp_path / "ls0", *[a for p in extra for a in ("--link", f"slcan:pty:{p}")])
    try:
        for p in extra:
            wait_for_path(p, c.proc)
        yield Rig(c, [c.pty, *map(str, extra)])
    finally:
        code = c.stop()
        log = c.log.read_text(errors="replace")
        assert code == 0, f"landscaped exited with {code}:\n{log[-4000:]}"


@pytest.fixture
def buses(rig: Rig) -> Iterator[list[can.BusABC]]:
    bs = [open_slcan(p) for p in rig.ptys]
    try:
        yield bs
    finally:
        for b in bs:
            b.shutdown()


def status(sup: Supervisor) -> str:
    return str(sup.send_command("status").result["result"])


def counter(text: str, name: str) -> int:
    m = re.search(rf"^{name}=(\d+)$", text, re.M)
    assert m is not None, f"no {name}= in status:\n{text}"
    return int(m.group(1))


def session_line(text: str, addr: int) -> str | None:
    return next((ln for ln in text.splitlines() if ln.startswith(f"session 0x{addr:02X} ")), None)


# ---------------------------------------------------------------- identity in connect

def test_a_second_client_on_the_owners_address_is_refused_naming_it(rig: Rig) -> None:
    owner_bus = open_slcan(rig.ptys[0])
    with Supervisor(owner_bus, source_address=FIRST, client_name="owner", owns_bus=True) as owner:
        owner.lock()
        epoch = owner.connect_result.device.session_epoch if owner.connect_result else 0
        # on the owner's own link segment (from another one, its frames never reach a session:
        # docs/protocol.md "Sessions bound to their link"): the owner's bus object and its listener
        # thread (a pty has one reader), an ISO-TP stack of its own opened now
        intruder = Supervisor(owner_bus, source_address=FIRST, client_name="recorder", notifier=owner._notifier)
        with pytest.raises(AddressInUseError) as exc:
            intruder.open()
        msg = str(exc.value)
        assert f"address 0x{FIRST:02X} is in use by another client, \"owner\" (the owner): " in msg, msg
        assert "connect from an address no live session uses" in msg, msg  # the device speaks protocol
        assert "pass another --source-address (Supervisor source_address), or none to let the host pick a free " \
               "one" in msg, msg  # the host tool adds its own words
        intruder.close()  # it never had a session: its close must not end the owner's
        time.sleep(HEARTBEAT_TIMEOUT_S + 0.3)  # the owner's heartbeats still keep its session
        st = owner.get_motion_control_state().result
        assert st["owner"] is True and st["state"] == "LOCKED"
        owner.set_speed(20.0, attribute="PERCENT_SPEED")  # owner-only: still works
        text = status(owner)
        assert counter(text, "connects_refused") == 1
        line = session_line(text, FIRST)
        assert line is not None and "name=owner " in line, text

        # the same client (its nonce) connects again: a reconnect, still the owner
        res = owner.connect()
        assert res.device.owner and res.device.session_epoch != epoch
        assert owner.get_motion_control_state().result["owner"] is True


# ---------------------------------------------------------------- heartbeat identity

@pytest.mark.parametrize("token", ["bare", "wrong"])
def test_heartbeats_without_the_token_do_not_keep_an_abandoned_session(buses: list[can.BusABC],
                                                                        token: str) -> None:
    victim_addr = 0xF4
    with Supervisor(buses[0], source_address=0xF2, client_name="observer") as observer:
        victim = Supervisor(buses[1], source_address=victim_addr, client_name="victim")
        victim.open()
        try:
            victim.lock()
            victim.activate()
            assert victim.device_info is not None and victim.device_info.heartbeat_token != 0
            forged = 0 if token == "bare" else victim.device_info.heartbeat_token ^ 0x5A5A5A
            victim._stop_heartbeat()  # the supervisor is gone; someone else beats for its address
            list(observer.notices(timeout_s=0.0))
            t0 = time.monotonic()
            alarm = None
            sent = 0
            while time.monotonic() - t0 < HEARTBEAT_TIMEOUT_S + 2.0 and alarm is None:
                # on the victim's own segment: from another one the network layer drops them before
                # the token is looked at (docs/protocol.md "Sessions bound to their link")
                buses[1].send(tm.encode("HEARTBEAT", victim_addr, hb_role=1, hb_counter=sent & 0xFF,
                                        hb_period_ms=200, hb_token=forged))
                sent += 1
                for n in observer.notices(timeout_s=0.1):
                    if n.event_id == "ownerLost":
                        alarm = n
                        break
            elapsed = time.monotonic() - t0
        finally:
            victim.close()
        assert alarm is not None, f"{sent} forged heartbeats kept the abandoned session alive"
        assert notice_data(alarm)["supervisor"] == f"0x{victim_addr:02X}"
        assert notice_data(alarm)["reason"] == "heartbeat lost"
        assert notice_data(alarm)["action"] == "stop_deactivate_release"
        print(f"{token} heartbeats every 0.1 s: ownerLost {elapsed:.3f} s after the last real one")
        assert elapsed < HEARTBEAT_TIMEOUT_S + 0.6, elapsed
        st = observer.get_motion_control_state().result
        assert st["state"] == "UNLOCKED" and st["control_mode"] == "power_off"
        assert counter(status(observer), "hb_refused") >= sent - 3  # all but those after the drop


# ---------------------------------------------------------------- the host picks a free address

def test_two_supervisors_without_an_address_get_different_ones(buses: list[can.BusABC]) -> None:
    # on different links they hear each other's heartbeats: the second never tries the first's
    with Supervisor(buses[0], client_name="a") as a:
        assert a.source_address == FIRST and not a.address_pinned
        a.lock()
        t0 = time.monotonic()
        with Supervisor(buses[1], client_name="b") as b:
            assert time.monotonic() - t0 >= ADDRESS_LISTEN_S
            assert b.source_address == SECOND
            assert b.connect_result is not None and not b.connect_result.device.owner
            assert a.get_motion_control_state().result["owner"] is True
            assert b.get_motion_control_state().result["owner"] is False
        # b's close disconnected b, not a
        assert a.get_motion_control_state().result["owner"] is True
        a.set_speed(30.0, attribute="PERCENT_SPEED")
        text = status(a)
        assert counter(text, "connects_refused") == 0, text


def test_a_supervisor_that_cannot_hear_the_other_moves_on_when_refused(buses: list[can.BusABC]) -> None:
    # one python-can bus object does not receive its own frames: the second does not hear the
    # first's heartbeats, takes the first address, is refused by the device and moves on
    notifier = can.Notifier(buses[0], [], timeout=0.01)
    try:
        with Supervisor(buses[0], notifier=notifier, client_name="a") as a:
            a.lock()
            with Supervisor(buses[0], notifier=notifier, client_name="b") as b:
                assert b.source_address == SECOND
                assert a.get_motion_control_state().result["owner"] is True
                assert b.get_motion_control_state().result["owner"] is False
                assert counter(status(b), "connects_refused") == 1
            assert a.get_motion_control_state().result["owner"] is True
    finally:
        notifier.stop()


def test_a_pinned_address_is_used_as_given(buses: list[can.BusABC]) -> None:
    with Supervisor(buses[0], source_address=0xF7, client_name="pinned") as sup:
        assert sup.source_address == 0xF7 and sup.address_pinned
        assert session_line(status(sup), 0xF7) is not None


# ---------------------------------------------------------------- the CLI

def cli(pty: str, *args: str, timeout: float = 60.0) -> subprocess.CompletedProcess[str]:
    return subprocess.run([str(CLI), "--interface", "slcan", "--channel", pty, *args], capture_output=True,
                          text=True, timeout=timeout)


def test_cli_invocations_without_s_next_to_a_session(rig: Rig, tmp_path: Path) -> None:
    os.environ["XDG_RUNTIME_DIR"] = str(tmp_path)
    pty = rig.ptys[0]
    try:
        r = cli(pty, "session", "start")
        assert r.returncode == 0, r.stderr
        r = cli(pty, "lock")  # through the session
        assert r.returncode == 0, r.stderr
        r = cli(pty, "--json", "session", "status")
        assert r.returncode == 0, r.stderr
        assert '"source_address": 241' in r.stdout, r.stdout  # the session took 0xF1
        # an invocation with its own session (no -s) picks another address; not the owner
        r = cli(pty, "--no-session", "get-motion-control-state")
        assert r.returncode == 0, r.stderr
        assert "  owner: False" in r.stdout, r.stdout
        # record next to the session, no flags
        out = tmp_path / "rec.csv"
        r = cli(pty, "record", str(out), "--duration", "0.5")
        assert r.returncode == 0, r.stderr
        assert out.exists() and out.stat().st_size > 0
        # -s pins: the session's address is refused naming the holder, exit 3
        r = cli(pty, "--no-session", "-s", f"{FIRST:#04x}", "get-motion-control-state")
        assert r.returncode == 3, (r.stdout, r.stderr)
        assert f"address 0x{FIRST:02X} is in use by another client, \"landscape-cli\" (the owner)" in r.stderr
        assert "Traceback" not in r.stderr
        # the session is still the owner
        r = cli(pty, "get-motion-control-state")
        assert r.returncode == 0 and "  owner: True" in r.stdout, (r.stdout, r.stderr)
    finally:
        cli(pty, "session", "stop")
        os.environ.pop("XDG_RUNTIME_DIR", None)


# ---------------------------------------------------------------- kill -9 of the owner, a recorder running

OWNER_SCRIPT = textwrap.dedent("""
    import sys, time
    import can
    from landscape.supervisor import Supervisor
    bus = can.Bus(interface="slcan", channel=sys.argv[1], bitrate=1000000, sleep_after_open=0)
    sup = Supervisor(bus, client_name="owner")
    sup.__enter__()
    sup.lock()
    sup.activate()
    sup.set_speed(20.0, attribute="PERCENT_SPEED")
    sup.move_absolute("far", [2.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    print(f"moving {sup.source_address}", flush=True)
    while True:
        time.sleep(1)
""")


def test_kill_9_of_the_owner_with_a_recorder_running_stops_the_arm(rig: Rig, tmp_path: Path) -> None:
    rec_file = tmp_path / "rec.csv"
    bus = open_slcan(rig.ptys[2])
    # the recorder: a CLI without flags on its own link
    recorder = subprocess.Popen([str(CLI), "--interface", "slcan", "--channel", rig.ptys[0], "record",
                                 str(rec_file), "--duration", "20"], stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, text=True)
    owner: subprocess.Popen[bytes] | None = None
    try:
        with Supervisor(bus, source_address=0xF8, client_name="observer") as observer:
            deadline = time.monotonic() + 10
            while session_line(status(observer), FIRST) is None:  # the recorder has connected
                assert recorder.poll() is None, recorder.communicate()
                assert time.monotonic() < deadline, "the recorder did not connect"
                time.sleep(0.1)
            env = dict(os.environ, PYTHONPATH=str(ROOT / "host_tools" / "src"))
            owner = subprocess.Popen([sys.executable, "-c", OWNER_SCRIPT, rig.ptys[1]], stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, env=env)
            assert owner.stdout is not None
            line = owner.stdout.readline().decode()
            assert line.startswith("moving "), owner.stderr.read().decode() if owner.stderr else ""
            assert int(line.split()[1]) == SECOND  # it heard the recorder at the first address
            time.sleep(0.5)
            st = observer.get_motion_control_state().result
            assert st["state"] == "MOVING", st
            list(observer.notices(timeout_s=0.0))
            owner.send_signal(signal.SIGKILL)
            t0 = time.monotonic()
            alarm = None
            for n in observer.notices(timeout_s=HEARTBEAT_TIMEOUT_S + 4.0):
                if n.event_id == "ownerLost":
                    alarm = n
                    break
            elapsed = time.monotonic() - t0
            assert alarm is not None, "the arm was not stopped: the owner's session outlived it"
            assert notice_data(alarm)["supervisor"] == f"0x{SECOND:02X}"
            st = observer.get_motion_control_state().result
            assert st["state"] == "UNLOCKED" and st["control_mode"] == "power_off", st
            # the alarm goes out once the arm is at rest: time-out plus the stop at 20 % speed
            print(f"kill -9 -> arm at rest, drives off, ownerLost: {elapsed:.3f} s")
            assert elapsed < HEARTBEAT_TIMEOUT_S + 1.5, elapsed
            assert recorder.poll() is None  # the recorder runs on, its session untouched
            assert session_line(status(observer), FIRST) is not None
    finally:
        bus.shutdown()
        if owner is not None:
            owner.kill()
            owner.wait(timeout=10)
        recorder.send_signal(signal.SIGINT)
        try:
            recorder.communicate(timeout=10)
        except subprocess.TimeoutExpired:
            recorder.kill()
            recorder.communicate()
