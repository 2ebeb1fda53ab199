"""The `landscape` group and what every subcommand module shares.

The group's options and state (`CliState`: the bus, the session or background
session, the output mode), the send/execute/collect path every command takes,
the error classification behind the exit codes, and one subcommand per schema
command, built from the registry at import time (docs/host-tool.md states the
argument rule). `cli.py` adds `run`, `shell` and `monitor`; `cli_tools.py` adds
the path, record, plot, view, demo and session commands. Neither is imported
here, so the modules form no cycle. Every error a user can meet ends as one
line on stderr and an exit code:

    0 success; 1 protocol or other error; 2 usage (bad arguments, unknown command);
    3 the device answered an error or a command ended with an alarm;
    4 bus cannot be opened, no controller answers, or it went away mid-command;
    5 version mismatch; 130 interrupted.
"""
from __future__ import annotations

import json
import logging
import sys
import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import can
import click
from google.protobuf.descriptor import EnumDescriptor, FieldDescriptor

from ._generated import landscape_pb2 as pb
from .auth import SupervisorKey, load_key
from .backend import Backend, BusBackend, SessionBackend, description_of
from .bus import DEFAULT_DEVICE, HOST_POOL, BusSpec
from .errors import (
    AlarmError,
    ArgumentError,
    BusError,
    CommandError,
    ControllerTimeoutError,
    LandscapeError,
    LinkLostError,
    ProtocolError,
    VersionMismatchError,
    error_for_code,
)
from .notices import Units, format_notice
from .registry import (
    COMMANDS,
    Command,
    absent_means,
    enum_choices,
    field_enum_type,
    field_message_type,
    is_repeated,
    message_to_dict,
    parse_enum,
)
from .retval import RetVal
from .session import SessionClient, SessionGoneError, socket_path
from .supervisor import Supervisor

log = logging.getLogger("landscape.cli")

EXIT_OK, EXIT_ERROR, EXIT_USAGE, EXIT_COMMAND, EXIT_BUS, EXIT_VERSION, EXIT_INTERRUPTED = 0, 1, 2, 3, 4, 5, 130


class CommandFailed(LandscapeError):
    """A command answered an error or ended with an alarm (already reported)."""

    def __init__(self, message: str, code: int = EXIT_COMMAND) -> None:
        super().__init__(message)
        self.code = code


class AlreadyReported(LandscapeError):
    """The invocation ends with exit code `code`; its one line was printed already (the shell
    printed the line of a lost device as it happened)."""

    def __init__(self, code: int) -> None:
        super().__init__("")
        self.code = code


# ---------------------------------------------------------------- parameter types


class IntType(click.ParamType[int]):
    name = "integer"

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> int:
        if isinstance(value, int):
            return value
        try:
            return int(str(value), 0)
        except ValueError:
            self.fail(f"'{value}' is not an integer (decimal or 0x hex)", param, ctx)


class EnumType(click.ParamType[int]):
    def __init__(self, enum: EnumDescriptor) -> None:
        self.enum = enum
        self.name = enum.name

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> int:
        try:
            return parse_enum(self.enum, value)
        except ArgumentError:
            self.fail(f"'{value}' is not a {self.enum.name}; choose one of {enum_choices(self.enum)} "
                      f"(any case, suffix optional)", param, ctx)

    def get_metavar(self, param: click.Parameter, ctx: click.Context | None = None) -> str:
        return self.enum.name.upper()


class CommaNumbers(click.ParamType[list[float] | list[int]]):
    def __init__(self, integer: bool) -> None:
        self.integer = integer
        self.name = "N,N,..."

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> list[float] | list[int]:
        if isinstance(value, list):
            return value
        items = [v for v in str(value).replace(" ", "").split(",") if v]
        try:
            return [int(v, 0) for v in items] if self.integer else [float(v) for v in items]
        except ValueError:
            self.fail(f"'{value}' is not a comma-separated list of numbers", param, ctx)


class JsonObject(click.ParamType[dict[str, Any]]):
    name = "JSON"

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> dict[str, Any]:
        if isinstance(value, dict):
            return value
        try:
            out = json.loads(value)
        except json.JSONDecodeError as exc:
            self.fail(f"'{value}' is not JSON: {exc.msg}", param, ctx)
        if not isinstance(out, dict):
            self.fail(f"'{value}' is not a JSON object", param, ctx)
        return out


_FLOATS = (FieldDescriptor.TYPE_DOUBLE, FieldDescriptor.TYPE_FLOAT)


def _is_number(fd: FieldDescriptor) -> bool:
    return fd.type not in (FieldDescriptor.TYPE_STRING, FieldDescriptor.TYPE_ENUM, FieldDescriptor.TYPE_MESSAGE,
                           FieldDescriptor.TYPE_BOOL, FieldDescriptor.TYPE_BYTES)


