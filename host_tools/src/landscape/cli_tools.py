"""The `path`, `teach`, `record`, `plot`, `demo` and `session` subcommands of the landscape CLI.

They follow the rules of cli.py: every error is one line on stderr and an exit
code (docs/host-tool.md); commands go through the background session when one
runs (CliState.backend), else through the invocation's own session.
"""
from __future__ import annotations

import json
import logging
import os
import queue
import select
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import click

from ._generated import landscape_pb2 as pb
from .backend import Backend
from .bus import SLCAN_DEFAULT_BITRATE, resolve_config
from .cli_core import (
    EXIT_COMMAND,
    EXIT_ERROR,
    CliState,
    CommandFailed,
    EnumType,
    UnitsWatch,
    call,
    classify,
    cli,
    execute,
    fmt_notice,
    fmt_value,
    one_line,
    send,
    session_units,
    state_of,
)
from .demo import StepResult, demo_steps, run_demo
from .errors import LandscapeError, error_for_code
from .link import LinkBroker, is_local_line, pid_alive
from .mcap_log import ChannelWriter, McapRecorder
from .notices import Units, format_notice
from .paths import build_path_load_requests, load_path_file, request_fields, resolve_settings
from .plotting import KINDS, plot
from .record_files import open_recorder, read_recording
from .recording import Recorder, record_format
from .registry import lookup, message_to_dict
from .retval import RetVal
from .session import SessionClient, SessionError, SessionServer
from .supervisor import Supervisor
from .teach import POINT_KINDS, append_taught
from .urdf import robot_urdf, urdf_text, write_urdf


def _stdout_is_tty() -> bool:
    """Whether stdout is a terminal (a seam for the tests of the progress bar)."""
    return sys.stdout.isatty()


# ---------------------------------------------------------------- path


@cli.group("path")
def path_group() -> None:
    """Load named paths from point files (CSV, YAML, JSON), run and clear them."""


def path_points_limit(backend: Backend) -> int | None:
    """The points one path holds on the device (describe: max_points_per_path): the bound a
    path file is read with. None when the device did not describe itself (a lossy link:
    the session checks requests against the host's copy of the schema, which has no tables)."""
    desc = backend.device_description()
    if desc is None or not desc.from_device:
        return None
    return int(desc.res.max_points_per_path) or None


@path_group.command("load")
@click.argument("file", type=click.Path(dir_okay=False, path_type=Path))
@click.option("--name", "path_name", default=None, help="path name (default: the file's `path`, else its stem)")
@click.option("--frame", type=EnumType(pb.ReferenceFrame.DESCRIPTOR), default=None,
              help="default: the file's, else JOINT_FRAME for j1.. columns, BASE_CARTESIAN_FRAME for x..yaw")
@click.option("--motion-type", type=EnumType(pb.MotionType.DESCRIPTOR), default=None,
              help="default: the file's, else JOINT_MOTION for joint values, STRAIGHT_MOTION for poses")
@click.option("--offset-type", type=EnumType(pb.OffsetType.DESCRIPTOR), default=None,
              help="default: the file's, else ABSOLUTE_DATA")
