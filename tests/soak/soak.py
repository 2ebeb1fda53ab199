#!/usr/bin/env python3
"""Soak: a bounded run of random valid and invalid commands from two supervisors
(each on its own link of one bus) against landscaped with faults injected on
every link (--link-faults). Exits non-zero when:

- landscaped crashed or stopped answering,
- its resident set grew by more than --rss-bound-kib after the warm-up
  (the firmware allocates nothing after init),
- a supervisor lost its session (an ownerLost alarm or a drop in
  sendCommand status) although no bus-off was injected,
- a command failed in a way the library does not promise (anything other than
  a device return code or ControllerTimeoutError).

Prints its figures: commands sent/ok/errors by code, time-outs,
retransmissions, RSS at start/after warm-up/end, faults injected (from
landscaped's shutdown log).

    python tests/soak/soak.py --short            # 60 s (the test suite's run)
    python tests/soak/soak.py --duration 600     # the documented 10-minute run
    LS_BUILD_DIR=build-asan python tests/soak/soak.py --short
"""
from __future__ import annotations

import argparse
import collections
import json
import logging
import os
import random
import re
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import can

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "host_tools" / "src"))

from landscape import errors  # noqa: E402
from landscape._generated import landscape_pb2 as pb  # noqa: E402
from landscape.supervisor import RetVal, Supervisor  # noqa: E402

DEFAULT_FAULTS = "drop=0.02,dup=0.002,corrupt=0.001,reorder=0.005,delay=0.01:3ms,seed=1"


@dataclass
class Figures:
    sent: int = 0
    ok: int = 0
    timeouts: int = 0
    by_code: collections.Counter[str] = field(default_factory=collections.Counter)
    unexpected: list[str] = field(default_factory=list)
    # Answers a corrupted frame made undecodable (ProtocolError "does not decode"): with
    # corrupt > 0 on a link without a checksum (SLCAN, ISO-TP and the envelope carry none,
    # docs/reliability.md section 4) the host's clear refusal is the right outcome, counted
    # here and checked against the corruptions injected; without corruption it is unexpected.
    undecodable: int = 0
    corrupting: bool = False
    owner_lost: int = 0
    alarms: collections.Counter[str] = field(default_factory=collections.Counter)
    lock = threading.Lock()

    def record(self, rv: RetVal | None, exc: BaseException | None) -> None:
        with self.lock:
            self.sent += 1
            if rv is not None:
                self.by_code[rv.ret_name] += 1
                if rv.ret_code >= 0:
                    self.ok += 1
            elif isinstance(exc, errors.ControllerTimeoutError):
                self.timeouts += 1
            elif self.from_corruption(exc):
                self.undecodable += 1
            else:
                self.unexpected.append(repr(exc))


    def from_corruption(self, exc: BaseException | None) -> bool:
        return self.corrupting and isinstance(exc, errors.ProtocolError) and "does not decode" in str(exc)


def corrupts(faults: str) -> bool:
    """Whether a --link-faults spec corrupts frames (a corrupt rate above 0)."""
    return any(float(rate) > 0 for rate in re.findall(r"corrupt=([0-9.eE+-]+)", faults))


class RetransmitCounter(logging.Handler):
    def __init__(self) -> None:
        super().__init__(logging.INFO)
        self.count = 0

    def emit(self, record: logging.LogRecord) -> None:
        if "retransmitting" in record.getMessage():
            self.count += 1


def rss_kib(pid: int) -> int:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1])
    raise RuntimeError("no VmRSS")


def _joints(rng: random.Random, scale: float) -> list[float]:
    return [rng.uniform(-scale, scale) for _ in range(6)]


def command_mix(rng: random.Random) -> list[tuple[str, int, Callable[[Supervisor], RetVal]]]:
    """(name, weight, call): valid commands first, then invalid ones (bad values,
    wrong shapes, wrong states are left to chance)."""
    return [
        ("getMotionControlState", 8, lambda s: s.get_motion_control_state(check=False)),
        ("status", 2, lambda s: s.send_command("status", check=False)),
        ("lock", 4, lambda s: s.lock(check=False)),
        ("release", 3, lambda s: s.release(check=False)),
        ("activate", 3, lambda s: s.activate(check=False)),
        ("deactivate", 2, lambda s: s.deactivate(check=False)),
        ("setSpeed", 3, lambda s: s.set_speed(rng.uniform(1, 100), check=False)),
        ("getVelocities", 2, lambda s: s.get_velocities(check=False)),
        ("getRobotPosition", 3, lambda s: s.get_robot_position(check=False)),
        ("moveRelative", 3, lambda s: s.move_relative("soak", _joints(rng, 0.05), check=False)),
        ("stopMotion", 1, lambda s: s.stop_motion(check=False)),
        ("resumeMotion", 1, lambda s: s.resume_motion(check=False)),
        ("abortMotion", 1, lambda s: s.abort_motion(check=False)),
        ("pathLoad", 2, lambda s: s.path_load("soak", [{"joints": _joints(rng, 0.1)} for _ in range(3)],
                                              check=False)),
        ("pathClearPath", 1, lambda s: s.path_clear_path("soak", check=False)),
        ("getDigitalIO", 2, lambda s: s.get_digital_io("sim", 0, check=False)),
        ("setDigitalIO", 1, lambda s: s.set_digital_io("sim", 0, bits_on=1 << 16, bits_off=1 << 17, check=False)),
        # invalid
        ("setSpeed(-5)", 1, lambda s: s.set_speed(-5.0, check=False)),
        ("setSpeed(1e9)", 1, lambda s: s.set_speed(1e9, check=False)),
        ("moveAbsolute(3 values)", 1, lambda s: s.move_absolute("bad", [0.0] * 3, check=False)),
        ("moveRelative(huge)", 1, lambda s: s.move_relative("far", [50.0] * 6, check=False)),
        ("getDigitalIO(unit 99)", 1, lambda s: s.get_digital_io("sim", 99, check=False)),
        ("pathLoad(count mismatch)", 1, lambda s: s.path_load("soak", [{"joints": [0.0] * 6}], number_of_points=5,
                                                               check=False)),
        ("pathMove(unknown path)", 1, lambda s: s.path_move("nope", number_of_cycles=1, check=False)),
        ("getSensorReading(bogus)", 1, lambda s: s.get_sensor_reading("bogus", check=False)),
        ("sendCommand(junk)", 1, lambda s: s.send_command("no-such-vendor-command", check=False)),
    ]


