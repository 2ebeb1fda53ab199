"""VM tier checks, run inside the QEMU guest by tests/vm/guest.sh.

The guest has real SocketCAN buses (vcan0 and the drive bus vcan1, with the
kernel's CAN_RAW and CAN_ISOTP), a real GPIO chip (gpio-sim, 8 lines) and
uinput (virtual input devices, made here with python evdev). guest.sh exports:
  LS_VM_CAN_IF      the CAN interface (vcan0)
  LS_VM_DRIVE_IF    the drive bus (vcan1)
  LS_VM_GPIO_CHIP   the gpio-sim chip (gpiochipN)
  LS_VM_GPIO_SYSFS  its sysfs dir (.../gpio-sim.N/gpiochipN with sim_gpioK/{value,pull})
  LS_BUILD_DIR      the build tree (bin/isotp_socketcan_echo, bin/landscaped)
Guest code runs ~20x slower than on the host (TCG): time-outs are generous and
the checks few and end to end.
"""
from __future__ import annotations

import math
import os
import re
import shutil
import signal
import socket
import struct
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import pytest
from evdev import AbsInfo, UInput
from evdev import ecodes as e

from landscape import BusSpec, RetVal, Supervisor
from landscape._generated import landscape_pb2 as pb
from landscape.supervisor import notice_data

if TYPE_CHECKING:
    import canopen

CAN_IF = os.environ.get("LS_VM_CAN_IF", "vcan0")
GPIO_CHIP = os.environ.get("LS_VM_GPIO_CHIP", "")
GPIO_SYSFS = Path(os.environ.get("LS_VM_GPIO_SYSFS", "/nonexistent"))
ROOT = Path(__file__).resolve().parents[2]
BUILD = Path(os.environ.get("LS_BUILD_DIR", ROOT / "build"))
ECHO = BUILD / "bin" / "isotp_socketcan_echo"

# ISO-TP normal fixed 29-bit addressing, the schema's default device and host addresses.
HOST_TO_DEV = pb.ISOTP_PHYSICAL_BASE | pb.DEFAULT_DEVICE_ADDRESS << 8 | pb.DEFAULT_HOST_ADDRESS
DEV_TO_HOST = pb.ISOTP_PHYSICAL_BASE | pb.DEFAULT_HOST_ADDRESS << 8 | pb.DEFAULT_DEVICE_ADDRESS

# Linux <linux/can/isotp.h>: socket options Python does not name.
SOL_CAN_ISOTP = 100 + socket.CAN_ISOTP  # SOL_CAN_BASE + CAN_ISOTP
CAN_ISOTP_RECV_FC = 2

pytestmark = pytest.mark.skipif(not hasattr(socket, "AF_CAN"), reason="not a Linux Python")


def payload(n: int, seed: int = 0) -> bytes:
    return bytes((seed + 7 * i) & 0xFF for i in range(n))


# ---------------------------------------------------------------- the guest itself


def test_vcan_carries_raw_frames() -> None:
    """The bus the other checks rely on: a raw 29-bit frame sent on vcan0 by
    one socket is received by another."""
    with socket.socket(socket.AF_CAN, socket.SOCK_RAW, socket.CAN_RAW) as rx, \
            socket.socket(socket.AF_CAN, socket.SOCK_RAW, socket.CAN_RAW) as tx:
        rx.bind((CAN_IF,))
        rx.settimeout(5)
        tx.bind((CAN_IF,))
        tx.send(struct.pack("=IB3x8s", 0x1ABCDE01 | socket.CAN_EFF_FLAG, 3, b"\x01\x02\x03"))
        can_id, dlc, data = struct.unpack("=IB3x8s", rx.recv(16))
        assert (can_id, dlc, data[:dlc]) == (0x1ABCDE01 | socket.CAN_EFF_FLAG, 3, b"\x01\x02\x03")


def test_gpio_sim_lines_follow_gpioset_and_pulls() -> None:
    """gpio-sim works with the libgpiod tools: a line driven by gpioset shows
    in sysfs, a pull set in sysfs shows in gpioget."""
    assert GPIO_CHIP, "guest.sh did not export LS_VM_GPIO_CHIP"
    out = subprocess.run(["gpiodetect"], capture_output=True, text=True, timeout=30, check=True).stdout
    assert re.search(rf"^{GPIO_CHIP} \[.*\] \(8 lines\)$", out, re.M), out
    # gpioset (libgpiod v1) holds the line until it exits; --mode=signal keeps it.
    p = subprocess.Popen(["gpioset", "--mode=signal", GPIO_CHIP, "5=1"])
    try:
        value = GPIO_SYSFS / "sim_gpio5" / "value"
        deadline = time.monotonic() + 20
        while value.read_text().strip() != "1" and time.monotonic() < deadline:
            time.sleep(0.05)
        assert value.read_text().strip() == "1"
    finally:
        p.terminate()
        p.wait(timeout=20)
    (GPIO_SYSFS / "sim_gpio2" / "pull").write_text("pull-up")
    up = subprocess.run(["gpioget", GPIO_CHIP, "2"], capture_output=True, text=True, timeout=30, check=True)
    (GPIO_SYSFS / "sim_gpio2" / "pull").write_text("pull-down")
    down = subprocess.run(["gpioget", GPIO_CHIP, "2"], capture_output=True, text=True, timeout=30, check=True)
    assert (up.stdout.strip(), down.stdout.strip()) == ("1", "0")


def linux_hal_groups() -> list[dict[str, bool]]:
    """Runs the Linux HAL's CMocka tests (test_linux_hal); returns per group
    (socketcan, gpiod, rt, slcan tty: the order of test_linux_main.c) each test's outcome."""
    exe = BUILD / "bin" / "test_linux_hal"
    assert exe.exists(), f"{exe} missing: build first"
    r = subprocess.run([str(exe)], capture_output=True, text=True, timeout=240)
    groups: list[dict[str, bool]] = []
    for chunk in r.stdout.split("[==========] Running")[1:]:
        outcome = {m[1]: m[0] == "OK" for m in re.findall(r"^\[ +(OK|FAILED) +\] (\w+)$", chunk, re.M)}
        groups.append(outcome)
    assert len(groups) == 4, f"expected 4 test groups (socketcan, gpiod, rt, slcan tty):\n{r.stdout}{r.stderr}"
    assert (r.returncode == 0) == all(all(g.values()) for g in groups), r.stdout + r.stderr
    return groups


@pytest.fixture(scope="module")
def hal_groups() -> list[dict[str, bool]]:
    return linux_hal_groups()


def test_linux_hal_socketcan_and_gpiod_tests_with_real_kernel_support(hal_groups: list[dict[str, bool]]) -> None:
    """The Linux HAL's CMocka tests, here on a kernel with AF_CAN and GPIO."""
    socketcan, gpiod, _, slcan_tty = hal_groups
    assert len(socketcan) == 10 and len(gpiod) == 4 and len(slcan_tty) == 4, hal_groups
    failed = [name for g in (socketcan, gpiod, slcan_tty) for name, ok in g.items() if not ok]
    assert failed == []


@pytest.mark.xfail(reason="TCG emulation: a 1 ms SCHED_FIFO loop overruns in the guest (timing tests of "
                          "hal_linux_rt assume real hardware); tracked, not a HAL defect", strict=False)
def test_linux_hal_rt_tests_under_emulation(hal_groups: list[dict[str, bool]]) -> None:
    rt = hal_groups[2]
    assert [name for name, ok in rt.items() if not ok] == []


# ---------------------------------------------------------------- ISO-TP interop


class EchoPeer:
    """isotp_socketcan_echo: the firmware's ls_isotp over the Linux HAL's SocketCAN link."""

    def __init__(self) -> None:
        assert ECHO.exists(), f"{ECHO} missing: build first (bash .ci/build)"
        self.proc = subprocess.Popen([str(ECHO), CAN_IF, "-t", "200"], stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, text=True)
        assert self.proc.stdout is not None
        first = self.proc.stdout.readline()
        if first.strip() != f"ready socketcan:{CAN_IF}":
            self.proc.kill()
            _, err = self.proc.communicate(timeout=20)
            raise AssertionError(f"isotp_socketcan_echo did not start: {first!r} {err}")

    def stop(self) -> tuple[list[str], str]:
        """Stops the peer; returns its 'echo N' lines and its summary line."""
        if self.proc.poll() is None:
            self.proc.terminate()
        out, err = self.proc.communicate(timeout=30)
        assert self.proc.returncode == 0, err
        return out.split("\n")[:-1], err.strip()


