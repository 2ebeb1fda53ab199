"""ISO-TP interop of the firmware's transport (ls_isotp) with python can-isotp
2.x over the SLCAN pseudo-terminal that landscaped uses.

isotp_pty_peer (tests/unit/isotp/isotp_pty_peer.c) runs one ls_isotp link on
hal_sim_link's pty and echoes every message. The host side is exactly what a
supervisor uses: python-can's slcan driver and isotp.NotifierBasedCanStack.
For every payload size and every (block size, STmin) pair both directions
run (the host's message, then the device's echo) and the frames are counted:

  - device -> host frames by a can.Listener on the host bus, and checked
    against the peer's own record of what it transmitted (nothing lost or
    duplicated on the pty);
  - host -> device frames by the peer's record of what it received, and
    checked against what the host stack handed to bus.send.

Each transfer must use the ISO 15765-2 minimum: 1 data frame up to 7 bytes,
else 1 FF + ceil((n - 6) / 7) CFs, and the number of flow controls the
receiver's block size implies.

Run through ctest (LS_ISOTP_PTY_PEER set), or with the build directory's peer:
    LS_BUILD_DIR=build .venv/bin/python -m pytest tests/integration/test_isotp_pty.py
"""
from __future__ import annotations

import os
import signal
import subprocess
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

import can
import isotp
import pytest

from conftest import BUILD
from landscape._generated import landscape_pb2 as pb

HOST_ADDR = pb.DEFAULT_HOST_ADDRESS
DEVICE_ADDR = pb.DEFAULT_DEVICE_ADDRESS
# ISO 15765-2 normal fixed addressing: the ids can-isotp computes itself
# (isotp.AddressingMode.NormalFixed_29bits); the test would fail if the
# schema's base disagreed with it.
ID_TO_DEVICE = pb.ISOTP_PHYSICAL_BASE | (DEVICE_ADDR << 8) | HOST_ADDR
ID_TO_HOST = pb.ISOTP_PHYSICAL_BASE | (HOST_ADDR << 8) | DEVICE_ADDR
SIZES = [1, 7, 8, 62, 63, 100, 1000, 4095]
PARAMS = [(0, 0), (0, 1), (8, 0), (8, 1)]  # (block size, STmin ms), the same on both sides
TRANSFER_TIMEOUT_S = 10.0