def cli_params(cmd: Command) -> list[click.Parameter]:
    """The click parameters of `cmd`, derived from its request fields (docs/host-tool.md)."""
    fields = cmd.fields()

    def helped(default: str | None, f: FieldDescriptor) -> str | None:
        return OPTION_HELP.get((cmd.field, f.name), default)
    positional = [f for f in fields if not is_repeated(f)
                  and f.type in (FieldDescriptor.TYPE_STRING, FieldDescriptor.TYPE_ENUM)]
    variadic = next((f for f in fields if is_repeated(f) and f.type in _FLOATS), None)
    params: list[click.Parameter] = []
    for i, f in enumerate(positional):
        trailing_string = (i == len(positional) - 1 and variadic is None
                           and f.type == FieldDescriptor.TYPE_STRING)
        ptype: click.ParamType[Any] = (EnumType(field_enum_type(f)) if f.type == FieldDescriptor.TYPE_ENUM
                                       else click.STRING)
        if trailing_string:
            params.append(click.Argument([f.name], type=ptype, required=False, default="", metavar=f.name.upper()))
        else:  # no default at all: click (8.3 on) takes an explicit default=None as a given value
            params.append(click.Argument([f.name], type=ptype, required=True, metavar=f.name.upper()))
    if variadic is not None:
        params.append(click.Argument([variadic.name], type=float, nargs=-1, required=True,
                                     metavar=f"{variadic.name.upper()}..."))
    for f in fields:
        if f in positional or f is variadic:
            continue
        opt = "--" + f.name.replace("_", "-")
        if is_repeated(f) and f.type == FieldDescriptor.TYPE_MESSAGE:
            params.append(click.Option([opt, f.name], type=JsonObject(), multiple=True,
                                       help=helped(f"one {field_message_type(f).name} as a JSON object; repeat "
                                                   f"per item", f)))
        elif is_repeated(f) and _is_number(f):
            params.append(click.Option([opt, f.name], type=CommaNumbers(f.type not in _FLOATS), default=None,
                                       help=helped("comma-separated numbers", f)))
        elif is_repeated(f):
            params.append(click.Option([opt, f.name], multiple=True, help=helped("repeat per item", f)))
        elif f.type == FieldDescriptor.TYPE_BOOL:
            params.append(click.Option([opt + "/--no-" + f.name.replace("_", "-"), f.name], default=False,
                                       help=helped(None, f)))
        elif f.type == FieldDescriptor.TYPE_ENUM:  # unreachable today (enums are positional)
            params.append(click.Option([opt, f.name], type=EnumType(field_enum_type(f)), default=0,
                                       help=helped(None, f)))
        elif f.type in _FLOATS:
            d = absent_means(f)
            params.append(click.Option([opt, f.name], type=float, default=0.0 if d is None else d, show_default=True,
                                       help=helped(None, f)))
        else:
            d = absent_means(f)
            params.append(click.Option([opt, f.name], type=IntType(), default=0 if d is None else d,
                                       show_default=True, help=helped(None, f)))
    if not cmd.blocking:
        params.append(click.Option(["--no-wait", "_no_wait"], is_flag=True,
                                   help="return after CMD_STARTED_OK instead of waiting for the final notice"))
        params.append(click.Option(["--wait-timeout", "_wait_timeout"], type=float, default=60.0, show_default=True,
                                   help="seconds to wait for the final notice"))
    return params


# ---------------------------------------------------------------- help texts the schema lacks

#: Per-command help beside the schema's summary: what each argument means, in which unit, and
#: an example (docs/conformance.md has the full behaviour). Units: "linear unit" and "angular
#: unit" are the session's (set-units, get-units; meters and radians until changed).
_MOVE_VALUES = (
    "VALUES: with JOINT_FRAME one value per joint (6 for ls-sim6, describe: joints), in the angular unit; with a "
    "Cartesian frame 6 values x y z roll pitch yaw: the tool tip, x y z in the linear unit, roll pitch yaw in the "
    "angular unit as fixed-axis rotations about x, then y, then z (R = Rz(yaw) Ry(pitch) Rx(roll)). "
    "BASE_CARTESIAN_FRAME: the arm's base; WORLD_CARTESIAN_FRAME: set-world-cartesian-frame's; TOOL_FRAME: the "
    "tool at the start. Units: the session's (set-units; meters and radians until changed).")
COMMAND_HELP: dict[str, str] = {
    "move_absolute": (
        f"{_MOVE_VALUES}\n\nExample (the README's ready pose): "
        "landscape move-absolute ready JOINT_FRAME 0 -0.3 0.6 0 0.9 0"),
    "move_relative": (
        f"{_MOVE_VALUES} The values are an offset from where the arm is.\n\n"
        "Example (5 cm up): landscape move-relative up BASE_CARTESIAN_FRAME 0 0 0.05 0 0 0"),
    "set_units": (
        "Both units are required, in this order: LINEAR (meters, millimeters, centimeters, inches, feet, or "
        "their symbols m, mm, cm, in, ft) and ANGULAR (radians, degrees, or rad, deg); `set-units millimeters` "
        "alone is a usage error, so the angular unit never changes silently. Every later position, speed and "
        "acceleration this session sends or receives is in them; telemetry broadcasts (monitor, record) stay "
        "SI and are labelled.\n\n"
        "Example: landscape set-units millimeters degrees"),
    "move_react": (
        "A guarded move: straight along MOTION_OFFSETS (x y z in the tool frame at the start, in the linear "
        "unit; c_x c_y c_z, if given, must be 0) until the sensor crosses the one non-zero threshold, then it "
        "returns to the crossing and stops. SENSOR_TYPE: force_sensor (components Fx Fy Fz Tx Ty Tz, N and Nm) "
        "or laser_standoff_sensor (component 0: the distance, in the linear unit; it stops when the distance "
        "falls below the threshold). Ends with event moveReactComplete (reason=threshold or max_distance, "
        "pose=, force= or distance=, travelled=) or an alarm.\n\n"
        "Example (move down 5 cm at 10 % until Fz reaches 5 N): "
        "landscape move-react force_sensor 0 0 0.05 --thresholds 0,0,5 --motion-speed-pct 10"),
    "comply": (
        "A compliant move: travel along x y z of --max-travel while holding the contact force along c_x c_y c_z "
        "(tool frame at the start, linear unit; travel and compliance direction orthogonal within 5 deg). "
        "SENSOR_TYPE: a force sensor (force_sensor). THRESHOLDS: Fx Fy Fz [Tx Ty Tz], the target contact force "
        "in N, along the compliance direction (torques must be 0). Ends with event complyComplete "
        "(reason=max_travel, pose=, force=, fn_mean/fn_min/fn_max) or an alarm (complyTimeout, "
        "complyPanicStop).\n\n"
        "Example (slide 15 cm along x at 3 % pressing 10 N along z, compliance range 5 cm): "
        "landscape comply force_sensor 0 0 10 --max-travel 0.15,0,0,0,0,0.05 --speed-pct 3 --max-timeout-s 20"),
}

