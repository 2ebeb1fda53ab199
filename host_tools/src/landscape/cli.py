"""The `landscape` command-line tool: the entry point, `run FILE`, `shell` and
`monitor`.

The group, its options and the schema subcommands are in `cli_core`; the path,
record, plot, demo and session subcommands in `cli_tools`, imported here so
that `landscape.cli.cli` carries every subcommand. Exit codes: see `cli_core`.
"""
from __future__ import annotations

import contextlib
import logging
import os
import shlex
import sys
import threading
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn

import click

from . import cli_drives, cli_gateway, cli_model, cli_tools, cli_view  # noqa: F401  (register drives, home; gateway; model; path, record, plot, demo, session; view)
from . import telemetry as tm
from ._generated import landscape_pb2 as pb
from .backend import Backend
from .cli_core import (
    EXIT_BUS,
    EXIT_COMMAND,
    EXIT_ERROR,
    EXIT_USAGE,
    EXIT_VERSION,
    AlreadyReported,
    CliState,
    CommandFailed,
    EnumType,
    UnitsWatch,
    classify,
    cli,
    fmt_notice,
    one_line,
    say_link_lost,
    state_of,
    stop_after_interrupt,
)
from .description import DeviceDescription
from .errors import (
    ArgumentError,
    LandscapeError,
    LinkLostError,
)
from .notices import SI, Units
from .registry import (
    enum_aliases,
)
from .session import SessionClient, SessionError, SessionGoneError
from .supervisor import Supervisor

if TYPE_CHECKING:
    from prompt_toolkit.application import Application

log = logging.getLogger("landscape.cli")


# ---------------------------------------------------------------- run, shell


#: Subcommands a `run` file or the shell cannot use (they hold the terminal or the session).
NOT_IN_SCRIPTS = ("run", "shell", "monitor", "events", "record", "plot", "demo", "session")


def not_in_scripts(name: str) -> click.UsageError:
    """The one line for a subcommand that exists but not in a `run` file or the shell."""
    return click.UsageError(f"'{name}' runs on its own, not in a `run` file or the shell (it holds the terminal "
                            f"or the session): run `landscape {name} ...` in another terminal")


def run_line(ctx: click.Context, line: str) -> None:
    """Run one command line (shlex) in the current session; errors propagate (a line that
    does not parse is a click.UsageError)."""
    try:
        args = shlex.split(line, comments=True)
    except ValueError as exc:
        raise click.UsageError(f"cannot split the line into words ({str(exc).lower()}): close the quote or "
                               f"escape it with a backslash") from None
    if not args:
        return
    name, rest = args[0], args[1:]
    group = ctx.find_root().command
    assert isinstance(group, click.Group)
    sub = group.get_command(ctx, name)
    if name in NOT_IN_SCRIPTS:
        raise not_in_scripts(name)
    if sub is None:
        raise click.UsageError(f"unknown command '{name}' (`help` in the shell, landscape --help, lists them)")
    with sub.make_context(name, rest, parent=ctx.find_root()) as sub_ctx:
        sub.invoke(sub_ctx)


def _script_failure(exc: BaseException) -> int | None:
    if isinstance(exc, click.UsageError):
        return EXIT_USAGE
    code, _ = classify(exc)
    if code in (EXIT_USAGE, EXIT_COMMAND):
        return code
    return None  # bus, time-out, version: the session is gone; stop


def read_script(file: str) -> tuple[str, list[str]]:
    """(name, lines) of a `run` script: '-' is stdin. ArgumentError (exit 2, one line) for a
    file that cannot be read or is not UTF-8 text."""
    name = "<stdin>" if file == "-" else file
    try:
        if file == "-":
            data = sys.stdin.buffer.read()
        else:
            with open(file, "rb") as f:
                data = f.read()
    except OSError as exc:
        raise ArgumentError(f"{name}: cannot read it: {exc.strerror or exc}") from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        raise ArgumentError(f"{name}: line {line}: not UTF-8 text (byte {data[exc.start]:#04x} at offset "
                            f"{exc.start}): save the script as UTF-8") from None
    return name, text.splitlines()


