"""Robot model files on the host: check one before it goes on a controller, and make one from a URDF.

A model file describes the arm landscaped runs (docs/deploy.md "Describe your arm"): DH geometry, joint and
Cartesian limits, torques, link masses and the workspace, every key required and each value a number with
its unit. landscaped reads it with firmware/model/ls_robot_model_file.c; this module reads it the same way
and refuses the same files with the same line (tests/integration/test_model_file.py runs both on every
kind of bad file). The keys, their units and ranges come from that C file's table, as the generated
`_generated/robot-model-keys.json` (`ls_robot_model keys`, host_tools/update_generated.sh); the reading
rules (inih's, as landscaped uses it) and the IK classes (firmware/kinematics/ls_kin.cpp,
`ls_kin_classify`) are written here again, and that test keeps them equal.

`from_urdf` converts a serial 6-joint URDF (revolute joints, one chain from the base to the flange) into a
model file: the DH parameters of the joint axes at zero, the limits, torques and masses the URDF has, and
stated choices for what a URDF does not carry (accelerations, jerks, Cartesian limits, workspace). It
refuses what a model file cannot represent, with the reason.
"""
from __future__ import annotations

import json
import math
import os
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from functools import cache
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from .errors import LandscapeError
from .urdf import rpy_matrix

N_JOINTS = 6
# inih's line buffer (INI_MAX_LINE of Debian's libinih): landscaped refuses longer lines.
INI_MAX_LINE = 200
SECTIONS_TEXT = "[robot], [joint.1] .. [joint.6] or [cartesian]"
SECTION_NAMES = ("robot", *(f"joint.{j}" for j in range(1, N_JOINTS + 1)), "cartesian")
DOCS = 'docs/deploy.md "Describe your arm"'
_NUMBER = re.compile(r"[+-]?([0-9]+(\.[0-9]*)?|\.[0-9]+)([eE][+-]?[0-9]+)?")
_STRUCT_TOL = 1e-12  # ls_kin.cpp kStructTol

Matrix = npt.NDArray[np.float64]


class ModelError(LandscapeError):
    """A robot model file (or a URDF to convert) is refused; the message is landscaped's one line."""


@dataclass(frozen=True)
class Unit:
    name: str
    multiply: float
    divide: float


@dataclass(frozen=True)
class Key:
    section: str        # "robot", "joint" or "cartesian"
    key: str
    quantity: str       # "an angle"
    min: float
    max: float
    min_open: bool
    range: str
    expected: str       # what a refusal says is allowed
    what: str


@dataclass(frozen=True)
class KeyTable:
    keys: tuple[Key, ...]
    units: dict[str, tuple[Unit, ...]]
    name_max: int


@cache
def key_table() -> KeyTable:
    """The firmware's key table (the generated JSON this package carries)."""
    raw: dict[str, Any] = json.loads(resources.files("landscape._generated")
                                     .joinpath("robot-model-keys.json").read_text(encoding="utf-8"))
    units = {q: tuple(Unit(u["name"], float(u["multiply"]), float(u["divide"])) for u in us)
             for q, us in raw["quantities"].items()}
    keys = tuple(Key(k["section"], k["key"], k["quantity"], float(k["min"]), float(k["max"]), bool(k["min_open"]),
                     k["range"], k["expected"], k["what"]) for k in raw["keys"])
    return KeyTable(keys, units, int(raw["name_max"]))


@dataclass
class RobotModel:
    """A model file's values in SI units (m, rad, s, kg, Nm), as landscaped holds them."""

    name: str = ""
    link_radius_m: float = 0.0
    joints: list[dict[str, float]] = field(default_factory=lambda: [{} for _ in range(N_JOINTS)])
    cartesian: dict[str, float] = field(default_factory=dict)
    workspace_min_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    workspace_max_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    ik_class: str = ""

    def dh(self) -> list[tuple[float, float, float, float]]:
        """(a, alpha, d, theta_offset) per joint."""
        return [(j["a"], j["alpha"], j["d"], j["theta_offset"]) for j in self.joints]

    def fk(self, q: list[float] | npt.NDArray[np.float64]) -> Matrix:
        """The flange in the base frame (4x4) for joint angles q: the DH product ls_kin_fk computes."""
        return dh_fk(self.dh(), q)

    def reach_m(self) -> float:
        """ls_robot_model_reach_m: the sum of the links' lengths."""
        return sum(math.hypot(a, d) for a, _, d, _ in self.dh())


