"""The adversarial probe: hostile input against a running landscaped, in one run.

Three kinds of input, each judged by the same invariants (docs/reliability.md
section 8, "The probe"):

- SLCAN garbage: lines no adapter would send, written raw on the pty between
  a supervisor's requests;
- absurd requests: every schema command with every field set to values that
  pass the wire format but make no sense (NaN, infinities, subnormals, 1e308,
  integer extremes, enum numbers the schema does not have, empty, long and
  multi-byte strings, arrays of the wrong length), sent by the owner at rest,
  by the owner while a move runs, and by a supervisor that is not the owner;
- bad configurations: every key of the shipped landscaped.conf set to values
  of the wrong kind, given to `landscaped --config FILE --check`.

Invariants: landscaped never dies; every request gets an answer (no
time-out) that decodes; a refusal is a negative code with a message; after
every case the device answers a state query, and after the whole run a valid
move still works; its resident memory grows by less than RSS_GROWTH_LIMIT_KB
after the warm-up; a bad configuration exits 2 with one line naming the
file, the key and what is expected, never a crash.

    .venv/bin/python tests/probe/probe.py [--build build] [--quick] [--markdown]

Exit 0 when every invariant held, 1 when one did not (each breach is printed),
2 on a usage error. --quick takes a subset of each kind (CI's smoke run).
"""
from __future__ import annotations

import argparse
import math
import os
import signal
import subprocess
import sys
import tempfile
import time
from collections import Counter
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "host_tools" / "src"))

import can  # noqa: E402
from google.protobuf.descriptor import FieldDescriptor  # noqa: E402

from landscape import BusSpec, Supervisor  # noqa: E402
from landscape._generated import landscape_pb2 as pb  # noqa: E402
from landscape.bus import open_bus, release_bus  # noqa: E402
from landscape.errors import LandscapeError  # noqa: E402
from landscape.registry import COMMANDS, Command, build_request, is_repeated  # noqa: E402

CONF = ROOT / "firmware" / "app" / "deploy" / "landscaped.conf"
RSS_GROWTH_LIMIT_KB = 1024
ANSWER_TIMEOUT_S = 3.0
#: The owner's address; the outsider (not the owner) takes the next one.
OWNER, OUTSIDER = 0xF1, 0xF2

FLOATS = [math.nan, math.inf, -math.inf, 1e308, -1e308, 5e-324, -0.0, 1e-300, 1e9]
INTS = [-1, -(2**31), 2**31 - 1, 0]
UINTS = [2**32 - 1, 2**31, 0]
STRINGS = ["", " ", "x" * 63, "\u00e9" * 31 + "x", "a\x00b", "\U0001f916" * 15, "../../etc/passwd", "%s%n%x"]
ENUM_NUMBERS = [99, -1, 2**31 - 1]

#: SLCAN lines no adapter sends (the 13 kinds of the first probe), and what each is.
SLCAN_GARBAGE: list[tuple[str, bytes]] = [
    ("empty frame line", b"T\r"),
    ("short standard frame", b"t12\r"),
    ("DLC 9", b"T18DA10F19" + b"00" * 9 + b"\r"),
    ("id not hex", b"TXYZ\r"),
    ("binary bytes", b"\x00\xff\xfe\x80\r"),
    ("unknown command letter", b"Z9\r"),
    ("bit rate change", b"S9\r"),
    ("a 600-byte line", b"x" * 600 + b"\r"),
    ("data not hex", b"t1238GG\r"),
    ("remote frames", b"r7FF\rR1FFFFFFF0\r"),
    ("no line end, then a line", b"T18DA10F1" + b"8" + b"11" * 4 + b"T18DA10F180011223344556677\r"),
    ("a run of line ends", b"\r" * 200),
    ("close and open", b"C\rO\r"),
]


VERBOSE = False


def say(text: str) -> None:
    if VERBOSE:
        print(text, flush=True)


@dataclass
class Tally:
    """What one kind of input got."""

    cases: int = 0
    codes: Counter[str] = field(default_factory=Counter)
    breaches: list[str] = field(default_factory=list)
    worst_answer_s: float = 0.0
    rss_growth_kb: int = 0
    accepted: list[str] = field(default_factory=list)  # bad configurations taken as valid

    def breach(self, what: str) -> None:
        self.breaches.append(what)
        print(f"BREACH: {what}", flush=True)