@cli.command("run")
@click.argument("file", type=click.Path(allow_dash=True))
@click.option("--keep-going", "-k", is_flag=True, help="run the remaining lines after a failing one")
@click.pass_context
def run_cmd(ctx: click.Context, file: str, keep_going: bool) -> None:
    """Run the commands of FILE (one per line, '#' comments; '-': stdin) in one session."""
    st = state_of(ctx)
    st.one_shot = False
    first_code = 0
    name, lines = read_script(file)
    for lineno, raw in enumerate(lines, 1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        if not st.json_out:
            click.echo(f"> {line}")
        try:
            run_line(ctx, line)
        except BaseException as exc:  # noqa: BLE001
            code = _script_failure(exc)
            if code is None:
                raise
            msg = exc.format_message() if isinstance(exc, click.UsageError) else str(exc)
            click.echo(f"{name}:{lineno}: {one_line(msg)}", err=True)
            first_code = first_code or code
            if not keep_going:
                break
    if first_code:
        raise CommandFailed(f"{name}: stopped at a failing line" if not keep_going
                            else f"{name}: some lines failed", first_code)


def _history_path() -> Path:
    base = Path(os.environ.get("XDG_STATE_HOME") or Path.home() / ".local" / "state") / "landscape"
    base.mkdir(parents=True, exist_ok=True)
    return base / "history"


def shell_help(group: click.Group, ctx: click.Context, names: Sequence[str], topic: str) -> str:
    """The text of the shell's `help [CMD]`."""
    if not topic:
        return ("commands (help CMD or CMD --help for one; Ctrl-C stops a running motion; quit or Ctrl-D "
                "leaves):\n" + "\n".join(f"  {n:<28} {group.commands[n].get_short_help_str(60)}" for n in names))
    sub = group.get_command(ctx, topic)
    if topic in NOT_IN_SCRIPTS:
        raise not_in_scripts(topic)
    if sub is None:
        raise click.UsageError(f"no command '{topic}' in the shell: `help` lists them")
    with click.Context(sub, info_name=topic, parent=ctx.find_root()) as sub_ctx:
        return sub.get_help(sub_ctx)


def shell_line(ctx: click.Context, line: str, names: Sequence[str]) -> bool:
    """Run one shell line; False when the shell should end. Nothing a line does ends the
    shell: help, --help, usage errors, device errors, a lost bus, Ctrl-C (which stops a running
    motion, see execute) are reported and the prompt comes back."""
    group = ctx.find_root().command
    assert isinstance(group, click.Group)
    line = line.strip()
    if line in ("quit", "exit"):
        return False
    try:
        words = line.split(None, 1)
        if words and words[0] in ("help", "?"):
            click.echo(shell_help(group, ctx, names, words[1].strip() if len(words) > 1 else ""))
            return True
        run_line(ctx, line)
    except click.exceptions.Exit:
        pass  # CMD --help printed its help
    except click.UsageError as exc:
        click.echo(f"error: {one_line(exc.format_message())}", err=True)
    except click.ClickException as exc:
        click.echo(f"error: {one_line(exc.format_message())}", err=True)
    except (KeyboardInterrupt, click.exceptions.Abort):
        click.echo("interrupted", err=True)
    except Exception as exc:  # noqa: BLE001 (one line, never a traceback; the shell goes on)
        code, msg = classify(exc)
        st = state_of(ctx)
        if isinstance(exc, (LinkLostError, SessionGoneError)):
            # the device, or the background session that held the lock and units, is gone:
            # nothing more this shell can do (never a session of its own opened behind the user)
            say_link_lost(st, exc, msg)  # a follower may have said it already
            return False
        click.echo(msg if code is not None else f"error: {type(exc).__name__}: {one_line(exc)}", err=True)
        if code in (EXIT_BUS, EXIT_VERSION, EXIT_ERROR) and st.client is not None:
            st.client.close()   # a broken session connection is opened afresh by the next line
            st.client = None
    return True


def published_choices(backend: Backend) -> Callable[[str], list[str]]:
    """The values the device publishes (describe) for a string argument, by its name: sensor
    types and tool ids; empty for free text, and when the device does not describe itself
    (completion then offers only values typed before). Our own session read it at connect;
    a background session is asked once."""
    desc: DeviceDescription | None = None
    try:
        desc = backend.device_description()
    except LandscapeError as exc:
        log.warning("no device description for completion: %s", exc)
    return (lambda field: desc.choices("", field)) if desc is not None else (lambda field: [])


def _history_values(lines: Sequence[str]) -> dict[str, list[str]]:
    """Values typed before for each string argument (path names, tools, sensors, ...), newest
    first, from shell lines: {field name: [values]}."""
    group = cli
    out: dict[str, list[str]] = {}
    for line in lines:
        try:
            words = shlex.split(line, comments=True)
        except ValueError:
            continue
        sub = group.commands.get(words[0]) if words else None
        if sub is None:
            continue
        args = words[1:]
        if isinstance(sub, click.Group):
            sub = sub.commands.get(args[0]) if args else None
            args = args[1:]
            if sub is None:
                continue
        positional = [p for p in sub.params if isinstance(p, click.Argument)]
        for value, param in zip(_positional_words(sub, args), positional, strict=False):
            if param.type is click.STRING and param.name and value and value not in out.get(param.name, []):
                out.setdefault(param.name, []).insert(0, value)
    return out


def _positional_words(sub: click.Command, args: Sequence[str]) -> list[str]:
    """The positional words of `args` for `sub` (options and their values skipped)."""
    takes_value = {o for p in sub.params if isinstance(p, click.Option) and not p.is_flag
                   for o in p.opts + p.secondary_opts}
    out: list[str] = []
    skip = False
    for a in args:
        if skip:
            skip = False
            continue
        if a.startswith("--") or (a.startswith("-") and len(a) > 1 and not a[1].isdigit() and a[1] != "."):
            skip = a in takes_value
            continue
        out.append(a)
    return out


def shell_completer(names: Sequence[str], history: Callable[[], Sequence[str]],
                    published: Callable[[str], list[str]] = lambda field: []) -> Any:
    """Tab completion for the shell: command names; option names; enum values (any accepted
    spelling); file names for file arguments; for string arguments, the values the device
    publishes (`published`: sensor types, tool ids from its description), then values typed
    before (path names and the rest)."""
    from prompt_toolkit.completion import Completer, Completion, PathCompleter
    from prompt_toolkit.document import Document

    paths = PathCompleter(expanduser=True)

    class ShellCompleter(Completer):
        def get_completions(self, document: Document, complete_event: Any) -> Any:
            text = document.text_before_cursor
            try:
                words = shlex.split(text)
            except ValueError:
                words = text.split()
            current = "" if not text or text[-1].isspace() else (words.pop() if words else "")
            if not words or words[0] in ("help", "?"):
                if len(words) <= 1:
                    pool = list(names) + ([] if words else ["help", "quit", "exit"])
                    yield from (Completion(w, -len(current)) for w in pool if w.startswith(current))
                return
            sub = cli.commands.get(words[0])
            args = words[1:]
            if isinstance(sub, click.Group):
                if not args:
                    yield from (Completion(w, -len(current)) for w in sorted(sub.commands) if w.startswith(current))
                    return
                sub, args = sub.commands.get(args[0]), args[1:]
            if sub is None or words[0] in NOT_IN_SCRIPTS:
                return
            options = {o: p for p in sub.params if isinstance(p, click.Option) for o in p.opts + p.secondary_opts}
            if current.startswith("-") and not current[1:2].isdigit():
                yield from (Completion(o, -len(current)) for o in sorted(options) + ["--help"] if o.startswith(current))
                return
            param: click.Parameter | None = None
            if args and args[-1] in options and not options[args[-1]].is_flag:
                param = options[args[-1]]  # the value of this option
            else:
                positional = [p for p in sub.params if isinstance(p, click.Argument)]
                i = len(_positional_words(sub, args))
                if positional:
                    param = positional[min(i, len(positional) - 1)] if positional[-1].nargs == -1 or \
                        i < len(positional) else None
            if param is None:
                return
            if isinstance(param.type, EnumType):
                pool = sorted(enum_aliases(param.type.enum))
            elif isinstance(param.type, (click.Path, click.File)):
                yield from paths.get_completions(Document(current, len(current)), complete_event)
                return
            elif param.type is click.STRING and param.name:
                offered = published(param.name)
                typed = [v for v in _history_values(history()).get(param.name, []) if v not in offered]
                pool = [shlex.quote(v) for v in [*offered, *typed]]
            else:
                return
            yield from (Completion(w, -len(current)) for w in pool if w.startswith(current))

    return ShellCompleter()


def stop_followed(st: CliState) -> bool:
    """Ctrl-C at the prompt while the shell follows a motion: stop-motion, as during a wait.
    False when no motion is followed."""
    running = [f for f in st.followers if f.running]
    if not running:
        return False
    stop_after_interrupt(st, running[-1].cmd)
    return True


class LinkWatch:
    """The shell's own session watched while the prompt waits for a line: a device that stops
    answering (its heartbeat answers stop) is said at once and ends the prompt, so the shell
    exits 4 then, not at the next line. A background session's link is its process's to watch;
    the shell learns of its loss at its next line."""

    PERIOD_S = 0.2

    def __init__(self, st: CliState, app: Application[str]) -> None:
        self.st = st
        self.app = app
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True, name="landscape-shell-link")

    def __enter__(self) -> LinkWatch:
        self.thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop.set()
        self.thread.join(2.0)

    def _run(self) -> None:
        while not self.stop.wait(self.PERIOD_S):
            sup = self.st.sup
            if sup is None or self.st.lost is not None:
                continue
            try:
                sup.check_link()
            except LinkLostError as exc:
                say_link_lost(self.st, exc, classify(exc)[1])
                loop = self.app.loop
                if self.app.is_running and loop is not None:
                    loop.call_soon_threadsafe(self._end_prompt)
                return

    def _end_prompt(self) -> None:
        if self.app.is_running:
            self.app.exit(exception=EOFError())


