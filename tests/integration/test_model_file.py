"""The robot model from a file (docs/deploy.md "Describe your arm"), end to end.

- An independent FK (pytransform3d, a library no one here wrote, on the URDF landscaped writes for the
  model) agrees with the firmware's FK (`ls_robot_model fk`) to 1e-9 on random joint vectors of every
  shipped arm: the UR5e, UR10e, KR 6 R900 and PUMA 560 of the makers' published tables, and ls-sim6.
- landscaped started with a model file (the default arm's and a UR5e's) runs Cartesian moves, arcs and a
  Cartesian path on the simulated arm built from that file; every getRobotPosition equals the
  independent FK of its joints, and the URDF the host receives (describeRobot) loads in yourdfpy with the
  same FK.
- Bad input: every kind of bad model file is refused by landscaped, by `landscaped --check` and by
  `landscape model check` with the same one line and exit 2; a URDF `landscape model from-urdf` cannot
  represent is refused with the reason, exit 2; a UR-style URDF written as ROS drivers lay one out
  converts into a model whose FK equals the URDF's."""
from __future__ import annotations

import math
import random
import subprocess
import time
from collections.abc import Iterator
from pathlib import Path

import can
import numpy as np
import pytest
import yourdfpy
from pytransform3d.urdf import UrdfTransformManager
from test_motion import _rpy, assert_on_segment

from conftest import BUILD, LANDSCAPED, Controller, run_cli, start_controller
from landscape._generated import landscape_pb2 as pb
from landscape.model import RobotModel, load_model
from landscape.supervisor import Supervisor
from landscape.urdf import rpy_matrix

ROOT = Path(__file__).resolve().parents[2]
ROBOTS = ROOT / "firmware" / "model" / "robots"
ARMS = ["ls-sim6.ini", "ur5e.ini", "ur10e.ini", "kr6-r900.ini", "puma560.ini"]
LS_URDF = BUILD / "bin" / "ls_urdf"
LS_ROBOT_MODEL = BUILD / "bin" / "ls_robot_model"
TOL = 1e-9


def model_urdf(model: Path) -> str:
    return subprocess.run([str(LS_URDF), "--model", str(model)], capture_output=True, text=True, check=True).stdout


def firmware_fk(model: Path, qs: list[list[float]]) -> list[np.ndarray]:
    """ls_kin_fk of each joint vector, through `ls_robot_model fk`."""
    out = subprocess.run([str(LS_ROBOT_MODEL), "fk", str(model)], input="".join(
        " ".join(repr(v) for v in q) + "\n" for q in qs), capture_output=True, text=True, check=True).stdout
    return [np.array([float(v) for v in line.split()]).reshape(4, 4).T for line in out.splitlines()]


class Pytransform3dFk:
    """FK of a URDF with pytransform3d's UrdfTransformManager: the flange in base_link."""

    def __init__(self, urdf: str) -> None:
        self.tm = UrdfTransformManager()
        self.tm.load_urdf(urdf)

    def __call__(self, q: list[float]) -> np.ndarray:
        for i, v in enumerate(q, 1):
            self.tm.set_joint(f"joint{i}", v)
        return np.asarray(self.tm.get_transform("flange", "base_link"))


def pose_errors(A: np.ndarray, B: np.ndarray) -> tuple[float, float]:
    """Distance of the origins (m) and the angle between the orientations (rad, accurate near 0)."""
    M = A[:3, :3].T @ B[:3, :3]
    v = np.array([M[2, 1] - M[1, 2], M[0, 2] - M[2, 0], M[1, 0] - M[0, 1]])
    angle = math.atan2(0.5 * float(np.linalg.norm(v)), 0.5 * (float(np.trace(M)) - 1))
    return float(np.linalg.norm(A[:3, 3] - B[:3, 3])), angle


def random_q(m: RobotModel, rng: random.Random) -> list[float]:
    return [rng.uniform(j["min"], j["max"]) for j in m.joints]