@click.pass_context
def path_load_cmd(ctx: click.Context, file: Path, path_name: str | None, frame: int | None,
                  motion_type: int | None, offset_type: int | None) -> None:
    """Append the points of FILE to a path: the whole file is checked first (against the
    device's points per path), then sent in as many pathLoad messages as the firmware needs
    (docs/host-tool.md lists the columns)."""
    st = state_of(ctx)
    backend = st.backend()
    pf = load_path_file(file, max_points=path_points_limit(backend))  # a bad file never reaches the device
    s = resolve_settings(pf, path_name=path_name, frame=frame, motion_type=motion_type, offset_type=offset_type)
    reqs = build_path_load_requests(s.path_name, pf.points, frame=s.frame, motion_type=s.motion_type,
                                    offset_type=s.offset_type)
    cmd = lookup("path_load")
    total = len(pf.points)
    bar = None
    if not st.json_out and _stdout_is_tty():
        from rich.console import Console
        from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

        bar = Progress(TextColumn("loading {task.description}"), BarColumn(), MofNCompleteColumn(),
                       TextColumn("points"), TimeElapsedColumn(), console=Console(file=sys.stdout,
                                                                                  force_terminal=True))
        bar.start()
        task = bar.add_task(s.path_name, total=total)
    sent = 0
    rv: RetVal | None = None
    try:
        for i, req in enumerate(reqs):
            rv = send(backend, cmd, request_fields(req), wait_s=None)
            if rv.ret_code < 0:
                rv.ret_msg = (f"{rv.ret_msg} (message {i + 1} of {len(reqs)}; {sent} of {total} points were "
                              f"loaded: `landscape path clear {s.path_name}` to start over)").lstrip()
                break
            sent += len(req.path_load.tags)
            if bar is not None:
                bar.update(task, completed=sent)
    finally:
        if bar is not None:
            bar.stop()
    assert rv is not None
    result = {"path_name": s.path_name, "frame": pb.ReferenceFrame.Name(s.frame),
              "motion_type": pb.MotionType.Name(s.motion_type), "offset_type": pb.OffsetType.Name(s.offset_type),
              "points_sent": sent, "messages": len(reqs),
              "points_in_path": rv.result.get("points_in_path") if rv.ret_code >= 0 else None}
    if st.json_out:
        click.echo(json.dumps({"command": "path load", "ret_code": rv.ret_code, "ret_name": rv.ret_name,
                               "ret_msg": rv.ret_msg, "result": result, "notices": []}))
    elif rv.ret_code >= 0:
        click.echo(f"path load: {rv.ret_name}")
        for k, v in result.items():
            click.echo(f"  {k}: {fmt_value(v)}")
    if rv.ret_code < 0:
        raise CommandFailed(one_line(error_for_code("path load", rv.ret_code, rv.ret_msg)))


@path_group.command("clear")
@click.argument("name")
@click.pass_context
def path_clear_cmd(ctx: click.Context, name: str) -> None:
    """Delete path NAME on the device (pathClearPath)."""
    execute(ctx, lookup("path_clear_path"), {"path_name": name})


@path_group.command("run")
@click.argument("name")
@click.option("--cycles", type=click.IntRange(min=0), default=1, show_default=True,
              help="how many times to run it (0: dry run without auxiliary commands)")
@click.option("--wait-timeout", type=float, default=300.0, show_default=True,
              help="seconds to wait for the path's end")
@click.pass_context
def path_run_cmd(ctx: click.Context, name: str, cycles: int, wait_timeout: float) -> None:
    """Run path NAME (pathMove), print its tag events as they come and wait for its end."""
    execute(ctx, lookup("path_move"), {"path_name": name, "number_of_cycles": cycles}, wait=True,
            wait_timeout_s=wait_timeout)


@cli.command("teach")
@click.argument("file", type=click.Path(dir_okay=False, path_type=Path))
@click.argument("name")
@click.option("--kind", type=click.Choice(POINT_KINDS), default=None,
              help="what a new FILE holds: joint values (default) or the tool tip's world pose; an existing "
                   "file keeps its kind")
@click.pass_context
def teach_cmd(ctx: click.Context, file: Path, name: str, kind: str | None) -> None:
    """Append where the arm is now to path file FILE as a point tagged NAME, in the session's
    units (getRobotPosition); `path load FILE` reads it back (docs/host-tool.md "teach")."""
    st = state_of(ctx)
    backend = st.backend()
    cmd = lookup("get_robot_position")
    rv = send(backend, cmd, {}, wait_s=None)
    if not rv.ok:
        raise CommandFailed(one_line(error_for_code("teach", rv.ret_code, rv.ret_msg)))
    written, count = append_taught(file, name, joints=list(rv.result.get("joints", [])),
                                   world_pose=list(rv.result.get("world_pose", [])), kind=kind)
    units = session_units(backend) or Units()
    unit = units.angular if written == "joint" else units.describe()
    if st.json_out:
        click.echo(json.dumps({"command": "teach", "ret_code": rv.ret_code, "ret_name": rv.ret_name, "ret_msg": "",
                               "result": {"file": str(file), "tag_name": name, "kind": written, "points": count,
                                          "units": unit}, "notices": []}))
    else:
        click.echo(f"teach: {name} appended to {file} ({written} values in {unit}; point {count})")


