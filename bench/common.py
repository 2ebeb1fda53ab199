"""Shared pieces of the benchmarks: the result row, percentiles, helper
processes on a pty, and the paths of the build."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
# The host package from this tree, also when the venv has another (or no) editable install of it.
sys.path.insert(0, str(ROOT / "host_tools" / "src"))
BUILD = Path(os.environ.get("LS_BENCH_BUILD", ROOT / "build-bench"))
BIN = BUILD / "bench"
PYTHON = sys.executable


class BenchError(Exception):
    """A benchmark cannot build or run here; the message says why and what to do. bench/run.py
    names the benchmark, puts the message into its table row and exits non-zero."""


@dataclass
class Row:
    """One line of the results table. `ratio` is ours / reference unless `ratio_note` says otherwise."""

    bench: str
    ours: str
    reference: str = ""
    ref_figure: str = ""
    ratio: str = ""
    note: str = ""


@dataclass
class Section:
    """The rows and the detail text one benchmark contributes to docs/performance.md."""

    number: int
    title: str
    rows: list[Row] = field(default_factory=list)
    details: list[str] = field(default_factory=list)
    commands: list[str] = field(default_factory=list)
    seconds: float = 0.0


def percentile(values: Sequence[float], q: float) -> float:
    """Nearest-rank percentile (q in 0..100) of a non-empty sample."""
    if not values:
        raise ValueError("percentile of an empty sample")
    s = sorted(values)
    k = max(0, min(len(s) - 1, int(-(-q * len(s) // 100)) - 1))
    return s[k]


def median(values: Sequence[float]) -> float:
    s = sorted(values)
    n = len(s)
    return s[n // 2] if n % 2 else 0.5 * (s[n // 2 - 1] + s[n // 2])


def fmt_ratio(x: float) -> str:
    return f"{x:.2f}"


def need(path: Path, what: str) -> Path:
    if not path.exists():
        raise BenchError(f"{path} is missing ({what}); build with bench/run.py (cmake -S bench -B build-bench)")
    return path


@contextmanager
def pty_peer(argv: Sequence[str], link: Path, timeout_s: float = 10.0) -> Iterator[subprocess.Popen[bytes]]:
    """Start a process that creates the SLCAN pty symlink `link`; stop it with SIGTERM afterwards."""
    if link.is_symlink():
        link.unlink()
    proc = subprocess.Popen(list(argv), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    deadline = time.monotonic() + timeout_s
    try:
        while not link.exists():
            if proc.poll() is not None:
                err = proc.stderr.read().decode(errors="replace") if proc.stderr else ""
                raise BenchError(f"{argv[0]} exited with {proc.returncode}: {err.strip()}")
            if time.monotonic() > deadline:
                raise BenchError(f"{argv[0]} did not create {link} within {timeout_s:g} s")
            time.sleep(0.01)
        yield proc
    finally:
        if proc.poll() is None:
            proc.send_signal(signal.SIGTERM)
            try:
                proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
        if proc.stderr is not None:
            proc.stderr.close()
