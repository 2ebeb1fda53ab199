"""The `gateway` subcommand of the landscape CLI: an OPC UA server for every controller on the bus
(gateway.Gateway, docs/gateway.md)."""
from __future__ import annotations

import asyncio
import getpass
import json
import logging
import sys
from pathlib import Path

import click

from .bus import BusSpec, resolve_config
from .cli_core import cli, state_of
from .errors import LandscapeError
from .gateway_config import GatewayConfig, hash_password, load_config


@cli.command("gateway")
@click.option("--config", "config_file", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="the gateway's TOML configuration (docs/gateway.md; the .deb installs "
                   "/etc/landscape/gateway.toml); default: localhost, anonymous read-only, no users")
@click.option("--host", default=None, help="address to listen on (default 127.0.0.1: this machine only)")
@click.option("--port", type=click.IntRange(1, 65535), default=None, help="TCP port (default 4840)")
@click.option("--hash-password", "hash_pw", is_flag=True,
              help="read a password (on a terminal: a prompt, no echo; else stdin's first line), print the "
                   "line to put under [users] NAME = ..., and exit")
@click.pass_context
def gateway_cmd(ctx: click.Context, config_file: Path | None, host: str | None, port: int | None,
                hash_pw: bool) -> None:
    """Serve every controller on the bus over OPC UA (opc.tcp://127.0.0.1:4840/landscape/).

    Each controller is an object under Objects/DeviceSet with its description, state, joints and
    tool pose (subscribable), one method per command and AnswerRsvp; notices arrive as events.
    Anonymous clients read; commands need a configured user or certificate. Each OPC UA session
    that calls a command is its own supervisor. Ctrl-C or SIGTERM closes every session and ends."""
    if hash_pw:
        # on a terminal: a prompt and no echo; from a pipe or file: its first line
        password = getpass.getpass("password: ") if sys.stdin.isatty() else sys.stdin.readline().rstrip("\n")
        if not password:
            raise click.UsageError("--hash-password: give the password on stdin (one line, not empty)")
        click.echo(json.dumps(hash_password(password)))
        return
    st = state_of(ctx)
    cfg = load_config(config_file)
    why = asyncua_missing()
    if why is not None:
        raise LandscapeError(why)
    if host is not None:
        cfg.host = host
    if port is not None:
        cfg.port = port
    spec = BusSpec(interface=st.spec.interface or cfg.interface, channel=st.spec.channel or cfg.channel,
                   bitrate=st.spec.bitrate or cfg.bitrate, context=st.spec.context, config_file=st.spec.config_file,
                   also_from=f"write interface and channel under [bus] in "
                             f"{config_file if config_file is not None else 'the gateway configuration (--config)'}")
    resolve_config(spec)  # no usable interface: say so before the server listens
    asyncio.run(_serve(cfg, spec, st.json_out))


async def _serve(cfg: GatewayConfig, spec: BusSpec, json_out: bool) -> None:
    from .gateway import Gateway  # asyncua is imported only by this command
    gw = Gateway(cfg, spec)
    await gw.start()
    if json_out:
        click.echo(json.dumps({"command": "gateway", "url": gw.url, "bus": spec.describe()}))
    else:
        users = len(cfg.users) + len(cfg.certificate_users)
        who = f"{users} user" + ("" if users == 1 else "s")
        click.echo(f"gateway: {gw.url} serving the controllers on {spec.describe()} ({who}, anonymous "
                   f"{'read-only' if cfg.allow_anonymous else 'refused'}, security {', '.join(cfg.security)}); "
                   f"Ctrl-C ends")
    sys.stdout.flush()
    await gw.run()
    logging.getLogger("landscape.gateway").info("gateway stopped")
    n = len(gw.controllers)
    click.echo(f"gateway: stopped; served {n} controller{'' if n == 1 else 's'}")


def asyncua_missing() -> str | None:
    """Why the gateway cannot run here (None: asyncua imports)."""
    try:
        import asyncua  # noqa: F401
    except ImportError:
        return ("the gateway needs the Python package asyncua: pip install 'landscape[gateway]' "
                "(in a checkout: bash .ci/setup)")
    return None