# ---------------------------------------------------------------- record, plot


class Follow:
    """What follows the device for record, events and the demo: call it (or stop()) to stop;
    check() raises what ended it early (the device went away, the session stopped)."""

    def __init__(self, stop: Callable[[], None] = lambda: None, sup: Supervisor | None = None) -> None:
        self.on_stop = stop
        self._sup = sup
        self.stopping = False
        self.error: LandscapeError | None = None

    def __call__(self) -> None:
        self.stop()

    def stop(self) -> None:
        self.stopping = True
        self.on_stop()

    def check(self) -> None:
        if self._sup is not None:
            self._sup.check_link()
        if self.error is not None:
            raise self.error

    def pump(self, watcher: SessionClient, items: Callable[[], Any], fn: Callable[[str, Any, float], None]) -> None:
        """In a thread: feed fn from a watch connection until stop(), or record why it ended."""
        try:
            for kind, item, ts in items():
                fn(kind, item, ts)
        except (OSError, ValueError, LandscapeError) as exc:
            if not self.stopping:
                self.error = exc if isinstance(exc, LandscapeError) else SessionError(
                    f"the session at {watcher.path} went away ({exc}): check `landscape session status`")


def device_urdf(backend: Backend) -> str:
    """The URDF of the arm the device runs (describeRobot), through our own session or the background one."""
    cmd = lookup("describe_robot")
    return robot_urdf(lambda offset: send(backend, cmd, {"offset": offset}, wait_s=None))


def start_recording(st: CliState, rec: Recorder | ChannelWriter) -> Follow:
    """Feed `rec` from the background session (a watch connection of its own) or from the
    invocation's own session; returns the Follow that stops it. Raw CAN frames (MCAP) come
    from the own session only: the background session forwards broadcasts and notices. An
    MCAP recording or a live view draws the device's own URDF (ChannelWriter.use_robot)."""
    if isinstance(rec, ChannelWriter):
        rec.use_robot(device_urdf(st.backend()))
    client = st.background()
    if client is None:
        sup = st.session()
        sup.on_telemetry(rec.broadcast)
        sup.on_notice(rec.notice)
        frames = rec.frame if isinstance(rec, ChannelWriter) else None
        if frames is not None:
            sup.add_frame_listener(frames)

        def stop_own() -> None:
            sup.remove_telemetry_callback(rec.broadcast)
            sup.remove_notice_callback(rec.notice)
            if frames is not None:
                sup.remove_frame_listener(frames)
        return Follow(stop_own, sup)
    watcher = SessionClient.attach(client.path)
    if watcher is None:
        raise SessionError(f"the session at {client.path} went away: check `landscape session status`")

    def feed(kind: str, item: Any, ts: float) -> None:
        if kind == "broadcast":
            rec.broadcast(item)
        else:
            rec.notice(item, ts)

    follow = Follow()
    t = threading.Thread(target=follow.pump, args=(watcher, watcher.watch, feed), daemon=True,
                         name="landscape-record")

    def stop_watch() -> None:
        watcher.close()
        t.join(2.0)
    follow.on_stop = stop_watch
    t.start()
    return follow


@cli.command("record")
@click.argument("file", type=click.Path(dir_okay=False, path_type=Path))
@click.option("--duration", type=click.FloatRange(min=0, min_open=True), default=None,
              help="seconds to record (default: until Ctrl-C)")