def dh_fk(dh: list[tuple[float, float, float, float]], q: list[float] | npt.NDArray[np.float64]) -> Matrix:
    T = np.eye(4)
    for (a, alpha, d, off), qi in zip(dh, q, strict=True):
        t = float(qi) + off
        ct, st, ca, sa = math.cos(t), math.sin(t), math.cos(alpha), math.sin(alpha)
        T = T @ np.array([[ct, -st * ca, st * sa, a * ct], [st, ct * ca, -ct * sa, a * st], [0, sa, ca, d],
                          [0, 0, 0, 1]])
    return T


# ---------------------------------------------------------------- reading (ls_robot_model_file.c's rules)


def _find(s: str, chars: str) -> int:
    """inih's find_chars_or_comment: the index of the first of `chars`, or of a ';' after a blank, or len."""
    was_space = False
    for i, c in enumerate(s):
        if c in chars or (was_space and c == ";"):
            return i
        was_space = c in " \t\n\v\f\r"
    return len(s)


def _quantity(k: Key, text: str) -> list[float] | None:
    toks = [t for t in re.split(r"[ \t]+", text) if t]
    n = 3 if k.quantity == "a point" else 1
    if len(toks) != n + 1 or len(text.encode("utf-8")) >= 128:
        return None
    unit = next((u for u in key_table().units[k.quantity] if u.name == toks[n]), None)
    if unit is None:
        return None
    out = []
    for tok in toks[:n]:
        if not _NUMBER.fullmatch(tok):
            return None
        v = float(tok)
        if not math.isfinite(v):
            return None
        v = v * unit.multiply / unit.divide
        if not ((v > k.min) if k.min_open else (v >= k.min)) or not v <= k.max:
            return None
        out.append(v)
    return out


