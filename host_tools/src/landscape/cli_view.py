"""The `view` subcommand of the landscape CLI: a live Foxglove WebSocket view (view.LiveView)."""
from __future__ import annotations

import json
import sys
import time
from pathlib import Path
from typing import Any

import click

from .cli_core import cli, state_of
from .cli_tools import start_recording
from .view import DEFAULT_HOST, DEFAULT_PORT, LiveView, write_layout


@cli.command("view")
@click.option("--host", default=DEFAULT_HOST, show_default=True,
              help="address to listen on (the default lets only this machine's programs connect)")
@click.option("--port", type=click.IntRange(0, 65535), default=DEFAULT_PORT, show_default=True,
              help="TCP port to listen on (0: a free one, printed)")
@click.option("--duration", type=click.FloatRange(min=0, min_open=True), default=None,
              help="seconds to serve (default: until Ctrl-C)")
@click.option("--write-layout", "layout_file", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="write the Foxglove layout (3D arm, joint plots, notices) to FILE and exit (no bus needed)")
@click.pass_context
def view_cmd(ctx: click.Context, host: str, port: int, duration: float | None, layout_file: Path | None) -> None:
    """Serve the channels of `record FILE.mcap` live on a Foxglove WebSocket (ws://127.0.0.1:8765).

    In Foxglove: Open connection > Foxglove WebSocket > the URL printed; import the layout of
    --write-layout. It listens like `record` (through a background session, else in a session of
    its own that takes no lock): other sessions command the arm meanwhile. Ctrl-C ends it."""
    st = state_of(ctx)
    if layout_file is not None:
        write_layout(layout_file)
        click.echo(f"view: wrote {layout_file} (Foxglove: Layouts > Import from file)")
        return
    view = LiveView(host=host, port=port)  # a port in use fails here, before the bus is opened
    t0 = time.monotonic()
    try:
        st.backend()
        follow = start_recording(st, view)
        via = " (via the session)" if st.background() is not None else ""
        if st.json_out:
            click.echo(json.dumps({"command": "view", "url": view.url, "device": st.device}))
        else:
            click.echo(f"view: {view.url} serving device {st.device:#04x} on {st.spec.describe()}{via}; "
                       f"Foxglove: Open connection > Foxglove WebSocket > {view.url}; Ctrl-C ends")
        sys.stdout.flush()
        progress = sys.stderr.isatty() and not st.json_out
        try:
            next_report = time.monotonic() + 1.0
            while duration is None or time.monotonic() - t0 < duration:
                time.sleep(0.05 if duration is None else min(0.05, max(0.0, duration - (time.monotonic() - t0))))
                follow.check()
                if progress and time.monotonic() >= next_report:
                    next_report += 1.0
                    click.echo(f"\rview: {time.monotonic() - t0:5.0f} s, {view.clients} clients, "
                               f"{view.messages} messages", nl=False, err=True)
        except KeyboardInterrupt:
            pass  # Ctrl-C is how the view ends
        finally:
            follow.stop()
            if progress:
                click.echo("", err=True)
    finally:
        view.close()
    summary: dict[str, Any] = {"url": view.url, "seconds": round(time.monotonic() - t0, 3),
                               "clients": len(view.listener.seen), "broadcasts": view.broadcasts,
                               "notices": view.notices, "frames": view.frames, "channels": dict(view.counts)}
    if st.json_out:
        click.echo(json.dumps({"command": "view", "result": summary}))
    else:
        click.echo(f"view: served {view.messages} messages on {len(view.counts)} channels ({view.broadcasts} "
                   f"broadcasts, {view.notices} notices, {view.frames} CAN frames) to {summary['clients']} clients "
                   f"in {summary['seconds']:g} s at {view.url}")
