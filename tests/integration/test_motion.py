"""Motion against the running landscaped with the simulated arm: joint moves,
straight lines, arcs, paths with tags and cycles, stop/resume/abort,
refusals. Positions are checked with FK of the joints the controller reports
(getRobotPosition when the firmware has it, else the JOINTS_* telemetry
broadcasts), computed here from the DH table of the default arm's model file,
firmware/model/robots/ls-sim6.ini (the compiled-in model to the bit,
tests/unit/modelfile). Paths during motion come from the telemetry (every
broadcast set of six joints). test_model_file runs moves like these on a
UR5e built from its model file."""
from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import can
import numpy as np
import pytest

from conftest import Controller
from landscape import errors
from landscape._generated import landscape_pb2 as pb
from landscape.model import load_model
from landscape.supervisor import RetVal, Supervisor, notice_data

ROOT = Path(__file__).resolve().parents[2]
HOME = [0.0, 0.3, 0.3, 0.0, 0.9, 0.0]  # rad, a pose well inside the reach
DH = load_model(ROOT / "firmware" / "model" / "robots" / "ls-sim6.ini").dh()


def fk(q: list[float]) -> np.ndarray:
    """Flange pose in the base frame (4x4)."""
    T = np.eye(4)
    for (a, alpha, d, off), qi in zip(DH, q, strict=False):
        th = qi + off
        ct, st, ca, sa = math.cos(th), math.sin(th), math.cos(alpha), math.sin(alpha)
        T = T @ np.array([[ct, -st * ca, st * sa, a * ct], [st, ct * ca, -ct * sa, a * st],
                          [0, sa, ca, d], [0, 0, 0, 1]])
    return T


class JointWatch:
    """Every complete set of joints broadcast by the device (JOINTS_12, _34, _56)."""

    def __init__(self, sup: Supervisor) -> None:
        self._lock = threading.Lock()
        self._cur: dict[str, float] = {}
        self.sets: list[list[float]] = []
        sup.on_telemetry(self._on)

    def _on(self, b: object) -> None:
        name = getattr(b, "name", "")
        if not name.startswith("JOINTS_"):
            return
        with self._lock:
            self._cur.update(b.signals)
            if name == "JOINTS_56" and all(f"j{i}" in self._cur for i in range(1, 7)):
                self.sets.append([float(self._cur[f"j{i}"]) for i in range(1, 7)])

    def mark(self) -> int:
        with self._lock:
            return len(self.sets)

    def since(self, mark: int) -> list[list[float]]:
        with self._lock:
            return list(self.sets[mark:])

    def latest(self, timeout_s: float = 1.0) -> list[float]:
        m = self.mark()
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            got = self.since(m)
            if got:
                return got[-1]
            time.sleep(0.01)
        raise AssertionError("no JOINTS_* telemetry from the device within 1 s")


WATCH: dict[int, JointWatch] = {}


def joints(sup: Supervisor) -> list[float]:
    rv = sup.get_robot_position(check=False)
    if rv.ret_code == pb.CMD_EXEC_OK:
        return list(rv.result["joints"])
    return WATCH[id(sup)].latest()


def tip(sup: Supervisor) -> np.ndarray:
    return fk(joints(sup))[:3, 3]


@pytest.fixture
def sup(controller: Controller) -> Iterator[Supervisor]:
    bus = can.Bus(interface="slcan", channel=controller.pty, bitrate=1000000, sleep_after_open=0)
    try:
        with Supervisor(bus, client_name="motion") as s:
            WATCH[id(s)] = JointWatch(s)
            s.lock()
            s.activate()  # units: metres and radians (the defaults)
            rv = s.move_absolute("home", HOME, speed_pct=50)
            s.wait_complete(rv, timeout_s=20)
            yield s
    finally:
        bus.shutdown()


def _tips_during(sup: Supervisor, start: Callable[[], RetVal], timeout_s: float = 30) -> list[np.ndarray]:
    """Start a motion, wait for its completion; the tip at every joint broadcast meanwhile."""
    w = WATCH[id(sup)]
    m = w.mark()
    rv = start()
    sup.wait_complete(rv, timeout_s=timeout_s)
    time.sleep(0.1)
    return [fk(q)[:3, 3] for q in w.since(m)]


def _finals(sup: Supervisor, seq: int, timeout_s: float) -> list[pb.Notice]:
    """Every notice with ref_seq `seq` until the final one."""
    out: list[pb.Notice] = []
    for n in sup.notices(timeout_s=timeout_s):
        if n.ref_seq == seq:
            out.append(n)
            if n.final:
                break
    return out


