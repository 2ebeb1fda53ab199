"""Background sessions: start/status/stop as a real process on an SLCAN pty, routing, stale sockets."""
from __future__ import annotations

import json
import os
import shutil
import signal
import socket
import tempfile
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import can
import pytest
from click.testing import CliRunner, Result

from fake_device import FakeDevice
from landscape import BusSpec, Supervisor, ls
from landscape.cli import cli
from landscape.session import SessionClient, SessionServer, socket_path
from pty_link import PtySlcanBus


@pytest.fixture
def runtime_dir(monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    d = Path(tempfile.mkdtemp(prefix="ls-rt-"))  # short: a socket path holds at most 107 bytes
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(d))
    yield d
    shutil.rmtree(d, ignore_errors=True)


@pytest.fixture
def pty_device(runtime_dir: Path) -> Iterator[tuple[FakeDevice, str]]:
    link = PtySlcanBus()
    n = can.Notifier(link, [], timeout=0.02)
    dev = FakeDevice(link, n, hosts=(0xF1, 0xF2)).start()
    yield dev, link.path
    pid_files = list(runtime_dir.glob("*.sock"))
    for sock in pid_files:  # a test that failed half way must not leave its session running
        client = SessionClient.attach(sock)
        if client is not None:
            with client:
                pid = client.status()["pid"]
            os.kill(pid, signal.SIGTERM)
    dev.stop()
    n.stop()
    link.shutdown()
    assert dev.undeclared == [], "the fake device was asked to send what the schema does not declare"


def slcan(pty: str, *args: str) -> Result:
    return CliRunner().invoke(cli, ["--interface", "slcan", "--channel", pty, *args])


def connects(dev: FakeDevice) -> int:
    return sum(1 for q in dev.requests if q.WhichOneof("cmd") == "connect")


def test_session_start_status_stop_and_a_lock_that_lives_on(pty_device: tuple[FakeDevice, str],
                                                            runtime_dir: Path) -> None:
    dev, pty = pty_device
    r = slcan(pty, "session", "start")
    assert r.exit_code == 0, r.stderr
    sock = socket_path(BusSpec("slcan", pty), 0x10, None)  # started without -s
    assert sock.parent == runtime_dir and sock.name.startswith("landscape-10-") and sock.exists()
    started, shared = r.stdout.splitlines()
    assert started.startswith("session started: pid ") and started.endswith(f"socket {sock}")
    # the session owns the pty and serves it on loopback for every other landscape process
    assert shared.startswith(f"  link: the session owns {pty} and shares it at socket://127.0.0.1:")
    assert connects(dev) == 1

    r = slcan(pty, "lock")                       # first invocation takes the lock and exits
    assert r.exit_code == 0, r.stderr
    assert r.stdout == "lock: CMD_EXEC_OK\n"
    assert dev.owner == 0xF1 and dev.state == ls.LOCKED
    r = slcan(pty, "get-motion-control-state")   # a second invocation still owns the device
    assert r.exit_code == 0, r.stderr
    assert "  owner: True" in r.stdout and "  state: LOCKED" in r.stdout
    assert connects(dev) == 1 and 0xF1 in dev.sessions

    r = slcan(pty, "--json", "session", "status")
    assert r.exit_code == 0, r.stderr
    status = json.loads(r.stdout)["result"]
    assert (status["connected"], status["owner"], status["state"], status["device"], status["socket"]) == \
        (True, True, "LOCKED", 0x10, str(sock))
    assert status["requests"] == 2
    text = slcan(pty, "session", "status").stdout.splitlines()
    assert text[0] == f"session: pid {status['pid']}, device 0x10 on slcan:{pty}, source 0xf1"
    assert text[1] == "  connected: True  owner: True  state: LOCKED"

    r = slcan(pty, "session", "start")
    assert r.exit_code == 1
    assert r.stderr.startswith(f"landscape: a session already runs for device 0x10 on slcan:{pty} (pid "
                               f"{status['pid']}, socket {sock}): `landscape session stop` first")

    r = slcan(pty, "session", "stop")
    assert r.exit_code == 0, r.stderr
    assert r.stdout == f"session stopped (pid {status['pid']})\n"
    assert not sock.exists()
    deadline = time.monotonic() + 3
    while dev.sessions and time.monotonic() < deadline:
        time.sleep(0.02)
    assert dev.sessions == {} and dev.owner is None  # the disconnect released the lock
    r = slcan(pty, "session", "status")
    assert r.exit_code == 1
    assert r.stderr == (f"landscape: no session runs for device 0x10 on slcan:{pty} (no socket {sock}): start one "
                        f"with `landscape session start`\n")


