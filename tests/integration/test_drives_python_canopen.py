"""landscaped's CiA 402 drive master against drives it did not write: python-canopen's
LocalNode holding two vendors' device descriptions (a maxon EPOS4 DCF, ros2_canopen's
CiA 402 test drive EDS; LS_VENDOR_EDS_DIR), with the glue of canopen_local_drives.py.

The master must boot them, remap their PDOs in CiA 301's order (the drives refuse
anything else), set CSP, the interpolation period and the drives' own supervision
(following error, quick stop), enable them through the 402 state machine and drive them;
an independent python-canopen RemoteNode then reads the configuration back. Drives that
send an EMCY or stop their heartbeat meet the reaction they meet on ls-simdrives
(test_drive_faults.py): the final notice, the alarm, the stop, nothing resuming by
itself, and recovery by activate."""
from __future__ import annotations

import signal
import subprocess
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import can
import canopen
import pytest

from canopen_local_drives import EPOS4_DCF, ROS2_EDS, LocalDrive, PtyBridge, wait_until
from conftest import LANDSCAPED, final_notice
from landscape._generated import landscape_pb2 as pb
from landscape.supervisor import Supervisor, notice_data

NODES = [0x21, 0x22, 0x23, 0x24, 0x25, 0x26]
FILES = [EPOS4_DCF, EPOS4_DCF, EPOS4_DCF, ROS2_EDS, ROS2_EDS, ROS2_EDS]
COUNTS_PER_RAD = 10000.0
CYCLE = 10  # control periods per drive cycle: 10 ms, python's pace (the drives here are Python)


@dataclass
class Rig:
    proc: subprocess.Popen[bytes]
    log: Path
    sup_pty: Path
    drives: list[LocalDrive]
    network: canopen.Network
    channel: str
    bridge: PtyBridge


FE_WINDOW_RAD = 0.2  # the drives' own following-error window, 2000 counts
FE_TIMEOUT_MS = 50
QUICK_STOP_OPTION = 6  # decelerate on the quick-stop ramp, stay in QUICK STOP ACTIVE


def _config(tmp: Path) -> Path:
    joints = "".join(f"[joint.{j + 1}]\nnode = {NODES[j]:#x}\neds = {FILES[j]}\ncounts_per_rad = {COUNTS_PER_RAD}\n"
                     f"following_window_rad = {FE_WINDOW_RAD}\nfollowing_timeout_ms = {FE_TIMEOUT_MS}\n"
                     + ("sign = -1\noffset_rad = 0.25\n" if j == 4 else "") for j in range(6))
    conf = tmp / "drives.conf"
    conf.write_text("[hal]\narm = cia402\ndio = none\n"
                    f"[drives]\nlink = slcan:pty:{tmp / 'drv'}\ncycle = {CYCLE}\nheartbeat_ms = 100\n"
                    f"heartbeat_timeout_ms = 600\nboot_timeout_ms = 8000\nquick_stop_option = {QUICK_STOP_OPTION}\n"
                    + joints)
    return conf


@pytest.fixture
def rig(tmp_path: Path) -> Iterator[Rig]:
    for f in sorted(set(FILES)):
        if not f.is_file():
            pytest.fail(f"{f} is missing: the vendor EDS directory (LS_VENDOR_EDS_DIR) holds it: run through "
                        "ctest, configure with -DLS_VENDOR_EDS_DIR=DIR, or set LS_VENDOR_EDS_DIR=DIR")
    channel = f"drives-{tmp_path.name}"
    network = canopen.Network()
    network.connect(interface="virtual", channel=channel)
    drives = [LocalDrive(network, n, f) for n, f in zip(NODES, FILES, strict=True)]
    log = tmp_path / "landscaped.log"
    sup_pty = tmp_path / "ls0"
    with open(log, "wb") as err:
        proc = subprocess.Popen([str(LANDSCAPED), "--config", str(_config(tmp_path)), "--link", f"slcan:pty:{sup_pty}",
                                 "--clock", "realtime", "--no-lock-memory", "--rt-priority", "0"],
                                stdout=subprocess.DEVNULL, stderr=err)
    bridge = None
    try:
        wait_until(lambda: (tmp_path / "drv").exists() or proc.poll() is not None, 10, "the drive pty")
        assert proc.poll() is None, log.read_text()
        bridge = PtyBridge(str(tmp_path / "drv"), channel)
        for d in drives:
            d.power_on()  # each drive switches on and says so (boot-up)
        wait_until(lambda: "ready: node" in log.read_text() or proc.poll() is not None, 30, "landscaped ready")
        assert proc.poll() is None, log.read_text()
        yield Rig(proc, log, sup_pty, drives, network, channel, bridge)
    finally:
        if proc.poll() is None:
            proc.send_signal(signal.SIGTERM)
            try:
                proc.wait(timeout=15)
            except subprocess.TimeoutExpired:
                proc.kill()
        if bridge is not None:
            bridge.close()
        network.disconnect()
    assert proc.returncode == 0, log.read_text()[-4000:]
    assert "Sanitizer" not in log.read_text()


