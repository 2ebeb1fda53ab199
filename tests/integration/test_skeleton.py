"""Walking skeleton: landscaped + the CLI over SLCAN on a pty (docs/protocol.md "SLCAN on a pseudo-terminal")."""
from __future__ import annotations

import json
import os
import pty
import signal
from pathlib import Path

from conftest import Controller, run_cli, start_controller


def _json_lines(text: str) -> list[dict]:
    return [json.loads(line) for line in text.splitlines() if line.strip().startswith("{")]


def test_lock_state_release_in_one_session(controller: Controller, tmp_path: Path) -> None:
    script = tmp_path / "session.lsc"
    script.write_text("# one session\nget-motion-control-state\nlock\nget-motion-control-state\n"
                      "release\nget-motion-control-state\n")
    r = controller.cli("--json", "run", str(script))
    assert r.returncode == 0, r.stderr
    results = _json_lines(r.stdout)
    assert [x["command"] for x in results] == ["get-motion-control-state", "lock", "get-motion-control-state",
                                                "release", "get-motion-control-state"]
    states = [x["result"].get("state") for x in results if x["command"] == "get-motion-control-state"]
    assert states == ["UNLOCKED", "LOCKED", "UNLOCKED"]
    assert all(x["ret_code"] == 0 for x in results)


def test_lock_does_not_outlive_the_invocation(controller: Controller) -> None:
    r = controller.cli("lock")
    assert r.returncode == 0, r.stderr
    # The first invocation disconnected: its lock ended with its session.
    r = controller.cli("--json", "get-motion-control-state")
    assert r.returncode == 0, r.stderr
    assert _json_lines(r.stdout)[0]["result"]["state"] == "UNLOCKED"


def test_wrong_state_is_a_clear_error(controller: Controller) -> None:
    r = controller.cli("release")
    assert r.returncode != 0
    assert "CMD_WRONG_STATE_ERR" in r.stdout + r.stderr
    assert "LOCKED" in r.stdout + r.stderr
    assert "Traceback" not in r.stderr


def test_run_stops_at_first_error_unless_keep_going(controller: Controller, tmp_path: Path) -> None:
    script = tmp_path / "bad.lsc"
    script.write_text("release\nlock\n")
    r = controller.cli("--json", "run", str(script))
    assert r.returncode != 0
    assert [x["command"] for x in _json_lines(r.stdout)] == ["release"]
    r = controller.cli("--json", "run", "--keep-going", str(script))
    assert r.returncode != 0
    assert [x["command"] for x in _json_lines(r.stdout)] == ["release", "lock"]


def test_no_such_channel() -> None:
    r = run_cli("--interface", "slcan", "--channel", "/nonexistent/ls-pty", "lock", timeout=30)
    assert r.returncode != 0
    assert "/nonexistent/ls-pty" in r.stderr
    assert "Traceback" not in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1


def test_no_controller_answering(tmp_path: Path) -> None:
    master, slave = pty.openpty()
    link = tmp_path / "silent"
    link.symlink_to(os.ttyname(slave))
    try:
        r = run_cli("--interface", "slcan", "--channel", str(link), "--timeout", "0.5", "lock", timeout=30)
    finally:
        os.close(master)
        os.close(slave)
    assert r.returncode != 0
    assert "0x10" in r.stderr and "Traceback" not in r.stderr


def test_clean_shutdown_removes_the_link(tmp_path: Path) -> None:
    for sig in (signal.SIGINT, signal.SIGTERM):
        path = tmp_path / f"ls-{sig}"
        c = start_controller(path)
        assert path.is_symlink()
        assert c.stop(sig) == 0
        assert not path.exists() and not path.is_symlink()


def test_bad_options_are_refused(tmp_path: Path) -> None:
    import subprocess

    from conftest import LANDSCAPED
    for args, needle in ((["--hal", "sim"], "--link"), (["--hal", "real", "--link", "slcan:pty:/tmp/x"], "--hal"),
                         (["--hal", "sim", "--link", "bogus:x"], "unknown link"),
                         (["--hal", "sim", "--link", "slcan:pty:/tmp/x", "--node", "0x1FF"], "--node")):
        r = subprocess.run([str(LANDSCAPED), *args], capture_output=True, text=True, timeout=10)
        assert r.returncode != 0
        assert needle in r.stderr