@cli.command("shell")
@click.pass_context
def shell_cmd(ctx: click.Context) -> None:
    """Interactive prompt: one session for every line; Tab completes command names, option names,
    enum values, file names, the sensors and tools the device describes, and values typed before
    (path names).

    A motion command returns to the prompt at once (its notices and end print as they arrive), so
    stop-motion, abort-motion or any other line can be typed while it runs; Ctrl-C while a motion
    runs sends stop-motion (the arm pauses). `help [CMD]` and `CMD --help` show help; errors are
    reported and the prompt comes back; Ctrl-C at the prompt otherwise clears the line; quit, exit
    or Ctrl-D leave."""
    from prompt_toolkit import PromptSession
    from prompt_toolkit.history import FileHistory
    from prompt_toolkit.patch_stdout import patch_stdout

    group = ctx.find_root().command
    assert isinstance(group, click.Group)
    names = sorted(n for n in group.list_commands(ctx) if n not in NOT_IN_SCRIPTS)
    history = FileHistory(str(_history_path()))
    st = state_of(ctx)
    st.one_shot = False
    st.follow_motions = True
    published = published_choices(st.backend())
    session: PromptSession[str] = PromptSession(
        history=history, completer=shell_completer(names, lambda: list(history.get_strings())[-500:], published))
    watch = LinkWatch(st, session.app)
    # On a terminal, lines a followed motion prints go above the prompt, which is redrawn.
    with watch, patch_stdout(raw=True) if sys.stdout.isatty() else contextlib.nullcontext():
        while st.lost is None:
            try:
                line = session.prompt("landscape> ")
            except EOFError:
                break
            except KeyboardInterrupt:
                stop_followed(st)
                continue
            if st.lost is not None or not shell_line(ctx, line, names):
                break
    for f in st.followers:
        if f.running:
            f.abandon()
    if st.lost is not None:
        raise AlreadyReported(EXIT_BUS)  # its line was printed when it happened


