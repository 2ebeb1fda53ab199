"""Reading landscaped's set-point trace (`--setpoint-trace PATH`, docs/deploy.md "Test-only
keys"): the joint positions the control loop handed to the simulated arm, one row per cycle
(hal/sim/world/hal_sim_world.h "Set-point trace"), and their finite differences."""
from __future__ import annotations

import re
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from conftest import ROOT, open_slcan, start_controller
from landscape.model import load_model
from landscape.supervisor import Supervisor

FIRST_LINE = re.compile(r"# landscaped setpoint trace: rate_hz=(\d+) samples=(\d+) dropped=(\d+)")
COLUMNS = "t_s,q1,q2,q3,q4,q5,q6"


@dataclass
class Trace:
    rate_hz: int
    dropped: int        # commands after the buffer was full (not in the file)
    t_s: np.ndarray     # (n,) the simulated world's time of each command: one period apart while the drives are on
    q_rad: np.ndarray   # (n, 6) the commanded joint positions

    @property
    def period_s(self) -> float:
        return 1.0 / self.rate_hz


@dataclass
class Derivatives:
    """Per joint (columns), from the differences of consecutive samples."""
    velocity: np.ndarray      # (n-1, 6) rad/s: first difference / dt
    acceleration: np.ndarray  # (n-2, 6) rad/s^2: second difference / dt^2
    jerk: np.ndarray          # (n-3, 6) rad/s^3: third difference / dt^3


def model_values(key: str) -> list[float]:
    """A key of the default arm's model file, firmware/model/robots/ls-sim6.ini (the compiled-in
    model, tests/unit/modelfile), in SI: per joint for a [jointN] key, else one value. The limits
    the device does not publish, such as jerk."""
    m = load_model(ROOT / "firmware" / "model" / "robots" / "ls-sim6.ini")
    if key in m.joints[0]:
        return [j[key] for j in m.joints]
    return [m.cartesian[key]]


@contextmanager
def traced(tmp_path: Path, name: str) -> Iterator[tuple[Supervisor, Path]]:
    """landscaped (sim arm) with a set-point trace and a connected Supervisor; on the way
    out landscaped is stopped, and must have exited 0 with the trace written, at the path
    yielded with the Supervisor."""
    trace_path = tmp_path / f"{name}.csv"
    c = start_controller(tmp_path / name, "--setpoint-trace", str(trace_path))
    try:
        bus = open_slcan(c.pty)
        try:
            with Supervisor(bus, client_name=name) as sup:
                yield sup, trace_path
        finally:
            bus.shutdown()
    finally:
        code = c.stop()
    log = c.log.read_text(errors="replace")
    assert code == 0, f"landscaped exited with {code}:\n{log[-4000:]}"
    assert "Sanitizer" not in log, log[-4000:]
    assert f"written to {trace_path}" in log, log[-4000:]


def read_trace(path: Path) -> Trace:
    """The trace file as arrays; ValueError naming the file when it is not one, or when its
    rows do not match the sample count of its first line."""
    lines = path.read_text().splitlines()
    m = FIRST_LINE.fullmatch(lines[0]) if lines else None
    if m is None:
        raise ValueError(f"{path}: the first line {lines[:1]} is not "
                         "'# landscaped setpoint trace: rate_hz=R samples=N dropped=D'")
    if len(lines) < 2 or lines[1] != COLUMNS:
        raise ValueError(f"{path}: the second line {lines[1:2]} is not the header {COLUMNS!r}")
    rate_hz, samples, dropped = (int(g) for g in m.groups())
    rows = np.loadtxt(lines[2:], delimiter=",", ndmin=2) if len(lines) > 2 else np.empty((0, 7))
    if rows.shape != (samples, 7):
        raise ValueError(f"{path}: {rows.shape[0]} rows of {rows.shape[1]} columns where the first line says "
                         f"samples={samples} of 7 columns")
    return Trace(rate_hz, dropped, rows[:, 0], rows[:, 1:])


def derivatives(trace: Trace) -> Derivatives:
    """Velocity, acceleration and jerk of every joint by finite differences of the samples over
    the control period. ValueError when two consecutive samples are not one period apart (the
    drives were off in between): a difference across the gap would be no derivative."""
    dt = trace.period_s
    steps = np.diff(trace.t_s)
    off = np.flatnonzero(np.abs(steps - dt) > 1e-6 * dt)
    if off.size:
        i = int(off[0])
        raise ValueError(f"samples {i} and {i + 1} are {steps[i]:.9g} s apart, not one period ({dt:g} s): "
                         "take the derivatives of a stretch without gaps")
    q = trace.q_rad
    return Derivatives(np.diff(q, 1, axis=0) / dt, np.diff(q, 2, axis=0) / dt**2, np.diff(q, 3, axis=0) / dt**3)
