"""`landscape gateway` against the running landscaped, through a client we did not write (asyncua's
Client, and its uaread/uacall tools): browse the controller, read it anonymously, subscribe to joint
positions while a method call moves the arm, the completion event, an RSVP answered by AnswerRsvp,
a second user session refused ownership but allowed to read, an anonymous session refused a
command, and a killed session whose supervisor the device drops (its disconnect handler runs)."""
from __future__ import annotations

import asyncio
import json
import os
import re
import shlex
import signal
import socket
import subprocess
import sys
import textwrap
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
from asyncua import Client, ua

from conftest import CLI, Controller, start_controller
from landscape._generated import landscape_pb2 as pb
from landscape.gateway_config import hash_password
from landscape.registry import lookup

BIN = Path(sys.executable).parent
TARGET = [0.4, -0.2, 0.3, 0.0, 0.4, 0.2]
CTRL = "Controller_10"
#: asyncua's per-request time-out: a session's first method call connects its supervisor (connect and
#: the device's description, ~200 frames), which takes seconds on a loaded machine.
UA_TIMEOUT_S = 30


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@dataclass
class GatewayRun:
    url: str
    proc: subprocess.Popen[str]
    log: Path  # its stderr, readable while it runs


@pytest.fixture
def gateway(gateway_run: GatewayRun) -> str:
    return gateway_run.url


@pytest.fixture
def gateway_run(controller: Controller, tmp_path: Path) -> Iterator[GatewayRun]:
    port = free_port()
    cfg = tmp_path / "gateway.toml"
    cfg.write_text(textwrap.dedent(f"""\
        [server]
        port = {port}
        session_timeout_s = 5
        [supervisors]
        pool = "0xF8-0xFE"
        [users]
        alice = "{hash_password('alice-pw', iterations=1000)}"
        bob = "{hash_password('bob-pw', iterations=1000)}"
        """))
    log = tmp_path / "gateway.log"
    with open(log, "w") as err_file:
        proc = subprocess.Popen([str(CLI), "--interface", "slcan", "--channel", controller.pty, "gateway",
                                 "--config", str(cfg)], stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                stderr=err_file, text=True)
    try:
        assert proc.stdout is not None
        first = proc.stdout.readline()
        m = re.match(r"gateway: (opc\.tcp://127\.0\.0\.1:\d+/landscape/) serving", first)
        assert m, first + (log.read_text() if proc.poll() is not None else "")
        yield GatewayRun(m.group(1), proc, log)
    finally:
        if proc.poll() is None:
            proc.send_signal(signal.SIGTERM)
        out, _ = proc.communicate(timeout=30)
        err = log.read_text()
        assert proc.returncode == 0, (out, err)
        assert "Traceback" not in err, err
        assert "never awaited" not in err, err  # a write left behind at shutdown
        assert re.search(r"^gateway: stopped; served 1 controller$", out, re.M), out


def user_url(url: str, user: str, pw: str) -> str:
    return url.replace("opc.tcp://", f"opc.tcp://{user}:{pw}@")


async def controller_node(client: Client, timeout_s: float = 30.0) -> Any:
    """The controller's object, once the gateway has discovered it and read its description."""
    ns = await client.get_namespace_index("urn:landscape:gateway")
    deadline = time.monotonic() + timeout_s
    while True:
        try:
            node = await client.nodes.objects.get_child([f"{ns}:DeviceSet", f"{ns}:{CTRL}"])
            if await (await node.get_child(f"{ns}:Description")).read_value():
                return node, ns
        except ua.UaError:
            pass
        assert time.monotonic() < deadline, "the gateway did not show controller 0x10 within the time"
        await asyncio.sleep(0.2)


async def call(node: Any, ns: int, name: str, *args: Any) -> list[Any]:
    cmds = await node.get_child(f"{ns}:Commands")
    out = await node.call_method(await cmds.get_child(f"{ns}:{name}"), *args)
    return list(out) if isinstance(out, list) else [out]