#: Per-option help (command field, request field) -> text; units in every one.
OPTION_HELP: dict[tuple[str, str], str] = {
    ("move_absolute", "speed_pct"): "% of the maximum speed (0: the current set-speed); e.g. 20",
    ("move_relative", "speed_pct"): "% of the maximum speed (0: the current set-speed); e.g. 20",
    ("move_react", "motion_speed_pct"): "speed along the line, % of the maximum linear speed (0: the current "
                                        "set-speed); e.g. 10",
    ("move_react", "compliance_speed_pct"): "accepted and not used by this firmware (%)",
    ("move_react", "thresholds"): "t1,t2,... exactly one non-zero; its position picks the sensor component "
                                  "(force_sensor: Fx,Fy,Fz,Tx,Ty,Tz in N/Nm; laser_standoff_sensor: distance in "
                                  "the linear unit); positive: stop when the reading reaches it, negative: when "
                                  "it falls to it; e.g. 0,0,5 (Fz 5 N)",
    ("move_react", "gains"): "g1,g2,g3: accepted and not used by this firmware",
    ("move_react", "envelope_min"): "accepted and not used by this firmware",
    ("move_react", "envelope_max"): "max: |F| bound in N, force sensors only, above |threshold| (0: none); "
                                    "beyond it the move stops with alarm moveReactEnvelope; e.g. 20",
    ("comply", "max_timeout_s"): "seconds before alarm complyTimeout (0: 30 s); e.g. 20",
    ("comply", "panic_stop_code"): "integer reported as panic_stop_code= in alarm complyPanicStop; e.g. 7",
    ("comply", "max_travel"): "x,y,z,c_x,c_y,c_z (6 values, tool frame, linear unit): the travel, then the "
                              "compliance direction and range; e.g. 0.15,0,0,0,0,0.05",
    ("comply", "proportional_gains"): "Kp per component Fx,Fy,Fz in (linear unit/s)/N (0: 5e-4 m/s/N); "
                                      "e.g. 0,0,0.0005",
    ("comply", "differential_gains"): "Kd per component Fx,Fy,Fz in linear unit/N (0: none); e.g. 0,0,0.00001",
    ("comply", "speed_pct"): "travel speed, % of the maximum linear speed (0: the current set-speed); e.g. 3",
    ("comply", "compliance_speed_pct"): "largest speed along the compliance direction, % of the maximum "
                                        "linear speed (0: 1 %); e.g. 1",
    ("comply", "envelope_min"): "accepted and not used by this firmware",
    ("comply", "envelope_max"): "max: |F| in N beyond which the move stops at once with alarm complyPanicStop "
                                "(0: 3 x the target); e.g. 30",
}


# ---------------------------------------------------------------- state shared by the subcommands




