"""`landscape gateway`: an OPC UA server (asyncua) for every controller on the bus (docs/gateway.md).

The gateway joins the CAN link as one more local client (bus.open_bus: it shares a line that a
background session serves) and listens to it with one can.Notifier. A device HEARTBEAT (hb_role 0)
from an address not seen before is a controller: it gets an object in the address space, shaped like
OPC 40010's MotionDeviceSystem (MotionDevices -> Arm -> Axes -> J1..J6 with positions and units), fed
by the telemetry broadcasts, and one method per command of the schema (registry.COMMANDS) plus
AnswerRsvp.

Each OPC UA session that calls a method on a controller gets its own Supervisor of it (an address of
the configured pool, its own heartbeat): ownership, exactly-once and the disconnect handler hold per
LAN client, and closing the session (or losing it) disconnects that supervisor. The gateway itself
holds one read-only supervisor per controller ("observer") that reads the device description and
turns the notices addressed to nobody in particular (alarms such as ownerLost) into events; the
notices of a session's own requests (completions, RSVPs) come through that session's supervisor.

A controller silent for twice its heartbeat time-out is gone: its values turn BadNoCommunication, a
controllerLost event and a log line say so, its supervisors leave; with none left the link is reopened
every RELINK_S, and its next HEARTBEAT brings it back (controllerBack, a new observer).

Threads: python-can's Notifier, each Supervisor's own. They reach the event loop only through
loop.call_soon_threadsafe; blocking Supervisor calls run in the loop's executor. One thing polls: every
OBSERVER_CHECK_S each observer asks its controller a query, since an observer sends no requests that
would find out that the device dropped its session (its heartbeats late: this process stalled); then
it connects again. A session's supervisor finds out on its next call and connects again on the one after.
"""
from __future__ import annotations

import asyncio
import contextvars
import datetime
import errno
import functools
import json
import logging
import signal
import socket
import time
from collections.abc import Callable, Coroutine, Sequence
from dataclasses import dataclass, field
from typing import Any

import can
from asyncua import ua
from asyncua.common.node import Node
from asyncua.crypto.permission_rules import SimpleRoleRuleset, User, UserRole
from asyncua.server.internal_server import InternalServer
from asyncua.server.internal_session import InternalSession, SessionState
from asyncua.server.server import Server
from asyncua.server.user_managers import UserManager
from asyncua.ua.attribute_ids import AttributeIds
from asyncua.ua.object_ids import ObjectIds
from asyncua.ua.status_codes import StatusCodes
from google.protobuf.descriptor import FieldDescriptor

from . import telemetry as tm
from ._generated import landscape_pb2 as pb
from .bus import BusSpec, SharedNotifier, open_bus, release_bus
from .errors import AddressInUseError, ArgumentError, CommandError, LandscapeError, ret_name
from .gateway_config import GatewayConfig
from .registry import COMMANDS, Command, build_request, enum_choices, field_enum_type, is_repeated, message_to_dict
from .supervisor import ALARM_KINDS, RSVP_KINDS, Supervisor, quiet_isotp

log = logging.getLogger("landscape.gateway")

NAMESPACE_URI = "urn:landscape:gateway"
ENDPOINT_PATH = "/landscape/"
JOINTS = 6
#: Every OPC UA method of a command returns these, in this order.
OUTPUTS = (("RetCode", ua.VariantType.Int32, "the device's return code (docs/protocol.md \"Return codes\")"),
           ("RetName", ua.VariantType.String, "the return code's name, e.g. CMD_STARTED_OK"),
           ("RetMsg", ua.VariantType.String, "what was wrong and what to do, when RetCode < 0"),
           ("Seq", ua.VariantType.UInt32, "the request's seq: a completion event's RefSeq names it"),
           ("SessionEpoch", ua.VariantType.UInt32, "the session epoch the device answered in"),
           ("Result", ua.VariantType.String, "the result message as JSON (schema field names)"))
#: The notice fields every LandScapeNotice event carries besides BaseEventType's.
EVENT_FIELDS: tuple[tuple[str, ua.VariantType], ...] = (
    ("Device", ua.VariantType.Byte), ("Supervisor", ua.VariantType.Byte), ("Kind", ua.VariantType.String),
    ("NoticeId", ua.VariantType.String), ("Data", ua.VariantType.String), ("RefSeq", ua.VariantType.UInt32),
    ("SessionEpoch", ua.VariantType.UInt32), ("Final", ua.VariantType.Boolean),
    ("RsvpId", ua.VariantType.UInt32), ("RsvpTimeoutMs", ua.VariantType.UInt32),
    ("RsvpDefault", ua.VariantType.String))

_VARIANT: dict[int, ua.VariantType] = {
    FieldDescriptor.TYPE_DOUBLE: ua.VariantType.Double, FieldDescriptor.TYPE_FLOAT: ua.VariantType.Double,
    FieldDescriptor.TYPE_INT32: ua.VariantType.Int32, FieldDescriptor.TYPE_SINT32: ua.VariantType.Int32,
    FieldDescriptor.TYPE_SFIXED32: ua.VariantType.Int32, FieldDescriptor.TYPE_UINT32: ua.VariantType.UInt32,
    FieldDescriptor.TYPE_FIXED32: ua.VariantType.UInt32, FieldDescriptor.TYPE_INT64: ua.VariantType.Int64,
    FieldDescriptor.TYPE_SINT64: ua.VariantType.Int64, FieldDescriptor.TYPE_SFIXED64: ua.VariantType.Int64,
    FieldDescriptor.TYPE_UINT64: ua.VariantType.UInt64, FieldDescriptor.TYPE_FIXED64: ua.VariantType.UInt64,
    FieldDescriptor.TYPE_BOOL: ua.VariantType.Boolean, FieldDescriptor.TYPE_STRING: ua.VariantType.String,
    FieldDescriptor.TYPE_BYTES: ua.VariantType.ByteString,
    FieldDescriptor.TYPE_ENUM: ua.VariantType.String,      # the value's name (or short name)
    FieldDescriptor.TYPE_MESSAGE: ua.VariantType.String,   # a JSON object with the schema's field names
}

# UNECE codes of OPC UA's EUInformation (namespace http://www.opcfoundation.org/UA/units/un/cefact)
_UNECE = "http://www.opcfoundation.org/UA/units/un/cefact"
_EU = {"rad": (ua.String("C81"), "rad", "radian"), "m": (ua.String("MTR"), "m", "metre")}