class Events:
    def __init__(self) -> None:
        self.got: list[Any] = []

    def event_notification(self, event: Any) -> None:
        self.got.append(event)


class Changes:
    def __init__(self) -> None:
        self.values: list[Any] = []

    def datachange_notification(self, node: Any, val: Any, data: Any) -> None:
        self.values.append(val)


def test_browse_subscribe_move_and_complete_by_method_calls(gateway: str) -> None:
    async def run() -> None:
        async with Client(gateway, timeout=UA_TIMEOUT_S) as anon:
            node, ns = await controller_node(anon)
            # browse: the MotionDeviceSystem shape, axes with units, one method per command
            names = {(await c.read_browse_name()).Name for c in await node.get_children()}
            assert {"Description", "State", "MotionDevices", "Commands"} <= names
            axis = await node.get_child([f"{ns}:MotionDevices", f"{ns}:Arm", f"{ns}:Axes", f"{ns}:J1",
                                         f"{ns}:ParameterSet", f"{ns}:ActualPosition"])
            eu = await (await axis.get_child(f"{ns}:EngineeringUnits")).read_value()
            assert eu.DisplayName.Text == "rad"
            methods = {(await m.read_browse_name()).Name for m in
                       await (await node.get_child(f"{ns}:Commands")).get_children()}
            assert {"lock", "activate", "moveAbsolute", "pathMove", "AnswerRsvp"} <= methods
            # each method says what it does, from the schema (protocol/landscape.proto summary)
            move = await node.get_child([f"{ns}:Commands", f"{ns}:moveAbsolute"])
            text = (await move.read_description()).Text
            assert text.startswith(lookup("moveAbsolute").summary), text
            assert "valid in RESTING" in text and "non-blocking" in text and "owner only" in text, text
            # anonymous: reads, but is refused a command
            assert await (await node.get_child(f"{ns}:State")).read_value() in ("IDLE", "UNLOCKED")
            with pytest.raises(ua.UaStatusCodeError) as refused:
                await call(node, ns, "lock")
            assert refused.value.code == ua.StatusCodes.BadUserAccessDenied

        async with Client(user_url(gateway, "alice", "alice-pw"), timeout=UA_TIMEOUT_S) as c:
            node, ns = await controller_node(c)
            events = await subscribe_notices(c, node, ns)
            joints = Changes()
            jsub = await c.create_subscription(20, joints)
            jp = await node.get_child([f"{ns}:MotionDevices", f"{ns}:Arm", f"{ns}:JointPositions"])
            await jsub.subscribe_data_change(jp)
            for name, args in (("lock", []), ("activate", []), ("setSpeed", [40.0, "PERCENT_SPEED"])):
                out = await call(node, ns, name, *args)
                assert out[0] >= 0, (name, out)
            out = await call(node, ns, "moveAbsolute", "p1", "JOINT_FRAME", TARGET)
            assert out[1] == "CMD_STARTED_OK", out
            seq = out[3]
            final = await first_event(events, lambda e: e.RefSeq == seq and e.Final, 30)
            assert final is not None, [(e.NoticeId, e.RefSeq) for e in events.got]
            assert final.NoticeId == "moveAbsoluteComplete" and final.Kind == "EVENT", final
            await asyncio.sleep(0.3)
            j1 = [v[0] for v in joints.values]
            assert len(j1) > 10, len(j1)  # followed the move, not one value
            assert joints.values[-1] == pytest.approx(TARGET, abs=2e-3)
            assert len({round(v, 3) for v in j1}) > 5
    asyncio.run(run())


