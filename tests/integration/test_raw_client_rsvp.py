"""A client written from protocol/landscape.proto, the DBC and docs/protocol.md alone
answers an RSVP with decline and sees the effect (issue 19, item 4).

Only python-can, can-isotp and the classes protoc generates from the schema at
test time: nothing from the `landscape` package. The supervisor heartbeat is
built from its documented layout (docs/protocol.md "Liveness", the DBC's
HEARTBEAT with hb_role 1)."""
from __future__ import annotations

import hashlib
import importlib.util
import socket
import subprocess
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType
from typing import Any

import can
import isotp
import pytest

from conftest import ROOT, start_controller

DEVICE, HOST = 0x10, 0xF1
HEARTBEAT_ID = 0x14FF0100
PERIOD_MS = 100


def _protoc_module(out: Path) -> tuple[ModuleType, int]:
    """landscape_pb2 generated now, and the schema hash by the published recipe."""
    proto = ROOT / "protocol"
    subprocess.run(["protoc", f"-I{proto}", "-I/usr/include", f"--python_out={out}",
                    str(proto / "landscape.proto")], check=True)
    desc = subprocess.run(["protoc", f"-I{proto}", "-I/usr/include", "--descriptor_set_out=/dev/stdout",
                           str(proto / "landscape.proto")], check=True, capture_output=True).stdout
    spec = importlib.util.spec_from_file_location("raw_landscape_pb2", out / "landscape_pb2.py")
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod, int.from_bytes(hashlib.sha256(desc).digest()[:4], "big")


class RawClient:
    def __init__(self, pb: Any, schema_hash: int, bus: can.BusABC) -> None:
        self.pb = pb
        self.schema_hash = schema_hash
        self.bus = bus
        self.notifier = can.Notifier(bus, [], timeout=0.01)
        addr = isotp.Address(isotp.AddressingMode.NormalFixed_29bits, source_address=HOST, target_address=DEVICE)
        self.stack = isotp.NotifierBasedCanStack(bus, self.notifier, address=addr,
                                                 params={"tx_padding": 0xCC, "tx_data_min_length": 8,
                                                         "blocksize": 8, "stmin": 0, "max_frame_size": 4095})
        self.stack.start()
        self.seq = 0
        self.notices: list[Any] = []
        self.acks: list[Any] = []
        self._stop = threading.Event()
        self._hb = threading.Thread(target=self._beat, daemon=True)
        self._hb.start()

    def _beat(self) -> None:
        counter = 0
        while not self._stop.is_set():
            # HEARTBEAT, hb_role 1: hb_counter, 0, hb_role, hb_period_ms (LE 16 bits), 0, 0, 0
            data = bytes([counter, 0, 1, PERIOD_MS & 0xFF, PERIOD_MS >> 8, 0, 0, 0])
            self.bus.send(can.Message(arbitration_id=HEARTBEAT_ID | HOST, is_extended_id=True, data=data))
            counter = (counter + 1) & 0xFF
            self._stop.wait(PERIOD_MS / 1000)

    def close(self) -> None:
        self._stop.set()
        self._hb.join(2)
        self.stack.stop()
        self.notifier.stop()

    def _pump(self, timeout_s: float) -> Any | None:
        data = self.stack.recv(block=True, timeout=timeout_s)
        if data is None:
            return None
        dl = self.pb.Downlink()
        dl.ParseFromString(bytes(data))
        which = dl.WhichOneof("msg")
        if which == "notice":
            self.notices.append(dl.notice)
        elif which == "rsvp_ack":
            self.acks.append(dl.rsvp_ack)
        return dl

    def request(self, **cmd: Any) -> Any:
        self.seq += 1
        self.stack.send(self.pb.Uplink(request=self.pb.Request(seq=self.seq, **cmd)).SerializeToString())
        deadline = time.monotonic() + 3
        while time.monotonic() < deadline:
            dl = self._pump(0.1)
            if dl is not None and dl.WhichOneof("msg") == "response" and dl.response.seq == self.seq:
                return dl.response
        raise AssertionError(f"no answer to seq {self.seq}")

    def wait(self, what: str, match: Any, timeout_s: float) -> Any | None:
        pool = self.notices if what == "notice" else self.acks
        deadline = time.monotonic() + timeout_s
        while True:
            for i, item in enumerate(pool):
                if match(item):
                    return pool.pop(i)
            left = deadline - time.monotonic()
            if left <= 0:
                return None
            self._pump(min(left, 0.05))


