"""Bad input on the bus against the running firmware: truncated transfers,
lengths the transport cannot take, messages that do not decode, unknown
commands, requests over nanopb's static sizes, random frames and SLCAN lines.
Each gets an error response or is dropped (and counted), never a crash or a
hang: after every case the device still answers, and its process still runs.

Raw frames come from python-can on the same pty; answers are read with an
ISO-TP stack of the sender's address (a listen-mode one beside a Supervisor,
whose own stack sends the flow controls)."""
from __future__ import annotations

import random
import threading
import time
from collections.abc import Iterator

import can
import isotp
import pytest

from conftest import Controller
from landscape import telemetry as tm
from landscape._generated import landscape_pb2 as pb
from landscape.errors import ArgumentError
from landscape.registry import COMMANDS
from landscape.supervisor import Supervisor

DEVICE = pb.DEFAULT_DEVICE_ADDRESS
HOST = pb.DEFAULT_HOST_ADDRESS
N_CR_S = 1.0  # the firmware's N_Cr (docs/protocol.md)
WAIT_S = 1.0


def phys_id(target: int, source: int) -> int:
    return pb.ISOTP_PHYSICAL_BASE | target << 8 | source


def frame(can_id: int, data: bytes) -> can.Message:
    return can.Message(arbitration_id=can_id, is_extended_id=True, data=data)


def varint(n: int) -> bytes:
    out = bytearray()
    while True:
        b = n & 0x7F
        n >>= 7
        out.append(b | (0x80 if n else 0))
        if not n:
            return bytes(out)


def field_bytes(number: int, payload: bytes) -> bytes:
    """A length-delimited protobuf field, encoded by hand."""
    return varint(number << 3 | 2) + varint(len(payload)) + payload


class Reader:
    """Downlinks the device sends to `source`."""

    def __init__(self, bus: can.BusABC, notifier: can.Notifier, source: int, listen: bool) -> None:
        address = isotp.Address(isotp.AddressingMode.NormalFixed_29bits, source_address=source,
                                target_address=DEVICE)
        self.stack = isotp.NotifierBasedCanStack(bus, notifier, address=address,
                                                 params={"listen_mode": listen, "max_frame_size": 4095,
                                                         "tx_padding": 0xCC, "blocksize": 8, "stmin": 0})
        self.stack.start()

    def drain(self, quiet_s: float = 0.5) -> None:
        """Wait until the device has been quiet towards `source` for quiet_s. A
        slow device (the TSan build) may still be answering a request the
        supervisor sent twice (the connect): 0.1 s let such a late answer land in
        the next test's "nothing sent" window (CI, TSan tier)."""
        while self.stack.recv(block=True, timeout=quiet_s) is not None:
            pass

    def responses(self, quiet_s: float) -> list[pb.Response]:
        out = []
        while (data := self.stack.recv(block=True, timeout=quiet_s)) is not None:
            dl = pb.Downlink.FromString(bytes(data))
            if dl.WhichOneof("msg") == "response":
                out.append(dl.response)
        return out

    def response(self, seq: int) -> pb.Response:
        deadline = time.monotonic() + WAIT_S
        while (left := deadline - time.monotonic()) > 0:
            data = self.stack.recv(block=True, timeout=left)
            if data is None:
                break
            dl = pb.Downlink.FromString(bytes(data))
            if dl.WhichOneof("msg") == "response" and dl.response.seq == seq:
                return dl.response
        raise AssertionError(f"no response with seq {seq} within {WAIT_S} s")

    def send(self, payload: bytes) -> None:
        self.stack.send(payload)

    def close(self) -> None:
        self.stack.stop()


class Frames(can.Listener):
    """Frames the device sends on the ISO-TP link to `source`."""

    def __init__(self, source: int) -> None:
        self.can_id = phys_id(source, DEVICE)
        self.lock = threading.Lock()
        self.frames: list[bytes] = []

    def on_message_received(self, msg: can.Message) -> None:
        if msg.is_extended_id and msg.arbitration_id == self.can_id:
            with self.lock:
                self.frames.append(bytes(msg.data))

    def flow_controls(self) -> list[bytes]:
        with self.lock:
            return [f for f in self.frames if f[0] >> 4 == 3]

    def clear(self) -> None:
        with self.lock:
            self.frames.clear()


