"""The set-point trace (`--setpoint-trace PATH`, docs/deploy.md "Test-only keys"): every
cycle's commanded joints as the control loop handed them to the simulated arm, written at a
clean shutdown. Rest-to-rest joint moves at 100 % speed and acceleration stay within the
model's joint limits cycle by cycle: velocity, acceleration and jerk from the first, second
and third differences of the recorded set-points, within 5 %. Velocity and acceleration
limits are the device's (describe); it does not publish the jerk limits, so they are read
from the default arm's model file, firmware/model/robots/ls-sim6.ini, as test_motion reads
its DH table."""
from __future__ import annotations

import re
import subprocess
from pathlib import Path

import numpy as np
from setpoint_trace import Trace, derivatives, model_values, read_trace, traced

from conftest import LANDSCAPED
from landscape.supervisor import Supervisor

#: Two joint points, every joint moving between them (rad), inside the joint limits and
#: clear of the table; the move from the rest pose at activation to A, then A to B.
POINT_A = [0.6, 0.3, 0.3, 1.2, 0.9, -1.5]
POINT_B = [-0.6, 0.1, 0.5, -1.0, 1.2, 1.5]
MARGIN = 1.05  # finite differences of a jerk-limited profile stay within its limits; 5 % for rounding


def model_jerk_limits() -> np.ndarray:
    """max_jerk of the model file (rad/s^3 per joint)."""
    limits = np.array(model_values("max_jerk"))
    assert limits.shape == (6,), f"qddd_max_rad_s3 has {limits.size} values, not 6"
    return limits


def device_rate_hz(sup: Supervisor) -> int:
    """The control rate the device runs at (sendCommand config)."""
    text = sup.send_command("config").result["result"]
    m = re.search(r"^rate_hz=(\d+)$", text, re.M)
    assert m is not None, f"sendCommand config: no rate_hz line in {text!r}"
    return int(m[1])


def run_moves(tmp_path: Path) -> tuple[Path, np.ndarray, np.ndarray, int]:
    """Start landscaped with the trace, run the two moves, stop it with SIGTERM. The trace,
    the device's velocity and acceleration limits per joint and its control rate."""
    with traced(tmp_path, "trace") as (sup, trace_path):
        assert sup.description is not None, "the device did not describe itself"
        joints = sup.description.res.joints
        qd_max = np.array([j.max_velocity_rad_s for j in joints])
        qdd_max = np.array([j.max_accel_rad_s2 for j in joints])
        rate_hz = device_rate_hz(sup)
        sup.lock()
        sup.activate()  # metres and radians
        sup.set_acceleration(100)
        for name, point in (("A", POINT_A), ("B", POINT_B)):
            sup.wait_complete(sup.move_absolute(name, point, speed_pct=100), timeout_s=30)
    return trace_path, qd_max, qdd_max, rate_hz


def moving_stretches(trace: Trace) -> list[tuple[int, int]]:
    """(first, last) sample index of every run of changing set-points."""
    moving = np.any(np.diff(trace.q_rad, axis=0) != 0.0, axis=1)
    edges = np.flatnonzero(np.diff(np.concatenate([[0], moving.astype(int), [0]])))
    return [(int(a), int(b)) for a, b in zip(edges[::2], edges[1::2], strict=True)]


def test_joint_moves_stay_within_the_models_limits_cycle_by_cycle(tmp_path: Path) -> None:
    trace_path, qd_max, qdd_max, rate_hz = run_moves(tmp_path)
    assert trace_path.exists() and not Path(f"{trace_path}.tmp").exists()
    trace = read_trace(trace_path)
    assert trace.dropped == 0
    assert trace.rate_hz == rate_hz

    # the samples cover both moves: at rest before, between and after them, and at the points
    stretches = moving_stretches(trace)
    assert len(stretches) == 2, f"expected 2 moves, the set-point changes in {stretches}"
    (a0, a1), (b0, b1) = stretches
    assert 0 < a0 and b1 < len(trace.q_rad), "the trace does not start or end at rest"
    np.testing.assert_allclose(trace.q_rad[a1], POINT_A, atol=1e-9)
    np.testing.assert_allclose(trace.q_rad[-1], POINT_B, atol=1e-9)
    assert b1 - b0 > 0.3 * rate_hz, f"the move A -> B took {b1 - b0} cycles"

    d = derivatives(trace)  # the drives stayed on: one sample every period
    jerk_max = model_jerk_limits()
    ratios = {"velocity": np.max(np.abs(d.velocity), axis=0) / qd_max,
              "acceleration": np.max(np.abs(d.acceleration), axis=0) / qdd_max,
              "jerk": np.max(np.abs(d.jerk), axis=0) / jerk_max}
    print(f"\n  {len(trace.q_rad)} set-points at {trace.rate_hz} Hz; max |x|/limit per joint:")
    for what, r in ratios.items():
        print(f"  {what:12s} " + " ".join(f"{v:6.3f}" for v in r) + f"   max {np.max(r):.3f}")
    for what, r in ratios.items():
        assert np.all(r <= MARGIN), f"{what} beyond {MARGIN} x the limit: {r}"
    # the slowest joint of a synchronised move runs at its limits: the check is not vacuous
    assert np.max(ratios["jerk"]) > 0.5 and np.max(ratios["acceleration"]) > 0.5, ratios


def test_a_path_that_cannot_be_created_stops_the_start(tmp_path: Path) -> None:
    """PATH.tmp is created at start, so a missing directory is found then, not at the exit."""
    pty = tmp_path / "ls0"
    trace = tmp_path / "missing" / "setpoints.csv"
    r = subprocess.run([str(LANDSCAPED), "--hal", "sim", "--link", f"slcan:pty:{pty}", "--setpoint-trace",
                        str(trace), "--rt-priority", "0", "--no-lock-memory"],
                       capture_output=True, text=True, timeout=30)
    assert r.returncode == 1, r.stderr
    assert (f"set-point trace: cannot create {trace}.tmp: No such file or directory; give a path in an existing, "
            "writable directory") in r.stderr, r.stderr
    assert not pty.exists()
