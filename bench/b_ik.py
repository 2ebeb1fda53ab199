"""Benchmark 13: inverse kinematics per call, for each IK class (ls_kin.h): instructions per call under
callgrind of ls_kin_ik_all and ls_kin_ik_nearest on random poses of a spherical-wrist arm (ls-sim6, the
compiled-in model) and of an offset-wrist arm (the UR5e of firmware/model/robots/ur5e.ini), against
ls_kin_fk of the same joint vectors."""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

from b_cycle import callgrind_ir

from common import BIN, ROOT, BenchError, Row, Section, need

ARMS = (("spherical wrist", "ls-sim6", "-"), ("offset wrist", "UR5e", str(ROOT / "firmware/model/robots/ur5e.ini")))
CALLS = {"ik_all": "ls_kin_ik_all (every branch)", "ik_nearest": "ls_kin_ik_nearest"}


def bench_ik(quick: bool) -> Section:
    sec = Section(12, "Inverse kinematics per call, by IK class (valgrind)")
    if shutil.which("valgrind") is None:
        raise BenchError("valgrind is not installed (apt-get install valgrind)")
    exe = need(BIN / "bench_ik", "IK driver")
    n = 2000 if quick else 20000
    with tempfile.TemporaryDirectory(prefix="lsbench-") as tmpdir:
        tmp = Path(tmpdir)

        def per_call(case: str, model: str) -> tuple[float, int, int]:
            base = callgrind_ir(exe, case, 0, tmp, model)
            total = callgrind_ir(exe, case, n, tmp, model)
            return (total - base) / n, total, base

        for cls, name, model in ARMS:
            fk, _, _ = per_call("fk", model)
            for case, text in CALLS.items():
                per, total, base = per_call(case, model)
                sec.rows.append(Row(f"13. IK, {cls} ({name}): {text}", f"{per:,.0f} instructions/call",
                                    "ls_kin_fk of the same joints", f"{fk:,.0f} instructions/call",
                                    f"{per / fk:.1f}", f"({total:,} - {base:,}) / {n}; closed form, no iteration"))
    sec.details.append(
        "`bench/ik.c` computes 256 random poses (FK of joint vectors inside the limits) at set-up, then runs N "
        f"calls (N = {n}) cycling through them; instructions per call = (callgrind total of the N-call run - "
        "total of a run without calls) / N, for `ls_kin_ik_all`, `ls_kin_ik_nearest` (seeded 0.01 rad from the "
        "generating joints) and, as the reference, `ls_kin_fk`. Both IK classes are closed form with a fixed "
        "number of branches (docs/architecture.md \"Inverse kinematics\"), so the count per call hardly varies "
        "with the pose: the mean is the bound. Counts are x86-64 instructions of the Release build.")
    sec.commands.append("valgrind --tool=callgrind build-bench/bench/bench_ik ik_nearest "
                        "firmware/model/robots/ur5e.ini 20000   # and ... 0")
    return sec