@pytest.mark.parametrize("arm", ARMS)
def test_an_independent_fk_agrees_with_the_firmware_on_every_shipped_arm(arm: str) -> None:
    path = ROBOTS / arm
    m = load_model(path)
    rng = random.Random(arm)
    qs = [random_q(m, rng) for _ in range(500)]
    ref = Pytransform3dFk(model_urdf(path))
    worst_m = worst_rad = worst_host = 0.0
    for q, T in zip(qs, firmware_fk(path, qs), strict=True):
        dp, da = pose_errors(ref(q), T)
        worst_m, worst_rad = max(worst_m, dp), max(worst_rad, da)
        worst_host = max(worst_host, float(np.abs(m.fk(q) - T).max()))
    print(f"\n{arm}: pytransform3d vs ls_kin_fk on 500 joint vectors: {worst_m:.2g} m, {worst_rad:.2g} rad; "
          f"landscape.model's DH product: {worst_host:.2g}")
    assert worst_m < TOL and worst_rad < TOL and worst_host < TOL


# ---------------------------------------------------------------- the arm from a file, moving


HOMES = {"ls-sim6.ini": [0.0, 0.3, 0.3, 0.0, 0.9, 0.0],
         "ur5e.ini": [0.0, -math.pi / 2, math.pi / 2, -math.pi / 2, -math.pi / 2, 0.0]}


class Arm:
    def __init__(self, controller: Controller, sup: Supervisor, model: RobotModel, file: Path) -> None:
        self.controller, self.sup, self.model, self.file = controller, sup, model, file
        self.sets: list[list[float]] = []
        self._cur: dict[str, float] = {}
        self.pairs: list[tuple[list[float], list[float]]] = []  # getRobotPosition: joints, world_pose
        sup.on_telemetry(self._on)

    def _on(self, b: object) -> None:
        name = getattr(b, "name", "")
        if name.startswith("JOINTS_") and not name.startswith("JOINTS_CMD"):
            self._cur.update(b.signals)  # type: ignore[attr-defined]
            if name == "JOINTS_56" and len(self._cur) == 6:
                self.sets.append([float(self._cur[f"j{i}"]) for i in range(1, 7)])

    def position(self) -> list[float]:
        res = self.sup.get_robot_position().result
        q = [float(v) for v in res["joints"]]
        self.pairs.append((q, [float(v) for v in res["world_pose"]]))
        return q

    def tips_during(self, start: object) -> list[np.ndarray]:
        """Start a motion (a callable returning its RetVal); the tip at every broadcast until it completes,
        sampling getRobotPosition meanwhile."""
        mark = len(self.sets)
        rv = start()  # type: ignore[operator]
        deadline = time.monotonic() + 30
        while self.sup.get_motion_control_state().result["state"] == "MOVING" and time.monotonic() < deadline:
            self.position()
            time.sleep(0.05)
        self.sup.wait_complete(rv, timeout_s=30)
        time.sleep(0.1)
        return [self.model.fk(q)[:3, 3] for q in self.sets[mark:]]