def _sdo_read(node: canopen.RemoteNode, index: int, sub: int) -> int:
    data = node.sdo.upload(index, sub)
    return int.from_bytes(data, "little")


def test_the_master_configures_python_canopen_drives_as_an_independent_reader_reads_them_back(rig: Rig) -> None:
    log = rig.log.read_text()
    assert "drives: 6 joints ready" in log, log
    # an independent reader on the same bus: python-canopen's RemoteNode over SDO
    reader = canopen.Network()
    reader.connect(interface="virtual", channel=rig.channel)
    try:
        for node_id, path, drive in zip(NODES, FILES, rig.drives, strict=True):
            node = canopen.RemoteNode(node_id, str(path))
            reader.add_node(node)
            node.sdo.RESPONSE_TIMEOUT = 2.0
            assert drive.node.nmt.state == "OPERATIONAL"
            # RPDO1: controlword + target position, synchronous, at the predefined COB-ID
            assert _sdo_read(node, 0x1400, 1) & 0x800007FF == 0x200 + node_id
            assert _sdo_read(node, 0x1400, 2) == 1
            assert _sdo_read(node, 0x1600, 0) == 2
            assert _sdo_read(node, 0x1600, 1) == 0x60400010
            assert _sdo_read(node, 0x1600, 2) == 0x607A0020
            # RPDO2: the velocity feed-forward, where the drive's file lets 0x60B1 be mapped
            if node.object_dictionary[0x60B1].pdo_mappable:
                assert _sdo_read(node, 0x1401, 1) & 0x800007FF == 0x300 + node_id
                assert _sdo_read(node, 0x1601, 0) == 1
                assert _sdo_read(node, 0x1601, 1) == 0x60B10020
            else:
                assert _sdo_read(node, 0x1401, 1) & 0x80000000
                assert f"joint {NODES.index(node_id) + 1} (node {node_id:#04x}): no velocity feed-forward" in log
            # TPDO1: statusword + position actual; every other PDO off
            assert _sdo_read(node, 0x1800, 1) & 0x800007FF == 0x180 + node_id
            assert _sdo_read(node, 0x1800, 2) == 1
            assert _sdo_read(node, 0x1A00, 0) == 2
            assert _sdo_read(node, 0x1A00, 1) == 0x60410010
            assert _sdo_read(node, 0x1A00, 2) == 0x60640020
            for n in (1, 2, 3):
                assert _sdo_read(node, 0x1800 + n, 1) & 0x80000000, f"node {node_id:#x} TPDO{n + 1} is still on"
            for n in (2, 3):
                assert _sdo_read(node, 0x1400 + n, 1) & 0x80000000, f"node {node_id:#x} RPDO{n + 1} is still on"
            # the interpolation period is the drive cycle (10 ms = 10 x 10^-3 s), CSP is set
            assert _sdo_read(node, 0x60C2, 1) == CYCLE
            assert _sdo_read(node, 0x60C2, 2) == 0xFD  # -3
            assert _sdo_read(node, 0x6060, 0) == 8
            assert _sdo_read(node, 0x6061, 0) == 8
            # heartbeats: the drive's own, and its watch of the controller's (node 0x7F, 600 ms)
            assert _sdo_read(node, 0x1017, 0) == 100
            assert _sdo_read(node, 0x1016, 1) == (0x7F << 16) | 600
            # the drive's own supervision, from the configuration where its file lets it be written
            assert _sdo_read(node, 0x6065, 0) == round(FE_WINDOW_RAD * COUNTS_PER_RAD)
            assert _sdo_read(node, 0x605A, 0) == QUICK_STOP_OPTION
            if 0x6066 in node.object_dictionary:
                assert _sdo_read(node, 0x6066, 0) == FE_TIMEOUT_MS
            else:
                assert f"joint {NODES.index(node_id) + 1} (node {node_id:#04x}): its EDS has no writable 0x6066" in log
    finally:
        reader.disconnect()


