"""Addressing against the running firmware: functional requests (0x18DBFF<SA>,
single frames to every device, e.g. stop all) and several supervisors, each
with its own physical ISO-TP link, working at the same time.

A functional request is answered physically (0x18DA<SA><node>) by each device
that received it. The Supervisor does not wait for those answers, so the tests
read them with a second ISO-TP stack in listen mode (it never sends flow
control; the Supervisor's own stack does)."""
from __future__ import annotations

import threading
import time
from collections.abc import Iterator

import can
import isotp
import pytest

from landscape._generated import landscape_pb2 as pb
from landscape.supervisor import Supervisor

DEVICE = pb.DEFAULT_DEVICE_ADDRESS
OWNER = pb.DEFAULT_HOST_ADDRESS
OTHER = 0xF2
WAIT_S = 1.0
NO_ANSWER_S = 0.5


def functional_id(target: int, source: int) -> int:
    return pb.ISOTP_FUNCTIONAL_BASE | target << 8 | source


def physical_id(target: int, source: int) -> int:
    return pb.ISOTP_PHYSICAL_BASE | target << 8 | source


def single_frame(uplink: pb.Uplink) -> bytes:
    payload = uplink.SerializeToString()
    assert len(payload) <= 7, "a functional request must fit one single frame"
    return bytes([len(payload)]) + payload + b"\xcc" * (7 - len(payload))


def stop_request(seq: int) -> pb.Uplink:
    return pb.Uplink(request=pb.Request(seq=seq, stop_motion=pb.StopMotionReq()))


class Sniffer:
    """Every Downlink the device sends to `source`, decoded. In listen mode (beside a
    Supervisor of that address, whose stack sends the flow controls) or, with
    listen=False, as the only stack of `source` (it sends the flow controls)."""

    def __init__(self, bus: can.BusABC, notifier: can.Notifier, source: int, listen: bool = True) -> None:
        address = isotp.Address(isotp.AddressingMode.NormalFixed_29bits, source_address=source,
                                target_address=DEVICE)
        self.stack = isotp.NotifierBasedCanStack(bus, notifier, address=address,
                                                 params={"listen_mode": listen, "max_frame_size": 4095,
                                                         "tx_padding": 0xCC})
        self.stack.start()

    def responses(self, within_s: float) -> list[pb.Response]:
        """Responses received until `within_s` passes without a new one."""
        out: list[pb.Response] = []
        while True:
            data = self.stack.recv(block=True, timeout=within_s)
            if data is None:
                return out
            dl = pb.Downlink.FromString(bytes(data))
            if dl.WhichOneof("msg") == "response":
                out.append(dl.response)

    def response(self, seq: int) -> pb.Response:
        deadline = time.monotonic() + WAIT_S
        while time.monotonic() < deadline:
            data = self.stack.recv(block=True, timeout=max(0.0, deadline - time.monotonic()))
            if data is None:
                break
            dl = pb.Downlink.FromString(bytes(data))
            if dl.WhichOneof("msg") == "response" and dl.response.seq == seq:
                return dl.response
        raise AssertionError(f"no physical response with seq {seq} within {WAIT_S} s")

    def close(self) -> None:
        self.stack.stop()


@pytest.fixture
def sniffer(bus: can.BusABC, notifier: can.Notifier) -> Iterator[Sniffer]:
    s = Sniffer(bus, notifier, OWNER)
    try:
        yield s
    finally:
        s.close()


def executed(sup: Supervisor, addr: int) -> int:
    """Requests the device executed for `addr` (sendCommand status; this call counts too)."""
    text = sup.send_command("status").result["result"]
    for line in text.splitlines():
        if line.startswith(f"session 0x{addr:02X} "):
            return int(line.split("executed=")[1])
    raise AssertionError(f"no session 0x{addr:02X} in status:\n{text}")


def test_stop_all_while_nothing_moves_is_answered_physically(bus: can.BusABC, notifier: can.Notifier,
                                                            sniffer: Sniffer) -> None:
    with Supervisor(bus, notifier=notifier, source_address=OWNER, client_name="owner") as sup:
        sup.lock()
        before = executed(sup, OWNER)
        sup.stop_all()
        seq = sup._seq
        res = sniffer.response(seq)
        assert res.ret_code == pb.CMD_WRONG_STATE_ERR
        assert res.ret_msg == ("stopMotion is valid in MOVING, the device is LOCKED: there is no motion to act on")
        assert res.WhichOneof("result") is None
        # executed: the status before, the functional stop, this status
        assert executed(sup, OWNER) - before == 2
        # the next physical request gets a fresh seq and is executed, not taken for a retransmission
        assert sup.get_motion_control_state().result["state"] == "LOCKED"