def test_joint_move_completes_with_one_final_event(sup: Supervisor) -> None:
    target = [0.5, 0.1, 0.6, -0.4, 0.7, 1.0]
    list(sup.notices(timeout_s=0.1))  # drop what came before
    rv = sup.move_absolute("p1", target)
    assert rv.ret_code == pb.CMD_STARTED_OK
    got = _finals(sup, rv.seq, 30)
    assert len(got) == 1 and got[0].final and got[0].kind == pb.EVENT
    assert got[0].event_id == "moveAbsoluteComplete"
    d = notice_data(got[0])
    assert d["point"] == "p1"
    assert [float(x) for x in d["joints"].split(",")] == pytest.approx(target, abs=1e-4)
    assert joints(sup) == pytest.approx(target, abs=2e-3)
    assert sup.get_motion_control_state().result["state"] == "RESTING"
    assert list(n for n in sup.notices(timeout_s=0.3) if n.ref_seq == rv.seq) == []  # nothing after the final


def test_straight_line_stays_within_1mm(sup: Supervisor) -> None:
    start = fk(HOME)
    goal = start.copy()
    goal[:3, 3] += [-0.15, 0.2, 0.1]
    xyzrpy = [*goal[:3, 3], *_rpy(goal)]
    pts = _tips_during(sup, lambda: sup.move_absolute("line", xyzrpy, frame=pb.BASE_CARTESIAN_FRAME, speed_pct=50))
    assert_on_segment(pts, start[:3, 3], goal[:3, 3], 1e-3)


def assert_on_segment(pts: list[np.ndarray], a: np.ndarray, b: np.ndarray, tol_m: float) -> None:
    """More than 10 tip positions, each within tol_m of the segment a-b, the last within tol_m of b."""
    assert len(pts) > 10
    for p in pts:
        t = np.clip(np.dot(p - a, b - a) / np.dot(b - a, b - a), 0, 1)
        assert np.linalg.norm(p - (a + t * (b - a))) < tol_m
    assert np.linalg.norm(pts[-1] - b) < tol_m


def test_arc_stays_on_its_circle(sup: Supervisor) -> None:
    start = fk(HOME)
    rpy = _rpy(start)
    c = start[:3, 3] + [0.0, 0.1, 0.0]
    via = [*(start[:3, 3] + [0.1, 0.1, 0.0]), *rpy]
    goal = [*(start[:3, 3] + [0.0, 0.2, 0.0]), *rpy]
    pts = _tips_during(sup, lambda: sup.move_arc("arc", via, goal))
    assert len(pts) > 10
    for p in pts:
        assert abs(np.linalg.norm((p - c)[:2]) - 0.1) < 1e-3
        assert abs(p[2] - c[2]) < 1e-3
    assert np.linalg.norm(pts[-1] - np.array(goal[:3])) < 1e-3
    here = tip(sup)
    with pytest.raises(errors.ParamError, match="collinear"):
        sup.move_arc("flat", [*(here + [0.05, 0, 0]), *rpy], [*(here + [0.1, 0, 0]), *rpy])


def _rpy(T: np.ndarray) -> list[float]:
    R = T[:3, :3]
    pitch = math.atan2(-R[2, 0], math.hypot(R[0, 0], R[1, 0]))
    return [math.atan2(R[2, 1], R[2, 2]), pitch, math.atan2(R[1, 0], R[0, 0])]


def _joint_points(n: int) -> list[dict[str, object]]:
    pts = []
    for k in range(n):
        q = list(HOME)
        q[0] += 0.2 * (k + 1)
        q[2] -= 0.1 * (k + 1)
        pts.append({"joints": q, "tag_name": f"T{k}", "tag_index": k})
    return pts


def test_path_with_tags_runs_two_cycles(sup: Supervisor) -> None:
    assert sup.path_load("p", _joint_points(3)).result["points_in_path"] == 3
    list(sup.notices(timeout_s=0.1))
    rv = sup.path_move("p", number_of_cycles=2)
    got = _finals(sup, rv.seq, 60)
    tags = [(notice_data(n)["tag"], notice_data(n)["cycle"]) for n in got if n.event_id == "tag"]
    assert tags == [("T0", "1"), ("T1", "1"), ("T2", "1"), ("T0", "2"), ("T1", "2"), ("T2", "2")]
    assert [n.event_id for n in got if n.final] == ["pathMoveComplete"]
    assert sup.get_tag_id().result == {"path_name": "p", "tag_id": "T2"}


def test_path_load_is_atomic(sup: Supervisor) -> None:
    sup.path_load("a", _joint_points(2))
    bad = _joint_points(3)
    bad[2]["aux_commands"] = ["dio 0 0x1"]  # OFF mask missing
    with pytest.raises(errors.ParamError, match="point 2"):
        sup.path_load("a", bad)
    bad = _joint_points(3)
    bad[1]["joints"] = [0, 0, 3.0, 0, 0, 0]  # joint 3 beyond 150 deg
    with pytest.raises(errors.ParamOutOfRangeError, match="point 1: joint 3"):
        sup.path_load("a", bad)
    assert sup.path_load("a", _joint_points(1)).result["points_in_path"] == 3  # nothing of the bad ones
    sup.path_clear_path("a")
    with pytest.raises(errors.ParamError, match="no path named"):
        sup.path_move("a", number_of_cycles=1)


