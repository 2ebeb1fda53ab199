"""Interop of the firmware's ISO-TP (ls_isotp, via the isotp_peer executable)
with python can-isotp 2.0.7 on a python-can virtual bus.

The bridge turns the peer's stdout ``F`` lines into frames on the bus and the
bus frames addressed to the device into ``F`` lines on its stdin; it also feeds
the peer real monotonic time (``T`` lines) so that STmin and timeouts run in
real time on both sides.

Run through ctest (which sets LS_ISOTP_PEER), or by hand:
    LS_ISOTP_PEER=build/bin/isotp_peer .venv/bin/python -m pytest tests/unit/isotp/test_isotp_interop.py
"""

from __future__ import annotations

import os
import queue
import subprocess
import threading
import time
import uuid
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field

import can
import isotp
import pytest

from landscape._generated import landscape_pb2 as pb

HOST_ADDR = pb.DEFAULT_HOST_ADDRESS
DEVICE_ADDR = pb.DEFAULT_DEVICE_ADDRESS
ID_TO_DEVICE = pb.ISOTP_PHYSICAL_BASE | (DEVICE_ADDR << 8) | HOST_ADDR
ID_TO_HOST = pb.ISOTP_PHYSICAL_BASE | (HOST_ADDR << 8) | DEVICE_ADDR
SIZES = [1, 7, 8, 62, 63, 100, 1000, 4095]
TRANSFER_TIMEOUT_S = 15.0


class PeerError(RuntimeError):
    """The isotp_peer process reported an error or misbehaved."""


