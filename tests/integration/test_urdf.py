"""The URDF the build generates (ls_urdf, from firmware/model/ls_robot_model.c) has the firmware's
forward kinematics: yourdfpy's FK of the flange equals getRobotPosition's tool pose on 100 random
configurations of the running landscaped, within 1e-6 m.

Route: getRobotPosition computes the pose by FK of the very snapshot of joint angles it returns
(firmware/core/cmd_settings.c), so every reply is an exact (joints, pose) pair whether the arm is at
rest or moving. The test moves the arm at half speed through random joint targets and samples
getRobotPosition during each move: 100 distinct random configurations in a few seconds of motion
instead of 100 settled moves (minutes). The tool offset and the world frame stay at identity, so the
tool pose is the flange pose in the base frame."""
from __future__ import annotations

import math
import random
import time

import can
import numpy as np
import yourdfpy

from conftest import BUILD, Controller
from landscape.supervisor import Supervisor
from landscape.urdf import ArmChain, rpy_matrix

URDF = BUILD / "share" / "landscape" / "ls-sim6.urdf"
N_CONFIGS = 100
TOL_M = 1e-6
SAMPLES_PER_MOVE = 10


def _load() -> yourdfpy.URDF:
    assert URDF.exists(), f"{URDF} is missing: the build writes it (bash .ci/build)"
    return yourdfpy.URDF.load(str(URDF), build_collision_scene_graph=False, load_meshes=False,
                              load_collision_meshes=False)


def _limits(robot: yourdfpy.URDF) -> list[tuple[float, float]]:
    out = []
    for name in robot.actuated_joint_names:
        lim = robot.joint_map[name].limit
        out.append((float(lim.lower), float(lim.upper)))
    return out


def test_urdf_is_a_six_joint_chain_with_the_model_limits() -> None:
    robot = _load()
    assert robot.actuated_joint_names == [f"joint{i}" for i in range(1, 7)]
    lims = _limits(robot)
    assert lims[0] == (-170 * math.pi / 180, 170 * math.pi / 180)
    assert robot.base_link == "base_link" and "flange" in robot.link_map


def _configs(sup: Supervisor, robot: yourdfpy.URDF, seed: int) -> list[tuple[list[float], list[float]]]:
    rng = random.Random(seed)
    lims = _limits(robot)
    got: list[tuple[list[float], list[float]]] = []
    seen: set[tuple[float, ...]] = set()
    while len(got) < N_CONFIGS:
        target = [rng.uniform(lo + 0.05, hi - 0.05) for lo, hi in lims]
        target[4] = math.copysign(max(abs(target[4]), 0.2), target[4])  # away from the wrist singularity
        rv = sup.move_absolute("urdf", target, speed_pct=50)
        taken = 0
        deadline = time.monotonic() + 30
        while taken < SAMPLES_PER_MOVE and len(got) < N_CONFIGS and time.monotonic() < deadline:
            res = sup.get_robot_position().result
            q = [float(v) for v in res["joints"]]
            key = tuple(round(v, 9) for v in q)
            if key not in seen:
                seen.add(key)
                got.append((q, [float(v) for v in res["world_pose"]]))
                taken += 1
            time.sleep(0.05)
        sup.wait_complete(rv, timeout_s=30)
        res = sup.get_robot_position().result  # the settled target too
        q = [float(v) for v in res["joints"]]
        key = tuple(round(v, 9) for v in q)
        if len(got) < N_CONFIGS and key not in seen:
            seen.add(key)
            got.append((q, [float(v) for v in res["world_pose"]]))
    return got


def test_urdf_fk_equals_get_robot_position(controller: Controller) -> None:
    robot = _load()
    chain = ArmChain(URDF.read_text())
    bus = can.Bus(interface="slcan", channel=controller.pty, bitrate=1000000, sleep_after_open=0)
    try:
        with Supervisor(bus, client_name="urdf") as sup:
            sup.lock()
            sup.activate()  # metres and radians; tool offset and world frame at identity
            configs = _configs(sup, robot, seed=23)
    finally:
        bus.shutdown()
    assert len(configs) == N_CONFIGS
    assert len({tuple(q) for q, _ in configs}) == N_CONFIGS
    worst_m = worst_rad = worst_chain_m = 0.0
    for q, pose in configs:
        robot.update_cfg(np.array(q))
        T = robot.get_transform(frame_to="flange", frame_from="base_link")
        worst_m = max(worst_m, float(np.linalg.norm(T[:3, 3] - np.array(pose[:3]))))
        R = rpy_matrix(*pose[3:6])
        cos_angle = (float(np.trace(R.T @ T[:3, :3])) - 1) / 2
        worst_rad = max(worst_rad, math.acos(max(-1.0, min(1.0, cos_angle))))
        worst_chain_m = max(worst_chain_m, float(np.linalg.norm(chain.fk(q)[:3, 3] - np.array(pose[:3]))))
    print(f"\nURDF FK vs getRobotPosition on {N_CONFIGS} configurations: max position error {worst_m:.3g} m, "
          f"max orientation error {worst_rad:.3g} rad; landscape.urdf.ArmChain: {worst_chain_m:.3g} m")
    assert worst_m < TOL_M
    assert worst_rad < 1e-6
    assert worst_chain_m < TOL_M
