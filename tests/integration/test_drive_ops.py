"""What an operator does with the drives (docs/deploy.md "Drives", docs/protocol.md
"Drives"): landscaped as the CiA 402 master of ls-simdrives, configured for homing,
brakes, safe torque off and readouts. Homing through `sendCommand home`, a move refused
before a required homing, the homing kept across deactivate/activate and lost when the
drive is booted again; brake, STO, temperature and torque as the drives report them in
`sendCommand drives`, `status` and `landscape drives`; safe torque off refusing activate
by name; the drive's own software limits against the robot model's at start."""
from __future__ import annotations

import json
import socket
import subprocess
import time
from collections.abc import Iterator
from pathlib import Path

import can
import canopen
import pytest
from simdrives_rig import EDS, canopen_network

from conftest import (
    LANDSCAPED,
    Controller,
    drive_config,
    start_controller,
    start_simdrives,
    stop_clean,
    stop_drives,
)
from landscape import errors
from landscape._generated import landscape_pb2 as pb
from landscape.supervisor import Supervisor

HOME_OFFSET_RAD = 0.05  # joint 2's angle at its home: 0x607C, "home here" (method 37)
READOUT_KEYS = {"brake": "0x2100:01/0", "sto": "0x2100:02/0", "temperature": "0x2100:03",
                "temperature_scale": "0.1"}
JOINTS = {n: dict(READOUT_KEYS) for n in range(1, 7)}
JOINTS[2].update({"home_required": "true", "home_method": "37", "home_offset_rad": str(HOME_OFFSET_RAD)})
DRIVES = {"readouts": "torque", "cycle": "8"}  # 8 ms: half the frames of the default on a loaded machine


def _send(ctl: Path, command: str) -> None:
    with socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM) as s:
        s.sendto(command.encode(), str(ctl))
    time.sleep(0.05)


