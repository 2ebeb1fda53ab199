"""Benchmarks 14-16: the arm behind CiA 402 drives (docs/architecture.md "Drives").

14. The drive bus's load per cycle for six axes at 1, 2 and 4 ms, with and without
    velocity feed-forward, at 1 Mbit/s and 500 kbit/s: landscaped's own figures
    (bench/drive_budget.c runs its drive plan and ls_drive_budget) against the ceiling
    landscaped enforces.
15. The SYNC period as the drives receive it on the host composition (landscaped ->
    SLCAN pty -> ls-simdrives, whose --sync-stats notes every SYNC's arrival) over N
    seconds of motion, against the configured drive cycle.
16. Tracking: the same joint move and straight line on the simulated arm inside
    landscaped and on the same arm behind the six simulated drives: max |q - q_cmd| per
    joint from the telemetry (JOINTS_* and JOINTS_CMD_* of one snapshot, through the
    host's decoder) and the tip's distance from the line (FK of the measured joints),
    side by side."""

from __future__ import annotations

import math
import re
import signal
import subprocess
import tempfile
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from common import BIN, BUILD, ROOT, BenchError, Row, Section, fmt_ratio, need
from landscape import BusSpec, Supervisor, telemetry
from landscape._generated import landscape_pb2 as pb
from landscape.supervisor import notice_data
from landscape.urdf import ArmChain

SIMDRIVE_EDS = ROOT / "hal" / "sim" / "drives" / "ls-simdrive.eds"
DRIVE_NODES = (0x21, 0x22, 0x23, 0x24, 0x25, 0x26)
COUNTS_PER_RAD = 2**17 * 100 / (2 * math.pi)  # ls-simdrives' default: a 17-bit encoder behind 100:1
RATE_HZ = 1000  # landscaped's default control rate
DRIVE_CYCLE = 4  # [drives] cycle's default: 4 control periods
# ls-simdrives is an ordinary process on a machine shared with builds: it may answer a SYNC
# tens of ms late where a drive would not (tests/integration/conftest.py allows the same).
STALE_CYCLES = 25
# Real-time below landscaped's control thread (80), as tests/integration/conftest.py runs it:
# drives answer each SYNC in time, as hardware does.
SIMDRIVES_RT_PRIORITY = 60
TELEMETRY_HZ = 200  # the most landscaped sends: one JOINTS/JOINTS_CMD snapshot every 5 ms
HOME = [0.0, 0.3, 0.3, 0.0, 0.9, 0.0]  # a pose well inside the reach (tests/integration/test_motion.py)
JOINT_TARGET = [0.5, 0.1, 0.6, -0.4, 0.7, 1.0]
LINE_OFFSET_M = (-0.15, 0.2, 0.1)


def drive_conf(path: Path, drive_link: str, hal_link: str = "") -> Path:
    """A landscaped.conf for arm = cia402: six joints of ls-simdrives behind `drive_link`;
    the supervisors' link in the file when given (else on landscaped's command line)."""
    keys = {"stale_cycles": str(STALE_CYCLES)}
    lines = ["[hal]", *([f"link = {hal_link}"] if hal_link else []), "arm = cia402", "dio = none", "[drives]",
             f"link = {drive_link}",
             *(f"{k} = {v}" for k, v in keys.items())]
    for j, node in enumerate(DRIVE_NODES):
        lines += [f"[joint.{j + 1}]", f"node = {node:#x}", f"eds = {SIMDRIVE_EDS}",
                  f"counts_per_rad = {COUNTS_PER_RAD!r}"]
    path.write_text("\n".join(lines) + "\n")
    return path


# ---------------------------------------------------------------- 14. the bus budget


@dataclass(frozen=True)
class BudgetCase:
    bitrate: int
    cycle_us: int
    feedforward: bool
    frames: float
    bits: float
    load_pct: float
    ceiling_pct: float
    fits: bool
    min_multiple: int
    line: str