@dataclass
class CliState:
    spec: BusSpec
    device: int
    source_address: int | None
    """--source-address; None: the session picks a free one (docs/host-tool.md "Addresses")."""
    timeout_s: float | None
    json_out: bool
    no_session: bool = False
    key_file: str | None = None
    """--key-file / LANDSCAPE_KEY_FILE: this supervisor's key (docs/host-tool.md "Signed sessions")."""
    key_id: str | None = None
    one_shot: bool = True
    """False in `run` and the shell, whose lines share one session."""
    follow_motions: bool = False
    """The shell: a motion command returns at once and a MotionFollower prints its notices."""
    followers: list[MotionFollower] = field(default_factory=list)
    sup: Supervisor | None = None
    client: SessionClient | None = None
    failures: list[str] = field(default_factory=list)
    lost: LinkLostError | SessionGoneError | None = None
    """The shell: the device (or the background session it spoke through) went away, reported once
    as it happened; the shell ends with exit 4."""

    def socket_path(self) -> Path:
        return socket_path(self.spec, self.device, self.source_address)

    def session(self) -> Supervisor:
        """The invocation's own session: opened on first use, reconnected after a disconnect command."""
        if self.sup is None:
            if self.no_session:
                self._refuse_second_supervisor()
            sup = Supervisor.open_bus(self.spec, device=self.device, source_address=self.source_address,
                                      timeout_s=self.timeout_s, client_name="landscape-cli", key=self.key())
            sup.open()
            self.sup = sup
        elif not self.sup.connected:
            self.sup.connect()
        return self.sup

    def key(self) -> SupervisorKey | None:
        """The key --key-file names (KeyFileError, exit 2, when it cannot be used), or none."""
        return load_key(self.key_file, self.key_id) if self.key_file else None

    def _refuse_second_supervisor(self) -> None:
        """--no-session while the background session speaks from the same address: two
        supervisors with one address would take each other's answers. Without a pinned address
        our own session picks another free one."""
        if self.source_address is None:
            return
        running = SessionClient.attach(self.socket_path())
        if running is None:
            return
        with running:
            pid = running.status().get("pid")
        raise ArgumentError(f"the background session (pid {pid}) already speaks as {self.source_address:#04x} "
                            f"to device {self.device:#04x}: drop --no-session to use it, or pass another "
                            f"--source-address (e.g. -s {(self.source_address + 1) & 0xFF:#04x})")

    def background(self) -> SessionClient | None:
        """A client of the background session of this bus and device, if one runs (and
        --no-session is not given). A stale socket file is removed with a message."""
        if self.no_session or self.sup is not None:
            return None
        if self.client is None:
            self.client = SessionClient.attach(
                self.socket_path(), on_stale=lambda msg: click.echo(f"landscape: {msg}", err=True))
        return self.client

    def backend(self) -> Backend:
        """Where commands go: the background session when one runs, else our own session."""
        client = self.background()
        return SessionBackend(client) if client is not None else BusBackend(self.session())

    def close(self) -> None:
        if self.client is not None:
            self.client.close()
            self.client = None
        if self.sup is not None:
            self.sup.close()
            self.sup = None


def state_of(ctx: click.Context) -> CliState:
    st = ctx.find_object(CliState)
    if st is None:  # pragma: no cover (always set by the group)
        raise click.UsageError("internal: no CLI state")
    return st


#: Decimals a shown number keeps: a billionth of its unit (a nanometre, a nanoradian in SI) is
#: below any arm's resolution, so what is left beyond it is float noise (1.6661e-10 shows as 0).
SHOWN_DECIMALS = 9


def fmt_value(v: Any) -> str:
    if isinstance(v, list):
        return " ".join(fmt_value(x) for x in v) if v else "(none)"
    if isinstance(v, float):
        return f"{round(v, SHOWN_DECIMALS) + 0.0:g}"  # + 0.0: never -0
    if isinstance(v, dict):
        return json.dumps(v)
    return str(v)


def fmt_notice(n: pb.Notice) -> str:
    return "  " + format_notice(n)


def send(backend: Backend, cmd: Command, fields: dict[str, Any], *, wait_s: float | None) -> RetVal:
    """Send one command through `backend` (never raises for a negative code). With a
    background session, `wait_s` asks it to stream the notices up to the final one.
    `-v` logs the request and its answer (logger landscape.cli)."""
    log.info("-> %s %s (via %s)", cmd.name, json.dumps(fields, default=str), backend.via)
    rv = backend.send(cmd, fields, wait_s=wait_s)
    log.info("<- %s seq %d %s%s %s", cmd.name, rv.seq, rv.ret_name, f" {rv.ret_msg!r}" if rv.ret_msg else "",
             json.dumps(rv.result, default=str))
    return rv


def collect(backend: Backend, rv: RetVal, *, wait_timeout_s: float,
            on_notice: Callable[[pb.Notice], None] | None = None) -> tuple[list[pb.Notice], pb.Notice | None]:
    """The notices of a started command up to its final one (on_notice sees each as it arrives)."""
    notices: list[pb.Notice] = []
    if not rv.started:
        return notices, None
    for n in backend.notices(timeout_s=wait_timeout_s):
        log.info("<- notice %s", fmt_notice(n).strip())
        notices.append(n)
        if on_notice is not None:
            on_notice(n)
        if n.final and n.ref_seq == rv.seq and n.session_epoch == rv.epoch:
            return notices, n
    return notices, None


def call(backend: Backend, cmd: Command, fields: dict[str, Any], *, wait: bool, wait_timeout_s: float,
         on_notice: Callable[[pb.Notice], None] | None = None) -> tuple[RetVal, list[pb.Notice], pb.Notice | None]:
    """send() then, when `wait`, collect()."""
    rv = send(backend, cmd, fields, wait_s=wait_timeout_s if wait else None)
    if not wait:
        return rv, [], None
    notices, final = collect(backend, rv, wait_timeout_s=wait_timeout_s, on_notice=on_notice)
    return rv, notices, final


_LINK_LOST_SAID = threading.Lock()


def say_link_lost(st: CliState, exc: LinkLostError | SessionGoneError, line: str,
                  then: Callable[[], None] | None = None) -> None:
    """The shell's lost link, said once (by the first thread to see it: the prompt's or a
    follower's), then recorded in st.lost, on which the shell ends with exit 4. `then` runs
    between the two (a follower marks itself ended there, so that the shell, once it sees
    st.lost, never finds it still running)."""
    with _LINK_LOST_SAID:
        first = st.lost is None
        if first:
            click.echo(line, err=True)
        if then is not None:
            then()
        if first:
            st.lost = exc


