"""The protocol and the core through the host library against the running
firmware: handshake, every command reachable, retransmission, several
supervisors on one bus, malformed input, liveness."""
from __future__ import annotations

import time

import can
import pytest

from landscape import errors
from landscape._generated import landscape_pb2 as pb
from landscape.registry import COMMANDS, SCHEMA_HASH, lookup
from landscape.supervisor import Supervisor


def _status(sup: Supervisor) -> dict[str, str]:
    text = sup.request("sendCommand", input="status").result["result"]
    out: dict[str, str] = {}
    for line in text.splitlines():
        if line.startswith("session "):
            addr, *kv = line.split()[1:]
            out[f"session {addr}"] = " ".join(kv)
        elif "=" in line:
            k, v = line.split("=", 1)
            out[k] = v
    return out


def test_every_command_reaches_the_firmware(bus: can.BusABC) -> None:
    with Supervisor(bus, client_name="walker") as sup:
        sup.lock()
        sup.activate()
        for cmd in COMMANDS.values():
            if cmd.field in ("connect", "disconnect", "deactivate", "release"):
                continue
            rv = sup.request(cmd.name, check=False)
            assert rv.ret_code in pb.RetCode.values(), cmd.name
            assert rv.ret_code != pb.CMD_UNKNOWN_CMD_ERR, cmd.name
            assert rv.ret_msg, f"{cmd.name} answered without a message"
            state = sup.get_motion_control_state().result["state"]
            if state != "RESTING":
                # a command changed the state (e.g. a motion started): go back to rest
                pytest.fail(f"{cmd.name} left the device in {state}")
        sup.deactivate()
        sup.release()


def test_retransmission_is_answered_but_executed_once(bus: can.BusABC) -> None:
    with Supervisor(bus, client_name="dup") as sup:
        before = _status(sup)["session 0xF1"]
        cmd = lookup("getMotionControlState")
        req = Supervisor.build_request(cmd, seq=0)
        with sup._req_lock:  # the library's own retransmission path, driven by hand
            sup._seq += 1
            req.seq = sup._seq
            first = sup._transact(cmd, req, 2.0)
            again = sup._transact(cmd, req, 2.0)
        assert first.seq == again.seq == req.seq
        assert first.SerializeToString() == again.SerializeToString()
        after = _status(sup)["session 0xF1"]
        n_before = int(before.split("executed=")[1])
        n_after = int(after.split("executed=")[1])
        # executed: the status request before + getMotionControlState once (not twice) + this status request
        assert n_after - n_before == 2, (before, after)


def test_two_supervisors_share_one_bus(bus: can.BusABC) -> None:
    notifier = can.Notifier(bus, [])
    try:
        with Supervisor(bus, notifier=notifier, source_address=0xF1, client_name="owner") as a, \
             Supervisor(bus, notifier=notifier, source_address=0xF2, client_name="observer") as b:
            a.lock()
            with pytest.raises(errors.NotOwnerError) as ei:
                b.activate()
            assert "0xF1" in str(ei.value)
            assert b.get_motion_control_state().result["state"] == "LOCKED"
            assert b.get_motion_control_state().result.get("owner", False) is False
            assert a.get_motion_control_state().result["owner"] is True
            with pytest.raises(errors.WrongStateError):
                b.lock()
            a.release()
            b.lock()
            assert a.get_motion_control_state().result.get("owner", False) is False
    finally:
        notifier.stop()


