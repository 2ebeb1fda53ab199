"""Helpers for the motion-lifecycle tests (test_lifecycle.py, test_lifecycle_model.py):
what the arm really does, from the device's own telemetry broadcasts (JOINTS_* at
the telemetry rate, STATUS with the drives' state), next to what the protocol says."""
from __future__ import annotations

import itertools
import threading
import time
from dataclasses import dataclass

import can

from landscape import telemetry as tm
from landscape._generated import landscape_pb2 as pb
from landscape.supervisor import Supervisor

HOME = [0.0, 0.3, 0.3, 0.0, 0.9, 0.0]  # rad, well inside the reach
FAR = [1.2, -0.2, 0.6, 0.4, 0.5, 0.3]   # a joint move of about 1.5 s at 50 % speed
#: a joint's broadcast position changes by at most this between two sets when at rest
#: (the JOINTS_* resolution is 1e-6 rad; the simulated arm settles to well below this)
REST_STEP_RAD = 2e-4
DRIVES_OFF, DRIVES_ON, DRIVES_FAULT = (tm.choice_value("STATUS", "st_control_mode", n)
                                       for n in ("power_off", "power_on", "controller_error"))


@dataclass
class JointSet:
    t: float                  # host monotonic time when the set was complete
    q: list[float]


class ArmWatch:
    """Every joint set the device broadcasts and its latest STATUS."""

    def __init__(self, sup: Supervisor) -> None:
        self._lock = threading.Lock()
        self._cur: dict[str, float] = {}
        self.sets: list[JointSet] = []
        self.control_mode: int | None = None
        self.status_t = 0.0
        sup.on_telemetry(self._on)

    def _on(self, b: tm.Broadcast) -> None:
        with self._lock:
            if b.name == "STATUS":
                self.control_mode = int(b.signals.get("st_control_mode", -1))
                self.status_t = time.monotonic()
                return
            if not b.name.startswith("JOINTS_"):
                return
            self._cur.update(b.signals)
            if b.name == "JOINTS_56" and all(f"j{i}" in self._cur for i in range(1, 7)):
                self.sets.append(JointSet(time.monotonic(), [float(self._cur[f"j{i}"]) for i in range(1, 7)]))
                if len(self.sets) > 20000:
                    del self.sets[:10000]

    def sets_between(self, t0: float, t1: float) -> list[JointSet]:
        with self._lock:
            return [s for s in self.sets if t0 <= s.t <= t1]

    def wait_sets(self, n: int, after: float, timeout_s: float = 2.0) -> list[JointSet]:
        """The first n sets completed after host time `after`."""
        deadline = time.monotonic() + timeout_s
        while True:
            got = self.sets_between(after, float("inf"))
            if len(got) >= n:
                return got[:n]
            if time.monotonic() > deadline:
                raise AssertionError(f"only {len(got)} JOINTS_* sets within {timeout_s} s (wanted {n})")
            time.sleep(0.005)

    def max_step(self, sets: list[JointSet]) -> float:
        """Largest change of any joint between consecutive sets (rad)."""
        steps = (abs(a - b) for s0, s1 in itertools.pairwise(sets) for a, b in zip(s0.q, s1.q, strict=True))
        return max(steps, default=0.0)

    def moving_after(self, t: float, n: int = 4) -> float:
        """max_step over the n sets that follow host time t."""
        return self.max_step(self.wait_sets(n, t))

    def status_after(self, t: float, timeout_s: float = 1.0) -> int:
        """control_mode of the first STATUS broadcast received after host time t."""
        deadline = time.monotonic() + timeout_s
        while True:
            with self._lock:
                if self.status_t > t and self.control_mode is not None:
                    return self.control_mode
            if time.monotonic() > deadline:
                raise AssertionError("no STATUS broadcast")
            time.sleep(0.005)


def send_emergency(bus: can.BusABC, sender: int = 0xF3) -> None:
    """An EMERGENCY frame from another node on the bus (protocol/landscape.dbc)."""
    bus.send(tm.encode("EMERGENCY", sender, emergency_code=1, emergency_state=1, emergency_source=sender))


def final_of(sup: Supervisor, seq: int, epoch: int, timeout_s: float) -> pb.Notice | None:
    """The final notice of request (epoch, seq) among the notices not read yet."""
    for n in sup.notices(timeout_s=timeout_s):
        if n.final and n.ref_seq == seq and n.session_epoch == epoch:
            return n
    return None


def state(sup: Supervisor) -> dict[str, object]:
    return dict(sup.get_motion_control_state().result)
