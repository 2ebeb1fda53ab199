"""Benchmark 5: control cycle cost in instructions (valgrind callgrind) and
allocations per cycle (valgrind memcheck's heap summary), both as the
difference between an N-cycle run and a set-up-only run, divided by N."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from common import BIN, BenchError, Row, Section, need

CASE_TEXT = {
    "traj": "joint move: ls_traj_sample, 6 axes",
    "fk": "hold: ls_kin_fk of the measured position",
    "cart_ik": "Cartesian line: pose interp + ls_kin_ik_nearest",
    "motion_hold": "executor holding (ls_motion_step)",
    "motion_joint": "executor, joint move (ls_motion_step)",
    "motion_line": "executor, Cartesian line with IK (ls_motion_step)",
    "motion_path": "executor, 4-point path with blends (ls_motion_step)",
    "control_hold": "whole loop body holding (ls_control_cycle, ideal arm)",
    "control_joint": "whole loop body, joint move (ls_control_cycle, ideal arm)",
    "control_line": "whole loop body, Cartesian line with IK (ls_control_cycle, ideal arm)",
    "react_guarded": "guarded move, travelling (ls_react_step)",
    "react_comply": "compliant move at its target force (ls_react_step)",
}


def callgrind_ir(exe: Path, case: str, n: int, tmp: Path, *extra: str) -> int:
    """callgrind's instruction total of `exe case [extra...] n`."""
    out = tmp / f"cg.{case}.{abs(hash(extra))}.{n}"
    run = subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", str(exe), case, *extra,
                          str(n)], capture_output=True, text=True, timeout=600)
    if run.returncode != 0:
        raise BenchError(f"{exe.name} {case} {n} under callgrind failed: {run.stderr.strip()[-300:]}")
    for line in out.read_text().splitlines():
        if line.startswith(("totals:", "summary:")):
            return int(line.split()[1])
    raise BenchError(f"no totals in callgrind's output for {case}")


def heap_allocs(exe: Path, case: str, n: int) -> int:
    run = subprocess.run(["valgrind", "--tool=memcheck", str(exe), case, str(n)], capture_output=True, text=True,
                         timeout=600)
    if run.returncode != 0:
        raise BenchError(f"bench_cycle {case} {n} under memcheck failed: {run.stderr.strip()[-300:]}")
    m = re.search(r"total heap usage: ([\d,]+) allocs", run.stderr)
    if m is None:
        raise BenchError(f"no heap summary from memcheck for {case}")
    return int(m.group(1).replace(",", ""))


def bench_cycle(quick: bool) -> Section:
    sec = Section(5, "Control cycle cost: instructions and allocations per cycle (valgrind)")
    if shutil.which("valgrind") is None:
        raise BenchError("valgrind is not installed (apt-get install valgrind)")
    exe = need(BIN / "bench_cycle", "cycle driver")
    cases = subprocess.run([str(exe), "cases"], capture_output=True, text=True, check=True).stdout.split()
    absent = [c for c in CASE_TEXT if c not in cases]
    if absent:
        raise BenchError(f"bench_cycle was built without the case(s) {', '.join(absent)}: see the "
                         "BENCH_HAVE_* conditions of bench_cycle in bench/CMakeLists.txt")
    n = 500 if quick else 2000
    with tempfile.TemporaryDirectory(prefix="lsbench-") as tmpdir:
        tmp = Path(tmpdir)

        def measure(case: str) -> tuple[int, int, float]:
            base = callgrind_ir(exe, case, 0, tmp)
            total = callgrind_ir(exe, case, n, tmp)
            return base, total, (heap_allocs(exe, case, n) - heap_allocs(exe, case, 0)) / n

        # Counts, not times: the valgrind runs (each mostly start-up) may share the cores.
        with ThreadPoolExecutor(max_workers=os.cpu_count() or 2) as pool:
            results = list(pool.map(measure, cases))
        for case, (base, total, allocs) in zip(cases, results, strict=True):
            per = (total - base) / n
            sec.rows.append(Row(f"5. cycle: {CASE_TEXT.get(case, case)}",
                                f"{per:,.0f} instructions/cycle; {allocs:g} allocations/cycle",
                                "machine-independent count", "", "",
                                f"({total:,} - {base:,}) / {n}; allocations goal 0"))
    sec.details.append(
        "`bench/cycle.c` runs N cycles (dt 1 ms) of one case after its set-up (planning is set-up and is "
        "subtracted). Instructions per cycle = (callgrind total of an N-cycle run - total of a set-up-only run) "
        f"/ N with N = {n}; allocations per cycle the same difference of memcheck's `total heap usage` "
        "(catches malloc, calloc, realloc and C++ new anywhere, libraries included). Executor cases run "
        "`ls_motion_step` alone, with the measured position equal to the command; `control_*` cases run the "
        "whole `ls_control_cycle` (command ring, executor, arm command/read, FK for the snapshot, seqlock "
        "publish, event ring drained each cycle) on an ideal in-driver arm, so the ODE world's physics (a "
        "simulator cost, not the firmware's) is not counted. Moves are planned long enough that all N cycles "
        "move. `react_*` cases run `ls_react_step` alone: a guarded move travelling without contact, and a "
        "compliant move whose force reading stays at its target (the PD correction, the travel profile and the "
        "IK of the new tip pose every cycle). Counts are x86-64 instructions of the Release build (-O3 by CMake's "
        "default).")
    sec.commands.append("valgrind --tool=callgrind build-bench/bench/bench_cycle cart_ik 2000   # and ... cart_ik 0")
    sec.commands.append("valgrind build-bench/bench/bench_cycle cart_ik 2000 2>&1 | grep 'total heap usage'")
    return sec