@pytest.fixture
def sup(bus: can.BusABC, notifier: can.Notifier, controller: Controller) -> Iterator[Supervisor]:
    with Supervisor(bus, notifier=notifier, source_address=HOST, client_name="victim") as s:
        yield s
    assert controller.proc.poll() is None, "landscaped died"


@pytest.fixture
def reader(bus: can.BusABC, notifier: can.Notifier, sup: Supervisor) -> Iterator[Reader]:
    r = Reader(bus, notifier, HOST, listen=True)
    try:
        yield r
    finally:
        r.close()


def status(sup: Supervisor) -> dict[str, str]:
    out: dict[str, str] = {}
    for line in sup.send_command("status").result["result"].splitlines():
        if "=" in line and not line.startswith("session "):
            k, v = line.split("=", 1)
            out[k] = v
    return out


def raw_request(sup: Supervisor, payload: bytes) -> int:
    """Send an encoded ls.Uplink on the supervisor's own link with the next seq; returns that seq.
    (The seq is taken so that the Supervisor's next request does not reuse it.)"""
    with sup._req_lock:
        sup._seq += 1
        sup._send(payload)
        seq = sup._seq
    # The answer is judged from the end of the transfer: a 3,000-byte request is 430
    # frames and 54 flow controls, which alone took over WAIT_S on a loaded machine.
    stack = sup._stack
    deadline = time.monotonic() + 10.0
    while stack is not None and stack.transmitting() and time.monotonic() < deadline:
        time.sleep(0.005)
    return seq


# ---------------------------------------------------------------- transport


def test_truncated_transfer_times_out_and_the_device_serves_on(bus: can.BusABC, notifier: can.Notifier,
                                                              sup: Supervisor) -> None:
    seen = Frames(0xF3)
    notifier.add_listener(seen)
    try:
        with Supervisor(bus, notifier=notifier, source_address=0xF2, client_name="bystander") as other:
            # 0xF3 announces 4095 bytes, gets its flow control, and goes silent
            bus.send(frame(phys_id(DEVICE, 0xF3), bytes([0x1F, 0xFF, 1, 2, 3, 4, 5, 6])))
            t0 = time.monotonic()
            deadline = t0 + WAIT_S
            while not seen.flow_controls() and time.monotonic() < deadline:
                time.sleep(0.005)
            assert seen.flow_controls() == [bytes([0x30, 8, 0, 0xCC, 0xCC, 0xCC, 0xCC, 0xCC])]
            # other supervisors are served while 0xF3's reception waits out N_Cr
            for _ in range(5):
                assert other.get_motion_control_state().ok
                assert sup.get_motion_control_state().ok
            assert time.monotonic() - t0 < N_CR_S
            time.sleep(N_CR_S + 0.2 - (time.monotonic() - t0))
            # after N_Cr the half message is gone: 0xF3's next CF is unexpected, a new SF is served
            seen.clear()
            bus.send(frame(phys_id(DEVICE, 0xF3), bytes([0x21, 7, 8, 9, 10, 11, 12, 13])))
            time.sleep(0.1)
            assert seen.frames == []
            r = Reader(bus, notifier, 0xF3, listen=False)
            try:
                r.send(pb.Uplink(request=pb.Request(seq=9, get_motion_control_state={})).SerializeToString())
                assert r.response(9).ret_code == pb.CMD_NOT_CONNECTED_ERR
            finally:
                r.close()
    finally:
        notifier.remove_listener(seen)


def test_a_new_request_replaces_a_truncated_one_of_the_same_supervisor(bus: can.BusABC, sup: Supervisor) -> None:
    bus.send(frame(phys_id(DEVICE, HOST), bytes([0x1F, 0xFF, 1, 2, 3, 4, 5, 6])))
    time.sleep(0.05)
    t0 = time.monotonic()
    assert sup.get_motion_control_state(timeout_s=0.5).ok  # no retransmission needed
    assert time.monotonic() - t0 < 0.5


@pytest.mark.parametrize("first_frame", [
    bytes([0x10, 0x00, 0x00, 0x00, 0x13, 0x88, 0, 0]),  # 32-bit escape: 5000 bytes
    bytes([0x10, 0x00, 0x00, 0x00, 0x00, 0x10, 0, 0]),  # escape announcing 16 bytes (still unsupported)
], ids=["escape-5000", "escape-16"])
def test_first_frame_with_the_length_escape_gets_overflow(bus: can.BusABC, notifier: can.Notifier,
                                                           sup: Supervisor, first_frame: bytes) -> None:
    seen = Frames(0xF3)
    notifier.add_listener(seen)
    try:
        bus.send(frame(phys_id(DEVICE, 0xF3), first_frame))
        deadline = time.monotonic() + WAIT_S
        while not seen.frames and time.monotonic() < deadline:
            time.sleep(0.005)
        time.sleep(0.05)
        assert len(seen.frames) == 1, "one flow control and nothing else"
        assert seen.frames[0][0] == 0x32 and len(seen.frames[0]) == 8  # FC.OVFLW, padded
    finally:
        notifier.remove_listener(seen)
    assert sup.get_motion_control_state().ok