@click.pass_context
def record_cmd(ctx: click.Context, file: Path, duration: float | None) -> None:
    """Record telemetry (JOINTS_12/34/56, TOOL_POS, TOOL_RPY, STATUS, DIO) and notices to FILE:
    MCAP for .mcap (joint states, link transforms for the URDF of `landscape urdf`, tool pose,
    status, DIO, notices as logs, raw CAN frames), CSV for .csv, JSON lines for .jsonl/.json/.ndjson."""
    st = state_of(ctx)
    record_format(file)  # a name it cannot record to fails before the bus is opened
    st.backend()  # connect first (picking a free address takes a moment): --duration is recording time
    rec = open_recorder(file)
    t0 = time.monotonic()
    progress = sys.stderr.isatty() and not st.json_out
    try:
        stop = start_recording(st, rec)
        try:
            next_report = t0 + 1.0
            while duration is None or time.monotonic() - t0 < duration:
                time.sleep(0.05 if duration is None else min(0.05, max(0.0, duration - (time.monotonic() - t0))))
                stop.check()
                if progress and time.monotonic() >= next_report:
                    next_report += 1.0
                    click.echo(f"\rrecord: {time.monotonic() - t0:5.0f} s, {rec.broadcasts} broadcasts, "
                               f"{rec.notices} notices", nl=False, err=True)
        except KeyboardInterrupt:
            pass  # Ctrl-C is how an open-ended recording ends
        finally:
            stop()
            if progress:
                click.echo("", err=True)
    finally:
        rec.close()
    summary: dict[str, Any] = {"file": str(file), "broadcasts": rec.broadcasts, "notices": rec.notices,
                               "seconds": round(time.monotonic() - t0, 3)}
    if isinstance(rec, McapRecorder):
        summary["frames"] = rec.frames
        summary["channels"] = dict(rec.counts)
    if st.json_out:
        click.echo(json.dumps({"command": "record", "result": summary}))
    else:
        extra = ""
        if isinstance(rec, McapRecorder):
            extra = f", {rec.frames} CAN frames, {rec.messages} messages on {len(rec.counts)} channels"
        click.echo(f"record: {rec.broadcasts} broadcasts and {rec.notices} notices{extra} in "
                   f"{summary['seconds']:g} s to {file}")


@cli.command("events")
@click.option("--duration", type=click.FloatRange(min=0, min_open=True), default=None,
              help="seconds to follow (default: until Ctrl-C)")
@click.pass_context
def events_cmd(ctx: click.Context, duration: float | None) -> None:
    """Follow the device's notices live: events, alarms, RSVPs, tags, signal-digital-io callbacks
    and the final notices of --no-wait moves, one line each with the host's time.

    With a background session running, every notice the session receives (the commands of
    every terminal); else the notices sent to this invocation's own session. Positions in
    notices are in the session's units (named in the first line). Ctrl-C ends it (exit 0)."""
    st = state_of(ctx)
    client = st.background()
    watch = UnitsWatch(st.backend(), follow=client is not None)
    units = watch.units
    where = f"device {st.device:#04x} on {st.spec.describe()}" + (" (via the session)" if client else "")
    units_text = (f"positions in {units.describe()} (get-units)" if units is not None
                  else "units unknown (get-units failed)")
    if st.json_out:
        click.echo(json.dumps({"command": "events", "device": st.device, "via_session": client is not None,
                               "units": None if units is None else {"linear": units.linear,
                                                                    "angular": units.angular}}))
    else:
        click.echo(f"events: {where}; {units_text}; Ctrl-C ends")
        if client is None:
            click.echo("events: no background session: only the notices of this invocation's own session show; "
                       "`landscape session start` to follow every command's", err=True)
    sys.stdout.flush()
    q: queue.Queue[tuple[pb.Notice, float]] = queue.Queue(maxsize=10000)
    stop = _follow_notices(st, client, lambda n, ts: q.put((n, ts)))
    end = None if duration is None else time.monotonic() + duration
    try:
        while end is None or time.monotonic() < end:
            left = 0.2 if end is None else max(0.0, min(0.2, end - time.monotonic()))
            if watch.poll() and watch.units is not None:  # another terminal's set-units
                u = watch.units
                click.echo(json.dumps({"units": {"linear": u.linear, "angular": u.angular}}) if st.json_out
                           else f"events: positions now in {u.describe()} (set-units)")
                sys.stdout.flush()
            try:
                n, _ = q.get(timeout=left)
            except queue.Empty:
                stop.check()
                continue
            now = time.time()
            if st.json_out:
                click.echo(json.dumps({"time": round(now, 3), "notice": message_to_dict(n)}))
            else:
                click.echo(time.strftime("%H:%M:%S", time.localtime(now)) + f".{int(now * 1000) % 1000:03d} "
                           + format_notice(n))
            sys.stdout.flush()
    except KeyboardInterrupt:
        pass  # Ctrl-C is how an open-ended follow ends
    finally:
        stop()