def budget_cases(conf: Path) -> list[BudgetCase]:
    exe = need(BIN / "bench_drive_budget", "the drive budget driver")
    out = subprocess.run([str(exe), str(conf)], capture_output=True, text=True, timeout=60)
    if out.returncode != 0:
        raise BenchError(f"bench_drive_budget failed: {out.stderr.strip()}")
    cases = []
    for row in out.stdout.splitlines():
        f = row.split("\t")
        cases.append(BudgetCase(int(f[0]), int(f[1]), f[2] == "1", float(f[3]), float(f[4]), float(f[5]),
                                float(f[6]), f[7] == "1", int(f[8]), f[9]))
    if len(cases) != 12:
        raise BenchError(f"bench_drive_budget gave {len(cases)} cases, expected 12 (2 bitrates x 2 x 3 cycles)")
    return cases


def bench_budget(quick: bool) -> Section:
    sec = Section(14, "Drive bus load per cycle, six CiA 402 axes")
    with tempfile.TemporaryDirectory(prefix="ls-bench-budget-") as tmp:
        cases = budget_cases(drive_conf(Path(tmp) / "drives.conf", "socketcan:can1", "socketcan:can0"))
    for bitrate in sorted({c.bitrate for c in cases}, reverse=True):
        for ff in (False, True):
            row = sorted((c for c in cases if c.bitrate == bitrate and c.feedforward == ff), key=lambda c: c.cycle_us)
            rate = f"{bitrate // 1000000} Mbit/s" if bitrate % 1000000 == 0 else f"{bitrate // 1000} kbit/s"
            pdos = "SYNC + 12 RPDO + 6 TPDO" if ff else "SYNC + 6 RPDO + 6 TPDO"
            fit = row[0].min_multiple * 1000 // RATE_HZ
            fits = f"the shortest cycle that fits: {fit} ms" if fit else "no cycle up to 1000 control periods fits"
            cycles = " / ".join(f"{c.cycle_us / 1000:g}" for c in row)
            sec.rows.append(Row(
                f"14. drive bus, 6 axes, {rate}, feed-forward {'on' if ff else 'off'}",
                " / ".join(f"{c.cycle_us / 1000:g} ms: {math.ceil(c.bits):,} bit-times = {c.load_pct:.0f} %"
                           f"{'' if c.fits else ' (refused)'}" for c in row),
                "landscaped's ceiling ([drives] budget_pct)", f"{row[0].ceiling_pct:g} %",
                " / ".join(fmt_ratio(c.load_pct / c.ceiling_pct) for c in row) + f" (load / ceiling at {cycles} ms)",
                f"{row[0].frames:.2f} frames per {row[0].cycle_us / 1000:g} ms cycle ({pdos} + heartbeats); {fits}"))
    worst = max(cases, key=lambda c: c.load_pct)
    sec.details.append(
        "`bench/drive_budget.c` loads a landscaped.conf with six joints of the simulated drive's EDS "
        "(`hal/sim/drives/ls-simdrive.eds`) through landscaped's own loader, and for each case sets `[drives] "
        "bitrate`, `velocity_feedforward` and `cycle` (control periods at 1 kHz), runs landscaped's drive plan "
        "(`ls_drive_plan`: the PDOs it maps from the EDS, the budget line start and `--check` print) and "
        "`ls_drive_budget_compute` on the same PDOs; the two lines must agree or the benchmark fails. Bit-times "
        "are worst-case stuffed (ls_drive_budget.h: 55 for a SYNC, 115 for a 6-byte PDO), "
        "heartbeats (the master's and six drives' at 100 ms) amortised over the cycle. A case above the ceiling "
        "is one landscaped refuses at start, naming the shortest cycle that fits.")
    sec.details.append(f"The heaviest case, as landscaped prints it: `{worst.line}`.")
    sec.commands.append("build-bench/bench/bench_drive_budget drives.conf   # 'bitrate cycle_us ff frames bits "
                        "load_pct ceiling fits min_multiple line' per case")
    return sec


# ---------------------------------------------------------------- the compositions


@dataclass
class Composition:
    """landscaped (and, with drives, ls-simdrives) running; `pty` is landscaped's SLCAN link."""

    pty: Path
    log: Path
    drives_log: Path | None


