"""Benchmark 17: a signed session's MAC per message (docs/protocol.md "Security"): instructions per call
under callgrind of firmware/auth on libsodium's HMAC-SHA256, by message size, against the heartbeat MAC and
the session key of a connect."""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

from b_cycle import callgrind_ir

from common import BIN, BenchError, Row, Section, need

# Message bodies: a small request (lock: 6 B), a joint move (about 80 B), a path point batch near one
# ISO-TP message's end (1,000 B) and the largest message (4,085 B + the MAC field).
SIZES = (6, 80, 1000, 4085)


def bench_mac(quick: bool) -> Section:
    sec = Section(17, "A signed session's MAC per message (valgrind)")
    if shutil.which("valgrind") is None:
        raise BenchError("valgrind is not installed (apt-get install valgrind)")
    exe = need(BIN / "bench_mac", "MAC driver")
    n = 2000 if quick else 20000
    with tempfile.TemporaryDirectory(prefix="lsbench-") as tmpdir:
        tmp = Path(tmpdir)

        def per_call(case: str, size: int) -> tuple[float, int, int]:
            base = callgrind_ir(exe, case, 0, tmp, str(size))
            total = callgrind_ir(exe, case, n, tmp, str(size))
            return (total - base) / n, total, base

        hb, _, _ = per_call("heartbeat", 0)
        for size in SIZES:
            per, total, base = per_call("verify", size)
            sign, _, _ = per_call("sign", size)
            sec.rows.append(Row(f"17. verify a {size} B message", f"{per:,.0f} instructions/call",
                                "a heartbeat MAC", f"{hb:,.0f} instructions/call", f"{per / hb:.1f}",
                                f"signing it: {sign:,.0f}; ({total:,} - {base:,}) / {n}"))
        ks, _, _ = per_call("session", 0)
        sec.rows.append(Row("17. session key of a signed connect", f"{ks:,.0f} instructions/call", "a heartbeat MAC",
                            f"{hb:,.0f} instructions/call", f"{ks / hb:.1f}", "once per connect"))
    sec.details.append(
        "`bench/mac.c` derives a session key from a key and two nonces, signs a message body of each size once, "
        f"then runs N calls (N = {n}) of `ls_auth_verify` (what each uplink of a signed session costs the device "
        "before it decodes it), `ls_auth_sign` (each downlink), `ls_auth_heartbeat_mac` (each supervisor "
        "heartbeat) and `ls_auth_session_key` (each signed connect); instructions per call = (callgrind total of "
        "the N-call run - total of a run without calls) / N. HMAC-SHA256 on a session key whose padded states "
        "are kept (firmware/auth/ls_auth.h): a message costs one SHA-256 compression per 64 bytes of head and "
        "body plus two to finish. Counts are x86-64 instructions of the Release build with Debian's libsodium "
        "(portable C SHA-256); the Cortex-M4F image compiles the same sources (section 7).")
    sec.commands.append("valgrind --tool=callgrind build-bench/bench/bench_mac verify 80 20000   # and ... 0")
    return sec