def _eu(unit: str) -> ua.EUInformation:
    code, short, long = _EU[unit]
    # UnitId: the UNECE common code packed as OPC UA Part 8 says (one byte per character)
    unit_id = 0
    for ch in str(code):
        unit_id = unit_id << 8 | ord(ch)
    return ua.EUInformation(NamespaceUri=_UNECE, UnitId=unit_id, DisplayName=ua.LocalizedText(short),
                            Description=ua.LocalizedText(long))


#: The gateway's own notices (no device sends them, so the schema has none): the controller's heartbeat
#: stopped (its values turn Bad), and it came back (Good again, calls work).
CONTROLLER_LOST = "controllerLost"
CONTROLLER_BACK = "controllerBack"
#: How long a controller may stay silent before it counts as gone, until its description gives the
#: device's own heartbeat time-out.
DEFAULT_SILENCE_S = 1.0
#: How often the gateway reopens its link while no controller beats.
RELINK_S = 1.0
#: How often the gateway asks each controller whether its observer's session still lives: a device
#: drops a supervisor whose heartbeats stop for longer than its time-out (this process stalled, the
#: bus lost them), and an observer sends no requests of its own that would find out.
OBSERVER_CHECK_S = 2.0
#: The status of a gone controller's values.
GONE = StatusCodes.BadNoCommunication
#: The variables of a controller that the telemetry feeds (Address and Description stay Good).
LIVE_VARS = ("State", "Motion", "Fault", "Owner", "Supervisors", "JointPositions", "ToolPose")


class GatewayError(LandscapeError):
    """The gateway cannot start (the port is taken, a certificate does not load)."""


#: How a non-blocking command's method answers (docs/gateway.md "Methods").
NON_BLOCKING = "non-blocking: returns CMD_STARTED_OK, then its final event or alarm (RefSeq = the call's Seq)"

class PoolExhaustedError(CommandError):
    """No address of the gateway's pool is free for a session's supervisor. Answered as the device
    answers a full supervisor table (CMD_NO_RESOURCES_ERR) although no device was asked; the message
    names the addresses held, heard and refused."""

    code = pb.CMD_NO_RESOURCES_ERR


#: A pool address whose heartbeat another supervisor sent this recently is taken: the gateway skips it.
HEARD_HOLDS_S = 1.0

# ---------------------------------------------------------------- arguments


def argument_of(fd: FieldDescriptor) -> ua.Argument:
    """The OPC UA Argument of request field `fd`: its type from the schema, an array for a repeated
    field, enum choices and JSON shape in the description."""
    arg = ua.Argument()
    arg.Name = fd.name
    arg.DataType = _nid(_VARIANT[fd.type].value)
    if is_repeated(fd):
        arg.ValueRank = 1
        arg.ArrayDimensions = [0]
    else:
        arg.ValueRank = -1
    if fd.type == FieldDescriptor.TYPE_ENUM:
        text = f"one of {enum_choices(field_enum_type(fd))} (\"\": absent)"
    elif fd.type == FieldDescriptor.TYPE_MESSAGE:
        text = f"a JSON object of {fd.message_type.name if fd.message_type else 'the message'}"
    else:
        text = fd.name
    arg.Description = ua.LocalizedText(text)
    return arg


class ArgumentShapeError(ArgumentError):
    """A method call's arguments do not have the shape of the method's InputArguments (too many, a scalar
    for an array, a String that is no JSON object): the client's program is wrong, and the call is
    BadInvalidArgument. A value of the right shape that does not fit (an enum name, a range, a length)
    is an ArgumentError, answered as the device answers it: CMD_PARAM_ERR with the reason."""


def fields_of(cmd: Command, args: Sequence[Any]) -> dict[str, Any]:
    """The request fields of `cmd` from a method call's input arguments (in schema order; missing trailing
    ones and "" for an enum stay absent). ArgumentShapeError for arguments of the wrong shape, ArgumentError
    for a value that does not fit; each names the field."""
    fds = cmd.fields()
    if len(args) > len(fds):
        raise ArgumentShapeError(f"{cmd.name} takes {len(fds)} arguments ({', '.join(f.name for f in fds) or 'none'}), "
                            f"got {len(args)}")
    out: dict[str, Any] = {}
    for fd, value in zip(fds, args, strict=False):
        if value is None or (fd.type == FieldDescriptor.TYPE_ENUM and value == ""):
            continue
        if is_repeated(fd) and not isinstance(value, (list, tuple)):
            raise ArgumentShapeError(f"{cmd.name}.{fd.name}: an array ({_VARIANT[fd.type].name}[]) is expected, got "
                                f"{type(value).__name__} {value!r}: pass one element per item")
        if fd.type == FieldDescriptor.TYPE_MESSAGE:
            items = value if is_repeated(fd) else [value]
            parsed = []
            for item in items:
                try:
                    parsed.append(json.loads(item))
                except (TypeError, json.JSONDecodeError) as exc:
                    raise ArgumentShapeError(f"{cmd.name}.{fd.name}: {item!r} is not a JSON object ({exc})") from None
            value = parsed if is_repeated(fd) else parsed[0]
        out[fd.name] = list(value) if is_repeated(fd) and not isinstance(value, list) else value
    build_request(cmd, **out)  # every value checked (enum names, numbers, ranges) before any supervisor connects
    return out


# ---------------------------------------------------------------- sessions and users


_current_session: contextvars.ContextVar[GatewaySession | None] = contextvars.ContextVar(
    "landscape_gateway_session", default=None)


class GatewaySession(InternalSession):
    """An OPC UA session that tells the gateway who calls a method and when it ends."""

    gateway: Gateway

    async def call(self, params: list[ua.CallMethodRequest]) -> list[ua.CallMethodResult]:
        token = _current_session.set(self)
        try:
            return await super().call(params)
        finally:
            _current_session.reset(token)

    async def close_session(self, delete_subs: bool = True) -> None:
        await super().close_session(delete_subs)
        await self.gateway.session_closed(self)


def _label(session: InternalSession) -> str:
    """A session as the log names it: where its client connects from and who it is
    ("127.0.0.1:60740 (alice)"; asyncua names a session by its peer address)."""
    peer = session.name
    where = f"{peer[0]}:{peer[1]}" if isinstance(peer, tuple) and len(peer) >= 2 else str(peer)
    return f"{where} ({session.user.name or session.user.role.name.lower()})"


