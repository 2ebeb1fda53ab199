"""Path files (CSV, YAML, JSON) and the splitting of a path into pathLoad messages.

A path file holds points, one per CSV row or one mapping per list item, with the
keys of ``POINT_KEYS``: the Cartesian pose ``x, y, z, roll, pitch, yaw`` or the
joint values ``j1 .. jN`` (one kind per file), and optionally ``tag_name``,
``tag_index``, ``time_delay_s``, ``transition_speed_pct``, ``speed_pct``,
``accel_pct`` and ``aux`` (auxiliary commands, ``;``-separated in CSV, a string
or a list in YAML/JSON). A YAML/JSON file may instead be a mapping with
``path``, ``frame``, ``motion_type``, ``offset_type`` and ``points``.

``load_path_file`` reads and checks the whole file before anything is sent;
the first problem is one PathFileError naming the file, the row (CSV line) or
index (``points[i]``) and the field. Given the device's limit (``max_points``:
the points one path holds, ``describe``'s max_points_per_path), it refuses a
file with more points, or more bytes than that many points can take
(``max_file_bytes``), before parsing it all: a huge file costs neither time
nor memory. ``build_path_load_requests`` is the pure
builder that splits points into requests the firmware can hold: at most
PATH_LOAD_MAX_POINTS points and MAX_MESSAGE_BYTES bytes per ISO-TP message.
"""
from __future__ import annotations

import csv
import io
import json
import math
import sys
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from google.protobuf.message import Message

from ._generated import landscape_pb2 as pb
from .bus import MAX_MESSAGE_BYTES
from .errors import ArgumentError
from .limits import max_count, max_string_bytes
from .registry import build_request, parse_enum

POSE_KEYS: tuple[str, ...] = ("x", "y", "z", "roll", "pitch", "yaw")
#: The most joints an arm of this firmware has (describe: joints), not the 24 values the
#: seed's tag_struct carries on the wire.
_MAX_JOINTS: int = max_count("DescribeRes", "joints") or 8
JOINT_KEYS: tuple[str, ...] = tuple(f"j{i}" for i in range(1, _MAX_JOINTS + 1))
OPTIONAL_KEYS: tuple[str, ...] = ("tag_name", "tag_index", "time_delay_s", "transition_speed_pct", "speed_pct",
                                  "accel_pct", "aux")
POINT_KEYS: tuple[str, ...] = POSE_KEYS + JOINT_KEYS + OPTIONAL_KEYS
FILE_KEYS: tuple[str, ...] = ("path", "frame", "motion_type", "offset_type", "points")
SUFFIXES: dict[str, str] = {".csv": "csv", ".yaml": "yaml", ".yml": "yaml", ".json": "json"}

#: Points the firmware holds in one pathLoad message (PathLoadReq.tags max_count).
PATH_LOAD_MAX_POINTS: int = max_count("PathLoadReq", "tags") or 32
MAX_PATH_NAME_BYTES: int = max_string_bytes("PathLoadReq", "path_name") or 63
MAX_TAG_NAME_BYTES: int = max_string_bytes("TagPoint", "tag_name") or 63
MAX_AUX_COMMANDS: int = max_count("TagPoint", "aux_commands") or 4
MAX_AUX_BYTES: int = max_string_bytes("TagPoint", "aux_commands") or 47
#: The NAME of `event NAME` / `rsvp NAME` becomes a notice's event id (docs/protocol.md
#: "Auxiliary commands"), which holds this many bytes (describe: downlink_limits).
MAX_EVENT_ID_BYTES: int = max_string_bytes("Notice", "event_id") or 31
#: The most text one point (or the header) of a path file may take: a point whose text is
#: longer than one ISO-TP message is not a point the device could take anyway.
MAX_POINT_TEXT_BYTES: int = MAX_MESSAGE_BYTES
#: The largest seq: requests are sized with it so that any seq the supervisor picks fits.
_SEQ_MAX = 0xFFFFFFFF
_INT32 = (-(2**31), 2**31 - 1)
_SHOWN_CHARS = 80


def shown(raw: Any, *, quote: bool = True) -> str:
    """`raw` as it appears in a message: text quoted (unless `quote` is False), cut after
    _SHOWN_CHARS characters (a 5,000-digit number is named by its length, not printed)."""
    text = raw if isinstance(raw, str) else repr(raw)
    if len(text) <= _SHOWN_CHARS:
        return f"'{text}'" if quote and isinstance(raw, str) else text
    return f"'{text[:_SHOWN_CHARS]}...' ({len(text)} characters)"