@pytest.mark.parametrize("data", [
    bytes([0x21, 1, 2, 3, 4, 5, 6, 7]),          # CF without a FF
    bytes([0x30, 8, 0, 0xCC, 0xCC, 0xCC, 0xCC, 0xCC]),  # FC while the device sends nothing
    bytes([0x00, 0xCC, 0xCC]),                   # SF of length 0
    bytes([0x08, 1, 2, 3, 4, 5, 6, 7]),          # SF of length 8
    bytes([0x05, 1, 2]),                         # SF shorter than it says
    bytes([0x10, 0x05, 1, 2, 3, 4, 5, 6]),       # FF of 5 bytes (fits a SF)
    bytes([0x40, 0, 0, 0, 0, 0, 0, 0]),          # unknown PCI type
    b"",                                         # empty frame
], ids=["cf-alone", "fc-idle", "sf-0", "sf-8", "sf-short", "ff-5", "pci-4", "empty"])
def test_malformed_transport_frames_are_dropped(bus: can.BusABC, notifier: can.Notifier, sup: Supervisor,
                                                reader: Reader, data: bytes) -> None:
    seen = Frames(HOST)
    notifier.add_listener(seen)
    try:
        reader.drain()
        seen.clear()
        bus.send(frame(phys_id(DEVICE, HOST), data))
        time.sleep(0.15)
        assert seen.frames == [], "the device must not answer a malformed frame"
    finally:
        notifier.remove_listener(seen)
    assert sup.get_motion_control_state().ok


def test_consecutive_frame_with_a_wrong_sequence_number_aborts_the_message(bus: can.BusABC, sup: Supervisor,
                                                                            reader: Reader) -> None:
    payload = pb.Uplink(request=pb.Request(seq=sup._seq + 1, send_command=pb.SendCommandReq(input="version"))) \
        .SerializeToString()
    assert len(payload) > 13  # FF + at least two CFs
    reader.drain()
    with sup._req_lock:
        sup._seq += 1
        bus.send(frame(phys_id(DEVICE, HOST), bytes([0x10, len(payload)]) + payload[:6]))
        time.sleep(0.02)
        rest = payload[6:] + b"\xcc" * (7 - len(payload[6:]))
        bus.send(frame(phys_id(DEVICE, HOST), bytes([0x22]) + rest))  # SN 2 instead of 1
    assert reader.responses(0.3) == []
    assert sup.send_command("version").ok


def test_back_to_back_single_frames_in_one_read_are_both_served(bus: can.BusABC, notifier: can.Notifier,
                                                                sup: Supervisor) -> None:
    """Two complete single frames of one sender that reach the device in one
    read of the pty: both requests are answered."""
    r = Reader(bus, notifier, 0xF4, listen=False)
    try:
        lines = b""
        for seq in (1, 2):
            uplink = pb.Uplink(request=pb.Request(seq=seq, get_motion_control_state={})).SerializeToString()
            data = bytes([len(uplink)]) + uplink + b"\xcc" * (7 - len(uplink))
            lines += f"T{phys_id(DEVICE, 0xF4):08X}8{data.hex().upper()}\r".encode()
        bus.serialPortOrig.write(lines)  # type: ignore[attr-defined]  # one write: one read on the device
        bus.serialPortOrig.flush()  # type: ignore[attr-defined]
        got = sorted(res.seq for res in r.responses(0.5))
        assert got == [1, 2]
    finally:
        r.close()


# ---------------------------------------------------------------- messages


def test_uplink_that_does_not_decode_is_answered_with_param_err(sup: Supervisor, reader: Reader) -> None:
    before = int(status(sup)["rx_malformed"])
    reader.drain()
    for garbage in (b"\xff\xff\xff\xff\x01", bytes(range(256)) * 16, b"\x0a\x80"):
        sup._send(garbage[:4095])
        res = reader.response(0)  # not even the seq could be read
        assert res.ret_code == pb.CMD_PARAM_ERR
        assert "did not decode (" in res.ret_msg
        assert "schemas differ" in res.ret_msg
    assert int(status(sup)["rx_malformed"]) - before == 3


