"""A model-based test of the motion lifecycle (docs/state-machine.md "Motion lifecycle",
docs/reliability.md section 7). A hypothesis state machine drives
one running landscaped (simulated arm) through the host library with random interleavings
of moves, paths, stopMotion/resumeMotion/abortMotion, deactivate/activate, EMERGENCY
frames, heartbeat loss, disconnect/reconnect and a second supervisor (and, on the drive
arm, LS_ARM=cia402: drive faults, an EMCY of a drive or a drive that goes silent and
answers again), and checks after every step:

- exactly one final notice per request answered CMD_STARTED_OK: none missing once the
  device says nothing moves, none extra, none for a request that did not start (a
  notice is identified by its session epoch and ref_seq), the event id names the command;
- the reported state is the arm's: the joints broadcast after the answer do not move in
  RESTING, PAUSED, LOCKED, UNLOCKED and IDLE, the drives are off in LOCKED/UNLOCKED/IDLE;
- no command is accepted outside its states (the schema's, via the registry) or by a
  supervisor that does not own the device.

Violations are collected (no shrinking: the failing step's history is printed instead).
CI runs a few hundred steps with a fixed seed; the long run (docs/reliability.md):

    LS_MODEL_EXAMPLES=400 LS_MODEL_STEPS=50 LS_MODEL_SEED=1 \\
        .venv/bin/python -m pytest -q -s tests/integration/test_lifecycle_model.py
"""
from __future__ import annotations

import collections
import contextlib
import os
import random
import socket
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import can
import hypothesis
import pytest
from hypothesis import Phase, settings
from hypothesis import strategies as st
from hypothesis.stateful import (
    RuleBasedStateMachine,
    invariant,
    rule,
    run_state_machine_as_test,
)
from lifecycle_rig import DRIVES_ON, HOME, REST_STEP_RAD, ArmWatch, send_emergency

import conftest
from conftest import Controller, open_slcan, start_controller
from landscape._generated import landscape_pb2 as pb
from landscape.errors import ControllerTimeoutError
from landscape.registry import lookup
from landscape.supervisor import RetVal, Supervisor, notice_data

EXAMPLES = int(os.environ.get("LS_MODEL_EXAMPLES", "8"))
STEPS = int(os.environ.get("LS_MODEL_STEPS", "40"))
SEED = int(os.environ.get("LS_MODEL_SEED", "16"))
PROGRESS_EVERY = 1000
ADDR = {"A": 0xF1, "B": 0xF2}
STILL = ("RESTING", "PAUSED", "LOCKED", "UNLOCKED", "IDLE")
OFF = ("LOCKED", "UNLOCKED", "IDLE")
ACTIONS = (["move"] * 6 + ["path"] * 3 + ["stop"] * 3 + ["resume"] * 2 + ["abort"] * 2 + ["deactivate"] * 2
           + ["activate"] * 5 + ["lock"] * 3 + ["release", "emergency", "heartbeat_loss", "disconnect_reconnect"]
           + ["wait"] * 3)
# On the drive arm a drive's fault is one more kind of step: ls-simdrives misbehaves on command
# (docs/simulated-drives.md); every started request still ends once, the arm at rest, drives off.
if conftest.ARM == "cia402":
    ACTIONS += ["drive_fault"] * 2
DRIVE_FAULTS = ("emcy {node:#x} 0x8611", "emcy {node:#x} 0x2310", "silence {node:#x}")
TARGETS = [HOME, [0.4, 0.3, 0.3, 0.0, 0.9, 0.0], [-0.3, 0.1, 0.5, 0.2, 0.7, 0.0], [0.2, 0.5, 0.1, -0.3, 1.1, 0.4]]


@dataclass
class Stats:
    steps: int = 0
    started: int = 0
    finals: int = 0
    reasons: collections.Counter[str] = field(default_factory=collections.Counter)
    rules: collections.Counter[str] = field(default_factory=collections.Counter)
    answers: collections.Counter[str] = field(default_factory=collections.Counter)  # "move:CMD_BUSY_ERR"
    violations: list[str] = field(default_factory=list)
    transport: int = 0        # steps that hit a host-side time-out (counted, not a lifecycle violation)
    t0: float = field(default_factory=time.monotonic)


