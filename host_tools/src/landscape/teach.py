"""Teach a pose: append where the arm is now to a path file that `path load` reads back.

`append_taught` is pure file work (the CLI's `teach` reads the pose from the device): it
appends one point, tagged with its name, in the kind of the file (joint values j1..jN, or
the tool tip's pose x..yaw) and in the units the values are given in (the session's, as
`path load` reads them: docs/host-tool.md "path load"). A new file gets the kind asked for.
The file is checked before and after: a file `path load` would refuse is never written,
and the result always loads.

A taught pose is the tool tip in the world frame (getRobotPosition's world_pose), so a
Cartesian point goes only to a YAML or JSON file that says `frame: WORLD_CARTESIAN_FRAME`
(teach writes it into a new one): a CSV file has no frame and loads in the base frame.
"""
from __future__ import annotations

import csv
import io
import json
import os
import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from ._generated import landscape_pb2 as pb
from .paths import (
    JOINT_KEYS,
    POSE_KEYS,
    SUFFIXES,
    PathFile,
    PathFileError,
    load_path_file,
    point_from_mapping,
)

POINT_KINDS = ("joint", "cartesian")
WORLD_FRAME = pb.ReferenceFrame.Name(pb.WORLD_CARTESIAN_FRAME)
#: Digits kept of each value: 1e-6 of the unit (a micrometre, a microradian in SI), so that
#: a value carries no float noise (1.6661e-10 is written 0).
DECIMALS = 6


def _clean(v: float) -> float:
    r = round(float(v), DECIMALS)
    return 0.0 if r == 0 else r  # never -0.0


def taught_values(kind: str, joints: Sequence[float], world_pose: Sequence[float], name: str) -> dict[str, Any]:
    """The point's fields: the coordinates of `kind` and the tag."""
    keys, values = (JOINT_KEYS[:len(joints)], joints) if kind == "joint" else (POSE_KEYS, world_pose)
    out: dict[str, Any] = {k: _clean(v) for k, v in zip(keys, values, strict=True)}
    out["tag_name"] = name
    return out


def _existing(file: Path) -> PathFile | None:
    if not file.exists() or file.stat().st_size == 0:
        return None
    return load_path_file(file)


def _write(file: Path, text: str) -> None:
    """Replace `file` by `text` in one step: a failure leaves the old file whole."""
    fd, tmp = tempfile.mkstemp(dir=file.parent, prefix=f".{file.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="") as f:
            f.write(text)
        os.replace(tmp, file)
    except OSError as exc:
        Path(tmp).unlink(missing_ok=True)
        raise PathFileError(str(file), "", None, f"cannot write it: {exc.strerror or exc}") from None


def _csv_text(file: Path, old: PathFile | None, values: dict[str, Any]) -> str:
    if old is None:
        header = list(values)
        text = ""
    else:
        text = file.read_text(encoding="utf-8")
        header = next(r for r in csv.reader(io.StringIO(text)) if any(c.strip() for c in r))
        header = [c.strip() for c in header]
        if "tag_name" not in header:
            raise PathFileError(str(file), "", "tag_name", "no such column: add a tag_name column to the header "
                                                           "so a taught point carries its name")
        if text and not text.endswith("\n"):
            text += "\n"
    row = io.StringIO()
    w = csv.writer(row, lineterminator="\n")
    if old is None:
        w.writerow(header)
    w.writerow([values.get(k, "") for k in header])
    return text + row.getvalue()


def _tree_text(file: Path, fmt: str, old: PathFile | None, kind: str, values: dict[str, Any]) -> str:
    data: Any
    if old is None:
        data = {"frame": WORLD_FRAME, "points": []} if kind == "cartesian" else {"points": []}
    else:
        text = file.read_text(encoding="utf-8")
        if fmt == "json":
            data = json.loads(text)
        else:
            import yaml

            data = yaml.safe_load(text)
    points = data["points"] if isinstance(data, dict) else data
    points.append(values)
    if fmt == "json":
        return json.dumps(data, indent=2) + "\n"
    import yaml

    return str(yaml.safe_dump(data, sort_keys=False, default_flow_style=None))


def append_taught(file: str | Path, name: str, *, joints: Sequence[float], world_pose: Sequence[float],
                  kind: str | None = None) -> tuple[str, int]:
    """Append the pose (joints, world_pose: in the session's units) as a point tagged `name`
    to `file`, created when missing (kind: `kind`, default joint values). Returns the kind
    written and the points the file now holds. PathFileError (nothing written) when the file
    is not a path file, is of the other kind, or cannot take a world pose (module doc)."""
    p = Path(file)
    fmt = SUFFIXES.get(p.suffix.lower())
    if fmt is None:
        raise PathFileError(str(p), "", None, f"unknown file type '{p.suffix}': use .csv, .yaml, .yml or .json")
    old = _existing(p)
    file_kind = old.kind if old is not None else (kind or "joint")
    if kind is not None and kind != file_kind:
        raise PathFileError(str(p), "", None, f"holds {file_kind} points; teach it {file_kind} points (one kind "
                                              f"per file) or name another file")
    if old is not None and file_kind == "joint" and len(old.points[0].joints) != len(joints):
        raise PathFileError(str(p), "", None, f"its points have {len(old.points[0].joints)} joint values, the "
                                              f"arm has {len(joints)}")
    if file_kind == "cartesian" and (fmt == "csv" or (old is not None and old.frame != pb.WORLD_CARTESIAN_FRAME)):
        raise PathFileError(str(p), "", "frame", f"a taught pose is the tool tip in the world frame: teach it "
                                                 f"into a YAML or JSON file with frame: {WORLD_FRAME} (teach "
                                                 f"writes it into a new one), or teach joint values")
    values = taught_values(file_kind, joints, world_pose, name)
    point_from_mapping(values, file_kind, len(joints), str(p), "taught point")  # the name's limits
    text = _csv_text(p, old, values) if fmt == "csv" else _tree_text(p, fmt, old, file_kind, values)
    _write(p, text)
    return file_kind, len(load_path_file(p).points)
