"""A client written from the contract alone (docs/protocol.md).

This module imports nothing of the `landscape` package: only python-can, can-isotp and
the classes protoc generates from protocol/landscape.proto while the test runs. What it
knows of the wire comes from docs/protocol.md (addresses, ISO-TP addressing, the schema
hash recipe, seq rules, absent fields, the device description, notices); where the docs
were not enough, the docs were fixed, not this file.

The session is a sequence of small steps (RawClient methods and the step_* functions):
connect, read the description, take control, a move, a two-cycle tagged path, an RSVP
answered with decline and its effect, give control back, disconnect.
"""
from __future__ import annotations

import hashlib
import hmac
import importlib.util
import secrets
import socket
import struct
import subprocess
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from types import ModuleType
from typing import Any

import can
import isotp
import pytest

from conftest import Controller, open_slcan, start_controller

ROOT = Path(__file__).resolve().parents[2]

# docs/protocol.md "Identifiers and priorities"
DEVICE = 0x10          # landscaped's default node address
HOST = 0xF1            # the first address of the hosts' pool (docs/protocol.md "Addresses")
HEARTBEAT_ID = 0x14FF0100  # | sender address; hb_role (byte 2) 1 = supervisor
HEARTBEAT_PERIOD_S = 0.2


# ---------------------------------------------------------------- the schema, at test time