@pytest.fixture
def rig(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[tuple[Controller, Supervisor]]:
    monkeypatch.setattr("conftest.ARM", "cia402")
    c = start_controller(tmp_path / "ls0", joints=JOINTS, drive_keys=DRIVES)
    bus = can.Bus(interface="slcan", channel=c.pty, bitrate=1000000, sleep_after_open=0)
    try:
        with Supervisor(bus, client_name="ops") as sup:
            sup.lock()
            yield c, sup
    finally:
        bus.shutdown()
        stop_clean(c)


def _joints(sup: Supervisor) -> list[float]:
    return list(sup.get_robot_position().result["joints"])


def _lines(sup: Supervisor, what: str) -> dict[str, dict[str, str]]:
    """sendCommand drives / status: the `drive jN k=v ...` lines by joint."""
    out: dict[str, dict[str, str]] = {}
    for line in str(sup.send_command(what).result["result"]).splitlines():
        words = line.split()
        if len(words) > 2 and words[0] == "drive":
            out[words[1]] = dict(w.split("=", 1) for w in words[2:])
    return out


def _full(sup: Supervisor, joint: int) -> dict[str, str]:
    text = str(sup.send_command(f"drives {joint}").result["result"])
    return dict(line.split("=", 1) for line in text.splitlines())


def test_a_move_waits_for_the_required_homing_which_sendcommand_home_does(
        rig: tuple[Controller, Supervisor]) -> None:
    c, sup = rig
    homing = sup.describe().result["homing"]
    assert [h.get("required", False) for h in homing] == [False, True, False, False, False, False]
    assert {h.get("state", "HOME_NOT_HOMED") for h in homing} == {"HOME_NOT_HOMED"}
    sup.activate()
    q0 = _joints(sup)
    # any motion before the homing is refused, naming the joint and what to do
    with pytest.raises(errors.WrongStateError) as e:
        sup.move_absolute("p", [0.1, 0.1, 0.1, 0.1, 0.1, 0.1])
    assert "joint 2 must be homed first (an incremental encoder): send sendCommand home" in str(e.value)
    assert _lines(sup, "status")["j2"]["home"] == "not_homed(required)"
    # homing: answered when it ends; the joint now reads its home offset, and did not move
    rv = sup.send_command("home")
    assert rv.ret_msg == "homed: joint 2", rv.ret_msg
    q1 = _joints(sup)
    assert q1[1] == pytest.approx(HOME_OFFSET_RAD, abs=2e-3)
    assert [q for j, q in enumerate(q1) if j != 1] == pytest.approx([q for j, q in enumerate(q0) if j != 1], abs=1e-3)
    time.sleep(0.3)
    assert _joints(sup) == pytest.approx(q1, abs=1e-3)  # held where it now reads: no jump
    assert sup.describe().result["homing"][1]["state"] == "HOME_HOMED"
    assert _full(sup, 2)["home"] == "homed"
    # the arm moves now, to where it was told in the new frame
    target = [0.2, 0.3, -0.2, 0.4, 0.3, -0.3]
    sup.wait_complete(sup.move_absolute("p", target, speed_pct=40), timeout_s=20)
    assert _joints(sup) == pytest.approx(target, abs=2e-3)
    # kept across deactivate and activate
    sup.deactivate()
    sup.activate()
    assert sup.describe().result["homing"][1]["state"] == "HOME_HOMED"
    sup.wait_complete(sup.move_absolute("back", [0.0] * 6, speed_pct=40), timeout_s=20)
    events = str(sup.send_command("events").result["result"])
    assert "sendCommand home: joint 2 homed" in events, events


def test_home_is_the_owners_at_rest_and_names_bad_joints(rig: tuple[Controller, Supervisor]) -> None:
    c, sup = rig
    rv = sup.send_command("home", check=False)
    assert rv.ret_code == pb.CMD_WRONG_STATE_ERR
    assert "sendCommand home is valid in RESTING (drives on, at rest), the device is LOCKED: activate first" in \
        rv.ret_msg
    sup.activate()
    rv = sup.send_command("home 7", check=False)
    assert rv.ret_code == pb.CMD_PARAM_ERR
    assert rv.ret_msg == "sendCommand home: '7' is no joint: name joints 1..6, or none for every joint that must " \
                         "be homed"
    # a joint that need not be homed may be, when named
    rv = sup.send_command("home 1 2")
    assert rv.ret_msg == "homed: joints 1, 2"


def test_a_drive_booted_again_has_lost_its_homing(rig: tuple[Controller, Supervisor]) -> None:
    c, sup = rig
    assert c.drives_control is not None
    sup.activate()
    sup.send_command("home")
    _send(c.drives_control, "silence 0x22")
    deadline = time.monotonic() + 3
    while sup.get_motion_control_state().result["state"] != "LOCKED":
        assert time.monotonic() < deadline, "the silent drive did not fault the arm"
        time.sleep(0.05)
    time.sleep(0.5)  # beyond heartbeat_timeout_ms: the master has lost the node, not only its feedback
    _send(c.drives_control, "reset")
    sup.activate()  # configures the drive again: it may have restarted meanwhile
    assert sup.describe().result["homing"][1].get("state", "HOME_NOT_HOMED") == "HOME_NOT_HOMED"
    with pytest.raises(errors.WrongStateError):
        sup.move_absolute("p", [0.1] * 6)


def test_brake_sto_temperature_and_torque_come_from_the_drives(rig: tuple[Controller, Supervisor]) -> None:
    c, sup = rig
    assert c.drives_control is not None
    off = _lines(sup, "drives")
    assert sorted(off) == ["j1", "j2", "j3", "j4", "j5", "j6"]
    for j, line in off.items():
        assert line["state"] == "SWITCH_ON_DISABLED" and line["brake"] == "engaged" and line["sto"] == "off", (j, line)
        assert line["node"] == f"0x{0x20 + int(j[1]):02X}"
    full = _full(sup, 2)
    assert full["temperature_c"] == "30.0" and full["torque_permille"] == "0", full
    assert full["error"] == "0x0000" and "velocity_rad_s" not in full  # not asked for: not mapped
    sup.activate()
    time.sleep(0.2)
    on = _lines(sup, "drives")
    assert {line["brake"] for line in on.values()} == {"released"}
    assert {line["state"] for line in on.values()} == {"OPERATION_ENABLED"}
    full = _full(sup, 2)
    assert int(full["torque_permille"]) != 0  # the shoulder holds the arm up
    assert float(full["temperature_c"]) > 30.0
    counters = dict(line.split("=") for line in str(sup.send_command("drives bus").result["result"]).splitlines())
    assert int(counters["sync_sent"]) > 0 and int(counters["frames_in"]) > 0
    # safe torque off: the drive's input, named when activate is refused
    sup.deactivate()
    _send(c.drives_control, "sto 0x24 on")
    time.sleep(0.1)
    assert _lines(sup, "status")["j4"]["sto"] == "active"
    rv = sup.activate(check=False)
    assert rv.ret_code == pb.CMD_ERR
    assert rv.ret_msg.startswith("activate failed, the drives are off: joint 4 (node 0x24): safe torque off is "
                                 "active (0x2100:02 bit 0"), rv.ret_msg
    _send(c.drives_control, "sto 0x24 off")
    sup.activate()
    # the drive's last EMCY, with its name, in the full view
    _send(c.drives_control, "emcy 0x25 0x4310")
    time.sleep(0.3)
    assert _full(sup, 5)["error"] == "0x4310"
    assert _full(sup, 5)["error_name"] == "excess drive temperature"


def test_the_host_view_lists_every_drive(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """`landscape drives`, its own session (the pty takes one reader at a time)."""
    monkeypatch.setattr("conftest.ARM", "cia402")
    c = start_controller(tmp_path / "ls0", joints=JOINTS, drive_keys=DRIVES)
    try:
        r = c.cli("--json", "drives")
        assert r.returncode == 0, r.stderr
        rows = json.loads(r.stdout)
        assert [row["joint"] for row in rows["drives"]] == [1, 2, 3, 4, 5, 6]
        j2 = rows["drives"][1]
        assert j2["node"] == "0x22" and j2["state"] == "SWITCH ON DISABLED" and j2["home"] == "not_homed"
        assert j2["home_required"] is True and j2["brake"] == "engaged" and j2["temperature_c"] == 30.0
        assert j2["torque_permille"] == 0 and j2["velocity_rad_s"] is None  # velocity: not asked for
        assert rows["bus"]["sync_sent"] > 0
        r = c.cli("drives")
        assert r.returncode == 0, r.stderr
        lines = r.stdout.splitlines()
        assert lines[0].split()[:5] == ["joint", "node", "state", "mode", "home"], lines
        assert "0x22" in lines[2] and "not_homed*" in lines[2] and "engaged" in lines[2], lines
        assert lines[-1].startswith("bus: frames_in="), lines
    finally:
        stop_clean(c)


def test_a_drive_range_narrower_than_the_models_refuses_the_start(tmp_path: Path) -> None:
    """0x607D of joint 4's drive set to +-1 rad (the model's joint 4 turns +-185 degrees):
    landscaped reads it at start and refuses, naming the joint, the node and both ranges."""
    pty = tmp_path / "drives0"
    drives, _control = start_simdrives(pty)
    try:
        counts = round(1.0 * 2**17 * 100 / (2 * 3.141592653589793))
        with canopen_network(str(pty)) as net:
            node = canopen.RemoteNode(0x24, str(EDS))
            net.add_node(node)
            node.sdo.download(0x607D, 1, (-counts).to_bytes(4, "little", signed=True))
            node.sdo.download(0x607D, 2, counts.to_bytes(4, "little", signed=True))
        conf = drive_config(tmp_path / "drives.conf", pty)
        log = tmp_path / "ls0.log"
        with open(log, "wb") as err:
            proc = subprocess.run([str(LANDSCAPED), "--config", str(conf), "--link", f"slcan:pty:{tmp_path / 'ls0'}"],
                                  stdout=subprocess.DEVNULL, stderr=err, timeout=30)
        text = log.read_text()
        assert proc.returncode == 1, text
        assert (f"drives: joint 4 (node 0x24): the drive's software position limits 0x607D = {-counts}..{counts} "
                "counts (-1.0000..1.0000 rad) do not contain the robot model's -3.2289..3.2289 rad") in text, text
    finally:
        stop_drives(drives)