def _follow_notices(st: CliState, client: SessionClient | None,
                    fn: Callable[[pb.Notice, float], None]) -> Follow:
    """Call fn(notice, host time) for every notice of the background session (a watch connection
    of its own) or of the invocation's own session; returns the Follow that stops it."""
    if client is None:
        sup = st.session()

        def on_n(n: pb.Notice) -> None:
            fn(n, time.monotonic())
        sup.on_notice(on_n)
        return Follow(lambda: sup.remove_notice_callback(on_n), sup)
    watcher = SessionClient.attach(client.path)
    if watcher is None:
        raise SessionError(f"the session at {client.path} went away: check `landscape session status`")
    follow = Follow()

    def notices() -> Any:
        return watcher.watch(notices_only=True)

    def feed(_kind: str, item: Any, ts: float) -> None:
        fn(item, ts)
    t = threading.Thread(target=follow.pump, args=(watcher, notices, feed), daemon=True, name="landscape-events")

    def stop_watch() -> None:
        watcher.close()
        t.join(2.0)
    follow.on_stop = stop_watch
    t.start()
    return follow


@cli.command("urdf")
@click.option("-o", "--output", "out", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="file to write (default: stdout)")
@click.option("--packaged", is_flag=True,
              help="the URDF of the default arm (ls-sim6) shipped with this package, without a device")
@click.pass_context
def urdf_cmd(ctx: click.Context, out: Path | None, packaged: bool) -> None:
    """The URDF of the arm the device runs (written from its robot model, describeRobot), for a 3D viewer."""
    text = urdf_text() if packaged else device_urdf(state_of(ctx).backend())
    if out is None:
        click.echo(text, nl=False)
    else:
        write_urdf(out, text)
        click.echo(f"urdf: wrote {out}")


@cli.command("plot")
@click.argument("file", type=click.Path(dir_okay=False, path_type=Path))
@click.option("-o", "--output", "out", type=click.Path(dir_okay=False, path_type=Path), required=True,
              help="image to write (PNG; the suffix chooses the format)")
@click.option("--kind", type=click.Choice(KINDS), default="joints", show_default=True,
              help="joints: positions over time; velocity: joint velocities over time; following: commanded minus "
                   "measured positions over time; path: the tool position in 3-D")
def plot_cmd(file: Path, out: Path, kind: str) -> None:
    """Plot a recording of `landscape record` (.mcap, .csv or .jsonl; no bus needed)."""
    plot(read_recording(file), out, kind)
    click.echo(f"plot: wrote {out} ({kind})")


# ---------------------------------------------------------------- demo


@cli.command("demo")
@click.option("--record", "record_file", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="record telemetry and notices during the demo (.csv or .jsonl)")
@click.option("--plot", "plot_file", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="plot the joints to this PNG (and the tool path to <name>-path.png)")
@click.option("--path-file", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="the Cartesian path to run instead of the built-in square")
@click.option("--wait-timeout", type=float, default=120.0, show_default=True,
              help="seconds to wait for each motion's end")