class _Reader:
    def __init__(self, path: str) -> None:
        self.path = path
        self.m = RobotModel()
        self.seen: dict[tuple[str, str], int] = {}
        self.text: dict[tuple[str, str], str] = {}

    def fail(self, line: int, msg: str) -> ModelError:
        return ModelError(f"{self.path}:{line}: {msg}" if line > 0 else f"{self.path}: {msg}")

    def key(self, line: int, section: str, name: str, value: str) -> None:
        if section == "":
            raise self.fail(line, f"key '{name}' outside any section: put it under {SECTIONS_TEXT}")
        kind = "joint" if section.startswith("joint") else section
        keys = [k for k in key_table().keys if k.section == kind]
        k = next((k for k in keys if k.key == name), None)
        if k is None:
            raise self.fail(line, f"[{section}] {name}: unknown key; expected one of {', '.join(x.key for x in keys)}")
        if (section, name) in self.seen:
            raise self.fail(line, f"[{section}] {name}: given twice (first on line {self.seen[section, name]}); "
                                  "keep one")
        self.seen[section, name] = line
        self.text[section, name] = value
        if k.quantity == "a name":
            if not 0 < len(value) <= key_table().name_max or any(not 0x20 <= ord(c) <= 0x7E for c in value):
                raise self.fail(line, f"[{section}] {name}: got '{value}', expected {k.expected}")
            self.m.name = value
            return
        v = _quantity(k, value)
        if v is None:
            raise self.fail(line, f"[{section}] {name}: got '{value}', expected {k.expected}")
        if section == "robot":
            self.m.link_radius_m = v[0]
        elif kind == "joint":
            self.m.joints[int(section[6:]) - 1][name] = v[0]
        elif name == "workspace_min":
            self.m.workspace_min_m = (v[0], v[1], v[2])
        elif name == "workspace_max":
            self.m.workspace_max_m = (v[0], v[1], v[2])
        else:
            self.m.cartesian[name] = v[0]

    def lines(self, data: bytes) -> None:
        section = ""
        text = data.decode("utf-8", errors="replace")
        rows = text.split("\n")
        if rows and rows[-1] == "":
            rows.pop()
        for n, raw in enumerate(rows, 1):
            if "\0" in raw:
                raise self.fail(n, "a NUL byte in the line: this is not a text file")
            if len(raw) + 1 >= INI_MAX_LINE and n < len(rows):
                raise self.fail(n, f"line longer than {INI_MAX_LINE - 3} characters")
            line = raw.removeprefix("\ufeff") if n == 1 else raw
            line = line.lstrip(" \t").rstrip(" \t\n\v\f\r")
            if not line or line[0] in ";#":
                continue
            if line[0] == "[":
                end = line.find("]")
                if end >= 0 and line[1:end] not in SECTION_NAMES:
                    raise self.fail(n, f"unknown section [{line[1:end]}]; expected {SECTIONS_TEXT}")
                end = _find(line[1:], "]") + 1
                if end >= len(line) or line[end] != "]":
                    raise self.fail(n, "syntax error: expected '[section]', 'key = value' or a ; or # comment")
                section = line[1:end]
                continue
            at = _find(line, "=:")
            if at >= len(line) or line[at] not in "=:":
                raise self.fail(n, "syntax error: expected '[section]', 'key = value' or a ; or # comment")
            name = line[:at].rstrip(" \t\n\v\f\r")
            value = line[at + 1:].lstrip(" \t\n\v\f\r")
            value = value[:_find(value, "")].rstrip(" \t\n\v\f\r")
            self.key(n, section, name, value)

    def whole(self) -> RobotModel:
        for section in SECTION_NAMES:
            kind = "joint" if section.startswith("joint") else section
            for k in key_table().keys:
                if k.section == kind and (section, k.key) not in self.seen:
                    raise self.fail(0, f"[{section}] {k.key}: missing; every key is required ({DOCS})")
        for j, joint in enumerate(self.m.joints, 1):
            s = f"joint.{j}"
            if not joint["max"] > joint["min"]:
                raise self.fail(self.seen[s, "max"], f"[{s}] max: got '{self.text[s, 'max']}', expected above min = "
                                                      f"{self.text[s, 'min']} (line {self.seen[s, 'min']})")
        for axis, lo, hi in zip("xyz", self.m.workspace_min_m, self.m.workspace_max_m, strict=True):
            if not hi > lo:
                raise self.fail(self.seen["cartesian", "workspace_max"],
                                f"[cartesian] workspace_max: got '{self.text['cartesian', 'workspace_max']}', expected "
                                f"above workspace_min = {self.text['cartesian', 'workspace_min']} (line "
                                f"{self.seen['cartesian', 'workspace_min']}) on every axis; {axis} is not")
        try:
            self.m.ik_class = classify(self.m.dh(), [(j["min"], j["max"]) for j in self.m.joints])
        except ModelError as exc:
            raise self.fail(0, f"no closed-form inverse kinematics fits this arm: {exc} "
                               '(docs/architecture.md "Inverse kinematics")') from None
        return self.m


def parse_model(data: bytes, path: str) -> RobotModel:
    """A model file's bytes, read as landscaped reads them; ModelError with its one line, naming `path`."""
    r = _Reader(path)
    r.lines(data)
    return r.whole()


def load_model(path: str | Path) -> RobotModel:
    """Read and check the model file at `path` (ModelError: landscaped's refusal, word for word)."""
    p = str(path)
    try:
        data = Path(p).read_bytes()
    except OSError as exc:
        why = os.strerror(exc.errno) if exc.errno is not None else str(exc)
        raise ModelError(f"{p}: cannot read the robot model file: {why} (name an existing file in [robot] model "
                         "or --model)") from None
    return parse_model(data, p)


# ---------------------------------------------------------------- IK classes (ls_kin_classify)


def _deg(rad: float) -> float:
    return rad * 180.0 / math.pi


def _right_angle(alpha: float) -> bool:
    return abs(math.cos(alpha)) < _STRUCT_TOL


def _parallel(alpha: float) -> bool:
    return abs(math.sin(alpha)) < _STRUCT_TOL and math.cos(alpha) > 0.0


def _wrist_and_shoulder_misfit(alpha1: float, alpha4: float, alpha5: float) -> str | None:
    if not _right_angle(alpha4) or not _right_angle(alpha5):
        j, al = (5, alpha5) if _right_angle(alpha4) else (4, alpha4)
        return f"alpha{j} = {_deg(al):.6g} deg; alpha4 and alpha5 must be +-90 deg"
    if abs(math.sin(alpha1)) <= 1e-9:
        return f"alpha1 = {_deg(alpha1):.6g} deg; joint 1 must not be parallel to joint 2"
    return None


