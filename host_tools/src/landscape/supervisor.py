"""The supervisor: one session with one device over ISO-TP.

A Supervisor owns one ISO-TP stack (normal fixed 29-bit addressing) on a bus
that it may share with other supervisors and controllers through one
python-can Notifier. Opening it connects (version and schema check) and starts
the heartbeat; closing it disconnects and stops every thread it started.

Threads: the ISO-TP stack's own two; a receiver that decodes Downlinks and
hands responses to the waiting request; a dispatcher that runs notice
callbacks and RSVP handlers (so a handler may itself call ``request``); the
heartbeat sender. Telemetry callbacks run in the Notifier's thread.
"""
from __future__ import annotations

import collections
import errno
import logging
import queue
import secrets
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import Any, Unpack

import can
import isotp
from google.protobuf import message_factory
from google.protobuf.message import DecodeError, Message

from . import auth
from . import telemetry as tm
from ._generated import landscape_pb2 as pb
from .bus import (
    ADDRESS_LISTEN_S,
    ADDRESS_TRIES,
    DEFAULT_DEVICE,
    DEFAULT_HEARTBEAT_PERIOD_MS,
    DEFAULT_HOST,
    HOST_POOL,
    ISOTP_PARAMS,
    MAX_MESSAGE_BYTES,
    BusSpec,
    SharedNotifier,
    functional_id,
    open_bus,
    physical_address,
    release_bus,
)
from .commands import Commands
from .description import DeviceDescription
from .downlink_scan import response_seq, undecodable_reason
from .errors import (
    AddressInUseError,
    AlarmError,
    ArgumentError,
    BusError,
    ControllerTimeoutError,
    LandscapeError,
    LinkLostError,
    ProtocolError,
    SeqConflictError,
    SignatureError,
    VersionMismatchError,
    error_for_code,
)
from .limits import max_string_bytes
from .registry import PROTOCOL_VERSION, SCHEMA_HASH, Command, build_request, lookup, message_to_dict
from .retval import CallOptions as CallOptions
from .retval import Enum as Enum
from .retval import RetVal as RetVal

log = logging.getLogger("landscape")


class _ToDebug(logging.Filter):
    """Lower a record to DEBUG: it reaches -vv's handler, not the last-resort one on the terminal."""

    def filter(self, record: logging.LogRecord) -> bool:
        if record.levelno > logging.DEBUG:
            record.msg = f"{record.levelname.lower()}: {record.msg}"
            record.levelno, record.levelname = logging.DEBUG, "DEBUG"
        return True


def quiet_isotp() -> None:
    """can-isotp warns on its own logger of what the supervisor already handles and logs at debug
    (_isotp_error: a FlowControl that never came while no controller answers, another supervisor's
    FlowControl on a shared bus): with no handler configured Python prints such warnings on stderr,
    before the one line that says what went wrong. Its warnings go to debug (-vv shows them)."""
    logger = logging.getLogger(isotp.TransportLayer.LOGGER_NAME)
    if not any(isinstance(f, _ToDebug) for f in logger.filters):
        logger.addFilter(_ToDebug())

RSVP_KINDS = (pb.EVENT_RSVP, pb.ALARM_RSVP)
ALARM_KINDS = (pb.ALARM, pb.ALARM_RSVP)


RsvpAnswer = int | tuple[int, Sequence[str]] | pb.RsvpReply | None
RsvpHandler = Callable[[pb.Notice], RsvpAnswer]
NoticeCallback = Callable[[pb.Notice], None]
TelemetryCallback = Callable[[tm.Broadcast], None]


def notice_data(notice: pb.Notice) -> dict[str, str]:
    """The notice's "key=value" strings as a dict (a bare word maps to "")."""
    out: dict[str, str] = {}
    for item in notice.data:
        key, _, value = item.partition("=")
        out[key] = value
    return out


def mismatch_message(host_version: int, host_hash: int, device_version: int, device_hash: int) -> str:
    """What to update when host and device disagree (pure, for tests and docs)."""
    if host_version < device_version:
        return (f"the device speaks protocol version {device_version}, this host tool {host_version}: "
                f"update the host tool (install the landscape package built from the firmware's tree)")
    if host_version > device_version:
        return (f"the device speaks protocol version {device_version}, this host tool {host_version}: "
                f"update the firmware (flash landscaped built from this tool's tree)")
    return (f"host and firmware were built from different schemas (host {host_hash:08X}, device "
            f"{device_hash:08X}): install the host tool built from the firmware's tree")


#: errno values of a write that means the line is gone (a pty whose other end closed, an
#: unplugged adapter), not a passing congestion.
_GONE_ERRNOS = frozenset({errno.EIO, errno.EBADF, errno.ENXIO, errno.ENODEV, errno.EPIPE})


def _line_gone(exc: BaseException) -> bool:
    """Whether a send error says the line itself is gone."""
    cause: BaseException | None = exc
    while cause is not None:
        if isinstance(cause, OSError) and cause.errno in _GONE_ERRNOS:
            return True
        cause = cause.__cause__ or cause.__context__
    return False


class _LinkWatch(can.Listener):
    """The supervisor's listener on the Notifier: frames go to _on_frame; a read error (the
    line closed) marks the link lost instead of ending the Notifier's thread with a traceback."""

    def __init__(self, sup: Supervisor) -> None:
        self.sup = sup

    def on_message_received(self, msg: can.Message) -> None:
        self.sup._on_frame(msg)

    def on_error(self, exc: Exception) -> None:
        self.sup._link_failed(f"the link closed ({exc.__cause__ or exc})")
        time.sleep(0.05)  # the Notifier calls recv again at once: do not spin on a dead line