def compile_schema(out: Path) -> ModuleType:
    """protoc --python_out from protocol/landscape.proto into `out`; the module it wrote."""
    subprocess.run(["protoc", "-I", str(ROOT / "protocol"), "-I", "/usr/include", f"--python_out={out}",
                    str(ROOT / "protocol" / "landscape.proto")], check=True, capture_output=True, timeout=60)
    spec = importlib.util.spec_from_file_location("raw_landscape_pb2", out / "landscape_pb2.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def schema_hash() -> int:
    """docs/protocol.md "Schema hash": the first 4 bytes, big-endian, of the SHA-256 of the
    FileDescriptorSet `protoc -I protocol -I /usr/include --descriptor_set_out` writes."""
    desc = subprocess.run(["protoc", "-I", "protocol", "-I", "/usr/include", "--descriptor_set_out=/dev/stdout",
                           "protocol/landscape.proto"], cwd=ROOT, check=True, capture_output=True, timeout=60).stdout
    return int.from_bytes(hashlib.sha256(desc).digest()[:4], "big")


# ---------------------------------------------------------------- the client

class RawClient:
    """One session over ISO-TP normal fixed 29-bit addressing (docs/protocol.md "ISO-TP
    parameters"), with the supervisor HEARTBEAT sent every 200 ms."""

    def __init__(self, bus: can.BusABC, pb: ModuleType) -> None:
        self.bus = bus
        self.pb = pb
        self.seq = 0
        self.epoch = 0
        # docs/protocol.md "Identity": a random nonce with every connect; the heartbeat
        # token the connect answers goes into every heartbeat (0 until then)
        self.nonce = secrets.randbits(64)
        self.token = 0
        self.notices: list[Any] = []
        self.acks: list[Any] = []  # RsvpAck: the device's answer to each RsvpReply
        # docs/protocol.md "Security": a signed session's key K_s and the epoch its MACs
        # carry (0 for the challenge's answer and the connect); None: unsigned
        self.ks: bytes | None = None
        self.mac_epoch = 0
        self._notifier = can.Notifier(bus, [], timeout=0.01)
        address = isotp.Address(isotp.AddressingMode.NormalFixed_29bits, source_address=HOST,
                                target_address=DEVICE)
        self._stack = isotp.NotifierBasedCanStack(bus, self._notifier, address=address,
                                                  params={"blocking_send": False})
        self._stop = threading.Event()
        self._hb = threading.Thread(target=self._heartbeat, daemon=True)

    def __enter__(self) -> RawClient:
        self._stack.start()
        self._hb.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._hb.join(2)
        self._stack.stop()
        self._notifier.stop()

    def _heartbeat(self) -> None:
        # docs/protocol.md "Liveness": byte 0 hb_counter (+1 per frame), byte 2 hb_role 1,
        # bytes 3-4 hb_period_ms little-endian (the period stated at connect), bytes 5-7
        # hb_token little-endian (ConnectRes.heartbeat_token), byte 1 0
        # docs/protocol.md "Security": in a signed session hb_token is the 24-bit MAC of a full
        # counter (1 for the first heartbeat of the session) whose low 8 bits are byte 0
        period_ms = int(HEARTBEAT_PERIOD_S * 1000)
        counter = 0
        full = 0
        while not self._stop.is_set():
            t = self.token
            if self.ks is not None and self.epoch:
                full += 1
                counter = full & 0xFF
                msg = b"LS1H" + bytes([HOST]) + struct.pack("<IIH", self.epoch, full, period_ms)
                t = int.from_bytes(hmac.new(self.ks, msg, hashlib.sha256).digest()[:3], "little")
            data = bytes([counter, 0, 1, period_ms & 0xFF, period_ms >> 8, t & 0xFF, (t >> 8) & 0xFF, t >> 16])
            self.bus.send(can.Message(arbitration_id=HEARTBEAT_ID | HOST, is_extended_id=True, data=data))
            counter = (counter + 1) & 0xFF
            self._stop.wait(HEARTBEAT_PERIOD_S)

    def mac(self, direction: bytes, source: int, target: int, body: bytes) -> bytes:
        """docs/protocol.md "The signature": HMAC-SHA256 under K_s of the direction, both
        addresses, the epoch (LE32) and the body, cut to 8 bytes."""
        assert self.ks is not None
        head = direction + bytes([source, target]) + struct.pack("<I", self.mac_epoch)
        return hmac.new(self.ks, head + body, hashlib.sha256).digest()[:8]

    def send(self, uplink: Any) -> None:
        body = uplink.SerializeToString()
        if self.ks is not None:
            # the field mac (15, length-delimited: tag 0x7A, length 8) ends a signed message
            body += b"\x7a\x08" + self.mac(b"LS1U", HOST, DEVICE, body)
        self._stack.send(body)

    def _receive(self, timeout_s: float) -> Any | None:
        data = self._stack.recv(block=True, timeout=timeout_s)
        if data is None:
            return None
        data = bytes(data)
        if self.ks is not None:
            assert data[-10:-8] == b"\x7a\x08", f"an unsigned downlink in a signed session: {data.hex()}"
            assert hmac.compare_digest(data[-8:], self.mac(b"LS1D", DEVICE, HOST, data[:-10])), \
                f"a downlink whose MAC does not verify: {data.hex()}"
        down = self.pb.Downlink()
        down.ParseFromString(data)
        if down.WhichOneof("msg") == "notice":
            self.notices.append(down.notice)
        elif down.WhichOneof("msg") == "rsvp_ack":
            self.acks.append(down.rsvp_ack)
        return down

    def exchange(self, request: Any, timeout_s: float = 5.0) -> Any:
        """Send `request` as it is and return the Response carrying its seq; notices that
        arrive meanwhile are kept in self.notices."""
        self.send(self.pb.Uplink(request=request))
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            down = self._receive(deadline - time.monotonic())
            if down is not None and down.WhichOneof("msg") == "response" and down.response.seq == request.seq:
                return down.response
        raise AssertionError(f"no answer to seq {request.seq} ({request.WhichOneof('cmd')}) within {timeout_s} s")

    def call(self, timeout_s: float = 5.0, **command: Any) -> Any:
        """Send one request with a new seq > 0 (docs/protocol.md "Sequence numbers")."""
        self.seq += 1
        return self.exchange(self.pb.Request(seq=self.seq, **command), timeout_s)

    def ok(self, **command: Any) -> Any:
        res = self.call(**command)
        assert res.ret_code in (self.pb.CMD_EXEC_OK, self.pb.CMD_STARTED_OK), \
            f"{list(command)}: {self.pb.RetCode.Name(res.ret_code)} {res.ret_msg}"
        assert self.epoch == 0 or res.session_epoch == self.epoch  # 0: the connect that opens it
        return res

    def wait_for(self, pool: list[Any], match: Callable[[Any], bool], timeout_s: float) -> Any | None:
        """The first item of `pool` (self.notices or self.acks) that matches, receiving
        while there is none; None after timeout_s."""
        deadline = time.monotonic() + timeout_s
        while True:
            for item in pool:
                if match(item):
                    return item
            left = deadline - time.monotonic()
            if left <= 0:
                return None
            self._receive(min(left, 0.05))

    def final(self, seq: int, timeout_s: float = 30.0) -> Any:
        """The one final notice of the non-blocking request `seq` of this session
        (matched by ref_seq and session_epoch: docs/protocol.md "Session epoch")."""
        n = self.wait_for(self.notices, lambda n: n.final and n.ref_seq == seq and n.session_epoch == self.epoch,
                          timeout_s)
        assert n is not None, f"no final notice for seq {seq} within {timeout_s} s: {list(self.notices)}"
        return n

    def of(self, seq: int) -> list[Any]:
        """Every notice received about request `seq` of this session, in order."""
        return [n for n in self.notices if n.ref_seq == seq and n.session_epoch == self.epoch]


def data(notice: Any) -> dict[str, str]:
    return dict(item.partition("=")[::2] for item in notice.data)


# ---------------------------------------------------------------- the steps of a session

def step_connect(c: RawClient) -> Any:
    pb = c.pb
    res = c.ok(connect=pb.ConnectReq(protocol_version=pb.PROTOCOL_VERSION, schema_hash=schema_hash(),
                                     client_nonce=c.nonce, client_name="raw-client",
                                     heartbeat_period_ms=int(HEARTBEAT_PERIOD_S * 1000)))
    assert res.connect.schema_hash == schema_hash()
    assert res.connect.client_nonce == c.nonce  # the answer to our own connect
    assert 0 < res.connect.heartbeat_token <= 0xFFFFFF
    c.token = res.connect.heartbeat_token
    c.epoch = res.connect.session_epoch
    assert c.epoch > 0 and res.session_epoch == c.epoch
    return res.connect


def step_signed_connect(c: RawClient, key_id: str, key: bytes) -> Any:
    """docs/protocol.md "Signed connect": a challenge with our nonce, the session key from
    both nonces, the challenge's answer verified, the connect signed at epoch 0, its
    acceptance verified at the new session's epoch."""
    pb = c.pb
    host_nonce = secrets.token_bytes(16)
    res = c.ok(challenge=pb.ChallengeReq(key_id=key_id, host_nonce=host_nonce))
    assert res.challenge.auth_policy == pb.AUTH_SIGNED and len(res.challenge.device_nonce) == 16
    # K_s = HMAC(K, "LS1K" | host_nonce | device_nonce | host | device); the answer was
    # checked by _receive only from here on, so check it by hand
    c.ks = hmac.new(key, b"LS1K" + host_nonce + res.challenge.device_nonce + bytes([HOST, DEVICE]),
                    hashlib.sha256).digest()
    c.mac_epoch = 0
    connect = pb.ConnectReq(protocol_version=pb.PROTOCOL_VERSION, schema_hash=schema_hash(), client_nonce=c.nonce,
                            client_name="raw-signed", heartbeat_period_ms=int(HEARTBEAT_PERIOD_S * 1000),
                            key_id=key_id, host_nonce=host_nonce)
    c.seq += 1
    c.send(pb.Uplink(request=pb.Request(seq=c.seq, connect=connect)))
    # the acceptance is signed in the session's epoch, which it carries: read it, then verify
    data = bytes(c._stack.recv(block=True, timeout=5.0) or b"")
    down = pb.Downlink()
    down.ParseFromString(data)
    res = down.response
    assert res.ret_code == pb.CMD_EXEC_OK, f"{pb.RetCode.Name(res.ret_code)} {res.ret_msg}"
    assert res.connect.session_signed and res.connect.auth_policy == pb.AUTH_SIGNED
    c.mac_epoch = res.connect.session_epoch
    assert hmac.compare_digest(data[-8:], c.mac(b"LS1D", DEVICE, HOST, data[:-10])), "the acceptance is not signed"
    c.epoch = res.connect.session_epoch
    c.token = res.connect.heartbeat_token
    return res.connect


def step_describe(c: RawClient) -> Any:
    d = c.ok(describe=c.pb.DescribeReq()).describe
    assert d.max_paths > 0 and d.max_points_per_path > 0
    assert len(d.joints) == 6 and all(j.min_rad < j.max_rad for j in d.joints)
    assert len(d.workspace_min_m) == 3 and len(d.workspace_max_m) == 3
    return d


def limit(c: RawClient, d: Any, *names: str) -> Any:
    """The FieldLimit of request field path `names` (e.g. "path_load", "tags"): FieldLimit.path
    holds field numbers from ls.Uplink down (docs/protocol.md "Device description")."""
    desc = c.pb.Uplink.DESCRIPTOR.fields_by_name["request"]
    path = [desc.number]
    msg = desc.message_type
    for name in names:
        fd = msg.fields_by_name[name]
        path.append(fd.number)
        msg = fd.message_type
    found = [fl for fl in d.field_limits if list(fl.path) == path]
    assert len(found) == 1, f"the description has no limit for {names}"
    return found[0]


def step_take_control(c: RawClient) -> None:
    c.ok(lock=c.pb.LockReq())
    c.ok(activate=c.pb.ActivateReq())


def joints_now(c: RawClient) -> list[float]:
    return list(c.ok(get_robot_position=c.pb.GetRobotPositionReq()).get_robot_position.joints)


def within(d: Any, q: list[float]) -> list[float]:
    """q kept 0.05 rad inside the published joint limits."""
    return [min(max(v, j.min_rad + 0.05), j.max_rad - 0.05) for v, j in zip(q, d.joints, strict=True)]


def step_move(c: RawClient, d: Any) -> Any:
    pb = c.pb
    q = joints_now(c)
    target = within(d, [q[0] + 0.2, *q[1:]])
    res = c.ok(move_absolute=pb.MoveAbsoluteReq(point_name="raw-move", frame=pb.JOINT_FRAME, values=target))
    assert res.ret_code == pb.CMD_STARTED_OK
    n = c.final(res.seq)
    assert n.kind == pb.EVENT and n.event_id == "moveAbsoluteComplete", n
    assert data(n)["reason"] == "complete" and data(n)["point"] == "raw-move"
    return n


def step_two_cycle_path(c: RawClient, d: Any) -> list[Any]:
    pb = c.pb
    q = joints_now(c)
    points = [pb.TagPoint(joints=within(d, [q[0] - 0.15, *q[1:]]), tag_name="first"),
              pb.TagPoint(joints=within(d, [q[0], q[1] + 0.1, *q[2:]]), tag_name="second")]
    assert len(points) <= limit(c, d, "path_load", "tags").max_count
    assert len(b"second") <= limit(c, d, "path_load", "tags", "tag_name").max_bytes
    loaded = c.ok(path_load=pb.PathLoadReq(path_name="raw-path", frame=pb.JOINT_FRAME, motion_type=pb.JOINT_MOTION,
                                           offset_type=pb.ABSOLUTE_DATA, number_of_points=len(points),
                                           tags=points))
    assert loaded.path_load.points_in_path == 2
    res = c.ok(path_move=pb.PathMoveReq(path_name="raw-path", number_of_cycles=2))
    assert res.ret_code == pb.CMD_STARTED_OK
    n = c.final(res.seq, timeout_s=60)
    assert n.kind == pb.EVENT and n.event_id == "pathMoveComplete", n
    assert data(n)["reason"] == "complete" and "dry_run" not in data(n)
    tags = [data(t) for t in c.of(res.seq) if t.event_id == "tag"]
    assert [(t["tag"], t["cycle"]) for t in tags] == [("first", "1"), ("second", "1"), ("first", "2"),
                                                      ("second", "2")]
    assert all(t["path"] == "raw-path" for t in tags)
    return tags


def set_inputs(dio_socket: Path, on: int, off: int = 0) -> None:
    """The simulated inputs, through the sim world's control socket (test equipment standing
    in for the wiring, not the protocol)."""
    with socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM) as s:
        s.sendto(f"in {on:x} {off:x}".encode(), str(dio_socket))