def _stop(proc: subprocess.Popen[bytes], name: str) -> int:
    if proc.poll() is None:
        proc.send_signal(signal.SIGTERM)
    try:
        return proc.wait(timeout=15)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()
        raise BenchError(f"{name} did not stop within 15 s of SIGTERM") from None


def _wait_for(pred: Callable[[], bool], proc: subprocess.Popen[bytes], log: Path, what: str, timeout_s: float) -> None:
    deadline = time.monotonic() + timeout_s
    while not pred():
        if proc.poll() is not None:
            raise BenchError(f"{what}: the process exited with {proc.returncode}: "
                             f"{log.read_text(errors='replace').strip()[-600:]}")
        if time.monotonic() > deadline:
            raise BenchError(f"{what} within {timeout_s:g} s: {log.read_text(errors='replace').strip()[-600:]}")
        time.sleep(0.02)


@contextmanager
def composition(tmp: Path, *, drives: bool, sync_stats: bool = False) -> Iterator[Composition]:
    """landscaped on an SLCAN pty with the simulated arm in its process (drives=False), or
    behind ls-simdrives on a drive pty of its own (drives=True, the composition of
    docs/deploy.md "Without hardware: the simulated drives"). Both are stopped with SIGTERM
    at the end; ls-simdrives after landscaped, which disables the drives on its way out."""
    landscaped = need(BUILD / "bin" / "landscaped", "the firmware")
    pty, log = tmp / "ls0", tmp / "landscaped.log"
    sim: subprocess.Popen[bytes] | None = None
    drives_log: Path | None = None
    args = ["--hal", "sim"]
    if drives:
        simdrives = need(BUILD / "bin" / "ls-simdrives", "the simulated drives")
        drive_pty, drives_log = tmp / "drives0", tmp / "ls-simdrives.log"
        with drives_log.open("wb") as err:
            sim = subprocess.Popen([str(simdrives), "--link", f"slcan:pty:{drive_pty}", "--counts-per-rad",
                                    repr(COUNTS_PER_RAD), "--rt-priority", str(SIMDRIVES_RT_PRIORITY),
                                    *(["--sync-stats"] if sync_stats else [])],
                                   stdout=subprocess.DEVNULL, stderr=err)
        _wait_for(drive_pty.exists, sim, drives_log, "ls-simdrives made its pty", 10)
        args = ["--config", str(drive_conf(tmp / "drives.conf", f"slcan:tty:{drive_pty}"))]
    try:
        with log.open("wb") as err:
            proc = subprocess.Popen([str(landscaped), *args, "--link", f"slcan:pty:{pty}", "--telemetry-hz",
                                     str(TELEMETRY_HZ)], stdout=subprocess.DEVNULL, stderr=err)
        try:
            _wait_for(lambda: "ready: node" in log.read_text(errors="replace"), proc, log,
                      "landscaped got ready" + (" (its drives booted)" if drives else ""), 30)
            yield Composition(pty, log, drives_log)
        finally:
            rc = _stop(proc, "landscaped")
            if rc != 0:
                raise BenchError(f"landscaped exited with {rc}: {log.read_text(errors='replace').strip()[-600:]}")
    finally:
        if sim is not None and drives_log is not None:
            rc = _stop(sim, "ls-simdrives")
            if rc != 0:
                raise BenchError(f"ls-simdrives exited with {rc}: {drives_log.read_text(errors='replace')[-600:]}")


def supervisor(pty: Path) -> Supervisor:
    return Supervisor.open_bus(BusSpec(interface="slcan", channel=str(pty)), client_name="bench-drives",
                               timeout_s=5.0)


def move(sup: Supervisor, name: str, values: list[float], *, frame: int = pb.JOINT_FRAME,
         speed_pct: float = 100) -> list[float]:
    """One motion to completion; the joints its completion reports."""
    done = sup.wait_complete(sup.move_absolute(name, values, frame=frame, speed_pct=speed_pct), timeout_s=60)
    if done.event_id != "moveAbsoluteComplete":
        raise BenchError(f"move {name} ended with {done.event_id}: {notice_data(done)}")
    return [float(v) for v in notice_data(done)["joints"].split(",")]


# ---------------------------------------------------------------- 15. the SYNC period


