"""Opening a python-can bus, and the ISO-TP addressing of the protocol.

The interface, channel and bitrate come from the arguments, else from
python-can's environment variables (CAN_INTERFACE, CAN_CHANNEL, CAN_BITRATE,
CAN_CONFIG; with a context NAME first the ones suffixed _NAME), else from its
configuration file (section [NAME], then [default], of the file given or of
~/can.conf, /etc/can.conf, ~/.can, ~/.canrc on Linux); see
``can.util.load_config``. Every failure to open is a BusError that names the
channel and says what to check.
"""
from __future__ import annotations

import logging
import os
import select
import socket
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import can
import isotp

from . import link
from ._generated import landscape_pb2 as pb
from .errors import BusError
from .telemetry import cycle_time_s

log = logging.getLogger("landscape.bus")

DEFAULT_DEVICE: int = pb.DEFAULT_DEVICE_ADDRESS
DEFAULT_HOST: int = pb.DEFAULT_HOST_ADDRESS
#: The addresses a supervisor picks a free one from when none is pinned (docs/protocol.md "Addresses").
HOST_POOL: tuple[int, ...] = tuple(range(pb.DEFAULT_HOST_ADDRESS, pb.HOST_ADDRESS_POOL_LAST + 1))
#: A supervisor's heartbeat period unless it is given one: the device's own, the HEARTBEAT message's
#: GenMsgCycleTime in protocol/landscape.dbc (200 ms). The device takes HEARTBEAT_PERIOD_MIN_MS ..
#: HEARTBEAT_PERIOD_MAX_MS of the schema (docs/protocol.md "Liveness").
DEFAULT_HEARTBEAT_PERIOD_MS: int = round(cycle_time_s("HEARTBEAT") * 1000)
#: How long a supervisor without a pinned address listens for other supervisors' heartbeats before it
#: picks one: 1.5 periods of the library's default heartbeat. A supervisor beating slower may go
#: unheard; the device then refuses the connect (address in use) and the next address is tried.
ADDRESS_LISTEN_S = 1.5 * DEFAULT_HEARTBEAT_PERIOD_MS / 1000
#: How many addresses a supervisor tries when the device refuses its connect as "in use".
ADDRESS_TRIES = 4
FUNCTIONAL_ALL: int = pb.FUNCTIONAL_ALL_DEVICES
PHYSICAL_BASE: int = pb.ISOTP_PHYSICAL_BASE
FUNCTIONAL_BASE: int = pb.ISOTP_FUNCTIONAL_BASE
SLCAN_DEFAULT_BITRATE = 1_000_000
MAX_MESSAGE_BYTES: int = pb.ISOTP_MAX_MESSAGE_BYTES

#: ISO-TP parameters shared with the firmware: the schema's enum IsotpParam (docs/protocol.md
#: "ISO-TP parameters"); every frame is padded to a whole classic CAN frame (8 bytes).
ISOTP_PARAMS: dict[str, Any] = {
    "tx_padding": pb.ISOTP_PADDING_BYTE,
    "blocksize": pb.ISOTP_BLOCK_SIZE,
    "stmin": pb.ISOTP_ST_MIN,
    "rx_flowcontrol_timeout": pb.ISOTP_N_TIMEOUT_MS,
    "rx_consecutive_frame_timeout": pb.ISOTP_N_TIMEOUT_MS,
    "tx_data_min_length": 8,
    "max_frame_size": MAX_MESSAGE_BYTES,
}


@dataclass(frozen=True)
class BusSpec:
    """Where to find the bus; None fields fall back to python-can's config and environment."""

    interface: str | None = None
    channel: str | None = None
    bitrate: int | None = None
    context: str | None = None       # python-can config context: section and env suffix
    config_file: str | None = None   # a python-can config file instead of the default ones
    #: Where else this program takes the interface from, for the "no usable CAN interface" message
    #: (the gateway: its configuration's [bus] section).
    also_from: str | None = None

    def describe(self) -> str:
        cfg = resolve_config(self, strict=False)
        return f"{cfg.get('interface', '?')}:{cfg.get('channel', '?')}"


