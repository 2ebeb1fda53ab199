"""Supervisor against the fake device on a virtual bus."""
from __future__ import annotations

import threading
import time

import can
import pytest

from fake_device import FakeDevice
from landscape import (
    AlarmError,
    ArgumentError,
    ControllerTimeoutError,
    LandscapeError,
    NotOwnerError,
    ParamError,
    ProtocolError,
    Supervisor,
    VersionMismatchError,
    WrongStateError,
    errors,
    ls,
    notice_data,
)
from landscape import telemetry as tm
from landscape.registry import PROTOCOL_VERSION, SCHEMA_HASH


def sup_on(bus: can.BusABC, notifier: can.Notifier, **kw: object) -> Supervisor:
    return Supervisor(bus, notifier=notifier, channel_name="virtual:test", **kw)  # type: ignore[arg-type]


def test_handshake_ok(bus, notifier, device: FakeDevice) -> None:
    with sup_on(bus, notifier, client_name="pytest") as sup:
        info = sup.device_info
        assert info is not None and sup.connected
        assert (info.device_name, info.joint_count, info.firmware_version, info.heartbeat_timeout_ms) == \
            ("fake", 6, "fake-1", 1000)
        first = device.requests[0]
        assert first.seq == 1 and first.WhichOneof("cmd") == "connect"
        assert (first.connect.protocol_version, first.connect.schema_hash, first.connect.client_name,
                first.connect.heartbeat_period_ms) == (PROTOCOL_VERSION, SCHEMA_HASH, "pytest", 200)
        # the handshake reads the device description once (docs/protocol.md "Device description")
        assert device.requests[1].WhichOneof("cmd") == "describe"
        assert sup.description is not None and sup.description.limit("pathLoad.tags").max_count == 32
        assert sup.get_motion_control_state().result["state"] == "UNLOCKED"
        assert [r.seq for r in device.requests] == [1, 2, 3]
    assert device.requests[-1].WhichOneof("cmd") == "disconnect" and device.requests[-1].seq == 4
    assert device.sessions == {}


@pytest.mark.parametrize("version,hash_delta,expect", [
    (PROTOCOL_VERSION + 1, 0, "the device speaks protocol version 2, this host tool 1: update the host tool"),
    (PROTOCOL_VERSION - 1, 0, "the device speaks protocol version 0, this host tool 1: update the firmware"),
    (PROTOCOL_VERSION, 1, "host and firmware were built from different schemas (host {h:08X}, device {d:08X}): "
                          "install the host tool built from the firmware's tree"),
])
@pytest.mark.parametrize("refuse", [False, True])
def test_version_mismatch_messages(bus, notifier, device: FakeDevice, version: int, hash_delta: int,
                                   expect: str, refuse: bool) -> None:
    device.version = version
    device.schema_hash = (SCHEMA_HASH + hash_delta) & 0xFFFFFFFF
    device.refuse_mismatch = refuse
    sup = sup_on(bus, notifier)
    with pytest.raises(VersionMismatchError) as ei:
        sup.open()
    assert str(ei.value).startswith(expect.format(h=SCHEMA_HASH, d=device.schema_hash))
    assert not sup.connected and sup._hb_thread is None and sup._stack is None


def test_retransmission_uses_same_seq_and_executes_once(bus, notifier, device: FakeDevice) -> None:
    with sup_on(bus, notifier, timeout_s=0.15) as sup:
        device.drop_responses = 1
        rv = sup.lock()
        assert rv.ret_code == ls.CMD_EXEC_OK and rv.seq == 3  # after connect and describe
        locks = [r for r in device.requests if r.WhichOneof("cmd") == "lock"]
        assert [r.seq for r in locks] == [3, 3]
        assert device.executions["lock"] == 1
        assert device.owner == 0xF1
        assert sup.get_motion_control_state().seq == 4


def test_time_out_names_address_channel_and_command(bus, notifier, device: FakeDevice) -> None:
    with sup_on(bus, notifier, timeout_s=0.1, retries=2) as sup:
        device.silent = True
        t0 = time.monotonic()
        with pytest.raises(ControllerTimeoutError) as ei:
            sup.get_tag_id()
        assert 0.28 < time.monotonic() - t0 < 1.0
        assert str(ei.value) == ("no answer from the controller at address 0x10 on virtual:test to getTagId "
                                 "(seq 3, 3 tries of 0.1 s): is landscaped running on that channel with node "
                                 "address 0x10?")
        assert [r.seq for r in device.requests if r.WhichOneof("cmd") == "get_tag_id"] == [3, 3, 3]
        device.silent = False