class _LongInteger(str):
    """An integer literal of a JSON file too long to be any field's value, kept as its text
    (Python refuses int() of more than 4300 digits, and reading it would be slow)."""


def _json_int(text: str) -> int | _LongInteger:
    return int(text) if len(text) <= 32 else _LongInteger(text)


def max_file_bytes(max_points: int) -> int:
    """The most bytes a path file of at most `max_points` points may have."""
    return (max_points + 1) * MAX_POINT_TEXT_BYTES


class PathFileError(ArgumentError):
    """A path file cannot be read or one of its values is wrong; nothing was sent."""

    def __init__(self, file: str, where: str, fld: str | None, problem: str) -> None:
        self.file = file
        self.where = where
        self.field = fld
        self.problem = problem
        parts = [file] + ([where] if where else []) + ([fld] if fld else []) + [problem]
        super().__init__(": ".join(parts))


@dataclass
class PathFile:
    """The checked content of a path file. Settings are None when the file does not give them."""

    file: str
    points: list[pb.TagPoint]
    kind: str                       # "cartesian" or "joint"
    path_name: str | None = None
    frame: int | None = None
    motion_type: int | None = None
    offset_type: int | None = None
    locations: list[str] = field(default_factory=list)  # where each point came from ("line 3", "points[0]")


@dataclass(frozen=True)
class PathSettings:
    """What pathLoad needs besides the points."""

    path_name: str
    frame: int
    motion_type: int
    offset_type: int


# ---------------------------------------------------------------- values


def _number(raw: Any, err: Callable[[str], PathFileError]) -> float:
    if isinstance(raw, bool):
        raise err(f"{raw!r} is not a number")
    if isinstance(raw, str):
        try:
            v = float(raw.strip())
        except ValueError:
            raise err(f"{shown(raw)} is not a number") from None
    elif isinstance(raw, (int, float)):
        try:
            v = float(raw)
        except OverflowError:
            v = math.inf
    else:
        raise err(f"{shown(raw)} is not a number")
    if not math.isfinite(v):
        raise err(f"{shown(raw)} is not a finite number")
    return v


def _integer(raw: Any, err: Callable[[str], PathFileError]) -> int:
    if isinstance(raw, bool):
        raise err(f"{raw!r} is not an integer")
    if isinstance(raw, int):
        v = raw
    elif isinstance(raw, float) and raw.is_integer():
        v = int(raw)
    elif isinstance(raw, str):
        text = raw.strip()
        if len(text) > 32:  # far beyond 32 bits; int() of thousands of digits is refused (or slow)
            raise err(f"{shown(raw)} is not an integer in {_INT32[0]}..{_INT32[1]}")
        try:
            v = int(text, 0)
        except ValueError:
            raise err(f"{shown(raw)} is not an integer") from None
    else:
        raise err(f"{shown(raw)} is not an integer")
    if not _INT32[0] <= v <= _INT32[1]:
        raise err(f"{shown(str(v), quote=False)} is outside {_INT32[0]}..{_INT32[1]}")
    return v


def _text(raw: Any, max_bytes: int, err: Callable[[str], PathFileError]) -> str:
    if not isinstance(raw, str) or isinstance(raw, _LongInteger):
        raise err(f"{shown(raw)} is not text")
    n = len(raw.encode("utf-8"))
    if n > max_bytes:
        raise err(f"{shown(raw)} is {n} bytes; the firmware holds at most {max_bytes}")
    return raw


def _aux(raw: Any, err: Callable[[str], PathFileError]) -> list[str]:
    if isinstance(raw, str):
        items = raw.split(";")
    elif isinstance(raw, (list, tuple)):
        items = list(raw)
    else:
        raise err(f"{shown(raw)} is not a ';'-separated string or a list of commands")
    out: list[str] = []
    for item in items:
        if not isinstance(item, str):
            raise err(f"{shown(item)} is not a command (text)")
        cmd = item.strip()
        if not cmd:
            if isinstance(raw, str):
                continue  # "a;;b" and a trailing ';' are harmless in a CSV cell
            raise err("an empty command")
        n = len(cmd.encode("utf-8"))
        if n > MAX_AUX_BYTES:
            raise err(f"{shown(cmd)} is {n} bytes; the firmware holds at most {MAX_AUX_BYTES} per command")
        words = cmd.split()
        if len(words) >= 2 and words[0] in ("event", "rsvp"):
            n = len(words[1].encode("utf-8"))
            if n > MAX_EVENT_ID_BYTES:
                raise err(f"{shown(cmd)}: NAME is {n} bytes, a notice's event id holds at most {MAX_EVENT_ID_BYTES} "
                          f"(describe: downlink_limits): use a shorter name")
        out.append(cmd)
    if len(out) > MAX_AUX_COMMANDS:
        raise err(f"{len(out)} commands; the firmware holds at most {MAX_AUX_COMMANDS} per point")
    return out