class GatewayUsers(UserManager):
    """Anonymous (when allowed): read-only. A configured user with the right password, or a client whose
    certificate is a configured user's: may call methods. Anything else is refused."""

    def __init__(self, cfg: GatewayConfig, certificates: dict[bytes, str]) -> None:
        self.cfg = cfg
        self.certificates = certificates

    def get_user(self, iserver: InternalServer, username: str | None = None, password: str | None = None,
                 certificate: Any = None) -> User | None:
        if username is not None:
            if password is not None and self.cfg.check_password(username, password):
                return User(role=UserRole.User, name=username)
            # the name an administrator needs to see who tried; never the password
            log.warning("refused a session as user %r: unknown user or wrong password ([users] in the "
                        "gateway's configuration)", username)
            return None
        # asyncua passes the certificate of an X509 identity token, else the secure channel's peer
        # certificate (the client's application certificate; b"" on a channel without security): either
        # proves its key, so a configured user's certificate is that user.
        name = self.certificates.get(certificate) if isinstance(certificate, bytes) and certificate else None
        if name is not None:
            return User(role=UserRole.User, name=name)
        if self.cfg.allow_anonymous:
            return User(role=UserRole.Anonymous)
        log.warning("refused an anonymous session: allow_anonymous is false and %s",
                    "its certificate is no [[certificate_users]] entry's" if certificate else
                    "it gave no user name or certificate")
        return None


class _Rules(SimpleRoleRuleset):
    """asyncua's roles, with anonymous allowed what a read-only client needs on a secure channel too
    (browse, read, subscribe, call: a method refuses an anonymous caller itself, with a clear status)."""

    def __init__(self) -> None:
        super().__init__()  # type: ignore[no-untyped-call]  # asyncua leaves it untyped
        allowed = set(self._permission_dict[UserRole.User])
        allowed.discard(_nid(ObjectIds.WriteRequest_Encoding_DefaultBinary))
        self._permission_dict[UserRole.Anonymous] = allowed


# ---------------------------------------------------------------- one controller


@dataclass
class Controller:
    address: int
    obj: Node
    vars: dict[str, Node]
    axes: list[Node]
    axes_cmd: list[Node]
    observer: Supervisor | None = None
    #: None while its heartbeat comes; else why the gateway counts it as gone (its values are Bad)
    lost: str | None = None
    heard: float = 0.0                        # time.monotonic() of its last frame
    timer: asyncio.TimerHandle | None = None  # fires when its heartbeat stays away too long
    joints: list[float] = field(default_factory=lambda: [0.0] * JOINTS)
    tool: list[float] = field(default_factory=lambda: [0.0] * 6)
    events: Any = None  # asyncua EventGenerator of the controller object