def test_no_device_at_all(bus, notifier) -> None:
    sup = sup_on(bus, notifier, timeout_s=0.05, retries=0)
    with pytest.raises(ControllerTimeoutError, match="to connect \\(seq 1, 1 tries of 0.05 s\\)"):
        sup.open()
    assert sup._threads == [] and sup._stack is None


NEGATIVE = [v.number for v in ls.RetCode.DESCRIPTOR.values if v.number < 0]


@pytest.mark.parametrize("code", NEGATIVE)
def test_negative_codes_raise_their_subclass(bus, notifier, device: FakeDevice, code: int) -> None:
    device.force_codes["get_tag_id"] = (code, "reason from the device")
    with sup_on(bus, notifier) as sup:
        with pytest.raises(errors.CommandError) as ei:
            sup.get_tag_id()
        assert type(ei.value) is type(errors.error_for_code("x", code, ""))
        assert (ei.value.ret_code, ei.value.command) == (code, "getTagId")
        if code == ls.CMD_SEQ_CONFLICT_ERR:  # retried once with a fresh seq, then the cause named
            assert ei.value.ret_msg.startswith("reason from the device; seq ")
            assert "another client speaks from 0xf1, or frames are forged on the bus" in ei.value.ret_msg
        else:
            assert ei.value.ret_msg == "reason from the device"
        if code == ls.CMD_NOT_CONNECTED_ERR:  # the device says it dropped the session: connect again first
            assert not sup.connected
            sup.connect()
        rv = sup.get_tag_id(check=False)
        assert (rv.ret_code, rv.ret_msg, rv.message, rv.result) == (code, "reason from the device", None, {})


def test_state_errors_from_the_device(bus, notifier, device: FakeDevice) -> None:
    with sup_on(bus, notifier) as sup:
        with pytest.raises(NotOwnerError, match="release: CMD_NOT_OWNER_ERR: lock first"):
            sup.release()
        sup.lock()
        with pytest.raises(WrongStateError, match="activate first"):
            sup.move_absolute("p", [0] * 6)


def test_notices_callbacks_iterator_and_wait_complete(bus, notifier, device: FakeDevice) -> None:
    seen: list[ls.Notice] = []
    with sup_on(bus, notifier) as sup:
        sup.on_notice(seen.append)
        sup.lock()
        sup.activate()
        rv = sup.move_absolute("p1", [0.1, 0, 0, 0, 0, 0])
        assert rv.started and rv.ret_name == "CMD_STARTED_OK"
        final = sup.wait_complete(rv, timeout_s=3)
        assert (final.kind, final.event_id, final.ref_seq, final.final) == \
            (ls.EVENT, "moveAbsoluteComplete", rv.seq, True)
        assert notice_data(final) == {"point": "p1", "reason": "complete", "joints": "0.1,0,0,0,0,0"}
        assert device.rsvp_outcomes == ["default"]
        got = list(sup.notices(timeout_s=0.2))
        assert [(n.event_id, n.kind, n.final) for n in got] == [
            ("tag", ls.EVENT, False), ("confirmMove", ls.EVENT_RSVP, False), ("moveAbsoluteComplete", ls.EVENT, True)]
        assert [n.notice_seq for n in got] == [1, 2, 3]
        deadline = time.monotonic() + 1
        while len(seen) < 3 and time.monotonic() < deadline:
            time.sleep(0.01)
        assert [n.event_id for n in seen] == ["tag", "confirmMove", "moveAbsoluteComplete"]
        assert list(sup.notices(timeout_s=0.05)) == []  # the iterator consumed them
        assert sup.wait_for_tag("p1", timeout_s=0.5).event_id == "tag"
        with pytest.raises(ControllerTimeoutError, match="tag 'p9' not reached within 0.1 s"):
            sup.wait_for_tag("p9", timeout_s=0.1)
        with pytest.raises(LandscapeError, match="only a command that answered CMD_STARTED_OK"):
            sup.wait_complete(sup.get_tag_id(check=False), timeout_s=0.1)


def test_wait_complete_raises_alarm(bus, notifier, device: FakeDevice) -> None:
    with sup_on(bus, notifier) as sup:
        sup.lock()
        sup.activate()
        rv = sup.move_absolute("far", [4.0, 0, 0, 0, 0, 0])
        with pytest.raises(AlarmError) as ei:
            sup.wait_complete(rv, timeout_s=3)
        assert ei.value.notice.event_id == "moveAbsoluteFailed" and ei.value.notice.ref_seq == rv.seq
        assert str(ei.value).startswith("moveAbsolute ended with alarm moveAbsoluteFailed (point=far reason=fault "
                                        "fault=joint 1 beyond its limit (4.0 rad))")


