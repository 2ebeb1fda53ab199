"""ls-simdrives seen from an independent CANopen stack: python-canopen (PyPI canopen,
written by no one here) as the master, over python-can's slcan interface on the
simulator's pty. Its RemoteNode built from ls-simdrive.eds reads every object and finds
the EDS's defaults; its BaseNode402 takes a drive through boot-up, the CiA 301 PDO
remapping, the CiA 402 state machine and cyclic synchronous position: the simulator is
a standard drive (hal/sim/drives/hal_sim_drives.h says what it implements)."""
from __future__ import annotations

import statistics
import threading
import time
from pathlib import Path

import can
import canopen
import pytest
from canopen.objectdictionary import ODArray, ODRecord, ODVariable
from canopen.sdo import SdoAbortedError
from simdrives_rig import EDS, canopen_network, reset_and_wait_for_bootup, running_simdrives

from conftest import COUNTS_PER_RAD

NODE = 0x21
ABORT_READ_ONLY = 0x06010002
ABORT_VALUE = 0x06090030
ABORT_MAP_LEN = 0x06040042
ABORT_NO_MAP = 0x06040041
PERIOD_S = 0.01  # the SYNC period the tests run, and the drive's 0x60C2


def variables(od: canopen.ObjectDictionary) -> list[ODVariable]:
    out: list[ODVariable] = []
    for obj in od.values():
        if isinstance(obj, (ODRecord, ODArray)):
            out.extend(obj.values())
        else:
            out.append(obj)
    return out


