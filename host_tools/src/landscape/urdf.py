"""The arm's URDF and its kinematic chain.

The device writes the URDF of the robot model it runs (firmware/model/ls_robot_urdf.c) and sends it in
pieces (describeRobot, docs/protocol.md "Robot description"): `robot_urdf` joins them, so `landscape urdf`,
`view` and `record` show the arm that is really there. The package also carries `_generated/ls-sim6.urdf`,
what `ls_urdf` prints for the compiled-in default arm (`urdf_text`, for use without a device).
`ArmChain` reads the joints of a URDF (standard library XML, no URDF package needed at run time) so the
recorder can publish one transform per URDF joint for a 3D panel that loads the same text.
Joint values are the controller's joint angles in rad.
"""
from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Callable
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any, Protocol

import numpy as np
import numpy.typing as npt

from .errors import LandscapeError

URDF_NAME = "ls-sim6.urdf"
BASE_FRAME = "base_link"
FLANGE_FRAME = "flange"

Matrix = npt.NDArray[np.float64]


class UrdfError(LandscapeError):
    """A URDF cannot be read or does not describe a serial arm."""


def urdf_text() -> str:
    """The URDF shipped with the package."""
    return resources.files("landscape._generated").joinpath(URDF_NAME).read_text(encoding="utf-8")


def write_urdf(path: str | Path, text: str | None = None) -> Path:
    """Write a URDF (default: the packaged one of the default arm) to `path` (for a viewer that opens a
    file)."""
    p = Path(path)
    try:
        p.write_text(urdf_text() if text is None else text, encoding="utf-8")
    except OSError as exc:
        raise UrdfError(f"cannot write {p}: {exc.strerror or exc}") from None
    return p


class Answer(Protocol):
    """What robot_urdf needs of an answer (supervisor.RetVal has it)."""

    @property
    def ok(self) -> bool: ...
    @property
    def ret_name(self) -> str: ...
    @property
    def ret_msg(self) -> str: ...
    @property
    def result(self) -> dict[str, Any]: ...


def robot_urdf(ask: Callable[[int], Answer]) -> str:
    """The device's URDF: `ask(offset)` sends describeRobot from that byte (through a Supervisor or a
    background session); the pieces are joined until the length the device states. UrdfError when the
    device refuses, or its pieces do not add up (docs/protocol.md "Robot description")."""
    pieces: list[str] = []
    offset, total = 0, -1
    while offset != total:
        rv = ask(offset)
        if not rv.ok:
            raise UrdfError(f"the device did not send its URDF ({rv.ret_name}: {rv.ret_msg})")
        piece = str(rv.result.get("urdf", ""))
        got_total, got_offset = int(rv.result.get("total_bytes", 0)), int(rv.result.get("offset", 0))
        if total < 0:
            total = got_total
        if got_total != total or got_offset != offset or (not piece and offset < total):
            raise UrdfError(f"the device's URDF pieces do not add up (asked from byte {offset} of {total}, got "
                            f"{len(piece)} bytes from {got_offset} of {got_total}): is the link losing frames?")
        pieces.append(piece)
        offset += len(piece.encode("utf-8"))
        if offset > total:
            raise UrdfError(f"the device sent {offset} bytes of a {total}-byte URDF")
    return "".join(pieces)


def rpy_matrix(roll: float, pitch: float, yaw: float) -> Matrix:
    """URDF's rpy: R = Rz(yaw) Ry(pitch) Rx(roll)."""
    cr, sr, cp, sp, cy, sy = (math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch),
                              math.cos(yaw), math.sin(yaw))
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def axis_angle_matrix(axis: Matrix, angle: float) -> Matrix:
    """Rotation by `angle` about the unit vector `axis` (Rodrigues)."""
    x, y, z = axis
    c, s, v = math.cos(angle), math.sin(angle), 1 - math.cos(angle)
    return np.array([[c + x * x * v, x * y * v - z * s, x * z * v + y * s],
                     [y * x * v + z * s, c + y * y * v, y * z * v - x * s],
                     [z * x * v - y * s, z * y * v + x * s, c + z * z * v]])


def quaternion_xyzw(R: Matrix) -> tuple[float, float, float, float]:
    """Unit quaternion (x, y, z, w) of a rotation matrix (Shepperd's method, w >= 0)."""
    m = R
    tr = float(m[0, 0] + m[1, 1] + m[2, 2])
    if tr > 0:
        s = math.sqrt(tr + 1.0) * 2
        q = ((m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s, 0.25 * s)
    elif m[0, 0] > m[1, 1] and m[0, 0] > m[2, 2]:
        s = math.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2]) * 2
        q = (0.25 * s, (m[0, 1] + m[1, 0]) / s, (m[0, 2] + m[2, 0]) / s, (m[2, 1] - m[1, 2]) / s)
    elif m[1, 1] > m[2, 2]:
        s = math.sqrt(1.0 + m[1, 1] - m[0, 0] - m[2, 2]) * 2
        q = ((m[0, 1] + m[1, 0]) / s, 0.25 * s, (m[1, 2] + m[2, 1]) / s, (m[0, 2] - m[2, 0]) / s)
    else:
        s = math.sqrt(1.0 + m[2, 2] - m[0, 0] - m[1, 1]) * 2
        q = ((m[0, 2] + m[2, 0]) / s, (m[1, 2] + m[2, 1]) / s, 0.25 * s, (m[1, 0] - m[0, 1]) / s)
    x, y, z, w = (float(v) for v in q)
    if w < 0:
        x, y, z, w = -x, -y, -z, -w
    return (x, y, z, w)