def rss_kb(pid: int) -> int:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1])
    raise RuntimeError(f"no VmRSS for pid {pid}")


@contextmanager
def controller(build: Path, tmp: Path) -> Iterator[subprocess.Popen[bytes]]:
    pty = tmp / "ls0"
    log = tmp / "landscaped.log"
    exe = build / "bin" / "landscaped"
    if not exe.exists():
        raise SystemExit(f"probe: {exe} is missing: build first (bash .ci/build {build})")
    with open(log, "wb") as err:
        proc = subprocess.Popen([str(exe), "--hal", "sim", "--link", f"slcan:pty:{pty}"],
                                stdout=subprocess.DEVNULL, stderr=err)
    deadline = time.monotonic() + 10
    while not pty.exists():
        if proc.poll() is not None or time.monotonic() > deadline:
            proc.kill()
            raise SystemExit(f"probe: landscaped did not start: {log.read_text(errors='replace')[-2000:]}")
        time.sleep(0.02)
    try:
        yield proc
    finally:
        if proc.poll() is None:
            proc.send_signal(signal.SIGTERM)
            try:
                proc.wait(timeout=15)
            except subprocess.TimeoutExpired:
                proc.kill()
        text = log.read_text(errors="replace")
        if "Sanitizer" in text or "runtime error" in text:
            print(f"BREACH: sanitizer report in landscaped's log:\n{text[-4000:]}", flush=True)
            raise SystemExit(1)
        if proc.returncode not in (0, None):
            print(f"BREACH: landscaped exited with {proc.returncode}:\n{text[-2000:]}", flush=True)
            raise SystemExit(1)


@contextmanager
def link(pty: Path) -> Iterator[tuple[can.BusABC, can.Notifier]]:
    """One python-can bus on the pty for every supervisor of the probe (a second bus on the
    same pty would take the line from the first) and the raw garbage."""
    bus = open_bus(BusSpec("slcan", str(pty)))
    notifier = can.Notifier(bus, [], timeout=0.05)
    try:
        yield bus, notifier
    finally:
        notifier.stop()
        bus.shutdown()
        release_bus(bus)


def open_supervisor(bus: can.BusABC, notifier: can.Notifier, addr: int) -> Supervisor:
    sup = Supervisor(bus, notifier=notifier, source_address=addr, client_name=f"probe-{addr:02x}",
                     timeout_s=ANSWER_TIMEOUT_S, retries=1)
    sup.open()
    sup.description = None  # the library's own size checks must not keep a case from the device
    return sup


#: A valid request of each command with fields: the probe makes one field absurd at a time, so
#: that the device's check of that field is reached (a request wrong everywhere is refused at
#: its first field). Commands missing here have no fields.
VALID: dict[str, dict[str, Any]] = {
    "set_speed": {"speed": 50.0, "attribute": pb.PERCENT_SPEED},
    "set_acceleration": {"accel": 50.0, "attribute": pb.PERCENT_ACCEL},
    "set_tool_offset": {"offset": [0.0] * 6},
    "set_world_cartesian_frame": {"frame": [0.0] * 6},
    "set_units": {"linear": pb.METERS, "angular": pb.RADIANS},
    "move_relative": {"point_name": "p", "frame": pb.JOINT_FRAME, "values": [0.01, 0, 0, 0, 0, 0],
                      "speed_pct": 50.0},
    "move_absolute": {"point_name": "p", "frame": pb.JOINT_FRAME, "values": [0.0] * 6, "speed_pct": 50.0},
    "move_arc": {"point_name": "p", "frame": pb.BASE_CARTESIAN_FRAME, "offset_type": pb.RELATIVE_DATA,
                 "arc_value": [0.02, 0.02, 0, 0, 0, 0], "goal_value": [0.04, 0, 0, 0, 0, 0]},
    "path_load": {"path_name": "probe", "frame": pb.JOINT_FRAME, "motion_type": pb.JOINT_MOTION,
                  "offset_type": pb.ABSOLUTE_DATA, "number_of_points": 1,
                  "tags": [{"joints": [0.0] * 6, "tag_name": "t"}]},
    "path_clear_path": {"path_name": "probe"},
    "path_move": {"path_name": "probe", "number_of_cycles": 1},
    "get_sensor_reading": {"sensor_type": "force_sensor"},
    "move_react": {"sensor_type": "force_sensor", "motion_offsets": [0, 0, -0.01, 0, 0, 0],
                   "motion_speed_pct": 10.0, "compliance_speed_pct": 10.0, "thresholds": [0.0, 0.0, 10.0]},
    "comply": {"sensor_type": "force_sensor", "thresholds": [0.0, 0.0, 10.0], "max_timeout_s": 0.5,
               "max_travel": [0.05, 0, 0, 0, 0, 0.05]},
    "manual_control": {"type": "off"},
    "get_tool": {"tool_id": "gripper"},
    "put_tool": {"tool_id": "gripper"},
    "activate_tool": {"tool_id": "gripper", "bit_field": 1},
    "deactivate_tool": {"tool_id": "gripper", "bit_field": 1},
    "set_digital_io": {"type": "digital", "unit_id": 0, "bits_on": 0x00010000},
    "get_digital_io": {"type": "digital", "unit_id": 0},
    "signal_digital_io": {"type": "digital", "unit_id": 0, "bit_string": 0x0100, "callback_type": pb.CB_EVENT},
    "send_command": {"input": "status"},
}