def iso_data_frames(length: int) -> int:
    """Minimum number of SF/FF/CF frames for `length` bytes on classic CAN."""
    return 1 if length <= 7 else 1 + -(-(length - 6) // 7)


def iso_flow_controls(length: int, block_size: int) -> int:
    """Flow control frames a receiver with `block_size` sends for `length` bytes."""
    if length <= 7:
        return 0
    n_cf = iso_data_frames(length) - 1
    return 1 if block_size == 0 else 1 + (n_cf - 1) // block_size


def pattern(length: int, seed: int) -> bytes:
    return bytes((i * 37 + seed * 11 + (i >> 8)) & 0xFF for i in range(length))


@dataclass
class Traffic:
    """Frames seen by the bridge, split by direction; guarded by `lock`."""

    lock: threading.Lock = field(default_factory=threading.Lock)
    to_device: list[bytes] = field(default_factory=list)
    to_host: list[bytes] = field(default_factory=list)
    to_host_us: list[int] = field(default_factory=list)  # the device's clock when it sent each

    def clear(self) -> None:
        with self.lock:
            self.to_device.clear()
            self.to_host.clear()
            self.to_host_us.clear()

    def snapshot(self) -> tuple[list[bytes], list[bytes]]:
        with self.lock:
            return list(self.to_device), list(self.to_host)


def cf_span_s(frames: list[bytes], times_us: list[int]) -> float:
    """Time from the first to the last consecutive frame of a transfer."""
    cf_times = [t for f, t in zip(frames, times_us, strict=True) if (f[0] >> 4) == 2]
    return (cf_times[-1] - cf_times[0]) / 1e6 if len(cf_times) > 1 else 0.0


def min_stmin_span_s(length: int, block_size: int, st_min_ms: int) -> float:
    """Least time STmin forces between the first and last CF: one STmin per
    gap inside a block (a block's first CF waits for flow control instead)."""
    n_cf = iso_data_frames(length) - 1
    if n_cf < 2:
        return 0.0
    blocks = 1 if block_size == 0 else -(-n_cf // block_size)
    return (n_cf - blocks) * st_min_ms / 1000.0


def split(frames: list[bytes]) -> tuple[list[bytes], list[bytes]]:
    """(data frames SF/FF/CF, flow control frames)."""
    data = [f for f in frames if (f[0] >> 4) in (0, 1, 2)]
    fcs = [f for f in frames if (f[0] >> 4) == 3]
    return data, fcs


class PeerBridge:
    """Runs isotp_peer and wires it to a virtual CAN bus channel."""

    def __init__(self, peer_path: str, channel: str, block_size: int, st_min: int, padding: bool) -> None:
        self.traffic = Traffic()
        self.messages: queue.Queue[bytes] = queue.Queue()
        self.errors: list[str] = []
        self._stop = threading.Event()
        self._stdin_lock = threading.Lock()
        self._t0 = time.monotonic()
        self.bus = can.Bus(interface="virtual", channel=channel, receive_own_messages=False)
        self.proc = subprocess.Popen(
            [peer_path, "-b", str(block_size), "-s", str(st_min), "-p", "1" if padding else "0"],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            bufsize=1,
        )
        self._reader = threading.Thread(target=self._read_peer, name="peer-stdout", daemon=True)
        self._pump = threading.Thread(target=self._pump_bus, name="bus-to-peer", daemon=True)
        self._reader.start()
        self._pump.start()

    def _now_us(self) -> int:
        return int((time.monotonic() - self._t0) * 1e6)

    def _write(self, line: str) -> None:
        with self._stdin_lock:
            assert self.proc.stdin is not None
            self.proc.stdin.write(line + "\n")
            self.proc.stdin.flush()

    def send(self, payload: bytes) -> None:
        self._write(f"T {self._now_us()}")
        self._write("S " + payload.hex())

    def _read_peer(self) -> None:
        assert self.proc.stdout is not None
        for raw in self.proc.stdout:
            line = raw.strip()
            kind, _, rest = line.partition(" ")
            if kind == "F":
                id_hex, data_hex, sent_us = rest.split(" ")
                data = bytes.fromhex(data_hex)
                with self.traffic.lock:
                    self.traffic.to_host.append(data)
                    self.traffic.to_host_us.append(int(sent_us))
                self.bus.send(can.Message(arbitration_id=int(id_hex, 16), is_extended_id=True, data=data))
            elif kind == "M":
                self.messages.put(bytes.fromhex(rest))
            else:
                self.errors.append(line)

    def _pump_bus(self) -> None:
        # Feeds time continuously (the peer polls on every line) and forwards
        # frames for the device; the 0.2 ms receive timeout bounds CF jitter.
        while not self._stop.is_set():
            try:
                msg = self.bus.recv(timeout=0.0002)
                lines = [f"T {self._now_us()}"]
                if msg is not None and msg.is_extended_id and msg.arbitration_id == ID_TO_DEVICE:
                    data = bytes(msg.data)
                    with self.traffic.lock:
                        self.traffic.to_device.append(data)
                    lines.append(f"F {msg.arbitration_id:08X} {data.hex()}")
                for line in lines:
                    self._write(line)
            except (BrokenPipeError, ValueError, OSError):
                return

    def close(self) -> str:
        self._stop.set()
        self._pump.join(timeout=5)
        try:
            self._write("Q")
        except (BrokenPipeError, ValueError, OSError):
            pass
        try:
            _, stderr = self.proc.communicate(timeout=5)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            _, stderr = self.proc.communicate()
        self._reader.join(timeout=5)
        self.bus.shutdown()
        return stderr


@dataclass
class Setup:
    bridge: PeerBridge
    stack: isotp.NotifierBasedCanStack
    block_size: int


@pytest.fixture
def peer_path() -> str:
    path = os.environ.get("LS_ISOTP_PEER", "")
    if not path or not os.access(path, os.X_OK):
        pytest.fail(
            "LS_ISOTP_PEER must name the built isotp_peer executable: build it with "
            "`cmake --build build --target isotp_peer` and run this file through ctest "
            "(-DLS_PYTEST=ON) or set LS_ISOTP_PEER=build/bin/isotp_peer."
        )
    return path


@contextmanager
def make_setup(peer: str, block_size: int, st_min: int, device_padding: bool,
               host_padding: int | None) -> Iterator[Setup]:
    channel = f"isotp-interop-{uuid.uuid4().hex}"
    bridge = PeerBridge(peer, channel, block_size, st_min, device_padding)
    host_bus = can.Bus(interface="virtual", channel=channel, receive_own_messages=False)
    notifier = can.Notifier(host_bus, [], timeout=0.01)
    address = isotp.Address(
        isotp.AddressingMode.NormalFixed_29bits, source_address=HOST_ADDR, target_address=DEVICE_ADDR
    )
    params = {
        "stmin": st_min,
        "blocksize": block_size,
        "tx_padding": host_padding,
        "rx_flowcontrol_timeout": 1000,
        "rx_consecutive_frame_timeout": 1000,
        "max_frame_size": 4095,
    }
    stack = isotp.NotifierBasedCanStack(host_bus, notifier, address=address, params=params)
    stack.start()
    try:
        yield Setup(bridge, stack, block_size)
    finally:
        stack.stop()
        notifier.stop()
        host_bus.shutdown()
        stderr = bridge.close()
        assert bridge.errors == [], f"isotp_peer reported errors: {bridge.errors}; stderr: {stderr}"


@pytest.fixture(params=[(0, 0), (0, 1), (8, 0), (8, 1)], ids=lambda p: f"bs{p[0]}-stmin{p[1]}")
def setup(request: pytest.FixtureRequest, peer_path: str) -> Iterator[Setup]:
    block_size, st_min = request.param
    with make_setup(peer_path, block_size, st_min, device_padding=True, host_padding=None) as s:
        yield s


def wait_idle(stack: isotp.NotifierBasedCanStack) -> None:
    deadline = time.monotonic() + TRANSFER_TIMEOUT_S
    while stack.transmitting():
        if time.monotonic() > deadline:
            raise PeerError("the host stack did not finish sending; the device never sent flow control?")
        time.sleep(0.001)


def host_to_device(s: Setup, payload: bytes) -> tuple[list[bytes], list[bytes]]:
    s.bridge.traffic.clear()
    s.stack.send(payload)
    try:
        got = s.bridge.messages.get(timeout=TRANSFER_TIMEOUT_S)
    except queue.Empty:
        raise PeerError(f"device did not receive a {len(payload)}-byte message; peer errors: {s.bridge.errors}") \
            from None
    wait_idle(s.stack)
    assert got == payload
    return s.bridge.traffic.snapshot()


def device_to_host(s: Setup, payload: bytes) -> tuple[list[bytes], list[bytes]]:
    s.bridge.traffic.clear()
    s.bridge.send(payload)
    got = s.stack.recv(block=True, timeout=TRANSFER_TIMEOUT_S)
    if got is None:
        raise PeerError(f"host did not receive a {len(payload)}-byte message; peer errors: {s.bridge.errors}")
    assert bytes(got) == payload
    return s.bridge.traffic.snapshot()


@pytest.mark.parametrize("length", SIZES)
def test_host_to_device(setup: Setup, length: int) -> None:
    payload = pattern(length, 1)
    to_device, to_host = host_to_device(setup, payload)
    data, fcs_from_host = split(to_device)
    _, fcs = split(to_host)
    assert len(data) == iso_data_frames(length)
    assert fcs_from_host == []
    assert len(fcs) == iso_flow_controls(length, setup.block_size)
    st_min = setup.stack.params.stmin
    for fc in fcs:
        assert fc == bytes([0x30, setup.block_size, st_min, 0xCC, 0xCC, 0xCC, 0xCC, 0xCC])


@pytest.mark.parametrize("length", SIZES)
def test_device_to_host(setup: Setup, length: int) -> None:
    payload = pattern(length, 2)
    to_device, to_host = device_to_host(setup, payload)
    data, fcs_from_device = split(to_host)
    _, fcs = split(to_device)
    assert len(data) == iso_data_frames(length)
    assert fcs_from_device == []
    assert len(fcs) == iso_flow_controls(length, setup.block_size)
    assert all(len(f) == 8 for f in data), "the device pads every frame to 8 bytes"
    # STmin is checked on the device's own clock (the bridge feeds it real
    # monotonic time): the times the bridge reads the frames at carry the
    # scheduling of two pipes and a thread, which bunches frames under load.
    with setup.bridge.traffic.lock:
        span = cf_span_s(setup.bridge.traffic.to_host, setup.bridge.traffic.to_host_us)
    assert span >= min_stmin_span_s(length, setup.block_size, setup.stack.params.stmin)
    if length > 7:
        assert data[0][:2] == bytes([0x10 | (length >> 8), length & 0xFF])
        sns = [f[0] & 0x0F for f in data[1:]]
        assert sns == [(i + 1) & 0x0F for i in range(len(sns))]


@pytest.mark.parametrize("length", [1, 7, 8, 20, 100])
def test_unpadded_device_padded_host(peer_path: str, length: int) -> None:
    with make_setup(peer_path, 4, 0, device_padding=False, host_padding=0xCC) as s:
        payload = pattern(length, 3)
        to_device, to_host = device_to_host(s, payload)
        data, _ = split(to_host)
        assert len(data) == iso_data_frames(length)
        # minimal lengths: SF 1+n, FF 8, CFs 8 except a short last one
        if length <= 7:
            assert len(data[0]) == 1 + length
        else:
            last = (length - 6) % 7 or 7
            assert [len(f) for f in data] == [8] * (len(data) - 1) + [1 + last]
        assert all(len(f) == 8 for f in to_device), "host pads its flow controls"

        to_device, to_host = host_to_device(s, payload)
        assert len(split(to_device)[0]) == iso_data_frames(length)
        assert all(len(f) == 3 for f in split(to_host)[1]), "unpadded FC is 3 bytes"