class MotionFollower:
    """A motion the shell started, followed in a thread of its own: its notices print as they
    arrive and its end is reported, while the prompt takes the next line (stop-motion above
    all). Through a background session it owns the connection the notices stream on."""

    def __init__(self, cmd: Command, rv: RetVal, backend: Backend, wait_timeout_s: float,
                 st: CliState | None = None) -> None:
        self.cmd = cmd
        self.rv = rv
        self.backend = backend
        self.wait_timeout_s = wait_timeout_s
        self.st = st
        self.thread = threading.Thread(target=self._run, daemon=True, name=f"landscape-follow-{cmd.cli_name}")
        self.abandoned = threading.Event()  # the shell is leaving: say nothing more
        self.ended = threading.Event()  # its end (or the link's loss) has been said

    def start(self) -> None:
        self.thread.start()

    @property
    def running(self) -> bool:
        """Still following: its end has not been said (the thread may be closing)."""
        return self.thread.is_alive() and not self.ended.is_set()

    def _run(self) -> None:
        try:
            _, final = collect(self.backend, self.rv, wait_timeout_s=self.wait_timeout_s,
                               on_notice=lambda n: click.echo(fmt_notice(n)))
            check_outcome(self.cmd, self.rv, final, wait=True, wait_timeout_s=self.wait_timeout_s)
            click.echo(f"{self.cmd.cli_name}: done" + (f" ({final.event_id})" if final is not None else ""))
            self.ended.set()
        except Exception as exc:  # noqa: BLE001 (one line, never a traceback; the shell goes on)
            if self.abandoned.is_set():
                return
            code, msg = classify(exc)
            line = f"error: {msg}" if code is not None else f"error: {type(exc).__name__}: {one_line(exc)}"
            if not (isinstance(exc, (LinkLostError, SessionGoneError)) and self.st is not None):
                click.echo(line, err=True)
                self.ended.set()
                return
            say_link_lost(self.st, exc, line, then=self.ended.set)
        finally:
            self.ended.set()
            if self.backend.shared:
                self.backend.close()

    def abandon(self) -> None:
        """The shell leaves while the motion has not ended: say what becomes of it, stop following."""
        self.abandoned.set()
        if self.backend.shared:
            click.echo(f"shell: {self.cmd.cli_name} has not ended; it goes on in the background session "
                       f"(`landscape events` follows its notices)", err=True)
            self.backend.close()
        else:
            click.echo(f"shell: {self.cmd.cli_name} has not ended; the shell's session ends, and the device ends "
                       f"the motion of an owner that disconnects", err=True)


def execute_followed(st: CliState, cmd: Command, fields: dict[str, Any], wait_timeout_s: float) -> RetVal:
    """The shell's way to run a motion: send it, print its answer, and follow it in a
    MotionFollower so the prompt comes back at once."""
    backend = st.backend()
    rv = send(backend, cmd, fields, wait_s=wait_timeout_s)
    if rv.ret_code >= 0:  # a refusal is said once, on stderr (check_outcome)
        click.echo(f"{cmd.cli_name}: {rv.ret_name}" + (f": {rv.ret_msg}" if rv.ret_msg else ""))
        for k, v in rv.result.items():
            click.echo(f"  {k}: {fmt_value(v)}")
    if not rv.started:
        check_outcome(cmd, rv, None, wait=False, wait_timeout_s=wait_timeout_s)
        return rv
    if backend.shared:
        st.client = None  # the follower owns this connection; the next line opens another
    follower = MotionFollower(cmd, rv, backend, wait_timeout_s, st)
    st.followers = [f for f in st.followers if f.running] + [follower]
    click.echo(f"  ({cmd.cli_name} runs; the prompt is free: stop-motion or Ctrl-C pauses it, abort-motion ends it)")
    follower.start()
    return rv


def execute(ctx: click.Context, cmd: Command, fields: dict[str, Any], *, wait: bool = True,
            wait_timeout_s: float = 60.0) -> RetVal:
    """Run one command in the CLI's session, print its result, then its notices as they
    arrive; raise CommandFailed on failure."""
    st = state_of(ctx)
    if st.follow_motions and wait and not cmd.blocking and not st.json_out and not (
            st.sup is not None and any(f.running for f in st.followers)):
        try:
            return execute_followed(st, cmd, fields, wait_timeout_s)
        except KeyboardInterrupt:
            stop_after_interrupt(st, cmd)
            raise
    backend = st.backend()
    try:
        rv = send(backend, cmd, fields, wait_s=wait_timeout_s if wait else None)
        if relocked(backend, cmd, rv):
            say_relocked(st, cmd, rv)
            return rv
        note = lock_note(st, cmd, rv, backend)
        if not st.json_out and rv.ret_code >= 0:  # a refusal is said once, on stderr (check_outcome)
            click.echo(f"{cmd.cli_name}: {rv.ret_name}" + (f": {rv.ret_msg}" if rv.ret_msg else ""))
            if cmd.field == "describe" and rv.ok:
                for line in description_of(rv).lines():
                    click.echo(f"  {line}")
            else:
                for k, v in rv.result.items():
                    click.echo(f"  {k}: {fmt_value(v)}")
            if note:
                click.echo(f"  note: {note}")
        notices: list[pb.Notice] = []
        final: pb.Notice | None = None
        if wait:
            notices, final = collect(backend, rv, wait_timeout_s=wait_timeout_s,
                                     on_notice=None if st.json_out else (lambda n: click.echo(fmt_notice(n))))
    except KeyboardInterrupt:
        if not cmd.blocking:
            stop_after_interrupt(st, cmd)
        raise
    if st.json_out:
        obj: dict[str, Any] = {
            "command": cmd.cli_name, "ret_code": rv.ret_code, "ret_name": rv.ret_name, "ret_msg": rv.ret_msg,
            "result": rv.result, "notices": [message_to_dict(n) for n in notices]}
        if note:
            obj["note"] = note
        click.echo(json.dumps(obj))
    check_outcome(cmd, rv, final, wait=wait, wait_timeout_s=wait_timeout_s)
    return rv