SYNC_LINE = re.compile(r"SYNC intervals as received: (\d+) over ([\d.]+) s: median (\d+) us, p99 (\d+) us, "
                       r"min (\d+) us, max (\d+) us, mean ([\d.]+) us")


def bench_sync(quick: bool) -> Section:
    sec = Section(15, "SYNC period as the drives receive it (host composition)")
    seconds = 5.0 if quick else 30.0
    cycle_ms = DRIVE_CYCLE * 1000 / RATE_HZ
    moves = 0
    with tempfile.TemporaryDirectory(prefix="ls-bench-sync-") as tmp:
        with composition(Path(tmp), drives=True, sync_stats=True) as c:
            with supervisor(c.pty) as sup:
                sup.lock()
                sup.activate()
                t_end = time.monotonic() + seconds
                while time.monotonic() < t_end:
                    move(sup, f"p{moves}", JOINT_TARGET if moves % 2 == 0 else HOME)
                    moves += 1
                sup.deactivate()
                sup.release()
        assert c.drives_log is not None
        text = c.drives_log.read_text(errors="replace")
    m = SYNC_LINE.search(text)
    if m is None:
        raise BenchError(f"ls-simdrives --sync-stats printed no SYNC figures: {text.strip()[-600:]}")
    n, span = int(m[1]), float(m[2])
    med, p99, lo, hi = (int(m[k]) / 1000 for k in range(3, 7))
    dev = max(hi - cycle_ms, cycle_ms - lo)
    sec.rows.append(Row(
        f"15. SYNC period at the drives, {n} intervals over {span:.0f} s",
        f"median {med:.3f} / p99 {p99:.3f} / min {lo:.3f} / max {hi:.3f} ms",
        "the configured drive cycle ([drives] cycle = 4 at 1 kHz)", f"{cycle_ms:g} ms",
        f"{fmt_ratio(med / cycle_ms)} (median), {fmt_ratio(hi / cycle_ms)} (max)",
        f"largest deviation {dev:.3f} ms; {moves} joint moves meanwhile; landscaped's loop SCHED_FIFO 80, "
        f"ls-simdrives SCHED_FIFO {SIMDRIVES_RT_PRIORITY}"))
    sec.details.append(
        f"`bench/b_drives.py`: ls-simdrives (`--sync-stats`) on an SLCAN pty, landscaped `--config` with "
        f"`arm = cia402` on it (the composition of docs/deploy.md \"Without hardware: the simulated drives\"), "
        f"the host library locking, activating and moving the arm back and forth for {seconds:g} s. ls-simdrives "
        "notes each SYNC's arrival (CLOCK_MONOTONIC when it reads the frame) and logs the interval statistics "
        "at exit; the figures cover the SYNCs from the drives' start to landscaped's exit. What they measure: "
        "landscaped's control thread waking on time (it sends each cycle's RPDOs, then the SYNC), the pty, and "
        "ls-simdrives' own wake-up; a short interval after a long one is the reader catching up. A drive "
        "interpolates each set-point over 0x60C2 = the drive cycle, so a late SYNC stretches one step.")
    sec.commands.append("build-bench/bin/ls-simdrives --link slcan:pty:/tmp/drives0 --sync-stats &")
    sec.commands.append("build-bench/bin/landscaped --config drives.conf --link slcan:pty:/tmp/ls0   # then moves; "
                        "SIGTERM both: ls-simdrives logs 'SYNC intervals as received: ...'")
    return sec


# ---------------------------------------------------------------- 16. tracking


@dataclass
class Snapshots:
    """(q, q_cmd) of every telemetry snapshot of the device: the JOINTS_* and JOINTS_CMD_*
    that landscaped sends from one control-loop snapshot (STATUS opens it)."""

    lock: threading.Lock = field(default_factory=threading.Lock)
    cur: dict[str, float] = field(default_factory=dict)
    sets: list[tuple[list[float], list[float]]] = field(default_factory=list)

    def on_broadcast(self, b: telemetry.Broadcast) -> None:
        with self.lock:
            if b.name == "STATUS":
                self.cur.clear()
            elif b.name.startswith("JOINTS_"):
                self.cur.update({k: float(v) for k, v in b.signals.items()})
                if b.name == "JOINTS_CMD_56" and len(self.cur) == 12:
                    self.sets.append(([self.cur[f"j{i}"] for i in range(1, 7)],
                                      [self.cur[f"j{i}_cmd"] for i in range(1, 7)]))

    def mark(self) -> int:
        with self.lock:
            return len(self.sets)

    def since(self, mark: int) -> list[tuple[list[float], list[float]]]:
        with self.lock:
            return list(self.sets[mark:])