def test_rsvp_handler_answers(bus, notifier, device: FakeDevice) -> None:
    asked: list[str] = []

    def refuse(n: ls.Notice) -> tuple[int, list[str]]:
        asked.append(n.event_id)
        return ls.CMD_ERR, ["why=operator said no"]

    with sup_on(bus, notifier) as sup:
        sup.on_rsvp("confirmMove", refuse)
        sup.lock()
        sup.activate()
        rv = sup.move_absolute("p2", [0] * 6)
        with pytest.raises(AlarmError, match="moveAbsoluteAborted"):
            sup.wait_complete(rv, timeout_s=3)
        assert asked == ["confirmMove"]
        assert [(r.rsvp_id, r.ret_code, list(r.data)) for r in device.rsvp_replies] == \
            [(1, ls.CMD_ERR, ["why=operator said no"])]
        sup.remove_rsvp_handler("confirmMove")
        sup.on_rsvp(None, lambda n: None)  # catch-all: go on
        rv = sup.move_absolute("p3", [0] * 6)
        assert notice_data(sup.wait_complete(rv, timeout_s=3))["reason"] == "complete"
        assert device.rsvp_outcomes[-1] == "answered"
        assert device.rsvp_replies[-1].ret_code == ls.CMD_EXEC_OK


def test_answer_rsvp_returns_the_devices_acknowledgement(bus, notifier, device: FakeDevice) -> None:
    device.rsvp_timeout_ms = 2000
    with sup_on(bus, notifier) as sup:
        sup.lock()
        sup.activate()
        rv = sup.move_absolute("p4", [0] * 6)
        ask = next(n for n in sup.notices(timeout_s=3) if n.kind == ls.EVENT_RSVP)
        assert ask.ref_seq == rv.seq
        ack = sup.decline_rsvp(ask, ["why=not now"])
        assert (ack.rsvp_id, ack.ret_code, ack.action) == (ask.rsvp_id, ls.CMD_EXEC_OK, "refuse")
        assert [(r.ret_code, list(r.data)) for r in device.rsvp_replies] == [(ls.CMD_ERR, ["why=not now"])]
        with pytest.raises(AlarmError, match="moveAbsoluteAborted"):
            sup.wait_complete(rv, timeout_s=3)
        # a second answer is refused, naming why; check=False returns the refusal
        with pytest.raises(ParamError, match="already answered"):
            sup.accept_rsvp(ask)
        assert sup.answer_rsvp(ask.rsvp_id, check=False).ret_code == ls.CMD_PARAM_ERR
        with pytest.raises(ArgumentError, match="is not an RSVP"):
            sup.answer_rsvp(ls.Notice(kind=ls.EVENT, event_id="tag"))
        with pytest.raises(ArgumentError, match="a decline is negative"):
            sup.decline_rsvp(ask, ret_code=0)


def test_rsvp_handler_may_call_request(bus, notifier, device: FakeDevice) -> None:
    states: list[str] = []
    with sup_on(bus, notifier) as sup:
        def check_state(n: ls.Notice) -> int:
            states.append(sup.get_motion_control_state().result["state"])
            return ls.CMD_EXEC_OK
        sup.on_rsvp("confirmMove", check_state)
        sup.lock()
        sup.activate()
        sup.wait_complete(sup.move_absolute("p", [0] * 6), timeout_s=3)
        assert states == ["MOVING"]


def test_heartbeat_frames_role_1_counter_increments(bus, notifier, device: FakeDevice, channel: str) -> None:
    spy_bus = can.Bus(interface="virtual", channel=channel)
    try:
        with sup_on(bus, notifier, heartbeat_period_ms=20) as sup:
            time.sleep(0.25)
            assert sup.device_info is not None
            token = sup.device_info.heartbeat_token
        assert 0 < token <= 0xFFFFFF
        frames = []
        while (m := spy_bus.recv(timeout=0)) is not None:
            if m.arbitration_id == tm.frame_id("HEARTBEAT", ls.DEFAULT_HOST_ADDRESS):
                frames.append(m)
        assert len(frames) >= 8
        db = tm.database()
        decoded = [db.decode_message("HEARTBEAT", bytes(f.data), decode_choices=False) for f in frames]
        assert all(f.is_extended_id and f.dlc == 8 for f in frames)
        # the DBC's supervisor payload: hb_counter, hb_role 1, hb_period_ms, the session's hb_token; byte 1 0
        assert all(d == {"hb_counter": d["hb_counter"], "hb_role": 1, "hb_period_ms": 20, "hb_token": token}
                   for d in decoded)
        assert all(bytes(f.data)[1] == 0 and bytes(f.data)[5:] == token.to_bytes(3, "little") for f in frames)
        assert [d["hb_counter"] for d in decoded] == list(range(len(decoded)))
    finally:
        spy_bus.shutdown()