def step_rsvp_decline(c: RawClient, dio_socket: Path) -> None:
    """docs/protocol.md "RSVP": a signalDigitalIO watch with an RSVP callback asks when its
    bits rise; decline cancels the watch, the reply's data reaches the event log, and the
    reply is acknowledged (a second answer to the same id is refused)."""
    pb = c.pb
    bit = 0x20
    set_inputs(dio_socket, 0, bit)
    armed = c.ok(signal_digital_io=pb.SignalDigitalIOReq(type="digital", unit_id=0, bit_string=bit,
                                                         callback_type=pb.CB_EVENT_RSVP))
    watch = armed.signal_digital_io.watch_id
    set_inputs(dio_socket, bit)
    ask = c.wait_for(c.notices, lambda n: n.event_id == "dioSignal" and n.kind == pb.EVENT_RSVP, 3.0)
    assert ask is not None, "no RSVP when the watched bit rose"
    assert (ask.ref_seq, ask.session_epoch) == (armed.seq, c.epoch)  # the request that armed it
    assert ask.rsvp_default == "cancel" and ask.rsvp_timeout_ms > 0

    c.send(pb.Uplink(rsvp_reply=pb.RsvpReply(rsvp_id=ask.rsvp_id, ret_code=pb.CMD_ERR, data=["raw=decline"])))
    ack = c.wait_for(c.acks, lambda a: a.rsvp_id == ask.rsvp_id, 2.0)
    assert ack is not None, "the reply was not acknowledged"
    assert (ack.ret_code, ack.action, ack.ref_seq) == (pb.CMD_EXEC_OK, "cancel", armed.seq)

    # the effect: the watch is gone, and the bit rising again asks nothing
    status = c.ok(send_command=pb.SendCommandReq(input="status")).send_command.result
    assert f"watch {watch} " not in status, status
    before = {id(n) for n in c.notices}
    set_inputs(dio_socket, 0, bit)
    time.sleep(0.05)
    set_inputs(dio_socket, bit)
    late = c.wait_for(c.notices, lambda n: id(n) not in before and n.event_id.startswith("dioSignal"), 1.0)
    assert late is None, f"the declined watch fired again: {late}"
    events = c.ok(send_command=pb.SendCommandReq(input="events")).send_command.result
    assert "declined -1, action cancel, data [raw=decline]" in events, events

    c.send(pb.Uplink(rsvp_reply=pb.RsvpReply(rsvp_id=ask.rsvp_id, ret_code=pb.CMD_EXEC_OK)))
    again = c.wait_for(c.acks, lambda a: a.rsvp_id == ask.rsvp_id and a is not ack, 2.0)
    assert again is not None and again.ret_code == pb.CMD_PARAM_ERR and "already answered" in again.ret_msg