def resolve_config(spec: BusSpec, *, strict: bool = True) -> dict[str, Any]:
    """The python-can configuration for `spec` (arguments override config file and env)."""
    given: dict[str, Any] = {}
    if spec.interface:
        given["interface"] = spec.interface
    if spec.channel:
        given["channel"] = spec.channel
    if spec.bitrate:
        given["bitrate"] = spec.bitrate
    try:
        if spec.config_file is not None and not Path(spec.config_file).is_file():
            raise FileNotFoundError(f"config file {spec.config_file} does not exist")
        return dict(can.util.load_config(path=spec.config_file, config=given, context=spec.context))
    except Exception as exc:  # python-can raises several types for a bad config
        if not strict:
            return given
        raise BusError(
            f"no usable CAN interface ({exc}): pass --interface and --channel "
            f"(e.g. --interface slcan --channel /dev/pts/3), {spec.also_from + ', ' if spec.also_from else ''}"
            f"set CAN_INTERFACE and CAN_CHANNEL, or write them "
            f"in ~/.canrc ([default] interface = ..., channel = ...)") from None


def _hint(cfg: dict[str, Any], exc: BaseException) -> str:
    iface = cfg.get("interface")
    if iface == "slcan":
        return "is landscaped running with --link slcan:pty:PATH, and is --channel that PATH?"
    if iface == "socketcan":
        if isinstance(exc, OSError) and exc.errno == 97:
            return "this kernel has no SocketCAN (AF_CAN); use --interface slcan with landscaped's pty"
        return "does the interface exist and is it up (ip link set CHANNEL up)?"
    return "check --interface and --channel"


def open_bus(spec: BusSpec | None = None, **kwargs: Any) -> can.BusABC:
    """Open the bus described by `spec`; a thread-safe bus, since the heartbeat,
    the ISO-TP stacks and the caller all send on it. Extra kwargs go to python-can."""
    spec = spec or BusSpec()
    cfg = resolve_config(spec)
    cfg.update(kwargs)
    if cfg.get("interface") == "slcan":
        cfg.setdefault("sleep_after_open", 0)
        cfg.setdefault("bitrate", SLCAN_DEFAULT_BITRATE)
    channel = cfg.get("channel")
    shared = False
    claimed: str | None = None
    if cfg.get("interface") == "slcan" and isinstance(channel, str) and link.is_local_line(channel):
        holder = link.read_holder(channel)
        if holder is not None:  # a session serves this line: share it (landscape/link.py)
            log.info("%s is served by pid %d: sharing it at %s", channel, holder.pid, holder.url)
            cfg["channel"] = holder.url
            shared = True
        else:
            link.claim(channel)
            claimed = channel
    try:
        bus = can.ThreadSafeBus(**cfg)
    except Exception as exc:
        if claimed is not None:
            link.release(claimed)
        if shared:
            raise BusError(f"cannot reach the link of {channel} at {cfg['channel']} ({exc}): check "
                           f"`landscape session status`, or stop the session and retry") from None
        raise BusError(
            f"cannot open CAN channel '{channel}' on interface '{cfg.get('interface')}': "
            f"{exc}; {_hint(cfg, exc)}") from None
    if shared:
        sock = getattr(getattr(bus, "serialPortOrig", None), "_socket", None)
        if isinstance(sock, socket.socket):
            # pyserial's socket URL leaves Nagle on: every frame line would wait for the previous ACK.
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            _read_lines_in_chunks(bus, sock)
    if claimed is not None:
        _read_serial_in_chunks(bus)
        _claims[id(bus)] = claimed
    return bus


def _take_line(buffer: bytearray) -> str | None:
    """The first whole SLCAN line in `buffer` with its terminator, taken out of it; None if none."""
    cut = link.line_end(buffer)
    if cut < 0:
        return None
    line = bytes(buffer[:cut + 1]).decode()
    del buffer[:cut + 1]
    return line


def _read_serial_in_chunks(bus: can.BusABC) -> None:
    """Read a serial line (landscaped's pty) in chunks instead of python-can's one byte per call.

    python-can's slcanBus._read costs a read system call per byte (28 per 29-bit frame), so a
    busy process (the gateway: an OPC UA server, a Notifier and one ISO-TP stack per session)
    reads the line slower than the device writes its telemetry and answers. The rest waits in
    the pty, and every answer waits behind it: 1.8 s behind with 4 gateway sessions coming and
    going, so connects timed out (docs/gateway.md "Sessions coming and going"). This reads
    what has arrived at once, with slcanBus._read's contract (one line with its terminator, or
    None) and its error (CanOperationError when the line fails)."""
    inner: Any = getattr(bus, "__wrapped__", bus)
    port = getattr(inner, "serialPortOrig", None)
    fd = getattr(port, "fd", None)
    if not isinstance(fd, int):
        return  # not a POSIX serial port (a pyserial URL): python-can's reader stays
    buffer: bytearray = inner._buffer

    def read(timeout: float | None) -> str | None:
        deadline = None if timeout is None else time.monotonic() + timeout
        with can.exceptions.error_check("Could not read from serial device"):
            while True:
                line = _take_line(buffer)
                if line is not None:
                    return line
                left = None if deadline is None else max(0.0, deadline - time.monotonic())
                ready, _, _ = select.select([fd], [], [], left)
                if not ready:
                    return None
                try:
                    chunk = os.read(fd, 4096)
                except BlockingIOError:
                    continue
                if not chunk:
                    raise OSError("the line reports data but returned none: the device is gone")
                buffer.extend(chunk)

    inner._read = read