LOCK_NOTE = ("this lock ends when this invocation exits (it disconnects, and the device releases it); "
             "to keep it across invocations run `landscape session start` first (then `landscape lock`), or put "
             "the commands in one `landscape run FILE` or `landscape shell`")


def lock_note(st: CliState, cmd: Command, rv: RetVal, backend: Backend) -> str | None:
    """What a one-shot `lock` without a background session says beside its answer."""
    if cmd.field == "lock" and rv.ok and st.one_shot and not backend.shared:
        return LOCK_NOTE
    return None


RELOCK_NOTE = "this session holds the lock already: nothing to do"


def relocked(backend: Backend, cmd: Command, rv: RetVal) -> bool:
    """A `lock` the device refused because this very session holds the lock (a script that
    starts with `lock` run again in a kept session): the seed's lock is valid only when
    unlocked, so the device refuses; the tool asks who owns it and says it is already done."""
    if cmd.field != "lock" or rv.ret_code != pb.CMD_WRONG_STATE_ERR:
        return False
    try:
        st = send(backend, COMMANDS["get_motion_control_state"], {}, wait_s=None)
    except LandscapeError:
        return False
    return st.ok and bool(st.result.get("owner"))


def say_relocked(st: CliState, cmd: Command, rv: RetVal) -> None:
    if st.json_out:
        click.echo(json.dumps({"command": cmd.cli_name, "ret_code": rv.ret_code, "ret_name": rv.ret_name,
                               "ret_msg": rv.ret_msg, "result": {}, "notices": [], "note": RELOCK_NOTE}))
    else:
        click.echo(f"{cmd.cli_name}: {RELOCK_NOTE}")


def session_units(backend: Backend) -> Units | None:
    """The units the session speaks in (getUnits), or None when the device does not answer them."""
    try:
        rv = send(backend, COMMANDS["get_units"], {}, wait_s=None)
    except LandscapeError:
        return None
    return Units.from_result(rv.result) if rv.ok else None


class UnitsWatch:
    """The session's units for a display that runs on (monitor, events): through a background
    session another terminal's set-units changes them under it, so `poll` asks again (getUnits,
    at most once per `period_s`) and says when they changed. Without one no one else speaks in
    this session: `follow` False asks once."""

    def __init__(self, backend: Backend, *, follow: bool, period_s: float = 1.0) -> None:
        import time

        self._backend = backend
        self._follow = follow
        self._period_s = period_s
        self.units = session_units(backend)
        self._next = time.monotonic() + period_s

    def poll(self) -> bool:
        """True when the units changed since the last look (self.units holds the new ones)."""
        import time

        if not self._follow or time.monotonic() < self._next:
            return False
        self._next = time.monotonic() + self._period_s
        now = session_units(self._backend)
        if now is None or now == self.units:
            return False
        self.units = now
        return True


def stop_after_interrupt(st: CliState, cmd: Command) -> None:
    """Ctrl-C while a motion command runs: send stopMotion (the move pauses; resume-motion
    continues it, abort-motion ends it) and say so on stderr. Never raises."""
    import signal

    old = signal.signal(signal.SIGINT, signal.SIG_IGN)  # a second Ctrl-C must not cut the stop short
    try:
        try:
            if st.client is not None or (st.sup is None and st.follow_motions and not st.no_session):
                # Our connection may be mid-stream: the stop goes through a connection of its own.
                if st.client is not None:
                    st.client.close()
                    st.client = None
                stopper = SessionClient.attach(st.socket_path())
                if stopper is None:
                    raise LandscapeError("the background session went away")
                with stopper:
                    rv = stopper.request("stop_motion", check=False, timeout_s=1.0)
            elif st.sup is not None and st.sup.connected:
                rv = st.sup.request("stop_motion", check=False, timeout_s=1.0)
            else:
                return
        except (LandscapeError, OSError) as exc:
            click.echo(f"landscape: {cmd.cli_name} interrupted; stop-motion could not be sent ({one_line(exc)}): "
                       f"the arm may still move, use `landscape stop-motion` or the emergency stop", err=True)
            return
        if rv.ok:
            click.echo(f"landscape: {cmd.cli_name} interrupted: stop-motion sent ({rv.ret_name}); the motion "
                       f"is paused: resume-motion continues it, abort-motion ends it", err=True)
        else:
            click.echo(f"landscape: {cmd.cli_name} interrupted: stop-motion answered {rv.ret_name}"
                       + (f" ({rv.ret_msg})" if rv.ret_msg else "") + " (nothing was moving)", err=True)
    finally:
        signal.signal(signal.SIGINT, old)