def _state_name(v: Any) -> str:
    try:
        return pb.State.Name(int(v))
    except (ValueError, TypeError):
        return str(v)


def monitor_view(t: dict[str, dict[str, Any]], title: str, last_notices: Sequence[pb.Notice],
                 units: Units | None = None) -> Any:
    """A rich renderable of the device's telemetry `t` (message name -> signals, SI as the DBC has
    them) and the last notices; joints and the tool pose shown in `units` (the session's; None:
    unknown, shown in SI), every row labelled with its unit."""
    from rich.table import Table

    table = Table(title=title, show_header=False)
    table.add_column("what", style="bold")
    table.add_column("value")
    st = t.get("STATUS", {})
    hb = t.get("HEARTBEAT", {})
    if st:
        m, c = int(st.get("st_motion", 0)), int(st.get("st_control_mode", 0))
        table.add_row("state", _state_name(st.get("st_state", 0)))
        table.add_row("motion", tm.choice_name("STATUS", "st_motion", m))
        table.add_row("control mode", tm.choice_name("STATUS", "st_control_mode", c))
        table.add_row("fault", str(st.get("st_fault", 0)))
        table.add_row("cycle", f"{st.get('st_cycle_us', 0)} us, {st.get('st_overruns', 0)} overruns")
    if hb:
        table.add_row("owner", f"{int(hb.get('hb_owner', 0)):#04x}")
        table.add_row("supervisors", str(hb.get("hb_supervisors", 0)))
    u = units or SI
    table.add_row("units", f"{u.describe()} (the session's, get-units)" if units is not None
                  else "meters and radians (telemetry; the session's units are unknown)")
    joints = [t[k][f"j{i}"] for k, r in (("JOINTS_12", (1, 2)), ("JOINTS_34", (3, 4)), ("JOINTS_56", (5, 6)))
              if k in t for i in r]
    if joints:
        table.add_row(f"joints ({u.angular_symbol})", " ".join(f"{u.from_rad(j):+.4f}" for j in joints))
    if "TOOL_POS" in t:
        p = t["TOOL_POS"]
        table.add_row(f"tool xyz ({u.linear_symbol})",
                      " ".join(f"{u.from_m(p[k]):+.4f}" for k in ("tool_x", "tool_y", "tool_z")))
    if "TOOL_RPY" in t:
        r = t["TOOL_RPY"]
        table.add_row(f"tool rpy ({u.angular_symbol})",
                      " ".join(f"{u.from_rad(r[k]):+.4f}" for k in ("tool_roll", "tool_pitch", "tool_yaw")))
    if "DIO" in t:
        table.add_row("DIO in/out", f"{int(t['DIO']['dio_inputs']):#010x} / {int(t['DIO']['dio_outputs']):#010x}")
    if "EMERGENCY" in t:
        table.add_row("EMERGENCY", str(t["EMERGENCY"]))
    if not t:
        table.add_row("telemetry", "(none received yet)")
    for n in last_notices:
        table.add_row("notice", fmt_notice(n).strip())
    return table