def test_an_rsvp_is_answered_by_a_method_call(gateway: str) -> None:
    async def run() -> None:
        async with Client(user_url(gateway, "alice", "alice-pw"), timeout=UA_TIMEOUT_S) as c:
            node, ns = await controller_node(c)
            events = await subscribe_notices(c, node, ns)
            for name, args in (("lock", []), ("activate", [])):
                assert (await call(node, ns, name, *args))[0] >= 0
            # a path with an RSVP point (docs/protocol.md "RSVP"): the device asks "go on?"
            tags = ['{"tag_name": "a", "joints": [0.1, 0, 0, 0, 0, 0], "aux_commands": ["rsvp goOn 5"]}',
                    '{"tag_name": "b", "joints": [0.2, 0, 0, 0, 0, 0]}']
            out = await call(node, ns, "pathLoad", "r", "JOINT_FRAME", "JOINT_MOTION", "ABSOLUTE_DATA", 2, tags)
            assert out[0] >= 0, out
            out = await call(node, ns, "pathMove", "r")
            assert out[1] == "CMD_STARTED_OK", out
            seq = out[3]
            rsvp = await first_event(events, lambda e: e.RsvpId, 20)
            assert rsvp is not None, [(e.Kind, e.NoticeId) for e in events.got]
            ack = await call(node, ns, "AnswerRsvp", ua.Variant(rsvp.RsvpId, ua.VariantType.UInt32),
                             ua.Variant(-1, ua.VariantType.Int32), ua.Variant(["why=test"], ua.VariantType.String))
            assert ack[0] == pb.CMD_EXEC_OK and ack[2] == "abort", ack
            final = await first_event(events, lambda e: e.RefSeq == seq and e.Final, 20)
            assert final is not None and final.Kind == "ALARM" and final.NoticeId == "pathMoveAborted", final
    asyncio.run(run())


KILLED_CLIENT = """
import asyncio, sys, time
from asyncua import Client
async def main():
    c = Client(sys.argv[1], timeout=30)
    await c.connect()
    ns = await c.get_namespace_index("urn:landscape:gateway")
    node = await c.nodes.objects.get_child([f"{ns}:DeviceSet", f"{ns}:Controller_10"])
    cmds = await node.get_child(f"{ns}:Commands")
    out = await node.call_method(await cmds.get_child(f"{ns}:lock"))
    # a subscription: asyncua keeps such a session after its connection drops, until its time-out
    sub = await c.create_subscription(100, None)
    await sub.subscribe_data_change(await node.get_child(f"{ns}:State"))
    print("locked", out[0], flush=True)
    await asyncio.sleep(60)
asyncio.run(main())
"""