def check_outcome(cmd: Command, rv: RetVal, final: pb.Notice | None, *, wait: bool, wait_timeout_s: float) -> None:
    """Raise CommandFailed (negative code, alarm) or ControllerTimeoutError (no final notice)."""
    if rv.ret_code < 0:
        raise CommandFailed(one_line(error_for_code(cmd.cli_name, rv.ret_code, rv.ret_msg)))
    if rv.started and wait:
        if final is None:
            raise ControllerTimeoutError(f"{cmd.cli_name}: no final notice within {wait_timeout_s:g} s "
                                         f"(--wait-timeout); check get-motion-control-state")
        if final.kind in (pb.ALARM, pb.ALARM_RSVP):
            raise CommandFailed(str(AlarmError(final, cmd.cli_name)))


def make_command(cmd: Command) -> click.Command:
    """The subcommand of `cmd`. `connect` takes no arguments (the session always runs the
    handshake first; the subcommand prints its result); `disconnect` ends the session."""
    def callback(**kwargs: Any) -> RetVal:
        ctx = click.get_current_context()
        no_wait = kwargs.pop("_no_wait", False)
        wait_timeout = kwargs.pop("_wait_timeout", 60.0)
        fields = {k: (list(v) if isinstance(v, tuple) else v) for k, v in kwargs.items()}
        fields = {k: v for k, v in fields.items() if v is not None}
        return execute(ctx, cmd, fields, wait=not no_wait, wait_timeout_s=wait_timeout)

    help_text = f"{cmd.summary}\n\n{cmd.contract('non-blocking: waits for its final event or alarm')}"
    for f in cmd.fields():
        if f.type == FieldDescriptor.TYPE_ENUM:
            names = " | ".join(v.name for v in field_enum_type(f).values)
            help_text += f"\n\n{f.name.upper()}: {names} (any case; suffix optional)"
    if cmd.field in COMMAND_HELP:
        help_text += "\n\n" + COMMAND_HELP[cmd.field]
    params = [] if cmd.field == "connect" else cli_params(cmd)
    if cmd.field == "connect":
        help_text += "\n\nEvery invocation connects first; this command prints the device description."
    has_variadic = any(isinstance(p, click.Argument) and p.nargs == -1 for p in params)
    return click.Command(cmd.cli_name, callback=callback, params=params, help=help_text,
                         short_help=cmd.summary,
                         context_settings={"ignore_unknown_options": True} if has_variadic else {})


# ---------------------------------------------------------------- the group


def one_line(exc: object) -> str:
    return " ".join(str(exc).split())


class LandscapeGroup(click.Group):
    """Maps every error to one line on stderr and an exit code (module docstring)."""

    def main(self, args: Sequence[str] | None = None, prog_name: str | None = None,
             complete_var: str | None = None, standalone_mode: bool = True, **extra: Any) -> Any:
        code = self.run(args, "landscape", **extra)
        if standalone_mode:
            sys.exit(code)
        return code

    def run(self, args: Sequence[str] | None, prog_name: str, **extra: Any) -> int:
        old_hook = threading.excepthook
        threading.excepthook = _thread_failed
        try:
            super().main(args=list(args) if args is not None else None, prog_name=prog_name,
                         standalone_mode=False, **extra)
            return EXIT_OK
        except click.exceptions.Exit as exc:
            return exc.exit_code
        except click.exceptions.Abort:
            click.echo(f"{prog_name}: interrupted", err=True)
            return EXIT_INTERRUPTED
        except click.UsageError as exc:
            hint = f" (try '{exc.ctx.command_path} --help')" if exc.ctx is not None else ""
            click.echo(f"{prog_name}: error: {one_line(exc.format_message())}{hint}", err=True)
            return EXIT_USAGE
        except click.ClickException as exc:
            click.echo(f"{prog_name}: error: {one_line(exc.format_message())}", err=True)
            return exc.exit_code
        except BaseException as exc:  # noqa: BLE001 (mapped below, never a traceback)
            code, line = classify(exc)
            if code is None:
                raise
            if line:
                click.echo(f"{prog_name}: {line}", err=True)
            return code
        finally:
            threading.excepthook = old_hook


def _thread_failed(args: threading.ExceptHookArgs) -> None:
    """An exception that ended a thread of a library below us (python-can, can-isotp) when
    the link died: logged (-vv shows it), never a traceback; the command's own error line
    says what happened."""
    if args.exc_type is SystemExit:
        return
    log.debug("thread %s ended: %s: %s", args.thread.name if args.thread else "?",
              args.exc_type.__name__, args.exc_value)


def classify(exc: BaseException) -> tuple[int | None, str]:
    """Exit code and one-line message of an exception (None: not ours, re-raise)."""
    if isinstance(exc, KeyboardInterrupt):
        return EXIT_INTERRUPTED, "interrupted"
    if isinstance(exc, AlreadyReported):
        return exc.code, ""
    if isinstance(exc, CommandFailed):
        return exc.code, one_line(exc)
    if isinstance(exc, ArgumentError):
        return EXIT_USAGE, "error: " + one_line(exc)
    if isinstance(exc, (CommandError, AlarmError)):
        return EXIT_COMMAND, one_line(exc)
    if isinstance(exc, (BusError, ControllerTimeoutError)):
        return EXIT_BUS, one_line(exc)
    if isinstance(exc, can.CanError):  # python-can below us: the bus failed under a command
        return EXIT_BUS, f"the CAN bus failed: {one_line(exc)}"
    if isinstance(exc, VersionMismatchError):
        return EXIT_VERSION, "version mismatch: " + one_line(exc)
    if isinstance(exc, (ProtocolError, LandscapeError)):
        return EXIT_ERROR, one_line(exc)
    if isinstance(exc, OSError):
        return EXIT_ERROR, f"error: {one_line(exc)}"
    return None, ""