def _spherical_misfit(dh: list[tuple[float, float, float, float]]) -> str | None:
    (_, a1, _, _), (a2l, al2, _, _), (a3l, _, _, _), (a4l, al4, d4, _), (a5l, al5, d5, _), (a6l, _, _, _) = dh
    for name, v in (("a4", a4l), ("a5", a5l), ("a6", a6l), ("d5", d5)):
        if not abs(v) < _STRUCT_TOL:
            return f"{name} = {v:.6g} m; a4, a5, a6 and d5 must be 0 so that joints 4-6 meet"
    if not _parallel(al2):
        return f"alpha2 = {_deg(al2):.6g} deg; it must be 0 so that joints 2 and 3 are parallel"
    common = _wrist_and_shoulder_misfit(a1, al4, al5)
    if common is not None:
        return common
    if abs(a2l) <= 1e-9 or math.hypot(a3l, d4) <= 1e-9:
        what = "a2 = 0 m" if abs(a2l) <= 1e-9 else "a3 = d4 = 0 m"
        return f"{what}; the upper arm (a2) and the forearm (a3, d4) must not be 0"
    return None


def _offset_misfit(dh: list[tuple[float, float, float, float]]) -> str | None:
    (_, a1, _, _), (a2l, al2, _, _), (a3l, al3, _, _), (a4l, al4, _, _), (a5l, al5, _, _), (a6l, _, _, _) = dh
    for j, v in ((4, a4l), (5, a5l), (6, a6l)):
        if not abs(v) < _STRUCT_TOL:
            return f"a{j} = {v:.6g} m; a4, a5 and a6 must be 0"
    if not _parallel(al2) or not _parallel(al3):
        j, al = (3, al3) if _parallel(al2) else (2, al2)
        return f"alpha{j} = {_deg(al):.6g} deg; alpha2 and alpha3 must be 0 so that joints 2-4 are parallel"
    common = _wrist_and_shoulder_misfit(a1, al4, al5)
    if common is not None:
        return common
    if abs(a2l) <= 1e-9 or abs(a3l) <= 1e-9:
        return f"a{2 if abs(a2l) <= 1e-9 else 3} = 0 m; the upper arm (a2) and the forearm (a3) must not be 0"
    return None


def classify(dh: list[tuple[float, float, float, float]], limits: list[tuple[float, float]]) -> str:
    """The IK class a geometry fits ("spherical_wrist", "offset_wrist"), as ls_kin_classify decides;
    ModelError with what each class needs when none fits."""
    for j, ((a, al, d, off), (lo, hi)) in enumerate(zip(dh, limits, strict=True), 1):
        if not all(math.isfinite(v) for v in (a, al, d, off, lo, hi)):
            raise ModelError(f"joint {j} has a non-finite DH parameter or limit")
        if lo > hi:
            raise ModelError(f"joint {j}: q_min {lo:.6g} rad is above q_max {hi:.6g} rad")
    sph = _spherical_misfit(dh)
    if sph is None:
        return "spherical_wrist"
    offset = _offset_misfit(dh)
    if offset is None:
        return "offset_wrist"
    raise ModelError(f"not a spherical wrist ({sph}) and not an offset wrist ({offset})")


# ---------------------------------------------------------------- from a URDF


@dataclass(frozen=True)
class _Joint:
    name: str
    type: str
    parent: str
    child: str
    origin: Matrix
    axis: Matrix
    limit: dict[str, float]


def _vec(text: str | None, default: str, what: str) -> list[float]:
    try:
        v = [float(x) for x in (text if text is not None else default).split()]
    except ValueError:
        raise ModelError(f"{what}: '{text}' is not three numbers") from None
    if len(v) != 3 or not all(math.isfinite(x) for x in v):
        raise ModelError(f"{what}: '{text}' is not three finite numbers")
    return v