def test_a_second_client_is_refused_ownership_and_a_killed_session_is_dropped(gateway: str, tmp_path: Path) -> None:
    script = tmp_path / "owner.py"
    script.write_text(KILLED_CLIENT)

    async def run() -> None:
        async with Client(user_url(gateway, "bob", "bob-pw"), timeout=UA_TIMEOUT_S) as bob:
            node, ns = await controller_node(bob)
            owner = subprocess.Popen([sys.executable, str(script), user_url(gateway, "alice", "alice-pw")],
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
            try:
                assert owner.stdout is not None
                line = await asyncio.get_running_loop().run_in_executor(None, owner.stdout.readline)
                assert line.startswith("locked 0"), line + (owner.stderr.read() if owner.stderr else "")
                events = await subscribe_notices(bob, node, ns)
                state = await node.get_child(f"{ns}:State")
                owner_var = await node.get_child(f"{ns}:Owner")
                await asyncio.sleep(0.5)
                assert await state.read_value() == "LOCKED"
                alice_addr = await owner_var.read_value()
                assert 0xF8 <= alice_addr <= 0xFE
                # bob: refused ownership (alice's lock holds), but reads
                out = await call(node, ns, "activate")
                assert out[1] == "CMD_NOT_OWNER_ERR", out
                assert await (await node.get_child([f"{ns}:MotionDevices", f"{ns}:Arm",
                                                     f"{ns}:JointPositions"])).read_value()
                # the owner's OPC UA client dies: its session, then its supervisor, goes
                owner.kill()
                owner.wait(timeout=10)
            finally:
                if owner.poll() is None:
                    owner.kill()
            killed = time.monotonic()
            deadline = killed + 20
            while time.monotonic() < deadline and await state.read_value() == "LOCKED":
                await asyncio.sleep(0.1)
            assert await state.read_value() in ("UNLOCKED", "IDLE")  # stop_deactivate_release ran
            # within the fixture's session time-out (5 s) plus the device's reaction and a loaded machine's
            # slack, not asyncua's own cap (10 min) for a session with subscriptions whose client is gone
            assert time.monotonic() - killed < 15
            # the alarm comes by ISO-TP to the observer, then a publish cycle: it may trail the STATUS broadcast
            deadline = time.monotonic() + 5
            while not any(e.NoticeId == "ownerLost" for e in events.got) and time.monotonic() < deadline:
                await asyncio.sleep(0.1)
            lost = [e for e in events.got if e.NoticeId == "ownerLost"]
            assert lost and f"supervisor={alice_addr:#04x}" in lost[0].Data.lower(), \
                [(e.NoticeId, e.Data) for e in events.got]
            # and now bob may own it
            out = await call(node, ns, "lock")
            assert out[0] >= 0, out
    asyncio.run(run())


async def sessions_dropped(node: Any, ns: int) -> int:
    """The device's count of supervisors it dropped for a lost heartbeat (sendCommand status)."""
    out = await call(node, ns, "sendCommand", "status")
    assert out[0] >= 0, out
    m = re.search(r"sessions_dropped=(\d+)", json.loads(out[5])["result"])
    assert m, out
    return int(m.group(1))


def test_a_stalled_gateway_connects_its_observer_and_a_sessions_supervisor_again(gateway_run: GatewayRun) -> None:
    """The gateway stops for longer than the device's heartbeat time-out (1 s) but shorter than its
    own judgement of a silent controller (2 s): the device drops the observer and alice's supervisor.
    The observer is connected again within OBSERVER_CHECK_S (so alarms keep coming), alice's next
    call says her session was dropped and the one after works."""
    async def run() -> None:
        async with Client(user_url(gateway_run.url, "alice", "alice-pw"), timeout=UA_TIMEOUT_S) as alice:
            node, ns = await controller_node(alice)
            supervisors = await node.get_child(f"{ns}:Supervisors")
            before = await sessions_dropped(node, ns)  # alice's supervisor connects
            deadline = time.monotonic() + 10
            while await supervisors.read_value() != 2:  # the observer and alice's
                assert time.monotonic() < deadline, await supervisors.read_value()
                await asyncio.sleep(0.1)
            # The device drops a supervisor 1 s after its last heartbeat (sent every 200 ms); the gateway
            # counts the controller gone 2 s after its last frame (HEARTBEAT every 200 ms). 1.4 s leaves
            # 0.2-0.4 s on either side.
            gateway_run.proc.send_signal(signal.SIGSTOP)
            try:
                time.sleep(1.4)
            finally:
                gateway_run.proc.send_signal(signal.SIGCONT)
            first = await call(node, ns, "getMotionControlState")
            assert first[1] == "CMD_NOT_CONNECTED_ERR", first
            second = await call(node, ns, "getMotionControlState")
            assert second[0] >= 0, second
            assert await sessions_dropped(node, ns) == before + 2  # the stall did drop both
            deadline = time.monotonic() + 10
            while await supervisors.read_value() != 2:
                assert time.monotonic() < deadline, ("the observer did not connect again",
                                                     await supervisors.read_value())
                await asyncio.sleep(0.1)
    asyncio.run(run())
    log = gateway_run.log.read_text()
    assert "controller 0x10 dropped the gateway's observer" in log, log
    assert "is gone" not in log, log  # the stall was shorter than the gateway's own silence limit


async def subscribe_notices(client: Client, node: Any, ns: int) -> Events:
    events = Events()
    sub = await client.create_subscription(50, events)
    await sub.subscribe_events(node, await client.nodes.root.get_child(
        ["0:Types", "0:EventTypes", "0:BaseEventType", f"{ns}:LandScapeNoticeEventType"]))
    return events


async def first_event(events: Events, match: Callable[[Any], Any], timeout_s: float) -> Any:
    """The first notice event that `match`es, waiting up to `timeout_s`; None if none came."""
    deadline = time.monotonic() + timeout_s
    while True:
        got = next((e for e in events.got if match(e)), None)
        if got is not None or time.monotonic() > deadline:
            return got
        await asyncio.sleep(0.05)


async def wait_status(var: Any, good: bool, timeout_s: float) -> ua.DataValue:
    deadline = time.monotonic() + timeout_s
    while True:
        dv = await var.read_data_value(raise_on_bad_status=False)
        if dv.StatusCode.is_good() == good:
            return dv
        assert time.monotonic() < deadline, f"{var} still {dv.StatusCode} after {timeout_s} s"
        await asyncio.sleep(0.1)


def test_a_controller_that_goes_turns_bad_and_recovers_when_it_comes_back(gateway: str,
                                                                          controller: Controller) -> None:
    """landscaped stops: its values turn BadNoCommunication, subscribers get controllerLost, calls are
    refused by name; landscaped starts again on the same line: the gateway finds it, values are Good,
    calls work, without a gateway restart."""
    async def run() -> None:
        async with Client(user_url(gateway, "alice", "alice-pw"), timeout=UA_TIMEOUT_S) as c:
            node, ns = await controller_node(c)
            state = await node.get_child(f"{ns}:State")
            joints = await node.get_child([f"{ns}:MotionDevices", f"{ns}:Arm", f"{ns}:JointPositions"])
            dv = await wait_status(state, True, 10)
            assert dv.SourceTimestamp is not None and dv.ServerTimestamp is not None, dv
            assert (await call(node, ns, "lock"))[0] >= 0
            events = await subscribe_notices(c, node, ns)
            assert controller.stop() == 0
            gone_at = time.monotonic()
            for var in (state, joints):
                dv = await wait_status(var, False, 15)
                assert dv.StatusCode.value == ua.StatusCodes.BadNoCommunication, dv
            # twice the device's heartbeat time-out (1 s) and a loaded machine's slack
            assert time.monotonic() - gone_at < 10
            await asyncio.sleep(0.5)
            lost = [e for e in events.got if e.NoticeId == "controllerLost"]
            assert lost and lost[0].Kind == "ALARM" and lost[0].Severity == 800, \
                [(e.NoticeId, e.Data) for e in events.got]
            with pytest.raises(ua.UaStatusCodeError) as refused:
                await call(node, ns, "getRobotPosition")
            assert refused.value.code == ua.StatusCodes.BadNoCommunication
            # landscaped again on the same line (a new pty behind the same name)
            again = start_controller(Path(controller.pty))
            controller.proc = again.proc
            await wait_status(state, True, 30)
            await wait_status(joints, True, 10)
            deadline = time.monotonic() + 30
            while not any(e.NoticeId == "controllerBack" for e in events.got):
                assert time.monotonic() < deadline, [(e.NoticeId, e.Data) for e in events.got]
                await asyncio.sleep(0.1)
            # the device forgot the old session: this session's calls connect anew and work
            deadline = time.monotonic() + 30
            while True:
                try:
                    out = await call(node, ns, "getRobotPosition")
                    break
                except ua.UaStatusCodeError:
                    assert time.monotonic() < deadline
                    await asyncio.sleep(0.5)
            assert out[1] == "CMD_EXEC_OK", out
            assert await state.read_value() in ("IDLE", "UNLOCKED")
    asyncio.run(run())


def test_bad_arguments_are_refused_by_name_and_anonymous_first(gateway_run: GatewayRun) -> None:
    gateway = gateway_run.url

    async def run() -> None:
        async with Client(gateway, timeout=UA_TIMEOUT_S) as anon:
            node, ns = await controller_node(anon)
            with pytest.raises(ua.UaStatusCodeError) as refused:
                await call(node, ns, "AnswerRsvp")  # no arguments at all: still the user first
            assert refused.value.code == ua.StatusCodes.BadUserAccessDenied
        async with Client(user_url(gateway, "alice", "alice-pw"), timeout=UA_TIMEOUT_S) as c:
            node, ns = await controller_node(c)
            for args in ([ua.Variant(5, ua.VariantType.UInt32)],
                         ["one", ua.Variant(0, ua.VariantType.Int32), ua.Variant([], ua.VariantType.String)],
                         [ua.Variant(5, ua.VariantType.UInt32), ua.Variant(0, ua.VariantType.Int32), "x", "y"]):
                with pytest.raises(ua.UaStatusCodeError) as refused:
                    await call(node, ns, "AnswerRsvp", *args)
                assert refused.value.code == ua.StatusCodes.BadInvalidArgument, args
            # a String where the schema wants an array: refused, not iterated character by character
            assert (await call(node, ns, "lock"))[0] >= 0
            assert (await call(node, ns, "activate"))[0] >= 0
            with pytest.raises(ua.UaStatusCodeError) as refused:
                await call(node, ns, "moveAbsolute", "p1", "JOINT_FRAME", "000000")
            assert refused.value.code == ua.StatusCodes.BadInvalidArgument
            with pytest.raises(ua.UaStatusCodeError) as refused:
                await call(node, ns, "pathLoad", "r", "JOINT_FRAME", "JOINT_MOTION", "ABSOLUTE_DATA", 1,
                           '{"tag_name": "a", "joints": [0.1, 0, 0, 0, 0, 0]}')
            assert refused.value.code == ua.StatusCodes.BadInvalidArgument
            # a value of the right shape that does not fit: the device's way, CMD_PARAM_ERR with the reason,
            # so a client on the LAN reads which argument and why
            out = await call(node, ns, "moveAbsolute", "p1", "NOT_A_FRAME", [0.1] * 6)
            assert out[:2] == [pb.CMD_PARAM_ERR, "CMD_PARAM_ERR"], out
            assert "moveAbsolute.frame: 'NOT_A_FRAME' is not a ReferenceFrame value (one of JOINT_FRAME" in out[2], out
            out = await call(node, ns, "moveAbsolute", "p" * 80, "JOINT_FRAME", [0.1] * 6)
            assert out[1] == "CMD_PARAM_ERR" and "point_name" in out[2] and "63" in out[2], out
            state = await node.get_child(f"{ns}:State")
            assert await state.read_value() != "MOVING"
    asyncio.run(run())
    log = gateway_run.log.read_text()
    # who was refused, by address and user, and what to do about it
    assert re.search(r"refused a method call from anonymous session 127\.0\.0\.1:\d+ \(anonymous\): commands "
                     r"need a user", log), log
    assert re.search(r"moveAbsolute from session 127\.0\.0\.1:\d+ \(alice\): ", log), log


def test_a_full_supervisor_table_is_the_devices_refusal(gateway: str) -> None:
    """The device takes max_sessions supervisors (the description says how many); the gateway's
    observer holds one, each commanding OPC UA session one: the session past the limit gets the
    device's CMD_NO_RESOURCES_ERR as a good call, not a communication error."""
    async def run() -> None:
        async with Client(gateway, timeout=UA_TIMEOUT_S) as anon:
            node, ns = await controller_node(anon)
            desc = json.loads(await (await node.get_child(f"{ns}:Description")).read_value())
        max_sessions = int(desc["max_sessions"])
        clients = []
        try:
            outs = []
            for _ in range(max_sessions):  # the observer holds one place: the last one is refused
                c = Client(user_url(gateway, "alice", "alice-pw"), timeout=UA_TIMEOUT_S)
                await c.connect()
                clients.append(c)
                node, ns = await controller_node(c)
                outs.append(await call(node, ns, "getMotionControlState"))
            assert all(o[0] >= 0 for o in outs[:-1]), outs
            assert outs[-1][1] == "CMD_NO_RESOURCES_ERR" and outs[-1][0] == pb.CMD_NO_RESOURCES_ERR, outs[-1]
            assert "supervisors" in outs[-1][2], outs[-1]
        finally:
            for c in clients:
                await c.disconnect()
    asyncio.run(run())


def test_asyncua_command_line_tools_read_and_call(gateway: str) -> None:
    for _ in range(50):
        r = subprocess.run([str(BIN / "uaread"), "--timeout", "20", "-u", gateway, "-n", f"ns=2;s={CTRL}.Description"],
                           capture_output=True, text=True, timeout=30)
        if r.returncode == 0 and "device" in r.stdout.lower():
            break
        time.sleep(0.2)
    assert r.returncode == 0 and r.stdout.strip(), (r.stdout, r.stderr)
    r = subprocess.run([str(BIN / "uaread"), "--timeout", "20", "-u", gateway, "-n", f"ns=2;s={CTRL}.State"],
                       capture_output=True, text=True, timeout=30)
    assert r.returncode == 0 and r.stdout.strip() in ("IDLE", "UNLOCKED"), (r.stdout, r.stderr)
    r = subprocess.run([str(BIN / "uacall"), "-u", user_url(gateway, "alice", "alice-pw"),
                        "-n", f"ns=2;s={CTRL}.Commands", "-m", "2:getRobotPosition"],
                       capture_output=True, text=True, timeout=30)
    assert r.returncode == 0 and "CMD_EXEC_OK" in r.stdout, (r.stdout, r.stderr)


def test_a_bad_config_is_one_line_and_exit_2(tmp_path: Path) -> None:
    cfg = tmp_path / "bad.toml"
    cfg.write_text('[users]\nalice = "alice-pw"\n')
    r = subprocess.run([str(CLI), "--interface", "slcan", "--channel", "/nonexistent", "gateway", "--config",
                        str(cfg)], capture_output=True, text=True, timeout=30, env={**os.environ})
    assert r.returncode == 2, (r.stdout, r.stderr)
    assert "Traceback" not in r.stderr
    assert "[users] alice: not a password hash" in r.stderr and "--hash-password" in r.stderr, r.stderr


def test_a_port_in_use_or_a_foreign_host_is_one_line_with_a_hint_that_fits(tmp_path: Path) -> None:
    cfg = tmp_path / "gateway.toml"
    cfg.write_text("[server]\nallow_anonymous = true\n")
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        cases = [(["--port", str(port)], "another program listens on that port"),
                 (["--port", str(port), "--host", "192.0.2.1"], "not an address of this machine"),
                 (["--port", str(port), "--host", "no.such.host.invalid"], "not an address of this machine")]
        for extra, hint in cases:
            r = subprocess.run([str(CLI), "--interface", "slcan", "--channel", "/nonexistent", "gateway",
                                "--config", str(cfg), *extra], capture_output=True, text=True, timeout=60)
            assert r.returncode == 1, (extra, r.stdout, r.stderr)
            assert "Traceback" not in r.stderr and "error starting server" not in r.stderr, r.stderr
            lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
            assert len(lines) == 1 and "cannot serve OPC UA" in lines[0] and hint in lines[0], (extra, r.stderr)


DOC = Path(__file__).resolve().parents[2] / "docs" / "gateway.md"
DOC_URL = "opc.tcp://127.0.0.1:4840/landscape/"


def doc_block(info: str) -> str:
    m = re.search(rf"^```{re.escape(info)}\n(.*?)^```$", DOC.read_text(), re.M | re.S)
    assert m, f"docs/gateway.md lost its ```{info} block"
    return m.group(1)


def test_the_example_session_of_the_docs_runs(gateway: str) -> None:
    """docs/gateway.md "Example session", line by line, against this test's gateway."""
    asyncio.run(_wait_for_description(gateway))
    lines = [ln for ln in doc_block("sh gateway-session").splitlines() if ln.strip()]
    assert len(lines) >= 4
    for line in lines:
        line = line.replace("127.0.0.1:4840", gateway.split("//")[1].split("/")[0])
        argv = shlex.split(line)
        r = subprocess.run([str(BIN / argv[0]), *argv[1:]], capture_output=True, text=True, timeout=60)
        assert r.returncode == 0 and "Traceback" not in r.stderr, (line, r.stdout, r.stderr)
        if argv[0] == "uals":
            assert "Commands" in r.stdout and "Description" in r.stdout, r.stdout
        if "getRobotPosition" in line:
            assert "CMD_EXEC_OK" in r.stdout, r.stdout
    code = doc_block("python").replace(DOC_URL.replace("opc.tcp://", "opc.tcp://alice:alice-pw@"),
                                       user_url(gateway, "alice", "alice-pw"))
    assert gateway in code.replace("alice:alice-pw@", "")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, (r.stdout, r.stderr)
    assert "CMD_STARTED_OK" in r.stdout, r.stdout
    # it waited for the event that ends its move (the line the example prints for it)
    assert re.search(r"^moveAbsoluteComplete ", r.stdout, re.M), r.stdout
    # the arm reached the target, read by another client after the example's session ended
    asyncio.run(_assert_joints(gateway, TARGET))


async def _assert_joints(url: str, target: list[float]) -> None:
    async with Client(url, timeout=UA_TIMEOUT_S) as c:
        node, ns = await controller_node(c)
        jp = await node.get_child([f"{ns}:MotionDevices", f"{ns}:Arm", f"{ns}:JointPositions"])
        assert await jp.read_value() == pytest.approx(target, abs=2e-3)


async def _wait_for_description(url: str) -> None:
    async with Client(url, timeout=UA_TIMEOUT_S) as c:
        await controller_node(c)


def make_pair(dir_: Path, name: str, uri: str) -> tuple[Path, Path]:
    key, cert = dir_ / f"{name}-key.pem", dir_ / f"{name}-cert.der"
    r = subprocess.run(["openssl", "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "30",
                        "-subj", f"/CN={name}", "-addext", f"subjectAltName=URI:{uri},DNS:localhost",
                        "-keyout", str(key), "-outform", "der", "-out", str(cert)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return cert, key


def test_basic256sha256_sign_and_encrypt_with_a_user(controller: Controller, tmp_path: Path) -> None:
    port = free_port()
    scert, skey = make_pair(tmp_path, "server", "urn:landscape:gateway:server")
    ccert, ckey = make_pair(tmp_path, "client", "urn:freeopcua:client")
    cfg = tmp_path / "gateway.toml"
    cfg.write_text(textwrap.dedent(f"""\
        [server]
        port = {port}
        security = ["Basic256Sha256_SignAndEncrypt"]
        certificate = "{scert.name}"
        private_key = "{skey.name}"
        allow_anonymous = false
        [users]
        alice = "{hash_password('alice-pw', iterations=1000)}"
        """))
    proc = subprocess.Popen([str(CLI), "--interface", "slcan", "--channel", controller.pty, "gateway",
                             "--config", str(cfg)], stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    url = f"opc.tcp://127.0.0.1:{port}/landscape/"

    async def run() -> None:
        # no unencrypted endpoint, and no anonymous session even encrypted
        plain = Client(url, timeout=UA_TIMEOUT_S)
        with pytest.raises(Exception):  # noqa: B017 (asyncua: no endpoint for the None policy)
            await plain.connect()
        c = Client(user_url(url, "alice", "alice-pw"), timeout=UA_TIMEOUT_S)
        await c.set_security_string(f"Basic256Sha256,SignAndEncrypt,{ccert},{ckey}")
        async with c:
            node, ns = await controller_node(c)
            out = await call(node, ns, "lock")
            assert out[0] == pb.CMD_EXEC_OK, out
        anon = Client(url, timeout=UA_TIMEOUT_S)
        await anon.set_security_string(f"Basic256Sha256,SignAndEncrypt,{ccert},{ckey}")
        with pytest.raises(ua.UaStatusCodeError):
            await anon.connect()
        await anon.disconnect()
    try:
        assert proc.stdout is not None
        first = proc.stdout.readline()
        assert "security Basic256Sha256_SignAndEncrypt" in first, first
        asyncio.run(run())
    finally:
        if proc.poll() is None:
            proc.send_signal(signal.SIGTERM)
        out, err = proc.communicate(timeout=30)
    assert proc.returncode == 0 and "Traceback" not in err, (out, err)
