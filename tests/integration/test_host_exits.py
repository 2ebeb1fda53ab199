"""landscaped killed (SIGKILL) in the middle of a command: the CLI ends with exit 4 and one
line naming what happened, no traceback, within seconds (docs/host-tool.md,
"Errors and exit codes").

Each case starts a landscaped of its own (the fixture of conftest.py would fail the test
on the non-zero exit that SIGKILL is), runs the command as a process, waits until the
command is under way (a line on stdout, or the time it takes to get going), kills the
controller and times the CLI's exit from the kill.
"""
from __future__ import annotations

import os
import select
import signal
import subprocess
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from conftest import CLI, Controller, start_controller
from landscape.link import lock_holder_pid

FAR = ["1.2", "-0.3", "1.2", "0.5", "0.9", "1.0"]
#: From the kill to the CLI's exit: the link closes at once (the pty's master goes), or the
#: device's heartbeat stays away for twice the session time-out (2 s): well within this.
EXIT_WITHIN_S = 8.0
#: prompt_toolkit's own line when the shell's stdin is a pipe (not an error of ours)
PROMPT_TOOLKIT_NOTE = "Warning: Input is not a terminal"


@pytest.fixture
def doomed(tmp_path: Path) -> Iterator[Controller]:
    c = start_controller(tmp_path / "ls0")
    try:
        yield c
    finally:
        if c.proc.poll() is None:
            c.proc.kill()
        c.proc.wait(10)