def test_the_master_enables_and_drives_them_in_csp(rig: Rig) -> None:
    bus = can.Bus(interface="slcan", channel=str(rig.sup_pty), bitrate=1000000, sleep_after_open=0)
    try:
        with Supervisor(bus, client_name="drives") as s:
            s.lock()
            t0 = time.monotonic()
            s.activate()
            took = time.monotonic() - t0
            for d in rig.drives:
                assert d.state == "OPERATION ENABLED"
                # one step per cycle, each confirmed: shutdown, switch on, enable operation
                steps = [cw & 0x8F for cw in d.controlwords]
                assert steps[steps.index(0x06):][:1] == [0x06]
                i6, i7, i15 = steps.index(0x06), steps.index(0x07), steps.index(0x0F)
                assert i6 < i7 < i15
            assert took < 2.0
            target = [0.3, -0.2, 0.4, 0.5, -0.6, 0.7]
            # slowly: the drives here are Python threads on a loaded machine, whose
            # answers may come tens of ms late (the master's timing is not what this checks)
            rv = s.move_absolute("p", target, speed_pct=10)
            s.wait_complete(rv, timeout_s=30)
            got = s.get_robot_position().result["joints"]
            assert list(got) == pytest.approx(target, abs=1e-3)
            for j, d in enumerate(rig.drives):
                sign, off = (-1, 0.25) if j == 4 else (1, 0.0)
                want = round(sign * (target[j] - off) * COUNTS_PER_RAD)
                assert abs(d.position - want) <= 1, f"joint {j + 1}: drive at {d.position}, wanted {want}"
            s.deactivate()
            wait_until(lambda: all(d.state == "READY TO SWITCH ON" for d in rig.drives), 2, "every drive disabled")
            assert s.get_motion_control_state().result["state"] == "LOCKED"
    finally:
        bus.shutdown()


def test_activate_resets_a_drive_in_fault_and_names_one_that_stays_in_fault(rig: Rig) -> None:
    rig.drives[2].fault()
    rig.drives[2].last_cw = 0x80  # no rising edge of bit 7 without a 0 first: the master must send one
    bus = can.Bus(interface="slcan", channel=str(rig.sup_pty), bitrate=1000000, sleep_after_open=0)
    try:
        with Supervisor(bus, client_name="drives") as s:
            s.lock()
            rv = s.activate(check=False)
            # the master resets the fault (bit 7 low, then its rising edge) and enables
            assert rv.ret_code == pb.CMD_EXEC_OK, rv.ret_msg
            cws = rig.drives[2].controlwords
            first_edge = next(i for i in range(1, len(cws)) if cws[i] & 0x80 and not cws[i - 1] & 0x80)
            assert first_edge > 0
            s.deactivate()
            # a drive that stays in FAULT is named
            rig.drives[2].fault()
            seen = rig.drives[2].syncs
            wait_until(lambda: rig.drives[2].syncs >= seen + 2, 2, "a TPDO with the FAULT")  # the master knows it
            orig = rig.drives[2]._controlword

            def sticky(cw: int) -> None:
                rig.drives[2].controlwords.append(cw)
                rig.drives[2].last_cw = cw

            rig.drives[2]._controlword = sticky  # type: ignore[method-assign]
            rv = s.activate(check=False)
            rig.drives[2]._controlword = orig  # type: ignore[method-assign]
            assert rv.ret_code != pb.CMD_EXEC_OK
            assert rv.ret_msg.startswith("activate failed, the drives are off: joint 3 (node 0x23): "), rv.ret_msg
            assert "stays in FAULT after 2 fault resets" in rv.ret_msg, rv.ret_msg
            assert s.get_motion_control_state().result["state"] == "LOCKED"
    finally:
        bus.shutdown()


