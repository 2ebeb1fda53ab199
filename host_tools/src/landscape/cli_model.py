"""`landscape model`: check a robot model file before it goes on a controller, convert a URDF into one.

Neither needs a bus. A refused file is one line, landscaped's own refusal of it, and exit 2
(docs/deploy.md "Describe your arm").
"""
from __future__ import annotations

import json
from pathlib import Path

import click

from .cli_core import EXIT_USAGE, CommandFailed, cli, state_of
from .model import ModelError, from_urdf, load_model


@cli.group("model")
def model_group() -> None:
    """Robot model files: the arm landscaped runs ([robot] model; no bus needed)."""


@model_group.command("check")
@click.argument("file", type=click.Path(path_type=Path))
@click.pass_context
def model_check_cmd(ctx: click.Context, file: Path) -> None:
    """Check FILE as landscaped will read it: its name, IK class and reach, or the refusal (exit 2)."""
    try:
        m = load_model(file)
    except ModelError as exc:
        raise CommandFailed(str(exc), EXIT_USAGE) from None
    if state_of(ctx).json_out:
        click.echo(json.dumps({"command": "model check", "file": str(file), "name": m.name, "ik_class": m.ik_class,
                               "reach_m": round(m.reach_m(), 6)}))
    else:
        click.echo(f"{file}: {m.name}, {m.ik_class} IK, reach {m.reach_m():.3f} m")


@model_group.command("from-urdf")
@click.argument("urdf", type=click.Path(dir_okay=False, path_type=Path))
@click.option("-o", "--output", "out", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="model file to write (default: stdout)")
@click.option("--name", default=None, help="the model's name (default: the URDF's robot name)")
@click.option("--base", default=None, help="the base link (default: the URDF's root link)")
@click.option("--tip", default=None,
              help="the flange link, a DH frame of the last joint (default: the end of the links it carries)")
@click.pass_context
def model_from_urdf_cmd(ctx: click.Context, urdf: Path, out: Path | None, name: str | None, base: str | None,
                        tip: str | None) -> None:
    """Convert a serial 6-joint URDF (revolute joints, one chain from base to flange) into a model file.

    The DH geometry, joint ranges, velocities, efforts and masses come from the URDF; what a URDF does
    not carry (accelerations, jerks, Cartesian limits, workspace) is chosen and marked CHOSEN in the
    file. A prismatic or mimic joint, a branch of moving joints, or a geometry no IK class fits is
    refused with the reason (exit 2)."""
    try:
        text = urdf.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        why = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
        raise CommandFailed(f"{urdf}: cannot read the URDF: {why}", EXIT_USAGE) from None
    try:
        model_text, m, chosen = from_urdf(text, str(urdf), name=name, base=base, tip=tip)
    except ModelError as exc:
        raise CommandFailed(str(exc), EXIT_USAGE) from None
    if out is None:
        click.echo(model_text, nl=False)
    else:
        try:
            out.write_text(model_text, encoding="utf-8")
        except OSError as exc:
            raise CommandFailed(f"cannot write {out}: {exc.strerror or exc}", EXIT_USAGE) from None
    if state_of(ctx).json_out:
        click.echo(json.dumps({"command": "model from-urdf", "name": m.name, "ik_class": m.ik_class,
                               "output": str(out) if out is not None else None, "chosen": chosen}), err=out is None)
    else:
        where = f"wrote {out}" if out is not None else "the model is on stdout"
        click.echo(f"model from-urdf: {where} ({m.name}, {m.ik_class} IK); chosen, not in the URDF: "
                   f"{', '.join(chosen)}: set them from the arm's data sheet", err=True)
