"""CiA 402 drives made of python-canopen's LocalNode and a vendor's EDS/DCF: the
independent slave side that landscaped's drive master is tested against.

python-canopen (PyPI `canopen`) answers SDO from the object dictionary of the file and
produces heartbeats; what a LocalNode does not do by itself, the glue here does, the way
a drive does it:

- power-on and NMT reset communication: the communication objects (0x1000-0x1FFF) go
  back to the file's values, a boot-up message goes out, the node is PRE-OPERATIONAL;
- CiA 301's PDO rules on SDO writes: a mapping or transmission type of a valid PDO
  (COB-ID bit 31 clear) is refused, mapping entries only while sub-index 0 is 0, sub 0 =
  N only with mappable entries that fit 64 bits (the aborts a real drive sends);
- at each SYNC while OPERATIONAL: the RPDOs received since the last SYNC are applied per
  their mapping, the CiA 402 power state machine takes the controlword, the position
  follows the target in CSP, and the TPDOs go out per their mapping;
- the statusword, position actual and mode display (0x6041, 0x6064, 0x6061) read live;
- faults on command: an EMCY with its code (the drive in FAULT, 0x603F set), and a hung
  NMT slave (no heartbeat, no boot-up after a reset command) until it beats again.

The network is python-can's `virtual` bus; `PtyBridge` joins it to the SLCAN pty of
landscaped's drive link, so a RemoteNode on the same virtual channel can read the
drives back independently.
"""
from __future__ import annotations

import os
import struct
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

import can
import canopen
from canopen.objectdictionary import ODVariable
from canopen.sdo import SdoAbortedError


def vendor_eds_dir() -> Path | None:
    """The vendor EDS directory (LS_VENDOR_EDS_DIR, set once in tests/CMakeLists.txt): ctest
    passes it on in the environment; run by hand, the build's own value from its
    CMakeCache.txt (LS_BUILD_DIR, else build/). None when neither says."""
    given = os.environ.get("LS_VENDOR_EDS_DIR")
    if given:
        return Path(given)
    build = Path(os.environ.get("LS_BUILD_DIR") or Path(__file__).resolve().parents[2] / "build")
    cache = build / "CMakeCache.txt"
    for line in cache.read_text().splitlines() if cache.is_file() else []:
        if line.startswith("LS_VENDOR_EDS_DIR:"):
            return Path(line.partition("=")[2])
    return None


# The vendor files (third-party: they stay outside the repository); a relative
# placeholder when no one says where they are, which the tests report as missing.
VENDOR_EDS = vendor_eds_dir() or Path("LS_VENDOR_EDS_DIR")
EPOS4_DCF = VENDOR_EDS / "epos4_50_15_can_ec90flat_gp52c_mile800_node1.dcf"
ROS2_EDS = VENDOR_EDS / "ros2_canopen_cia402_slave.eds"

# CiA 301 / 402 (the values common/ls_canopen.h names; this side is the independent one).
ABORT_STATE = 0x08000022  # data cannot be transferred in the present device state
ABORT_NO_MAP = 0x06040041  # object cannot be mapped to the PDO
ABORT_MAP_LEN = 0x06040042  # mapped objects would exceed the PDO length
PROFILE_402 = 0x00020192  # device type: CiA 402, servo drive
SW_READY, SW_SWITCHED_ON, SW_ENABLED, SW_FAULT = 0x0001, 0x0002, 0x0004, 0x0008
SW_VOLTAGE, SW_QUICK_STOP, SW_SWITCH_ON_DISABLED, SW_REMOTE, SW_CSP_FOLLOWING = 0x0010, 0x0020, 0x0040, 0x0200, 0x1000
STATES = {
    "SWITCH ON DISABLED": SW_SWITCH_ON_DISABLED,
    "READY TO SWITCH ON": SW_QUICK_STOP | SW_READY,
    "SWITCHED ON": SW_QUICK_STOP | SW_SWITCHED_ON | SW_READY,
    "OPERATION ENABLED": SW_QUICK_STOP | SW_ENABLED | SW_SWITCHED_ON | SW_READY,
    "QUICK STOP ACTIVE": SW_ENABLED | SW_SWITCHED_ON | SW_READY,
    "FAULT": SW_FAULT,
}
MODE_CSP = 8