def test_stop_all_keeps_its_seq_in_one_frame_after_seq_127(bus: can.BusABC, notifier: can.Notifier,
                                                           sniffer: Sniffer) -> None:
    with Supervisor(bus, notifier=notifier, source_address=OWNER, client_name="long") as sup:
        while sup._seq < 130:
            sup.get_motion_control_state()
        sent: list[bytes] = []
        real_send = bus.send

        def spy(msg: can.Message, timeout: float | None = None) -> None:
            if msg.arbitration_id == functional_id(0xFF, OWNER):
                sent.append(bytes(msg.data))
            real_send(msg, timeout)

        bus.send = spy  # type: ignore[method-assign]
        try:
            for _ in range(3):
                sniffer.responses(0.05)  # drop the earlier answers: their seqs repeat below
                sup.stop_all()
                res = sniffer.response(pb.Uplink.FromString(sent[-1][1:1 + sent[-1][0]]).request.seq)
                assert res.ret_code == pb.CMD_WRONG_STATE_ERR  # executed, not answered from a cache
        finally:
            bus.send = real_send  # type: ignore[method-assign]
        decoded = [pb.Uplink.FromString(f[1:1 + f[0]]).request for f in sent]
        assert [len(f) for f in sent] == [8, 8, 8]
        assert all(f[0] == 7 and f[0] >> 4 == 0 for f in sent)  # single frames, 7 payload bytes
        assert all(r.WhichOneof("cmd") == "stop_motion" for r in decoded)
        seq_values = [r.seq for r in decoded]
        assert all(1 <= s <= 127 for s in seq_values)
        assert len(set(seq_values)) == 3, seq_values
        assert sup.get_motion_control_state().ok


def test_functional_frame_to_another_target_is_ignored(bus: can.BusABC, notifier: can.Notifier,
                                                       sniffer: Sniffer) -> None:
    with Supervisor(bus, notifier=notifier, source_address=OWNER, client_name="owner") as sup:
        sup.lock()
        sniffer.responses(0.1)  # drain
        before = executed(sup, OWNER)
        sniffer.responses(0.1)
        bus.send(can.Message(arbitration_id=functional_id(0x22, OWNER), is_extended_id=True,
                             data=single_frame(stop_request(100))))
        assert sniffer.responses(NO_ANSWER_S) == []
        assert executed(sup, OWNER) - before == 1  # only the status call itself
        sniffer.responses(0.1)
        # the same frame addressed to the device's own node, and to everyone, is served
        for target, seq in ((DEVICE, 101), (0xFF, 102)):
            bus.send(can.Message(arbitration_id=functional_id(target, OWNER), is_extended_id=True,
                                 data=single_frame(stop_request(seq))))
            assert sniffer.response(seq).ret_code == pb.CMD_WRONG_STATE_ERR


def test_functional_request_without_a_session_is_refused(bus: can.BusABC, notifier: can.Notifier) -> None:
    stranger = 0xF5
    sniffer = Sniffer(bus, notifier, stranger, listen=False)
    try:
        bus.send(can.Message(arbitration_id=functional_id(0xFF, stranger), is_extended_id=True,
                             data=single_frame(stop_request(1))))
        res = sniffer.response(1)
        assert res.ret_code == pb.CMD_NOT_CONNECTED_ERR
        assert "0xF5" in res.ret_msg and "connect" in res.ret_msg
    finally:
        sniffer.close()