#: Path points that decode but make no sense.
ABSURD_TAGS: list[list[dict[str, Any]]] = [
    [],
    [{}],
    [{"joints": [math.nan] * 6}],
    [{"joints": [0.0] * 25}],
    [{"joints": [0.0] * 6, "pose": [1e308] * 6}],
    [{"joints": [0.0] * 6, "time_delay_s": 1e308, "transition_speed_pct": -1.0, "accel_pct": math.inf}],
    [{"joints": [0.0] * 6, "tag_index": -(2**31), "aux_commands": ["%n%s" * 30, "", "\u00e9" * 40]}],
]


# bytes fields (a challenge's nonce): empty, one short, far over the schema's size, all ones
BYTES: list[bytes] = [b"", b"\x00" * 15, b"\xa5" * 300, b"\xff" * 16]

def absurd_values(fd: FieldDescriptor) -> list[Any]:
    """Values of `fd`'s wire type that make no sense for it."""
    if fd.type == FieldDescriptor.TYPE_MESSAGE:
        return list(ABSURD_TAGS)
    if fd.type in (FieldDescriptor.TYPE_DOUBLE, FieldDescriptor.TYPE_FLOAT):
        one: list[Any] = FLOATS
    elif fd.type == FieldDescriptor.TYPE_ENUM:
        one = ENUM_NUMBERS
    elif fd.type == FieldDescriptor.TYPE_STRING:
        one = STRINGS
    elif fd.type == FieldDescriptor.TYPE_BYTES:
        one = BYTES
    elif fd.type == FieldDescriptor.TYPE_BOOL:
        one = [True]
    elif fd.type in (FieldDescriptor.TYPE_UINT32, FieldDescriptor.TYPE_UINT64):
        one = UINTS
    else:
        one = INTS
    if not is_repeated(fd):
        return list(one)
    return [[], [one[0]], [one[0]] * 6, [one[0]] * 25, [one[-1]] * 7, [one[1]] * 3]


def raw_request(cmd: Command, fields: dict[str, Any]) -> pb.Request:
    """The command's valid request (VALID) with `fields` set as they are (no parsing, no
    range check): what a client written from the .proto alone could send."""
    req = build_request(cmd, 0, **VALID.get(cmd.field, {}))
    body = getattr(req, cmd.field)
    body.SetInParent()
    for name, value in fields.items():
        fd = cmd.request_type.fields_by_name[name]
        target = getattr(body, name)
        if fd.type == FieldDescriptor.TYPE_MESSAGE and is_repeated(fd):
            del target[:]
            for point in value:
                target.add().CopyFrom(pb.TagPoint(**point))
        elif is_repeated(fd):
            del target[:]
            target.extend(value)
        else:
            setattr(body, name, value)
    return req


def send_raw(sup: Supervisor, cmd: Command, req: pb.Request) -> Any:
    """Send a prebuilt request through the session (its seq, its retransmissions)."""
    with sup._req_lock:  # noqa: SLF001 (the probe sends what the library would refuse to build)
        sup._seq += 1  # noqa: SLF001
        req.seq = sup._seq  # noqa: SLF001
        resp = sup._transact(cmd, req, ANSWER_TIMEOUT_S)  # noqa: SLF001
    return sup._retval(cmd, resp)  # noqa: SLF001