def test_heartbeat_stops_after_close_and_device_sees_it(bus, notifier, device: FakeDevice) -> None:
    sup = sup_on(bus, notifier, heartbeat_period_ms=20)
    with sup:
        time.sleep(0.1)
    n = len(device.heartbeats[0xF1])
    assert n >= 3
    time.sleep(0.1)
    assert len(device.heartbeats[0xF1]) == n
    assert not any(t.is_alive() for t in sup._threads) and sup._hb_thread is None


def test_device_drops_owner_when_heartbeat_stops(bus, notifier, device: FakeDevice) -> None:
    device.heartbeat_timeout_ms = 150
    with sup_on(bus, notifier) as sup:
        sup.lock()
        assert device.owner == 0xF1
        sup._stop_heartbeat()
        time.sleep(0.4)
        assert device.owner is None and 0xF1 not in device.sessions
        with pytest.raises(errors.NotConnectedError):
            sup.get_tag_id()
        assert not sup.connected  # so the session daemon, the CLI and the gateway connect again
        sup.connect()  # a new session: seq starts again at 1 (connect), 2 (describe)
        assert [r.seq for r in device.requests[-2:]] == [1, 2] and sup.get_tag_id(check=False).seq == 3


def test_a_description_given_is_used_by_the_first_connect_only(bus, notifier, device: FakeDevice) -> None:
    """The gateway's sessions take the observer's description instead of reading it again; a reconnect
    (the device may have restarted) reads its own."""
    with sup_on(bus, notifier, source_address=0xF1) as observer:
        known = observer.description
        assert known is not None and known.from_device
        with sup_on(bus, notifier, source_address=0xF2, description=known) as session:
            mine = [r.WhichOneof("cmd") for r in device.requests if r.WhichOneof("cmd") in ("connect", "describe")]
            assert mine == ["connect", "describe", "connect"], mine  # the second supervisor read none
            assert session.description is known
            session.disconnect()
            session.connect()
            assert device.requests[-1].WhichOneof("cmd") == "describe"
            assert session.description is not known and session.description is not None


def test_two_supervisors_share_one_bus_and_notifier(bus, notifier, device: FakeDevice) -> None:
    with sup_on(bus, notifier, source_address=0xF1) as a, sup_on(bus, notifier, source_address=0xF2) as b:
        assert set(device.sessions) == {0xF1, 0xF2}
        a.lock()
        with pytest.raises(NotOwnerError, match="supervisor 0xf1 owns the device"):
            b.lock()
        results: dict[str, list[int]] = {"a": [], "b": []}

        def hammer(s: Supervisor, key: str) -> None:
            for _ in range(20):
                results[key].append(s.get_motion_control_state().seq)
        ta = threading.Thread(target=hammer, args=(a, "a"))
        tb = threading.Thread(target=hammer, args=(b, "b"))
        ta.start()
        tb.start()
        ta.join(10)
        tb.join(10)
        assert results["a"] == list(range(4, 24)) and results["b"] == list(range(4, 24))
        assert a.get_motion_control_state().result["owner"] is True
        assert b.get_motion_control_state().result["owner"] is False
    assert device.sessions == {}


def test_telemetry_snapshot_and_callbacks(bus, notifier, device: FakeDevice) -> None:
    got: list[str] = []
    with sup_on(bus, notifier) as sup:
        sup.on_telemetry(lambda b: got.append(b.name))
        time.sleep(0.2)
        snap = sup.telemetry()
        assert snap["JOINTS_12"] == {"j1": 0.5, "j2": -0.25}
        assert snap["STATUS"]["st_cycle_us"] == 1000
        assert snap["HEARTBEAT"]["hb_role"] == 0 and snap["HEARTBEAT"]["hb_supervisors"] == 1
        assert {"HEARTBEAT", "STATUS", "JOINTS_12"} <= set(got)
        assert sup.device_last_seen is not None