def test_connect_with_another_schema_is_refused(bus: can.BusABC) -> None:
    with Supervisor(bus) as sup:
        rv = sup.request("connect", check=False, protocol_version=pb.PROTOCOL_VERSION,
                         schema_hash=0x12345678, client_nonce=sup.nonce, client_name="old")
        assert rv.ret_code == pb.CMD_VERSION_MISMATCH_ERR
        assert "build the client from the device's protocol/landscape.proto" in rv.ret_msg, rv.ret_msg
        assert "12345678" in rv.ret_msg
        # the device's version and hash as numbers too, not only inside the text (docs/protocol.md "Schema hash")
        assert isinstance(rv.message, pb.ConnectRes)
        assert (rv.message.protocol_version, rv.message.schema_hash) == (pb.PROTOCOL_VERSION, SCHEMA_HASH)
        rv = sup.request("connect", check=False, protocol_version=pb.PROTOCOL_VERSION + 1,
                         schema_hash=SCHEMA_HASH, client_nonce=sup.nonce, client_name="new")
        assert rv.ret_code == pb.CMD_VERSION_MISMATCH_ERR
        assert "firmware" in rv.ret_msg


def test_malformed_uplink_gets_an_error_and_the_device_lives_on(bus: can.BusABC) -> None:
    with Supervisor(bus) as sup:
        sup._send(b"\xff\xff\xff\xff\x01")  # not an ls.Uplink
        time.sleep(0.2)
        st = _status(sup)
        assert int(st["rx_malformed"]) >= 1
        assert sup.get_motion_control_state().ok


def test_owner_heartbeat_loss_deactivates_and_releases(bus: can.BusABC) -> None:
    notifier = can.Notifier(bus, [])
    try:
        with Supervisor(bus, notifier=notifier, source_address=0xF2, client_name="watcher") as watcher:
            owner = Supervisor(bus, notifier=notifier, source_address=0xF1, client_name="owner")
            owner.__enter__()
            owner.lock()
            owner.activate()
            owner._stop_heartbeat()  # the owner vanishes without a word
            t0 = time.monotonic()
            alarm = None
            for n in watcher.notices(timeout_s=3.0):
                if n.event_id == "ownerLost":
                    alarm = n
                    break
            elapsed = time.monotonic() - t0
            assert alarm is not None and alarm.kind == pb.ALARM
            assert elapsed < 1.0 + 0.5  # time-out (1 s) plus scheduling margin
            state = watcher.get_motion_control_state().result
            assert state["state"] == "UNLOCKED" and state["control_mode"] == "power_off"
            owner._running = False
            owner.close()
    finally:
        notifier.stop()


def test_send_command_vendor_hooks(bus: can.BusABC) -> None:
    with Supervisor(bus, client_name="vendor") as sup:
        helps = sup.request("sendCommand", input="help").result["result"].split()
        assert helps == ["help", "version", "status", "security", "faults", "events", "rtstats", "config", "stopping",
                         "drives", "home"]
        # the simulated arm has no drives to read and nothing to home: one line each, naming why
        rv = sup.request("sendCommand", check=False, input="drives")
        assert rv.ret_code == pb.CMD_UNSUPPORTED_ERR
        assert rv.ret_msg == "sendCommand drives: this arm has no drives to read (docs/deploy.md \"Drives\")"
        sup.lock()
        sup.activate()
        rv = sup.request("sendCommand", check=False, input="home")
        assert rv.ret_code == pb.CMD_UNSUPPORTED_ERR
        assert rv.ret_msg == "sendCommand home: this arm has no homing: its joints' positions are absolute"
        assert "homing" not in sup.describe().result or not sup.describe().result["homing"]
        stopping = sup.request("sendCommand", input="stopping").result["result"].splitlines()
        assert len(stopping) == 6 and stopping[0].startswith("j1 time_s="), stopping
        rt = dict(line.split("=", 1) for line in sup.request("sendCommand", input="rtstats").result["result"].split())
        assert int(rt["cycles"]) > 0 and rt["realtime"] in ("yes", "no")
        cfg = sup.request("sendCommand", input="config").result["result"]
        assert "arm=sim" in cfg and "link=slcan:pty:" in cfg
        assert "no faults" in sup.request("sendCommand", input="faults").result["result"]
        assert "no events" in sup.request("sendCommand", input="events").result["result"]
        assert "disconnect_action=stop_deactivate_release" in cfg
        with pytest.raises(errors.ParamError):
            sup.request("sendCommand", input="reboot")
