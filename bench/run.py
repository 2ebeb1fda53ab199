"""Run every benchmark and regenerate docs/performance.md.

    .venv/bin/python bench/run.py            # build (build-bench/, Release), run all, write the doc
    .venv/bin/python bench/run.py --quick    # every benchmark, fewer samples; the page goes to build-bench/
    .venv/bin/python bench/run.py --only 2,3 # some benchmarks only (the page goes to build-bench/)

A figure never fails: benchmarks print figures, they do not judge them. A
benchmark that cannot build or run fails the run: its table row says why, the
end of the output names it, and the exit status is 1. docs/performance.md is
rewritten only by a full run in which every benchmark ran.
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import re
import shutil
import subprocess
import sys
import time
import traceback
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import b_blend
import b_cmd
import b_cycle
import b_drives
import b_footprint
import b_heartbeat
import b_ik
import b_isotp
import b_jitter
import b_mac
import b_otg
import b_pathspeed
import b_traj
import b_wire

from common import BUILD, ROOT, BenchError, Row, Section

HERE = Path(__file__).resolve().parent
DOC = ROOT / "docs" / "performance.md"


@dataclass(frozen=True)
class Bench:
    number: int
    title: str
    run: Callable[[bool], Section]
    targets: tuple[str, ...]  # what it needs from build-bench (bench/CMakeLists.txt target names)


BENCHES = [
    Bench(1, "ISO-TP efficiency", b_isotp.bench_frames, ("bench_isotp_frames",)),
    Bench(2, "ISO-TP throughput and latency (pty)", b_isotp.bench_pty, ("bench_isotp_pty_echo",)),
    Bench(3, "Command round trip", b_cmd.bench_command, ("landscaped", "bench_frame_echo", "bench_isotp_pty_echo")),
    Bench(4, "Trajectories vs ruckig", b_traj.bench_traj, ("bench_traj",)),
    Bench(5, "Control cycle cost", b_cycle.bench_cycle, ("bench_cycle",)),
    Bench(6, "Bytes on the wire per path point", b_wire.bench_wire, ()),
    # The generated codecs, dispatch table and DBC code the cross build compiles; landscaped because the
    # image is its portable part (and must build with it).
    Bench(7, "Footprint (Cortex-M4F)", b_footprint.bench_footprint,
          ("landscaped", "ls_cmd_table_gen", "ls_proto", "ls_dbc")),
    Bench(8, "Real-time jitter", b_jitter.bench_jitter, ("bench_rt_jitter",)),
    Bench(9, "Blended paths", b_blend.bench_blend, ("bench_blend",)),
    Bench(10, "State-to-state trajectories vs ruckig", b_otg.bench_otg, ("bench_otg",)),
    Bench(11, "Heartbeat period", b_heartbeat.bench_heartbeat, ("landscaped",)),
    Bench(12, "Path speed vs toppra", b_pathspeed.bench_pathspeed, ("bench_pathspeed",)),
    Bench(13, "Inverse kinematics per IK class", b_ik.bench_ik, ("bench_ik",)),
    Bench(14, "Drive bus load per cycle", b_drives.bench_budget, ("bench_drive_budget",)),
    Bench(15, "SYNC period at the drives", b_drives.bench_sync, ("landscaped", "ls-simdrives")),
    Bench(16, "Tracking behind the drives", b_drives.bench_tracking, ("landscaped", "ls-simdrives")),
    Bench(17, "A signed session's MAC per message", b_mac.bench_mac, ("bench_mac",)),
]


def cmake_build(targets: list[str] | None, keep_going: bool) -> subprocess.CompletedProcess[str]:
    cmd = ["cmake", "--build", str(BUILD), "-j", str(os.cpu_count() or 2)]
    if targets:
        cmd += ["--target", *targets]
    if keep_going:
        cmd += ["--", "-k", "0"] if (BUILD / "build.ninja").exists() else ["--", "-k"]
    return subprocess.run(cmd, check=False, capture_output=True, text=True)


def build(benches: list[Bench]) -> dict[int, str]:
    """Configure (once) and build the bench project: the main tree + the drivers, Release. Returns the
    benchmarks that cannot build, with the build's own error lines."""
    if not (BUILD / "CMakeCache.txt").exists():
        gen = ["-G", "Ninja"] if shutil.which("ninja") else []
        conf = subprocess.run(["cmake", "-S", str(HERE), "-B", str(BUILD), *gen, "-DCMAKE_BUILD_TYPE=Release",
                               f"-DLS_PYTHON={sys.executable}"], check=False, capture_output=True, text=True)
        if conf.returncode != 0:
            print(conf.stdout + conf.stderr, file=sys.stderr)
            return {b.number: f"configuring {BUILD} failed (cmake -S bench -B {BUILD})" for b in benches}
    everything = cmake_build(None, keep_going=True)
    if everything.returncode == 0:
        return {}
    print(everything.stdout[-6000:] + everything.stderr[-2000:], file=sys.stderr)
    broken: dict[int, str] = {}
    for b in benches:
        if not b.targets:
            continue
        one = cmake_build(list(b.targets), keep_going=True)
        if one.returncode != 0:
            out = one.stdout + one.stderr
            failed = re.findall(r"^FAILED: (.*)$", out, re.MULTILINE)
            errors = re.findall(r"^(.*(?:error:|undefined reference to).*)$", out, re.MULTILINE)
            broken[b.number] = (f"building {', '.join(b.targets)} failed"
                                + (f" at {', '.join(f.strip() for f in failed[:2])}" if failed else "") + ": "
                                + ("; ".join(errors[:2]) if errors else out.strip()[-300:]))
    if not broken:  # something no benchmark needs (bench_firmware's ALL) failed: it still is a broken build
        return {b.number: "the bench build failed (see the output above)" for b in benches}
    return broken