@dataclass
class Tracking:
    joint_err: list[float]  # max |q - q_cmd| per joint over the joint move, rad
    joint_speed: list[float]  # the set-point's peak speed per joint, rad/s
    line_err: list[float]  # max |q - q_cmd| per joint over the line
    line_dev_m: float  # the measured tip's largest distance from the line
    line_cmd_dev_m: float  # the set-point's (FK of q_cmd)
    end_err_m: float  # the measured tip at completion vs the line's end
    samples: int


def _during(snaps: Snapshots, fn: Callable[[], object]) -> list[tuple[list[float], list[float]]]:
    m = snaps.mark()
    fn()
    time.sleep(0.2)  # the last broadcasts of the motion, and the lag behind drives
    got = snaps.since(m)
    if len(got) < 20:
        raise BenchError(f"{len(got)} telemetry snapshots during a motion: expected hundreds at {TELEMETRY_HZ} Hz")
    return got


def _segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    t = float(np.clip(np.dot(p - a, b - a) / np.dot(b - a, b - a), 0.0, 1.0))
    return float(np.linalg.norm(p - (a + t * (b - a))))


def track(drives: bool) -> Tracking:
    chain = ArmChain()
    snaps = Snapshots()
    with tempfile.TemporaryDirectory(prefix="ls-bench-track-") as tmp:
        with composition(Path(tmp), drives=drives) as c, supervisor(c.pty) as sup:
            sup.on_telemetry(snaps.on_broadcast)
            sup.lock()
            sup.activate()
            move(sup, "home", HOME, speed_pct=50)
            time.sleep(0.3)
            joint = _during(snaps, lambda: move(sup, "joint", JOINT_TARGET))
            q0 = move(sup, "home2", HOME, speed_pct=50)
            time.sleep(0.3)
            start = chain.fk(q0)
            pose = [float(v) for v in sup.get_robot_position().result["world_pose"]]
            goal = [pose[0] + LINE_OFFSET_M[0], pose[1] + LINE_OFFSET_M[1], pose[2] + LINE_OFFSET_M[2], *pose[3:]]
            q1: list[float] = []
            line = _during(snaps, lambda: q1.extend(move(sup, "line", goal, frame=pb.BASE_CARTESIAN_FRAME,
                                                              speed_pct=50)))
            time.sleep(0.3)
            q_end = [float(v) for v in sup.get_robot_position().result["joints"]]
            sup.deactivate()
            sup.release()
    a, b = start[:3, 3], chain.fk(q1)[:3, 3]

    def err(sets: list[tuple[list[float], list[float]]]) -> list[float]:
        return [max(abs(q[j] - qc[j]) for q, qc in sets) for j in range(6)]

    period = 1.0 / TELEMETRY_HZ
    speed = [max(abs(joint[k + 1][1][j] - joint[k][1][j]) / period for k in range(len(joint) - 1)) for j in range(6)]
    return Tracking(
        joint_err=err(joint), joint_speed=speed, line_err=err(line),
        line_dev_m=max(_segment_distance(chain.fk(q)[:3, 3], a, b) for q, _ in line),
        line_cmd_dev_m=max(_segment_distance(chain.fk(qc)[:3, 3], a, b) for _, qc in line),
        end_err_m=float(np.linalg.norm(chain.fk(q_end)[:3, 3] - b)), samples=len(joint) + len(line))


def _lag_s(t: Tracking) -> float:
    """The fastest joint's largest error over its peak speed: the lag that error amounts to."""
    j = max(range(6), key=lambda k: t.joint_speed[k])
    return t.joint_err[j] / t.joint_speed[j]