def step_give_back(c: RawClient) -> None:
    c.ok(deactivate=c.pb.DeactivateReq())
    c.ok(release=c.pb.ReleaseReq())


def step_disconnect(c: RawClient) -> None:
    c.ok(disconnect=c.pb.DisconnectReq())
    # the session is gone: the next request (a new seq) is refused
    res = c.call(get_motion_control_state=c.pb.GetMotionControlStateReq())
    assert res.ret_code == c.pb.CMD_NOT_CONNECTED_ERR


# ---------------------------------------------------------------- the tests

def stopped_cleanly(controller: Controller) -> None:
    """Stop landscaped; a crash, a sanitizer report or a leak at shutdown fails the test."""
    code = controller.stop()
    log = controller.log.read_text(errors="replace")
    assert code == 0, f"landscaped exited with {code}:\n{log[-4000:]}"
    assert "Sanitizer" not in log, log[-4000:]


@pytest.fixture
def dio_socket(tmp_path: Path) -> Path:
    return tmp_path / "dio.sock"


@pytest.fixture
def raw(tmp_path: Path, dio_socket: Path) -> Iterator[RawClient]:
    pb = compile_schema(tmp_path)
    controller = start_controller(tmp_path / "ls0", "--dio-socket", str(dio_socket))
    bus = open_slcan(controller.pty)
    try:
        deadline = time.monotonic() + 10
        while not dio_socket.exists():
            assert time.monotonic() < deadline, "landscaped made no DIO control socket"
            time.sleep(0.02)
        with RawClient(bus, pb) as client:
            yield client
    finally:
        bus.shutdown()
        stopped_cleanly(controller)


