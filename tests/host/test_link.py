"""Sharing one SLCAN link (landscape/link.py): the broker's fan-out, its holder file, and the
one line a second opener of a held line gets."""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

import can
import pytest

from landscape import BusSpec
from landscape import telemetry as tm
from landscape._generated import landscape_pb2 as pb
from landscape.bus import open_bus, release_bus
from landscape.errors import BusError
from landscape.link import LinkBroker, LinkBusyError, busy_message, read_holder
from pty_link import PtySlcanBus

#: A device's broadcast and a host's request to it, as the broker carries them.
DEVICE_FRAME_ID = tm.frame_id("STATUS", pb.DEFAULT_DEVICE_ADDRESS)
HOST_FRAME_ID = pb.ISOTP_PHYSICAL_BASE | pb.DEFAULT_DEVICE_ADDRESS << 8 | pb.DEFAULT_HOST_ADDRESS


@pytest.fixture
def runtime_dir(monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    d = Path(tempfile.mkdtemp(prefix="ls-link-"))
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(d))
    yield d
    shutil.rmtree(d, ignore_errors=True)


@pytest.fixture
def device_end() -> Iterator[PtySlcanBus]:
    link = PtySlcanBus()
    yield link
    link.shutdown()


@pytest.fixture
def broker(device_end: PtySlcanBus, runtime_dir: Path) -> Iterator[LinkBroker]:
    b = LinkBroker(device_end.path)
    b.start()
    yield b
    b.stop()


def shared_bus(url: str) -> can.BusABC:
    return can.Bus(interface="slcan", channel=url, bitrate=1000000, sleep_after_open=0)


def recv_ids(bus: can.BusABC, n: int, timeout_s: float = 3.0) -> list[int]:
    out: list[int] = []
    deadline = time.monotonic() + timeout_s
    while len(out) < n and time.monotonic() < deadline:
        m = bus.recv(0.1)
        if m is not None:
            out.append(m.arbitration_id)
    return out


def test_frames_fan_out_as_on_a_bus(broker: LinkBroker, device_end: PtySlcanBus) -> None:
    a, b = shared_bus(broker.url), shared_bus(broker.url)
    try:
        time.sleep(0.2)  # both accepted
        # device -> every client
        device_end.send(can.Message(arbitration_id=DEVICE_FRAME_ID, is_extended_id=True, data=b"\x01\x02"))
        assert recv_ids(a, 1) == [DEVICE_FRAME_ID]
        assert recv_ids(b, 1) == [DEVICE_FRAME_ID]
        # client a -> the device and client b, never back to a
        a.send(can.Message(arbitration_id=HOST_FRAME_ID, is_extended_id=True, data=b"\x02\x10\x01"))
        got = device_end.recv(2.0)
        assert got is not None and got.arbitration_id == HOST_FRAME_ID and bytes(got.data) == b"\x02\x10\x01"
        assert recv_ids(b, 1) == [HOST_FRAME_ID]
        assert recv_ids(a, 1, timeout_s=0.3) == []
    finally:
        a.shutdown()
        # a client closing its bus (python-can writes C) must not close the channel for the others
        device_end.send(can.Message(arbitration_id=0x123, data=b"\x07"))
        assert recv_ids(b, 1) == [0x123]
        b.shutdown()
    assert broker.frames_to_device == 1 and broker.frames_from_device == 2


def test_open_bus_shares_a_served_line(broker: LinkBroker, device_end: PtySlcanBus) -> None:
    holder = read_holder(device_end.path)
    assert holder is not None and holder.url == broker.url and holder.url.startswith("socket://127.0.0.1:")
    bus = open_bus(BusSpec("slcan", device_end.path))
    try:
        assert bus.serialPortOrig.portstr == broker.url  # python-can's slcan on the broker's loopback URL
        time.sleep(0.2)
        device_end.send(can.Message(arbitration_id=0x321, data=b"\x01"))
        assert recv_ids(bus, 1) == [0x321]
    finally:
        bus.shutdown()
        release_bus(bus)


def test_holder_file_goes_with_the_broker(device_end: PtySlcanBus, runtime_dir: Path) -> None:
    b = LinkBroker(device_end.path)
    b.start()
    assert read_holder(device_end.path) is not None
    b.stop()
    assert read_holder(device_end.path) is None and not list(runtime_dir.glob("landscape-link-*"))


def test_second_broker_on_a_served_line_is_refused(broker: LinkBroker, device_end: PtySlcanBus) -> None:
    script = ("import sys\nfrom landscape.link import LinkBroker, LinkBusyError\n"
              "try:\n    LinkBroker(sys.argv[1]).start()\nexcept LinkBusyError as e:\n    print(e)\n")
    p = subprocess.run([sys.executable, "-c", script, device_end.path], capture_output=True, text=True, timeout=60)
    assert p.returncode == 0, p.stderr
    import os
    assert p.stdout.strip() == (f"{device_end.path} is already served by pid {os.getpid()} at {broker.url}: "
                                f"use that session (`landscape session status`)")