@pytest.fixture
def echo_peer() -> Iterator[EchoPeer]:
    peer = EchoPeer()
    try:
        yield peer
    finally:
        if peer.proc.poll() is None:
            peer.proc.kill()
            peer.proc.wait(timeout=30)


def hex_words(data: bytes) -> str:
    return " ".join(f"{b:02X}" for b in data)


def wait_blocked_in_read(pid: int, timeout_s: float = 30.0) -> None:
    """Waits until process `pid` sits in read(2) (x86-64 syscall 0): isotprecv
    has bound its socket and waits for a message, so nothing sent later is lost."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        try:
            if Path(f"/proc/{pid}/syscall").read_text().split()[0] == "0":
                return
        except (OSError, IndexError):
            pass
        time.sleep(0.02)
    raise AssertionError(f"process {pid} did not block in read() within {timeout_s} s")


@pytest.mark.parametrize("size", [5, 200])
def test_can_utils_isotpsend_isotprecv_echo(echo_peer: EchoPeer, size: int) -> None:
    """can-utils (kernel CAN_ISOTP) sends a single-frame (5 B) or a
    multi-frame (200 B) message; the firmware's ISO-TP echoes it back."""
    data = payload(size, seed=size)
    ids = ["-s", f"{HOST_TO_DEV:08X}", "-d", f"{DEV_TO_HOST:08X}"]  # 8 digits: extended ids
    recv = subprocess.Popen(["isotprecv", *ids, CAN_IF], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        wait_blocked_in_read(recv.pid)
        send = subprocess.run(["isotpsend", *ids, CAN_IF], input=hex_words(data), capture_output=True, text=True,
                              timeout=60)
        assert send.returncode == 0, send.stderr
        out, err = recv.communicate(timeout=60)
    finally:
        if recv.poll() is None:
            recv.kill()
            recv.wait()
    assert recv.returncode == 0, err
    assert bytes.fromhex(out) == data
    lines, summary = echo_peer.stop()
    assert lines == [f"echo {size}"]
    assert "echoed 1, rx ok 1, tx ok 1" in summary, summary


def isotp_socket(bs: int | None = None, stmin: int | None = None) -> socket.socket:
    s = socket.socket(socket.AF_CAN, socket.SOCK_DGRAM, socket.CAN_ISOTP)
    if bs is not None and stmin is not None:
        # Flow control this socket sends as a receiver: block size, STmin, max FC.WAIT.
        s.setsockopt(SOL_CAN_ISOTP, CAN_ISOTP_RECV_FC, struct.pack("=BBB", bs, stmin, 0))
    s.bind((CAN_IF, DEV_TO_HOST | socket.CAN_EFF_FLAG, HOST_TO_DEV | socket.CAN_EFF_FLAG))
    s.settimeout(30)
    return s


def test_python_isotp_socket_echo_of_every_frame_shape(echo_peer: EchoPeer) -> None:
    """A Python CAN_ISOTP socket exchanges messages of 1 B, 7 B (largest
    single frame), 8 B (smallest first frame), 200 B and 4095 B (largest)."""
    sizes = [1, 7, 8, 200, 4095]
    with isotp_socket() as s:
        for i, n in enumerate(sizes):
            data = payload(n, seed=i)
            s.send(data)
            assert s.recv(4096) == data, f"echo of {n} bytes differs"
    lines, summary = echo_peer.stop()
    assert lines == [f"echo {n}" for n in sizes]
    assert f"echoed {len(sizes)}, rx ok {len(sizes)}, tx ok {len(sizes)}, last error N_OK" in summary, summary


def test_firmware_sender_honours_kernel_flow_control(echo_peer: EchoPeer) -> None:
    """The kernel receiver asks for block size 4 and STmin 10 ms: the firmware's
    sender waits for each flow control and keeps 10 ms between the consecutive
    frames of a block (the first CF of a block goes at once, ls_isotp.h).
    200 B = first frame + 28 CFs = 7 blocks of 4, so at least 7 x 3 gaps."""
    data = payload(200, seed=9)
    with isotp_socket(bs=4, stmin=10) as s:
        s.send(data)
        t0 = time.monotonic()
        got = s.recv(4096)
        elapsed = time.monotonic() - t0
    assert got == data
    assert elapsed >= 21 * 0.010, f"echo took {elapsed * 1000:.1f} ms: STmin 10 ms was not honoured"
    _, summary = echo_peer.stop()
    assert "echoed 1, rx ok 1, tx ok 1, last error N_OK" in summary, summary


# ---------------------------------------------------------------- landscaped on vcan0 + gpio-sim
#
# Feature probes: these checks need landscaped options that land on main in
# steps. A missing feature skips its checks with a reason naming it, so the
# summary (-rs) shows what waits; a missing binary fails them.

LANDSCAPED = BUILD / "bin" / "landscaped"
CLI = Path(sys.executable).parent / "landscape"
INPUT_LINES = [0, 1, 2, 3]    # gpio-sim lines read as DIO inputs, bits 0..3
OUTPUT_LINES = [4, 5, 6, 7]   # gpio-sim lines driven as DIO outputs, bits 16..19




def landscaped_args(tmp: Path, node: int, dio: str, rt_priority: int = 50, conf: str = "",
                    arm: str = "sim") -> list[str]:
    """Options for one controller on vcan0, by default with the real-time
    (SCHED_FIFO) control thread. Under TCG the simulated arm's loop takes most
    of a vCPU even at 100 Hz, and SCHED_FIFO leaves normal threads 5 %: two
    real-time controllers on the guest's 2 vCPUs starve the host tool, so a
    second controller runs a normal thread. Telemetry is 2 Hz: at 50 Hz (7
    frames each) the emulated host tool cannot keep up with the bus and
    misses its ISO-TP time-outs. The heartbeat time-out is 10 s: the emulated
    host tool's 200 ms heartbeats arrive more than 1 s apart at times. The DIO line offsets are the
    [dio] keys of a --config file (docs/deploy.md), and `conf` more of that file (e.g. [manual],
    or the [drives] and [joint.N] of arm = cia402)."""
    args = ["--link", f"socketcan:{CAN_IF}", "--arm", arm, "--node", f"{node:#04x}",
            "--rt-priority", str(rt_priority), "--rate", "100", "--telemetry-hz", "2",
            "--heartbeat-timeout", "10000", "--name", f"vm-{node:02x}"]
    if dio.startswith("gpiod:"):
        ins, outs = ",".join(map(str, INPUT_LINES)), ",".join(map(str, OUTPUT_LINES))
        conf = f"[hal]\ndio = {dio}\n[dio]\ninputs = {ins}\noutputs = {outs}\n{conf}"
    else:
        args += ["--dio", dio]
    if conf:
        path = tmp / f"landscaped-{node:02x}.conf"
        path.write_text(conf)
        args = ["--config", str(path), *args]
    return args


class Landscaped:
    def __init__(self, tmp: Path, node: int, dio: str, rt_priority: int = 50, conf: str = "", arm: str = "sim",
                 ready_s: float = 60) -> None:
        assert LANDSCAPED.exists(), f"{LANDSCAPED} missing: build first (bash .ci/build)"
        self.node = node
        self.log = tmp / f"landscaped-{node:02x}.log"
        with self.log.open("w") as f:
            self.proc = subprocess.Popen([str(LANDSCAPED), *landscaped_args(tmp, node, dio, rt_priority, conf, arm)],
                                         stdout=subprocess.DEVNULL, stderr=f)
        deadline = time.monotonic() + ready_s
        while f"ready: node 0x{node:02X}" not in self.log.read_text():
            if self.proc.poll() is not None or time.monotonic() > deadline:
                self.stop()
                raise AssertionError(f"landscaped --node {node:#04x} did not get ready:\n{self.log.read_text()}")
            time.sleep(0.1)

    def stop(self) -> int:
        if self.proc.poll() is None:
            self.proc.terminate()
        try:
            return self.proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
            raise AssertionError(f"landscaped --node {self.node:#04x} did not stop within 30 s of SIGTERM") from None


def sysfs_line(n: int, attr: str) -> Path:
    return GPIO_SYSFS / f"sim_gpio{n}" / attr


def set_pulls(pull: str) -> None:
    for n in INPUT_LINES:
        sysfs_line(n, "pull").write_text(pull)


def wait_for(pred: Callable[[], bool], timeout_s: float, what: str) -> None:
    deadline = time.monotonic() + timeout_s
    while not pred():
        assert time.monotonic() < deadline, f"{what} within {timeout_s} s"
        time.sleep(0.05)


def log_dir(tmp: Path) -> Path:
    """Where landscaped's logs go: the host-visible output dir when there is one."""
    out = os.environ.get("LS_VM_OUT")
    return Path(out) if out else tmp


@pytest.fixture
def controller(tmp_path: Path) -> Iterator[Landscaped]:
    """Node 0x10 with gpio-sim DIO, one per test: it holds the DIO lines, which
    the --check tests need free, and no state leaks from one test to the next."""
    set_pulls("pull-down")
    c = Landscaped(log_dir(tmp_path), 0x10, f"gpiod:{GPIO_CHIP}")
    try:
        yield c
    finally:
        rc = c.stop()
        assert rc == 0, f"landscaped exited with {rc}:\n{c.log.read_text()}"


def supervisor(device: int, source: int, name: str) -> Supervisor:
    return Supervisor.open_bus(BusSpec("socketcan", CAN_IF), device=device, source_address=source,
                               client_name=name, timeout_s=5.0)


def test_cli_session_moves_the_arm_over_socketcan(controller: Landscaped, tmp_path: Path) -> None:
    """The host CLI on python-can's socketcan interface: connect, lock,
    activate, a joint move to completion, deactivate, release, in one run."""
    script = tmp_path / "session.lsc"
    script.write_text("connect\nlock\nactivate\n"
                      "move-absolute p1 JOINT_FRAME 0.2 -0.3 0.25 0 0.1 0 --speed-pct 50\n"
                      "get-motion-control-state\ndeactivate\nrelease\n")
    r = subprocess.run([str(CLI), "--interface", "socketcan", "--channel", CAN_IF, "--device", "0x10",
                        "run", str(script)], capture_output=True, text=True, timeout=240)
    assert r.returncode == 0, f"exit {r.returncode}\n{r.stdout}\n{r.stderr}"
    out = r.stdout
    for cmd in ("lock", "activate", "deactivate", "release"):
        assert f"\n{cmd}: CMD_EXEC_OK" in out, out
    assert "\nmove-absolute: CMD_STARTED_OK" in out, out
    done = re.search(r"EVENT moveAbsoluteComplete point=p1 reason=complete joints=(\S+) .*final", out)
    assert done, out
    joints = [float(v) for v in done[1].split(",")]
    assert joints == pytest.approx([0.2, -0.3, 0.25, 0, 0.1, 0], abs=2e-3)


def test_set_digital_io_drives_gpio_sim_lines(controller: Landscaped) -> None:
    """setDigitalIO output bits 16 and 18 are gpio-sim lines 4 and 6: their
    values in sysfs follow, the other outputs stay low."""
    with supervisor(0x10, 0xF1, "vm-dio") as sup:
        sup.lock()
        values = lambda: [sysfs_line(n, "value").read_text().strip() for n in OUTPUT_LINES]  # noqa: E731
        wait_for(lambda: values() == ["0", "0", "0", "0"], 10, "outputs not all low at start")
        sup.set_digital_io("digital", 0, bits_on=0x00050000)
        wait_for(lambda: values() == ["1", "0", "1", "0"], 10, "lines 4 and 6 did not go high")
        assert sup.get_digital_io("digital", 0).result["bits_on"] & 0xFFFF0000 == 0x00050000
        sup.set_digital_io("digital", 0, bits_off=0x00010000)
        wait_for(lambda: values() == ["0", "0", "1", "0"], 10, "line 4 did not go low")
        sup.set_digital_io("digital", 0, bits_off=0x00040000)
        wait_for(lambda: values() == ["0", "0", "0", "0"], 10, "line 6 did not go low")
        sup.release()


def test_pull_on_gpio_sim_input_signals_the_host(controller: Landscaped) -> None:
    """A pull-up on gpio-sim lines 1 and 2 (DIO inputs 1 and 2) fires a
    signalDigitalIO watch on bits 0x6: one dioSignal event at the host, and
    getDigitalIO reads the levels."""
    set_pulls("pull-down")
    with supervisor(0x10, 0xF2, "vm-watch") as sup:
        wait_for(lambda: sup.get_digital_io("digital", 0).result["bits_on"] & 0xF == 0, 10, "inputs not low")
        watch = sup.signal_digital_io("digital", 0, 0x0006).result["watch_id"]
        assert watch > 0
        sysfs_line(1, "pull").write_text("pull-up")
        assert not [n for n in sup.notices(timeout_s=1.0) if n.event_id == "dioSignal"], "fired on one of two bits"
        sysfs_line(2, "pull").write_text("pull-up")
        got = [n for n in sup.notices(timeout_s=10.0) if n.event_id == "dioSignal"]
        assert len(got) == 1, got
        d = notice_data(got[0])
        assert (d["unit"], d["bits"], d["watch"]) == ("0", "0x6", str(watch))
        assert sup.get_digital_io("digital", 0).result["bits_on"] & 0xF == 0x6
    set_pulls("pull-down")


def test_two_controllers_and_two_supervisors_on_one_bus(controller: Landscaped, tmp_path: Path) -> None:
    """Nodes 0x10 and 0x11 on vcan0, each owned by its own supervisor (0xF1,
    0xF3) sharing one socket and Notifier (the library's documented way):
    both move at once and each owner gets its own completion."""
    import can
    second = Landscaped(log_dir(tmp_path), 0x11, "none", rt_priority=0)
    bus = can.Bus(interface="socketcan", channel=CAN_IF)
    notifier = can.Notifier(bus, [])
    try:
        with Supervisor(bus, notifier=notifier, device=0x10, source_address=0xF1, client_name="vm-a",
                        timeout_s=5.0) as a, \
             Supervisor(bus, notifier=notifier, device=0x11, source_address=0xF3, client_name="vm-b",
                        timeout_s=5.0) as b:
            a.lock()
            b.lock()
            a.activate()
            b.activate()
            ra = a.move_absolute("pa", [0.1, 0, 0, 0, 0, 0], speed_pct=50)
            rb = b.move_absolute("pb", [0, 0.2, 0, 0, 0, 0], speed_pct=50)
            na = a.wait_complete(ra, timeout_s=120)
            nb = b.wait_complete(rb, timeout_s=120)
            assert (na.event_id, nb.event_id) == ("moveAbsoluteComplete", "moveAbsoluteComplete")
            for n, want in ((na, [0.1, 0, 0, 0, 0, 0]), (nb, [0, 0.2, 0, 0, 0, 0])):
                assert [float(v) for v in notice_data(n)["joints"].split(",")] == pytest.approx(want, abs=2e-3)
            for s in (a, b):
                s.deactivate()
                s.release()
    finally:
        notifier.stop()
        bus.shutdown()
        rc = second.stop()
    assert rc == 0, second.log.read_text()


def test_two_supervisors_in_separate_processes(controller: Landscaped, tmp_path: Path) -> None:
    """Sharing real SocketCAN (docs/host-tool.md "Sharing the link"): two supervisor processes with their own
    sockets and addresses (0xF1 in this process, 0xF3 a CLI process), each
    owning its own controller (0x10, 0x11), move at the same time."""
    import can
    second = Landscaped(log_dir(tmp_path), 0x11, "none", rt_priority=0)
    script = tmp_path / "b.lsc"
    script.write_text("lock\nactivate\nmove-absolute pb JOINT_FRAME 0 0.2 0 0 0 0 --speed-pct 50\n"
                      "deactivate\nrelease\n")
    # Both supervisors wait 5 s per try: the guest runs under TCG next to two 1 kHz control
    # loops, and a loaded fresh-root run saw the CLI's default 1 s pass three times at connect.
    other = subprocess.Popen([str(CLI), "--interface", "socketcan", "--channel", CAN_IF, "--device", "0x11",
                              "--source-address", "0xF3", "--timeout", "5", "run", str(script)],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    bus = can.Bus(interface="socketcan", channel=CAN_IF)
    try:
        with Supervisor(bus, device=0x10, source_address=0xF1, client_name="vm-a", timeout_s=5.0) as a:
            a.lock()
            a.activate()
            na = a.wait_complete(a.move_absolute("pa", [0.1, 0, 0, 0, 0, 0], speed_pct=50), timeout_s=120)
            assert na.event_id == "moveAbsoluteComplete"
            a.deactivate()
            a.release()
        out, err = other.communicate(timeout=240)
        assert other.returncode == 0, f"{out}\n{err}"
        assert re.search(r"EVENT moveAbsoluteComplete point=pb .*final", out), out
    finally:
        if other.poll() is None:
            other.kill()
        bus.shutdown()
        rc = second.stop()
    assert rc == 0, second.log.read_text()


CONFIG_DRIVER = BUILD / "bin" / "ls_config_driver"  # landscaped's configuration and --check, alone


def check_command(which: str, tmp: Path, link: str) -> list[str]:
    """`--check` for vcan/gpio-sim through `which`: the config driver (the
    ls_config/ls_check code landscaped will use) or landscaped itself."""
    ins, outs = ",".join(map(str, INPUT_LINES)), ",".join(map(str, OUTPUT_LINES))
    conf = tmp / "check.conf"
    # arm = none: a simulated arm on a real bus is a WARN of its own (nothing real would move)
    conf.write_text(f"[hal]\nlink = {link}\narm = none\ndio = gpiod:{GPIO_CHIP}\n[dio]\ninputs = {ins}\n"
                    f"outputs = {outs}\n")
    if which == "driver":
        assert CONFIG_DRIVER.exists(), f"{CONFIG_DRIVER} missing: build first"
        return [str(CONFIG_DRIVER), "--config", str(conf), "--check"]
    return [str(LANDSCAPED), "--config", str(conf), "--check"]


@pytest.mark.parametrize("which", ["driver", "landscaped"])
def test_check_passes_for_vcan_and_the_gpio_sim_chip(which: str, tmp_path: Path) -> None:
    """On a kernel with AF_CAN, vcan0 and gpio-sim every check passes (root:
    real-time and memory locking are granted)."""
    r = subprocess.run(check_command(which, tmp_path, f"socketcan:{CAN_IF}"), capture_output=True, text=True,
                       timeout=120)
    lines = r.stdout.splitlines()
    assert r.returncode == 0, r.stdout + r.stderr
    assert any(ln.startswith("PASS  AF_CAN") for ln in lines), r.stdout
    assert any(ln.startswith(f"PASS  link socketcan:{CAN_IF}") for ln in lines), r.stdout
    assert any(ln.startswith(f"PASS  gpio chip {GPIO_CHIP}") for ln in lines), r.stdout
    assert [ln for ln in lines if ln.startswith(("FAIL", "WARN"))] == []


@pytest.mark.parametrize("which", ["driver", "landscaped"])
def test_check_fails_for_a_missing_interface_and_a_busy_line(which: str, tmp_path: Path) -> None:
    """No vcan9 on this guest, and gpio-sim output line 5 held by gpioset:
    --check exits 1 and names both."""
    cmd = check_command(which, tmp_path, "socketcan:vcan9")
    busy = OUTPUT_LINES[1]
    holder = subprocess.Popen(["gpioset", "--mode=signal", GPIO_CHIP, f"{busy}=1"])
    try:
        wait_for(lambda: sysfs_line(busy, "value").read_text().strip() == "1", 20, "gpioset did not hold the line")
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    finally:
        holder.terminate()
        holder.wait(timeout=20)
    assert r.returncode == 1, r.stdout + r.stderr
    fails = [ln for ln in r.stdout.splitlines() if ln.startswith("FAIL")]
    assert any(ln.startswith("FAIL  link socketcan:vcan9") for ln in fails), r.stdout
    assert any(ln.startswith("FAIL  gpio") and re.search(rf"\b{busy}\b", ln) for ln in fails), r.stdout


# ---------------------------------------------------------------- simulated drives on vcan

SIMDRIVES = BUILD / "bin" / "ls-simdrives"
SIMDRIVE_EDS = ROOT / "hal" / "sim" / "drives" / "ls-simdrive.eds"


def test_simulated_drives_answer_python_canopen_over_vcan(tmp_path: Path) -> None:
    """ls-simdrives on real SocketCAN (docs/simulated-drives.md): python-canopen over
    python-can's socketcan interface resets a node, hears its boot-up, reads objects
    expedited and segmented, and gets a synchronous TPDO for a SYNC."""
    import threading

    import canopen

    assert SIMDRIVES.exists(), f"{SIMDRIVES} missing: build first (bash .ci/build)"
    log = log_dir(tmp_path) / "ls-simdrives.log"
    with log.open("w") as f:
        proc = subprocess.Popen([str(SIMDRIVES), "--link", f"socketcan:{CAN_IF}", "--nodes", "0x21,0x22"],
                                stdout=subprocess.DEVNULL, stderr=f)
    net = canopen.Network()
    try:
        wait_for(lambda: "ready:" in log.read_text() or proc.poll() is not None, 60, "ls-simdrives ready")
        assert proc.poll() is None, log.read_text()
        net.connect(interface="socketcan", channel=CAN_IF)
        node = canopen.RemoteNode(0x21, str(SIMDRIVE_EDS))
        net.add_node(node)
        booted = threading.Event()
        node.nmt.add_heartbeat_callback(lambda state: booted.set() if state == 0 else None)
        node.nmt.send_command(0x81)
        assert booted.wait(30), "no boot-up after NMT reset node"
        node.sdo.RESPONSE_TIMEOUT = 5.0  # the emulated guest is slow
        assert node.sdo[0x1000].raw & 0xFFFF == 402
        assert node.sdo[0x1008].raw == "LandScape simulated drive"  # segmented
        node.tpdo.read()
        assert node.tpdo[3].enabled and node.tpdo[3].trans_type == 1  # statusword + position, every SYNC
        node.nmt.state = "OPERATIONAL"
        time.sleep(0.5)
        net.sync.transmit()
        assert node.tpdo[3].wait_for_reception(10) is not None, "no TPDO after a SYNC"
        assert node.tpdo[3][0x6041].raw & 0x4F == 0x40  # SWITCH ON DISABLED
    finally:
        net.disconnect()
        if proc.poll() is None:
            proc.terminate()
        rc = proc.wait(timeout=30)
    assert rc == 0, log.read_text()


# ---------------------------------------------------------------- the drive arm on its own vcan
#
# The composition of docs/deploy.md "Drives" on real SocketCAN: the supervisors on vcan0,
# the drives on vcan1 (ls-simdrives), landscaped the CANopen master between them, and
# can-utils' candump recording the drive bus. The checks read the log against CiA 301 and
# CiA 402 as written, not against our own encoder, so their constants are spelt here.

DRIVE_IF = os.environ.get("LS_VM_DRIVE_IF", "vcan1")
DRIVES_NODE = 0x13  # landscaped's node on vcan0 for the drive arm
DRIVE_NODES = (0x21, 0x22, 0x23, 0x24, 0x25, 0x26)  # ls-simdrives' defaults: joints 1..6
DRIVE_COUNTS_PER_RAD = 2**17 * 100 / (2 * math.pi)  # ls-simdrives' default position unit
RATE_HZ = 100  # landscaped_args' --rate under TCG
DRIVE_CYCLE = 2  # [drives] cycle: control periods per SYNC
DRIVE_CYCLE_S = DRIVE_CYCLE / RATE_HZ
COB_SYNC = 0x080  # CiA 301: SYNC (no data, or the counter)
COB_TPDO1, COB_RPDO1, COB_RPDO2 = 0x180, 0x200, 0x300  # + node id
COB_SDO_TX, COB_SDO_RX = 0x580, 0x600  # + node id: server -> client, client -> server
CW_COMMAND_MASK, CW_ENABLE_OPERATION = 0x008F, 0x000F  # CiA 402 controlword bits 0-3 and 7
SW_STATE_MASK_LONG, SW_READY_TO_SWITCH_ON = 0x006F, 0x0021  # CiA 402 statusword bits 0-3, 5, 6
SW_STATE_MASK_SHORT, SW_SWITCH_ON_DISABLED = 0x004F, 0x0040  # bits 0-3, 6


@dataclass(frozen=True)
class Frame:
    t: float  # the kernel's receive time stamp, s
    can_id: int
    data: bytes


def read_candump(path: Path) -> list[Frame]:
    """The data frames of a `candump -L -d` log: '(1700000000.123456) vcan1 080#' per line;
    fails when candump reported frames the kernel dropped (the log would have holes)."""
    frames = []
    for line in path.read_text().splitlines():
        m = re.match(r"^\((\d+\.\d+)\) \S+ ([0-9A-F]{3}|[0-9A-F]{8})#([0-9A-F]*)$", line)
        if m:
            frames.append(Frame(float(m[1]), int(m[2], 16), bytes.fromhex(m[3])))
        assert "DROPCOUNT" not in line, f"{path}: {line}: the drive bus log is incomplete"
    return frames


def is_sync(f: Frame) -> bool:
    return f.can_id == COB_SYNC and len(f.data) <= 1


def rpdo_node(f: Frame, base: int) -> int | None:
    return f.can_id - base if f.can_id - base in DRIVE_NODES else None


def is_sdo(f: Frame) -> bool:
    return COB_SDO_TX < f.can_id <= COB_SDO_TX + 0x7F or COB_SDO_RX < f.can_id <= COB_SDO_RX + 0x7F


def drive_arm_conf() -> str:
    """[drives] on vcan1 with the longest time-outs the keys take (docs/deploy.md): the
    emulated guest's processes stall for a second at times when the host is busy, and a
    drive's heartbeat or TPDO comes that late."""
    lines = ["[drives]", f"link = socketcan:{DRIVE_IF}", f"cycle = {DRIVE_CYCLE}", "heartbeat_timeout_ms = 5000",
             "boot_timeout_ms = 30000", "stale_cycles = 100"]
    for j, node in enumerate(DRIVE_NODES):
        lines += [f"[joint.{j + 1}]", f"node = {node:#x}", f"eds = {SIMDRIVE_EDS}",
                  f"counts_per_rad = {DRIVE_COUNTS_PER_RAD!r}"]
    return "\n".join(lines) + "\n"


def statusword_by_sdo(net: canopen.Network, node_id: int) -> int:
    """0x6041 read by python-canopen's SDO client."""
    import canopen
    node = canopen.RemoteNode(node_id, str(SIMDRIVE_EDS))
    net.add_node(node)
    node.sdo.RESPONSE_TIMEOUT = 5.0  # the emulated guest is slow
    return int(node.sdo[0x6041].raw)


def statuswords_by_sdo() -> dict[int, int]:
    """Every drive's 0x6041, read by python-canopen's SDO client on the drive bus."""
    import canopen
    net = canopen.Network()
    net.connect(interface="socketcan", channel=DRIVE_IF)
    try:
        return {n: statusword_by_sdo(net, n) for n in DRIVE_NODES}
    finally:
        net.disconnect()


def test_the_drive_bus_carries_each_cycles_rpdos_before_its_sync_and_no_sdo_while_enabled(tmp_path: Path) -> None:
    """landscaped with arm = cia402 drives ls-simdrives on vcan1 while the host library on
    vcan0 locks, activates and moves the arm. candump's log of vcan1 shows: in every drive
    cycle while the drives are enabled, each drive's RPDO1 (and RPDO2, the feed-forward)
    once, sent with the cycle's SYNC and before it; the SYNC period's median at the configured
    drive cycle (its jitter printed); no SDO between the first enable-operation controlword
    and the disable. The arm moved; after deactivate and landscaped's exit no drive is in
    OPERATION ENABLED."""

    assert SIMDRIVES.exists(), f"{SIMDRIVES} missing: build first (bash .ci/build)"
    out = log_dir(tmp_path)
    # the log on the guest's own file system (the shared output dir is slow to write under TCG,
    # and candump reads no frame while it writes); copied there at the end for a failure's reader
    dump = tmp_path / "drive-bus.candump"
    with dump.open("w") as f:
        # a 16 MB socket buffer holds seconds of the bus while candump waits for a CPU; -d logs
        # any frame the kernel dropped all the same
        candump = subprocess.Popen(["candump", "-L", "-d", "-r", str(16 << 20), DRIVE_IF], stdout=f,
                                   stderr=subprocess.PIPE, text=True)
    sd_log = out / "ls-simdrives-vcan1.log"
    sim: subprocess.Popen[bytes] | None = None
    ctl: Landscaped | None = None
    # small slow moves: a stall of the guest longer than 0.05 rad / speed is a following error
    targets = [[0.15, -0.1, 0.1, 0.05, 0.1, -0.15], [0.0, 0.05, -0.05, -0.1, 0.15, 0.0]]
    try:
        # candump holds its socket before anything goes on the bus
        wait_for(lambda: candump.poll() is not None or any(os.readlink(p).startswith("socket:")
                                                           for p in Path(f"/proc/{candump.pid}/fd").iterdir()),
                 30, "candump opened its CAN socket")
        assert candump.poll() is None, candump.communicate()[1]
        time.sleep(0.5)
        with sd_log.open("w") as f:
            # SCHED_FIFO below landscaped's loop, as a drive's firmware is real-time; 10 ms physics
            # steps, as one step of the world costs about 4 ms of CPU under TCG and 1 ms steps fall
            # behind real time (landscaped's own simulated arm steps at 100 Hz here)
            sim = subprocess.Popen([str(SIMDRIVES), "--link", f"socketcan:{DRIVE_IF}", "--counts-per-rad",
                                    repr(DRIVE_COUNTS_PER_RAD), "--rt-priority", "40", "--substep-ms", "10"],
                                   stdout=subprocess.DEVNULL, stderr=f)
        wait_for(lambda: "ready:" in sd_log.read_text() or sim.poll() is not None, 60, "ls-simdrives ready")
        assert sim.poll() is None, sd_log.read_text()
        ctl = Landscaped(out, DRIVES_NODE, "none", conf=drive_arm_conf(), arm="cia402", ready_s=180)
        with supervisor(DRIVES_NODE, 0xF1, "vm-drives") as sup:
            sup.lock()
            sup.activate()
            for k, q in enumerate(targets):
                done = sup.wait_complete(sup.move_absolute(f"d{k}", q, speed_pct=5), timeout_s=120)
                assert done.event_id == "moveAbsoluteComplete", done
                # the measured joints come some drive cycles after the set-point (docs/architecture.md
                # "Drives", Timing), and the emulated guest is slow: they settle after the completion
                wait_for(lambda q=q: list(sup.get_robot_position().result["joints"]) == pytest.approx(q, abs=2e-3),
                         10, f"the arm reached {q}")
            sup.deactivate()
            sup.release()
        rc = ctl.stop()
        assert rc == 0, ctl.log.read_text()
        words = statuswords_by_sdo()
    finally:
        if ctl is not None:
            ctl.stop()
        if sim is not None and sim.poll() is None:
            sim.terminate()
            sim.wait(timeout=30)
        if candump.poll() is None:
            # the bus is quiet now: let candump write out what its socket still holds (it drops
            # that at SIGINT), then stop it
            size = -1
            deadline = time.monotonic() + 30
            while dump.stat().st_size != size and time.monotonic() < deadline:
                size = dump.stat().st_size
                time.sleep(1.0)
            candump.send_signal(signal.SIGINT)
            candump.wait(timeout=30)
        if out != tmp_path:
            shutil.copy(dump, out / dump.name)
    # after deactivate and landscaped's exit: every drive disabled (READY TO SWITCH ON after
    # shutdown, or SWITCH ON DISABLED), none in OPERATION ENABLED
    for n, sw in words.items():
        assert sw & SW_STATE_MASK_LONG == SW_READY_TO_SWITCH_ON or sw & SW_STATE_MASK_SHORT == SW_SWITCH_ON_DISABLED, \
            f"node {n:#x}: statusword {sw:#06x} after landscaped's exit"

    frames = read_candump(dump)
    cw = [(f.t, int.from_bytes(f.data[:2], "little") & CW_COMMAND_MASK) for f in frames
          if rpdo_node(f, COB_RPDO1) is not None and len(f.data) >= 2]
    t_on = next((t for t, c in cw if c == CW_ENABLE_OPERATION), None)
    assert t_on is not None, f"no enable-operation controlword in {len(frames)} frames of {dump}"
    t_off = next((t for t, c in cw if t > t_on and c != CW_ENABLE_OPERATION), None)
    assert t_off is not None, "no disabling controlword after the enable: deactivate was not seen on the bus"
    window = [f for f in frames if t_on <= f.t < t_off]
    sdo = [f for f in window if is_sdo(f)]
    assert sdo == [], f"SDO while the drives were enabled: {[(f.t, hex(f.can_id)) for f in sdo[:5]]}"

    syncs = [i for i, f in enumerate(window) if is_sync(f)]
    assert len(syncs) > 50, f"{len(syncs)} SYNCs in {t_off - t_on:.1f} s of operation"
    lead: list[float] = []
    bad: list[str] = []
    for a, b in zip(syncs, syncs[1:], strict=False):
        t_a, t_b = window[a].t, window[b].t
        cycle = window[a + 1:b]
        for base in (COB_RPDO1, COB_RPDO2):
            got = sorted(n for n in (rpdo_node(f, base) for f in cycle) if n is not None)
            if got != list(DRIVE_NODES):
                bad.append(f"{t_b:.6f}: RPDO {base:#x}+node from {[hex(n) for n in got]}")
        # the master sends a cycle's RPDOs, then its SYNC (ls_co_master_sync; a frame the socket
        # refuses waits for the next control cycle, the SYNC still last): each RPDO nearer its
        # own SYNC than the one before, where RPDOs sent after a SYNC for the next would be
        for f in cycle:
            if rpdo_node(f, COB_RPDO1) is not None or rpdo_node(f, COB_RPDO2) is not None:
                lead.append(t_b - f.t)
                if t_b - f.t > f.t - t_a:
                    bad.append(f"{t_b:.6f}: RPDO {f.can_id:#x} {1000 * (t_b - f.t):.1f} ms before its SYNC, "
                               f"{1000 * (f.t - t_a):.1f} ms after the one before")
    assert bad == [], f"{len(bad)} cycles out of order, e.g. {bad[:5]}"
    periods = sorted(window[b].t - window[a].t for a, b in zip(syncs, syncs[1:], strict=False))
    median = periods[len(periods) // 2]
    dev = sorted(abs(p - DRIVE_CYCLE_S) for p in periods)
    p99 = dev[min(len(dev) - 1, math.ceil(0.99 * len(dev)) - 1)]
    tpdo = sum(1 for f in window if f.can_id - COB_TPDO1 in DRIVE_NODES)
    print(f"\ndrive bus on {DRIVE_IF}: {len(periods)} SYNC periods in {t_off - t_on:.1f} s enabled: median "
          f"{1000 * median:.3f} ms (configured {1000 * DRIVE_CYCLE_S:g} ms), deviation p99 {1000 * p99:.3f} ms, "
          f"max {1000 * dev[-1]:.3f} ms; RPDO to its SYNC: median {1000 * sorted(lead)[len(lead) // 2]:.3f} ms, "
          f"max {1000 * max(lead):.3f} ms; "
          f"{tpdo} TPDOs; statuswords after exit {', '.join(f'{n:#x}: {w:#06x}' for n, w in words.items())}")
    assert median == pytest.approx(DRIVE_CYCLE_S, rel=0.05)
    # generous: the guest's processes stall when the host is busy (the figure above is the report)
    assert p99 < 5 * DRIVE_CYCLE_S, "the SYNC period's 99th percentile deviation exceeds five cycles"


# ---------------------------------------------------------------- the drive arm when the drive bus fails
#
# Two faults a bench shows on real SocketCAN that a pty cannot: every drive's process killed
# (the nodes vanish from vcan1), and the interface taken down under both ends. Each fails the
# move in progress naming what went, leaves the controller LOCKED with nothing resuming by
# itself, and an activate after the cause is gone configures the drives again and moves the
# arm without restarting landscaped (docs/reliability.md, "Drives").

DRIVE_FAULT_NODE = 0x14  # landscaped's node on vcan0 for these tests
# joint 1 sets the pace: 1.2 rad at 5 % of its 2.5 rad/s takes about 10 s, so the move is still
# under way seconds after the emulated host tool has seen it start
FAULT_TARGET = [1.2, -0.3, 0.3, 0.3, 0.4, -0.4]


class DriveArm:
    """landscaped (arm = cia402, drive bus vcan1) and ls-simdrives on vcan1, for a module."""

    def __init__(self, out: Path, dump: Path) -> None:
        assert SIMDRIVES.exists(), f"{SIMDRIVES} missing: build first (bash .ci/build)"
        self.out = out
        self.dump = dump
        self.starts = 0
        self.sim: subprocess.Popen[bytes] | None = None
        self.dumps: list[tuple[subprocess.Popen[bytes], Path]] = []
        self.record()
        self.start_drives()
        self.ctl = Landscaped(out, DRIVE_FAULT_NODE, "none", conf=drive_arm_conf(), arm="cia402", ready_s=180)

    def record(self) -> None:
        """candump of the drive bus, for the reader of a failure (copied to the output dir at
        the end); again after the interface was down, as candump exits then."""
        path = self.dump.with_suffix(f".{len(self.dumps) + 1}.candump")
        with path.open("w") as f:
            self.dumps.append((subprocess.Popen(["candump", "-L", "-r", str(16 << 20), DRIVE_IF], stdout=f,
                                                stderr=subprocess.DEVNULL), path))

    def start_drives(self) -> None:
        """A fresh ls-simdrives, as landscaped's drive-bus test runs it (SCHED_FIFO, 10 ms physics)."""
        self.starts += 1
        log = self.out / f"ls-simdrives-faults-{self.starts}.log"
        with log.open("w") as f:
            self.sim = subprocess.Popen([str(SIMDRIVES), "--link", f"socketcan:{DRIVE_IF}", "--counts-per-rad",
                                         repr(DRIVE_COUNTS_PER_RAD), "--rt-priority", "40", "--substep-ms", "10"],
                                        stdout=subprocess.DEVNULL, stderr=f)
        sim = self.sim
        wait_for(lambda: "ready:" in log.read_text() or sim.poll() is not None, 60, "ls-simdrives ready")
        assert sim.poll() is None, log.read_text()

    def stop(self) -> int:
        rc = self.ctl.stop()
        if self.sim is not None and self.sim.poll() is None:
            self.sim.terminate()
            self.sim.wait(timeout=30)
        for proc, path in self.dumps:
            if proc.poll() is None:
                proc.send_signal(signal.SIGINT)
                proc.wait(timeout=30)
            if self.out != path.parent:
                shutil.copy(path, self.out / path.name)
        return rc


@pytest.fixture(scope="module")
def drive_arm(tmp_path_factory: pytest.TempPathFactory) -> Iterator[DriveArm]:
    subprocess.run(["ip", "link", "set", DRIVE_IF, "up"], check=True)
    tmp = tmp_path_factory.mktemp("drive-faults")
    arm = DriveArm(log_dir(tmp), tmp / "drive-bus")
    try:
        yield arm
    finally:
        subprocess.run(["ip", "link", "set", DRIVE_IF, "up"], check=False)
        rc = arm.stop()
        assert rc == 0, f"landscaped exited with {rc}:\n{arm.ctl.log.read_text()}"


def state_of(sup: Supervisor) -> str:
    return str(sup.get_motion_control_state().result["state"])


def start_moving(sup: Supervisor) -> tuple[RetVal, list[float]]:
    """Activate, start a slow joint move and see it under way; the move's RetVal and where
    the arm was."""
    sup.activate()
    start = list(sup.get_robot_position().result["joints"])
    rv = sup.move_absolute("far", FAULT_TARGET, speed_pct=5)
    wait_for(lambda: list(sup.get_robot_position().result["joints"]) != pytest.approx(start, abs=5e-3), 30,
             "the arm moving")
    q1 = float(sup.get_robot_position().result["joints"][0])
    assert state_of(sup) == "MOVING"
    assert q1 < start[0] + 0.5 * (FAULT_TARGET[0] - start[0]), f"joint 1 at {q1:.3f} rad: too near its target"
    return rv, start


def failed_move(sup: Supervisor, rv: RetVal, t0: float) -> tuple[dict[str, str], float]:
    """The move's final alarm (`...Failed`, reason fault) and seconds from t0 to it."""
    from landscape.errors import AlarmError
    with pytest.raises(AlarmError) as err:
        sup.wait_complete(rv, timeout_s=60)
    t = time.monotonic() - t0
    n = err.value.notice
    assert n.event_id == "moveAbsoluteFailed", n
    return notice_data(n), t


def nothing_resumes(sup: Supervisor, hold_s: float) -> None:
    """For hold_s: LOCKED, and the arm where it stopped."""
    q = list(sup.get_robot_position().result["joints"])
    deadline = time.monotonic() + hold_s
    while time.monotonic() < deadline:
        assert state_of(sup) == "LOCKED"
        time.sleep(0.5)
    assert list(sup.get_robot_position().result["joints"]) == pytest.approx(q, abs=2e-3)


def recovers(sup: Supervisor, target: list[float]) -> None:
    """activate configures the drives again; a move completes and the arm is there."""
    sup.activate()
    done = sup.wait_complete(sup.move_absolute("back", target, speed_pct=10), timeout_s=120)
    assert done.event_id == "moveAbsoluteComplete", done
    wait_for(lambda: list(sup.get_robot_position().result["joints"]) == pytest.approx(target, abs=2e-3), 10,
             f"the arm at {target}")
    sup.deactivate()


def test_drives_killed_on_vcan_fail_the_move_and_activate_recovers_them(drive_arm: DriveArm) -> None:
    """SIGKILL of ls-simdrives during a move: no TPDO and no heartbeat on vcan1 any more.
    The move fails naming a joint, its node and "no feedback"; LOCKED; a new ls-simdrives
    boots and nothing resumes; activate configures the drives again and the arm moves."""

    with supervisor(DRIVE_FAULT_NODE, 0xF1, "vm-drive-kill") as sup:
        sup.lock()
        rv, start = start_moving(sup)
        assert drive_arm.sim is not None
        t0 = time.monotonic()
        drive_arm.sim.kill()
        drive_arm.sim.wait(timeout=30)
        data, t = failed_move(sup, rv, t0)
        assert data.get("reason") == "fault", data
        assert re.search(r"joint \d \(node 0x2\d\): no feedback \(TPDO1\)", data.get("fault", "")), data
        assert state_of(sup) == "LOCKED"
        print(f"\ndrives killed on {DRIVE_IF}: the move failed {t:.2f} s later ({data['fault']}; stale_cycles 100 "
              f"x {1000 * DRIVE_CYCLE_S:g} ms)")
        drive_arm.start_drives()  # the drives power up again, PRE-OPERATIONAL
        nothing_resumes(sup, 3.0)
        words = statuswords_by_sdo()
        on = {hex(n): hex(w) for n, w in words.items() if w & SW_STATE_MASK_LONG == 0x0027}
        assert on == {}, f"drives in OPERATION ENABLED before any activate: {on}"
        recovers(sup, start)
        sup.release()


def test_the_drive_bus_taken_down_fails_the_move_and_activate_recovers_once_up(drive_arm: DriveArm) -> None:
    """`ip link set vcan1 down` during a move: landscaped's drive socket reports ENETDOWN.
    The move fails naming the drive bus; LOCKED; an activate while it is down is refused;
    once it is up nothing resumes by itself, and activate brings the drives back."""
    from landscape.errors import CommandError

    with supervisor(DRIVE_FAULT_NODE, 0xF1, "vm-drive-down") as sup:
        sup.lock()
        rv, start = start_moving(sup)
        t0 = time.monotonic()
        subprocess.run(["ip", "link", "set", DRIVE_IF, "down"], check=True)
        try:
            data, t = failed_move(sup, rv, t0)
            assert data.get("reason") == "fault", data
            assert f"the drive bus socketcan:{DRIVE_IF}" in data.get("fault", "") and \
                "every drive is lost" in data.get("fault", ""), data
            assert state_of(sup) == "LOCKED"
            print(f"\n{DRIVE_IF} down: the move failed {t:.2f} s later ({data['fault']})")
            with pytest.raises(CommandError) as refused:
                sup.activate()
            print(f"activate while {DRIVE_IF} is down: {refused.value}")
            assert state_of(sup) == "LOCKED"
        finally:
            subprocess.run(["ip", "link", "set", DRIVE_IF, "up"], check=True)
            drive_arm.record()
        nothing_resumes(sup, 3.0)
        recovers(sup, start)
        sup.release()


# ---------------------------------------------------------------- manual devices through evdev (uinput)
#
# python evdev's UInput makes a virtual gamepad and a virtual 6-DOF device in
# the guest's kernel; landscaped reads their /dev/input/event* nodes like real
# hardware ([manual], hal/linux/hal_linux_evdev.h). The guest runs no udev, so
# the tests make the /dev/input/by-id-style link themselves and point it at the
# new node when they re-plug a device, as udev would.

# The jog of a teach pendant at full deflection and its stop (docs/conformance.md
# "manualControl"): 10 % of the model's 1 m/s, braking at setAcceleration's
# default 1 m/s^2 with the model's jerk for it (ls_robot_model_linear_jerk:
# 40 m/s^3 * 1 / 4), so 0.1 / 1 + 1 / 10 = 0.2 s and 0.1 * 0.2 / 2 = 10 mm.
PENDANT_SPEED_M_S = 0.1
PENDANT_STOP_M = 0.010

PAD_ABS = 32767
MANUAL_NODE = 0x12  # its own node: its controller lives through these tests (a module fixture)


def virtual_gamepad() -> UInput:
    """A gamepad with the axes and buttons of the gamepad map."""
    stick = AbsInfo(value=0, min=-PAD_ABS - 1, max=PAD_ABS, fuzz=16, flat=128, resolution=0)
    hat = AbsInfo(value=0, min=-1, max=1, fuzz=0, flat=0, resolution=0)
    cap = {e.EV_KEY: [e.BTN_TL, e.BTN_NORTH, e.BTN_SOUTH, e.BTN_WEST, e.BTN_EAST],
           e.EV_ABS: [(e.ABS_X, stick), (e.ABS_Y, stick), (e.ABS_RX, stick), (e.ABS_RY, stick),
                      (e.ABS_HAT0X, hat), (e.ABS_HAT0Y, hat)]}
    return UInput(cap, name="ls-vm-pendant", vendor=0x045E, product=0x028E, bustype=e.BUS_USB)


def virtual_spacemouse() -> UInput:
    """A 6-DOF device like a SpaceMouse: six axes of -350..350, two buttons."""
    ax = AbsInfo(value=0, min=-350, max=350, fuzz=0, flat=0, resolution=0)
    cap = {e.EV_KEY: [e.BTN_0, e.BTN_1],
           e.EV_ABS: [(c, ax) for c in (e.ABS_X, e.ABS_Y, e.ABS_Z, e.ABS_RX, e.ABS_RY, e.ABS_RZ)]}
    return UInput(cap, name="ls-vm-spacemouse", vendor=0x256F, product=0xC635, bustype=e.BUS_USB)


def event_node(ui: UInput) -> str:
    node = str(ui.device.path)
    assert node.startswith("/dev/input/event"), node
    return node


def link_to(link: Path, ui: UInput) -> None:
    """Point the by-id-style link at the device's node (replacing it atomically)."""
    tmp = link.with_suffix(".new")
    tmp.unlink(missing_ok=True)
    tmp.symlink_to(event_node(ui))
    tmp.replace(link)


def emit(ui: UInput, *events: tuple[int, int, int]) -> None:
    for ev in events:
        ui.write(*ev)
    ui.syn()


def tip(sup: Supervisor) -> list[float]:
    return list(sup.get_robot_position().result["world_pose"][:3])


def wait_notice(sup: Supervisor, event_id: str, timeout_s: float = 30.0, **data: str) -> pb.Notice:
    for n in sup.notices(timeout_s=timeout_s):
        if n.event_id == event_id and all(notice_data(n).get(k) == v for k, v in data.items()):
            return n
    raise AssertionError(f"no {event_id} {data} within {timeout_s} s")


def still(sup: Supervisor, seconds: float = 1.0) -> list[float]:
    """The tip, after checking it did not move for `seconds`."""
    p0 = tip(sup)
    time.sleep(seconds)
    p1 = tip(sup)
    assert math.dist(p0, p1) < 1e-4, f"the tip moved {1000 * math.dist(p0, p1):.2f} mm while it should rest"
    return p1


def at_rest(sup: Supervisor, within_s: float = 5.0) -> list[float]:
    """The tip once the stop ramp has ended: two positions 0.5 s apart within 0.1 mm, looked
    for up to `within_s` (in the emulated guest the ramp's end comes later than the notice of
    its start); then still for a second more."""
    deadline = time.monotonic() + within_s
    p0 = tip(sup)
    while True:
        time.sleep(0.5)
        p1 = tip(sup)
        if math.dist(p0, p1) < 1e-4:
            return still(sup)
        assert time.monotonic() < deadline, f"the tip still moves {within_s:g} s after the stop began"
        p0 = p1


def dist(a: list[float], b: list[float]) -> float:
    return math.dist(a, b)


# A joint pose from which the tool points down over the table (tool x = base x,
# tool y = -base y, tool z = -base z), away from the wrist singularity of the
# zero pose (tests/integration/sensor_fixtures.py Q_OVER_TABLE).
Q_TOOL_DOWN = [-0.2, 0.8, 0.45, 0.0, 0.3, 0.0]


def ready(sup: Supervisor) -> None:
    """Lock, activate and bring the arm to Q_TOOL_DOWN."""
    sup.lock()
    sup.activate()
    done = sup.wait_complete(sup.move_absolute("tool_down", Q_TOOL_DOWN, speed_pct=50), timeout_s=120)
    assert done.event_id == "moveAbsoluteComplete", done


def press_enable(sup: Supervisor, ui: UInput) -> None:
    emit(ui, (e.EV_KEY, e.BTN_TL, 0))
    time.sleep(0.1)  # two reports the loop sees apart (100 Hz)
    emit(ui, (e.EV_KEY, e.BTN_TL, 1))
    wait_notice(sup, "manualSwitch", switch="enabled")


@pytest.fixture(scope="module")
def manual_rig(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Landscaped, Path, Path, list[UInput]]]:
    """Node MANUAL_NODE (no DIO) with a virtual gamepad as its teach pendant and a
    virtual SpaceMouse as its spaceball, both through by-id-style links; the
    list holds the devices alive (a test may replace one). One controller for
    these tests: a start costs seconds under TCG."""
    tmp = tmp_path_factory.mktemp("manual")
    devices = [virtual_gamepad(), virtual_spacemouse()]
    pad, mouse = tmp / "by-id-pad-event-joystick", tmp / "by-id-spacemouse-event-if00"
    link_to(pad, devices[0])
    link_to(mouse, devices[1])
    conf = f"[manual]\nteachpendant = {pad}\nspaceball = {mouse}\n"
    c = Landscaped(log_dir(tmp), MANUAL_NODE, "none", conf=conf)
    try:
        yield c, pad, mouse, devices
    finally:
        rc = c.stop()
        for d in devices:
            d.close()
        assert rc == 0, f"landscaped exited with {rc}:\n{c.log.read_text()}"


def test_a_virtual_pendant_jogs_only_while_its_enabling_switch_is_held(
        manual_rig: tuple[Landscaped, Path, Path, list[UInput]]) -> None:
    """The gamepad's stick jogs the simulated arm while LB (the enabling switch)
    is held, not before it was pressed; its release stops the tip within the
    jog's ramp (10 mm); the override button is reported."""
    _, _, _, devices = manual_rig
    pad = devices[0]
    with supervisor(MANUAL_NODE, 0xF1, "vm-pendant") as sup:
        ready(sup)
        assert sup.manual_control("teachpendant").ok
        emit(pad, (e.EV_ABS, e.ABS_X, PAD_ABS))  # full deflection, switch released
        p0 = still(sup)
        press_enable(sup, pad)
        time.sleep(1.5)
        p1 = tip(sup)
        assert dist(p0, p1) > 0.5 * PENDANT_SPEED_M_S, f"moved {1000 * dist(p0, p1):.1f} mm in 1.5 s"
        emit(pad, (e.EV_KEY, e.BTN_TL, 0))  # released: it brakes on the ramp
        wait_notice(sup, "manualSwitch", switch="released")
        p2 = tip(sup)
        p3 = at_rest(sup)
        print(f"\npendant: jogged {1000 * dist(p0, p1):.1f} mm; after the release notice {1000 * dist(p2, p3):.2f} mm "
              f"(ramp bound {1000 * PENDANT_STOP_M:.0f} mm)")
        assert dist(p2, p3) <= PENDANT_STOP_M * 1.05
        emit(pad, (e.EV_KEY, e.BTN_SOUTH, 1))
        wait_notice(sup, "manualOverride", device="teachpendant", percent="50")
        emit(pad, (e.EV_KEY, e.BTN_SOUTH, 0), (e.EV_ABS, e.ABS_X, 0))
        assert sup.manual_control("off").ok
        sup.deactivate()
        sup.release()


def test_unplugging_the_pendant_stops_and_alarms_and_it_jogs_again_after_a_new_press(
        manual_rig: tuple[Landscaped, Path, Path, list[UInput]]) -> None:
    """Destroying the uinput device stops the jog with manualDeviceLost; a new
    device at the same link is picked up (manualDeviceFound) without a restart,
    and with its switch held through the re-plug it jogs only after the switch
    was released and pressed again."""
    _, link, _, devices = manual_rig
    with supervisor(MANUAL_NODE, 0xF1, "vm-unplug") as sup:
        ready(sup)
        assert sup.manual_control("teachpendant").ok
        press_enable(sup, devices[0])
        p_start = tip(sup)
        emit(devices[0], (e.EV_ABS, e.ABS_Y, -PAD_ABS - 1))  # stick up: +vy
        time.sleep(1.0)
        assert dist(p_start, tip(sup)) > 0.3 * PENDANT_SPEED_M_S
        devices[0].close()  # unplugged: udev would remove its by-id link too (the kernel
        link.unlink()       # reuses event node numbers: a new device could take the old one's)
        alarm = wait_notice(sup, "manualDeviceLost", device="teachpendant", reason="unplugged")
        assert alarm.kind == pb.ALARM
        assert notice_data(alarm)["path"] == str(link)
        time.sleep(0.5)  # the ramp down
        p0 = still(sup)
        devices[0] = virtual_gamepad()  # plugged in again, the switch held, the stick pushed,
        emit(devices[0], (e.EV_KEY, e.BTN_TL, 1), (e.EV_ABS, e.ABS_Y, -PAD_ABS - 1))
        link_to(link, devices[0])  # and only then its link appears
        wait_notice(sup, "manualDeviceFound", device="teachpendant", path=str(link))
        p1 = still(sup)
        assert dist(p0, p1) < 1e-4  # held over the re-plug: nothing
        press_enable(sup, devices[0])
        time.sleep(1.0)
        assert dist(p1, tip(sup)) > 0.3 * PENDANT_SPEED_M_S
        emit(devices[0], (e.EV_KEY, e.BTN_TL, 0), (e.EV_ABS, e.ABS_Y, 0))
        assert sup.manual_control("off").ok
        sup.deactivate()
        sup.release()


def test_a_virtual_6dof_device_jogs_the_arm_and_check_reports_both_devices(
        manual_rig: tuple[Landscaped, Path, Path, list[UInput]], tmp_path: Path) -> None:
    """The SpaceMouse-like device, switched to the base frame by its first
    button, jogs the tip up when pulled (ABS_Z < 0: the spacemouse map's +vz)
    with no enabling switch; --check finds both devices with every mapped axis
    and button."""
    _, pad, mouse, devices = manual_rig
    with supervisor(MANUAL_NODE, 0xF1, "vm-6dof") as sup:
        ready(sup)
        assert sup.manual_control("spaceball").ok
        emit(devices[1], (e.EV_KEY, e.BTN_0, 1))
        wait_notice(sup, "manualFrame", device="spaceball", frame="base")
        emit(devices[1], (e.EV_KEY, e.BTN_0, 0))
        p0 = tip(sup)
        emit(devices[1], (e.EV_ABS, e.ABS_Z, -350))
        time.sleep(0.6)
        emit(devices[1], (e.EV_ABS, e.ABS_Z, 0))
        time.sleep(0.5)
        p1 = still(sup)
        print(f"\nspaceball: the tip went from {p0} to {p1}")
        assert p1[2] > p0[2] + 0.03, f"z went from {p0[2]:.4f} to {p1[2]:.4f} m"
        assert abs(p1[0] - p0[0]) < 2e-3 and abs(p1[1] - p0[1]) < 2e-3
        assert sup.manual_control("off").ok
        sup.deactivate()
        sup.release()
    conf = tmp_path / "check-manual.conf"
    conf.write_text(f"[hal]\nlink = socketcan:{CAN_IF}\ndio = none\n[manual]\nteachpendant = {pad}\n"
                    f"spaceball = {mouse}\n")
    r = subprocess.run([str(LANDSCAPED), "--config", str(conf), "--check"], capture_output=True, text=True,
                       timeout=120)
    lines = r.stdout.splitlines()
    assert r.returncode == 0, r.stdout + r.stderr
    for kind, name in (("teachpendant", "ls-vm-pendant"), ("spaceball", "ls-vm-spacemouse")):
        row = [ln for ln in lines if ln.startswith(f"PASS  manual {kind}: ")]
        assert row and f'"{name}" readable; has every mapped axis' in row[0], r.stdout