def _addr(value: str) -> int:
    try:
        v = int(value, 0)
    except ValueError:
        raise click.BadParameter(f"'{value}' is not a node address (e.g. 0x10)") from None
    if not 0 <= v <= 0xFF:
        raise click.BadParameter(f"{value} is outside 0x00..0xFF")
    return v


def _verbose_logging(ctx: click.Context, verbose: int) -> None:
    """-v: the landscape loggers (requests, answers, notices) on stderr; -vv: every logger at debug."""
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter("%(name)s: %(message)s"))
    ours = logging.getLogger("landscape")
    old_level, old_propagate = ours.level, ours.propagate
    ours.addHandler(handler)
    ours.setLevel(logging.DEBUG if verbose > 1 else logging.INFO)
    ours.propagate = False
    if verbose > 1:
        logging.basicConfig(level=logging.DEBUG, stream=sys.stderr, format="%(name)s: %(message)s")

    def restore() -> None:
        ours.removeHandler(handler)
        ours.setLevel(old_level)
        ours.propagate = old_propagate
    ctx.call_on_close(restore)


def _print_version(ctx: click.Context, param: click.Parameter, value: bool) -> None:
    if not value or ctx.resilient_parsing:
        return
    from importlib.metadata import PackageNotFoundError, version

    from .registry import PROTOCOL_VERSION, SCHEMA_HASH
    try:
        v = version("landscape")
    except PackageNotFoundError:
        v = "(not installed)"
    click.echo(f"landscape {v} (protocol {PROTOCOL_VERSION}, schema {SCHEMA_HASH:08X})")
    ctx.exit(0)


@click.group(cls=LandscapeGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.option("--interface", "-i", default=None,
              help="python-can interface (default: python-can config / CAN_INTERFACE)")
@click.option("--channel", "-c", default=None,
              help="channel, e.g. the pty of landscaped (default: config / CAN_CHANNEL)")
@click.option("--bitrate", "-b", type=int, default=None, help="bit rate (slcan default 1000000)")
@click.option("--device", "-d", default=f"{DEFAULT_DEVICE:#04x}", show_default=True, callback=lambda c, p, v: _addr(v),
              help="node address of the controller")
@click.option("--source-address", "-s", default=None, metavar="ADDR",
              callback=lambda c, p, v: None if v is None else _addr(v),
              help=f"node address of this supervisor (default: a free one of {HOST_POOL[0]:#04x}.."
                   f"{HOST_POOL[-1]:#04x}, picked at connect)")
@click.option("--timeout", "-t", type=float, default=None,
              help="seconds to wait for each response try (default: the command's host_timeout_ms)")
@click.option("--can-context", default=None, metavar="NAME",
              help="python-can config context: section [NAME] of the config file, CAN_INTERFACE_NAME ...")
@click.option("--can-config", default=None, metavar="FILE",
              help="python-can config file to read instead of ~/can.conf, /etc/can.conf, ~/.can, ~/.canrc")
@click.option("--key-file", default=None, metavar="FILE", envvar="LANDSCAPE_KEY_FILE",
              help="sign the session with a key of this file (NAME = 64 hex digits per line, mode 0600; "
                   "env LANDSCAPE_KEY_FILE)")
@click.option("--key-id", default=None, metavar="NAME", envvar="LANDSCAPE_KEY_ID",
              help="which key of --key-file (default: its only one; env LANDSCAPE_KEY_ID)")
@click.option("--no-session", is_flag=True,
              help="open a session of our own even when a background session (landscape session start) runs")
@click.option("--json", "json_out", is_flag=True, help="print one JSON object per command")
@click.option("--verbose", "-v", count=True,
              help="show each request, its answer and its notices on stderr (-vv: every protocol detail)")
@click.option("--version", is_flag=True, expose_value=False, is_eager=True, callback=_print_version,
              help="print the tool's version, protocol version and schema hash, then exit")
@click.pass_context
def cli(ctx: click.Context, interface: str | None, channel: str | None, bitrate: int | None, device: int,
        source_address: int | None, timeout: float | None, can_context: str | None, can_config: str | None,
        key_file: str | None, key_id: str | None, no_session: bool, json_out: bool, verbose: int) -> None:
    """Command a LandScape controller (landscaped) over CAN.

    Every schema command is a subcommand (landscape COMMAND --help). Exit codes: 0 ok,
    1 protocol error, 2 usage, 3 command error or alarm, 4 bus or time-out, 5 version mismatch.
    """
    if verbose:
        _verbose_logging(ctx, verbose)
    st = CliState(BusSpec(interface, channel, bitrate, can_context, can_config), device, source_address, timeout,
                  json_out, no_session=no_session, key_file=key_file, key_id=key_id)
    ctx.obj = st
    ctx.call_on_close(st.close)


for _cmd in COMMANDS.values():
    cli.add_command(make_command(_cmd))