class Gateway:
    """The OPC UA server and its link to the bus. `run()` serves until `stop()` (or SIGINT/SIGTERM)."""

    def __init__(self, cfg: GatewayConfig, spec: BusSpec, *, client_name: str = "landscape-gateway") -> None:
        self.cfg = cfg
        self.spec = spec
        self.client_name = client_name
        self.server = Server()
        self.ns = 0
        self.controllers: dict[int, Controller] = {}
        self._pending: set[int] = set()
        self._sups: dict[tuple[int, int], Supervisor] = {}           # (session id, device) -> supervisor
        self._sup_locks: dict[tuple[int, int], asyncio.Lock] = {}
        self._used: set[int] = set()                                   # addresses our supervisors hold
        self._heard: dict[int, float] = {}                             # other supervisors' addresses
        self._loop: asyncio.AbstractEventLoop | None = None
        self._stop = asyncio.Event()
        self._events: asyncio.Queue[tuple[int, int, pb.Notice]] = asyncio.Queue()
        self._bus: can.BusABC | None = None
        self._notifier: can.Notifier | None = None
        self._root: Node | None = None
        self._event_type: Node | None = None
        self._tasks: set[asyncio.Task[None]] = set()  # held until done (the loop keeps weak references)
        self._relinking = False
        self._closing = False
        self.channel = spec.describe()
        self.url = ""

    def _spawn(self, coro: Coroutine[Any, Any, None], what: str) -> None:
        """Run `coro` in the background; a failure is one log line, never a traceback on stderr."""
        async def guarded() -> None:
            try:
                await coro
            except asyncio.CancelledError:
                raise
            except Exception as exc:
                log.warning("%s failed: %s", what, exc)
        task = asyncio.get_running_loop().create_task(guarded())
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)
        task.add_done_callback(lambda _: coro.close())  # cancelled before it started: no "never awaited"

    # ------------------------------------------------------------ start and stop

    async def start(self) -> None:
        self._loop = asyncio.get_running_loop()
        quiet_isotp()
        certificates: dict[bytes, str] = {}
        server = self.server
        server.iserver.set_user_manager(GatewayUsers(self.cfg, certificates))
        await server.init()
        # A session whose client is gone (asyncua keeps one with subscriptions after its connection drops)
        # ends after this time-out at most, whatever the client asked for: then its supervisors leave.
        timeout_ms = self.cfg.session_timeout_s * 1000
        server.iserver.max_session_timeout_ms = timeout_ms
        server.iserver.min_session_timeout_ms = min(server.iserver.min_session_timeout_ms, timeout_ms)
        setattr(server.iserver, "create_session", self._create_session)  # noqa: B010 (our session class)
        host = f"[{self.cfg.host}]" if ":" in self.cfg.host else self.cfg.host
        self.url = f"opc.tcp://{host}:{self.cfg.port}{ENDPOINT_PATH}"
        server.set_endpoint(self.url)
        server.set_server_name("LandScape gateway")
        await server.set_application_uri("urn:landscape:gateway:server")
        policies = [ua.SecurityPolicyType.NoSecurity] if "None" in self.cfg.security else []
        if "Basic256Sha256_SignAndEncrypt" in self.cfg.security:
            policies.append(ua.SecurityPolicyType.Basic256Sha256_SignAndEncrypt)
        server.set_security_policy(policies, permission_ruleset=_Rules())
        tokens: list[type] = []
        if self.cfg.allow_anonymous:
            tokens.append(ua.AnonymousIdentityToken)
        if self.cfg.users:
            tokens.append(ua.UserNameIdentityToken)
        if self.cfg.certificate_users:
            tokens.append(ua.X509IdentityToken)
        server.set_identity_tokens(tokens)
        try:
            if self.cfg.certificate is not None and self.cfg.private_key is not None:
                await server.load_certificate(str(self.cfg.certificate))
                await server.load_private_key(str(self.cfg.private_key))
            from asyncua.crypto import uacrypto
            for cu in self.cfg.certificate_users:
                certificates[uacrypto.der_from_x509(  # type: ignore[no-untyped-call]
                    await uacrypto.load_certificate(str(cu.certificate)))] = cu.name
        except (OSError, ValueError) as exc:
            raise GatewayError(f"cannot load a certificate or key of {self.cfg.source}: {exc}: check the files "
                               f"([server] certificate, private_key, [[certificate_users]])") from None
        self.ns = await server.register_namespace(NAMESPACE_URI)
        self._event_type = await server.create_custom_event_type(
            self.ns, "LandScapeNoticeEventType", ObjectIds.BaseEventType,
            [(name, vt) for name, vt in EVENT_FIELDS])
        self._root = await server.nodes.objects.add_folder(_nid("DeviceSet", self.ns), f"{self.ns}:DeviceSet")
        # asyncua logs a failed start with its traceback before it raises: the one line below says it all
        server_log = logging.getLogger("asyncua.server.server")
        was_disabled, server_log.disabled = server_log.disabled, True
        try:
            await server.start()
        except OSError as exc:
            raise GatewayError(f"cannot serve OPC UA on {self.cfg.host}:{self.cfg.port}: {exc.strerror or exc}: "
                               f"{_listen_hint(exc)}") from None
        finally:
            server_log.disabled = was_disabled
        try:
            self._bus = open_bus(self.spec)
        except BaseException:
            await server.stop()
            raise
        self._notifier = SharedNotifier(self._bus, [self._on_frame], timeout=0.05, loop=None)
        self._spawn(self._event_pump(), "the event pump")
        self._spawn(self._watch_observers(), "watching the observers")

    async def run(self) -> None:
        """Serve until stop(); then close every session's supervisor (the device sees each leave)."""
        loop = asyncio.get_running_loop()
        for sig in (signal.SIGINT, signal.SIGTERM):
            loop.add_signal_handler(sig, self._stop.set)
        try:
            await self._stop.wait()
        finally:
            for sig in (signal.SIGINT, signal.SIGTERM):
                loop.remove_signal_handler(sig)
            await self.close()

    def stop(self) -> None:
        self._stop.set()

    async def close(self) -> None:
        self._closing = True
        for c in self.controllers.values():
            if c.timer is not None:
                c.timer.cancel()
                c.timer = None
        for task in list(self._tasks):
            task.cancel()
        sups = list(self._sups.values()) + [c.observer for c in self.controllers.values() if c.observer]
        self._sups.clear()
        for c in self.controllers.values():
            c.observer = None
        loop = asyncio.get_running_loop()
        await asyncio.gather(*(loop.run_in_executor(None, s.close) for s in sups))
        await self.server.stop()
        notifier, bus = self._notifier, self._bus
        self._notifier, self._bus = None, None
        _close_bus(notifier, bus)

    # ------------------------------------------------------------ the bus (Notifier thread -> loop)

    def _on_frame(self, frame: can.Message) -> None:
        b = tm.decode(frame)
        if b is None or self._loop is None:
            return
        if b.name == "HEARTBEAT" and b.signals.get("hb_role", 0) != 0:
            self._heard[b.sender] = time.monotonic()  # another supervisor's address is taken
            return
        self._loop.call_soon_threadsafe(self._apply, b)

    def _apply(self, b: tm.Broadcast) -> None:
        if self._closing:
            return
        c = self.controllers.get(b.sender)
        if c is None:
            if b.name == "HEARTBEAT" and b.sender not in self._pending:
                self._pending.add(b.sender)
                self._spawn(self._add_controller(b.sender), f"adding controller {b.sender:#04x}")
            return
        c.heard = time.monotonic()
        if c.lost is not None:
            if b.name == "HEARTBEAT" and b.sender not in self._pending:
                self._pending.add(b.sender)
                self._spawn(self._back(c), f"recovering controller {b.sender:#04x}")
            return
        s = b.signals
        writes: list[tuple[Node, Any, ua.VariantType]] = []
        if b.name == "HEARTBEAT":
            writes += [(c.vars["Owner"], int(s["hb_owner"]), ua.VariantType.Byte),
                       (c.vars["Supervisors"], int(s["hb_supervisors"]), ua.VariantType.Byte)]
        elif b.name == "STATUS":
            state = int(s["st_state"])
            writes += [(c.vars["State"], pb.State.Name(state) if state in pb.State.values() else str(state),
                        ua.VariantType.String),
                       (c.vars["Motion"], tm.choice_name("STATUS", "st_motion", int(s["st_motion"])),
                        ua.VariantType.String),
                       (c.vars["Fault"], int(s["st_fault"]), ua.VariantType.UInt32)]
        elif b.name.startswith("JOINTS_"):
            cmd = b.name.startswith("JOINTS_CMD_")
            for key, value in s.items():
                i = int(key[1]) - 1
                if cmd:
                    writes.append((c.axes_cmd[i], float(value), ua.VariantType.Double))
                else:
                    c.joints[i] = float(value)
                    writes.append((c.axes[i], float(value), ua.VariantType.Double))
            if not cmd and b.name == "JOINTS_56":  # the last of the three: the set is whole
                writes.append((c.vars["JointPositions"], list(c.joints), ua.VariantType.Double))
        elif b.name in ("TOOL_POS", "TOOL_RPY"):
            keys = ("tool_x", "tool_y", "tool_z") if b.name == "TOOL_POS" else ("tool_roll", "tool_pitch", "tool_yaw")
            off = 0 if b.name == "TOOL_POS" else 3
            for i, k in enumerate(keys):
                c.tool[off + i] = float(s[k])
            writes.append((c.vars["ToolPose"], list(c.tool), ua.VariantType.Double))
        if writes:
            self._spawn(self._write(writes), f"updating controller {b.sender:#04x}")

    async def _write(self, writes: list[tuple[Node, Any, ua.VariantType]]) -> None:
        now = ua.DateTime.now(datetime.UTC)
        for node, value, vt in writes:
            await self.server.write_attribute_value(node.nodeid, ua.DataValue(
                ua.Variant(value, vt), SourceTimestamp=now, ServerTimestamp=now))

    # ------------------------------------------------------------ a controller that goes and comes back

    def _live_nodes(self, c: Controller) -> list[Node]:
        return [c.vars[k] for k in LIVE_VARS] + c.axes + c.axes_cmd

    def _silence_limit_s(self, c: Controller) -> float:
        """How long `c` may stay silent: as the CLI's supervisors judge a device (twice its heartbeat
        time-out, the description's), DEFAULT_SILENCE_S before the description is read."""
        limit = c.observer.device_silence_limit_s() if c.observer is not None else None
        return limit if limit is not None else DEFAULT_SILENCE_S

    def _arm(self, c: Controller) -> None:
        assert self._loop is not None
        if c.timer is not None:
            c.timer.cancel()
        c.timer = self._loop.call_later(self._silence_limit_s(c), self._check_silence, c.address)

    def _check_silence(self, address: int) -> None:
        """The timer of a controller: re-armed while it is heard, else it is gone."""
        c = self.controllers.get(address)
        if c is None or c.lost is not None or self._closing or self._loop is None:
            return
        c.timer = None
        silent = time.monotonic() - c.heard
        limit = self._silence_limit_s(c)
        if silent < limit:
            c.timer = self._loop.call_later(limit - silent, self._check_silence, address)
            return
        why = c.observer.link_problem() if c.observer is not None else None
        c.lost = why or f"no heartbeat from it for {silent:.1f} s"
        self._spawn(self._gone(c), f"marking controller {address:#04x} gone")

    async def _gone(self, c: Controller) -> None:
        """`c` stopped beating: its values turn Bad (BadNoCommunication), subscribers get the
        CONTROLLER_LOST alarm, its supervisors leave (the device forgot them, or will), and when no
        controller is left the gateway reopens its link until one beats again."""
        why = c.lost or "gone"
        log.warning("controller %#04x on %s is gone: %s: its values are BadNoCommunication until its heartbeat "
                    "returns (is landscaped still running?)", c.address, self.channel, why)
        self._events.put_nowait((c.address, 0, pb.Notice(kind=pb.ALARM, event_id=CONTROLLER_LOST,
                                                         data=[f"reason={why}", f"channel={self.channel}"])))
        now = ua.DateTime.now(datetime.UTC)
        for node in self._live_nodes(c):
            old = self.server.read_attribute_value(node.nodeid)
            await self.server.write_attribute_value(node.nodeid, ua.DataValue(
                old.Value, StatusCode=_status(GONE), SourceTimestamp=now, ServerTimestamp=now))
        sups = [sup for key, sup in self._sups.items() if key[1] == c.address]
        for key in [key for key in self._sups if key[1] == c.address]:
            del self._sups[key]
            self._sup_locks.pop(key, None)
        if c.observer is not None:
            sups.append(c.observer)
            c.observer = None
        loop = asyncio.get_running_loop()
        await asyncio.gather(*(loop.run_in_executor(None, sup.close) for sup in sups))
        for sup in sups:
            self._used.discard(sup.source_address)
        if not self._relinking and all(x.lost is not None for x in self.controllers.values()):
            self._relinking = True
            self._spawn(self._relink(), "reopening the link")

    async def _relink(self) -> None:
        """No controller beats: the line itself may be gone (landscaped's pty, a session's shared link),
        so reopen it every RELINK_S until a heartbeat comes (then _back recovers the controller)."""
        loop = asyncio.get_running_loop()
        reported = False
        try:
            while not self._closing and all(c.lost is not None for c in self.controllers.values()):
                await asyncio.sleep(RELINK_S)
                if self._closing or any(c.lost is None or c.address in self._pending
                                        for c in self.controllers.values()):
                    return
                notifier, bus = self._notifier, self._bus
                self._notifier, self._bus = None, None
                await loop.run_in_executor(None, _close_bus, notifier, bus)
                try:
                    bus = await loop.run_in_executor(None, open_bus, self.spec)
                except LandscapeError as exc:
                    if not reported:
                        log.info("reopening %s: %s (trying every %g s)", self.channel, exc, RELINK_S)
                        reported = True
                    continue
                self._bus = bus
                self._notifier = SharedNotifier(bus, [self._on_frame], timeout=0.05, loop=None)
                # give its heartbeat time to come before the next reopen
                deadline = time.monotonic() + 2 * DEFAULT_SILENCE_S
                while time.monotonic() < deadline and all(c.lost is not None for c in self.controllers.values()):
                    if any(c.address in self._pending for c in self.controllers.values()):
                        return
                    await asyncio.sleep(0.1)
        finally:
            self._relinking = False

    async def _back(self, c: Controller) -> None:
        """A gone controller beats again: a new observer, Good values with the next telemetry, calls work."""
        try:
            c.lost = None
            c.heard = time.monotonic()
            log.info("controller %#04x on %s is back: its values follow its telemetry again", c.address,
                     self.channel)
            self._events.put_nowait((c.address, 0, pb.Notice(kind=pb.EVENT, event_id=CONTROLLER_BACK,
                                                             data=[f"channel={self.channel}"])))
            await self._observe(c)
        finally:
            self._pending.discard(c.address)
        self._arm(c)

    async def _watch_observers(self) -> None:
        """Every OBSERVER_CHECK_S, a query from each live controller's observer: when the device answers
        that it dropped the observer's session (Supervisor.connected turns False), connect it again, so
        the description and the alarms keep reaching the sessions."""
        loop = asyncio.get_running_loop()
        while not self._closing:
            await asyncio.sleep(OBSERVER_CHECK_S)
            for c in list(self.controllers.values()):
                observer = c.observer
                if observer is None or c.lost is not None or self._closing:
                    continue
                try:
                    await loop.run_in_executor(None, functools.partial(
                        observer.request, "get_motion_control_state", check=False))
                    if observer.connected or c.observer is not observer:
                        continue
                    log.warning("controller %#04x dropped the gateway's observer %#04x (its heartbeats did not "
                                "reach the controller in time: this process stalled or the bus lost them); "
                                "connecting it again", c.address, observer.source_address)
                    await loop.run_in_executor(None, observer.connect)
                    log.info("controller %#04x: the observer %#04x is connected again", c.address,
                             observer.source_address)
                except LandscapeError as exc:
                    # silence is the silence timer's to judge (_check_silence); this says only what failed
                    log.info("controller %#04x: checking the observer's session: %s", c.address, exc)

    # ------------------------------------------------------------ the address space of a controller

    async def _add_controller(self, address: int) -> None:
        assert self._root is not None
        ns = self.ns
        name = f"Controller_{address:02X}"
        obj = await self._root.add_object(_nid(name, ns), f"{ns}:{name}")
        await obj.write_attribute(AttributeIds.EventNotifier, ua.DataValue(ua.Variant(1, ua.VariantType.Byte)))
        nid = f"{name}."

        async def var(parent: Node, key: str, value: Any, vt: ua.VariantType) -> Node:
            return await parent.add_variable(_nid(nid + key, ns), f"{ns}:{key}", ua.Variant(value, vt))

        v: dict[str, Node] = {}
        v["Address"] = await var(obj, "Address", address, ua.VariantType.Byte)
        v["Description"] = await var(obj, "Description", "", ua.VariantType.String)
        v["State"] = await var(obj, "State", "", ua.VariantType.String)
        v["Motion"] = await var(obj, "Motion", "", ua.VariantType.String)
        v["Fault"] = await var(obj, "Fault", 0, ua.VariantType.UInt32)
        v["Owner"] = await var(obj, "Owner", 0, ua.VariantType.Byte)
        v["Supervisors"] = await var(obj, "Supervisors", 0, ua.VariantType.Byte)
        devices = await obj.add_folder(_nid(nid + "MotionDevices", ns), f"{ns}:MotionDevices")
        arm = await devices.add_object(_nid(nid + "Arm", ns), f"{ns}:Arm")
        v["JointPositions"] = await var(arm, "JointPositions", [0.0] * JOINTS, ua.VariantType.Double)
        v["ToolPose"] = await var(arm, "ToolPose", [0.0] * 6, ua.VariantType.Double)
        await v["ToolPose"].write_attribute(AttributeIds.Description, ua.DataValue(ua.Variant(
            ua.LocalizedText("x, y, z (m), roll, pitch, yaw (rad) of the tool in the world frame"))))
        axes_folder = await arm.add_folder(_nid(nid + "Axes", ns), f"{ns}:Axes")
        axes: list[Node] = []
        axes_cmd: list[Node] = []
        for j in range(1, JOINTS + 1):
            axis = await axes_folder.add_object(_nid(f"{nid}Axes.J{j}", ns), f"{ns}:J{j}")
            params = await axis.add_folder(_nid(f"{nid}Axes.J{j}.ParameterSet", ns), f"{ns}:ParameterSet")
            for key, out in (("ActualPosition", axes), ("CommandedPosition", axes_cmd)):
                node = await params.add_variable(_nid(f"{nid}Axes.J{j}.{key}", ns), f"{ns}:{key}",
                                                 ua.Variant(0.0, ua.VariantType.Double))
                await node.add_property(ns, "EngineeringUnits", _eu("rad"))
                out.append(node)
        await v["ToolPose"].add_property(ns, "EngineeringUnits", _eu("m"))
        methods = await obj.add_folder(_nid(nid + "Commands", ns), f"{ns}:Commands")
        outs = [self._out(n, vt, d) for n, vt, d in OUTPUTS]
        for cmd in COMMANDS.values():
            if cmd.field in ("connect", "disconnect"):
                continue  # the gateway holds the session: an OPC UA session is the connection
            method = await methods.add_method(_nid(nid + cmd.name, ns), f"{ns}:{cmd.name}",
                                              self._method(address, cmd), [argument_of(fd) for fd in cmd.fields()],
                                              outs)
            await method.write_attribute(AttributeIds.Description, ua.DataValue(ua.Variant(
                ua.LocalizedText(f"{cmd.summary}. {cmd.contract(NON_BLOCKING)}"))))
        rsvp_in = [self._out("RsvpId", ua.VariantType.UInt32, "the RsvpId of the RSVP event"),
                   self._out("RetCode", ua.VariantType.Int32, ">= 0 accepts, < 0 declines"),
                   self._out("Data", ua.VariantType.String, "recorded in the device's event log", array=True)]
        rsvp_out = [self._out("RetCode", ua.VariantType.Int32, "the device's RsvpAck: CMD_EXEC_OK, taken"),
                    self._out("RetMsg", ua.VariantType.String, "why a reply was refused"),
                    self._out("Action", ua.VariantType.String, "what the device did")]
        await methods.add_method(_nid(nid + "AnswerRsvp", ns), f"{ns}:AnswerRsvp", self._rsvp_method(address),
                                 rsvp_in, rsvp_out)
        c = Controller(address, obj, v, axes, axes_cmd)
        c.events = await self.server.get_event_generator(self._event_type, obj.nodeid)
        c.heard = time.monotonic()
        self.controllers[address] = c
        self._pending.discard(address)
        log.info("controller %#04x on %s: %s", address, self.channel, obj.nodeid.to_string())
        self._arm(c)
        await self._observe(c)

    async def _observe(self, c: Controller) -> None:
        """Connect the gateway's observer of `c`: the description, and the alarms to every session."""
        address = c.address
        try:
            observer = await self._open_supervisor(address, f"{self.client_name}-observer")
        except LandscapeError as exc:
            log.warning("controller %#04x: the gateway's observer did not connect (%s): no description, and "
                        "alarms reach only the sessions' own supervisors", address, exc)
            return
        if c.lost is not None or self._closing:  # it went again while we connected
            await asyncio.get_running_loop().run_in_executor(None, observer.close)
            self._used.discard(observer.source_address)
            return
        c.observer = observer
        observer.on_notice(lambda n: self._notice(address, observer.source_address, n, unsolicited=True))
        if observer.description is not None:
            text = json.dumps(message_to_dict(observer.description.res), sort_keys=True)
            await c.vars["Description"].write_value(ua.Variant(text, ua.VariantType.String))

    @staticmethod
    def _out(name: str, vt: ua.VariantType, text: str, *, array: bool = False) -> ua.Argument:
        arg = ua.Argument()
        arg.Name = name
        arg.DataType = _nid(vt.value)
        arg.ValueRank = 1 if array else -1
        if array:
            arg.ArrayDimensions = [0]
        arg.Description = ua.LocalizedText(text)
        return arg

    # ------------------------------------------------------------ supervisors, one per session and device

    async def _open_supervisor(self, device: int, client_name: str) -> Supervisor:
        """A connected Supervisor of `device` from the first address of the pool that neither this gateway
        nor a supervisor heard on the bus holds; the next on a refusal "in use"."""
        if self._bus is None or self._notifier is None:
            raise LandscapeError(f"the gateway's link {self.channel} is closed (it reopens it until a controller "
                                 f"beats again)")
        loop = asyncio.get_running_loop()
        now = time.monotonic()
        refused: list[str] = []
        heard: list[str] = []
        for addr in self.cfg.pool:
            if addr in self._used:
                continue
            if now - self._heard.get(addr, -1e9) < HEARD_HOLDS_S:
                heard.append(f"{addr:#04x}")
                continue
            self._used.add(addr)
            # the observer read the description; a session's supervisor takes its copy
            c = self.controllers.get(device)
            known = c.observer.description if c is not None and c.observer is not None else None
            if known is not None and not known.from_device:
                known = None  # the host's stand-in: let this session try the device's own
            sup = Supervisor(self._bus, device=device, source_address=addr, notifier=self._notifier,
                             client_name=client_name, heartbeat_period_ms=self.cfg.heartbeat_period_ms,
                             key=self.cfg.key,
                             channel_name=self.channel, description=known)
            try:
                await loop.run_in_executor(None, sup.open)
            except AddressInUseError:
                self._used.discard(addr)
                refused.append(f"{addr:#04x}")
                continue
            except BaseException:
                self._used.discard(addr)
                raise
            return sup
        observers = {c.observer.source_address: c.address for c in self.controllers.values() if c.observer}
        held = [f"{a:#04x} (the observer of {observers[a]:#04x})" if a in observers else f"{a:#04x} (a session)"
                for a in sorted(self._used)]
        raise PoolExhaustedError(
            "connect", pb.CMD_NO_RESOURCES_ERR,
            f"no free address in the gateway's pool {', '.join(f'{a:#04x}' for a in self.cfg.pool)}; held by this "
            f"gateway: {', '.join(held) or 'none'}; heard beating on the bus from another supervisor: "
            f"{', '.join(heard) or 'none'}; refused by the controller as in use: {', '.join(refused) or 'none'}: "
            f"widen [supervisors] pool or close OPC UA sessions")

    def _create_session(self, name: str, user: User = User(role=UserRole.Anonymous),  # noqa: B008
                        external: bool = False) -> InternalSession:
        s = GatewaySession(self.server.iserver, self.server.iserver.aspace, self.server.iserver.subscription_service,
                           name, user=user, external=external)
        s.gateway = self
        return s

    async def _session_supervisor(self, session: GatewaySession, device: int) -> Supervisor:
        key = (_session_key(session), device)
        lock = self._sup_locks.setdefault(key, asyncio.Lock())
        async with lock:
            sup = self._sups.get(key)
            if sup is not None and sup.connected:
                return sup
            if sup is not None:
                # the device dropped this session's supervisor (a call was answered CMD_NOT_CONNECTED_ERR):
                # connect it again from its address, as the CLI's session does
                try:
                    await asyncio.get_running_loop().run_in_executor(None, sup.connect)
                    log.info("session %s: supervisor %#04x of %#04x is connected again", _label(session),
                             sup.source_address, device)
                    return sup
                except LandscapeError as exc:
                    log.warning("session %s: supervisor %#04x of %#04x did not connect again (%s): a new one "
                                "takes its place", _label(session), sup.source_address, device, exc)
                    del self._sups[key]
                    await asyncio.get_running_loop().run_in_executor(None, sup.close)
                    self._used.discard(sup.source_address)
            who = session.user.name or "user"
            sup = await self._open_supervisor(device, f"opcua:{who}"[:24])
            sup.on_notice(lambda n: self._notice(device, sup.source_address, n, unsolicited=False))
            if session.state == SessionState.Closed:
                await asyncio.get_running_loop().run_in_executor(None, sup.close)  # it ended while we connected
                self._used.discard(sup.source_address)
                raise LandscapeError("the OPC UA session ended")
            self._sups[key] = sup
            log.info("session %s is supervisor %#04x of %#04x", _label(session), sup.source_address, device)
            return sup

    async def session_closed(self, session: GatewaySession) -> None:
        """An OPC UA session ended (closed, timed out, its connection lost): its supervisors disconnect,
        so the device runs its disconnect handler for an owner, as for a lost CAN supervisor."""
        k = _session_key(session)
        gone = [(key, sup) for key, sup in self._sups.items() if key[0] == k]
        loop = asyncio.get_running_loop()
        for key, sup in gone:
            del self._sups[key]
            self._sup_locks.pop(key, None)
            log.info("session %s ended: supervisor %#04x of %#04x leaves", _label(session), sup.source_address,
                     key[1])
            await loop.run_in_executor(None, sup.close)
            self._used.discard(sup.source_address)

    # ------------------------------------------------------------ methods

    def _caller(self) -> GatewaySession | ua.StatusCode:
        session = _current_session.get()
        if session is None:
            return _status(StatusCodes.BadSessionIdInvalid)
        if session.user.role == UserRole.Anonymous:
            log.warning("refused a method call from anonymous session %s: commands need a user ([users] or "
                        "[[certificate_users]] in the gateway's configuration)", _label(session))
            return _status(StatusCodes.BadUserAccessDenied)
        return session

    def _gone_message(self, device: int) -> str | None:
        c = self.controllers.get(device)
        if c is None or c.lost is None:
            return None
        return (f"controller {device:#04x} on {self.channel} is gone ({c.lost}): start landscaped again; the "
                f"gateway finds it by its heartbeat")

    def _method(self, device: int, cmd: Command) -> Callable[..., Any]:
        async def call(parent: ua.NodeId, *args: ua.Variant) -> Any:
            session = self._caller()
            if isinstance(session, ua.StatusCode):
                return session
            gone = self._gone_message(device)
            if gone is not None:
                log.warning("%s from session %s: %s", cmd.name, _label(session), gone)
                return _failed(GONE, pb.CMD_ERR, gone)
            try:
                fields = fields_of(cmd, [a.Value if isinstance(a, ua.Variant) else a for a in args])
                sup = await self._session_supervisor(session, device)
                rv = await asyncio.get_running_loop().run_in_executor(
                    None, lambda: sup.request(cmd.field, check=False, **fields))
            except ArgumentShapeError as exc:
                log.warning("%s from session %s: %s", cmd.name, _label(session), exc)
                return _failed(StatusCodes.BadInvalidArgument, pb.CMD_PARAM_ERR, str(exc))
            except ArgumentError as exc:
                # a value that does not fit: answered as the device answers one, so a client on the LAN reads why
                log.warning("%s from session %s: %s", cmd.name, _label(session), exc)
                return _refused(pb.CMD_PARAM_ERR, str(exc))
            except CommandError as exc:
                # the device refused this session's connect (its supervisor table is full, ...): a good
                # call with the device's code and text, as for any refusal of the command itself
                log.warning("%s from session %s: %s", cmd.name, _label(session), exc)
                return _refused(exc.ret_code, f"{exc.command}: {exc.ret_msg}")
            except LandscapeError as exc:
                log.warning("%s from session %s: %s", cmd.name, _label(session), exc)
                return _failed(StatusCodes.BadCommunicationError, pb.CMD_ERR, str(exc))
            result = json.dumps(rv.result, sort_keys=True) if rv.result else "{}"
            return [ua.Variant(rv.ret_code, ua.VariantType.Int32), ua.Variant(rv.ret_name, ua.VariantType.String),
                    ua.Variant(rv.ret_msg, ua.VariantType.String), ua.Variant(rv.seq, ua.VariantType.UInt32),
                    ua.Variant(rv.epoch, ua.VariantType.UInt32), ua.Variant(result, ua.VariantType.String)]
        return call

    def _rsvp_method(self, device: int) -> Callable[..., Any]:
        async def call(parent: ua.NodeId, *args: ua.Variant) -> Any:
            session = self._caller()  # first: an anonymous caller learns nothing about the arguments
            if isinstance(session, ua.StatusCode):
                return session
            try:
                rid, code, items = rsvp_arguments([a.Value if isinstance(a, ua.Variant) else a for a in args])
            except ArgumentError as exc:
                log.warning("AnswerRsvp from session %s: %s", _label(session), exc)
                res = ua.CallMethodResult()
                res.StatusCode = _status(StatusCodes.BadInvalidArgument)
                res.OutputArguments = [ua.Variant(pb.CMD_PARAM_ERR, ua.VariantType.Int32), ua.Variant(str(exc)),
                                       ua.Variant("", ua.VariantType.String)]
                return res
            gone = self._gone_message(device)
            if gone is not None:
                log.warning("AnswerRsvp from session %s: %s", _label(session), gone)
                return _status(GONE)
            sup = self._sups.get((_session_key(session), device))
            if sup is None:
                return _status(StatusCodes.BadInvalidState)  # this session armed no RSVP here
            try:
                ack = await asyncio.get_running_loop().run_in_executor(
                    None, lambda: sup.answer_rsvp(rid, code, items, check=False))
            except LandscapeError as exc:
                return [ua.Variant(pb.CMD_TIMEOUT_ERR, ua.VariantType.Int32), ua.Variant(str(exc)),
                        ua.Variant("", ua.VariantType.String)]
            return [ua.Variant(ack.ret_code, ua.VariantType.Int32), ua.Variant(ack.ret_msg, ua.VariantType.String),
                    ua.Variant(ack.action, ua.VariantType.String)]
        return call

    # ------------------------------------------------------------ notices -> events

    def _notice(self, device: int, supervisor: int, n: pb.Notice, *, unsolicited: bool) -> None:
        """A supervisor's dispatcher thread: queue the notice as an event. The observer forwards the notices
        of no request (alarms to every session), a session's supervisor those of its own requests."""
        if (n.ref_seq == 0 and n.kind not in RSVP_KINDS) != unsolicited or self._loop is None:
            return
        self._loop.call_soon_threadsafe(self._events.put_nowait, (device, supervisor, n))

    async def _event_pump(self) -> None:
        """One task fires every event: an EventGenerator's fields are shared between triggers."""
        while True:
            device, supervisor, n = await self._events.get()
            c = self.controllers.get(device)
            if c is None or c.events is None:
                continue
            ev = c.events.event
            alarm = n.kind in ALARM_KINDS
            ev.Severity = 800 if alarm else 300
            ev.SourceName = f"Controller_{device:02X}"
            ev.Device, ev.Supervisor = device, supervisor
            ev.Kind, ev.NoticeId, ev.Data = pb.NoticeKind.Name(n.kind), n.event_id, "; ".join(n.data)
            ev.RefSeq, ev.SessionEpoch, ev.Final = n.ref_seq, n.session_epoch, n.final
            ev.RsvpId, ev.RsvpTimeoutMs, ev.RsvpDefault = n.rsvp_id, n.rsvp_timeout_ms, n.rsvp_default
            await c.events.trigger(message=f"{pb.NoticeKind.Name(n.kind)} {n.event_id} {' '.join(n.data)}".strip())