def test_session_streams_notices_and_locks_at_start(pty_device: tuple[FakeDevice, str], tmp_path: Path) -> None:
    dev, pty = pty_device
    r = slcan(pty, "session", "start", "--lock")
    assert r.exit_code == 0, r.stderr
    assert ", locked, socket " in r.stdout and dev.owner == 0xF1
    try:
        f = tmp_path / "sq.csv"
        f.write_text("j1,j2,tag_name\n0,0,a\n0.1,0,b\n")
        assert slcan(pty, "activate").exit_code == 0
        r = slcan(pty, "path", "load", str(f))
        assert r.exit_code == 0, r.stderr
        assert "  points_in_path: 2" in r.stdout
        r = slcan(pty, "path", "run", "sq", "--cycles", "2")
        assert r.exit_code == 0, r.stderr
        lines = r.stdout.splitlines()
        assert lines[0] == "path-move: CMD_STARTED_OK"
        assert [line.split()[2] for line in lines[1:5]] == ["tag=a", "tag=b", "tag=a", "tag=b"]
        assert lines[5].startswith("  EVENT pathMoveComplete point=sq reason=complete") and lines[5].endswith("final")
        r = slcan(pty, "move-absolute", "far", "joint", "4", "0", "0", "0", "0", "0")
        assert r.exit_code == 3 and "move-absolute ended with alarm moveAbsoluteFailed" in r.stderr
        rec = tmp_path / "rec.jsonl"
        r = slcan(pty, "record", str(rec), "--duration", "0.4")  # through the session's watch stream
        assert r.exit_code == 0, r.stderr
        names = {json.loads(line)["name"] for line in rec.read_text().splitlines()}
        assert {"JOINTS_12", "TOOL_POS", "STATUS"} <= names
        assert connects(dev) == 1
    finally:
        assert slcan(pty, "session", "stop").exit_code == 0


def test_session_start_reports_the_failure(pty_device: tuple[FakeDevice, str]) -> None:
    dev, pty = pty_device
    dev.silent = True
    r = slcan(pty, "--timeout", "0.1", "session", "start")
    assert r.exit_code == 4
    assert r.stderr.startswith("landscape: session start: no answer from the controller at address 0x10 on "
                               f"slcan:{pty} to connect")
    assert len(r.stderr.splitlines()) == 1


def _stale_socket(path: Path) -> None:
    s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    s.bind(str(path))
    s.close()  # the file stays, nobody listens: what a killed session leaves behind


def test_stale_socket_is_removed_with_a_message(channel: str, device: FakeDevice, runtime_dir: Path) -> None:
    sock = socket_path(BusSpec("virtual", channel), 0x10, None)
    _stale_socket(sock)
    r = CliRunner().invoke(cli, ["--interface", "virtual", "--channel", channel, "get-motion-control-state"])
    assert r.exit_code == 0, r.stderr
    assert r.stderr == f"landscape: removed stale session socket {sock} (no process listens on it)\n"
    assert "  state: UNLOCKED" in r.stdout and not sock.exists()
    _stale_socket(sock)
    r = CliRunner().invoke(cli, ["--interface", "virtual", "--channel", channel, "session", "stop"])
    assert r.exit_code == 1
    assert r.stderr.splitlines() == [f"landscape: removed stale session socket {sock} (no process listens on it)",
                                     f"landscape: no session runs for device 0x10 on virtual:{channel} (no socket "
                                     f"{sock}): start one with `landscape session start`"]