def _mrad(v: list[float]) -> str:
    return " / ".join(f"{1000 * x:.2f}" for x in v)


def bench_tracking(quick: bool) -> Section:
    sec = Section(16, "Tracking behind the drives vs the simulated arm")
    sim = track(drives=False)
    drv = track(drives=True)
    lag_ms = 1000 * (3 * DRIVE_CYCLE + 2) / RATE_HZ
    sec.rows.append(Row(
        "16a. joint move, max |q - q_cmd| per joint (mrad)", f"behind the drives: {_mrad(drv.joint_err)}",
        "the simulated arm in landscaped", _mrad(sim.joint_err),
        f"{fmt_ratio(max(drv.joint_err) / max(sim.joint_err))} (largest joint)",
        f"set-point peak speed {' / '.join(f'{v:.2f}' for v in drv.joint_speed)} rad/s; on the fastest joint "
        f"error / speed = {1000 * _lag_s(drv):.1f} ms behind the drives, {1000 * _lag_s(sim):.1f} ms on the sim "
        f"arm; the drives' feedback lags by up to 3 x cycle + 2 periods = {lag_ms:g} ms"))
    sec.rows.append(Row(
        "16b. straight line, max |q - q_cmd| per joint (mrad)", f"behind the drives: {_mrad(drv.line_err)}",
        "the simulated arm in landscaped", _mrad(sim.line_err),
        f"{fmt_ratio(max(drv.line_err) / max(sim.line_err))} (largest joint)",
        f"{LINE_OFFSET_M} m at 50 % speed"))
    sec.rows.append(Row(
        "16c. straight line, the tip's largest distance from the line",
        f"behind the drives: {1000 * drv.line_dev_m:.3f} mm",
        "the simulated arm in landscaped", f"{1000 * sim.line_dev_m:.3f} mm",
        fmt_ratio(drv.line_dev_m / sim.line_dev_m) if sim.line_dev_m > 0 else "-",
        f"FK of the measured joints; the set-point's own: {1000 * drv.line_cmd_dev_m:.3f} mm (drives run), "
        f"{1000 * sim.line_cmd_dev_m:.3f} mm (sim run); at rest after completion the tip is "
        f"{1000 * drv.end_err_m:.3f} / {1000 * sim.end_err_m:.3f} mm from the line's end (drives / sim)"))
    sec.details.append(
        f"`bench/b_drives.py`: two compositions run the same session through the host library: lock, activate, "
        f"a joint move HOME {HOME} -> {JOINT_TARGET} at 100 % speed, back to HOME, then a straight line of "
        f"{LINE_OFFSET_M} m in the base frame at 50 % speed. One is landscaped `--hal sim` (the ODE arm in its "
        f"process); the other is landscaped `arm = cia402` behind ls-simdrives on an SLCAN pty (the same ODE "
        f"arm behind six CiA 402 nodes, stepped by each SYNC, 4 ms drive cycle, velocity feed-forward 0x60B1 on). "
        f"Telemetry at {TELEMETRY_HZ} Hz: each snapshot's JOINTS_* (measured) and JOINTS_CMD_* (the set-point "
        f"of the same control cycle) decoded with `landscape.telemetry`; {drv.samples} snapshots behind the "
        f"drives, {sim.samples} on the sim arm. The tip is the flange by FK of the measured joints "
        "(`landscape.urdf.ArmChain`), its distance taken from the segment between the FK of the joints at rest "
        "before and at completion. Behind drives q lags q_cmd by the drive cycles the set-point and the feedback "
        "travel (docs/architecture.md \"Drives\", Timing), so the joint error is mostly speed x lag; along a line "
        "all joints lag alike in time, and the tip leaves the line only by the path's curvature in joint space "
        "over that lag.")
    sec.commands.append("build-bench/bin/landscaped --hal sim --link slcan:pty:/tmp/ls0 --telemetry-hz 200")
    sec.commands.append("build-bench/bin/ls-simdrives --link slcan:pty:/tmp/drives0 & build-bench/bin/landscaped "
                        "--config drives.conf --link slcan:pty:/tmp/ls0 --telemetry-hz 200")
    return sec