@click.pass_context
def demo_cmd(ctx: click.Context, record_file: Path | None, plot_file: Path | None, path_file: Path | None,
             wait_timeout: float) -> None:
    """Lock, activate, joint moves, a tagged Cartesian path, deactivate, release. Commands this
    firmware does not implement are skipped; exit 0 when every implemented step succeeded."""
    st = state_of(ctx)
    backend = st.backend()
    steps = demo_steps(load_path_file(path_file, max_points=path_points_limit(backend))
                       if path_file is not None else None)
    rec_path = record_file
    if plot_file is not None and rec_path is None:
        rec_path = Path(tempfile.mkstemp(prefix="landscape-demo-", suffix=".csv")[1])
    rec = open_recorder(rec_path) if rec_path is not None else None
    backend.confirm_every_rsvp()  # the demo goes on
    info = send(backend, lookup("connect"), {}, wait_s=None)
    if not st.json_out:
        r = info.result
        click.echo(f"demo: device '{r.get('device_name', '?')}' (firmware {r.get('firmware_version', '?')}, "
                   f"{r.get('joint_count', '?')} joints), state {r.get('state', '?')}")
    stop_rec = start_recording(st, rec) if rec is not None else None
    n = len(steps)
    index = {id(s): i + 1 for i, s in enumerate(steps)}
    notices_of: dict[int, list[pb.Notice]] = {}

    def head(step: Any) -> str:
        return f"[{index[id(step)]}/{n}] {step.title} ({lookup(step.command).cli_name})"

    def do_call(command: str, fields: dict[str, Any], wait: bool) -> tuple[RetVal, pb.Notice | None]:
        step = next(s for s in steps if s.command == command and s.fields is fields)
        if not st.json_out:
            click.echo(head(step))
        got: list[pb.Notice] = []
        notices_of[id(step)] = got

        def on_notice(nt: pb.Notice) -> None:
            got.append(nt)
            if not st.json_out:
                click.echo(fmt_notice(nt))
        rv, _, final = call(backend, lookup(command), fields, wait=wait, wait_timeout_s=wait_timeout,
                            on_notice=on_notice)
        return rv, final

    def report(res: StepResult) -> None:
        step = res.step
        if st.json_out:
            rv = res.retval
            click.echo(json.dumps({
                "step": step.key, "title": step.title, "command": lookup(step.command).cli_name,
                "status": res.status, "detail": res.detail,
                "ret_code": rv.ret_code if rv else None, "ret_name": rv.ret_name if rv else None,
                "ret_msg": rv.ret_msg if rv else None, "result": rv.result if rv else {},
                "notices": [message_to_dict(x) for x in notices_of.get(id(step), [])]}))
            return
        if res.retval is None:
            click.echo(head(step))
        if res.status == "ok" and res.retval is not None:
            extra = "; ".join(f"{k}: {fmt_value(v)}" for k, v in res.retval.result.items())
            click.echo("    ok" + (f" ({extra})" if extra else ""))
        elif res.status == "tolerated":
            click.echo(f"    nothing to do ({res.detail})")
        elif res.status == "failed":
            click.echo(f"    FAILED: {res.detail}")
        else:
            click.echo(f"    {res.detail}")

    try:
        result = run_demo(do_call, report, steps=steps)
    finally:
        if stop_rec is not None:
            stop_rec()
        if rec is not None:
            rec.close()
    ok = sum(r.status in ("ok", "tolerated") for r in result.results)
    skipped = sum(r.status == "skipped" for r in result.results)
    if not st.json_out:
        click.echo(f"demo: {ok} steps ok, {skipped} skipped, {len(result.failed)} failed")
        if record_file is not None:
            click.echo(f"demo: recorded to {record_file}")
    if plot_file is not None and rec_path is not None:
        recording = read_recording(rec_path)
        written = [plot(recording, plot_file, "joints")]
        if recording.series.get("TOOL_POS"):
            written.append(plot(recording, plot_file.with_name(plot_file.stem + "-path" + plot_file.suffix), "path"))
        if not st.json_out:
            click.echo("demo: plotted " + ", ".join(str(w) for w in written))
        if record_file is None:
            rec_path.unlink(missing_ok=True)
    if result.failed:
        first = result.failed[0]
        raise CommandFailed(f"demo: step '{first.step.title}' failed: {first.detail}", EXIT_COMMAND)