def _missing(raw: Any) -> bool:
    return raw is None or (isinstance(raw, str) and raw.strip() == "")


def point_from_mapping(values: Mapping[str, Any], kind: str, n_joints: int, file: str,
                       where: str) -> pb.TagPoint:
    """One checked TagPoint from `values` (a CSV row or a YAML/JSON mapping). `kind` and
    `n_joints` say which coordinates every point of the file carries."""
    def err_for(key: str) -> Callable[[str], PathFileError]:
        return lambda problem: PathFileError(file, where, key, problem)

    for key in values:
        if key not in POINT_KEYS:
            raise PathFileError(file, where, shown(str(key), quote=False),
                                f"unknown field; a point has {', '.join(_key_help())}")
    p = pb.TagPoint()
    if kind == "cartesian":
        for key in POSE_KEYS:
            if _missing(values.get(key)):
                raise PathFileError(file, where, key, "missing (a Cartesian point needs x, y, z, roll, pitch, yaw)")
            p.pose.append(_number(values[key], err_for(key)))
        extra = [k for k in JOINT_KEYS if not _missing(values.get(k))]
        if extra:
            raise PathFileError(file, where, extra[0], "a Cartesian path takes no joint values; use one kind per file")
    else:
        for key in JOINT_KEYS[:n_joints]:
            if _missing(values.get(key)):
                raise PathFileError(file, where, key, f"missing (every point of this file needs j1..j{n_joints})")
            p.joints.append(_number(values[key], err_for(key)))
        extra = [k for k in JOINT_KEYS[n_joints:] + POSE_KEYS if not _missing(values.get(k))]
        if extra:
            raise PathFileError(file, where, extra[0], f"unexpected: the points of this file have j1..j{n_joints} "
                                                       f"only (one kind of coordinates per file)")
    if not _missing(values.get("tag_name")):
        p.tag_name = _text(values["tag_name"], MAX_TAG_NAME_BYTES, err_for("tag_name")).strip()
    if not _missing(values.get("tag_index")):
        p.tag_index = _integer(values["tag_index"], err_for("tag_index"))
    if not _missing(values.get("time_delay_s")):
        v = _number(values["time_delay_s"], err_for("time_delay_s"))
        if v < 0:
            raise PathFileError(file, where, "time_delay_s", f"{v:g} is negative")
        p.time_delay_s = v
    for key in ("transition_speed_pct", "speed_pct", "accel_pct"):
        if not _missing(values.get(key)):
            v = _number(values[key], err_for(key))
            if not 0.0 <= v <= 100.0:
                raise PathFileError(file, where, key, f"{v:g} is outside 0..100 (percent)")
            setattr(p, key, v)
    if not _missing(values.get("aux")):
        p.aux_commands.extend(_aux(values["aux"], err_for("aux")))
    return p


def _key_help() -> list[str]:
    return ["x, y, z, roll, pitch, yaw", f"j1..j{_MAX_JOINTS}"] + list(OPTIONAL_KEYS)


def _kind_of(keys: Sequence[str], file: str, where: str) -> tuple[str, int]:
    """(kind, joint count) from the coordinate keys present in the first point or the header."""
    pose = [k for k in keys if k in POSE_KEYS]
    joints = [k for k in keys if k in JOINT_KEYS]
    if pose and joints:
        raise PathFileError(file, where, joints[0], "the file mixes Cartesian (x..yaw) and joint (j1..) "
                                                    "coordinates; use one kind per file")
    if pose:
        return "cartesian", 0
    if joints:
        n = max(JOINT_KEYS.index(k) for k in joints) + 1
        for k in JOINT_KEYS[:n]:
            if k not in joints:
                raise PathFileError(file, where, k, f"missing (joint values run j1..j{n} without a gap)")
        return "joint", n
    raise PathFileError(file, where, None, "no coordinates: name x, y, z, roll, pitch, yaw or j1..jN")