@pytest.fixture
def rig(tmp_path: Path) -> Iterator[tuple[RawClient, Path]]:
    pb, schema_hash = _protoc_module(tmp_path)
    sock = tmp_path / "dio.sock"
    c = start_controller(tmp_path / "ls0", "--dio-socket", str(sock))
    bus = can.Bus(interface="slcan", channel=c.pty, bitrate=1000000, sleep_after_open=0)
    client = RawClient(pb, schema_hash, bus)
    try:
        deadline = time.monotonic() + 10
        while not sock.exists():
            assert time.monotonic() < deadline, "no DIO control socket"
            time.sleep(0.02)
        yield client, sock
    finally:
        client.close()
        bus.shutdown()
        assert c.stop() == 0


def _inputs(sock: Path, on: int, off: int = 0) -> None:
    """The simulated inputs (the sim world's control socket: test equipment, not the protocol)."""
    with socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM) as s:
        s.sendto(f"in {on:x} {off:x}".encode(), str(sock))


def test_decline_of_a_dio_rsvp_cancels_the_watch(rig: tuple[RawClient, Path]) -> None:
    cl, sock = rig
    pb = cl.pb
    res = cl.request(connect=pb.ConnectReq(protocol_version=pb.PROTOCOL_VERSION, schema_hash=cl.schema_hash,
                                           client_name="raw", heartbeat_period_ms=PERIOD_MS))
    assert res.ret_code == pb.CMD_EXEC_OK, res.ret_msg
    epoch = res.connect.session_epoch
    assert (res.connect.linear_unit, res.connect.angular_unit) == (pb.METERS, pb.RADIANS)
    assert res.connect.disconnect_action == pb.DISCONNECT_STOP_DEACTIVATE_RELEASE
    _inputs(sock, 0, 0xFFFF)
    time.sleep(0.05)
    res = cl.request(signal_digital_io=pb.SignalDigitalIOReq(type="digital", unit_id=0, bit_string=0x20,
                                                             callback_type=pb.CB_EVENT_RSVP))
    assert res.ret_code == pb.CMD_EXEC_OK, res.ret_msg
    armed_by, watch = res.seq, res.signal_digital_io.watch_id
    _inputs(sock, 0x20)
    ask = cl.wait("notice", lambda n: n.event_id == "dioSignal", 3.0)
    assert ask is not None and ask.kind == pb.EVENT_RSVP
    assert (ask.ref_seq, ask.session_epoch) == (armed_by, epoch)  # the request that armed it
    assert ask.rsvp_default == "cancel" and ask.rsvp_timeout_ms > 0

    cl.stack.send(pb.Uplink(rsvp_reply=pb.RsvpReply(rsvp_id=ask.rsvp_id, ret_code=pb.CMD_ERR,
                                                    data=["raw=decline"])).SerializeToString())
    ack = cl.wait("ack", lambda a: a.rsvp_id == ask.rsvp_id, 2.0)
    assert ack is not None, "the reply was not acknowledged"
    assert (ack.ret_code, ack.action, ack.ref_seq) == (pb.CMD_EXEC_OK, "cancel", armed_by)

    # the effect: the watch is gone and the bits rising again say nothing
    status = cl.request(send_command=pb.SendCommandReq(input="status")).send_command.result
    assert f"watch {watch} " not in status, status
    _inputs(sock, 0, 0x20)
    time.sleep(0.05)
    _inputs(sock, 0x20)
    assert cl.wait("notice", lambda n: n.event_id.startswith("dioSignal"), 1.0) is None
    events = cl.request(send_command=pb.SendCommandReq(input="events")).send_command.result
    assert "declined -1, action cancel, data [raw=decline]" in events, events

    # a second answer is refused with the reason
    cl.stack.send(pb.Uplink(rsvp_reply=pb.RsvpReply(rsvp_id=ask.rsvp_id, ret_code=0)).SerializeToString())
    again = cl.wait("ack", lambda a: a.rsvp_id == ask.rsvp_id, 2.0)
    assert again is not None and again.ret_code == pb.CMD_PARAM_ERR and "already answered" in again.ret_msg
    assert cl.request(disconnect=pb.DisconnectReq()).ret_code == pb.CMD_EXEC_OK