def test_unknown_uplink_kind_is_dropped_and_counted(sup: Supervisor, reader: Reader) -> None:
    before = int(status(sup)["rx_malformed"])
    reader.drain()
    sup._send(field_bytes(9, b"\x08\x01"))  # ls.Uplink field 9 does not exist
    assert reader.responses(0.3) == []
    assert int(status(sup)["rx_malformed"]) - before == 1


@pytest.mark.parametrize("number", [2, 15, 1 + max(c.number for c in COMMANDS.values()), 100, 536870911],
                         ids=lambda n: f"field{n}")
def test_unknown_command_id_is_answered_with_unknown_cmd(sup: Supervisor, reader: Reader, number: int) -> None:
    """An ls.Request whose command field is not in the schema: protobuf drops the
    unknown field, so the firmware sees a request without a command."""
    reader.drain()
    seq = sup._seq + 1
    request = b"\x08" + varint(seq) + field_bytes(number, b"")
    assert raw_request(sup, field_bytes(1, request)) == seq
    res = reader.response(seq)
    assert res.ret_code == pb.CMD_UNKNOWN_CMD_ERR
    assert res.ret_msg == (f"command id {number} is not in this firmware's schema: update the firmware or the "
                           f"client (they must come from the same schema)")
    assert res.WhichOneof("result") is None


def test_request_without_a_command_is_answered_with_unknown_cmd(sup: Supervisor, reader: Reader) -> None:
    reader.drain()
    seq = sup._seq + 1
    assert raw_request(sup, pb.Uplink(request=pb.Request(seq=seq)).SerializeToString()) == seq
    res = reader.response(seq)
    assert res.ret_code == pb.CMD_UNKNOWN_CMD_ERR
    assert res.ret_msg.startswith("the request carries no command")


@pytest.mark.parametrize("request_,name", [
    (pb.Request(move_absolute=pb.MoveAbsoluteReq(point_name="p" * 200, values=[0] * 6)), "moveAbsolute"),
    (pb.Request(move_absolute=pb.MoveAbsoluteReq(point_name="p1", values=[0.0] * 100)), "moveAbsolute"),
    (pb.Request(send_command=pb.SendCommandReq(input="s" * 3000)), "sendCommand"),
    (pb.Request(path_load=pb.PathLoadReq(path_name="p", tags=[pb.TagPoint(joints=[0] * 6)] * 40)), "pathLoad"),
    (pb.Request(connect=pb.ConnectReq(client_name="c" * 64)), "connect"),  # names hold 63 bytes
], ids=["point_name-200", "values-100", "input-3000", "tags-40", "client_name-64"])
def test_request_over_the_static_sizes_is_answered_with_param_err(sup: Supervisor, reader: Reader,
                                                                  request_: pb.Request, name: str) -> None:
    before = int(status(sup)["rx_malformed"])
    reader.drain()
    request_.seq = sup._seq + 1
    payload = pb.Uplink(request=request_).SerializeToString()
    assert len(payload) <= 4095
    raw_request(sup, payload)
    res = reader.response(request_.seq)  # the seq is recovered from the raw bytes
    assert res.ret_code == pb.CMD_PARAM_ERR
    assert "did not decode (" in res.ret_msg
    assert res.ret_msg.startswith(registry_name(request_))
    assert int(status(sup)["rx_malformed"]) - before == 1
    assert sup.get_motion_control_state().ok


def registry_name(request_: pb.Request) -> str:
    from landscape.registry import lookup
    return lookup(request_.WhichOneof("cmd")).name


# ---------------------------------------------------------------- noise