def worker(sup: Supervisor, seed: int, stop: threading.Event, fig: Figures) -> None:
    rng = random.Random(seed)
    mix = command_mix(rng)
    names = [m for m in mix]
    weights = [m[1] for m in mix]
    while not stop.is_set():
        _, _, call = rng.choices(names, weights)[0]
        try:
            fig.record(call(sup), None)
        except errors.ControllerTimeoutError as exc:
            fig.record(None, exc)
        except errors.LandscapeError as exc:  # e.g. an argument the library refuses: still a clear error
            fig.record(None, exc)
            if not isinstance(exc, errors.ArgumentError) and not fig.from_corruption(exc):
                stop.set()
        time.sleep(rng.uniform(0.0, 0.02))


def start_landscaped(build: Path, tmp: Path, faults: str) -> tuple[subprocess.Popen[bytes], list[str]]:
    exe = build / "bin" / "landscaped"
    if not exe.exists():
        raise SystemExit(f"{exe} is missing: build first (bash .ci/build) or set LS_BUILD_DIR")
    ptys = [str(tmp / "ls0"), str(tmp / "ls1")]
    args = [str(exe), "--hal", "sim", "--link", f"slcan:pty:{ptys[0]}", "--link", f"slcan:pty:{ptys[1]}"]
    if faults:
        args += ["--link-faults", faults]
    proc = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 15
    while not all(Path(p).exists() for p in ptys):
        if proc.poll() is not None:
            err = proc.stderr.read().decode() if proc.stderr else ""
            raise SystemExit(f"landscaped exited with {proc.returncode}: {err}")
        if time.monotonic() > deadline:
            proc.kill()
            raise SystemExit("landscaped did not create its pty links within 15 s")
        time.sleep(0.02)
    return proc, ptys