@dataclass
class World:
    controller: Controller
    bus: can.BusABC
    notifier: can.Notifier
    stats: Stats
    clients: dict[str, Client] = field(default_factory=dict)
    watch: ArmWatch | None = None


def _state_name(v: int) -> str:
    return pb.State.Name(v)


class Client:
    """One supervisor and every final notice it received, by (session epoch, ref_seq)."""

    def __init__(self, name: str, world: World) -> None:
        self.name = name
        self.sup = Supervisor(world.bus, notifier=world.notifier, client_name=f"model-{name}",
                              source_address=ADDR[name], timeout_s=5.0)
        self.finals: dict[tuple[int, int], list[pb.Notice]] = collections.defaultdict(list)
        self.sup.on_notice(self._on)
        try:
            self.sup.open()
        except ControllerTimeoutError:
            # A loaded machine: one more try, then it is a failure. open() left
            # nothing running when it failed, so the retry is a whole open().
            time.sleep(2.0)
            self.sup.open()

    def _on(self, n: pb.Notice) -> None:
        if n.final:
            self.finals[(n.session_epoch, n.ref_seq)].append(n)


class LifecycleModel(RuleBasedStateMachine):
    world: World

    def __init__(self) -> None:
        super().__init__()
        w = self.world
        self.stats = w.stats
        self.history: collections.deque[str] = collections.deque(maxlen=25)
        # the two supervisors live as long as the controller (a new ISO-TP stack per
        # example would only test the host's start-up); each example starts clean
        if not w.clients:
            w.clients = {k: Client(k, w) for k in ("A", "B")}
            w.watch = ArmWatch(w.clients["A"].sup)
        assert w.watch is not None
        self.clients = w.clients
        self.watch = w.watch
        for c in self.clients.values():
            c.finals.clear()
            if not c.sup.connected:
                c.sup.connect()
        self.started: dict[tuple[str, int, int], str] = {}   # (client, epoch, seq) -> command
        self.counted: set[tuple[str, int, int]] = set()      # finals seen and counted
        self.reported: set[tuple[str, int, int]] = set()     # missing or unknown, reported once
        self.extra: dict[tuple[str, int, int], int] = {}
        self.owner: str | None = None
        self._resync_owner()
        a = self.clients["A"]
        st0 = self._state(a)
        if st0 == "UNLOCKED":
            if self._call(a, "lock").ok:
                self.owner = "A"
            self._call(a, "activate")
        a.sup.path_load("mp", [{"joints": TARGETS[1]}, {"joints": TARGETS[2]}], check=False)

    # ------------------------------------------------------------ helpers

    def _violation(self, text: str) -> None:
        self.stats.violations.append(f"{text}\n    last steps: " + " | ".join(self.history))

    def _state(self, c: Client) -> str | None:
        rv = c.sup.request("getMotionControlState", check=False)
        if rv.ret_code < 0:
            return None
        return str(rv.result.get("state", "IDLE"))

    def _any_state(self) -> tuple[str | None, float]:
        for c in self.clients.values():
            if c.sup.connected:
                s = self._state(c)
                if s is not None:
                    return s, time.monotonic()
        return None, time.monotonic()

    def _call(self, c: Client, command: str, **fields: object) -> RetVal:
        """Send `command`; check that an accepted one was valid in the state just before."""
        before, _ = self._any_state()
        rv = c.sup.request(command, check=False, **fields)
        cmd = lookup(command)
        self.history.append(f"{c.name}:{command}->{rv.ret_name}({before})")
        self.stats.answers[f"{command}:{rv.ret_name}"] += 1
        if rv.ret_code >= 0:
            valid = cmd.state_names
            # a motion may complete between the state query and the command
            ok = before in valid or (before == "MOVING" and "RESTING" in valid) or command in ("connect",)
            if before is not None and not ok:
                self._violation(f"{c.name} {command} accepted in {before} (valid: {valid})")
            if cmd.owner_only and self.owner not in (None, c.name) and before not in (None, "UNLOCKED"):
                self._violation(f"{c.name} {command} accepted although {self.owner} owns the device")
        if rv.started:
            self.started[(c.name, rv.epoch, rv.seq)] = cmd.name
            self.stats.started += 1
        return rv

    def _transport(self) -> str:
        """The device's downlink counters that tell a lost notice from one never sent."""
        for c in self.clients.values():
            rv = c.sup.request("sendCommand", check=False, input="status")
            if rv.ret_code >= 0:
                text = str(rv.result.get("result", ""))
                keep = [ln for ln in text.splitlines()
                        if ln.startswith(("tx_", "isotp_", "link_"))]
                return " ".join(keep)
        return "?"

    def _owner_client(self) -> Client | None:
        return self.clients[self.owner] if self.owner is not None else None

    def _wait_not_moving(self, timeout_s: float = 8.0) -> str | None:
        deadline = time.monotonic() + timeout_s
        while True:
            s, _ = self._any_state()
            if s not in ("MOVING", "PAUSED") or time.monotonic() > deadline:
                return s
            time.sleep(0.05)

    def _resync_owner(self) -> None:
        """Who owns the device now (after losses, reconnects)."""
        for k, c in self.clients.items():
            if not c.sup.connected:
                continue
            rv = c.sup.request("getMotionControlState", check=False)
            if rv.ret_code >= 0 and rv.result.get("owner"):
                self.owner = k
                return
        self.owner = None

    # ------------------------------------------------------------ rules

    def _count(self, name: str) -> None:
        self.stats.steps += 1
        self.stats.rules[name] += 1
        s = self.stats
        if s.steps % PROGRESS_EVERY == 0:
            # a long run says how far it is (pytest -s shows it)
            print(f"lifecycle model: {s.steps} steps, {time.monotonic() - s.t0:.0f} s, {s.started} started, "
                  f"{s.finals} finals, {s.transport} host time-outs, {len(s.violations)} violations",
                  file=sys.stderr, flush=True)

    def _pick(self, role: str) -> Client:
        """The owner (or A when nobody owns the device), or the other supervisor."""
        own = self.owner or "A"
        return self.clients[own if role == "owner" else ("B" if own == "A" else "A")]

    def move(self, role: str, pose: int, speed: float) -> None:
        self._count("move")
        self._call(self._pick(role), "moveAbsolute", point_name=f"t{pose}", frame=pb.JOINT_FRAME,
                   values=TARGETS[pose], speed_pct=speed)

    def path(self, role: str) -> None:
        self._count("path")
        c = self._pick(role)
        if c.sup.connected and self.owner == c.name:
            c.sup.path_load("mp", [{"joints": TARGETS[1]}, {"joints": TARGETS[2]}], check=False)
        self._call(c, "pathMove", path_name="mp", number_of_cycles=1)

    def stop(self) -> None:
        self._count("stop")
        c = self._owner_client() or self.clients["A"]
        rv = self._call(c, "stopMotion")
        if rv.ok:
            s, _ = self._any_state()
            if s not in ("PAUSED", "RESTING", "LOCKED"):
                self._violation(f"stopMotion answered OK but the state is {s}")

    def resume(self) -> None:
        self._count("resume")
        self._call(self._owner_client() or self.clients["A"], "resumeMotion")

    def abort(self) -> None:
        self._count("abort")
        self._call(self._owner_client() or self.clients["A"], "abortMotion")

    def deactivate(self) -> None:
        self._count("deactivate")
        c = self._owner_client() or self.clients["A"]
        rv = self._call(c, "deactivate")
        if rv.ok:
            t = time.monotonic()
            step = self.watch.moving_after(t, 3)
            if step > REST_STEP_RAD:
                self._violation(f"deactivate answered while the joints moved {step:.2e} rad per broadcast")
            if self.watch.status_after(t) == DRIVES_ON:
                self._violation("deactivate answered with the drives on")

    def activate(self) -> None:
        self._count("activate")
        self._call(self._owner_client() or self.clients["A"], "activate")

    def lock(self, who: str) -> None:
        self._count("lock")
        if self._call(self.clients[who], "lock").ok:
            self.owner = who

    def release(self) -> None:
        self._count("release")
        c = self._owner_client() or self.clients["A"]
        if self._call(c, "release").ok:
            self.owner = None

    def emergency(self) -> None:
        self._count("emergency")
        self.history.append("EMERGENCY")
        send_emergency(self.world.bus)
        time.sleep(0.01)
        self._wait_not_moving()

    def heartbeat_loss(self, who: str) -> None:
        self._count("heartbeat_loss")
        c = self.clients[who]
        self.history.append(f"{who}:heartbeat-stop")
        c.sup._stop_heartbeat()
        time.sleep(1.3)  # the device's time-out is 1 s
        other = self.clients["B" if who == "A" else "A"]
        deadline = time.monotonic() + 8
        while time.monotonic() < deadline:
            s = self._state(other)
            if s not in ("MOVING", "PAUSED"):
                break
            time.sleep(0.05)
        c.sup.connect()
        self.history.append(f"{who}:reconnect")
        self._resync_owner()

    def disconnect_reconnect(self, who: str) -> None:
        self._count("disconnect")
        c = self.clients[who]
        rv = c.sup.disconnect(check=False)
        self.history.append(f"{who}:disconnect->{rv.ret_name}")
        time.sleep(0.05)
        self._wait_not_moving()
        c.sup.connect()
        self.history.append(f"{who}:reconnect")
        self._resync_owner()

    def drive_fault(self, pose: int, speed: float) -> None:
        """A drive of the drive arm faults (an EMCY) or goes silent, then answers again:
        drawn from the step's other draws, so that the seed alone fixes the run."""
        self._count("drive_fault")
        ctl = self.world.controller.drives_control
        assert ctl is not None
        node = 0x21 + (pose + int(speed)) % 6
        what = DRIVE_FAULTS[pose % len(DRIVE_FAULTS)].format(node=node)
        self.history.append(f"drive: {what}")
        with socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM) as sk:
            sk.sendto(what.encode(), str(ctl))
            time.sleep(0.3)  # its heartbeat or its feedback missed for longer than the device allows
            if what.startswith("silence"):
                sk.sendto(b"reset", str(ctl))
        self._wait_not_moving()

    def wait(self, dt: float) -> None:
        self._count("wait")
        time.sleep(dt)

    @rule(action=st.sampled_from(ACTIONS), who=st.sampled_from(["A", "B"]),
          role=st.sampled_from(["owner", "owner", "owner", "other"]),
          pose=st.sampled_from(range(len(TARGETS))), speed=st.sampled_from([8.0, 20.0, 100.0]),
          dt=st.sampled_from([0.0, 0.05, 0.3]))
    def act(self, action: str, who: str, role: str, pose: int, speed: float, dt: float) -> None:
        """One step: the action drawn (weighted by repetition in ACTIONS). A host-side
        time-out (the bus or the machine too slow) is counted and the sessions resynced."""
        try:
            self._act(action, who, role, pose, speed, dt)
        except ControllerTimeoutError as exc:
            self.stats.transport += 1
            self.history.append(f"{action}: time-out ({exc})")
            for c in self.clients.values():
                if not c.sup.connected or self._state(c) is None:
                    with contextlib.suppress(ControllerTimeoutError):
                        c.sup.connect()
            self._resync_owner()

    def _act(self, action: str, who: str, role: str, pose: int, speed: float, dt: float) -> None:
        if action == "move":
            self.move(role, pose, speed)
        elif action == "path":
            self.path(role)
        elif action in ("lock", "heartbeat_loss", "disconnect_reconnect"):
            getattr(self, action)(who)
        elif action == "wait":
            self.wait(dt)
        elif action == "drive_fault":
            self.drive_fault(pose, speed)
        else:
            getattr(self, action)()

    # ------------------------------------------------------------ invariants

    def _check_finals(self, settle_s: float) -> None:
        """Extra and misattributed finals always; missing ones (after settle_s) when settle_s > 0."""
        for name, c in self.clients.items():
            for (epoch, seq), ns in list(c.finals.items()):
                key = (name, epoch, seq)
                if key not in self.started:
                    if key not in self.reported:
                        self.reported.add(key)
                        self._violation(f"{name}: final {ns[0].event_id} for (epoch {epoch}, seq {seq}) that "
                                        f"did not start")
                    continue
                if key not in self.counted:
                    self.counted.add(key)
                    self.stats.finals += 1
                    self.stats.reasons[notice_data(ns[0]).get("reason", "?")] += 1
                    if not ns[0].event_id.startswith(self.started[key]):
                        self._violation(f"{name}: final {ns[0].event_id} for a {self.started[key]}")
                if len(ns) > 1 and self.extra.get(key, 1) != len(ns):
                    self.extra[key] = len(ns)
                    self._violation(f"{name}: {len(ns)} final notices for {key}: {[n.event_id for n in ns]}")
        if settle_s <= 0:
            return
        deadline = time.monotonic() + settle_s
        while True:
            missing = [k for k in self.started
                       if (k[1], k[2]) not in self.clients[k[0]].finals and k not in self.reported]
            if not missing or time.monotonic() > deadline:
                break
            time.sleep(0.02)
        for k in missing:
            self.reported.add(k)
            self._violation(f"no final notice for {self.started[k]} {k}; device transport: {self._transport()}")

    @invariant()
    def state_is_the_arms(self) -> None:
        try:
            self._check_state()
        except ControllerTimeoutError as exc:
            self.stats.transport += 1
            self.history.append(f"check: time-out ({exc})")

    def _check_state(self) -> None:
        s, t = self._any_state()
        if s is None:
            return
        if s in STILL:
            step = self.watch.moving_after(t, 3)
            if step > REST_STEP_RAD:
                self._violation(f"state {s} while the joints moved {step:.2e} rad per broadcast")
        if s in OFF and self.watch.status_after(t) == DRIVES_ON:
            self._violation(f"state {s} with the drives on")
        self._check_finals(1.0 if s not in ("MOVING", "PAUSED") else 0.0)

    def teardown(self) -> None:
        # the owner deactivates and releases: whatever moves halts, every started request ends
        s: str | None = "MOVING"
        for _ in range(3):
            try:
                self._resync_owner()
                c = self._owner_client()
                if c is not None:
                    self._call(c, "deactivate")
                    self._call(c, "release")
                s = self._wait_not_moving(20.0)
                break
            except ControllerTimeoutError:
                self.stats.transport += 1
        self._check_finals(2.0 if s not in ("MOVING", "PAUSED") else 0.0)