# ---------------------------------------------------------------- files


def _too_many(file: str, where: str, max_points: int) -> PathFileError:
    return PathFileError(file, where, None, f"more than {max_points} points: the device holds at most {max_points} "
                                            f"per path (describe: max_points_per_path); split the file into paths "
                                            f"of at most {max_points} points")


def _parse_csv(text: str, file: str, max_points: int | None = None) -> PathFile:
    rows = csv.reader(io.StringIO(text))
    header: list[str] | None = None
    points: list[pb.TagPoint] = []
    locations: list[str] = []
    kind, n_joints = "", 0
    while True:
        try:
            row = next(rows)
        except StopIteration:
            break
        except csv.Error as exc:  # a NUL byte, a cell beyond the csv module's field limit
            raise PathFileError(file, f"line {rows.line_num}", None, f"not a CSV row: {exc}") from None
        line = rows.line_num
        if not row or all(not c.strip() for c in row):
            continue
        if header is None:
            header = [c.strip() for c in row]
            for c in header:
                if c not in POINT_KEYS:
                    raise PathFileError(file, f"line {line}", shown(c, quote=False) if c else "(empty column name)",
                                        f"unknown column; columns are {', '.join(_key_help())}")
            dup = next((c for c in header if header.count(c) > 1), None)
            if dup is not None:
                raise PathFileError(file, f"line {line}", dup, "column named twice")
            kind, n_joints = _kind_of(header, file, f"line {line}")
            continue
        if max_points is not None and len(points) >= max_points:
            raise _too_many(file, f"line {line}", max_points)
        if len(row) != len(header):
            raise PathFileError(file, f"line {line}", None,
                                f"{len(row)} cells, the header names {len(header)} columns")
        values = {k: v for k, v in zip(header, row, strict=False) if v.strip() != ""}
        points.append(point_from_mapping(values, kind, n_joints, file, f"line {line}"))
        locations.append(f"line {line}")
    if header is None:
        raise PathFileError(file, "", None, "empty file: the first row names the columns (x,y,z,roll,pitch,yaw "
                                            "or j1..j6, then optional ones)")
    if not points:
        raise PathFileError(file, "", None, "no points below the header")
    return PathFile(file, points, kind, locations=locations)


def _parse_tree(data: Any, file: str, max_points: int | None = None) -> PathFile:
    settings: dict[str, Any] = {}
    if isinstance(data, Mapping):
        for key in data:
            if key not in FILE_KEYS:
                raise PathFileError(file, "", shown(str(key), quote=False),
                                    f"unknown key; a path file has {', '.join(FILE_KEYS)}")
        if "points" not in data:
            raise PathFileError(file, "", "points", "missing: list the points under 'points'")
        settings = {k: v for k, v in data.items() if k != "points" and v is not None}
        items = data["points"]
    else:
        items = data
    if not isinstance(items, list):
        raise PathFileError(file, "", "points" if settings or isinstance(data, Mapping) else None,
                            "expected a list of points (mappings with x, y, z, roll, pitch, yaw or j1..jN)")
    if not items:
        raise PathFileError(file, "", "points", "no points")
    if max_points is not None and len(items) > max_points:
        raise _too_many(file, f"points[{max_points}]", max_points)
    pf = PathFile(file, [], "")
    if "path" in settings:
        pf.path_name = _check_path_name(settings["path"], file, "path")
    for key, enum in (("frame", pb.ReferenceFrame), ("motion_type", pb.MotionType),
                      ("offset_type", pb.OffsetType)):
        if key in settings:
            try:
                setattr(pf, key, parse_enum(enum.DESCRIPTOR, settings[key]))
            except ArgumentError as exc:
                raise PathFileError(file, "", key, str(exc)) from None
    kind, n_joints = "", 0
    for i, item in enumerate(items):
        where = f"points[{i}]"
        if not isinstance(item, Mapping):
            raise PathFileError(file, where, None, f"{shown(item)} is not a mapping of point fields")
        if i == 0:
            kind, n_joints = _kind_of([str(k) for k in item], file, where)
        pf.points.append(point_from_mapping(item, kind, n_joints, file, where))
        pf.locations.append(where)
    pf.kind = kind
    return pf


def _check_path_name(raw: Any, file: str, what: str) -> str:
    def err(problem: str) -> PathFileError:
        return PathFileError(file, "", what, problem)

    name = _text(raw, MAX_PATH_NAME_BYTES, err).strip()
    if not name:
        raise err("empty path name")
    return name