class Supervisor(Commands):
    """One session with the device at `device`, speaking from node `source_address`.

    `source_address` None (the default): open() picks a free address of the hosts' pool
    (0xF1..0xFE): it listens for other supervisors' heartbeats for ADDRESS_LISTEN_S, takes the
    lowest address not heard, and moves on to the next when the device refuses the connect
    because another client holds that address (docs/protocol.md "Addresses"). A number pins
    the address. Either way the session is this object's: it sends a random `nonce` with every
    connect and the device's heartbeat token with every heartbeat ("Identity").

    Use as a context manager::

        with Supervisor(bus) as sup:
            sup.lock(); sup.activate()
            sup.wait_complete(sup.move_absolute("p1", [0, 0, 0, 0, 0, 0]), timeout_s=10)

    `notifier`: share one can.Notifier between every stack and listener on the
    bus; when None the supervisor creates one and stops it on close.

    `description`: the description of this same device that another supervisor read during
    this run of it (the gateway's observer, for each OPC UA session's supervisor): the first
    connect takes it instead of reading the device's largest answer (about 140 frames) again.
    A later connect (after a dropped session; the device may have restarted) reads its own.

    `key`: a key of the device's key file (``auth.load_key``): every connect is then a signed
    one (a challenge first) and every message of the session both ways carries a MAC; a
    downlink that does not verify is dropped and counted in `auth_refused` (docs/protocol.md
    "Security"). None: an unsigned session, which a device of policy signed refuses.
    """

    def __init__(self, bus: can.BusABC, *, device: int = DEFAULT_DEVICE,
                 source_address: int | None = None, notifier: can.Notifier | None = None,
                 client_name: str = "landscape", heartbeat_period_ms: int = DEFAULT_HEARTBEAT_PERIOD_MS,
                 retries: int = 2, timeout_s: float | None = None, channel_name: str | None = None,
                 owns_bus: bool = False, disconnect_action: Enum | None = None,
                 description: DeviceDescription | None = None, key: auth.SupervisorKey | None = None) -> None:
        if retries < 0:
            raise ArgumentError("retries must be >= 0")
        if heartbeat_period_ms <= 0:
            raise ArgumentError("heartbeat_period_ms must be > 0")
        name_max = max_string_bytes("ConnectReq", "client_name")
        if name_max is not None and len(client_name.encode("utf-8")) > name_max:
            raise ArgumentError(f"client_name is {len(client_name.encode('utf-8'))} bytes of UTF-8; the device "
                                f"holds at most {name_max}: shorten it")
        self.bus = bus
        self.device = device
        #: True when the caller chose the address; else open() picks a free one.
        self.address_pinned = source_address is not None
        self.source_address = source_address if source_address is not None else DEFAULT_HOST
        #: Who this supervisor is to the device: drawn once, sent with every connect (a
        #: reconnect of this object is the same client, another object is another client).
        self.nonce = secrets.randbits(64)
        self._hb_token = 0  # ConnectRes.heartbeat_token of the current session
        self.key = key
        # A signed session (docs/protocol.md "Security"): what signs the uplinks and what the
        # downlinks must verify with. "none": unsigned; "challenge": the challenge's answer is
        # checked by _challenge; "connect": the session key of the connect under way;
        # "session": the session's key and epoch.
        self._auth_mode = "none"
        self._ks: bytes | None = None
        self._epoch = 0
        self._hb_full = 0           # a signed session's heartbeat counter
        self._last_notice_seq = 0   # a signed session's freshness of notices and acks
        self._challenge_signer: tuple[bytes, int] | None = None  # (K_s, epoch) a challenge is signed in
        #: Downlinks that did not verify in a signed session (forged, or another key's).
        self.auth_refused = 0
        self._given_description = description  # for the first connect only
        self._heard: dict[int, float] = {}  # supervisor address -> when its heartbeat was last heard
        self.client_name = client_name
        self.heartbeat_period_ms = heartbeat_period_ms
        # None: the device's configured disconnect handler; else narrow it (docs/protocol.md)
        self.disconnect_action = disconnect_action
        self.retries = retries
        self.timeout_s = timeout_s
        self.channel_name = channel_name or str(getattr(bus, "channel_info", "") or "the bus")
        self._address = physical_address(device, self.source_address)
        self._notifier = notifier
        self._owns_notifier = notifier is None
        self._owns_bus = owns_bus

        self._cv = threading.Condition()
        self._req_lock = threading.Lock()
        self._seq = 0
        self._pending_seq: int | None = None
        self._pending_resp: pb.Response | None = None
        self._pending_bad: str | None = None  # why the answer to _pending_seq did not decode
        self._pending_raw = b""               # the bytes of _pending_resp (a challenge's answer is checked)
        self._pending_raw_last = b""          # the same, of the answer _transact returned last
        self._pending_unsigned: pb.Response | None = None  # an unsigned refusal, taken if nothing signed comes
        # final notices by (session epoch, ref_seq): a late notice of an earlier session
        # never ends a request of this one that reused its seq
        self._finals: collections.OrderedDict[tuple[int, int], pb.Notice] = collections.OrderedDict()
        # the device's RsvpAck to each of our replies, by rsvp_id
        self._acks: collections.OrderedDict[int, pb.RsvpAck] = collections.OrderedDict()
        self._hist: collections.deque[pb.Notice] = collections.deque(maxlen=1024)
        self._hist_base = 0          # index of _hist[0] among every notice received
        self._read_cursor = 0        # next index notices() yields
        self._mark = 0               # index when the last request was sent

        self._notice_cbs: list[NoticeCallback] = []
        self._rsvp_handlers: dict[str | None, RsvpHandler] = {}
        self._telemetry_cbs: list[TelemetryCallback] = []
        self._telemetry: dict[str, tm.Broadcast] = {}
        self._tm_lock = threading.Lock()
        self.device_last_seen: float | None = None
        self._device_heard: float | None = None  # time.monotonic() of the device's last HEARTBEAT
        self._lost: str | None = None            # why the link is gone (LinkLostError), None while it lives
        self._watch: _LinkWatch | None = None
        self.protocol_errors = 0

        self._stack: isotp.NotifierBasedCanStack | None = None
        self._threads: list[threading.Thread] = []
        self._stop = threading.Event()
        self._hb_stop = threading.Event()
        self._hb_thread: threading.Thread | None = None
        self._dispatch_q: queue.Queue[pb.Notice | None] = queue.Queue()
        self._running = False
        self._connected = False
        self.device_info: pb.ConnectRes | None = None
        self.connect_result: ConnectResult | None = None
        #: What the device published about itself (describe), read once per session at connect;
        #: every request is checked against its limits before it is sent.
        self.description: DeviceDescription | None = None

    @property
    def connected(self) -> bool:
        """Whether the session lives as far as this host knows: connected, not dropped by the
        device, and the link not lost (link_problem)."""
        return self._connected and self.link_problem() is None

    @connected.setter
    def connected(self, value: bool) -> None:
        self._connected = value

    @property
    def session_signed(self) -> bool:
        """Whether the current session is a signed one (docs/protocol.md "Security")."""
        return self._auth_mode == "session"

    # ------------------------------------------------------------ construction helpers

    @classmethod
    def open_bus(cls, spec: BusSpec | None = None, **kwargs: Any) -> Supervisor:
        """A Supervisor over a bus opened from `spec` (config/env defaults apply); it
        shuts the bus down on close. Not yet connected: use it as a context manager."""
        spec = spec or BusSpec()
        bus = open_bus(spec)
        kwargs.setdefault("channel_name", spec.describe())
        return cls(bus, owns_bus=True, **kwargs)

    def __enter__(self) -> Supervisor:
        self.open()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ------------------------------------------------------------ life cycle

    def open(self) -> ConnectResult:
        """Start the transport, connect and start the heartbeat. Raises VersionMismatchError,
        ControllerTimeoutError, BusError or CommandError; nothing is left running on failure."""
        if self._running:
            raise LandscapeError("this Supervisor is already open")
        try:
            self._start_transport()
            if self.address_pinned:
                return self.connect()
            return self._connect_from_a_free_address()
        except BaseException:
            self.close()
            raise

    def _connect_from_a_free_address(self) -> ConnectResult:
        """Listen for other supervisors, then connect from the lowest address of the pool nobody
        uses; on a refusal "in use by another client" try the next (ADDRESS_TRIES in all)."""
        start = time.monotonic()
        self._stop.wait(ADDRESS_LISTEN_S)
        with self._tm_lock:
            taken = {a for a, t in self._heard.items() if t >= start - ADDRESS_LISTEN_S}
        refused: list[str] = []
        for addr in [a for a in HOST_POOL if a not in taken][:ADDRESS_TRIES]:
            self._use_address(addr)
            try:
                return self.connect()
            except AddressInUseError as exc:
                log.info("source address %#04x is in use (%s); trying the next", addr, exc.ret_msg)
                refused.append(f"{addr:#04x}")
        heard = ", ".join(f"{a:#04x}" for a in sorted(taken)) or "none"
        raise AddressInUseError(
            "connect", pb.CMD_NOT_OWNER_ERR,
            f"no free supervisor address on {self.channel_name}: heard heartbeats from {heard}, the device "
            f"refused {', '.join(refused) or 'none'} as in use by other clients (pool {HOST_POOL[0]:#04x}.."
            f"{HOST_POOL[-1]:#04x}); end a supervisor you do not need, or pin a free address with "
            f"--source-address (source_address=)")

    def _use_address(self, addr: int) -> None:
        self.source_address = addr
        self._address = physical_address(self.device, addr)
        if self._stack is not None:
            self._stack.set_address(self._address)

    def _start_transport(self) -> None:
        quiet_isotp()
        if self._notifier is None:
            self._notifier = SharedNotifier(self.bus, [], timeout=0.05)
        self._stop.clear()
        self._lost = None
        self._device_heard = None
        self._stack = isotp.NotifierBasedCanStack(self.bus, self._notifier, address=self._address,
                                                  params=dict(ISOTP_PARAMS),
                                                  error_handler=self._isotp_error)
        inner_tx = self._stack.txfn

        def tx(msg: Any) -> None:  # in the stack's thread: an error there would end it with a traceback
            try:
                inner_tx(msg)
            except Exception as exc:
                self._link_failed(f"cannot send on it ({exc.__cause__ or exc})")
        self._stack.txfn = tx
        self._stack.start()
        self._watch = _LinkWatch(self)
        self._notifier.add_listener(self._watch)
        self._running = True
        for fn, name in ((self._rx_loop, "rx"), (self._dispatch_loop, "dispatch")):
            t = threading.Thread(target=fn, name=f"landscape-{name}-{self.source_address:02x}", daemon=True)
            t.start()
            self._threads.append(t)

    def connect(self) -> ConnectResult:
        """Open a session (the handshake). Called by open(); call again after a dropped session."""
        with self._req_lock:
            self._seq = 0
        with self._cv:
            self._finals.clear()
            self._acks.clear()
        signed: dict[str, Any] = {}
        # a signed session of ours that the device may still hold (a reconnect): the device takes
        # nothing unsigned from its address, so the challenge goes out signed in it
        live = (self._ks, self._epoch) if self._auth_mode == "session" and self._ks is not None else None
        self._auth_mode = "none"
        if self.key is not None:
            host_nonce = secrets.token_bytes(auth.NONCE_BYTES)
            self._ks = self._challenge(self.key, host_nonce, live)
            self._auth_mode = "connect"
            signed = {"key_id": self.key.key_id, "host_nonce": host_nonce}
        try:
            rv = self.request("connect", check=False, protocol_version=PROTOCOL_VERSION,
                              schema_hash=SCHEMA_HASH, client_nonce=self.nonce, client_name=self.client_name,
                              heartbeat_period_ms=self.heartbeat_period_ms,
                              disconnect_action=self.disconnect_action, **signed)
        except BaseException:
            self._auth_mode = "none"
            raise
        res = rv.message if isinstance(rv.message, pb.ConnectRes) else None
        if rv.ret_code < 0 or res is None:
            self._auth_mode = "none"
        if res is not None and res.client_nonce != self.nonce and rv.ret_code != pb.CMD_VERSION_MISMATCH_ERR:
            # the answer to another client's connect: another client speaks from this address
            raise AddressInUseError("connect", pb.CMD_NOT_OWNER_ERR,
                                    f"the answer on {self.source_address:#04x} accepts another client's connect "
                                    f"(its nonce is not ours): another client uses this address")
        if rv.ret_code == pb.CMD_NOT_OWNER_ERR:
            raise AddressInUseError("connect", rv.ret_code, rv.ret_msg)
        if rv.ret_code == pb.CMD_VERSION_MISMATCH_ERR:
            if res is not None and (res.protocol_version or res.schema_hash):
                raise VersionMismatchError(mismatch_message(PROTOCOL_VERSION, SCHEMA_HASH,
                                                            res.protocol_version, res.schema_hash))
            raise VersionMismatchError(
                f"the device refused the connection: {rv.ret_msg or 'protocol or schema differ'}; "
                f"this host tool speaks protocol {PROTOCOL_VERSION}, schema {SCHEMA_HASH:08X}: update "
                f"whichever side is older so both are built from one tree")
        if rv.ret_code < 0:
            raise error_for_code(rv.name, rv.ret_code, rv.ret_msg)
        if res is None:
            raise ProtocolError("connect answered without a ConnectRes: the firmware is broken or not landscaped")
        if res.protocol_version != PROTOCOL_VERSION or res.schema_hash != SCHEMA_HASH:
            self._quiet_disconnect()
            raise VersionMismatchError(mismatch_message(PROTOCOL_VERSION, SCHEMA_HASH,
                                                        res.protocol_version, res.schema_hash))
        if self.key is not None:
            if not res.session_signed:
                self._quiet_disconnect()
                raise ProtocolError("the device accepted a signed connect as an unsigned session: its firmware "
                                    "does not follow docs/protocol.md \"Security\"")
            self._epoch = res.session_epoch
            self._hb_full = 0
            self._last_notice_seq = 0
            self._auth_mode = "session"
        self.device_info = res
        self._hb_token = res.heartbeat_token
        self.connected = True
        self._start_heartbeat()
        self.description = None
        given, self._given_description = self._given_description, None
        self.description = given if given is not None else self._read_description()
        self.connect_result = ConnectResult(rv, res)
        return self.connect_result

    def _challenge(self, key: auth.SupervisorKey, host_nonce: bytes, live: tuple[bytes, int] | None) -> bytes:
        """The first half of a signed connect: the device's nonce for `key`, and the session key
        both derive from the two nonces. The device signs its answer with that key, so a device
        holding another key of that name is found out here, before the connect."""
        self._auth_mode = "challenge"
        self._challenge_signer = live
        cmd = lookup("challenge")
        req = build_request(cmd, 0, key_id=key.key_id, host_nonce=host_nonce)
        with self._req_lock:
            self._seq += 1
            req.seq = self._seq
            try:
                resp, raw = self._transact(cmd, req, None), self._pending_raw_last
            finally:
                self._challenge_signer = None
        rv = self._retval(cmd, resp)
        if rv.ret_code < 0:
            self._auth_mode = "none"
            raise error_for_code(cmd.name, rv.ret_code, rv.ret_msg)
        if not isinstance(rv.message, pb.ChallengeRes) or len(rv.message.device_nonce) != auth.NONCE_BYTES:
            self._auth_mode = "none"
            raise ProtocolError("the device answered the challenge without its nonce: is its firmware built from "
                                "this tool's tree?")
        ks = auth.session_key(key.key, host_nonce, rv.message.device_nonce, self.source_address, self.device)
        if not auth.verify(ks, auth.DOWN, self.device, self.source_address, 0, raw):
            self._auth_mode = "none"
            where = key.source or "the key given"
            raise SignatureError(
                f"the device at {self.device:#04x} does not hold this host's key {key.key_id!r} ({where}): its answer "
                f"to the challenge does not verify; the two key files differ for that name (or the answer is "
                f"forged): compare them")
        return ks

    def _read_description(self) -> DeviceDescription:
        """The device's describe answer, read once per session. It is the largest answer (about
        200 frames): on a link that loses frames it may not come through, so after two tries
        the session goes on with the limits of the host's copy of the schema (a warning says
        so) instead of failing the connect."""
        cmd = lookup("describe")
        req = build_request(cmd)
        with self._req_lock:
            self._seq += 1
            req.seq = self._seq
            try:
                resp = self._transact(cmd, req, None, tries=min(2, 1 + self.retries))
            except ControllerTimeoutError as exc:
                log.warning("the device's description did not come through (%s); checking requests against "
                            "this host tool's copy of the limits", exc)
                return DeviceDescription.host_copy()
        rv = self._retval(cmd, resp)
        if not rv.ok or not isinstance(rv.message, pb.DescribeRes):
            self._quiet_disconnect()
            raise ProtocolError(f"the device did not describe itself ({rv.ret_name}: {rv.ret_msg}): its limits "
                                f"are unknown; is the firmware built from this tool's tree?")
        return DeviceDescription(rv.message)

    def disconnect(self, **opts: Unpack[CallOptions]) -> RetVal:
        """End the session at once (an owner's disconnect runs the device's disconnect handler)."""
        try:
            rv = self.request("disconnect", **opts)
        finally:
            self.connected = False
            self._stop_heartbeat()
        return rv

    def _quiet_disconnect(self) -> None:
        try:
            self.request("disconnect", check=False, timeout_s=0.3)
        except LandscapeError:
            pass
        self.connected = False

    def close(self) -> None:
        """Disconnect (best effort) and stop everything this Supervisor started. Idempotent."""
        if self.connected and self._running:
            try:
                self.request("disconnect", check=False, timeout_s=min(self.timeout_s or 0.5, 0.5))
            except LandscapeError:
                pass
            self.connected = False
        self._stop_heartbeat()
        self._running = False
        self._stop.set()
        self._dispatch_q.put(None)
        if self._owns_notifier and self._notifier is not None:
            # first, while our listener still takes a dead line's read errors (else the
            # Notifier's thread would end on one with a traceback)
            self._notifier.stop()
        if self._notifier is not None and self._watch is not None:
            try:
                self._notifier.remove_listener(self._watch)
            except ValueError:
                pass
            self._watch = None
        if self._stack is not None:
            self._stack.stop()
            self._stack = None
        for t in self._threads:
            if t is not threading.current_thread():
                t.join(2.0)
        self._threads.clear()
        with self._cv:
            self._cv.notify_all()
        if self._owns_notifier:
            self._notifier = None
        if self._owns_bus:
            try:
                self.bus.shutdown()
            except (can.CanError, OSError) as exc:  # a line that is gone cannot be closed cleanly
                log.debug("closing %s: %s", self.channel_name, exc)
            release_bus(self.bus)
            self._owns_bus = False

    # ------------------------------------------------------------ liveness of the link and the device

    def _link_failed(self, why: str) -> None:
        """The transport's threads report a dead line here (never raise there)."""
        with self._cv:
            if self._lost is None:
                self._lost = why
                log.debug("link %s lost: %s", self.channel_name, why)
            self._cv.notify_all()

    def device_silence_limit_s(self) -> float | None:
        """How long the device may stay silent before it counts as gone: twice the session's
        heartbeat time-out (after which the device itself would drop us); None before connect."""
        info = self.device_info
        if info is None or not info.heartbeat_timeout_ms:
            return None
        return 2.0 * info.heartbeat_timeout_ms / 1000.0

    def link_problem(self) -> str | None:
        """Why the device is gone (the link closed, a send failed, its HEARTBEAT stopped for
        longer than device_silence_limit_s()), or None while it lives. A device whose heartbeat
        was never seen is not judged by it."""
        if self._lost is not None:
            return self._lost
        limit = self.device_silence_limit_s()
        heard = self._device_heard
        if self._connected and limit is not None and heard is not None:
            silent = time.monotonic() - heard
            if silent > limit:
                return f"no heartbeat from it for {silent:.1f} s"
        return None

    def check_link(self) -> None:
        """Raise LinkLostError when link_problem() names one (for loops that only wait)."""
        why = self.link_problem()
        if why is not None:
            raise self._link_lost_error(why)

    def _link_lost_error(self, why: str) -> LinkLostError:
        return LinkLostError(f"landscaped at {self.device:#04x} on {self.channel_name} stopped answering: {why}: "
                             f"is it still running? Start it again, then rerun the command")

    # ------------------------------------------------------------ heartbeat

    def _start_heartbeat(self) -> None:
        if self._hb_thread is not None:
            return
        self._hb_stop.clear()
        self._hb_thread = threading.Thread(target=self._hb_loop, daemon=True,
                                           name=f"landscape-hb-{self.source_address:02x}")
        self._hb_thread.start()

    def _stop_heartbeat(self) -> None:
        self._hb_stop.set()
        if self._hb_thread is not None and self._hb_thread is not threading.current_thread():
            self._hb_thread.join(2.0)
        self._hb_thread = None

    def _hb_loop(self) -> None:
        period = self.heartbeat_period_ms / 1000.0
        counter = 0
        next_t = time.monotonic()
        reported = False
        while not self._hb_stop.is_set():
            token = self._hb_token
            ks = self._ks if self._auth_mode == "session" else None
            if ks is not None:
                # a signed session: the MAC of a counter newer than the last (docs/protocol.md "Security")
                self._hb_full += 1
                counter = self._hb_full & 0xFF
                token = auth.heartbeat_mac(ks, self.source_address, self._epoch, self._hb_full,
                                           self.heartbeat_period_ms)
            try:
                self.bus.send(tm.encode("HEARTBEAT", self.source_address, hb_role=1, hb_counter=counter,
                                        hb_period_ms=self.heartbeat_period_ms, hb_token=token))
                reported = False
            except Exception as exc:  # keep beating: a transient bus error must not end the session
                if _line_gone(exc):
                    self._link_failed(f"cannot send on it ({exc.__cause__ or exc})")
                elif not reported and self._lost is None:
                    log.warning("heartbeat: cannot send on %s: %s", self.channel_name, exc)
                    reported = True
            counter = (counter + 1) & 0xFF
            next_t += period
            delay = next_t - time.monotonic()
            if delay < 0:
                next_t = time.monotonic()
                delay = 0
            self._hb_stop.wait(delay)

    # ------------------------------------------------------------ requests

    @staticmethod
    def build_request(command: str | Command, seq: int = 0, **fields: Any) -> pb.Request:
        """The ls.Request for `command` (pure; see registry.build_request)."""
        return build_request(command, seq, **fields)

    def request(self, command: str | Command, /, *, check: bool = True, timeout_s: float | None = None,
                **fields: Any) -> RetVal:
        """Send one command and return its RetVal.

        `command`: oneof field, seed name or CLI name. On a response time-out the
        request is retransmitted with the same seq (`retries` times) before
        ControllerTimeoutError. A negative code raises its CommandError subclass
        unless check=False.
        """
        cmd = command if isinstance(command, Command) else lookup(command)
        req = build_request(cmd, 0, **fields)
        if self.description is not None:
            self.description.check_request(req)
        if not self._running:
            raise LandscapeError("the session is not open: use `with Supervisor(bus) as sup:`")
        if cmd.field != "connect" and cmd.field != "disconnect" and not self._connected:
            raise LandscapeError("not connected: call connect() first (or use the Supervisor as a context manager)")
        rv = self._send_with_new_seq(cmd, req, timeout_s)
        if rv.ret_code == pb.CMD_SEQ_CONFLICT_ERR and cmd.field != "connect":
            # Nothing ran: the device ran another request with this seq, which this host did not
            # send (another client on this address, or a forged frame). Once with a fresh seq.
            first = rv.seq
            log.warning("%s: the device ran another request with seq %d (%s); sending it again with a fresh seq",
                        cmd.name, first, rv.ret_msg)
            rv = self._send_with_new_seq(cmd, req, timeout_s)
            if rv.ret_code == pb.CMD_SEQ_CONFLICT_ERR and check:
                raise SeqConflictError(
                    cmd.name, rv.ret_code,
                    f"{rv.ret_msg}; seq {first} was taken too: another client speaks from {self.source_address:#04x}, "
                    f"or frames are forged on the bus: pin another --source-address, or sign the session "
                    f"(docs/protocol.md \"Security\")")
        if rv.ret_code == pb.CMD_NOT_CONNECTED_ERR and cmd.field not in ("connect", "disconnect") and self._connected:
            # The device has no session of ours: it says why (its heartbeats stopped reaching it,
            # or a disconnect came from this address). Every front end connects again on its next
            # request when `connected` is False (session daemon, CLI, gateway).
            log.warning("the device at %#04x ended this session of %#04x: %s; the next request connects again",
                        self.device, self.source_address, rv.ret_msg)
            self.connected = False
        if check and rv.ret_code < 0:
            raise error_for_code(cmd.name, rv.ret_code, rv.ret_msg)
        return rv

    def _send_with_new_seq(self, cmd: Command, req: pb.Request, timeout_s: float | None) -> RetVal:
        with self._req_lock:
            self._seq = self._seq + 1 if self._seq < 0xFFFFFFFF else 1
            req.seq = self._seq
            resp = self._transact(cmd, req, timeout_s)
        return self._retval(cmd, resp)

    def _sign(self, body: bytes) -> bytes:
        """An uplink as it goes out: with its MAC field in a signed session or connect."""
        ks = self._ks
        if self._auth_mode == "session" and ks is not None:
            return auth.sign(ks, auth.UP, self.source_address, self.device, self._epoch, body)
        if self._auth_mode == "connect" and ks is not None:
            return auth.sign(ks, auth.UP, self.source_address, self.device, 0, body)
        live = self._challenge_signer
        if self._auth_mode == "challenge" and live is not None:
            return auth.sign(live[0], auth.UP, self.source_address, self.device, live[1], body)
        return body

    def _transact(self, cmd: Command, req: pb.Request, timeout_s: float | None,
                  tries: int | None = None) -> pb.Response:
        data = self._sign(pb.Uplink(request=req).SerializeToString())
        if len(data) > MAX_MESSAGE_BYTES:
            raise ArgumentError(f"{cmd.name}: the request is {len(data)} bytes, more than one ISO-TP "
                                f"message holds ({MAX_MESSAGE_BYTES}); split it (e.g. several path-load calls)")
        per_try = timeout_s if timeout_s is not None else (
            self.timeout_s if self.timeout_s is not None else cmd.host_timeout_ms / 1000.0)
        tries = 1 + self.retries if tries is None else tries
        with self._cv:
            self._pending_seq = req.seq
            self._pending_resp = None
            self._pending_bad = None
            self._pending_unsigned = None
            self._mark = self._hist_base + len(self._hist)
        try:
            for attempt in range(tries):
                if attempt:
                    log.info("%s: no answer to seq %d, retransmitting", cmd.name, req.seq)
                self.check_link()
                self._send(data)
                deadline = time.monotonic() + per_try
                with self._cv:
                    while self._pending_resp is None and self._pending_bad is None and self._running:
                        left = deadline - time.monotonic()
                        if left <= 0:
                            break
                        if self.link_problem() is not None:
                            break
                        self._cv.wait(min(left, 0.2))
                    if self._pending_resp is None and self._pending_bad is None:
                        self.check_link()
                    if self._pending_resp is None and self._pending_unsigned is not None:
                        # nothing signed came: the device's unsigned word that it has no session
                        # of ours (it cannot sign for a session it no longer has)
                        self._pending_resp = self._pending_unsigned
                    if self._pending_resp is not None:
                        self._pending_raw_last = self._pending_raw
                        return self._pending_resp
                    if self._pending_bad is not None:
                        raise ProtocolError(f"{cmd.name} (seq {req.seq}): the controller answered, but its "
                                            f"answer does not decode: {self._pending_bad}")
                    if not self._running:
                        raise LandscapeError("the session was closed while waiting for an answer")
        finally:
            with self._cv:
                self._pending_seq = None
                self._pending_resp = None
                self._pending_bad = None
                self._pending_unsigned = None
        raise ControllerTimeoutError(
            f"no answer from the controller at address {self.device:#04x} on {self.channel_name} to "
            f"{cmd.name} (seq {req.seq}, {tries} tries of {per_try:g} s): is landscaped running on that "
            f"channel with node address {self.device:#04x}?")

    def _send(self, data: bytes) -> None:
        stack = self._stack
        if stack is None:
            raise LandscapeError("the session is not open")
        try:
            stack.send(data)
        except (RuntimeError, ValueError) as exc:
            raise BusError(f"cannot send on {self.channel_name}: {exc}") from None

    def _retval(self, cmd: Command, resp: pb.Response) -> RetVal:
        which = resp.WhichOneof("result")
        msg: Message | None = None
        if which is not None:
            if which != cmd.field:
                raise ProtocolError(f"{cmd.name}: the device answered a '{which}' result; host tool and "
                                    f"firmware disagree on the schema")
            msg = getattr(resp, which)
        elif resp.ret_code >= 0:
            msg = message_factory.GetMessageClass(cmd.response_type)()
        result = message_to_dict(msg) if msg is not None else {}
        return RetVal(cmd, resp.seq, resp.ret_code, resp.ret_msg, msg, result, resp.session_epoch)

    def stop_all(self) -> None:
        """Ask every device on the bus to stopMotion: one functional ISO-TP single frame
        to 0x18DBFF<source>. Each device answers physically (its Response is not awaited:
        a device where nothing moves answers CMD_WRONG_STATE_ERR, which is fine).

        The request must fit one single frame (7 bytes), so its seq is 1..127: the next
        seq while that is small, else a small value that differs from the seqs around it
        (the device only compares a seq with the previous one, to spot retransmissions)."""
        if not self._running:
            raise LandscapeError("the session is not open: use `with Supervisor(bus) as sup:`")
        with self._req_lock:
            self._seq = self._seq + 1 if self._seq < 0xFFFFFFFF else 1
            seq = self._seq if self._seq < 128 else 1 + self._seq % 127
            payload = pb.Uplink(request=pb.Request(seq=seq, stop_motion=pb.StopMotionReq())).SerializeToString()
            frame = bytes([len(payload)]) + payload + b"\xcc" * (7 - len(payload))
            try:
                self.bus.send(can.Message(arbitration_id=functional_id(self.source_address),
                                          is_extended_id=True, data=frame))
            except can.CanError as exc:
                raise BusError(f"cannot send stop-all on {self.channel_name}: {exc}") from None

    def send_rsvp_reply(self, rsvp_id: int, ret_code: int = pb.CMD_EXEC_OK, data: Sequence[str] = ()) -> None:
        """Send an RsvpReply without waiting: the device's RsvpAck arrives later
        (wait_rsvp_ack). ret_code >= 0 accepts, < 0 declines (docs/protocol.md "RSVP")."""
        reply = pb.RsvpReply(rsvp_id=rsvp_id, ret_code=ret_code, data=list(data))
        with self._cv:
            self._acks.pop(rsvp_id, None)  # a new answer: wait for its own acknowledgement
        self._send(self._sign(pb.Uplink(rsvp_reply=reply).SerializeToString()))

    def answer_rsvp(self, rsvp: int | pb.Notice, ret_code: int = pb.CMD_EXEC_OK, data: Sequence[str] = (), *,
                    timeout_s: float = 1.0, check: bool = True) -> pb.RsvpAck:
        """Answer an RSVP notice (or its rsvp_id) and return the device's RsvpAck, whose
        `action` says what the device did. ret_code >= 0 accepts, < 0 declines; `data` goes
        to the device's event log (sendCommand events). A refused reply (late, unknown or
        already answered) raises its CommandError unless check=False."""
        rsvp_id = rsvp.rsvp_id if isinstance(rsvp, pb.Notice) else int(rsvp)
        if isinstance(rsvp, pb.Notice) and rsvp.kind not in RSVP_KINDS:
            raise ArgumentError(f"notice {rsvp.event_id} is not an RSVP (kind {pb.NoticeKind.Name(rsvp.kind)}): "
                                f"only EVENT_RSVP and ALARM_RSVP notices take an answer")
        self.send_rsvp_reply(rsvp_id, ret_code, data)
        ack = self.wait_rsvp_ack(rsvp_id, timeout_s)
        if check and ack.ret_code < 0:
            raise error_for_code(f"rsvp {rsvp_id}", ack.ret_code, ack.ret_msg)
        return ack

    def accept_rsvp(self, rsvp: int | pb.Notice, data: Sequence[str] = (), **kw: Any) -> pb.RsvpAck:
        """answer_rsvp with CMD_EXEC_OK."""
        return self.answer_rsvp(rsvp, pb.CMD_EXEC_OK, data, **kw)

    def decline_rsvp(self, rsvp: int | pb.Notice, data: Sequence[str] = (), *, ret_code: int = pb.CMD_ERR,
                     **kw: Any) -> pb.RsvpAck:
        """answer_rsvp with a negative code (CMD_ERR unless told)."""
        if ret_code >= 0:
            raise ArgumentError(f"decline_rsvp: ret_code {ret_code} accepts; a decline is negative")
        return self.answer_rsvp(rsvp, ret_code, data, **kw)

    def wait_rsvp_ack(self, rsvp_id: int, timeout_s: float = 1.0) -> pb.RsvpAck:
        """The device's RsvpAck to our reply to `rsvp_id`; ControllerTimeoutError after timeout_s."""
        deadline = time.monotonic() + timeout_s
        with self._cv:
            while rsvp_id not in self._acks:
                if not self._running:
                    raise LandscapeError("the session was closed while waiting for an RSVP acknowledgement")
                self.check_link()
                left = deadline - time.monotonic()
                if left <= 0:
                    raise ControllerTimeoutError(
                        f"no acknowledgement of the reply to rsvp {rsvp_id} within {timeout_s:g} s: is the "
                        f"controller at {self.device:#04x} still running?")
                self._cv.wait(min(left, 0.2))
            return self._acks[rsvp_id]

    # ------------------------------------------------------------ receiving

    def _isotp_error(self, error: Exception) -> None:
        log.debug("isotp %02x: %s", self.source_address, error)

    def _rx_loop(self) -> None:
        while not self._stop.is_set():
            stack = self._stack
            if stack is None:
                return
            data = stack.recv(block=True, timeout=0.05)
            if data is None:
                continue
            try:
                self._on_downlink(bytes(data))
            except Exception:  # a bad message must never kill the receiver
                log.exception("landscape: dropping a downlink message")

    def _on_downlink(self, data: bytes) -> None:
        dl = pb.Downlink()
        try:
            dl.ParseFromString(data)
        except DecodeError as exc:
            if self._auth_mode == "session" and self._ks is not None and not auth.verify(
                    self._ks, auth.DOWN, self.device, self.source_address, self._epoch, data):
                self.auth_refused += 1  # not the device's: nothing to fail a request for
                return
            self.protocol_errors += 1
            what = undecodable_reason(data, exc)
            seq = response_seq(data)
            with self._cv:
                if seq is not None and seq == self._pending_seq and self._pending_resp is None:
                    # the request waiting for it fails now, naming why, instead of timing out
                    self._pending_bad = what
                    self._cv.notify_all()
                    return
            log.warning("undecodable message from %#04x (%d bytes): %s", self.device, len(data), what)
            return
        which = dl.WhichOneof("msg")
        if which == "response":
            with self._cv:
                if self._pending_seq is not None and dl.response.seq == self._pending_seq \
                        and self._pending_resp is None:
                    if self._response_verifies(data, dl.response):
                        self._pending_resp = dl.response
                        self._pending_raw = data
                        self._cv.notify_all()
                    elif not auth.has_mac(data) and (
                            dl.response.ret_code == pb.CMD_NOT_CONNECTED_ERR
                            or (self._auth_mode == "connect" and dl.response.ret_code < 0)):
                        # unsigned, so anyone's: taken only when nothing signed comes (_transact);
                        # a refused connect carries no state to protect
                        self._pending_unsigned = dl.response
                        if self._auth_mode == "connect":
                            self._pending_resp = dl.response
                            self._pending_raw = data
                            self._cv.notify_all()
                    else:
                        self.auth_refused += 1
            return
        if self._auth_mode == "session" and not self._fresh_and_signed(data, dl):
            self.auth_refused += 1
            return
        if which == "notice":
            n = dl.notice
            with self._cv:
                if len(self._hist) == self._hist.maxlen:
                    self._hist_base += 1  # the deque drops its oldest notice
                self._hist.append(n)
                if n.final and n.ref_seq:
                    self._finals[(n.session_epoch, n.ref_seq)] = n
                    while len(self._finals) > 256:
                        self._finals.popitem(last=False)
                self._cv.notify_all()
            self._dispatch_q.put(n)
            return
        if which == "rsvp_ack":
            ack = dl.rsvp_ack
            if ack.ret_code < 0:
                log.warning("the device refused the reply to rsvp %d: %s", ack.rsvp_id, ack.ret_msg)
            with self._cv:
                self._acks[ack.rsvp_id] = ack
                while len(self._acks) > 256:
                    self._acks.popitem(last=False)
                self._cv.notify_all()
            return
        self.protocol_errors += 1

    def _response_verifies(self, data: bytes, res: pb.Response) -> bool:
        """Whether an answer to the pending request carries the MAC it must (always, outside a
        signed session; the challenge's answer is checked by _challenge)."""
        ks = self._ks
        if self._auth_mode in ("none", "challenge") or ks is None:
            return True
        epoch = res.session_epoch if self._auth_mode == "connect" else self._epoch
        return auth.verify(ks, auth.DOWN, self.device, self.source_address, epoch, data)

    def _fresh_and_signed(self, data: bytes, dl: pb.Downlink) -> bool:
        """A notice or an RsvpAck of a signed session: its MAC verifies and its notice_seq is newer
        than the last one taken (a replayed one is not)."""
        ks = self._ks
        if ks is None or not auth.verify(ks, auth.DOWN, self.device, self.source_address, self._epoch, data):
            return False
        seq = dl.notice.notice_seq if dl.WhichOneof("msg") == "notice" else dl.rsvp_ack.notice_seq
        with self._cv:
            if seq <= self._last_notice_seq:
                return False
            self._last_notice_seq = seq
        return True

    @property
    def _hist_end(self) -> int:
        return self._hist_base + len(self._hist)

    def _dispatch_loop(self) -> None:
        while True:
            n = self._dispatch_q.get()
            if n is None:
                return
            for cb in list(self._notice_cbs):
                try:
                    cb(n)
                except Exception:
                    log.exception("notice callback %r failed", cb)
            if n.kind in RSVP_KINDS:
                self._answer_rsvp(n)

    def _answer_rsvp(self, n: pb.Notice) -> None:
        handler = self._rsvp_handlers.get(n.event_id) or self._rsvp_handlers.get(None)
        if handler is None:
            return  # the device takes rsvp_default after rsvp_timeout_ms
        code: int
        data: list[str]
        try:
            ans = handler(n)
            if ans is None:
                code, data = int(pb.CMD_EXEC_OK), []
            elif isinstance(ans, pb.RsvpReply):
                code, data = ans.ret_code, list(ans.data)
            elif isinstance(ans, tuple):
                code, data = int(ans[0]), list(ans[1])
            else:
                code, data = int(ans), []
        except Exception as exc:
            log.exception("RSVP handler for %s failed; answering CMD_ERR", n.event_id)
            code, data = int(pb.CMD_ERR), [f"error={exc}"]
        try:
            self.send_rsvp_reply(n.rsvp_id, code, data)
        except LandscapeError as exc:
            log.warning("cannot answer RSVP %d: %s", n.rsvp_id, exc)

    # ------------------------------------------------------------ notices

    def on_notice(self, fn: NoticeCallback) -> NoticeCallback:
        """Call fn(notice) for every event and alarm (in the dispatcher thread). Usable as a decorator."""
        self._notice_cbs.append(fn)
        return fn

    def remove_notice_callback(self, fn: NoticeCallback) -> None:
        self._notice_cbs.remove(fn)

    def on_rsvp(self, event_id: str | None, handler: RsvpHandler) -> RsvpHandler:
        """Answer RSVP notices of `event_id` (None: every RSVP without its own handler).

        handler(notice) returns None (CMD_EXEC_OK), a ret_code, (ret_code, data) or an
        RsvpReply; an exception answers CMD_ERR. Without a handler the device takes
        the notice's rsvp_default after rsvp_timeout_ms.
        """
        self._rsvp_handlers[event_id] = handler
        return handler

    def remove_rsvp_handler(self, event_id: str | None) -> None:
        """Stop answering RSVPs of `event_id` (None: the catch-all handler)."""
        self._rsvp_handlers.pop(event_id, None)

    def notices(self, timeout_s: float | None = None) -> Iterator[pb.Notice]:
        """Yield every notice not yet yielded by any notices() iterator, in arrival order,
        waiting for new ones; stops when `timeout_s` (total) has passed (None: never)."""
        deadline = None if timeout_s is None else time.monotonic() + timeout_s
        while True:
            with self._cv:
                while self._read_cursor >= self._hist_end and self._running:
                    self.check_link()
                    left = None if deadline is None else deadline - time.monotonic()
                    if left is not None and left <= 0:
                        return
                    self._cv.wait(min(left, 0.2) if left is not None else 0.2)
                if self._read_cursor >= self._hist_end:
                    return
                self._read_cursor = max(self._read_cursor, self._hist_base)
                n = self._hist[self._read_cursor - self._hist_base]
                self._read_cursor += 1
            yield n

    def wait_complete(self, retval: RetVal, timeout_s: float | None = None) -> pb.Notice:
        """Wait for the notice that ends the non-blocking command `retval` and return it.
        Raises AlarmError when it is an alarm, ControllerTimeoutError after `timeout_s`."""
        if not retval.started:
            raise LandscapeError(f"{retval.name} answered {retval.ret_name}: only a command that answered "
                                 f"CMD_STARTED_OK has a completion to wait for")
        deadline = None if timeout_s is None else time.monotonic() + timeout_s
        with self._cv:
            key = (retval.epoch, retval.seq)
            while key not in self._finals:
                if not self._running:
                    raise LandscapeError("the session was closed while waiting for a completion")
                self.check_link()
                left = None if deadline is None else deadline - time.monotonic()
                if left is not None and left <= 0:
                    raise ControllerTimeoutError(
                        f"{retval.name} (seq {retval.seq}) did not complete within {timeout_s:g} s: "
                        f"check get-motion-control-state, or stop-motion")
                self._cv.wait(min(left, 0.2) if left is not None else 0.2)
            n = self._finals[key]
        if n.kind in ALARM_KINDS:
            raise AlarmError(n, retval.name)
        return n

    def wait_for_tag(self, tag_name: str, timeout_s: float | None = None) -> pb.Notice:
        """Wait for the tag event of `tag_name` (event_id "tag", data "tag=<name>"), counting
        tag events received since the last request was sent."""
        deadline = None if timeout_s is None else time.monotonic() + timeout_s
        with self._cv:
            pos = self._mark
            while True:
                pos = max(pos, self._hist_base)
                while pos < self._hist_end:
                    n = self._hist[pos - self._hist_base]
                    pos += 1
                    if n.event_id == "tag":
                        d = notice_data(n)
                        if d.get("tag") == tag_name or d.get("tag_name") == tag_name:
                            return n
                if not self._running:
                    raise LandscapeError("the session was closed while waiting for a tag")
                self.check_link()
                left = None if deadline is None else deadline - time.monotonic()
                if left is not None and left <= 0:
                    raise ControllerTimeoutError(f"tag '{tag_name}' not reached within {timeout_s:g} s")
                self._cv.wait(min(left, 0.2) if left is not None else 0.2)

    # ------------------------------------------------------------ telemetry

    def _on_frame(self, frame: can.Message) -> None:
        b = tm.decode(frame)
        if b is None:
            return
        if b.name == "HEARTBEAT" and b.signals.get("hb_role", 0) != 0:
            with self._tm_lock:  # another supervisor's: its address is taken
                self._heard[b.sender] = time.monotonic()
            return
        if b.sender != self.device:
            return
        with self._tm_lock:
            self._telemetry[b.name] = b
            if b.name == "HEARTBEAT":
                self.device_last_seen = b.timestamp
                self._device_heard = time.monotonic()
        for cb in list(self._telemetry_cbs):
            try:
                cb(b)
            except Exception:
                log.exception("telemetry callback %r failed", cb)

    def telemetry(self) -> dict[str, dict[str, Any]]:
        """Latest decoded broadcast of the device, by DBC message name."""
        with self._tm_lock:
            return {k: dict(v.signals) for k, v in self._telemetry.items()}

    def on_telemetry(self, fn: TelemetryCallback) -> TelemetryCallback:
        """Call fn(broadcast) for every broadcast of the device (in the Notifier's thread: keep it short)."""
        self._telemetry_cbs.append(fn)
        return fn

    def remove_telemetry_callback(self, fn: TelemetryCallback) -> None:
        self._telemetry_cbs.remove(fn)

    def add_frame_listener(self, fn: Callable[[can.Message], None]) -> None:
        """Call fn(frame) for every CAN frame received, decoded or not (the Notifier's thread: keep
        it short). Frames this host sends are not among them (python-can does not echo them)."""
        if self._notifier is None:
            raise LandscapeError("the session is not open: call open() before add_frame_listener()")
        self._notifier.add_listener(fn)

    def remove_frame_listener(self, fn: Callable[[can.Message], None]) -> None:
        if self._notifier is not None:
            self._notifier.remove_listener(fn)


@dataclass
class ConnectResult:
    """The connect RetVal and the device description."""

    retval: RetVal
    device: pb.ConnectRes

    @property
    def units(self) -> tuple[str, str]:
        """The session's units as the device reports them at connect (a new session is in SI)."""
        return pb.LinearUnit.Name(self.device.linear_unit), pb.AngularUnit.Name(self.device.angular_unit)

    @property
    def disconnect_action(self) -> str:
        """What the device does if this session's owner is lost (ls.DisconnectAction name)."""
        return pb.DisconnectAction.Name(self.device.disconnect_action)