def test_random_frames_and_slcan_lines_do_not_hurt(bus: can.BusABC, sup: Supervisor, controller: Controller) -> None:
    rng = random.Random(20261122)
    functional = pb.ISOTP_FUNCTIONAL_BASE
    ids = [phys_id(DEVICE, HOST), phys_id(DEVICE, 0xF7), functional | pb.FUNCTIONAL_ALL_DEVICES << 8 | 0xF7,
           functional | DEVICE << 8 | 0xF7, tm.frame_id("HEARTBEAT", 0xF7), tm.frame_id("STATUS", 0xF7),
           phys_id(DEVICE, HOST) & 0x7FF]
    for i in range(600):
        can_id = rng.choice(ids) if i % 3 else rng.getrandbits(29)
        data = bytes(rng.getrandbits(8) for _ in range(rng.randint(0, 8)))
        extended = can_id > 0x7FF or rng.random() < 0.5
        bus.send(can.Message(arbitration_id=can_id, is_extended_id=extended, data=data,
                             is_remote_frame=rng.random() < 0.05))
        if i % 50 == 0:
            time.sleep(0.01)
    too_long = f"T{phys_id(DEVICE, HOST):08X}9".encode() + b"00" * 9 + b"\r"  # DLC 9
    junk = [b"T\r", b"t12\r", too_long, b"TXYZ\r", b"\x00\xff\xfe\r",
            b"Z9\r", b"S9\r", b"x" * 600 + b"\r", b"t1238GG\r", b"r7FF\r", b"R1FFFFFFF0\r"]
    for j in junk:
        bus.serialPortOrig.write(j)  # type: ignore[attr-defined]
    bus.serialPortOrig.write(b"O\r")  # type: ignore[attr-defined]  # keep the channel open
    bus.serialPortOrig.flush()  # type: ignore[attr-defined]
    time.sleep(0.3)
    assert controller.proc.poll() is None, "landscaped died"
    # the supervisor's own link may have been hit by the noise: a request still goes through
    # (possibly after a retransmission), and the session is alive
    assert sup.get_motion_control_state().ok
    st = status(sup)
    assert st["state"] == "UNLOCKED"


def test_status_counts_transport_drops(bus: can.BusABC, sup: Supervisor) -> None:
    bus.send(frame(phys_id(DEVICE, HOST), bytes([0x21, 1, 2, 3, 4, 5, 6, 7])))
    bus.send(frame(phys_id(DEVICE, 0xF3), bytes([0x10, 0x00, 0x00, 0x00, 0x13, 0x88, 0, 0])))
    time.sleep(0.1)
    st = status(sup)
    assert int(st["isotp_unexp_pdu"]) >= 1
    assert int(st["isotp_buffer_ovflw"]) >= 1


def test_oversize_request_through_the_library_is_refused_before_sending(sup: Supervisor) -> None:
    before = int(status(sup)["rx_malformed"])
    with pytest.raises(ArgumentError, match=r"moveAbsolute.point_name is 200 bytes .* at most 63 \(describe\)"):
        sup.move_absolute("p" * 200, [0.0] * 6, check=False, timeout_s=0.5)
    assert int(status(sup)["rx_malformed"]) == before  # nothing reached the device
    # a host without the description still gets the device's answer, not a time-out
    sup.description = None
    t0 = time.monotonic()
    rv = sup.move_absolute("p" * 200, [0.0] * 6, check=False, timeout_s=0.5)
    assert rv.ret_code == pb.CMD_PARAM_ERR
    assert rv.ret_msg.startswith("moveAbsolute did not decode (")
    assert time.monotonic() - t0 < 0.5


def test_a_request_while_a_blocking_one_runs_is_refused_and_the_first_still_answers(
        sup: Supervisor, reader: Reader) -> None:
    """One request in flight per session: a second request while stopMotion is
    still decelerating (a deferred answer) gets CMD_BUSY_ERR and does not run;
    the stop's own answer still arrives."""
    sup.lock()
    sup.activate()
    sup.move_absolute("far", [1.2, 0.3, 0.2, 0.5, 0.4, 1.0], speed_pct=20)
    time.sleep(0.3)
    reader.drain(0.05)
    stop_seq = raw_request(sup, pb.Uplink(request=pb.Request(seq=sup._seq + 1, stop_motion={})).SerializeToString())
    query_seq = raw_request(sup, pb.Uplink(request=pb.Request(
        seq=sup._seq + 1, get_motion_control_state={})).SerializeToString())
    busy = reader.response(query_seq)
    assert busy.ret_code == pb.CMD_BUSY_ERR
    assert busy.ret_msg.startswith(f"stopMotion (seq {stop_seq}) is still running")
    stopped = reader.response(stop_seq)
    assert stopped.ret_code == pb.CMD_EXEC_OK
    # both answers name this session's epoch (a refusal too: it answers this session)
    assert busy.session_epoch == stopped.session_epoch != 0
    assert sup.get_motion_control_state().result["state"] == "PAUSED"
    sup.abort_motion()
    sup.deactivate()
    sup.release()