def _urdf_joints(root: ET.Element, where: str) -> list[_Joint]:
    out = []
    for j in root.findall("joint"):
        name, jtype = j.get("name", "?"), j.get("type", "")
        if jtype == "prismatic":
            raise ModelError(f"{where}: joint {name} is prismatic: a robot model has revolute joints only")
        if jtype not in ("revolute", "continuous", "fixed"):
            raise ModelError(f"{where}: joint {name} is of type '{jtype}': a robot model has revolute joints "
                             "(and fixed ones between them) only")
        mimic = j.find("mimic")
        if mimic is not None:
            raise ModelError(f"{where}: joint {name} mimics joint {mimic.get('joint', '?')}: a robot model has six "
                             "independent joints")
        par, chi = j.find("parent"), j.find("child")
        if par is None or chi is None or not par.get("link") or not chi.get("link"):
            raise ModelError(f"{where}: joint {name} has no parent or child link")
        o = j.find("origin")
        T = np.eye(4)
        T[:3, :3] = rpy_matrix(*_vec(o.get("rpy") if o is not None else None, "0 0 0", f"{where}: joint {name} rpy"))
        T[:3, 3] = _vec(o.get("xyz") if o is not None else None, "0 0 0", f"{where}: joint {name} xyz")
        a = j.find("axis")
        axis = np.array(_vec(a.get("xyz") if a is not None else None, "1 0 0", f"{where}: joint {name} axis"))
        if jtype != "fixed" and not float(np.linalg.norm(axis)) > 0:
            raise ModelError(f"{where}: joint {name} has a zero axis")
        limit: dict[str, float] = {}
        lim = j.find("limit")
        if lim is not None:
            for attr in ("lower", "upper", "velocity", "effort"):
                if lim.get(attr) is not None:
                    try:
                        limit[attr] = float(lim.get(attr, ""))
                    except ValueError:
                        raise ModelError(f"{where}: joint {name} limit {attr}='{lim.get(attr)}' is not a number") \
                            from None
        out.append(_Joint(name, jtype, par.get("link", ""), chi.get("link", ""), T,
                          axis / (float(np.linalg.norm(axis)) or 1.0), limit))
    return out


def _chain(joints: list[_Joint], base: str | None, tip: str | None, where: str) -> tuple[str, list[_Joint]]:
    """The joints from the base link to the tip: one path, with every movable joint of the URDF on it."""
    children: dict[str, list[_Joint]] = {}
    for j in joints:
        children.setdefault(j.parent, []).append(j)
    if base is None:
        roots = sorted({j.parent for j in joints} - {j.child for j in joints})
        if len(roots) != 1:
            raise ModelError(f"{where}: {len(roots)} root links ({', '.join(roots) or 'none'}): not one tree; "
                             "name the base with --base LINK")
        base = roots[0]

    def movable_below(link: str, seen: frozenset[str] = frozenset()) -> int:
        if link in seen:
            raise ModelError(f"{where}: the links form a loop at {link}: not a serial arm")
        return sum((j.type != "fixed") + movable_below(j.child, seen | {link}) for j in children.get(link, []))

    path: list[_Joint] = []
    link = base
    while True:
        moving = [j for j in children.get(link, []) if j.type != "fixed" or movable_below(j.child) > 0]
        if len(moving) > 1:
            raise ModelError(f"{where}: link {link} branches into joints {moving[0].name} and {moving[1].name} that "
                             "both lead to moving joints: a robot model is one chain from base to flange")
        n_moving = sum(j.type != "fixed" for j in path)
        if not moving:
            break
        path.append(moving[0])
        link = moving[0].child
        if n_moving + (moving[0].type != "fixed") == N_JOINTS:
            break
    movable = [j for j in path if j.type != "fixed"]
    total = movable_below(base)
    if total != N_JOINTS:
        raise ModelError(f"{where}: {total} moving joints below {base}; a robot model has {N_JOINTS}")
    if tip is None:  # the end of the fixed links the last joint carries, if they are one chain
        while children.get(link):
            nxt = children[link]
            if len(nxt) > 1:
                raise ModelError(f"{where}: below joint {movable[-1].name} the links branch at {link} "
                                 f"({', '.join(j.child for j in nxt)}): name the flange with --tip LINK")
            path.append(nxt[0])
            link = nxt[0].child
    while link != tip and tip is not None:
        fixed_to_tip = [j for j in children.get(link, []) if _reaches(children, j.child, tip)]
        if not fixed_to_tip:
            raise ModelError(f"{where}: link {tip} is not fixed below joint {movable[-1].name}: choose a --tip link "
                             "the last joint carries")
        path.append(fixed_to_tip[0])
        link = fixed_to_tip[0].child
    return base, path


def _reaches(children: dict[str, list[_Joint]], link: str, tip: str) -> bool:
    return link == tip or any(_reaches(children, j.child, tip) for j in children.get(link, []))


def _angle(a: Matrix, b: Matrix, about: Matrix) -> float:
    """The angle that turns unit vector a into b about the axis `about` (both perpendicular to it)."""
    return math.atan2(float(np.dot(np.cross(a, b), about)), float(np.dot(a, b)))