def popen(c: Controller, *args: str, stdin: int | None = subprocess.DEVNULL) -> subprocess.Popen[str]:
    return subprocess.Popen([str(CLI), "--interface", "slcan", "--channel", c.pty, *args], stdin=stdin,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def wait_for_line(proc: subprocess.Popen[str], text: str, timeout_s: float = 30.0) -> list[str]:
    """stdout lines of `proc` up to the first containing `text`."""
    assert proc.stdout is not None
    seen: list[str] = []
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        ready, _, _ = select.select([proc.stdout], [], [], 0.2)
        if ready:
            line = proc.stdout.readline()
            if not line:
                break
            seen.append(line)
            if text in line:
                return seen
    proc.kill()
    raise AssertionError(f"'{text}' not seen; stdout so far: {seen}; stderr: {proc.communicate()[1]}")


def kill_and_finish(c: Controller, proc: subprocess.Popen[str]) -> tuple[str, float]:
    """SIGKILL the controller; (the CLI's stderr, seconds from the kill to its exit)."""
    t0 = time.monotonic()
    c.proc.send_signal(signal.SIGKILL)
    try:
        _, err = proc.communicate(timeout=EXIT_WITHIN_S + 22)
    except subprocess.TimeoutExpired:
        proc.kill()
        raise AssertionError(f"the CLI did not exit within {EXIT_WITHIN_S + 22} s of the kill") from None
    return err, time.monotonic() - t0


def assert_one_line_exit_4(proc: subprocess.Popen[str], err: str, took_s: float) -> None:
    print(f"exit {proc.returncode} {took_s:.2f} s after the kill: {err.strip().splitlines()[-1:]}")  # pytest -s
    assert "Traceback" not in err and "Exception in thread" not in err, err
    assert proc.returncode == 4, (proc.returncode, err)
    lines = [line for line in err.splitlines() if not line.startswith("events: no background session: ")]
    assert len(lines) == 1, err
    assert lines[0].startswith("landscape: landscaped at 0x10 on slcan:"), lines[0]
    assert " stopped answering: " in lines[0] and lines[0].endswith("then rerun the command"), lines[0]
    assert took_s < EXIT_WITHIN_S, took_s


def script(tmp_path: Path, *lines: str) -> str:
    f = tmp_path / "s.ls"
    f.write_text("\n".join(lines) + "\n")
    return str(f)


def test_a_long_move(doomed: Controller, tmp_path: Path) -> None:
    s = script(tmp_path, "lock", "activate", "set-speed percent --speed 3",
               "move-absolute p JOINT_FRAME " + " ".join(FAR) + " --wait-timeout 120")
    proc = popen(doomed, "run", s)
    wait_for_line(proc, "move-absolute: CMD_STARTED_OK")
    err, took = kill_and_finish(doomed, proc)
    assert_one_line_exit_4(proc, err, took)


def test_path_run_does_not_wait_out_its_time_out(doomed: Controller, tmp_path: Path) -> None:
    points = tmp_path / "far.csv"
    points.write_text("j1,j2,j3,j4,j5,j6,tag_name\n" + ",".join(FAR) + ",a\n" + "0,0,0,0,0,0,b\n")
    s = script(tmp_path, "lock", "activate", "set-speed percent --speed 3", f"path load {points}",
               "path run far --cycles 5 --wait-timeout 300")
    proc = popen(doomed, "run", s)
    wait_for_line(proc, "path-move: CMD_STARTED_OK")
    err, took = kill_and_finish(doomed, proc)
    assert_one_line_exit_4(proc, err, took)


@pytest.mark.parametrize("command", [["record", "{tmp}/r.csv", "--duration", "60"],
                                     ["monitor", "--duration", "60"], ["events", "--duration", "60"]])
def test_record_monitor_events(doomed: Controller, tmp_path: Path, command: list[str]) -> None:
    proc = popen(doomed, *[c.format(tmp=tmp_path) for c in command])
    deadline = time.monotonic() + 30
    while lock_holder_pid(doomed.pty) != proc.pid:  # it has opened the pty ...
        assert proc.poll() is None and time.monotonic() < deadline, proc.communicate()
        time.sleep(0.05)
    time.sleep(1.5)  # ... and connected (a handshake and a describe: tens of ms unloaded)
    assert proc.poll() is None, proc.communicate()
    err, took = kill_and_finish(doomed, proc)
    assert_one_line_exit_4(proc, err, took)


def test_the_shell_says_it_once_and_ends_with_exit_4(doomed: Controller) -> None:
    proc = popen(doomed, "shell", stdin=subprocess.PIPE)
    assert proc.stdin is not None
    proc.stdin.write("lock\nactivate\nset-speed percent --speed 3\nmove-absolute p JOINT_FRAME "
                     + " ".join(FAR) + "\n")
    proc.stdin.flush()
    wait_for_line(proc, "move-absolute: CMD_STARTED_OK")
    t0 = time.monotonic()
    doomed.proc.send_signal(signal.SIGKILL)
    assert proc.stderr is not None
    first = ""
    while " stopped answering: " not in first:
        ready, _, _ = select.select([proc.stderr], [], [], max(0.0, t0 + EXIT_WITHIN_S - time.monotonic()))
        assert ready, "the shell said nothing after the kill"
        first = proc.stderr.readline()
        assert first, "the shell's stderr closed"
        if first.startswith(PROMPT_TOOLKIT_NOTE):
            first = ""
    took = time.monotonic() - t0
    proc.stdin.write("get-motion-control-state\n")  # the next line ends the shell
    proc.stdin.close()
    assert proc.stdout is not None
    proc.stdout.read()
    rest = proc.stderr.read()
    proc.wait(30)
    err = first + rest
    assert "Traceback" not in err and "Exception in thread" not in err, err
    assert proc.returncode == 4, err
    lines = [line for line in err.splitlines() if not line.startswith(PROMPT_TOOLKIT_NOTE)]
    assert len(lines) == 1 and " stopped answering: " in first, err
    print(f"shell: the line {took:.2f} s after the kill: {first.strip()}")  # pytest -s
    assert took < EXIT_WITHIN_S


def test_the_shell_idle_at_its_prompt_ends_when_the_device_goes(doomed: Controller) -> None:
    """Nothing typed, nothing running: the shell's own session sees the device's heartbeat
    answers stop, says it once and ends with exit 4 without waiting for a line."""
    proc = popen(doomed, "shell", stdin=subprocess.PIPE)
    assert proc.stdin is not None
    proc.stdin.write("lock\n")
    proc.stdin.flush()
    wait_for_line(proc, "lock: CMD_EXEC_OK")
    t0 = time.monotonic()
    doomed.proc.send_signal(signal.SIGKILL)
    try:
        proc.wait(timeout=EXIT_WITHIN_S + 22)  # stdin stays open: no line comes, no end of input
    except subprocess.TimeoutExpired:
        proc.kill()
        raise AssertionError(f"the shell did not exit within {EXIT_WITHIN_S + 22} s of the kill") from None
    took = time.monotonic() - t0
    assert proc.stderr is not None
    err = "\n".join(line for line in proc.stderr.read().splitlines() if not line.startswith(PROMPT_TOOLKIT_NOTE))
    proc.stdin.close()
    print(f"shell idle: exit {proc.returncode} {took:.2f} s after the kill: {err.strip()}")  # pytest -s
    assert "Traceback" not in err and "Exception in thread" not in err, err
    assert proc.returncode == 4, (proc.returncode, err)
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("landscaped at 0x10 on slcan:"), err
    assert " stopped answering: " in lines[0] and lines[0].endswith("then rerun the command"), err
    assert took < EXIT_WITHIN_S, took


def test_the_shell_through_a_background_session_ends_when_the_session_goes(doomed: Controller,
                                                                          tmp_path: Path) -> None:
    """The shell spoke through a background session that held the lock; the device dies and
    the session process with it. The shell's next line ends it with exit 4 and one line,
    never a session of its own opened without the lock and the units."""
    os.environ["XDG_RUNTIME_DIR"] = str(tmp_path)
    try:
        assert doomed.cli("session", "start", "--lock").returncode == 0
        proc = popen(doomed, "shell", stdin=subprocess.PIPE)
        assert proc.stdin is not None and proc.stderr is not None and proc.stdout is not None
        proc.stdin.write("get-motion-control-state\n")
        proc.stdin.flush()
        wait_for_line(proc, "get-motion-control-state: CMD_EXEC_OK")
        doomed.proc.send_signal(signal.SIGKILL)
        doomed.proc.wait(10)
        deadline = time.monotonic() + 10
        while doomed.cli("session", "status").returncode != 1 and time.monotonic() < deadline:
            time.sleep(0.2)  # the session process saw its device go and stopped
        proc.stdin.write("get-motion-control-state\n")
        proc.stdin.flush()
        try:
            proc.wait(timeout=EXIT_WITHIN_S + 22)
        except subprocess.TimeoutExpired:
            proc.kill()
            raise AssertionError(f"the shell did not end: {proc.communicate()}") from None
        out, err = proc.stdout.read(), proc.stderr.read()
        proc.stdin.close()
        err = "\n".join(line for line in err.splitlines() if not line.startswith(PROMPT_TOOLKIT_NOTE))
        print(f"shell through a session: exit {proc.returncode}: {err.strip()}")  # pytest -s
        assert "Traceback" not in err and proc.returncode == 4, (proc.returncode, err)
        assert len(err.splitlines()) == 1, err
        # the session gone (its socket closed), or met on its way out (it says why)
        gone = "the background session at " in err and ("and its lock and units with it" in err
                                                         or "is stopping" in err)
        assert gone or " stopped answering: " in err, err
        assert "CMD_EXEC_OK" not in out and "no controller" not in err, (out, err)
    finally:
        doomed.cli("session", "stop")
        os.environ.pop("XDG_RUNTIME_DIR", None)


def test_a_background_session_and_its_clients(doomed: Controller, tmp_path: Path) -> None:
    os.environ["XDG_RUNTIME_DIR"] = str(tmp_path)
    try:
        r = doomed.cli("session", "start", "--lock")
        assert r.returncode == 0, r.stderr
        for cmd in (["activate"], ["set-speed", "percent", "--speed", "3"]):
            r = doomed.cli(*cmd)
            assert r.returncode == 0, (cmd, r.stderr)
        mv = popen(doomed, "move-absolute", "p", "JOINT_FRAME", *FAR, "--wait-timeout", "120")
        wait_for_line(mv, "move-absolute: CMD_STARTED_OK")
        err, took = kill_and_finish(doomed, mv)
        assert_one_line_exit_4(mv, err, took)
        # the session process noticed too and stopped: later invocations do not use a dead session
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline:
            r = doomed.cli("session", "status")
            if r.returncode == 1 and "no session runs" in r.stderr:
                break  # (while it stops, one status may meet it on the way out: "went away", exit 1)
            time.sleep(0.2)
        assert r.returncode == 1 and "no session runs" in r.stderr, (r.returncode, r.stdout, r.stderr)
        assert "Traceback" not in r.stderr
    finally:
        doomed.cli("session", "stop")
        os.environ.pop("XDG_RUNTIME_DIR", None)