def parse_path_text(text: str, fmt: str, file: str = "<text>", *, max_points: int | None = None) -> PathFile:
    """Parse and check path-file `text` of format "csv", "yaml" or "json" (pure). With
    `max_points`, more points than that is an error (the device's limit)."""
    if fmt == "csv":
        return _parse_csv(text, file, max_points)
    if fmt not in ("json", "yaml"):
        raise ArgumentError(f"unknown path file format '{fmt}': use csv, yaml or json")
    try:
        if fmt == "json":
            try:
                data = json.loads(text, parse_int=_json_int)
            except json.JSONDecodeError as exc:
                raise PathFileError(file, f"line {exc.lineno}", None, f"not valid JSON: {exc.msg}") from None
        else:
            import yaml

            try:
                data = yaml.safe_load(text)
            except yaml.YAMLError as exc:
                mark = getattr(exc, "problem_mark", None)
                where = f"line {mark.line + 1}" if mark is not None else ""
                problem = getattr(exc, "problem", None) or str(exc)
                raise PathFileError(file, where, None, f"not valid YAML: {problem}") from None
    except RecursionError:
        raise PathFileError(file, "", None, "nested too deeply: a path file is a list of points (or a mapping "
                                            "with 'points')") from None
    except PathFileError:
        raise
    except ValueError as exc:  # YAML: an integer of more than sys.get_int_max_str_digits() digits
        problem = (f"an integer of more than {sys.get_int_max_str_digits()} digits: no field of a point takes "
                   f"such a number" if "digits" in str(exc) else f"a value cannot be read: {_one_line(str(exc))}")
        raise PathFileError(file, "", None, problem) from None
    if data is None:
        raise PathFileError(file, "", None, "empty file: list the points")
    try:
        return _parse_tree(data, file, max_points)
    except RecursionError:
        raise PathFileError(file, "", None, "nested too deeply: a path file is a list of points") from None


def _one_line(text: str) -> str:
    return " ".join(text.split())


def load_path_file(path: str | Path, *, max_points: int | None = None) -> PathFile:
    """Read and check a whole path file; the format comes from its extension. With
    `max_points` (the device's points per path), a file of more points, or of more than
    max_file_bytes(max_points) bytes, is refused without reading it all."""
    p = Path(path)
    fmt = SUFFIXES.get(p.suffix.lower())
    if fmt is None:
        raise PathFileError(str(p), "", None, f"unknown file type '{p.suffix}': use .csv, .yaml, .yml or .json")
    limit = None if max_points is None else max_file_bytes(max_points)
    try:
        with p.open("rb") as f:
            raw = f.read() if limit is None else f.read(limit + 1)
    except OSError as exc:
        raise PathFileError(str(p), "", None, f"cannot read it: {exc.strerror or exc}") from None
    if limit is not None and max_points is not None and len(raw) > limit:
        raise PathFileError(str(p), "", None, f"more than {limit} bytes: a path of at most {max_points} points "
                                              f"(the device's limit, describe: max_points_per_path) takes at most "
                                              f"{MAX_POINT_TEXT_BYTES} bytes per point; split the file")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = raw.count(b"\n", 0, exc.start) + 1
        raise PathFileError(str(p), f"line {line}", None, f"not UTF-8 text (byte {raw[exc.start]:#04x} at offset "
                                                          f"{exc.start}): save the file as UTF-8") from None
    return parse_path_text(text, fmt, str(p), max_points=max_points)