def cases(quick: bool) -> Iterator[tuple[Command, dict[str, Any]]]:
    """Every command with one absurd field at a time (the others valid); a command without
    fields as it is."""
    for cmd in COMMANDS.values():
        if cmd.field in ("connect", "disconnect"):
            continue
        if not cmd.fields():
            yield cmd, {}
        for fd in cmd.fields():
            values = absurd_values(fd)
            for v in values[:2] if quick else values:
                yield cmd, {fd.name: v}


def alive(sup: Supervisor, proc: subprocess.Popen[bytes], tally: Tally, what: str) -> None:
    if proc.poll() is not None:
        tally.breach(f"landscaped died after {what} (exit {proc.returncode})")
        raise SystemExit(1)
    try:
        sup.request("get_motion_control_state", check=False)
    except LandscapeError as exc:
        tally.breach(f"no answer to a state query after {what}: {exc}")


def settle(sup: Supervisor) -> None:
    """End whatever a case started, so the next one starts from the same state."""
    state = sup.request("get_motion_control_state", check=False).result.get("state")
    if state == "MOVING":
        sup.request("stop_motion", check=False)
        deadline = time.monotonic() + 15
        while time.monotonic() < deadline and state == "MOVING":
            time.sleep(0.05)
            state = sup.request("get_motion_control_state", check=False).result.get("state")
    if state == "PAUSED":
        sup.request("abort_motion", check=False)
        deadline = time.monotonic() + 15
        while time.monotonic() < deadline:
            if sup.request("get_motion_control_state", check=False).result.get("state") == "RESTING":
                break
            time.sleep(0.05)


def reset_owner(sup: Supervisor) -> None:
    for name, kw in (("set_units", {"linear": pb.METERS, "angular": pb.RADIANS}),
                     ("set_tool_offset", {"offset": [0.0] * 6}),
                     ("set_world_cartesian_frame", {"frame": [0.0] * 6}),
                     ("set_speed", {"speed": 100.0, "attribute": pb.PERCENT_SPEED}),
                     ("set_acceleration", {"accel": 100.0, "attribute": pb.PERCENT_ACCEL})):
        sup.request(name, check=False, **kw)
    if sup.request("get_motion_control_state", check=False).result.get("state") in ("LOCKED", "UNLOCKED"):
        sup.request("lock", check=False)
        sup.request("activate", check=False)


def run_requests(pty: Path, proc: subprocess.Popen[bytes], quick: bool, where: str,
                 prepare: Callable[[Supervisor, Supervisor], None]) -> Tally:
    tally = Tally()
    with link(pty) as (bus, notifier):
        owner = open_supervisor(bus, notifier, OWNER)
        outsider = open_supervisor(bus, notifier, OUTSIDER)
        try:
            run_cases(owner, outsider, proc, quick, where, prepare, tally)
        except LandscapeError as exc:  # the session itself failed: say so, go on with the next kind
            tally.breach(f"{where}: the probe's session failed: {type(exc).__name__}: {exc}")
        finally:
            outsider.close()
            owner.close()
    return tally


def run_cases(owner: Supervisor, outsider: Supervisor, proc: subprocess.Popen[bytes], quick: bool, where: str,
              prepare: Callable[[Supervisor, Supervisor], None], tally: Tally) -> None:
    owner.request("lock", check=False)
    owner.request("activate", check=False)
    rss0 = 0
    for i, (cmd, fields) in enumerate(cases(quick)):
        sender = outsider if where == "not the owner" else owner
        prepare(owner, outsider)
        req = raw_request(cmd, fields)
        t0 = time.monotonic()
        try:
            rv = send_raw(sender, cmd, req)
        except LandscapeError as exc:
            tally.breach(f"{cmd.name} {fields!r} ({where}): {type(exc).__name__}: {exc}")
            continue
        finally:
            tally.cases += 1
        tally.worst_answer_s = max(tally.worst_answer_s, time.monotonic() - t0)
        tally.codes[rv.ret_name] += 1
        say(f"{where}: {cmd.name} {fields!r}: {rv.ret_name} {rv.ret_msg!r} ({time.monotonic() - t0:.3f} s)")
        if rv.ret_code < 0 and not rv.ret_msg:
            tally.breach(f"{cmd.name} {fields!r} ({where}): {rv.ret_name} without a message")
        if cmd.field in ("lock", "release", "activate", "deactivate", "disconnect") or rv.started:
            settle(owner)
            reset_owner(owner)
        if cmd.field.startswith("set_"):
            reset_owner(owner)
        if i == 20:
            rss0 = rss_kb(proc.pid)
        if i % 25 == 0:
            alive(owner, proc, tally, f"{cmd.name} {fields!r}")
    settle(owner)
    reset_owner(owner)
    tally.rss_growth_kb = rss_kb(proc.pid) - rss0
    rv = owner.request("move_relative", check=False, point_name="probe", values=[0.05, 0, 0, 0, 0, 0],
                       frame=pb.JOINT_FRAME)
    if not rv.started:
        tally.breach(f"after the absurd requests ({where}) a valid move was refused: {rv.ret_name} {rv.ret_msg}")
    else:
        owner.wait_complete(rv, timeout_s=20)