@dataclass(frozen=True)
class _Line:
    point: Matrix
    dir: Matrix


def _dh_link(origin: Matrix, x_prev: Matrix, z_prev: Matrix, nxt: _Line, tol: float = 1e-9
             ) -> tuple[tuple[float, float, float, float], Matrix, Matrix]:
    """The DH parameters from frame i-1 (origin, x, z) to the next axis line: (a, alpha, d, theta) and the
    next frame's origin and x."""
    z = nxt.dir
    n = np.cross(z_prev, z)
    w = nxt.point - origin
    if float(np.linalg.norm(n)) > tol:  # skew or intersecting: the common normal
        x = n / float(np.linalg.norm(n))
        # origin + t z_prev + a x = point + s z
        A = np.column_stack([z_prev, x, -z])
        t, a, s = (float(v) for v in np.linalg.solve(A, w))
        foot, nxt_origin = origin + t * z_prev, nxt.point + s * z
    else:  # parallel: the common normal through the previous origin (d = 0)
        foot = origin
        nxt_origin = nxt.point + float(np.dot(origin - nxt.point, z)) * z
        off = nxt_origin - foot
        a = float(np.linalg.norm(off))
        x = off / a if a > tol else x_prev
        if a <= tol:
            a = 0.0
    d = float(np.dot(foot - origin, z_prev))
    theta = _angle(x_prev, x, z_prev)
    alpha = _angle(z_prev, z, x)
    return (a, alpha, d, theta), nxt_origin, x


def _number(v: float, unit: str) -> str:
    return f"{0.0 if abs(v) < 1e-15 else v!r} {unit}"


def _angle_text(rad: float) -> str:
    d = math.degrees(rad)
    r = round(d, 6)
    if abs(d - r) < 1e-9 and r * (math.pi / 180.0) == rad or abs(rad) < 1e-15:
        return f"{0 if abs(rad) < 1e-15 else r:g} deg"
    return f"{rad!r} rad"