def test_a_session_from_the_contract_alone(raw: RawClient, dio_socket: Path) -> None:
    step_connect(raw)
    d = step_describe(raw)
    step_take_control(raw)
    step_move(raw, d)
    step_two_cycle_path(raw, d)
    step_rsvp_decline(raw, dio_socket)
    step_give_back(raw)
    step_disconnect(raw)


def test_a_signed_session_from_the_contract_alone(tmp_path: Path) -> None:
    """docs/protocol.md "Security" alone: a device of policy signed refuses the unsigned
    connect naming the policy, then serves a signed one: describe, a move, give back,
    disconnect, with every message both ways signed and heartbeats carrying their MACs."""
    pb = compile_schema(tmp_path)
    key = secrets.token_bytes(32)
    keys = tmp_path / "keys"
    keys.write_text(f"raw = {key.hex()}\n")
    keys.chmod(0o600)
    conf = tmp_path / "landscaped.conf"
    conf.write_text(f"[security]\npolicy = signed\nkey_file = {keys}\n")
    controller = start_controller(tmp_path / "ls0", "--config", str(conf))
    bus = open_slcan(controller.pty)
    try:
        with RawClient(bus, pb) as c:
            res = c.call(connect=pb.ConnectReq(protocol_version=pb.PROTOCOL_VERSION, schema_hash=schema_hash(),
                                               client_nonce=c.nonce, heartbeat_period_ms=200))
            assert res.ret_code == pb.CMD_AUTH_ERR and "policy signed" in res.ret_msg, res.ret_msg
            step_signed_connect(c, "raw", key)
            d = step_describe(c)
            assert d.auth_policy == pb.AUTH_SIGNED
            step_take_control(c)
            time.sleep(1.5)  # longer than the 1 s time-out: only signed heartbeats kept the session
            step_move(c, d)
            step_give_back(c)
            c.ok(disconnect=pb.DisconnectReq())
    finally:
        bus.shutdown()
        stopped_cleanly(controller)