def machine() -> str:
    cpu = "unknown CPU"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    load = ", ".join(f"{x:.1f}" for x in os.getloadavg())
    return (f"{cpu}, {os.cpu_count()} cores, Linux {platform.release()}, Python {platform.python_version()}; "
            f"load average at the end {load} (other work shares the machine: timing figures are noisy, the "
            f"side-by-side ratios less so)")


def esc(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def _git(*args: str) -> str:
    """git's output in ROOT, or "" where there is no git (an exported tree, the fresh root)."""
    try:
        return subprocess.run(["git", "-C", str(ROOT), *args], capture_output=True, text=True).stdout.strip()
    except FileNotFoundError:
        return ""


def render(sections: list[Section], total_s: float) -> str:
    commit = _git("rev-parse", "--short", "HEAD") or "unknown (no git)"
    if _git("status", "--porcelain", "--", "bench", "firmware", "hal", "protocol", "host_tools"):
        commit += " + uncommitted changes"
    out = [
        "# Performance",
        "",
        "Generated by `bash bench/run` (= `.venv/bin/python bench/run.py`); do not edit by hand. Every figure is "
        "a ratio against a reference run side by side in the same script, or a machine-independent count "
        "(frames, bytes, instructions). A figure never fails a run; a benchmark that cannot build or run does.",
        "",
        f"Run of {datetime.date.today().isoformat()} at commit {commit} on {machine()}; "
        f"{total_s:.0f} s in all (build included).",
        "",
        "| benchmark | ours | reference | reference figure | ratio | notes |",
        "|---|---|---|---|---|---|",
    ]
    for sec in sections:
        for r in sec.rows:
            out.append(f"| {esc(r.bench)} | {esc(r.ours)} | {esc(r.reference)} | {esc(r.ref_figure)} | "
                       f"{esc(r.ratio)} | {esc(r.note)} |")
    out += ["", "Ratios are ours / reference unless the column says otherwise.", ""]
    for sec in sections:
        out += [f"## {sec.number}. {sec.title}", ""]
        for d in sec.details:
            out += [d, ""]
        out += [f"Took {sec.seconds:.1f} s.", ""]
        if sec.commands:
            out += ["Reproduce (after `cmake -S bench -B build-bench -G Ninja -DCMAKE_BUILD_TYPE=Release && "
                    "cmake --build build-bench`):", "", "```sh", *sec.commands, "```", ""]
    out += ["## Reproduce everything", "", "```sh",
            "bash .ci/setup                      # packages (incl. gcc-arm-none-eabi, libnewlib-arm-none-eabi), venv",
            "bash bench/run                      # builds build-bench/ (Release) and rewrites this file",
            "bash bench/run --quick              # every benchmark, fewer samples (page: build-bench/performance.md)",
            "bash bench/run --only 3 --quick     # one benchmark", "```", ""]
    return "\n".join(out)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true",
                    help="every benchmark with fewer samples; the page goes to build-bench/performance.md")
    ap.add_argument("--only", default="", help="comma-separated benchmark numbers (the doc is not rewritten)")
    ap.add_argument("--no-build", action="store_true", help="use build-bench/ as it is")
    ap.add_argument("--out", type=Path, default=None,
                    help="where to write the page (default: docs/performance.md for a full run in which every "
                         "benchmark ran, else build-bench/performance.md)")
    args = ap.parse_args()
    numbers = {b.number for b in BENCHES}
    try:
        only = {int(x) for x in args.only.split(",") if x.strip()}
    except ValueError:
        only = {0}
    if only - numbers:
        ap.error(f"--only takes benchmark numbers {min(numbers)}..{max(numbers)}, e.g. --only 2,3")
    benches = [b for b in BENCHES if not only or b.number in only]
    t_start = time.monotonic()
    broken: dict[int, str] = {}
    if not args.no_build:
        print("bench: building build-bench (Release) ...", file=sys.stderr, flush=True)
        broken = build(benches)
        print(f"bench: build {time.monotonic() - t_start:.1f} s", file=sys.stderr, flush=True)
    sections: list[Section] = []
    failed: dict[int, str] = {}
    for b in benches:
        t0 = time.monotonic()
        if b.number in broken:
            failed[b.number] = broken[b.number]
            sec = Section(b.number, b.title, rows=[Row(f"{b.number}. {b.title}", f"not built: {broken[b.number]}")])
        else:
            print(f"bench {b.number}: {b.title} ...", file=sys.stderr, flush=True)
            try:
                sec = b.run(args.quick)
            except BenchError as exc:
                failed[b.number] = str(exc)
                sec = Section(b.number, b.title, rows=[Row(f"{b.number}. {b.title}", f"not run: {exc}")])
            except Exception as exc:  # a broken benchmark must not take the others down
                traceback.print_exc()
                failed[b.number] = f"{type(exc).__name__}: {exc}"
                sec = Section(b.number, b.title, rows=[Row(f"{b.number}. {b.title}",
                                                           f"not run: {type(exc).__name__}: {exc}")])
        sec.seconds = time.monotonic() - t0
        print(f"bench {b.number}: {sec.seconds:.1f} s", file=sys.stderr, flush=True)
        for r in sec.rows:
            print(f"  {r.bench}: {r.ours} | {r.reference} {r.ref_figure} | {r.ratio} | {r.note}")
        sections.append(sec)
    total_s = time.monotonic() - t_start
    text = render(sections, total_s)
    full = not (args.quick or only)
    out = args.out or (DOC if full and not failed else BUILD / "performance.md")
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(text)
    print(f"bench: wrote {out} ({total_s:.0f} s in all)", file=sys.stderr)
    if failed:
        for number, why in failed.items():
            title = next(b.title for b in BENCHES if b.number == number)
            print(f"bench: FAILED: benchmark {number} ({title}) cannot build or run: {why}", file=sys.stderr)
        if full and args.out is None:
            print(f"bench: {DOC} left as it was (a full run rewrites it only when every benchmark ran)",
                  file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