@pytest.fixture
def in_process_session(bus, notifier, device: FakeDevice, channel: str, runtime_dir: Path) -> Iterator[SessionServer]:
    """A session server in a thread of the test process (the virtual bus cannot leave it)."""
    sup = Supervisor(bus, notifier=notifier, channel_name=f"virtual:{channel}")
    sup.open()
    server = SessionServer(sup, socket_path(BusSpec("virtual", channel), 0x10, None), channel=f"virtual:{channel}")
    server.bind()
    t = threading.Thread(target=server.serve_forever, daemon=True)
    t.start()
    yield server
    server.stop()
    t.join(2)
    sup.close()


def test_routing_and_no_session(in_process_session: SessionServer, device: FakeDevice, channel: str) -> None:
    def cli_run(*args: str) -> Result:
        return CliRunner().invoke(cli, ["--interface", "virtual", "--channel", channel, *args])

    assert cli_run("lock").exit_code == 0
    assert device.owner == 0xF1 and in_process_session.requests == 1
    r = cli_run("--json", "release")
    assert r.exit_code == 0 and json.loads(r.stdout)["ret_name"] == "CMD_EXEC_OK"
    r = cli_run("release")
    assert r.exit_code == 3 and r.stderr.startswith("landscape: release: CMD_NOT_OWNER_ERR: lock first")
    assert in_process_session.requests == 3
    r = cli_run("--no-session", "-s", "0xf2", "get-motion-control-state")  # its own session, not the server's
    assert r.exit_code == 0 and in_process_session.requests == 3
    assert [q.WhichOneof("cmd") for q in device.requests].count("connect") == 2


def test_socket_protocol_errors(in_process_session: SessionServer) -> None:
    path = in_process_session.path
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as s:
        s.connect(str(path))
        f = s.makefile("rw")
        for line, err in (("[1]", "each line must be a JSON object"),
                          ('{"op": "dance"}', "unknown op 'dance'"),
                          ('{"op": "request", "command": "fly"}', "unknown command 'fly'"),
                          ('{"op": "request", "command": "lock", "fields": {"speed": 1}}', "no field 'speed'"),
                          ("not json", "Expecting value")):
            f.write(line + "\n")
            f.flush()
            got = json.loads(f.readline())
            assert err in got["error"]["message"], got
        f.write('{"op": "request", "command": "lock", "fields": {}}\n')
        f.flush()
        assert json.loads(f.readline())["retval"]["ret_name"] == "CMD_EXEC_OK"
        assert json.loads(f.readline()) == {"done": True}


def test_socket_path_is_bounded(monkeypatch: pytest.MonkeyPatch, bus, notifier) -> None:
    from landscape import ArgumentError

    monkeypatch.setenv("XDG_RUNTIME_DIR", "/tmp/" + "d" * 100)
    path = socket_path(BusSpec("virtual", "x"), 0x10, 0xF1)
    with pytest.raises(ArgumentError, match="longer than 107 bytes: set XDG_RUNTIME_DIR to a shorter directory"):
        SessionServer(Supervisor(bus, notifier=notifier), path)
    monkeypatch.delenv("XDG_RUNTIME_DIR")
    assert socket_path(BusSpec("virtual", "x"), 0x22, 0xF1).parent == Path(tempfile.gettempdir())
    assert socket_path(BusSpec("virtual", "x"), 0x22, 0xF1).name.startswith("landscape-22-")
    assert socket_path(BusSpec("virtual", "x"), 0x22, 0xF1) != socket_path(BusSpec("virtual", "y"), 0x22, 0xF1)
    assert socket_path(BusSpec("virtual", "x"), 0x22, 0xF1) != socket_path(BusSpec("virtual", "x"), 0x22, 0xF2)
    # a session started without -s is found by every invocation without -s, whatever address it took
    assert socket_path(BusSpec("virtual", "x"), 0x22, None) != socket_path(BusSpec("virtual", "x"), 0x22, 0xF1)
