"""The `drives` and `home` subcommands of the landscape CLI: each joint's drive as it
reports itself (what moteus_tool and odrivetool show), and the drives' own homing
(docs/deploy.md "Drives"). Both speak through the vendor hook, sendCommand."""
from __future__ import annotations

import json
import time

import click

from .backend import Backend
from .cli_core import CliState, CommandFailed, cli, one_line, send, state_of
from .drives import BUS_REQUEST, DrivesView, home_request, joint_request, parse_bus, parse_joint
from .errors import error_for_code
from .registry import lookup
from .supervisor import RetVal

#: How long `home` waits for the answer when the device does not say (describe's homing_timeout_ms).
HOME_TIMEOUT_DEFAULT_S = 30.0


def _ask(backend: Backend, text: str, timeout_s: float | None = None) -> RetVal:
    """One sendCommand; CommandFailed (one line) when the device refuses it."""
    fields: dict[str, object] = {"input": text}
    if timeout_s is not None:
        fields["timeout_s"] = timeout_s
    rv = send(backend, lookup("send_command"), fields, wait_s=None)
    if not rv.ok:
        raise CommandFailed(one_line(error_for_code(f"sendCommand {text}", rv.ret_code, rv.ret_msg)))
    return rv


def read_view(st: CliState) -> DrivesView:
    """Every joint's readouts, then the bus counters."""
    backend = st.backend()
    listing = str(_ask(backend, "drives").result.get("result", ""))
    joints = sum(1 for line in listing.splitlines() if line.startswith("drive j"))
    view = DrivesView()
    for j in range(1, joints + 1):
        view.drives.append(parse_joint(str(_ask(backend, joint_request(j)).result.get("result", ""))))
    view.bus = parse_bus(str(_ask(backend, BUS_REQUEST).result.get("result", "")))
    return view


@cli.command("drives")
@click.option("--watch", type=click.FloatRange(min=0.2), default=None, metavar="SECONDS",
              help="read them again every SECONDS until Ctrl-C")
@click.pass_context
def drives_cmd(ctx: click.Context, watch: float | None) -> None:
    """Each joint's drive as it reports itself: CiA 402 state, mode, homing (* must be homed),
    brake, safe torque off, last error, position, velocity, torque (% of rated), temperature,
    feedback age (control cycles); then the drive bus master's counters. Velocity, torque,
    temperature, brake and STO show where the drives publish them ([drives] readouts,
    [joint.N] brake, sto, temperature)."""
    st = state_of(ctx)
    try:
        while True:
            view = read_view(st)
            if st.json_out:
                click.echo(json.dumps(view.as_dict()))
            else:
                if watch is not None:
                    click.echo("\x1b[H\x1b[2J", nl=False)  # the terminal's top, cleared
                for line in view.lines():
                    click.echo(line)
            if watch is None:
                return
            time.sleep(watch)
    except KeyboardInterrupt:
        if watch is None:
            raise  # a single read interrupted is an interrupted command; --watch ends this way


@cli.command("home")
@click.argument("joints", nargs=-1, type=click.IntRange(min=1))
@click.option("--timeout", "timeout_s", type=click.FloatRange(min=0, min_open=True), default=None,
              help="seconds to wait for the answer (default: the device's homing time-out)")
@click.pass_context
def home_cmd(ctx: click.Context, joints: tuple[int, ...], timeout_s: float | None) -> None:
    """Home JOINTS with their drives' own homing (none: every joint that must be homed);
    the device must be locked by this session and active, at rest. Answers when the homing
    ends, naming the joint and what its drive said when it fails."""
    st = state_of(ctx)
    backend = st.backend()
    if timeout_s is None:
        desc = backend.device_description()
        ms = desc.res.homing_timeout_ms if desc is not None else 0
        timeout_s = ms / 1000.0 + 2.0 if ms else HOME_TIMEOUT_DEFAULT_S
    rv = _ask(backend, home_request(joints), timeout_s)
    if st.json_out:
        click.echo(json.dumps({"command": "home", "ret_msg": rv.ret_msg}))
    else:
        click.echo(f"home: {rv.ret_msg}")