def iso_data_frames(length: int) -> int:
    """Minimum number of SF/FF/CF frames for `length` bytes on classic CAN."""
    return 1 if length <= 7 else 1 + -(-(length - 6) // 7)


def iso_flow_controls(length: int, block_size: int) -> int:
    """Flow controls a receiver asking for `block_size` sends for `length` bytes."""
    if length <= 7:
        return 0
    n_cf = iso_data_frames(length) - 1
    return 1 if block_size == 0 else 1 + (n_cf - 1) // block_size


def min_cf_span_s(length: int, block_size: int, st_min_ms: int) -> float:
    """Least time STmin forces between the first and the last CF: one STmin per
    gap inside a block (a block's first CF waits for a flow control instead)."""
    n_cf = iso_data_frames(length) - 1
    if n_cf < 2:
        return 0.0
    blocks = 1 if block_size == 0 else -(-n_cf // block_size)
    return (n_cf - blocks) * st_min_ms / 1000.0


def pattern(length: int, seed: int) -> bytes:
    return bytes((i * 31 + seed * 7 + (i >> 8)) & 0xFF for i in range(length))


def pci(frame: bytes) -> int:
    return frame[0] >> 4


def data_frames(frames: list[bytes]) -> list[bytes]:
    return [f for f in frames if pci(f) in (0, 1, 2)]


def flow_controls(frames: list[bytes]) -> list[bytes]:
    return [f for f in frames if pci(f) == 3]


@dataclass
class PeerLog:
    """What isotp_pty_peer reported, guarded by `lock`."""

    lock: threading.Lock = field(default_factory=threading.Lock)
    rx: list[tuple[float, bytes]] = field(default_factory=list)  # (peer time s, data) host -> device
    tx: list[tuple[float, bytes]] = field(default_factory=list)  # device -> host
    messages: list[int] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)
    ready: threading.Event = field(default_factory=threading.Event)

    def clear(self) -> None:
        with self.lock:
            self.rx.clear()
            self.tx.clear()
            self.messages.clear()


class Peer:
    """isotp_pty_peer as a subprocess, with a thread that parses its stdout."""

    def __init__(self, exe: str, pty: Path, block_size: int, st_min_ms: int) -> None:
        self.log = PeerLog()
        self.proc = subprocess.Popen([exe, "-b", str(block_size), "-s", str(st_min_ms), f"slcan:pty:{pty}"],
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, bufsize=1)
        self._reader = threading.Thread(target=self._read, name="pty-peer-stdout", daemon=True)
        self._reader.start()
        if not self.log.ready.wait(10.0):
            self.proc.kill()
            _, err = self.proc.communicate()
            raise AssertionError(f"isotp_pty_peer did not open {pty} within 10 s: {err.strip()}")

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for raw in self.proc.stdout:
            kind, _, rest = raw.strip().partition(" ")
            if kind == "READY":
                self.log.ready.set()
            elif kind in ("R", "T"):
                t_us, id_hex, data_hex = rest.split(" ")
                entry = (int(t_us) / 1e6, bytes.fromhex(data_hex))
                expected = ID_TO_DEVICE if kind == "R" else ID_TO_HOST
                with self.log.lock:
                    if int(id_hex, 16) != expected:
                        self.log.errors.append(f"frame with id {id_hex}: {raw.strip()}")
                    (self.log.rx if kind == "R" else self.log.tx).append(entry)
            elif kind == "M":
                with self.log.lock:
                    self.log.messages.append(int(rest))
            else:
                with self.log.lock:
                    self.log.errors.append(raw.strip())

    def stop(self) -> tuple[int, str]:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
        try:
            _, err = self.proc.communicate(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            _, err = self.proc.communicate()
            raise AssertionError("isotp_pty_peer did not exit within 10 s of SIGTERM") from None
        self._reader.join(timeout=5)
        return self.proc.returncode, err


class FrameRecorder(can.Listener):
    """Every frame of the device's ISO-TP link that reaches the host bus."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.frames: list[bytes] = []
        self.foreign: list[can.Message] = []

    def on_message_received(self, msg: can.Message) -> None:
        with self.lock:
            if msg.is_extended_id and msg.arbitration_id == ID_TO_HOST:
                self.frames.append(bytes(msg.data))
            else:
                self.foreign.append(msg)

    def clear(self) -> None:
        with self.lock:
            self.frames.clear()


@dataclass
class Setup:
    peer: Peer
    stack: isotp.NotifierBasedCanStack
    recorder: FrameRecorder
    host_sent: list[bytes]
    host_sent_at: list[float]  # time.monotonic() of each host_sent frame, when python-can was handed it
    block_size: int
    st_min_ms: int


@pytest.fixture(scope="module")
def peer_exe() -> str:
    path = os.environ.get("LS_ISOTP_PTY_PEER") or str(BUILD / "bin" / "isotp_pty_peer")
    if not os.access(path, os.X_OK):
        pytest.fail(f"{path} is missing: build it with `cmake --build build --target isotp_pty_peer` "
                    f"(or set LS_ISOTP_PTY_PEER to the executable)")
    return path


@pytest.fixture(params=PARAMS, ids=lambda p: f"bs{p[0]}-stmin{p[1]}")
def setup(request: pytest.FixtureRequest, peer_exe: str, tmp_path: Path) -> Iterator[Setup]:
    block_size, st_min_ms = request.param
    pty = tmp_path / "isotp-pty"
    peer = Peer(peer_exe, pty, block_size, st_min_ms)
    bus = can.Bus(interface="slcan", channel=str(pty), bitrate=1000000, sleep_after_open=0)
    host_sent: list[bytes] = []
    host_sent_at: list[float] = []
    real_send = bus.send

    def counting_send(msg: can.Message, timeout: float | None = None) -> None:
        if msg.is_extended_id and msg.arbitration_id == ID_TO_DEVICE:
            host_sent.append(bytes(msg.data))
            host_sent_at.append(time.monotonic())
        real_send(msg, timeout)

    bus.send = counting_send  # type: ignore[method-assign]
    recorder = FrameRecorder()
    notifier = can.Notifier(bus, [recorder], timeout=0.01)
    address = isotp.Address(isotp.AddressingMode.NormalFixed_29bits, source_address=HOST_ADDR,
                            target_address=DEVICE_ADDR)
    params = {"stmin": st_min_ms, "blocksize": block_size, "tx_padding": 0xCC, "tx_data_min_length": 8,
              "rx_flowcontrol_timeout": 1000, "rx_consecutive_frame_timeout": 1000, "max_frame_size": 4095}
    stack = isotp.NotifierBasedCanStack(bus, notifier, address=address, params=params)
    stack.start()
    try:
        yield Setup(peer, stack, recorder, host_sent, host_sent_at, block_size, st_min_ms)
    finally:
        stack.stop()
        notifier.stop()
        bus.shutdown()
        code, err = peer.stop()
        assert code == 0, f"isotp_pty_peer exited with {code}: {err}"
        assert not pty.exists(), "isotp_pty_peer left its symlink behind"
        assert peer.log.errors == [], f"isotp_pty_peer reported: {peer.log.errors}; stderr: {err}"
        assert recorder.foreign == [], f"unexpected frames on the bus: {recorder.foreign[:5]}"


def settle(cond: Callable[[], bool], what: str, timeout_s: float = 2.0) -> None:
    deadline = time.monotonic() + timeout_s
    while not cond():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out waiting for {what}")
        time.sleep(0.002)


def cf_span_s(entries: list[tuple[float, bytes]]) -> float:
    times = [t for t, f in entries if pci(f) == 2]
    return times[-1] - times[0] if len(times) > 1 else 0.0


def echo(s: Setup, payload: bytes) -> None:
    """Send `payload`, receive its echo, and check every frame of both transfers."""
    n = len(payload)
    s.peer.log.clear()
    s.recorder.clear()
    s.host_sent.clear()
    s.host_sent_at.clear()
    s.stack.send(payload)
    got = s.stack.recv(block=True, timeout=TRANSFER_TIMEOUT_S)
    if got is None:
        with s.peer.log.lock:
            detail = (f"peer received {len(s.peer.log.rx)} frames, sent {len(s.peer.log.tx)}, messages "
                      f"{s.peer.log.messages}, errors {s.peer.log.errors}; host sent {len(s.host_sent)}, "
                      f"saw {len(s.recorder.frames)}")
        raise AssertionError(f"no echo of a {n}-byte message within {TRANSFER_TIMEOUT_S} s: {detail}")
    assert bytes(got) == payload

    # The echo completed, so the host's transfer did too; wait for the last
    # log lines and frames (stdout and the pty are read by other threads).
    settle(lambda: len(s.peer.log.messages) >= 1, "the peer's message log")
    with s.peer.log.lock:
        assert s.peer.log.messages == [n]
    settle(lambda: len(s.recorder.frames) >= iso_data_frames(n) + iso_flow_controls(n, s.block_size),
           "the device's frames on the host bus")
    settle(lambda: len(s.peer.log.tx) >= len(s.recorder.frames), "the peer's transmit log")
    time.sleep(0.02)  # a stray extra frame would show up by now

    with s.peer.log.lock:
        rx = list(s.peer.log.rx)
        tx = list(s.peer.log.tx)
    with s.recorder.lock:
        seen_by_host = list(s.recorder.frames)
    received_by_device = [f for _, f in rx]

    # Nothing lost, added or altered on the pty, in either direction.
    assert seen_by_host == [f for _, f in tx]
    assert received_by_device == s.host_sent

    # host -> device: the host's data frames and the device's flow controls.
    assert len(data_frames(received_by_device)) == iso_data_frames(n)
    device_fcs = flow_controls(seen_by_host)
    assert len(device_fcs) == iso_flow_controls(n, s.block_size)
    for fc in device_fcs:
        assert fc == bytes([0x30, s.block_size, s.st_min_ms, 0xCC, 0xCC, 0xCC, 0xCC, 0xCC])

    # device -> host: the device's data frames and the host's flow controls.
    device_data = data_frames(seen_by_host)
    assert len(device_data) == iso_data_frames(n)
    assert len(flow_controls(received_by_device)) == iso_flow_controls(n, s.block_size)
    assert len(seen_by_host) == len(device_data) + len(device_fcs)
    assert len(received_by_device) == iso_data_frames(n) + iso_flow_controls(n, s.block_size)
    assert all(len(f) == 8 for f in seen_by_host), "the device pads every frame to 8 bytes"
    if n > 7:
        assert device_data[0][:2] == bytes([0x10 | (n >> 8), n & 0xFF])
        assert [f[0] & 0x0F for f in device_data[1:]] == [(i + 1) & 0x0F for i in range(len(device_data) - 1)]

    # STmin, each side by its own send times: the device's are exact; the
    # host's are when can-isotp handed each frame to python-can (1 ms covers
    # the timer granularity). The device's read times cannot judge the host:
    # a loaded machine delays the reader, and every frame waiting in the pty
    # then arrives in one read (seen: 62 bytes, all 8 CFs at one instant).
    tx_data = [(t, f) for t, f in tx if pci(f) != 3]
    assert cf_span_s(tx_data) >= min_cf_span_s(n, s.block_size, s.st_min_ms)
    host_data = list(zip(s.host_sent_at, s.host_sent, strict=True))
    assert cf_span_s(host_data) >= min_cf_span_s(n, s.block_size, s.st_min_ms) - 0.001


def test_echo_every_size(setup: Setup) -> None:
    for seed, n in enumerate(SIZES):
        echo(setup, pattern(n, seed))


def test_back_to_back_messages_keep_their_order(setup: Setup) -> None:
    """Several messages queued at once arrive whole and in order (the host stack
    serialises them; the device echoes each before taking the next)."""
    payloads = [pattern(n, 40 + i) for i, n in enumerate([100, 7, 1000, 8, 63])]
    for p in payloads:
        setup.stack.send(p)
    echoes = []
    for _ in payloads:
        got = setup.stack.recv(block=True, timeout=TRANSFER_TIMEOUT_S)
        assert got is not None, f"an echo is missing after {len(echoes)}; peer: {setup.peer.log.errors}"
        echoes.append(bytes(got))
    assert echoes == payloads


def test_peer_refuses_a_bad_command_line(peer_exe: str, tmp_path: Path) -> None:
    for args in ([], ["-b"], ["-s", "256", "slcan:pty:/tmp/x"], ["-x", "1", f"slcan:pty:{tmp_path}/p"],
                 ["-s", "0x80", f"slcan:pty:{tmp_path}/p"]):
        r = subprocess.run([peer_exe, *args], capture_output=True, text=True, timeout=10)
        assert r.returncode == 2, args
        assert "usage" in r.stderr or "STmin" in r.stderr, (args, r.stderr)
    regular = tmp_path / "not-a-link"
    regular.write_text("keep me")
    r = subprocess.run([peer_exe, f"slcan:pty:{regular}"], capture_output=True, text=True, timeout=10)
    assert r.returncode == 2 and "not a symlink" in r.stderr
    assert regular.read_text() == "keep me"