class TelemetryFeed:
    """The latest telemetry and notices for `monitor`: from the background session (a watch
    connection of its own, so the session's commands go on) or from our own session."""

    def __init__(self, st: CliState, last: int = 5) -> None:
        import collections

        self.notices: collections.deque[pb.Notice] = collections.deque(maxlen=last)
        self._latest: dict[str, dict[str, Any]] = {}
        self._lock = threading.Lock()
        self._sup: Supervisor | None = None
        self._watcher: SessionClient | None = None
        self._thread: threading.Thread | None = None
        self._closing = False
        self.error: LandscapeError | None = None
        client = st.background()
        self._units = UnitsWatch(st.backend(), follow=client is not None)
        if client is None:
            self._sup = st.session()
            self._sup.on_notice(self.notices.append)
            self.title = f"landscape monitor: device {st.device:#04x} on {self._sup.channel_name}"
            return
        self.title = f"landscape monitor: device {st.device:#04x} on {st.spec.describe()} (via the session)"
        with self._lock:
            self._latest.update(client.telemetry())
        self._watcher = SessionClient.attach(client.path)
        if self._watcher is None:
            raise SessionError(f"the session at {client.path} went away: check `landscape session status`")
        self._thread = threading.Thread(target=self._pump, args=(self._watcher,), daemon=True,
                                        name="landscape-monitor")
        self._thread.start()

    def _pump(self, watcher: SessionClient) -> None:
        try:
            for kind, item, _ in watcher.watch():
                if kind == "broadcast":
                    with self._lock:
                        self._latest[item.name] = dict(item.signals)
                else:
                    self.notices.append(item)
        except (OSError, ValueError, LandscapeError) as exc:
            if not self._closing:
                self.error = exc if isinstance(exc, LandscapeError) else SessionError(
                    f"the session at {watcher.path} went away ({exc}): check `landscape session status`")

    @property
    def units(self) -> Units | None:
        """The session's units now (another terminal's set-units shows within a second)."""
        self._units.poll()
        return self._units.units

    def check(self) -> None:
        """Raise what ended the feed: the device went away (LinkLostError), the session stopped."""
        if self._sup is not None:
            self._sup.check_link()
        if self.error is not None:
            raise self.error

    def telemetry(self) -> dict[str, dict[str, Any]]:
        if self._sup is not None:
            return self._sup.telemetry()
        with self._lock:
            return {k: dict(v) for k, v in self._latest.items()}

    def close(self) -> None:
        self._closing = True
        if self._sup is not None:
            with contextlib.suppress(ValueError):
                self._sup.remove_notice_callback(self.notices.append)
        if self._watcher is not None:
            self._watcher.close()
        if self._thread is not None:
            self._thread.join(2.0)