def test_what_the_contract_refuses(raw: RawClient) -> None:
    """The rules of docs/protocol.md that a careless client meets first: a connect without
    its nonce, seq 0 after connect, an absent required field, an absent number_of_cycles (one
    cycle, not a dry run)."""
    pb = raw.pb
    res = raw.call(connect=pb.ConnectReq(protocol_version=pb.PROTOCOL_VERSION, schema_hash=schema_hash()))
    assert res.ret_code == pb.CMD_PARAM_ERR and "client_nonce is missing" in res.ret_msg, res.ret_msg
    step_connect(raw)
    d = step_describe(raw)
    # seq 0 is not a seq: refused, nothing runs
    res = raw.exchange(pb.Request(seq=0, lock=pb.LockReq()))
    assert res.ret_code == pb.CMD_PARAM_ERR and "seq is 0" in res.ret_msg
    state = raw.ok(get_motion_control_state=pb.GetMotionControlStateReq()).get_motion_control_state.state
    assert state == pb.UNLOCKED
    step_take_control(raw)
    # a move without its frame: refused naming the field
    res = raw.call(move_absolute=pb.MoveAbsoluteReq(point_name="p", values=joints_now(raw)))
    assert res.ret_code == pb.CMD_PARAM_ERR and "frame is missing" in res.ret_msg
    # -1 for an enum without negative values (a 10-byte varint): refused naming the field and
    # the range its type holds (the probe found "integer too large" naming nothing)
    res = raw.call(signal_digital_io=pb.SignalDigitalIOReq(type="digital", unit_id=0, bit_string=1,
                                                           callback_type=-1))
    assert res.ret_code == pb.CMD_PARAM_ERR
    assert res.ret_msg == ("signalDigitalIO did not decode (integer too large): signal_digital_io.callback_type "
                           "is -1, outside 0..4294967295 (the schema's type): send a value it holds"), res.ret_msg
    # pathMove without number_of_cycles runs once (seed 3.5.2), with its auxiliary command
    q = joints_now(raw)
    point = pb.TagPoint(joints=within(d, [q[0] + 0.1, *q[1:]]), tag_name="only", aux_commands=["event aux"])
    raw.ok(path_load=pb.PathLoadReq(path_name="once", frame=pb.JOINT_FRAME, motion_type=pb.JOINT_MOTION,
                                    offset_type=pb.ABSOLUTE_DATA, number_of_points=1, tags=[point]))
    res = raw.ok(path_move=pb.PathMoveReq(path_name="once"))
    n = raw.final(res.seq)
    assert n.event_id == "pathMoveComplete" and "dry_run" not in data(n)
    assert [data(t)["cycle"] for t in raw.of(res.seq) if t.event_id == "tag"] == ["1"]
    assert any(x.event_id == "aux" for x in raw.notices), "the auxiliary command did not run"
    step_give_back(raw)
    step_disconnect(raw)