def start_far_move(owner: Supervisor, _outsider: Supervisor) -> None:
    state = owner.request("get_motion_control_state", check=False).result.get("state")
    if state != "MOVING":
        owner.request("set_speed", check=False, speed=5.0, attribute=pb.PERCENT_SPEED)
        owner.request("move_absolute", check=False, point_name="far", values=[2.0, 0, 0, 0, 0, 0],
                      frame=pb.JOINT_FRAME)


def run_garbage(pty: Path, proc: subprocess.Popen[bytes], quick: bool) -> Tally:
    tally = Tally()
    with link(pty) as (bus, notifier):
        sup = open_supervisor(bus, notifier, OWNER)
        try:
            garbage(bus, sup, proc, quick, tally)
        except LandscapeError as exc:
            tally.breach(f"SLCAN garbage: the probe's session failed: {type(exc).__name__}: {exc}")
        finally:
            sup.close()
    return tally


def garbage(bus: can.BusABC, sup: Supervisor, proc: subprocess.Popen[bytes], quick: bool, tally: Tally) -> None:
    port = bus.serialPortOrig  # type: ignore[attr-defined]  # python-can slcan's serial port
    alive(sup, proc, tally, "the start")
    rss0 = rss_kb(proc.pid)
    rounds = 1 if quick else 20
    for _ in range(rounds):
        for name, line in SLCAN_GARBAGE:
            port.write(line)
            port.write(b"O\r")  # a close among the garbage must not keep the link shut
            port.flush()
            tally.cases += 1
            t0 = time.monotonic()
            alive(sup, proc, tally, f"SLCAN garbage: {name}")
            tally.worst_answer_s = max(tally.worst_answer_s, time.monotonic() - t0)
            tally.codes["answered after"] += 1
    tally.rss_growth_kb = rss_kb(proc.pid) - rss0


def config_cases(quick: bool) -> Iterator[tuple[str, str]]:
    """(description, configuration text): the shipped file with one key given a bad value,
    and broken files."""
    lines = CONF.read_text().splitlines()
    section = ""
    keyed: list[tuple[int, str, str]] = []
    for i, line in enumerate(lines):
        s = line.strip()
        if s.startswith("[") and s.endswith("]"):
            section = s[1:-1]
        elif s and not s.startswith("#") and "=" in s:
            keyed.append((i, section, s.split("=", 1)[0].strip()))
    bad = ["", "-1", "1e308", "nan", "abc", "9" * 400, "0x", "\u00e9\u00e9", "1 2"]
    for i, sec, key in keyed:
        for v in bad[:3] if quick else bad:
            text = "\n".join(lines[:i] + [f"{key} = {v}"] + lines[i + 1:]) + "\n"
            yield f"[{sec}] {key} = {v!r}", text
    yield "a key outside any section", "name = x\n"
    yield "an unterminated section", "[device\nname = x\n"
    yield "an unknown section", "[nope]\nx = 1\n"
    yield "a 100 kB line", "[device]\nname = " + "x" * 100_000 + "\n"
    yield "bytes that are not UTF-8", "[device]\nname = \udcff\n"