@dataclass
class LocalDrive:
    """One drive: a LocalNode built from `eds` at `node_id` plus the glue."""

    network: canopen.Network
    node_id: int
    eds: Path
    state: str = "SWITCH ON DISABLED"
    position: int = 0
    velocity_offset: int = 0
    mode: int = 0
    last_cw: int = 0
    rpdo_data: dict[int, bytes] = field(default_factory=dict)
    syncs: int = 0
    silent: bool = False  # stop_heartbeat: no heartbeat, no boot-up
    controlwords: list[int] = field(default_factory=list)
    lock: threading.Lock = field(default_factory=threading.Lock)

    def __post_init__(self) -> None:
        od = canopen.import_od(str(self.eds), self.node_id)
        self.node = canopen.LocalNode(self.node_id, od)
        self.network.add_node(self.node)
        self.node.add_read_callback(self._on_read)
        self.node.add_write_callback(self._on_write)
        dev = od.device_information
        self.identity = {1: dev.vendor_number or 0, 2: dev.product_number or 0, 3: dev.revision_number or 0}
        self.network.subscribe(0x000, self._on_nmt)
        self.network.subscribe(0x080, self._on_sync)
        for n in range(4):
            self.network.subscribe(0x200 + 0x100 * n + self.node_id, self._on_rpdo)

    # ---- NMT: power on / reset communication

    def power_on(self) -> None:
        """The drive switches on: PRE-OPERATIONAL after its boot-up message."""
        self._reset_communication()

    def _reset_communication(self) -> None:
        with self.lock:
            for index in [i for i in self.node.data_store if 0x1000 <= i <= 0x1FFF]:
                del self.node.data_store[index]
            self.rpdo_data.clear()
        self.node.nmt.stop_heartbeat()
        if self.silent:
            return
        self.node.nmt.send_command(0x82)  # INITIALISING: python-canopen sends the boot-up
        self.node.nmt.send_command(0x80)  # PRE-OPERATIONAL, heartbeat at 0x1017's time

    def _on_nmt(self, can_id: int, data: bytearray, timestamp: float) -> None:
        cmd, node = data[0], data[1]
        if node in (0, self.node_id) and cmd in (0x81, 0x82):
            self._reset_communication()

    # ---- the object dictionary, live

    def _on_read(self, index: int, subindex: int, od: ODVariable) -> int | None:
        if index == 0x6041:
            return self.statusword()
        if index == 0x6064:
            return self.position
        if index == 0x6061:
            return self.mode
        if index == 0x1000 and od.value is None and od.default is None:
            return PROFILE_402
        if index == 0x1018 and subindex in self.identity and od.value is None and od.default is None:
            return self.identity[subindex]
        return None

    def raw(self, index: int, sub: int) -> int:
        value = self.node.sdo[index].raw if sub == 0 and isinstance(self.node.object_dictionary[index],
                                                                        ODVariable) else self.node.sdo[index][sub].raw
        return int(value)

    def _on_write(self, index: int, subindex: int, od: ODVariable, data: bytes) -> None:
        value = od.decode_raw(data)
        if 0x1400 <= index <= 0x15FF or 0x1800 <= index <= 0x19FF:
            if subindex == 2 and not self.raw(index, 1) & 0x80000000:
                raise SdoAbortedError(ABORT_STATE)  # transmission type of a valid PDO
        elif 0x1600 <= index <= 0x17FF or 0x1A00 <= index <= 0x1BFF:
            comm = index - 0x200
            if not self.raw(comm, 1) & 0x80000000:
                raise SdoAbortedError(ABORT_STATE)  # mapping of a valid PDO
            if subindex != 0 and self.raw(index, 0) != 0:
                raise SdoAbortedError(ABORT_STATE)  # entries only while sub 0 is 0
            if subindex == 0 and value:
                bits = 0
                for k in range(1, int(value) + 1):
                    entry = self.raw(index, k)
                    obj = self._object(entry >> 16, (entry >> 8) & 0xFF)
                    if obj is None or not obj.pdo_mappable:
                        raise SdoAbortedError(ABORT_NO_MAP)
                    bits += entry & 0xFF
                if bits > 64:
                    raise SdoAbortedError(ABORT_MAP_LEN)
        elif index == 0x6060:
            self.mode = int(value)
        elif index == 0x6040:
            self._controlword(int(value))

    def _object(self, index: int, sub: int) -> ODVariable | None:
        od = self.node.object_dictionary
        if index not in od:
            return None
        obj = od[index]
        if isinstance(obj, ODVariable):
            return obj if sub == 0 else None
        return obj[sub] if sub in obj else None

    # ---- CiA 402

    def statusword(self) -> int:
        sw = STATES[self.state] | SW_VOLTAGE * (self.state != "SWITCH ON DISABLED") | SW_REMOTE
        if self.state == "OPERATION ENABLED" and self.mode == MODE_CSP:
            sw |= SW_CSP_FOLLOWING
        return sw

    def _controlword(self, cw: int) -> None:
        self.controlwords.append(cw)
        rising_reset = cw & 0x80 and not self.last_cw & 0x80
        self.last_cw = cw
        s = self.state
        if s == "FAULT":
            if rising_reset:
                self.state = "SWITCH ON DISABLED"
            return
        if cw & 0x02 == 0:  # disable voltage
            self.state = "SWITCH ON DISABLED"
        elif cw & 0x04 == 0:  # quick stop
            self.state = "QUICK STOP ACTIVE" if s == "OPERATION ENABLED" else "SWITCH ON DISABLED"
        elif cw & 0x8F == 0x06:  # shutdown
            if s in ("SWITCH ON DISABLED", "SWITCHED ON", "OPERATION ENABLED"):
                self.state = "READY TO SWITCH ON"
        elif cw & 0x8F == 0x07:  # switch on / disable operation
            if s in ("READY TO SWITCH ON", "OPERATION ENABLED"):
                self.state = "SWITCHED ON"
        elif cw & 0x8F == 0x0F and s == "SWITCHED ON":  # enable operation
            self.state = "OPERATION ENABLED"

    def fault(self) -> None:
        self.state = "FAULT"

    def emcy(self, code: int, register: int = 0x01) -> None:
        """A fault of the drive's own: FAULT, its error code in 0x603F, and the EMCY frame
        (CiA 301: code, error register, five manufacturer bytes)."""
        if 0x603F in self.node.object_dictionary:
            self.node.set_data(0x603F, 0, struct.pack("<H", code), check_writable=False)
        self.state = "FAULT"
        self.node.emcy.send(code, register, b"\x00\x00\x00\x00\x00")

    def stop_heartbeat(self) -> None:
        """The drive's NMT slave hangs: no heartbeat, and no boot-up after a reset command
        either (its PDOs go on: a half-dead node), until start_heartbeat."""
        self.silent = True
        self.node.nmt.stop_heartbeat()

    def start_heartbeat(self) -> None:
        self.silent = False
        self.node.nmt.start_heartbeat(self.raw(0x1017, 0))

    # ---- PDOs at SYNC

    def _on_rpdo(self, can_id: int, data: bytearray, timestamp: float) -> None:
        with self.lock:
            self.rpdo_data[can_id] = bytes(data)

    def _mapping(self, comm: int) -> tuple[int, list[tuple[int, int, int]]] | None:
        """(COB-ID, [(index, sub, bits)]) of a valid synchronous PDO, else None."""
        if comm not in self.node.object_dictionary:
            return None
        cob = self.raw(comm, 1)
        if cob & 0x80000000 or not 1 <= self.raw(comm, 2) <= 240:
            return None
        mapping = comm + 0x200
        entries = []
        for k in range(1, self.raw(mapping, 0) + 1):
            e = self.raw(mapping, k)
            entries.append((e >> 16, (e >> 8) & 0xFF, e & 0xFF))
        return cob & 0x7FF, entries

    def _on_sync(self, can_id: int, data: bytearray, timestamp: float) -> None:
        if self.node.nmt.state != "OPERATIONAL":
            return
        with self.lock:
            received = dict(self.rpdo_data)
            self.rpdo_data.clear()
        self.syncs += 1
        for n in range(4):
            m = self._mapping(0x1400 + n)
            if m is None or m[0] not in received:
                continue
            payload, offset = received[m[0]], 0
            for index, _sub, bits in m[1]:
                size = bits // 8
                value = int.from_bytes(payload[offset:offset + size], "little", signed=index in (0x607A, 0x60B1))
                offset += size
                if index == 0x6040:
                    self._controlword(value)
                elif index == 0x607A and self.state == "OPERATION ENABLED" and self.mode == MODE_CSP:
                    self.position = value
                elif index == 0x60B1:
                    self.velocity_offset = value
                elif index == 0x6060:
                    self.mode = value
        for n in range(4):
            m = self._mapping(0x1800 + n)
            if m is None:
                continue
            out = b""
            for index, sub, bits in m[1]:
                if index == 0x6041:
                    out += struct.pack("<H", self.statusword())
                elif index == 0x6064:
                    out += struct.pack("<i", self.position)
                elif index == 0x6061:
                    out += struct.pack("<b", self.mode)
                else:
                    out += self.node.get_data(index, sub)[: bits // 8]
            self.network.send_message(m[0], out)


class PtyBridge:
    """Frames between landscaped's drive link (an SLCAN pty) and a python-can virtual
    channel, both ways, on two threads."""

    def __init__(self, pty: str, channel: str) -> None:
        self.pty = can.Bus(interface="slcan", channel=pty, bitrate=1000000, sleep_after_open=0)
        self.virtual = can.Bus(interface="virtual", channel=channel)
        self._stop = threading.Event()
        self._threads = [threading.Thread(target=self._pump, args=(self.pty, self.virtual), daemon=True),
                         threading.Thread(target=self._pump, args=(self.virtual, self.pty), daemon=True)]
        for t in self._threads:
            t.start()

    def _pump(self, src: can.BusABC, dst: can.BusABC) -> None:
        try:
            while not self._stop.is_set():
                msg = src.recv(timeout=0.05)
                if msg is not None:
                    dst.send(msg)
        except can.CanError:
            self.closed_by_peer = True  # landscaped exited: its pty is gone

    closed_by_peer = False

    def close(self) -> None:
        self._stop.set()
        for t in self._threads:
            t.join(timeout=2)
        try:
            self.pty.shutdown()  # writes SLCAN's close: the pty may be gone with landscaped
        except can.CanError:
            pass
        self.virtual.shutdown()


def wait_until(cond: object, timeout_s: float, what: str) -> None:
    deadline = time.monotonic() + timeout_s
    while not cond():  # type: ignore[operator]
        assert time.monotonic() < deadline, f"{what} did not happen within {timeout_s:g} s"
        time.sleep(0.01)
