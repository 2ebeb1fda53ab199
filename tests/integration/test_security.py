"""Signed supervisors and sessions bound to their link (docs/protocol.md "Security").

The forgery set an attacker on the bus tries against the owner at 0xF1: a release, a move,
a deactivate and a disconnect sent from the owner's address (physical and functional
frames), a forged seq that would make the owner's next request fail, a replayed request and
a replayed connect, and a flood of connects that would fill the session slots. Against a
device of policy `signed` every one fails and the owner keeps control; against policy
`unsigned` with two link segments the ones sent on the other segment fail too."""
from __future__ import annotations

import os
import secrets
import subprocess
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import can
import isotp
import pytest

from conftest import CLI, Controller, open_slcan, start_controller
from landscape import auth, errors
from landscape._generated import landscape_pb2 as pb
from landscape.registry import SCHEMA_HASH
from landscape.supervisor import Supervisor

DEVICE = 0x10
OWNER = 0xF1
PHYSICAL = 0x18DA0000  # | target << 8 | source (docs/protocol.md "Identifiers and priorities")
FUNCTIONAL = 0x18DBFF00  # | source


@dataclass
class Rig:
    controller: Controller
    key_file: Path
    pty: str        # the first link segment: the owner's
    other_pty: str  # the second link segment


def write_keys(path: Path, **keys: bytes) -> Path:
    path.write_text("".join(f"{name} = {key.hex()}\n" for name, key in keys.items()))
    path.chmod(0o600)
    return path


def start_rig(tmp_path: Path, policy: str) -> Rig:
    key_file = write_keys(tmp_path / "landscaped.keys", ops=secrets.token_bytes(32))
    conf = tmp_path / "landscaped.conf"
    conf.write_text(f"[security]\npolicy = {policy}\nkey_file = {key_file}\n")
    other = tmp_path / "ls1"
    c = start_controller(tmp_path / "ls0", "--config", str(conf), "--link", f"slcan:pty:{other}")
    deadline = time.monotonic() + 10
    while not other.exists():
        assert time.monotonic() < deadline, "landscaped did not create its second pty link"
        time.sleep(0.02)
    return Rig(c, key_file, c.pty, str(other))


def stop_rig(rig: Rig) -> None:
    code = rig.controller.stop()
    log = rig.controller.log.read_text(errors="replace")
    assert code == 0, f"landscaped exited with {code}:\n{log[-4000:]}"
    assert "Sanitizer" not in log, log[-4000:]


def running_rig(tmp_path: Path, policy: str) -> Iterator[Rig]:
    rig = start_rig(tmp_path, policy)
    try:
        yield rig
    finally:
        stop_rig(rig)


@pytest.fixture
def signed(tmp_path: Path) -> Iterator[Rig]:
    yield from running_rig(tmp_path, "signed")


@pytest.fixture
def unsigned(tmp_path: Path) -> Iterator[Rig]:
    yield from running_rig(tmp_path, "unsigned")