def from_urdf(text: str, where: str, *, name: str | None = None, base: str | None = None,
              tip: str | None = None) -> tuple[str, RobotModel, list[str]]:
    """A model file for the arm of a URDF: (its text, the model as landscaped will read it, the keys chosen
    because the URDF does not carry them). ModelError naming what cannot be represented."""
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise ModelError(f"{where}: not a URDF (XML): {exc}") from None
    if root.tag != "robot":
        raise ModelError(f"{where}: not a URDF: the root element is <{root.tag}>, not <robot>")
    joints = _urdf_joints(root, where)
    base_link, path = _chain(joints, base, tip, where)
    masses = {lk.get("name", ""): float(m.get("value", "0")) for lk in root.findall("link")
              for m in [lk.find("inertial/mass")] if m is not None}

    # Every joint's axis (a line) and the tip's frame in the base frame, at zero.
    T = np.eye(4)
    axes: list[_Line] = []
    movable: list[_Joint] = []
    mass = [0.0] * N_JOINTS
    for j in path:
        T = T @ j.origin
        if j.type != "fixed":
            axes.append(_Line(T[:3, 3].copy(), T[:3, :3] @ j.axis))
            movable.append(j)
        if movable:
            mass[len(movable) - 1] += masses.get(j.child, 0.0)
    flange = T
    z0 = np.array([0.0, 0.0, 1.0])
    if float(np.linalg.norm(np.cross(axes[0].dir, z0))) > 1e-9 or float(np.dot(axes[0].dir, z0)) < 0 \
            or float(np.linalg.norm(axes[0].point[:2])) > 1e-9:
        raise ModelError(f"{where}: joint {movable[0].name} does not turn about +z of {base_link} through its origin "
                         f"(axis {np.round(axes[0].dir, 6).tolist()} at {np.round(axes[0].point, 6).tolist()}): a "
                         "robot model's base frame has joint 1 as its z axis; choose --base, or re-root the URDF")
    dh: list[tuple[float, float, float, float]] = []
    origin, x, z = np.zeros(3), np.array([1.0, 0.0, 0.0]), z0
    for i in range(1, N_JOINTS):
        row, origin, x = _dh_link(origin, x, z, axes[i])
        z = axes[i].dir
        dh.append(row)
    # Frame 6 is the flange, Rz(theta6) Tz(d6) Tx(a6) Rx(alpha6) from frame 5: its x axis must be
    # perpendicular to joint 6's axis and meet it.
    xf, zf, pf = flange[:3, 0], flange[:3, 2], flange[:3, 3]
    d6, a6 = float(np.dot(pf - origin, z)), float(np.dot(pf - origin, xf))
    if abs(float(np.dot(xf, z))) > 1e-9 or float(np.linalg.norm(pf - origin - d6 * z - a6 * xf)) > 1e-9:
        raise ModelError(f"{where}: the frame of {path[-1].child} is not a DH frame of joint {movable[-1].name} "
                         "(its x axis must be perpendicular to the joint's axis and meet it): choose another --tip, "
                         "or reach that frame with setToolOffset")
    dh.append((a6, _angle(z, zf, xf), d6, _angle(x, xf, z)))
    chosen: list[str] = []
    robot_name = name if name is not None else root.get("name", "") or Path(where).stem
    lines = [f"# {robot_name}: converted from the URDF {Path(where).name} by `landscape model from-urdf`.",
             "#",
             "# From the URDF: the DH geometry of its joint axes at zero, joint ranges, velocities, efforts",
             "# (max_torque) and link masses. Not in a URDF, so chosen here: see the comments marked CHOSEN",
             "# and set them from your arm's data sheet (docs/deploy.md \"Describe your arm\").", "",
             "[robot]", f"name = {robot_name}",
             "# CHOSEN: capsule radius of the simulated links and the URDF's visuals", "link_radius = 0.04 m"]
    chosen.append("link_radius")
    for i, (j, (a, al, d, off)) in enumerate(zip(movable, dh, strict=True), 1):
        lim = j.limit
        if j.type == "continuous":
            lo, hi = -2 * math.pi, 2 * math.pi
        elif "lower" not in lim or "upper" not in lim:
            raise ModelError(f"{where}: joint {j.name} has no lower and upper limit")
        else:
            lo, hi = lim["lower"], lim["upper"]
        vel, eff = lim.get("velocity", 0.0), lim.get("effort", 0.0)
        if not vel > 0 or not eff > 0:
            raise ModelError(f"{where}: joint {j.name} has no velocity and effort limit above 0: a robot model needs "
                             "both")
        m = mass[i - 1]
        lines += ["", f"# URDF joint {j.name}" + (" (continuous: limited to +-360 deg here)" if j.type == "continuous"
                                                 else ""),
                  f"[joint.{i}]", f"a = {_number(a, 'm')}", f"alpha = {_angle_text(al)}", f"d = {_number(d, 'm')}",
                  f"theta_offset = {_angle_text(off)}", f"min = {lo!r} rad", f"max = {hi!r} rad",
                  f"max_velocity = {vel!r} rad/s",
                  "# CHOSEN: full speed in 0.25 s, full acceleration in 0.1 s",
                  f"max_acceleration = {4 * vel!r} rad/s^2", f"max_jerk = {40 * vel!r} rad/s^3",
                  f"max_torque = {eff!r} Nm"]
        if m > 0:
            lines.append(f"mass = {m!r} kg")
        else:
            lines += ["# CHOSEN: no <inertial> mass in the URDF for the links this joint moves", "mass = 1 kg"]
            chosen.append(f"joint.{i} mass")
    chosen += ["max_acceleration", "max_jerk", "[cartesian]"]
    reach = min(9.99, sum(math.hypot(a, d) for a, _, d, _ in dh))
    lines += ["", "# CHOSEN: the tool tip's Cartesian limits, and a workspace box of the arm's reach: narrow it to",
              "# your cell", "[cartesian]", "max_linear_speed = 1 m/s", "max_angular_speed = 3 rad/s",
              "max_linear_acceleration = 4 m/s^2", "max_angular_acceleration = 12 rad/s^2",
              "max_linear_jerk = 40 m/s^3", "max_angular_jerk = 120 rad/s^3",
              f"workspace_min = {-reach:.3f} {-reach:.3f} {-reach:.3f} m",
              f"workspace_max = {reach:.3f} {reach:.3f} {reach:.3f} m", ""]
    out = "\n".join(lines)
    try:
        model = parse_model(out.encode(), where)
    except ModelError as exc:
        raise ModelError(f"{where}: converts to a robot model landscaped refuses: {exc}") from None
    return out, model, chosen