def test_request_before_open_and_bad_arguments(bus, notifier, device: FakeDevice) -> None:
    sup = sup_on(bus, notifier)
    with pytest.raises(LandscapeError, match="not open"):
        sup.lock()
    with sup:
        with pytest.raises(errors.ArgumentError, match="no field 'speed'"):
            sup.request("move_absolute", speed=3)
        assert len(device.requests) == 2  # connect and describe; nothing sent, no seq used
        assert sup.lock().seq == 3


def test_oversized_request_is_refused_locally(bus, notifier, device: FakeDevice) -> None:
    with sup_on(bus, notifier) as sup:
        with pytest.raises(errors.ArgumentError, match="more than one ISO-TP message holds"):
            sup.set_tool_offset([0.0] * 600)


def test_multi_frame_request_and_response(bus, notifier, device: FakeDevice) -> None:
    device.force_codes["send_command"] = (ls.CMD_PARAM_ERR, "x" * 1500)
    with sup_on(bus, notifier) as sup:
        rv = sup.send_command("y" * 2000, check=False)
        assert rv.ret_msg == "x" * 1500
        assert device.requests[-1].send_command.input == "y" * 2000


def test_an_answer_that_is_not_utf8_fails_its_request_naming_why(bus, notifier, device: FakeDevice) -> None:
    """A device that cuts a character in half (docs/protocol.md "Strings"): the request fails at once with
    a ProtocolError naming the undecodable text, not a time-out asking whether
    landscaped runs."""
    with sup_on(bus, notifier, timeout_s=2.0, retries=0) as sup:
        device.force_codes["send_command"] = (ls.CMD_PARAM_ERR, "unknown 'ab\u00e9XY'")
        device.rewrite = (b"XY", b"\xc3(")  # a lead byte without its continuation
        t0 = time.monotonic()
        with pytest.raises(ProtocolError) as ei:
            sup.send_command("abc")
        assert time.monotonic() - t0 < 1.0, "waited for the time-out instead of failing at once"
        msg = str(ei.value)
        assert "sendCommand" in msg and "not valid UTF-8" in msg and "byte" in msg, msg
        assert "is landscaped running" not in msg
        assert sup.protocol_errors == 1
        # the session goes on: the next answer decodes
        device.rewrite = None
        del device.force_codes["send_command"]
        assert sup.get_motion_control_state().ok


def test_requests_beyond_the_described_limits_are_refused_before_sending(bus, notifier,
                                                                          device: FakeDevice) -> None:
    with sup_on(bus, notifier) as sup:
        sent = len(device.requests)
        with pytest.raises(errors.ArgumentError, match=r"pathLoad.path_name is 64 bytes .* at most 63 \(describe\)"):
            sup.path_load("p" * 64, [{"joints": [0.0] * 6}])
        with pytest.raises(errors.ArgumentError, match=r"pathLoad.tags has 33 items; the device holds at most 32"):
            sup.path_load("p", [{"joints": [0.0] * 6}] * 33)
        with pytest.raises(errors.ArgumentError, match=r"pathLoad.tags.tag_name is 64 bytes"):
            sup.path_load("p", [{"joints": [0.0] * 6, "tag_name": "\u00e9" * 32}])  # 32 characters, 64 bytes
        assert len(device.requests) == sent  # nothing went out
        device.state = ls.LOCKED
        device.owner = 0xF1
        assert sup.path_load("p" * 63, [{"joints": [0.0] * 6, "tag_name": "t" * 63}]).ok  # at the limits: sent


def test_path_move_leaves_cycles_to_the_device(bus, notifier, device: FakeDevice) -> None:
    with sup_on(bus, notifier) as sup:
        device.state, device.owner = ls.LOCKED, 0xF1
        sup.path_load("p", [{"joints": [0.0] * 6}])
        device.state = ls.RESTING
        sup.wait_complete(sup.path_move("p"), timeout_s=5)
        assert not device.requests[-1].path_move.HasField("number_of_cycles")  # absent: the device runs 1
        sup.wait_complete(sup.path_move("p", number_of_cycles=0), timeout_s=5)
        assert device.requests[-1].path_move.HasField("number_of_cycles")  # 0 sent: the dry run


def test_connected_is_false_once_the_link_is_lost(bus, notifier, device: FakeDevice) -> None:
    """A supervisor whose line is gone says so through `connected` too, not only through
    link_problem() (front ends connect again or stop when it is False)."""
    with sup_on(bus, notifier) as sup:
        assert sup.connected
        sup._link_failed("the line closed")
        assert not sup.connected
        assert sup.link_problem() == "the line closed"