# ---------------------------------------------------------------- session


def _global_args(st: CliState) -> list[str]:
    out: list[str] = []
    spec = st.spec
    for opt, value in (("--interface", spec.interface), ("--channel", spec.channel), ("--bitrate", spec.bitrate),
                       ("--can-context", spec.context), ("--can-config", spec.config_file),
                       ("--timeout", st.timeout_s), ("--key-file", st.key_file), ("--key-id", st.key_id)):
        if value is not None:
            out += [opt, str(value)]
    out += ["--device", f"{st.device:#04x}"]
    if st.source_address is not None:  # else the session picks a free address itself
        out += ["--source-address", f"{st.source_address:#04x}"]
    return out


def _no_session(st: CliState) -> SessionError:
    return SessionError(f"no session runs for device {st.device:#04x} on {st.spec.describe()} (no socket "
                        f"{st.socket_path()}): start one with `landscape session start`")


@cli.group("session")
def session_group() -> None:
    """A background process holding one session; other invocations use it (docs/host-tool.md)."""


@session_group.command("start")
@click.option("--lock", is_flag=True, help="lock the device once connected (the lock lives until stop)")
@click.option("--start-timeout", type=float, default=20.0, show_default=True,
              help="seconds to wait for the background process to connect")
@click.pass_context
def session_start_cmd(ctx: click.Context, lock: bool, start_timeout: float) -> None:
    """Start the background session of this bus and device."""
    st = state_of(ctx)
    path = st.socket_path()
    running = SessionClient.attach(path, on_stale=lambda msg: click.echo(f"landscape: {msg}", err=True))
    if running is not None:
        with running:
            pid = running.status().get("pid")
        raise SessionError(f"a session already runs for device {st.device:#04x} on {st.spec.describe()} "
                           f"(pid {pid}, socket {path}): `landscape session stop` first")
    pkg_parent = str(Path(__file__).resolve().parent.parent)
    env = dict(os.environ)
    env["PYTHONPATH"] = pkg_parent + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    argv = [sys.executable, "-m", "landscape", *_global_args(st), "session", "serve"] + (["--lock"] if lock else [])
    log_path = path.with_suffix(".log")
    with open(log_path, "a", encoding="utf-8") as log:
        proc = subprocess.Popen(argv, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=log,
                                start_new_session=True, env=env, text=True)
    assert proc.stdout is not None
    ready, _, _ = select.select([proc.stdout], [], [], start_timeout)
    line = proc.stdout.readline() if ready else ""
    proc.stdout.close()
    if not line:
        if proc.poll() is None:
            proc.terminate()
        raise SessionError(f"the session process did not start within {start_timeout:g} s "
                           f"(exit {proc.poll()}): see {log_path}")
    obj = json.loads(line)
    if "error" in obj:
        proc.wait(5)
        raise CommandFailed(f"session start: {obj['error']}", int(obj.get("exit", EXIT_ERROR)))
    if st.json_out:
        click.echo(json.dumps({"command": "session start", "result": obj}))
    else:
        click.echo(f"session started: pid {obj['pid']}, device {st.device:#04x} on {st.spec.describe()}"
                   + (", locked" if lock else "") + f", socket {obj['socket']}")
        if obj.get("link"):
            owned = resolve_config(st.spec, strict=False).get("channel")
            click.echo(f"  link: the session owns {owned} and shares it at "
                       f"{obj['link']}; other landscape commands use it automatically")


