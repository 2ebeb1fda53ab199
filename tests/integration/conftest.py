"""Integration tier: start the built landscaped (sim HAL, SLCAN on a pty) and
drive it through the host library and the CLI.

The arm behind landscaped is the environment's `LS_ARM`: `sim` (the default: the
simulated arm in landscaped's process) or `cia402`: the same simulated arm behind six
CiA 402 drives, `ls-simdrives`, on a drive bus of its own (an SLCAN pty the drives
offer, landscaped's `[drives] link = slcan:tty:PATH`). The motion and lifecycle suites
run on both (ctest pytest_drives); what needs the simulated world inside landscaped
(its DIO, sensors, tool rack, set-point trace) runs on `sim` only."""
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

from landscape import telemetry as tm
from landscape._generated import landscape_pb2 as pb
from landscape.supervisor import Supervisor

ROOT = Path(__file__).resolve().parents[2]
BUILD = Path(os.environ.get("LS_BUILD_DIR", ROOT / "build"))
LANDSCAPED = BUILD / "bin" / "landscaped"
SIMDRIVES = BUILD / "bin" / "ls-simdrives"
SIMDRIVE_EDS = BUILD / "share" / "landscape" / "ls-simdrive.eds"
CLI = Path(sys.executable).parent / "landscape"
ARM = os.environ.get("LS_ARM", "sim")
DRIVE_NODES = (0x21, 0x22, 0x23, 0x24, 0x25, 0x26)
COUNTS_PER_RAD = 2**17 * 100 / (2 * 3.141592653589793)  # a 17-bit encoder behind a 100:1 gear


@dataclass
class Controller:
    pty: str
    proc: subprocess.Popen[bytes]
    log: Path
    drives: subprocess.Popen[bytes] | None = None  # ls-simdrives, with LS_ARM=cia402
    drives_control: Path | None = None  # its misbehaviour socket

    def cli(self, *args: str, timeout: float = 60.0, check: bool = False) -> subprocess.CompletedProcess[str]:
        return run_cli("--interface", "slcan", "--channel", self.pty, *args, timeout=timeout, check=check)

    def stop(self, sig: int = signal.SIGTERM) -> int:
        try:
            return stop_process(self.proc, "landscaped", sig)
        finally:
            stop_drives(self.drives)


def stop_process(proc: subprocess.Popen[bytes], name: str, sig: int = signal.SIGTERM) -> int:
    """Send `sig` to a program a test started (when it still runs) and wait for its exit
    code; kill it and fail when it has not stopped within 10 s."""
    if proc.poll() is None:
        proc.send_signal(sig)
    try:
        return proc.wait(timeout=10)
    except subprocess.TimeoutExpired:
        proc.kill()
        raise AssertionError(f"{name} did not stop within 10 s of a signal") from None


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


def stop_drives(drives: subprocess.Popen[bytes] | None) -> None:
    if drives is not None and drives.poll() is None:
        drives.send_signal(signal.SIGTERM)
        try:
            drives.wait(timeout=10)
        except subprocess.TimeoutExpired:
            drives.kill()


def start_simdrives(path: Path, *extra: str) -> tuple[subprocess.Popen[bytes], Path]:
    """ls-simdrives offering its drive bus as an SLCAN pty at `path`; returns the process
    and its misbehaviour socket."""
    if not SIMDRIVES.exists():
        raise AssertionError(f"{SIMDRIVES} is missing: build first (bash .ci/build)")
    control = path.with_name(path.name + ".ctl")
    with open(path.with_name(path.name + ".log"), "wb") as err_file:
        # SCHED_FIFO (when granted) below landscaped's control thread: the drives answer each
        # SYNC in time while builds share the machine, as hardware would
        proc = subprocess.Popen([str(SIMDRIVES), "--link", f"slcan:pty:{path}", "--control", str(control),
                                 "--counts-per-rad", repr(COUNTS_PER_RAD), "--rt-priority", "60", *extra],
                                stdout=subprocess.DEVNULL, stderr=err_file)
    wait_for_path(path, proc)
    return proc, control


def drive_config(path: Path, drive_pty: Path, joints: dict[int, dict[str, str]] | None = None,
                 **drives: str) -> Path:
    """A landscaped.conf for arm = cia402 on `drive_pty`: six joints of ls-simdrives;
    `drives` sets more [drives] keys, `joints` more [joint.N] keys (N = 1..6)."""
    # ls-simdrives is a process on a machine the test shares with builds: even at SCHED_FIFO
    # it was seen answering a SYNC over 100 ms late there (once in a few runs of a module
    # whose other tests load both cores), where a drive would not; so the suites allow
    # 200 ms of missing feedback (the default, 5 cycles, is docs/deploy.md's).
    drives = {"stale_cycles": "50", **drives}
    lines = ["[hal]", "arm = cia402", "dio = none", "[drives]", f"link = slcan:tty:{drive_pty}",
             *(f"{k} = {v}" for k, v in drives.items())]
    for j, node in enumerate(DRIVE_NODES):
        lines += [f"[joint.{j + 1}]", f"node = {node:#x}", f"eds = {SIMDRIVE_EDS}",
                  f"counts_per_rad = {COUNTS_PER_RAD!r}",
                  *(f"{k} = {v}" for k, v in (joints or {}).get(j + 1, {}).items())]
    path.write_text("\n".join(lines) + "\n")
    return path