def rsvp_arguments(args: Sequence[Any]) -> tuple[int, int, list[str]]:
    """AnswerRsvp's (RsvpId, RetCode, Data) from a call's input arguments; ArgumentError naming the one
    that does not fit."""
    if not 2 <= len(args) <= 3:
        raise ArgumentError(f"AnswerRsvp takes RsvpId, RetCode and optionally Data, got {len(args)} arguments")
    rid, code = args[0], args[1]
    data = args[2] if len(args) > 2 else None
    for name, value, low, high in (("RsvpId", rid, 0, 0xFFFFFFFF), ("RetCode", code, -2**31, 2**31 - 1)):
        if isinstance(value, bool) or not isinstance(value, int):
            raise ArgumentError(f"AnswerRsvp.{name}: an integer is expected, got {type(value).__name__} {value!r}")
        if not low <= value <= high:
            raise ArgumentError(f"AnswerRsvp.{name}: {value} is outside {low}..{high}")
    if data is None:
        items: list[str] = []
    elif isinstance(data, (list, tuple)) and all(isinstance(d, str) for d in data):
        items = list(data)
    else:
        raise ArgumentError(f"AnswerRsvp.Data: an array of String is expected, got {type(data).__name__} {data!r}")
    return rid, code, items


def _listen_hint(exc: OSError) -> str:
    """What to do when the server cannot listen (`exc` from binding its socket)."""
    if exc.errno == errno.EADDRINUSE:
        return "another program listens on that port: pass --port, or set [server] port"
    if exc.errno == errno.EADDRNOTAVAIL or isinstance(exc, socket.gaierror):
        return ("the host is not an address of this machine: pass --host (or set [server] host) to one of its "
                "addresses, e.g. 127.0.0.1 or 0.0.0.0 for all")
    if exc.errno == errno.EACCES:
        return "a port below 1024 needs privileges: pass --port, or set [server] port"
    return "check --host and --port ([server] host, port)"