class Forger:
    """A node on a link segment that sends whatever it likes from any address: on a pty of
    its own, or sharing the owner's (a pty has one reader: the same bus object)."""

    def __init__(self, pty: str | None = None, shared: tuple[can.BusABC, can.Notifier] | None = None) -> None:
        if shared is not None:
            self.bus, self.notifier = shared
            self._own = False
        else:
            assert pty is not None
            self.bus = open_slcan(pty)
            self.notifier = can.Notifier(self.bus, [], timeout=0.01)
            self._own = True

    def close(self) -> None:
        if self._own:
            self.notifier.stop()
            self.bus.shutdown()

    def single(self, payload: bytes, source: int = OWNER, functional: bool = False) -> None:
        """One ISO-TP single frame (at most 7 bytes)."""
        assert len(payload) <= 7
        can_id = (FUNCTIONAL if functional else PHYSICAL | DEVICE << 8) | source
        self.bus.send(can.Message(arbitration_id=can_id, is_extended_id=True,
                                  data=bytes([len(payload)]) + payload + b"\xcc" * (7 - len(payload))))

    def message(self, payload: bytes, source: int = OWNER, wait_s: float = 1.5) -> list[pb.Downlink]:
        """A whole ISO-TP message from `source` (multi-frame when it must be); the downlinks to
        `source` within wait_s."""
        address = isotp.Address(isotp.AddressingMode.NormalFixed_29bits, source_address=source,
                                target_address=DEVICE)
        stack = isotp.NotifierBasedCanStack(self.bus, self.notifier, address=address,
                                            params={"blocking_send": False, "tx_padding": 0xCC})
        stack.start()
        try:
            stack.send(payload)
            got: list[pb.Downlink] = []
            deadline = time.monotonic() + wait_s
            while time.monotonic() < deadline:
                data = stack.recv(block=True, timeout=0.05)
                if data is not None:
                    dl = pb.Downlink()
                    dl.ParseFromString(bytes(data))
                    got.append(dl)
            return got
        finally:
            stack.stop()


def request(seq: int, **cmd: object) -> bytes:
    return pb.Uplink(request=pb.Request(seq=seq, **cmd)).SerializeToString()  # type: ignore[arg-type]


def state_of(sup: Supervisor) -> tuple[int, bool]:
    m = sup.get_motion_control_state().message
    assert isinstance(m, pb.GetMotionControlStateRes)
    return m.state, m.owner


def joints(sup: Supervisor) -> list[float]:
    m = sup.get_robot_position().message
    assert isinstance(m, pb.GetRobotPositionRes)
    return list(m.joints)


def status(sup: Supervisor, what: str = "security") -> str:
    """sendCommand `what`: "security" (docs/protocol.md "Security"), "status" (the transport's counters)."""
    return str(sup.send_command(what).result["result"])


def counter(text: str, name: str) -> int:
    for item in text.replace("\n", " ").split():
        key, _, value = item.partition("=")
        if key == name and value.isdigit():
            return int(value)
    raise AssertionError(f"no {name}= in status:\n{text}")


@dataclass
class Owner:
    bus: can.BusABC
    notifier: can.Notifier
    sup: Supervisor

    def close(self) -> None:
        self.sup.close()
        self.notifier.stop()
        self.bus.shutdown()


def owner_of(rig: Rig, key: auth.SupervisorKey | None, recorded: list[bytes] | None = None) -> Owner:
    """The owner at 0xF1 on the first segment; `recorded` keeps every message it sends."""
    bus = open_slcan(rig.pty)
    notifier = can.Notifier(bus, [], timeout=0.01)
    sup = Supervisor(bus, source_address=OWNER, client_name="owner", key=key, notifier=notifier)
    if recorded is not None:
        send = sup._send

        def keep(data: bytes) -> None:
            recorded.append(data)
            send(data)

        sup._send = keep  # type: ignore[method-assign]
    sup.open()
    return Owner(bus, notifier, sup)


def signed_messages(recorded: list[bytes]) -> list[bytes]:
    return [m for m in recorded if auth.has_mac(m)]


def unanswered(forger: Forger, payload: bytes) -> None:
    got = forger.message(payload, wait_s=0.3)
    assert got == [], f"a forgery was answered ({payload.hex()}): {got}"