@pytest.fixture(scope="module", params=["ls-sim6.ini", "ur5e.ini"])
def arm(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> Iterator[Arm]:
    file = ROBOTS / request.param
    c = start_controller(tmp_path_factory.mktemp("model") / "ls0", "--model", str(file))
    bus = can.Bus(interface="slcan", channel=c.pty, bitrate=1000000, sleep_after_open=0)
    try:
        with Supervisor(bus, client_name="model") as sup:
            a = Arm(c, sup, load_model(file), file)
            sup.lock()
            sup.activate()  # metres and radians; tool offset and world frame at identity
            sup.wait_complete(sup.move_absolute("home", HOMES[request.param], speed_pct=50), timeout_s=30)
            yield a
            sup.deactivate()
    finally:
        bus.shutdown()
        code = c.stop()
        log = c.log.read_text(errors="replace")
        assert code == 0, log[-4000:]
        assert "Sanitizer" not in log, log[-4000:]


def test_the_device_describes_the_model_of_its_file(arm: Arm) -> None:
    d = arm.sup.description
    assert d is not None and d.res.robot_model == arm.model.name
    assert [j.max_rad for j in d.res.joints] == [j["max"] for j in arm.model.joints]
    assert arm.sup.describe_robot().result["ik_class"] == arm.model.ik_class
    assert arm.sup.robot_urdf() == model_urdf(arm.file)


def test_a_straight_line_stays_within_1mm(arm: Arm) -> None:
    start = arm.model.fk(arm.position())
    goal = start.copy()
    goal[:3, 3] += [0.1, 0.12, 0.08]
    pts = arm.tips_during(lambda: arm.sup.move_absolute("line", [*goal[:3, 3], *_rpy(goal)],
                                                        frame=pb.BASE_CARTESIAN_FRAME, speed_pct=50))
    assert_on_segment(pts, start[:3, 3], goal[:3, 3], 1e-3)


def test_an_arc_stays_on_its_circle(arm: Arm) -> None:
    start = arm.model.fk(arm.position())
    rpy = _rpy(start)
    c = start[:3, 3] + [0.0, 0.1, 0.0]
    via = [*(start[:3, 3] + [0.1, 0.1, 0.0]), *rpy]
    goal = [*(start[:3, 3] + [0.0, 0.2, 0.0]), *rpy]
    pts = arm.tips_during(lambda: arm.sup.move_arc("arc", via, goal))
    assert len(pts) > 10
    for p in pts:
        assert abs(np.linalg.norm((p - c)[:2]) - 0.1) < 1e-3
        assert abs(p[2] - c[2]) < 1e-3
    assert np.linalg.norm(pts[-1] - np.array(goal[:3])) < 1e-3


def test_a_cartesian_path_with_tags_reaches_its_points(arm: Arm) -> None:
    start = arm.model.fk(arm.position())
    rpy = _rpy(start)
    corners = [start[:3, 3] + d for d in ([-0.08, 0, 0], [-0.08, -0.08, 0], [0, -0.08, 0.05], [0, 0, 0])]
    pts = [{"pose": [*p, *rpy], "tag_name": f"C{k}", "tag_index": k, "speed_pct": 40.0}
           for k, p in enumerate(corners)]
    assert arm.sup.path_load("square", pts, frame=pb.BASE_CARTESIAN_FRAME,
                             motion_type=pb.STRAIGHT_MOTION).result["points_in_path"] == 4
    list(arm.sup.notices(timeout_s=0.1))
    tips = arm.tips_during(lambda: arm.sup.path_move("square", number_of_cycles=1))
    assert np.linalg.norm(tips[-1] - corners[-1]) < 1e-3
    for corner in corners:
        assert min(float(np.linalg.norm(t - corner)) for t in tips) < 2e-3
    arm.sup.path_clear_path("square")


def test_get_robot_position_equals_the_independent_fk_of_the_received_urdf(arm: Arm) -> None:
    """Every (joints, pose) pair the moves above sampled, and a few more, against pytransform3d and
    yourdfpy on the URDF the device sent: pytransform3d to 1e-9; yourdfpy, whose own arithmetic loses a
    few nanoradians (ls-sim6 to 1e-11, the UR5e's +-360 deg joints to 6e-9), to 1e-7."""
    urdf = arm.sup.robot_urdf()
    for _ in range(5):
        arm.position()
    assert len(arm.pairs) > 20
    ref = Pytransform3dFk(urdf)
    path = arm.controller.log.with_name("robot.urdf")
    path.write_text(urdf)
    robot = yourdfpy.URDF.load(str(path), build_collision_scene_graph=False, load_meshes=False,
                               load_collision_meshes=False)
    assert robot.actuated_joint_names == [f"joint{i}" for i in range(1, 7)]
    worst = [0.0, 0.0, 0.0, 0.0]
    for q, pose in arm.pairs:
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = rpy_matrix(*pose[3:6]), pose[:3]
        robot.update_cfg(np.array(q))
        for k, other in enumerate((ref(q), robot.get_transform(frame_to="flange", frame_from="base_link"))):
            dp, da = pose_errors(other, T)
            worst[2 * k], worst[2 * k + 1] = max(worst[2 * k], dp), max(worst[2 * k + 1], da)
    print(f"\n{arm.model.name}: getRobotPosition vs pytransform3d {worst[0]:.2g} m {worst[1]:.2g} rad, "
          f"vs yourdfpy {worst[2]:.2g} m {worst[3]:.2g} rad, {len(arm.pairs)} configurations")
    assert max(worst[:2]) < TOL
    assert max(worst[2:]) < 1e-7


# ---------------------------------------------------------------- bad input: one line, exit 2


def _variant(tmp_path: Path, name: str, old: str | None, new: str) -> Path:
    text = (ROBOTS / "ls-sim6.ini").read_text()
    if old is None:
        text += new + "\n"
    else:
        assert old in text
        text = text.replace(old + "\n", new + ("\n" if new else ""), 1)
    p = tmp_path / name
    p.write_text(text)
    return p


BAD = [
    ("missing-key", "max_jerk = 80 rad/s^3", ""),
    ("inverted-limit", "max = 110 deg", "max = -120 deg"),
    ("not-finite", "alpha = -90 deg", "alpha = nan deg"),
    ("too-big", "d = 0.400 m", "d = 1e999 m"),
    ("no-ik-class", "a = 0 m", "a = 0.02 m"),
    ("no-unit", "mass = 5 kg", "mass = 5"),
    ("wrong-unit", "max_velocity = 2.5 rad/s", "max_velocity = 2.5 m/s"),
    ("out-of-range", "link_radius = 0.04 m", "link_radius = 4 m"),
    ("unknown-key", "mass = 3 kg", "weight = 3 kg"),
    ("given-twice", "mass = 3 kg", "mass = 3 kg\nmass = 3 kg"),
    ("unknown-section", "[joint.3]", "[elbow]"),
    ("outside-section", "[robot]", "name = x\n[robot]"),
    ("syntax", "mass = 3 kg", "mass 3 kg"),
    ("bad-name", "name = ls-sim6", "name = an arm whose name is far too long to be kept"),
    ("workspace", "workspace_max = 0.95 0.95 1.40 m", "workspace_max = 0.95 -1 1.40 m"),
]


@pytest.mark.parametrize(("name", "old", "new"), BAD, ids=[b[0] for b in BAD])
def test_a_bad_model_file_is_refused_alike_by_landscaped_and_the_host(tmp_path: Path, name: str, old: str,
                                                                     new: str) -> None:
    bad = _variant(tmp_path, f"{name}.ini", old, new)
    run = subprocess.run([str(LANDSCAPED), "--hal", "sim", "--link", f"slcan:pty:{tmp_path}/ls0", "--model", str(bad)],
                         capture_output=True, text=True, timeout=10)
    assert run.returncode == 2, run.stderr
    lines = run.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("<3>landscaped: error: "), run.stderr
    msg = lines[0].removeprefix("<3>landscaped: error: ")
    assert msg.startswith(str(bad) + ":")
    host = run_cli("model", "check", str(bad))
    assert host.returncode == 2 and host.stdout == ""
    assert host.stderr == f"landscape: {msg}\n"
    check = subprocess.run([str(LANDSCAPED), "--hal", "sim", "--link", f"slcan:pty:{tmp_path}/ls0", "--model",
                            str(bad), "--check"], capture_output=True, text=True, timeout=10)
    assert check.returncode == 2
    assert check.stdout.startswith(f"FAIL  configuration: (command line only): {msg}\n")


def test_the_refusals_name_what_was_wrong(tmp_path: Path) -> None:
    def refusal(name: str) -> str:
        old, new = next((o, n) for k, o, n in BAD if k == name)
        r = run_cli("model", "check", str(_variant(tmp_path, f"{name}.ini", old, new)))
        assert r.returncode == 2
        return r.stderr
    assert "[joint.3] max_jerk: missing; every key is required" in refusal("missing-key")
    assert "[joint.2] max: got '-120 deg', expected above min = -110 deg (line 35)" in refusal("inverted-limit")
    assert ":19: [joint.1] alpha: got 'nan deg', expected an angle: a number and its unit (deg or rad), " \
           "-360..360 deg" in refusal("not-finite")
    assert "no closed-form inverse kinematics fits this arm: not a spherical wrist (a4 = 0.02 m; a4, a5, a6 " \
           "and d5 must be 0 so that joints 4-6 meet) and not an offset wrist (a4 = 0.02 m; a4, a5 and a6 must " \
           "be 0)" in refusal("no-ik-class")


def test_a_directory_or_a_missing_file_is_refused_alike(tmp_path: Path) -> None:
    for path in (tmp_path, tmp_path / "missing.ini"):
        run = subprocess.run([str(LANDSCAPED), "--hal", "sim", "--link", f"slcan:pty:{tmp_path}/ls0", "--model",
                              str(path)], capture_output=True, text=True, timeout=10)
        assert run.returncode == 2
        host = run_cli("model", "check", str(path))
        assert host.returncode == 2
        assert host.stderr == "landscape: " + run.stderr.removeprefix("<3>landscaped: error: ")
        assert "cannot read the robot model file: " in host.stderr


def test_an_arm_the_simulator_cannot_build_is_a_refused_configuration(tmp_path: Path) -> None:
    run = subprocess.run([str(LANDSCAPED), "--hal", "sim", "--link", f"slcan:pty:{tmp_path}/ls0", "--model",
                          str(ROBOTS / "puma560.ini")], capture_output=True, text=True, timeout=10)
    assert run.returncode == 2
    assert run.stderr.startswith("<3>landscaped: error: [hal] arm = sim cannot simulate robot model puma560 (")
    assert "d6 >= 10 mm" in run.stderr and len(run.stderr.splitlines()) == 1


def test_every_shipped_model_passes_the_host_check() -> None:
    for arm_file in ARMS:
        r = run_cli("model", "check", str(ROBOTS / arm_file))
        m = load_model(ROBOTS / arm_file)
        assert r.returncode == 0, r.stderr
        assert r.stdout == f"{ROBOTS / arm_file}: {m.name}, {m.ik_class} IK, reach {m.reach_m():.3f} m\n"
        c = subprocess.run([str(LS_ROBOT_MODEL), "check", str(ROBOTS / arm_file)], capture_output=True, text=True)
        assert c.stdout == r.stdout  # the firmware's loader says the same


# ---------------------------------------------------------------- from a URDF

PI = math.pi


def _ur_style_urdf(*, prismatic: bool = False, mimic: bool = False, branch: bool = False, joints: int = 6) -> str:
    """A UR5e as ROS drivers lay its URDF out: joint origins with rpy, every axis z, a base frame turned
    by pi, a dead-end `base` frame beside the chain, and flange and tool0 fixed after the last joint.
    Written here from UR's DH table (d1 0.1625, a2 -0.425, a3 -0.3922, d4 0.1333, d5 0.0997, d6 0.0996)."""
    specs = [("shoulder_pan", "base_link_inertia", "shoulder_link", "0 0 0.1625", "0 0 0", 3.761),
             ("shoulder_lift", "shoulder_link", "upper_arm_link", "0 0 0", f"{PI / 2} 0 0", 8.058),
             ("elbow", "upper_arm_link", "forearm_link", "-0.425 0 0", "0 0 0", 2.846),
             ("wrist_1", "forearm_link", "wrist_1_link", "-0.3922 0 0.1333", "0 0 0", 1.37),
             ("wrist_2", "wrist_1_link", "wrist_2_link", "0 -0.0997 0", f"{PI / 2} 0 0", 1.3),
             ("wrist_3", "wrist_2_link", "wrist_3_link", "0 0.0996 0", f"{PI / 2} {PI} {PI}", 0.365)][:joints]
    links = {"base_link", "base", "base_link_inertia", "flange", "tool0"} | {s[2] for s in specs}
    out = ['<?xml version="1.0"?>', '<robot name="ur5e_ros">']
    masses = {s[2]: s[5] for s in specs}
    for link in sorted(links):
        inertial = (f'<inertial><mass value="{masses[link]}"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" '
                    'iyz="0" izz="0.01"/></inertial>') if link in masses else ""
        out.append(f'  <link name="{link}">{inertial}</link>')
    out.append(f'  <joint name="base_link-base_link_inertia" type="fixed"><parent link="base_link"/>'
               f'<child link="base_link_inertia"/><origin xyz="0 0 0" rpy="0 0 {PI}"/></joint>')
    out.append(f'  <joint name="base_link-base_fixed_joint" type="fixed"><parent link="base_link"/>'
               f'<child link="base"/><origin xyz="0 0 0" rpy="0 0 {PI}"/></joint>')
    for k, (name, parent, child, xyz, rpy, _) in enumerate(specs):
        kind = "prismatic" if prismatic and k == 2 else "revolute"
        extra = '<mimic joint="shoulder_lift_joint"/>' if mimic and k == 2 else ""
        out.append(f'  <joint name="{name}_joint" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
                   f'<origin xyz="{xyz}" rpy="{rpy}"/><axis xyz="0 0 1"/>'
                   f'<limit lower="{-2 * PI}" upper="{2 * PI}" velocity="3.14" effort="150"/>{extra}</joint>')
    last = specs[-1][2]
    out.append(f'  <joint name="wrist_3-flange" type="fixed"><parent link="{last}"/><child link="flange"/>'
               f'<origin xyz="0 0 0" rpy="0 {-PI / 2} {-PI / 2}"/></joint>')
    out.append(f'  <joint name="flange-tool0" type="fixed"><parent link="flange"/><child link="tool0"/>'
               f'<origin xyz="0 0 0" rpy="{PI / 2} 0 {PI / 2}"/></joint>')
    if branch:
        out.append('  <link name="camera_link"/>')
        out.append('  <joint name="camera_pan" type="revolute"><parent link="base_link"/><child link="camera_link"/>'
                   '<axis xyz="0 0 1"/><limit lower="-1" upper="1" velocity="1" effort="1"/></joint>')
    out.append("</robot>")
    return "\n".join(out) + "\n"


def test_a_ros_style_ur_urdf_converts_into_a_model_with_its_fk(tmp_path: Path) -> None:
    urdf = tmp_path / "ur5e_ros.urdf"
    urdf.write_text(_ur_style_urdf())
    out = tmp_path / "ur5e_ros.ini"
    r = run_cli("model", "from-urdf", str(urdf), "-o", str(out))
    assert r.returncode == 0, r.stderr
    assert r.stderr.startswith(f"model from-urdf: wrote {out} (ur5e_ros, offset_wrist IK); chosen, not in the "
                               "URDF: link_radius, max_acceleration, max_jerk, [cartesian]")
    m = load_model(out)
    assert [round(j["mass"], 6) for j in m.joints] == [3.761, 8.058, 2.846, 1.37, 1.3, 0.365]
    tm = UrdfTransformManager()
    tm.load_urdf(urdf.read_text())
    rng = random.Random(5)
    worst = 0.0
    qs = [random_q(m, rng) for _ in range(300)]
    for q, T in zip(qs, firmware_fk(out, qs), strict=True):
        for i, v in enumerate(q):
            tm.set_joint(["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint",
                          "wrist_2_joint", "wrist_3_joint"][i], v)
        ref = np.asarray(tm.get_transform("tool0", "base_link"))
        dp, da = pose_errors(ref, T)
        worst = max(worst, dp, da)
    assert worst < TOL
    check = run_cli("model", "check", str(out))
    assert check.returncode == 0 and "offset_wrist IK" in check.stdout


@pytest.mark.parametrize(("kind", "expect"), [
    ("prismatic", "joint elbow_joint is prismatic: a robot model has revolute joints only"),
    ("mimic", "joint elbow_joint mimics joint shoulder_lift_joint: a robot model has six independent joints"),
    ("branch", "link base_link branches into joints"),
    ("five", "5 moving joints below base_link; a robot model has 6"),
])
def test_a_urdf_a_model_cannot_represent_is_refused_with_the_reason(tmp_path: Path, kind: str, expect: str) -> None:
    urdf = tmp_path / f"{kind}.urdf"
    urdf.write_text(_ur_style_urdf(prismatic=kind == "prismatic", mimic=kind == "mimic", branch=kind == "branch",
                                   joints=5 if kind == "five" else 6))
    r = run_cli("model", "from-urdf", str(urdf), "-o", str(tmp_path / "out.ini"))
    assert r.returncode == 2
    assert r.stderr.startswith(f"landscape: {urdf}: ") and expect in r.stderr, r.stderr
    assert len(r.stderr.splitlines()) == 1 and "Traceback" not in r.stderr
    assert not (tmp_path / "out.ini").exists()