def resolve_settings(pf: PathFile, *, path_name: str | None = None, frame: int | str | None = None,
                     motion_type: int | str | None = None, offset_type: int | str | None = None) -> PathSettings:
    """The pathLoad settings: arguments first, then the file's, then defaults (name: the
    file's stem; frame: JOINT_FRAME for joint values, BASE_CARTESIAN_FRAME for poses;
    motion: JOINT_MOTION or STRAIGHT_MOTION likewise; offset: ABSOLUTE_DATA)."""
    name = path_name if path_name is not None else pf.path_name
    name = _check_path_name(name if name is not None else Path(pf.file).stem, pf.file, "path name")
    fr = parse_enum(pb.ReferenceFrame.DESCRIPTOR, frame) if frame is not None else pf.frame
    if fr is None:
        fr = pb.JOINT_FRAME if pf.kind == "joint" else pb.BASE_CARTESIAN_FRAME
    if pf.kind == "joint" and fr != pb.JOINT_FRAME:
        raise PathFileError(pf.file, "", "frame", f"{pb.ReferenceFrame.Name(fr)} needs Cartesian points "
                                                  f"(x..yaw); the file has joint values")
    if pf.kind == "cartesian" and fr == pb.JOINT_FRAME:
        raise PathFileError(pf.file, "", "frame", "JOINT_FRAME needs joint values (j1..); the file has "
                                                  "Cartesian points: choose base, world or tool")
    mt = parse_enum(pb.MotionType.DESCRIPTOR, motion_type) if motion_type is not None else pf.motion_type
    if mt is None:
        mt = pb.JOINT_MOTION if pf.kind == "joint" else pb.STRAIGHT_MOTION
    ot = parse_enum(pb.OffsetType.DESCRIPTOR, offset_type) if offset_type is not None else pf.offset_type
    return PathSettings(name, fr, mt, pb.ABSOLUTE_DATA if ot is None else ot)


# ---------------------------------------------------------------- chunking


def uplink_size(req: pb.Request) -> int:
    """Bytes of `req` as an ISO-TP message (an Uplink), sized with the largest seq."""
    sized = pb.Request()
    sized.CopyFrom(req)
    sized.seq = _SEQ_MAX
    return pb.Uplink(request=sized).ByteSize()


def _path_load(path_name: str, points: Sequence[pb.TagPoint], frame: int, motion_type: int,
               offset_type: int) -> pb.Request:
    return build_request("path_load", 0, path_name=path_name, frame=frame, motion_type=motion_type,
                         offset_type=offset_type, number_of_points=len(points), tags=list(points))


def build_path_load_requests(path_name: str, points: Sequence[pb.TagPoint | Mapping[str, Any]], *,
                             frame: int | str = pb.JOINT_FRAME, motion_type: int | str = pb.JOINT_MOTION,
                             offset_type: int | str = pb.ABSOLUTE_DATA,
                             max_message_bytes: int = MAX_MESSAGE_BYTES,
                             max_points: int = PATH_LOAD_MAX_POINTS) -> list[pb.Request]:
    """The pathLoad requests (seq 0) that carry `points` in order, each holding as many
    points as fit: at most `max_points` and `max_message_bytes` encoded (Uplink, any seq).
    Pure; raises ArgumentError for no points or a point that fits no message alone."""
    if not points:
        raise ArgumentError(f"path '{path_name}': no points to load")
    if max_points < 1:
        raise ArgumentError("max_points must be >= 1")
    fr = parse_enum(pb.ReferenceFrame.DESCRIPTOR, frame)
    mt = parse_enum(pb.MotionType.DESCRIPTOR, motion_type)
    ot = parse_enum(pb.OffsetType.DESCRIPTOR, offset_type)
    tags: list[pb.TagPoint] = []
    for p in points:
        if isinstance(p, pb.TagPoint):
            tags.append(p)
        else:
            tags.append(build_request("path_load", 0, tags=[p]).path_load.tags[0])  # checks names and types
    out: list[pb.Request] = []
    chunk: list[pb.TagPoint] = []
    for i, tag in enumerate(tags):
        trial = chunk + [tag]
        if len(trial) <= max_points and uplink_size(_path_load(path_name, trial, fr, mt, ot)) <= max_message_bytes:
            chunk = trial
            continue
        if chunk:
            out.append(_path_load(path_name, chunk, fr, mt, ot))
        chunk = [tag]
        size = uplink_size(_path_load(path_name, chunk, fr, mt, ot))
        if size > max_message_bytes:
            raise ArgumentError(f"path '{path_name}': point {i} alone needs {size} bytes, more than one "
                                f"message holds ({max_message_bytes})")
    out.append(_path_load(path_name, chunk, fr, mt, ot))
    return out


def request_fields(req: pb.Request) -> dict[str, Any]:
    """The command fields of `req` as keyword arguments for Supervisor.request (messages stay messages)."""
    which = req.WhichOneof("cmd")
    if which is None:
        raise ArgumentError("the request carries no command")
    sub: Message = getattr(req, which)
    out: dict[str, Any] = {}
    for fd in sub.DESCRIPTOR.fields:
        value = getattr(sub, fd.name)
        out[fd.name] = list(value) if hasattr(value, "__len__") and not isinstance(value, (str, bytes)) else value
    return out