@session_group.command("serve", hidden=True)
@click.option("--lock", is_flag=True)
@click.pass_context
def session_serve_cmd(ctx: click.Context, lock: bool) -> None:
    """The background process (started by `session start`): reports readiness as one JSON line."""
    st = state_of(ctx)
    st.no_session = True
    broker: LinkBroker | None = None
    try:
        cfg = resolve_config(st.spec)
        channel = cfg.get("channel")
        if cfg.get("interface") == "slcan" and isinstance(channel, str) and is_local_line(channel):
            # Own the serial line and share it (landscape/link.py); our Supervisor is one client of it.
            broker = LinkBroker(channel, bitrate=int(cfg.get("bitrate") or SLCAN_DEFAULT_BITRATE))
            broker.start()
        sup = st.session()
        if lock:
            sup.lock()
        server = SessionServer(sup, st.socket_path(), channel=st.spec.describe(),
                               link_url=broker.url if broker is not None else None)
        server.bind()
    except BaseException as exc:  # noqa: BLE001 (reported to `session start` as one line)
        if broker is not None:
            broker.stop()
        code, line = classify(exc)
        print(json.dumps({"error": line or str(exc), "exit": code if code is not None else EXIT_ERROR}), flush=True)
        raise SystemExit(code if code is not None else EXIT_ERROR) from None
    print(json.dumps({"ready": True, "pid": os.getpid(), "socket": str(server.path),
                      "link": broker.url if broker is not None else None}), flush=True)
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)
    # The session log (stderr, the .log file next to the socket): requests, answers and every
    # notice, so the final notices of --no-wait moves are kept even when nobody follows them.
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter("%(asctime)s %(name)s: %(message)s"))
    ours = logging.getLogger("landscape")
    ours.addHandler(handler)
    ours.setLevel(logging.INFO)
    ours.propagate = False
    signal.signal(signal.SIGTERM, lambda *_: server.stop())
    signal.signal(signal.SIGINT, lambda *_: server.stop())
    signal.signal(signal.SIGHUP, signal.SIG_IGN)
    try:
        server.serve_forever()
    finally:
        st.close()  # disconnect while the link still carries it
        if broker is not None:
            broker.stop()


@session_group.command("status")
@click.pass_context
def session_status_cmd(ctx: click.Context) -> None:
    """Show the background session of this bus and device (exit 1 when none runs)."""
    st = state_of(ctx)
    client = st.background() if not st.no_session else SessionClient.attach(st.socket_path())
    if client is None:
        raise _no_session(st)
    s = client.status()
    if st.json_out:
        click.echo(json.dumps({"command": "session status", "result": s}))
        return
    up = time.time() - float(s.get("started_at", time.time()))
    click.echo(f"session: pid {s['pid']}, device {int(s['device']):#04x} on {s['channel']}, "
               f"source {int(s['source_address']):#04x}")
    click.echo(f"  connected: {s['connected']}  owner: {s['owner']}  state: {s['state']}")
    click.echo(f"  requests: {s['requests']}  up: {up:.0f} s  socket: {s['socket']}")
    if s.get("link"):
        click.echo(f"  link: shared at {s['link']} (python-can: --interface slcan --channel {s['link']})")


@session_group.command("stop")
@click.option("--stop-timeout", type=float, default=10.0, show_default=True)
@click.pass_context
def session_stop_cmd(ctx: click.Context, stop_timeout: float) -> None:
    """Stop the background session: it disconnects (the device releases an owner's lock)."""
    st = state_of(ctx)
    client = st.background() if not st.no_session else SessionClient.attach(st.socket_path())
    if client is None:
        raise _no_session(st)
    pid = int(client.status()["pid"])
    client.stop()
    client.close()
    st.client = None
    deadline = time.monotonic() + stop_timeout
    while time.monotonic() < deadline and (_alive(pid) or client.path.exists()):
        time.sleep(0.05)
    if _alive(pid):
        raise SessionError(f"the session process {pid} did not exit within {stop_timeout:g} s: kill {pid}")
    click.echo(f"session stopped (pid {pid})")


def _alive(pid: int) -> bool:
    if not pid_alive(pid):
        return False
    try:  # a child of ours that exited is a zombie until reaped
        done, _ = os.waitpid(pid, os.WNOHANG)
        return done == 0
    except ChildProcessError:
        return True

