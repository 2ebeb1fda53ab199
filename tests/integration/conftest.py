"""Integration tier: start the built landscaped (sim HAL, SLCAN on a pty) and
drive it through the host library and the CLI."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import can
import pytest

ROOT = Path(__file__).resolve().parents[2]
BUILD = Path(os.environ.get("LS_BUILD_DIR", ROOT / "build"))
LANDSCAPED = BUILD / "bin" / "landscaped"
CLI = Path(sys.executable).parent / "landscape"


@dataclass
class Controller:
    pty: str
    proc: subprocess.Popen[bytes]
    log: Path

    def cli(self, *args: str, timeout: float = 60.0, check: bool = False) -> subprocess.CompletedProcess[str]:
        return run_cli("--interface", "slcan", "--channel", self.pty, *args, timeout=timeout, check=check)

    def stop(self, sig: int = signal.SIGTERM) -> int:
        if self.proc.poll() is None:
            self.proc.send_signal(sig)
        try:
            return self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            raise AssertionError("landscaped did not stop within 10 s of a signal") from None


def run_cli(*args: str, timeout: float = 60.0, check: bool = False) -> subprocess.CompletedProcess[str]:
    return subprocess.run([str(CLI), *args], capture_output=True, text=True, timeout=timeout, check=check)


def wait_for_path(path: Path, proc: subprocess.Popen[bytes], timeout_s: float = 10.0) -> None:
    """Wait until landscaped (`proc`) has made `path` (a pty link or a socket); fail when it
    exits first or the time runs out."""
    deadline = time.monotonic() + timeout_s
    while not path.exists():
        assert proc.poll() is None, f"landscaped exited with {proc.returncode} before {path} appeared"
        assert time.monotonic() < deadline, f"{path} did not appear within {timeout_s:g} s"
        time.sleep(0.02)


def start_controller(path: Path, *extra: str) -> Controller:
    if not LANDSCAPED.exists():
        raise AssertionError(f"{LANDSCAPED} is missing: build first (bash .ci/build)")
    # stderr to a file, never a pipe: a pipe nobody reads would block the controller's logging
    log = path.with_name(path.name + ".log")
    with open(log, "wb") as err_file:
        proc = subprocess.Popen([str(LANDSCAPED), "--hal", "sim", "--link", f"slcan:pty:{path}", *extra],
                                stdout=subprocess.DEVNULL, stderr=err_file)
    deadline = time.monotonic() + 10
    while not path.exists():
        if proc.poll() is not None:
            err = log.read_text(errors="replace")
            raise AssertionError(f"landscaped exited with {proc.returncode}: {err}")
        if time.monotonic() > deadline:
            proc.kill()
            raise AssertionError("landscaped did not create its pty link within 10 s")
        time.sleep(0.02)
    return Controller(str(path), proc, log)


@pytest.fixture
def controller(tmp_path: Path) -> Iterator[Controller]:
    c = start_controller(tmp_path / "ls0")
    try:
        yield c
    finally:
        code = c.stop()
        # A crash, a sanitizer report or a leak at shutdown must fail the test that caused it.
        log = c.log.read_text(errors="replace")
        assert code == 0, f"landscaped exited with {code}:\n{log[-4000:]}"
        assert "Sanitizer" not in log, log[-4000:]


def open_slcan(pty: str) -> can.BusABC:
    """python-can's slcan interface on a controller's pty (no 2 s sleep after open)."""
    return can.Bus(interface="slcan", channel=pty, bitrate=1000000, sleep_after_open=0)


@pytest.fixture
def bus(controller: Controller) -> Iterator[can.BusABC]:
    b = open_slcan(controller.pty)
    try:
        yield b
    finally:
        b.shutdown()


@pytest.fixture
def notifier(bus: can.BusABC) -> Iterator[can.Notifier]:
    n = can.Notifier(bus, [], timeout=0.01)
    try:
        yield n
    finally:
        n.stop()