def _close_bus(notifier: can.Notifier | None, bus: can.BusABC | None) -> None:
    if notifier is not None:
        notifier.stop()
    if bus is not None:
        try:
            bus.shutdown()
        except (can.CanError, OSError) as exc:
            log.debug("closing the bus: %s", exc)
        release_bus(bus)


def _session_key(session: InternalSession) -> int:
    return hash(session.session_id)


def _refused(code: int, msg: str) -> list[ua.Variant]:
    """A good call's outputs for a refusal that no device answer carries (no Seq, no epoch)."""
    return [ua.Variant(code, ua.VariantType.Int32), ua.Variant(ret_name(code), ua.VariantType.String),
            ua.Variant(msg, ua.VariantType.String), ua.Variant(0, ua.VariantType.UInt32),
            ua.Variant(0, ua.VariantType.UInt32), ua.Variant("{}", ua.VariantType.String)]


def _failed(status: int, code: int, msg: str) -> ua.CallMethodResult:
    res = ua.CallMethodResult()
    res.StatusCode = _status(status)
    res.OutputArguments = _refused(code, msg)
    return res


def _nid(identifier: str | int, ns: int = 0) -> ua.NodeId:
    """A NodeId (asyncua types its fields with NewTypes)."""
    ident = ua.Int32(identifier) if isinstance(identifier, int) else ua.String(identifier)
    return ua.NodeId(ident, ua.Int16(ns))


def _status(code: int) -> ua.StatusCode:
    return ua.StatusCode(ua.UInt32(code))