def test_stop_resume_abort(sup: Supervisor) -> None:
    target = [1.2, 0.0, 0.7, 0.0, 0.9, 0.0]
    rv = sup.move_absolute("far", target, speed_pct=20)
    time.sleep(0.5)
    stop = sup.stop_motion()
    assert stop.ret_code == pb.CMD_EXEC_OK
    assert sup.get_motion_control_state().result["state"] == "PAUSED"
    q_paused = joints(sup)
    # on the joint-space line from HOME to the target (a synchronised joint move)
    frac = [(q - h) / (t - h) for q, h, t in zip(q_paused, HOME, target, strict=False) if abs(t - h) > 0.1]
    assert 0.0 < frac[0] < 1.0 and max(frac) - min(frac) < 0.02
    time.sleep(0.3)
    assert joints(sup) == pytest.approx(q_paused, abs=1e-3)
    sup.resume_motion()
    sup.wait_complete(rv, timeout_s=30)
    assert joints(sup) == pytest.approx(target, abs=2e-3)

    # a path stopped and aborted: the queue is gone and the arm stays where it paused
    sup.path_load("q", _joint_points(3))
    rv = sup.path_move("q", number_of_cycles=1)
    time.sleep(0.3)
    sup.stop_motion()
    q_paused = joints(sup)
    sup.abort_motion()
    assert sup.get_motion_control_state().result["state"] == "RESTING"
    with pytest.raises(errors.AlarmError):
        sup.wait_complete(rv, timeout_s=5)
    with pytest.raises(errors.ParamError, match="no path named"):
        sup.path_move("q", number_of_cycles=1)
    assert joints(sup) == pytest.approx(q_paused, abs=2e-3)


def test_refusals_name_the_limit_and_nothing_moves(sup: Supervisor) -> None:
    before = joints(sup)
    with pytest.raises(errors.ParamOutOfRangeError, match=r"joint 3: 2\.9 rad beyond its limit 2\.618 rad"):
        sup.move_absolute("x", [0, 0, 2.9, 0, 0, 0])
    start = fk(HOME)
    with pytest.raises(errors.ParamOutOfRangeError, match="unreachable"):
        sup.move_absolute("far", [0.9, 0.9, 0.5, *_rpy(start)], frame=pb.BASE_CARTESIAN_FRAME)
    with pytest.raises(errors.ParamOutOfRangeError, match="axis z"):
        sup.move_relative("down", [0, 0, -2.0, 0, 0, 0], frame=pb.BASE_CARTESIAN_FRAME)
    time.sleep(0.2)
    assert joints(sup) == pytest.approx(before, abs=1e-4)
    assert sup.get_motion_control_state().result["state"] == "RESTING"


@pytest.mark.sim_world
def test_wait_aux_times_out_into_path_move_failed(sup: Supervisor) -> None:
    """A `wait` that times out ends the path with pathMoveFailed naming the point
    and the cause; the device stays RESTING and takes the next motion."""
    pts = _joint_points(1)
    pts[0]["aux_commands"] = ["wait 0 0x80 0.3"]
    sup.path_load("w", pts)
    rv = sup.path_move("w", number_of_cycles=1)
    with pytest.raises(errors.AlarmError) as exc:
        sup.wait_complete(rv, timeout_s=20)
    n = exc.value.notice
    assert n.event_id == "pathMoveFailed"
    data = notice_data(n)
    assert data["reason"] == "auxFailed" and data["at_point"] == "0"
    assert "not all set in time" in data["fault"]
    st = sup.get_motion_control_state().result
    assert st["state"] == "RESTING" and st["motion_control_state"] == "robot_stopped_on_error"
    assert st["fault"] == ""
    sup.wait_complete(sup.move_absolute("home", HOME), timeout_s=20)


def test_rsvp_aux_waits_for_the_owner(sup: Supervisor) -> None:
    seen = threading.Event()

    def answer(n: pb.Notice) -> int:
        seen.set()
        return pb.CMD_EXEC_OK

    sup.on_rsvp("ready", answer)
    pts = _joint_points(2)
    pts[0]["aux_commands"] = ["event here", "rsvp ready 5"]
    sup.path_load("r", pts)
    list(sup.notices(timeout_s=0.1))
    rv = sup.path_move("r", number_of_cycles=1)
    got = _finals(sup, rv.seq, 30)
    assert seen.is_set()
    assert [n.event_id for n in got if n.final] == ["pathMoveComplete"]
    assert "here" in [n.event_id for n in got]