def test_a_remote_node_from_the_eds_reads_every_object_at_its_default(tmp_path: Path) -> None:
    with running_simdrives(tmp_path) as sd, canopen_network(sd.pty) as net:
        od = canopen.import_od(str(EDS), NODE)
        node = canopen.RemoteNode(NODE, od)
        net.add_node(node)
        reset_and_wait_for_bootup(node)
        readable = [v for v in variables(od) if v.readable]
        assert len(readable) > 100
        wrong = []
        for var in readable:
            got = node.sdo.upload(var.index, var.subindex)
            value = var.decode_raw(got)
            if value != var.default:
                wrong.append(f"0x{var.index:04X}:{var.subindex:02X} {var.name}: {value!r}, EDS {var.default!r}")
        assert not wrong, "\n".join(wrong)
        # The identity a master checks against the EDS's device information.
        assert node.sdo[0x1018][1].raw == od.device_information.vendor_number
        assert node.sdo[0x1018][2].raw == od.device_information.product_number
        # Every object the EDS makes read-only or const refuses a write, with 0x06010002.
        read_only = [v for v in variables(od) if not v.writable]
        assert len(read_only) > 20
        for var in read_only:
            size = max(1, len(var) // 8)
            with pytest.raises(SdoAbortedError) as e:
                node.sdo.download(var.index, var.subindex, bytes(size))
            assert e.value.code == ABORT_READ_ONLY, f"0x{var.index:04X}:{var.subindex:02X} {var.name}"
        print(f"{len(readable)} objects read back at their EDS default, {len(read_only)} refused a write")


def remap_for_csp(node: canopen.BaseNode402) -> None:
    """RPDO1 = controlword + target position, TPDO1 = statusword + position actual, both
    synchronous at every SYNC; the other PDOs off. python-canopen's save() follows the
    CiA 301 order (COB-ID bit 31, sub 0 = 0, entries, sub 0 = N, COB-ID)."""
    node.tpdo.read()
    node.rpdo.read()
    for pdos, objs in ((node.rpdo, (0x6040, 0x607A)), (node.tpdo, (0x6041, 0x6064))):
        for k in (1, 2, 3, 4):
            pdos[k].enabled = False
        pdos[1].clear()
        for index in objs:
            pdos[1].add_variable(index)
        pdos[1].trans_type = 1
        pdos[1].enabled = True
        pdos.save()


def test_the_drive_refuses_a_mapping_that_breaks_the_cia_301_rules(tmp_path: Path) -> None:
    with running_simdrives(tmp_path, "--nodes", "0x21") as sd, canopen_network(sd.pty) as net:
        node = canopen.RemoteNode(NODE, str(EDS))
        net.add_node(node)
        reset_and_wait_for_bootup(node)
        # RPDO1 is valid at power-on: its mapping and type are fixed until bit 31 is set.
        for index, sub, data in ((0x1600, 0, b"\x00"), (0x1400, 2, b"\x01")):
            with pytest.raises(SdoAbortedError) as e:
                node.sdo.download(index, sub, data)
            assert e.value.code == ABORT_VALUE
        node.sdo[0x1400][1].raw = 0x80000000 | (0x200 + NODE)
        node.sdo[0x1600][0].raw = 0
        with pytest.raises(SdoAbortedError) as e:  # the statusword is not an RPDO's
            node.sdo[0x1600][1].raw = 0x60410010
        assert e.value.code == ABORT_NO_MAP
        for k in range(1, 4):
            node.sdo[0x1600][k].raw = 0x607A0020
        with pytest.raises(SdoAbortedError) as e:  # 96 bits
            node.sdo[0x1600][0].raw = 3
        assert e.value.code == ABORT_MAP_LEN


class Pdo402:
    """A BaseNode402 driving one ls-simdrives node in CSP: SYNC and RPDO1 periodic from
    python-can's send_periodic, position read back from TPDO1."""

    def __init__(self, net: canopen.Network) -> None:
        self.node = canopen.BaseNode402(NODE, str(EDS))
        net.add_node(self.node)
        self.net = net

    def configure(self) -> None:
        node = self.node
        reset_and_wait_for_bootup(node)
        node.sdo[0x60C2][1].raw = round(PERIOD_S * 1000)  # the interpolation period: the SYNC's
        node.sdo[0x60C2][2].raw = -3
        node.sdo[0x605A].raw = 6  # quick stop stays in QUICK STOP ACTIVE (transition 16 possible)
        remap_for_csp(node)
        node.setup_402_state_machine(read_pdos=True)
        node.op_mode = "CYCLIC SYNCHRONOUS POSITION"
        assert node.op_mode == "CYCLIC SYNCHRONOUS POSITION"
        node.nmt.state = "OPERATIONAL"
        self.net.sync.start(PERIOD_S)
        node.rpdo[1].start(PERIOD_S)
        assert node.tpdo[1].wait_for_reception(1.0) is not None, "no TPDO1 after SYNC"

    def position(self) -> int:
        self.node.tpdo[1].wait_for_reception(1.0)
        return int(self.node.tpdo_values[0x6064])

    def hold_here(self) -> int:
        """Target = actual, as a master must before enable operation."""
        p = self.position()
        self.node.rpdo[1]["Target position"].raw = p
        return p

    def stop(self) -> None:
        self.node.rpdo[1].stop()
        self.net.sync.stop()


def test_base_node_402_takes_the_drive_through_every_transition_and_csp(tmp_path: Path) -> None:
    with running_simdrives(tmp_path) as sd, canopen_network(sd.pty) as net:
        m = Pdo402(net)
        m.configure()
        node = m.node
        assert node.state == "SWITCH ON DISABLED"
        m.hold_here()
        # Every transition BaseNode402 offers, each one controlword step confirmed in the
        # statusword (CiA 402 numbers in the comments).
        for target in ("READY TO SWITCH ON",  # 2
                       "SWITCHED ON",  # 3
                       "OPERATION ENABLED",  # 4
                       "SWITCHED ON",  # 5
                       "READY TO SWITCH ON",  # 6
                       "SWITCH ON DISABLED",  # 7
                       "READY TO SWITCH ON", "SWITCHED ON", "OPERATION ENABLED",
                       "READY TO SWITCH ON",  # 8
                       "SWITCHED ON", "OPERATION ENABLED",
                       "SWITCH ON DISABLED",  # 9
                       "READY TO SWITCH ON", "SWITCHED ON",
                       "SWITCH ON DISABLED",  # 10
                       "READY TO SWITCH ON", "SWITCHED ON", "OPERATION ENABLED",
                       "QUICK STOP ACTIVE",  # 11
                       "OPERATION ENABLED",  # 16 (0x605A = 6)
                       "QUICK STOP ACTIVE",
                       "SWITCH ON DISABLED"):  # 12
            node.state = target
            assert node.state == target
        # A fault from outside (EMCY 0x2310), then fault reset on the edge of bit 7 (15).
        node.state = "OPERATION ENABLED"
        sd.control(f"emcy 0x{NODE:02X} 0x2310")
        deadline = time.monotonic() + 2.0
        while not any(e.code == 0x2310 for e in node.emcy.log):
            assert time.monotonic() < deadline, "no EMCY 0x2310"
            time.sleep(0.01)
        while not node.is_faulted():
            assert time.monotonic() < deadline, "the drive did not report FAULT"
            node.check_statusword()
        assert node.sdo[0x603F].raw == 0x2310
        m.hold_here()
        node.reset_from_fault()
        assert node.state == "OPERATION ENABLED"
        assert node.sdo[0x603F].raw == 0

        # CSP: a 0.2 rad ramp over 2 s (0.1 rad/s), the actual position read back from
        # every TPDO as it moves. Each reading lies between the set-point of a little
        # earlier and the one of now: the drive follows, never leads, and its lag (the
        # RPDO's and SYNC's periods, one physics period, the servo's v / 200 and the
        # host's scheduling) stays bounded.
        p0 = m.position()
        span = round(0.2 * COUNTS_PER_RAD)
        rate = span / 2.0  # counts/s
        samples: list[tuple[float, int]] = []
        node.tpdo[1].add_callback(lambda pdo: samples.append((time.monotonic(), int(pdo[0x6064].raw))))
        t0 = time.monotonic()
        while (t := time.monotonic() - t0) < 2.0:
            node.rpdo[1]["Target position"].raw = p0 + round(rate * t)
            time.sleep(0.002)
        node.rpdo[1]["Target position"].raw = p0 + span
        time.sleep(0.3)
        moved = (m.position() - p0) / COUNTS_PER_RAD
        tol = 0.0005 * COUNTS_PER_RAD
        lags, wrong = [], []
        for ts, pos in samples:
            t = ts - t0
            if not 0.3 < t < 1.9:
                continue
            lag_s = (p0 + rate * t - pos) / rate
            lags.append(lag_s)
            if pos > p0 + rate * t + tol or lag_s > 0.25:
                wrong.append(f"t={t:.3f} s: {pos - p0} counts, set-point {rate * t:.0f}")
        print(f"CSP: moved {moved:.5f} rad of 0.2; lag behind the set-point: median "
              f"{statistics.median(lags) * 1e3:.0f} ms, max {max(lags) * 1e3:.0f} ms ({len(lags)} TPDOs)")
        assert len(lags) > 100
        assert not wrong, "\n".join(wrong[:10])
        assert abs(moved - 0.2) < 2e-4
        assert node.statusword & 0x1000  # bit 12: the drive follows the target
        node.state = "SWITCH ON DISABLED"
        m.stop()


def test_a_sync_is_answered_by_its_tpdo_within_milliseconds_on_the_pty(tmp_path: Path) -> None:
    """SYNC-to-TPDO latency: from python-can's send of the SYNC to the TPDO's arrival in
    python-can (pty, SLCAN encoding both ways, the simulator's physics step)."""
    with running_simdrives(tmp_path) as sd, canopen_network(sd.pty) as net:
        m = Pdo402(net)
        node = m.node
        reset_and_wait_for_bootup(node)
        node.sdo[0x60C2][1].raw = 4  # 4 ms of physics per SYNC
        remap_for_csp(node)
        node.nmt.state = "OPERATIONAL"
        got = threading.Event()
        arrival: list[float] = []

        def on_tpdo(_: object) -> None:
            arrival.append(time.perf_counter())
            got.set()

        node.tpdo[1].add_callback(on_tpdo)
        latencies = []
        sync = can.Message(arbitration_id=0x80, is_extended_id=False, data=b"")
        for _ in range(300):
            got.clear()
            arrival.clear()
            t = time.perf_counter()
            net.bus.send(sync)
            assert got.wait(1.0), "no TPDO after a SYNC"
            latencies.append(arrival[0] - t)
            time.sleep(0.004)
        latencies.sort()
        median = statistics.median(latencies) * 1e3
        p99 = latencies[int(len(latencies) * 0.99)] * 1e3
        print(f"SYNC -> TPDO over the pty: median {median:.2f} ms, 99th percentile {p99:.2f} ms, "
              f"max {latencies[-1] * 1e3:.2f} ms ({len(latencies)} SYNCs)")
        assert median < 5.0


def test_misbehaviour_commands_act_on_the_bus(tmp_path: Path) -> None:
    with running_simdrives(tmp_path, "--nodes", "0x21,0x22") as sd, canopen_network(sd.pty) as net:
        node = canopen.RemoteNode(NODE, str(EDS))
        net.add_node(node)
        reset_and_wait_for_bootup(node)
        node.sdo[0x1017].raw = 20  # a heartbeat every 20 ms: 15 in a 0.3 s window
        beats: list[int] = []
        node.nmt.add_heartbeat_callback(beats.append)

        def beats_in(seconds: float, after_s: float = 0.1) -> list[int]:
            """The heartbeat states heard in a window that starts `after_s` from now
            (frames in flight before a command have arrived by then)."""
            time.sleep(after_s)
            beats.clear()
            time.sleep(seconds)
            return list(beats)

        assert len(beats_in(0.3)) >= 5
        sd.control(f"silence 0x{NODE:02X}")
        assert beats_in(0.3) == []
        with pytest.raises(canopen.SdoCommunicationError):
            node.sdo[0x1000].raw  # noqa: B018 (no answer)
        sd.control("reset")
        assert len(beats_in(0.3)) >= 5
        sd.control(f"identity 0x{NODE:02X} 0xFB 0x65520000")
        assert node.sdo[0x1018][1].raw == 0xFB
        sd.control("bus-off 400", settle_s=0.0)
        assert beats_in(0.2) == []
        assert len(beats_in(0.3, after_s=0.2)) >= 5
        sd.control("reset")
        assert node.sdo[0x1018][1].raw == node.object_dictionary.device_information.vendor_number
        sd.control(f"no-boot 0x{NODE:02X}")
        beats.clear()
        node.nmt.send_command(0x81)
        time.sleep(0.4)
        assert 0 not in beats, "a node told not to boot sent its boot-up"
        assert beats_in(0.3) == []
        sd.control("reset", settle_s=0.0)
        deadline = time.monotonic() + 2.0
        while 0 not in beats:  # it boots
            assert time.monotonic() < deadline, "the node did not boot after reset"
            time.sleep(0.01)
        sd.control("nonsense")
        deadline = time.monotonic() + 2
        while "malformed" not in sd.log_text():
            assert time.monotonic() < deadline, "a malformed command was not logged"
            time.sleep(0.02)