@dataclass(frozen=True)
class UrdfJoint:
    name: str
    type: str            # revolute or fixed (the generator writes no other kind)
    parent: str
    child: str
    origin: Matrix       # 4x4, parent frame -> joint frame at q = 0
    axis: Matrix         # unit vector in the joint frame


@dataclass(frozen=True)
class Transform:
    parent: str
    child: str
    translation_m: tuple[float, float, float]
    rotation_xyzw: tuple[float, float, float, float]


def _floats(text: str | None, default: str, what: str) -> list[float]:
    try:
        vals = [float(v) for v in (text if text is not None else default).split()]
    except ValueError:
        raise UrdfError(f"{what}: '{text}' is not three numbers") from None
    if len(vals) != 3:
        raise UrdfError(f"{what}: '{text}' is not three numbers")
    return vals


class ArmChain:
    """The serial chain of a URDF from `base_link` to `flange`, in order."""

    def __init__(self, text: str | None = None) -> None:
        try:
            root = ET.fromstring(text if text is not None else urdf_text())
        except ET.ParseError as exc:
            raise UrdfError(f"the URDF is not XML: {exc}") from None
        self.name = root.get("name", "")
        by_parent: dict[str, UrdfJoint] = {}
        for j in root.iter("joint"):
            name, jtype = j.get("name", ""), j.get("type", "")
            if jtype not in ("revolute", "continuous", "fixed"):
                raise UrdfError(f"joint {name}: type '{jtype}' is not supported (revolute, continuous or fixed)")
            par, chi = j.find("parent"), j.find("child")
            if par is None or chi is None:
                raise UrdfError(f"joint {name}: no parent or child link")
            o = j.find("origin")
            xyz = _floats(o.get("xyz") if o is not None else None, "0 0 0", f"joint {name} origin xyz")
            rpy = _floats(o.get("rpy") if o is not None else None, "0 0 0", f"joint {name} origin rpy")
            a = j.find("axis")
            axis = np.array(_floats(a.get("xyz") if a is not None else None, "1 0 0", f"joint {name} axis"))
            T = np.eye(4)
            T[:3, :3] = rpy_matrix(*rpy)
            T[:3, 3] = xyz
            parent = par.get("link", "")
            if parent in by_parent:
                raise UrdfError(f"link {parent} has two child joints: not a serial arm")
            by_parent[parent] = UrdfJoint(name, jtype, parent, chi.get("link", ""), T,
                                          axis / float(np.linalg.norm(axis)))
        self.joints: list[UrdfJoint] = []
        link = BASE_FRAME
        while link in by_parent:
            self.joints.append(by_parent[link])
            link = by_parent[link].child
        if link != FLANGE_FRAME:
            raise UrdfError(f"the chain from {BASE_FRAME} ends at '{link}', not at {FLANGE_FRAME}")
        self.movable = [j.name for j in self.joints if j.type != "fixed"]

    def joint_transforms(self, q_rad: list[float]) -> list[tuple[UrdfJoint, Matrix]]:
        """Each joint's parent -> child transform (4x4) at joint angles q_rad."""
        if len(q_rad) != len(self.movable):
            raise UrdfError(f"{len(q_rad)} joint values given, the arm has {len(self.movable)} joints")
        out: list[tuple[UrdfJoint, Matrix]] = []
        it = iter(q_rad)
        for j in self.joints:
            T = j.origin
            if j.type != "fixed":
                M = np.eye(4)
                M[:3, :3] = axis_angle_matrix(j.axis, next(it))
                T = T @ M
            out.append((j, T))
        return out

    def transforms(self, q_rad: list[float]) -> list[Transform]:
        """One Transform per URDF joint (what a 3D panel needs to place every link)."""
        return [Transform(j.parent, j.child, (float(T[0, 3]), float(T[1, 3]), float(T[2, 3])),
                          quaternion_xyzw(T[:3, :3])) for j, T in self.joint_transforms(q_rad)]

    def fk(self, q_rad: list[float]) -> Matrix:
        """The flange pose in the base frame (4x4)."""
        T = np.eye(4)
        for _, M in self.joint_transforms(q_rad):
            T = T @ M
        return T