TARGET = [0.4, -0.3, 0.5, 0.6, -0.5, 0.6]


@contextmanager
def _owner(rig: Rig, name: str) -> Iterator[Supervisor]:
    """A supervisor on landscaped's pty that has locked the device and activated it."""
    bus = can.Bus(interface="slcan", channel=str(rig.sup_pty), bitrate=1000000, sleep_after_open=0)
    try:
        with Supervisor(bus, client_name=name) as s:
            s.lock()
            s.activate()
            list(s.notices(timeout_s=0.1))
            yield s
    finally:
        bus.shutdown()


def test_an_emcy_of_a_python_canopen_drive_ends_the_move_as_with_the_simulated_drives(rig: Rig) -> None:
    """The same reaction as tests/integration/test_drive_faults.py on ls-simdrives: the
    motion's one final notice names the joint, the node and the code; the EMCY is an alarm to
    every supervisor; the drive's 0x603F is read back once the drives are off; activate resets
    the fault and the arm moves again."""
    with _owner(rig, "emcy") as s:
        seq = s.move_absolute("far", TARGET, speed_pct=10).seq
        time.sleep(0.8)
        rig.drives[2].emcy(0x8611)
        seen: list[pb.Notice] = []
        final = final_notice(s, seq, seen, timeout_s=15)
        assert final.event_id == "moveAbsoluteFailed" and final.kind == pb.ALARM
        d = notice_data(final)
        assert d["reason"] == "fault" and d["fault"] == "joint 3 (node 0x23): FAULT, EMCY 0x8611 following error", d
        st = s.get_motion_control_state().result
        assert st["state"] == "LOCKED" and st["motion_control_state"] == "robot_stopped_on_error", st
        seen += list(s.notices(timeout_s=2.0))
        emcy = [notice_data(n) for n in seen if n.event_id == "driveEmcy"]
        assert emcy and (emcy[0]["joint"], emcy[0]["node"], emcy[0]["code"]) == ("3", "0x23", "0x8611"), seen
        assert any(notice_data(n).get("code") == "0x8611" for n in seen if n.event_id == "driveErrorCode"), seen
        q = s.get_robot_position().result["joints"]
        time.sleep(0.3)
        assert s.get_robot_position().result["joints"] == pytest.approx(q, abs=1e-4)  # nothing resumes
        s.activate()  # the master's reset edge clears the drive's FAULT
        s.wait_complete(s.move_absolute("back", [0.0] * 6, speed_pct=10), timeout_s=30)


def test_a_python_canopen_drive_whose_heartbeat_stops_is_lost_until_activate_finds_it(rig: Rig) -> None:
    """Its PDOs go on, its heartbeat does not: the master's consumer time-out (600 ms) loses
    the node, the move ends naming it, activate is refused while it stays silent, and once it
    beats again activate configures it anew and the arm moves."""
    with _owner(rig, "heartbeat") as s:
        seq = s.move_absolute("far", TARGET, speed_pct=10).seq
        time.sleep(0.5)
        t0 = time.monotonic()
        rig.drives[3].stop_heartbeat()
        final = final_notice(s, seq, [], timeout_s=15)
        took = time.monotonic() - t0
        d = notice_data(final)
        assert final.event_id == "moveAbsoluteFailed" and d["reason"] == "fault", d
        assert d["fault"].startswith("joint 4 (node 0x24): ") and "heartbeat" in d["fault"], d
        assert took < 2.0, f"the silent drive was noticed after {took:.2f} s"
        rv = s.activate(check=False)
        assert rv.ret_code != pb.CMD_EXEC_OK and "joint 4 (node 0x24)" in rv.ret_msg, rv.ret_msg
        rig.drives[3].start_heartbeat()
        s.activate()
        s.wait_complete(s.move_absolute("back", [0.0] * 6, speed_pct=10), timeout_s=30)