@pytest.fixture
def world(tmp_path: Path) -> Iterator[World]:
    # 50 Hz: 350 telemetry frames/s leave the host's SLCAN reader (one byte per
    # read) room on a loaded machine; at 200 Hz (1,400 frames/s) it fell behind,
    # the pty filled and the first connect went unanswered for 15 s. Three joint
    # sets (60 ms) still judge "at rest" after every step.
    c = start_controller(tmp_path / "ls0", "--telemetry-hz", "50")
    bus = open_slcan(c.pty)
    notifier = can.Notifier(bus, [], timeout=0.01)
    w = World(c, bus, notifier, Stats())
    try:
        yield w
    finally:
        for cl in w.clients.values():
            with contextlib.suppress(Exception):
                cl.sup.close()
        notifier.stop()
        bus.shutdown()
        code = c.stop()
        assert code == 0, c.log.read_text(errors="replace")[-3000:]


def test_lifecycle_model(world: World) -> None:
    LifecycleModel.world = world
    random.seed(SEED)

    def factory() -> LifecycleModel:
        return LifecycleModel()

    factory = hypothesis.seed(SEED)(factory)
    t0 = time.monotonic()
    run_state_machine_as_test(factory, settings=settings(
        max_examples=EXAMPLES, stateful_step_count=STEPS, deadline=None, database=None,
        phases=[Phase.generate], suppress_health_check=list(hypothesis.HealthCheck), print_blob=False))
    s = world.stats
    print(f"\nlifecycle model: seed {SEED}, {s.steps} steps in {time.monotonic() - t0:.0f} s, "
          f"{s.started} started, {s.finals} finals, reasons {dict(s.reasons)}, rules {dict(s.rules)}, "
          f"answers {dict(s.answers)}, "
          f"{s.transport} host time-outs, {len(s.violations)} violations")
    assert s.steps > 0 and s.started > 0
    # the model sends well-formed requests only: a parameter refusal is a model gone stale
    # (it once sent no frame, and not one move started)
    bad = {k: n for k, n in s.answers.items() if k.endswith(("PARAM_ERR", "PARAM_OUT_OF_RANGE_ERR"))}
    assert not bad, f"requests the device found malformed: {bad}"
    assert s.answers["moveAbsolute:CMD_STARTED_OK"] > 0, "not one move started"
    assert not s.violations, "\n".join(s.violations[:10])
    # A time-out is not a lifecycle violation, but a device that stopped
    # answering would turn every later step into one: more than a tenth fails.
    assert s.transport * 10 <= s.steps, f"{s.transport} of {s.steps} steps timed out on the host"