def forge_everything(sup: Supervisor, forger: Forger, seq_ahead: int) -> None:
    """The forgery set from the owner's address while it owns an active arm: release,
    deactivate and disconnect as physical and functional single frames, a move as a
    multi-frame message, a forged seq ahead of the owner's, each also with a MAC field of
    random bytes."""
    q = joints(sup)
    move = request(seq_ahead, move_absolute=pb.MoveAbsoluteReq(point_name="forged", frame=pb.JOINT_FRAME,
                                                               values=[q[0] + 0.3, *q[1:]]))
    fake_mac = bytes([auth.MAC_FIELD << 3 | 2, auth.MAC_BYTES]) + secrets.token_bytes(auth.MAC_BYTES)
    for seq, cmd in ((seq_ahead + 1, "release"), (seq_ahead + 2, "deactivate"), (seq_ahead + 3, "disconnect")):
        body = request(seq, **{cmd: getattr(pb, {"release": "ReleaseReq", "deactivate": "DeactivateReq",
                                                 "disconnect": "DisconnectReq"}[cmd])()})
        forger.single(body)
        forger.single(body, functional=True)
        unanswered(forger, body + fake_mac)
    unanswered(forger, move)
    unanswered(forger, move + fake_mac)
    time.sleep(0.3)


def assert_in_control(sup: Supervisor, q_before: list[float]) -> None:
    state, owner = state_of(sup)
    assert (state, owner) == (pb.RESTING, True), f"the owner lost control: {pb.State.Name(state)}, owner {owner}"
    assert max(abs(a - b) for a, b in zip(joints(sup), q_before, strict=True)) < 1e-3, "a forged move ran"
    assert sup.connected and sup.link_problem() is None


def forged_while_active(sup: Supervisor, forger: Forger) -> list[float]:
    """Lock and activate, the whole forgery set, the owner still in control, then the owner's own
    move of joint 1 by +0.2 rad runs (no forged seq was consumed). The joints before the move."""
    sup.lock()
    sup.activate()
    q0 = joints(sup)
    forge_everything(sup, forger, seq_ahead=sup._seq + 1)
    assert_in_control(sup, q0)
    rv = sup.move_absolute("mine", [q0[0] + 0.2, *q0[1:]])
    sup.wait_complete(rv, timeout_s=30)
    return q0


def test_signed_forgeries_change_nothing_and_the_owner_keeps_control(signed: Rig) -> None:
    key = auth.load_key(signed.key_file)
    recorded: list[bytes] = []
    owner = owner_of(signed, key, recorded)
    sup = owner.sup
    forger = Forger(shared=(owner.bus, owner.notifier))  # the owner's own segment: only the MAC tells them apart
    try:
        assert sup.session_signed and sup.connect_result is not None
        assert sup.connect_result.device.auth_policy == pb.AUTH_SIGNED
        q0 = forged_while_active(sup, forger)
        q1 = joints(sup)
        assert abs(q1[0] - (q0[0] + 0.2)) < 1e-3
        back = sup.move_absolute("back", q0)
        sup.wait_complete(back, timeout_s=30)

        # a replayed request (the owner's signed move to q0 + 0.2, byte for byte) is dropped
        moves = [m for m in signed_messages(recorded) if pb.Uplink.FromString(m[:-auth.TRAILER_BYTES]).request
                 .WhichOneof("cmd") == "move_absolute"]
        assert moves and forger.message(moves[0], wait_s=1.0) == []
        assert_in_control(sup, joints(sup))
        assert abs(joints(sup)[0] - q0[0]) < 1e-3, "a replayed move ran"

        # the owner connects again while its signed session lives (its challenge signed in it):
        # still the owner, in a new signed session
        epoch = sup.connect_result.device.session_epoch
        again = sup.connect()
        assert again.device.owner and again.device.session_signed and again.device.session_epoch != epoch

        text = status(sup)
        assert counter(text, "auth_refused") >= 8, text  # MAC missing or wrong
        assert counter(text, "auth_stale") >= 1, text     # the replay
        assert counter(text, "functional_refused") >= 3, text
        sup.deactivate()
        sup.release()
    finally:
        forger.close()
        owner.close()

    # a replayed connect: its challenge was used up
    connects = [m for m in signed_messages(recorded)
                if pb.Uplink.FromString(m[:-auth.TRAILER_BYTES]).request.HasField("connect")]
    assert connects
    forger = Forger(signed.pty)
    try:
        answers = forger.message(connects[0], wait_s=1.5)
        assert [a.response.ret_code for a in answers] == [pb.CMD_AUTH_ERR], answers
        assert "no challenge of this host_nonce" in answers[0].response.ret_msg
    finally:
        forger.close()