def run_configs(build: Path, tmp: Path, quick: bool) -> Tally:
    tally = Tally()
    exe = build / "bin" / "landscaped"
    for i, (what, text) in enumerate(config_cases(quick)):
        conf = tmp / f"bad{i}.conf"
        conf.write_bytes(text.encode("utf-8", "surrogateescape"))
        t0 = time.monotonic()
        try:
            r = subprocess.run([str(exe), "--config", str(conf), "--check"], capture_output=True, text=True,
                               errors="replace", timeout=30)
        except subprocess.TimeoutExpired:
            tally.breach(f"config {what}: --check did not end within 30 s")
            continue
        tally.cases += 1
        tally.worst_answer_s = max(tally.worst_answer_s, time.monotonic() - t0)
        first = r.stdout.splitlines()[0] if r.stdout else ""
        if r.returncode < 0 or r.returncode > 2:
            tally.breach(f"config {what}: exit {r.returncode}: {r.stderr[-500:]}")
        elif r.returncode == 2:
            tally.codes["refused (exit 2)"] += 1
            if not first.startswith(f"FAIL  configuration: {conf}:"):
                tally.breach(f"config {what}: exit 2 without a line naming the file: {first!r}")
        elif first.startswith("PASS  configuration"):
            tally.codes["accepted"] += 1
            tally.accepted.append(what)
        else:
            tally.breach(f"config {what}: exit {r.returncode} without a configuration verdict: {first!r}")
        say(f"config {what}: exit {r.returncode}: {first}")
        if "Sanitizer" in r.stderr or "runtime error" in r.stderr:
            tally.breach(f"config {what}: sanitizer report: {r.stderr[-2000:]}")
    return tally


def report(results: dict[str, Tally], markdown: bool, build: Path) -> None:
    load = os.getloadavg()[0]
    if markdown:
        print(f"\nProbe of `{build}` ({time.strftime('%Y-%m-%d')}, load average {load:.1f}):\n")
        print("| input | cases | answers | worst answer | RSS growth | breaches |")
        print("|---|---:|---|---:|---:|---:|")
    for name, t in results.items():
        codes = ", ".join(f"{k} {v}" for k, v in t.codes.most_common())
        if markdown:
            print(f"| {name} | {t.cases} | {codes} | {t.worst_answer_s * 1000:.0f} ms | {t.rss_growth_kb} kB "
                  f"| {len(t.breaches)} |")
        else:
            print(f"{name}: {t.cases} cases; {codes}; worst answer {t.worst_answer_s * 1000:.0f} ms; "
                  f"RSS growth {t.rss_growth_kb} kB; breaches {len(t.breaches)}")
        if t.accepted:
            print(f"  taken as valid: {'; '.join(t.accepted)}")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0] if __doc__ else None)
    ap.add_argument("--build", default=os.environ.get("LS_BUILD_DIR", str(ROOT / "build")),
                    help="the build directory whose bin/landscaped is probed (default: build, or $LS_BUILD_DIR)")
    ap.add_argument("--quick", action="store_true", help="a subset of each kind (CI's smoke run)")
    ap.add_argument("--markdown", action="store_true", help="print the summary as a docs table")
    ap.add_argument("--verbose", "-v", action="store_true", help="print every case and its answer")
    ap.add_argument("--keep", metavar="DIR", help="keep landscaped's log and the configurations in DIR")
    args = ap.parse_args()
    global VERBOSE
    VERBOSE = args.verbose
    build = Path(args.build).resolve()
    results: dict[str, Tally] = {}
    with tempfile.TemporaryDirectory(prefix="ls-probe-") as d:
        tmp = Path(args.keep) if args.keep else Path(d)
        tmp.mkdir(parents=True, exist_ok=True)
        with controller(build, tmp) as proc:
            pty = tmp / "ls0"
            results["SLCAN garbage (13 kinds)"] = run_garbage(pty, proc, args.quick)
            results["absurd requests, owner at rest"] = run_requests(
                pty, proc, args.quick, "owner at rest", lambda o, x: None)
            results["absurd requests, owner while a move runs"] = run_requests(
                pty, proc, args.quick, "owner while moving", start_far_move)
            results["absurd requests, not the owner"] = run_requests(
                pty, proc, args.quick, "not the owner", lambda o, x: None)
        results["bad configurations (--check)"] = run_configs(build, tmp, args.quick)
    report(results, args.markdown, build)
    breaches = sum(len(t.breaches) for t in results.values())
    for name, t in results.items():
        if t.rss_growth_kb > RSS_GROWTH_LIMIT_KB:
            print(f"BREACH: {name}: RSS grew {t.rss_growth_kb} kB (limit {RSS_GROWTH_LIMIT_KB} kB)")
            breaches += 1
    print(f"probe: {'every invariant held' if breaches == 0 else f'{breaches} breaches'}")
    return 0 if breaches == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