def test_a_held_line_gives_one_line_naming_the_holder(device_end: PtySlcanBus, runtime_dir: Path) -> None:
    # Another process opens the line with landscape's one-shot claim and keeps it.
    holder = subprocess.Popen([sys.executable, "-c", "import sys, time\nfrom landscape.link import claim\n"
                               "claim(sys.argv[1]); print('held', flush=True); time.sleep(60)", device_end.path],
                              stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout is not None and holder.stdout.readline().strip() == "held"
        with pytest.raises(LinkBusyError) as err:
            open_bus(BusSpec("slcan", device_end.path))
        msg = str(err.value)
        assert "\n" not in msg and msg.startswith(f"{device_end.path} is already open in pid {holder.pid} (")
        assert "run `landscape session start` once and every landscape command shares the link" in msg
        assert isinstance(err.value, BusError)
    finally:
        holder.kill()
        holder.wait(10)


def test_busy_message_without_a_known_pid() -> None:
    assert busy_message("/dev/pts/9", None).startswith("/dev/pts/9 is already open in another process; ")


def test_unknown_bitrate_is_refused_with_the_choices() -> None:
    with pytest.raises(BusError, match=r"SLCAN has no bit rate 123; use one of 10000, 20000"):
        LinkBroker("/dev/null", bitrate=123)


@pytest.mark.parametrize("buf,want", [(b"", -1), (b"t1230", -1), (b"t1230\r", 5), (b"\a", 0), (b"x\ay\r", 1),
                                      (b"x\ry\a", 1)])
def test_line_end_finds_the_first_terminator(buf: bytes, want: int) -> None:
    from landscape.link import line_end
    assert line_end(buf) == want


def test_a_client_outlives_the_broker_quietly(device_end: PtySlcanBus, runtime_dir: Path,
                                              monkeypatch: pytest.MonkeyPatch,
                                              caplog: pytest.LogCaptureFixture) -> None:
    """The session stops while another process's supervisor uses the link: no exception in
    python-can's or can-isotp's threads, one warning, and a request ends in a clean time-out."""
    import threading

    from landscape import Supervisor
    from landscape.errors import ControllerTimeoutError

    thread_errors: list[BaseException | None] = []
    monkeypatch.setattr(threading, "excepthook", lambda args: thread_errors.append(args.exc_value))
    b = LinkBroker(device_end.path)
    b.start()
    bus = open_bus(BusSpec("slcan", device_end.path))
    notifier = can.Notifier(bus, [], timeout=0.05)
    sup = Supervisor(bus, timeout_s=0.2, retries=0, notifier=notifier)
    try:
        sup._start_transport()  # no device answers here: the transport alone, as after a connect
        sup.connected = True
        b.stop()
        time.sleep(0.5)
        with pytest.raises(ControllerTimeoutError):
            sup.request("get_motion_control_state")
        time.sleep(0.3)
    finally:
        sup.connected = False
        sup.close()
        notifier.stop()
        bus.shutdown()   # writes C: goes nowhere, raises nothing
        release_bus(bus)
    assert thread_errors == []
    warnings = [r.getMessage() for r in caplog.records if "the shared link" in r.getMessage()]
    assert len(warnings) == 1 and warnings[0].startswith(f"the shared link {b.url} closed (")


def test_a_claimed_line_is_read_in_chunks(device_end: PtySlcanBus, runtime_dir: Path,
                                          monkeypatch: pytest.MonkeyPatch) -> None:
    # python-can's slcan reader makes a read call per byte: a busy gateway then reads the pty
    # slower than the device writes, and answers wait behind seconds of telemetry in the pty.
    bus = open_bus(BusSpec("slcan", device_end.path))
    try:
        fd = bus.__wrapped__.serialPortOrig.fd  # type: ignore[attr-defined]
        reads = 0
        real_read = os.read

        def counting_read(f: int, n: int) -> bytes:
            nonlocal reads
            reads += f == fd
            return real_read(f, n)

        frames = 200
        for i in range(frames):  # all waiting in the pty (15 bytes each) before the host reads
            device_end.send(can.Message(arbitration_id=DEVICE_FRAME_ID, data=i.to_bytes(2, "little")))
        time.sleep(0.2)
        monkeypatch.setattr(os, "read", counting_read)
        got = [m for m in (bus.recv(1.0) for _ in range(frames)) if m is not None]
        monkeypatch.undo()
        assert [int.from_bytes(m.data, "little") for m in got] == list(range(frames))
        assert reads <= 20, f"{reads} read calls for {frames} frames ({frames * 15} bytes): read byte by byte"
    finally:
        bus.shutdown()
        release_bus(bus)