def _read_lines_in_chunks(bus: can.BusABC, sock: socket.socket) -> None:
    """Adapt python-can's slcan bus on the broker's socket.

    It reads one byte per call (two system calls and a select each: some 10 % of a core for
    the telemetry alone); this reads what has arrived at once, with the same contract as
    slcanBus._read (one line with its terminator, or None). And when the session serving
    the link stops, the bus goes quiet instead of raising in python-can's and can-isotp's
    threads (tracebacks no user should see): reads time out, writes go nowhere, one warning
    says why, and the next request ends in a clean time-out error."""
    inner: Any = getattr(bus, "__wrapped__", bus)
    buffer: bytearray = inner._buffer
    original_write = inner._write
    closed = threading.Event()
    host, port = sock.getpeername()[:2]

    def lost(why: object) -> None:
        if not closed.is_set():
            closed.set()
            log.warning("the shared link socket://%s:%d closed (%s): the session serving it stopped; check "
                        "`landscape session status`", host, port, why)

    def read(timeout: float | None) -> str | None:
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            line = _take_line(buffer)
            if line is not None:
                return line
            left = None if deadline is None else max(0.0, deadline - time.monotonic())
            if closed.is_set():
                time.sleep(0.05 if left is None else left)
                return None
            ready, _, _ = select.select([sock], [], [], left)
            if not ready:
                return None
            try:
                chunk = sock.recv(4096)
            except BlockingIOError:
                continue
            except OSError as exc:
                lost(exc.strerror)
                continue
            if not chunk:
                lost("end of stream")
                continue
            buffer.extend(chunk)

    def write(string: str) -> None:
        if closed.is_set():
            return
        try:
            original_write(string)
        except can.CanError as exc:
            lost(exc.__cause__ or exc)

    inner._read = read
    inner._write = write


class SharedNotifier(can.Notifier):
    """A can.Notifier whose listeners may come and go while it delivers a frame.

    python-can's Notifier calls its listeners in a `for` over its list, in its own thread, while
    add_listener/remove_listener change that list in place from others. A listener removed
    before the one being called shifts the rest down by one, so the next listener misses that
    frame. Where supervisors join and leave one shared Notifier (the gateway: one per OPC UA
    session), the frame missed is another supervisor's ISO-TP flow control or consecutive
    frame, and its transfer stalls until a time-out. Here both replace the list instead (copy
    on write), so a delivery in progress keeps the list it started with."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        self._listeners_lock = threading.Lock()
        super().__init__(*args, **kwargs)

    def add_listener(self, listener: can.notifier.MessageRecipient) -> None:
        with self._listeners_lock:
            self.listeners = [*self.listeners, listener]

    def remove_listener(self, listener: can.notifier.MessageRecipient) -> None:
        """Raises ValueError when `listener` is not registered (as can.Notifier does)."""
        with self._listeners_lock:
            rest = list(self.listeners)
            rest.remove(listener)
            self.listeners = rest


_claims: dict[int, str] = {}


def release_bus(bus: can.BusABC) -> None:
    """Release the claim open_bus took on `bus`'s serial line (call after bus.shutdown())."""
    channel = _claims.pop(id(bus), None)
    if channel is not None:
        link.release(channel)


def physical_address(device: int, host: int) -> isotp.Address:
    """ISO-TP normal fixed 29-bit addressing of one supervisor <-> device pair, as seen
    from `host` (tx 0x18DA<device><host>, rx 0x18DA<host><device>)."""
    _check_node(device, "device")
    _check_node(host, "source")
    return isotp.Address(isotp.AddressingMode.NormalFixed_29bits,
                         source_address=host, target_address=device)


def functional_id(host: int) -> int:
    """CAN id of a functional (broadcast) request from `host`: 0x18DBFF<host>."""
    _check_node(host, "source")
    return FUNCTIONAL_BASE | FUNCTIONAL_ALL << 8 | host


def _check_node(addr: int, what: str) -> None:
    if not 0 <= addr <= 0xFF:
        raise BusError(f"{what} address {addr:#x} is not a node address (0x00..0xFF)")