def start_controller(path: Path, *extra: str, joints: dict[int, dict[str, str]] | None = None,
                     drive_keys: dict[str, str] | None = None) -> Controller:
    """landscaped on a new pty at `path` with `extra` options; with LS_ARM=cia402 behind
    ls-simdrives, `drive_keys` setting more [drives] keys and `joints` more [joint.N] keys
    of its configuration (drive_config)."""
    if not LANDSCAPED.exists():
        raise AssertionError(f"{LANDSCAPED} is missing: build first (bash .ci/build)")
    # stderr to a file, never a pipe: a pipe nobody reads would block the controller's logging
    log = path.with_name(path.name + ".log")
    drives: subprocess.Popen[bytes] | None = None
    control: Path | None = None
    if ARM == "cia402":
        # the drives move the arm landscaped is told of: the same model file
        model = [a for i, a in enumerate(extra) if i > 0 and extra[i - 1] == "--model"]
        drives, control = start_simdrives(path.with_name(path.name + "-drives"),
                                          *(["--model", model[0]] if model else []))
        conf = drive_config(path.with_name(path.name + "-drives.conf"), path.with_name(path.name + "-drives"),
                            joints, **(drive_keys or {}))
        hal = ["--config", str(conf)]
    else:
        hal = ["--hal", "sim"]
    with open(log, "wb") as err_file:
        proc = subprocess.Popen([str(LANDSCAPED), *hal, "--link", f"slcan:pty:{path}", *extra],
                                stdout=subprocess.DEVNULL, stderr=err_file)
    deadline = time.monotonic() + 10
    # with drives, the control loop (and the link's answers) start once they are configured
    ready = "ready: node" if drives is not None else None
    while not path.exists() or (ready is not None and ready not in log.read_text(errors="replace")):
        if proc.poll() is not None:
            err = log.read_text(errors="replace")
            stop_drives(drives)
            raise AssertionError(f"landscaped exited with {proc.returncode}: {err}")
        if time.monotonic() > deadline:
            proc.kill()
            stop_drives(drives)
            raise AssertionError("landscaped did not create its pty link (and boot its drives) within 10 s")
        time.sleep(0.02)
    return Controller(str(path), proc, log, drives, control)


@pytest.fixture
def controller(tmp_path: Path) -> Iterator[Controller]:
    c = start_controller(tmp_path / "ls0")
    try:
        yield c
    finally:
        stop_clean(c)


def stop_clean(c: Controller) -> None:
    """Stop a controller a test started. A crash, a sanitizer report or a leak at shutdown
    must fail the test that caused it."""
    code = c.stop()
    log = c.log.read_text(errors="replace")
    assert code == 0, f"landscaped exited with {code}:\n{log[-4000:]}"
    assert "Sanitizer" not in log, log[-4000:]


def final_notice(sup: Supervisor, seq: int, seen: list[pb.Notice], timeout_s: float = 10) -> pb.Notice:
    """The final notice of request `seq`; every notice until then goes to `seen`."""
    for n in sup.notices(timeout_s=timeout_s):
        seen.append(n)
        if n.ref_seq == seq and n.final:
            return n
    raise AssertionError(f"no final notice for seq {seq} within {timeout_s} s")


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


class BroadcastMotion:
    """STATUS st_motion as the broadcast says it, by its DBC value name (docs/protocol.md:
    getMotionControlState's motion_control_state is that name): what a client that reads only
    the broadcast learns."""

    def __init__(self, sup: Supervisor) -> None:
        self._last: int | None = None
        sup.on_telemetry(self._on)

    def _on(self, b: object) -> None:
        if getattr(b, "name", "") == "STATUS":
            self._last = int(b.signals["st_motion"])  # type: ignore[attr-defined]

    def now(self, settle_s: float = 0.15) -> str:
        """The name in the STATUS frames after `settle_s` (a few telemetry periods)."""
        self._last = None
        time.sleep(settle_s)
        assert self._last is not None, f"no STATUS broadcast within {settle_s} s"
        return tm.choice_name("STATUS", "st_motion", self._last)


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers", "sim_world: needs the simulated world inside landscaped (its DIO, sensors, tool rack, set-point "
                   "trace): runs with LS_ARM=sim only (the cia402 tier deselects it with -m 'not sim_world')")


@pytest.hookimpl(trylast=True)  # after -m has deselected what it deselects
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """A sim_world test selected for the drive arm is a mistake in the selection: stop
    with the list rather than let it fail on a missing DIO or pass on nothing."""
    if ARM != "cia402":
        return
    wrong = [item.nodeid for item in items if item.get_closest_marker("sim_world") is not None]
    if wrong:
        raise pytest.UsageError(f"LS_ARM=cia402 has no simulated world for {', '.join(wrong)}: "
                                "select with -m 'not sim_world'")