def run(duration_s: float, faults: str, rss_bound_kib: int, seed: int, build: Path) -> dict[str, Any]:
    fig = Figures(corrupting=corrupts(faults))
    rt = RetransmitCounter()
    lg = logging.getLogger("landscape")
    lg.setLevel(logging.INFO)
    lg.addHandler(rt)
    lg.propagate = False
    logging.getLogger("isotp").setLevel(logging.ERROR)  # expected under faults; counted as retransmissions
    induced = "busoff" in faults
    failures: list[str] = []
    with tempfile.TemporaryDirectory(prefix="ls-soak-") as td:
        proc, ptys = start_landscaped(build, Path(td), faults)
        buses = [can.Bus(interface="slcan", channel=p, bitrate=1000000, sleep_after_open=0) for p in ptys]
        sups = [Supervisor(b, source_address=0xF1 + i, client_name=f"soak-{i}", retries=5, timeout_s=0.4,
                           heartbeat_period_ms=100) for i, b in enumerate(buses)]
        rss: list[tuple[float, int]] = []
        t_start = time.monotonic()
        stop = threading.Event()
        try:
            for s in sups:
                for _ in range(5):
                    try:
                        s.open()
                        break
                    except errors.ControllerTimeoutError:
                        continue
                else:
                    raise SystemExit(f"supervisor 0x{s.source_address:02X} could not connect through the faults")

                def on_notice(n: pb.Notice) -> None:
                    with fig.lock:
                        if n.kind in (pb.ALARM, pb.ALARM_RSVP):
                            fig.alarms[n.event_id] += 1
                        if n.event_id == "ownerLost":
                            fig.owner_lost += 1
                s.on_notice(on_notice)
            threads = [threading.Thread(target=worker, args=(s, seed + i, stop, fig), daemon=True)
                       for i, s in enumerate(sups)]
            for t in threads:
                t.start()
            warmup_s = min(20.0, duration_s / 4)
            while time.monotonic() - t_start < duration_s and not stop.is_set():
                if proc.poll() is not None:
                    failures.append(f"landscaped exited with {proc.returncode} during the run")
                    break
                rss.append((time.monotonic() - t_start, rss_kib(proc.pid)))
                time.sleep(1.0)
            stop.set()
            for t in threads:
                t.join(15)
            # still answering (through the faults: retries)
            alive = False
            for _ in range(5):
                try:
                    alive = sups[0].get_motion_control_state(check=False) is not None
                    break
                except errors.ControllerTimeoutError:
                    continue
            if not alive:
                failures.append("landscaped stopped answering")
            dropped = -1
            for _ in range(10):
                try:
                    text = sups[1].send_command("status").result["result"]
                    dropped = int(next(ln for ln in text.splitlines()
                                       if ln.startswith("sessions_dropped=")).split("=")[1])
                    break
                except errors.ControllerTimeoutError:
                    continue
        finally:
            stop.set()
            for s in sups:
                s.close()
            for b in buses:
                b.shutdown()
            if proc.poll() is None:
                proc.send_signal(signal.SIGTERM)
            try:
                rc = proc.wait(timeout=15)
            except subprocess.TimeoutExpired:
                proc.kill()
                rc = -9
                failures.append("landscaped did not stop within 15 s of SIGTERM")
            err = proc.stderr.read().decode() if proc.stderr else ""
    if rc != 0:
        failures.append(f"landscaped exit status {rc}")
    if "AddressSanitizer" in err or "runtime error:" in err:
        failures.append("sanitizer report in landscaped's stderr:\n" + err[-4000:])
    fault_lines = [ln.split(" faults: ", 1)[1] for ln in err.splitlines() if " faults: tx " in ln]
    injected: collections.Counter[str] = collections.Counter()
    for ln in fault_lines:
        side = ""
        for kv in ln.split():
            if kv in ("tx", "rx"):
                side = kv
            elif "=" in kv:
                k, v = kv.split("=")
                injected[f"{side}.{k}" if side and k != "busoff_windows" else k] += int(v)
    after_warmup = [r for t, r in rss if t >= warmup_s]
    rss_start = rss[0][1] if rss else 0
    rss_warm = after_warmup[0] if after_warmup else rss_start
    rss_end = rss[-1][1] if rss else 0
    rss_max = max((r for _, r in rss), default=0)
    if after_warmup and max(after_warmup) - rss_warm > rss_bound_kib:
        failures.append(f"RSS grew from {rss_warm} KiB to {max(after_warmup)} KiB after the warm-up "
                        f"(bound {rss_bound_kib} KiB)")
    if fig.unexpected:
        failures.append(f"{len(fig.unexpected)} unexpected exceptions, first: {fig.unexpected[0]}")
    corrupted = injected["tx.corrupt"] + injected["rx.corrupt"]
    if fig.undecodable > corrupted:
        failures.append(f"{fig.undecodable} undecodable answers but only {corrupted} corrupted frames injected")
    if not induced and (fig.owner_lost or dropped > 0):
        failures.append(f"sessions lost without an induced bus-off: ownerLost alarms {fig.owner_lost}, "
                        f"sessions_dropped {dropped}")
    if fig.sent == 0:
        failures.append("no command was sent")
    return {
        "duration_s": round(time.monotonic() - t_start, 1),
        "faults": faults,
        "commands_sent": fig.sent,
        "commands_ok": fig.ok,
        "timeouts": fig.timeouts,
        "undecodable_answers": fig.undecodable,
        "retransmissions": rt.count,
        "answers_by_code": dict(sorted(fig.by_code.items())),
        "alarms": dict(fig.alarms),
        "owner_lost": fig.owner_lost,
        "sessions_dropped": dropped,
        "rss_kib": {"start": rss_start, "after_warmup": rss_warm, "end": rss_end, "max": rss_max},
        "faults_injected": dict(sorted(injected.items())),
        "landscaped_exit": rc,
        "failures": failures,
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--duration", type=float, default=600.0, help="seconds (default 600)")
    ap.add_argument("--short", action="store_true", help="60 s, the test suite's run")
    ap.add_argument("--faults", default=DEFAULT_FAULTS, help=f"--link-faults SPEC (default {DEFAULT_FAULTS})")
    ap.add_argument("--rss-bound-kib", type=int, default=1024, help="allowed RSS growth after warm-up")
    ap.add_argument("--seed", type=int, default=1, help="seed of the command choice")
    ap.add_argument("--json", action="store_true", help="print the figures as one JSON object")
    a = ap.parse_args(argv)
    build = Path(os.environ.get("LS_BUILD_DIR", ROOT / "build"))
    if not build.is_absolute():
        build = ROOT / build
    res = run(60.0 if a.short else a.duration, a.faults, a.rss_bound_kib, a.seed, build)
    if a.json:
        print(json.dumps(res, indent=2))
    else:
        for k, v in res.items():
            if k != "failures":
                print(f"{k:18s} {v}")
    for f in res["failures"]:
        print(f"FAIL: {f}", file=sys.stderr)
    return 1 if res["failures"] else 0


if __name__ == "__main__":
    sys.exit(main())
