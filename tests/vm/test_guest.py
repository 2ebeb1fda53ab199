"""VM tier checks, run inside the QEMU guest by tests/vm/guest.sh.

The guest has a real SocketCAN bus (vcan0 with the kernel's CAN_RAW and
CAN_ISOTP) and a real GPIO chip (gpio-sim, 8 lines). guest.sh exports:
  LS_VM_CAN_IF      the CAN interface (vcan0)
  LS_VM_GPIO_CHIP   the gpio-sim chip (gpiochipN)
  LS_VM_GPIO_SYSFS  its sysfs dir (.../gpio-sim.N/gpiochipN with sim_gpioK/{value,pull})
  LS_BUILD_DIR      the build tree (bin/isotp_socketcan_echo, bin/landscaped)
Guest code runs ~20x slower than on the host (TCG): time-outs are generous and
the checks few and end to end.
"""
from __future__ import annotations

import os
import re
import socket
import struct
import subprocess
import time
from pathlib import Path
from typing import Iterator

import pytest

CAN_IF = os.environ.get("LS_VM_CAN_IF", "vcan0")
GPIO_CHIP = os.environ.get("LS_VM_GPIO_CHIP", "")
GPIO_SYSFS = Path(os.environ.get("LS_VM_GPIO_SYSFS", "/nonexistent"))
ROOT = Path(__file__).resolve().parents[2]
BUILD = Path(os.environ.get("LS_BUILD_DIR", ROOT / "build"))
ECHO = BUILD / "bin" / "isotp_socketcan_echo"

# ISO-TP normal fixed 29-bit addressing, device 0x10, host 0xF1.
HOST_TO_DEV = 0x18DA10F1
DEV_TO_HOST = 0x18DAF110

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
    (socketcan, gpiod, rt: the order of test_linux_main.c) each test's outcome."""
    exe = BUILD / "bin" / "test_linux_hal"
    assert exe.exists(), f"{exe} missing: build first"
    r = subprocess.run([str(exe)], capture_output=True, text=True, timeout=240)
    groups: list[dict[str, bool]] = []
    for chunk in r.stdout.split("[==========] Running")[1:]:
        outcome = {m[1]: m[0] == "OK" for m in re.findall(r"^\[ +(OK|FAILED) +\] (\w+)$", chunk, re.M)}
        groups.append(outcome)
    assert len(groups) == 3, f"expected 3 test groups (socketcan, gpiod, rt):\n{r.stdout}{r.stderr}"
    assert (r.returncode == 0) == all(all(g.values()) for g in groups), r.stdout + r.stderr
    return groups


@pytest.fixture(scope="module")
def hal_groups() -> list[dict[str, bool]]:
    return linux_hal_groups()


def test_linux_hal_socketcan_and_gpiod_tests_with_real_kernel_support(hal_groups: list[dict[str, bool]]) -> None:
    """The Linux HAL's CMocka tests, here on a kernel with AF_CAN and GPIO."""
    socketcan, gpiod, _ = hal_groups
    assert len(socketcan) == 10 and len(gpiod) == 4, hal_groups
    failed = [name for g in (socketcan, gpiod) for name, ok in g.items() if not ok]
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
    assert f"echoed 1, rx ok 1, tx ok 1" in summary, summary


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