def test_multi_frame_functional_request_is_ignored(bus: can.BusABC, notifier: can.Notifier,
                                                   sniffer: Sniffer) -> None:
    """Functional addressing carries single frames only: a first frame gets no
    flow control and nothing is executed."""
    fcs: list[can.Message] = []

    class FcWatch(can.Listener):
        def on_message_received(self, msg: can.Message) -> None:
            if msg.arbitration_id == functional_id(OWNER, DEVICE) or (
                    msg.arbitration_id == physical_id(OWNER, DEVICE) and msg.data[0] >> 4 == 3):
                fcs.append(msg)

    watch = FcWatch()
    notifier.add_listener(watch)
    with Supervisor(bus, notifier=notifier, source_address=OWNER, client_name="owner") as sup:
        before = executed(sup, OWNER)
        sniffer.responses(0.1)
        payload = pb.Uplink(request=pb.Request(seq=200, send_command=pb.SendCommandReq(input="version"))) \
            .SerializeToString()
        assert len(payload) > 7
        fcs.clear()
        bus.send(can.Message(arbitration_id=functional_id(0xFF, OWNER), is_extended_id=True,
                             data=bytes([0x10, len(payload)]) + payload[:6]))
        assert sniffer.responses(NO_ANSWER_S) == []
        assert fcs == []
        assert executed(sup, OWNER) - before == 1
    notifier.remove_listener(watch)


def test_two_supervisors_issue_50_requests_each_at_the_same_time(bus: can.BusABC,
                                                                 notifier: can.Notifier) -> None:
    """Both supervisors keep one request in flight all the time; every answer
    carries its own seq and its own request's content (sendCommand echoes its
    input in the error message), and the device counts 50 for each."""
    n = 50
    failures: list[str] = []
    with Supervisor(bus, notifier=notifier, source_address=OWNER, client_name="a") as a, \
         Supervisor(bus, notifier=notifier, source_address=OTHER, client_name="b") as b:
        a.lock()
        start = threading.Barrier(2)
        before = {OWNER: executed(a, OWNER), OTHER: executed(b, OTHER)}

        def worker(sup: Supervisor, tag: str) -> None:
            start.wait()
            for i in range(n):
                seq_before = sup._seq
                if i % 2 == 0:
                    rv = sup.send_command(f"probe-{tag}-{i}", check=False)
                    ok = rv.ret_code == pb.CMD_PARAM_ERR and f"'probe-{tag}-{i}'" in rv.ret_msg
                else:
                    rv = sup.get_motion_control_state()
                    ok = rv.result["state"] == "LOCKED" and rv.result.get("owner", False) == (tag == "a")
                if rv.seq != seq_before + 1 or not ok:
                    failures.append(f"{tag} #{i}: seq {rv.seq} (expected {seq_before + 1}) {rv!r}")

        threads = [threading.Thread(target=worker, args=(a, "a")), threading.Thread(target=worker, args=(b, "b"))]
        t0 = time.monotonic()
        for t in threads:
            t.start()
        for t in threads:
            t.join(60)
        elapsed = time.monotonic() - t0
        assert not any(t.is_alive() for t in threads), "a worker hung"
        assert failures == []
        # each side: its 50 requests, the status call before and this one
        assert executed(a, OWNER) - before[OWNER] == n + 1
        assert executed(b, OTHER) - before[OTHER] == n + 1
        assert a.protocol_errors == 0 and b.protocol_errors == 0
        assert elapsed < 30


def test_stop_all_during_a_move_pauses_it(bus: can.BusABC, notifier: can.Notifier, sniffer: Sniffer) -> None:
    with Supervisor(bus, notifier=notifier, source_address=OWNER, client_name="owner") as sup:
        sup.lock()
        sup.activate()
        assert sup.move_absolute("far", [1.0, 0.5, 0.5, 1.0, 1.0, 1.0], speed_pct=10).started
        time.sleep(0.2)
        assert sup.get_motion_control_state().result["state"] == "MOVING"
        sniffer.responses(0.05)
        sup.stop_all()
        deadline = time.monotonic() + 10.0  # stopMotion answers once the arm has decelerated on its path
        res = None
        while res is None and time.monotonic() < deadline:
            for r in sniffer.responses(0.2):
                if r.seq == sup._seq:
                    res = r
        assert res is not None, "the functional stopMotion was not answered"
        assert res.ret_code == pb.CMD_EXEC_OK
        assert res.ret_msg.startswith("paused on the planned path")
        state = sup.get_motion_control_state().result
        assert state["state"] == "PAUSED" and state["motion_control_state"] == "robot_paused"
        a = sup.get_robot_position().result["joints"]
        time.sleep(0.2)
        b = sup.get_robot_position().result["joints"]
        assert b == pytest.approx(a, abs=1e-4), "the arm still moves after the stop"
        assert a != pytest.approx([0.0] * 6, abs=1e-3), "the arm had not moved before the stop"
