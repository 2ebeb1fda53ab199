"""landscaped composes HAL backends from options; a missing AF_CAN, CAN
interface or gpiochip gives one clear message naming the cause and the fix,
never a crash or a hang (on a machine without CAN and GPIO: docs/deploy.md)."""
from __future__ import annotations

import socket
import subprocess
from pathlib import Path

import pytest

from conftest import CLI, LANDSCAPED, stop_process, wait_for_path


def _run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([str(LANDSCAPED), *args], capture_output=True, text=True, timeout=20)


def _have_af_can() -> bool:
    try:
        socket.socket(socket.AF_CAN, socket.SOCK_RAW, socket.CAN_RAW).close()
        return True
    except OSError:
        return False


def test_missing_can_support_or_interface_is_named_with_the_fix() -> None:
    r = _run("--link", "socketcan:nosuchcan0", "--arm", "none", "--dio", "none")
    assert r.returncode != 0
    errors = [line for line in r.stderr.splitlines() if "error" in line]
    assert len(errors) == 1
    if _have_af_can():
        assert "nosuchcan0" in errors[0] and "ip link" in errors[0]
    else:
        assert "AF_CAN" in errors[0] and "modprobe" in errors[0] and "slcan:pty" in errors[0]


def test_missing_gpiochip_is_named_with_the_fix(tmp_path: Path) -> None:
    if Path("/dev/gpiochip99").exists():
        pytest.fail("this machine has /dev/gpiochip99: the test needs a chip name that does not exist")
    r = _run("--link", f"slcan:pty:{tmp_path / 'ls'}", "--arm", "none", "--dio", "gpiod:gpiochip99")
    assert r.returncode != 0
    errors = [line for line in r.stderr.splitlines() if "error" in line]
    assert len(errors) == 1 and "gpiochip99" in errors[0] and "/dev/gpiochip" in errors[0]
    assert not (tmp_path / "ls").exists()  # the pty link opened first is removed again


def test_sim_dio_needs_the_sim_arm() -> None:
    r = _run("--link", "slcan:pty:/tmp/ls-never", "--arm", "none", "--dio", "sim")
    assert r.returncode != 0 and "arm = sim" in r.stderr


def test_check_names_every_problem_and_fails() -> None:
    r = _run("--check", "--link", "socketcan:can0", "--dio", "gpiod:gpiochip0", "--arm", "none")
    assert r.returncode != 0
    fails = [line for line in r.stdout.splitlines() if line.startswith("FAIL")]
    assert any("can0" in f or "AF_CAN" in f for f in fails)
    assert any("gpiochip0" in f for f in fails)


def test_activate_without_an_arm_says_nothing_can_be_enabled(tmp_path: Path) -> None:
    """With arm = none, activate is refused and the CLI says why in one line: never "drives
    enabled" followed by a move that fails."""
    pty = tmp_path / "ls0"
    proc = subprocess.Popen([str(LANDSCAPED), "--link", f"slcan:pty:{pty}", "--arm", "none", "--dio", "none"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        wait_for_path(pty, proc)
        script = tmp_path / "activate.lsc"
        script.write_text("lock\nactivate\n")
        r = subprocess.run([str(CLI), "--interface", "slcan", "--channel", str(pty), "run", str(script)],
                           capture_output=True, text=True, timeout=60)
    finally:
        assert stop_process(proc, "landscaped") == 0
    assert r.returncode == 3, r
    assert "Traceback" not in r.stdout + r.stderr and "drives enabled" not in r.stdout + r.stderr
    why = "activate failed, the drives are off: no arm backend is composed (arm = none): nothing can be enabled"
    assert f"{script}:2: activate: CMD_ERR: {why}" in r.stderr.splitlines(), r.stderr