def test_signed_mode_gives_no_slot_to_a_client_without_the_key(signed: Rig) -> None:
    """Unsigned connects are refused naming what is missing and take no session slot, and
    challenges from many addresses take none either: a supervisor with the key still gets in."""
    forger = Forger(signed.other_pty)
    try:
        for addr in range(0xF2, 0xFA):
            connect = pb.ConnectReq(protocol_version=pb.PROTOCOL_VERSION, schema_hash=SCHEMA_HASH,
                                    client_nonce=addr, client_name="rogue", heartbeat_period_ms=200)
            answers = forger.message(request(1, connect=connect), source=addr, wait_s=0.5)
            assert [a.response.ret_code for a in answers] == [pb.CMD_AUTH_ERR], answers
            assert "signed" in answers[0].response.ret_msg
            challenge = pb.ChallengeReq(key_id="ops", host_nonce=secrets.token_bytes(auth.NONCE_BYTES))
            forger.message(request(2, challenge=challenge), source=addr, wait_s=0.2)
    finally:
        forger.close()
    owner = owner_of(signed, auth.load_key(signed.key_file))
    sup = owner.sup
    try:
        assert sup.session_signed
        text = status(sup)
        assert [line.split()[1] for line in text.splitlines() if line.startswith("session ")] == [f"{OWNER:#04X}"
                                                                                                  .replace("0X", "0x")]
        assert counter(text, "auth_connects_refused") >= 8, text
    finally:
        owner.close()


def test_a_wrong_key_is_refused_with_one_clear_line(signed: Rig, tmp_path: Path) -> None:
    wrong = write_keys(tmp_path / "wrong.keys", ops=secrets.token_bytes(32))
    bus = open_slcan(signed.pty)
    try:
        sup = Supervisor(bus, source_address=OWNER, key=auth.load_key(wrong))
        with pytest.raises(errors.SignatureError, match="does not hold this host's key 'ops'"):
            sup.open()
        sup.close()
    finally:
        bus.shutdown()
    out = signed.controller.cli("--key-file", str(wrong), "get-motion-control-state")
    assert out.returncode != 0
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and "does not hold this host's key 'ops'" in lines[0], out.stderr
    assert "Traceback" not in out.stderr
    # no key at all: the device names what is missing
    out = signed.controller.cli("get-motion-control-state")
    assert out.returncode != 0 and "CMD_AUTH_ERR" in out.stderr and "LANDSCAPE_KEY_FILE" in out.stderr, out.stderr
    # a key file others may read: refused before anything is sent
    wrong.chmod(0o644)
    out = signed.controller.cli("--key-file", str(wrong), "get-motion-control-state")
    assert out.returncode == 2 and "chmod 600" in out.stderr, out.stderr
    # the right key, from the environment: served
    env = {**os.environ, auth.ENV_KEY_FILE: str(signed.key_file)}
    out = subprocess.run([str(CLI), "--interface", "slcan", "--channel", signed.pty, "get-motion-control-state"],
                         capture_output=True, text=True, timeout=60, env=env)
    assert out.returncode == 0, out.stderr


def test_unsigned_cross_link_forgeries_fail(unsigned: Rig) -> None:
    """Unsigned, the owner's address on another link segment is not the owner: its frames are
    dropped before they reach a session (frames_foreign)."""
    owner = owner_of(unsigned, None)
    sup = owner.sup
    forger = Forger(unsigned.other_pty)
    try:
        assert not sup.session_signed
        assert sup.connect_result is not None and sup.connect_result.device.auth_policy == pb.AUTH_UNSIGNED
        forged_while_active(sup, forger)
        assert counter(status(sup, "status"), "frames_foreign") > 0
        sup.deactivate()
        sup.release()
    finally:
        forger.close()
        owner.close()