@cli.command("monitor")
@click.option("--duration", type=float, default=None, help="stop after this many seconds (default: Ctrl-C)")
@click.option("--once", is_flag=True, help="print one snapshot after a short wait and exit")
@click.pass_context
def monitor_cmd(ctx: click.Context, duration: float | None, once: bool) -> None:
    """Live view of state, joints, tool pose, DIO and the last notices.

    With a background session running it watches through the session (commands from
    other terminals go on); else it opens a session of its own. Ctrl-C ends it."""
    import time

    from rich.console import Console
    from rich.live import Live

    feed = TelemetryFeed(state_of(ctx))
    console = Console()
    try:
        if once:
            time.sleep(0.5)
            feed.check()
            console.print(monitor_view(feed.telemetry(), feed.title, list(feed.notices), feed.units))
            return
        end = None if duration is None else time.monotonic() + duration
        try:
            with Live(monitor_view(feed.telemetry(), feed.title, [], feed.units), console=console,
                      refresh_per_second=5) as live:
                while end is None or time.monotonic() < end:
                    time.sleep(0.2)
                    feed.check()
                    live.update(monitor_view(feed.telemetry(), feed.title, list(feed.notices), feed.units))
        except KeyboardInterrupt:
            pass  # Ctrl-C is how an open-ended monitor ends
    finally:
        feed.close()




def main(argv: Sequence[str] | None = None) -> NoReturn:
    """Console-script entry point."""
    cli.main(args=argv, prog_name="landscape")
    raise SystemExit(0)  # pragma: no cover (main exits)
