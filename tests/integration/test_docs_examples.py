"""Every example in README.md and docs/host-tool.md runs against the simulated controller.

The examples are read from the documents, never copied here: a fenced block whose info
string has the word `example` (```sh example, ```python example, ```csv example
file=square.csv). Per document, the `file=` blocks are written first (into a working
directory of the test's own, `~/` into its home), then each `sh` block runs line by line
against a fresh landscaped, and each `python` block is executed. `/tmp/ls0` in an example
stands for the test's pty. A line must exit 0 without a traceback; `monitor` and `events`
without `--duration`/`--once`, and `view` without `--duration`/`--write-layout`, get SIGINT two
seconds after they run (their first line, or at most STARTUP_S), as a user ends them, and must
then exit 0. A block holding `landscape`
commands that is not marked `example` (or `synopsis`, for a usage line) fails
`test_every_command_block_is_marked`.
"""
from __future__ import annotations

import os
import re
import select
import shlex
import signal
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import pytest

from conftest import CLI, ROOT, start_controller

#: Runs the command that follows with SIGINT at its default action. A suite started in the
#: background by a non-interactive shell (`nohup ... &`) has SIGINT ignored, and an ignored
#: signal stays ignored across exec: the open-ended commands would never see the SIGINT that
#: ends them. Resetting it in the child itself, just before its exec, keeps the test's own
#: disposition and needs no preexec_fn (not safe while the test has threads).
WITH_DEFAULT_SIGINT = [sys.executable, "-c",
                       "import os, signal, sys; signal.signal(signal.SIGINT, signal.SIG_DFL); "
                       "os.execv(sys.argv[1], sys.argv[1:])"]

DOCS = ("README.md", "docs/host-tool.md")
DOC_PTY = "/tmp/ls0"
#: Commands that run until Ctrl-C unless bounded by one of these options.
OPEN_ENDED = {"monitor": ("--duration", "--once"), "events": ("--duration",), "view": ("--duration", "--write-layout")}
INTERRUPT_AFTER_S = 2.0
STARTUP_S = 6.0
FENCE = re.compile(r"^(?P<indent> *)(?P<fence>```+)(?P<info>.*)$")


@dataclass(frozen=True)
class Block:
    doc: str
    line: int       # 1-based line of the opening fence
    lang: str
    words: tuple[str, ...]
    text: str

    @property
    def is_example(self) -> bool:
        return "example" in self.words

    @property
    def file(self) -> str | None:
        return next((w.split("=", 1)[1] for w in self.words if w.startswith("file=")), None)

    def __str__(self) -> str:
        return f"{self.doc}:{self.line}"


def fenced_blocks(doc: str) -> list[Block]:
    """Every fenced block of `doc`, with its info string split into words."""
    lines = (ROOT / doc).read_text(encoding="utf-8").splitlines()
    out: list[Block] = []
    i = 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if m is None:
            i += 1
            continue
        indent, fence, info = len(m["indent"]), m["fence"], m["info"].split()
        body: list[str] = []
        j = i + 1
        while j < len(lines) and lines[j].strip() != fence:
            body.append(lines[j][indent:] if lines[j][:indent].strip() == "" else lines[j])
            j += 1
        out.append(Block(doc, i + 1, info[0] if info else "", tuple(info[1:]), "\n".join(body) + "\n"))
        i = j + 1
    return out


def indented_blocks(doc: str) -> list[tuple[int, str]]:
    """Indented code blocks (4 spaces after a blank line) outside fences: (line, text)."""
    lines = (ROOT / doc).read_text(encoding="utf-8").splitlines()
    out: list[tuple[int, str]] = []
    in_fence = False
    i = 0
    while i < len(lines):
        if FENCE.match(lines[i]):
            in_fence = not in_fence
            i += 1
            continue
        if not in_fence and lines[i].startswith("    ") and lines[i].strip() and (i == 0 or not lines[i - 1].strip()):
            start = i
            body = []
            while i < len(lines) and (lines[i].startswith("    ") or not lines[i].strip()):
                body.append(lines[i][4:])
                i += 1
            out.append((start + 1, "\n".join(body)))
            continue
        i += 1
    return out


def _is_cli(word: str) -> bool:
    return word == "landscape" or word.endswith("/landscape")


def _has_cli_line(text: str) -> bool:
    return any(line.split()[:1] and _is_cli(line.split()[0]) for line in text.splitlines())


EXAMPLES = [b for doc in DOCS for b in fenced_blocks(doc) if b.is_example]


def test_every_command_block_is_marked() -> None:
    """A block of landscape commands is an example the test runs, or a synopsis."""
    assert {b.doc for b in EXAMPLES} == set(DOCS), "the documents lost their example blocks"
    unmarked = [str(b) for doc in DOCS for b in fenced_blocks(doc)
                if _has_cli_line(b.text) and not b.is_example and "synopsis" not in b.words]
    unmarked += [f"{doc}:{line} (indented)" for doc in DOCS for line, text in indented_blocks(doc)
                 if _has_cli_line(text)]
    assert unmarked == [], "mark these blocks `example` (the test runs them) or `synopsis`"


class Workspace:
    """The directory and environment the examples of one document run in."""

    def __init__(self, tmp_path: Path) -> None:
        self.cwd = tmp_path / "work"
        self.home = tmp_path / "home"
        self.cwd.mkdir()
        self.home.mkdir()
        for name in ("docs", "build"):
            (self.cwd / name).symlink_to(ROOT / name)
        (self.cwd / ".venv").mkdir()
        (self.cwd / ".venv" / "bin").mkdir()
        (self.cwd / ".venv" / "bin" / "landscape").symlink_to(CLI)
        (self.cwd / ".venv" / "bin" / "python").symlink_to(sys.executable)
        self.runtime = tmp_path / "run"
        self.runtime.mkdir()
        self.pty = str(tmp_path / "ls0")
        self.base_env = {k: v for k, v in os.environ.items() if not k.startswith("CAN_")}
        self.base_env.update(HOME=str(self.home), XDG_RUNTIME_DIR=str(self.runtime),
                             XDG_STATE_HOME=str(tmp_path / "state"),
                             PATH=f"{CLI.parent}{os.pathsep}{os.environ.get('PATH', '')}")
        self.env = dict(self.base_env)

    def here(self, text: str) -> str:
        return text.replace(DOC_PTY, self.pty)

    def write_files(self, doc: str) -> None:
        for b in fenced_blocks(doc):
            if b.is_example and b.file is not None:
                target = self.home / b.file[2:] if b.file.startswith("~/") else self.cwd / b.file
                target.write_text(self.here(b.text), encoding="utf-8")


def _no_traceback(*texts: str) -> None:
    for t in texts:
        assert "Traceback" not in t and "Exception in thread" not in t, t


def run_sh_line(ws: Workspace, block: Block, lineno: int, line: str) -> list[str]:
    """Run one example line (`&&`-joined commands); returns what it printed, for the report."""
    where = f"{block}+{lineno}: {line}"
    words = shlex.split(line, comments=True)
    commands: list[list[str]] = [[]]
    for w in words:
        if w == "&&":
            commands.append([])
        else:
            commands[-1].append(w)
    printed: list[str] = []
    for argv in (c for c in commands if c):
        if argv[0] == "export":
            for assignment in argv[1:]:
                k, _, v = assignment.partition("=")
                ws.env[k] = ws.here(v)
            continue
        if argv[0].endswith("landscaped"):
            # the test started it: the example must start it on the same link
            assert argv[-1] == "&" and f"slcan:pty:{DOC_PTY}" in argv and ["--hal", "sim"] == argv[1:3], where
            continue
        assert _is_cli(argv[0]), f"{where}: the test runs landscape commands only"
        args = [ws.here(a) for a in argv[1:]]
        sub = next((a for a in args if not a.startswith("-") and a in OPEN_ENDED), None)
        open_ended = sub is not None and not any(a in OPEN_ENDED[sub] for a in args)
        proc = subprocess.Popen([*WITH_DEFAULT_SIGINT, str(CLI), *args], cwd=ws.cwd, env=ws.env,
                                stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        first = ""
        if open_ended:
            # once it runs (its first line, or a few seconds for a display that prints at its end)
            assert proc.stdout is not None
            ready, _, _ = select.select([proc.stdout], [], [], STARTUP_S)
            if ready:
                first = proc.stdout.readline()
            time.sleep(INTERRUPT_AFTER_S)
            proc.send_signal(signal.SIGINT)
        try:
            out, err = proc.communicate(timeout=180)
            out = first + out
        except subprocess.TimeoutExpired:
            proc.kill()
            out, err = proc.communicate()
            raise AssertionError(f"{where}: still running after 180 s\n{out}\n{err}") from None
        _no_traceback(out, err)
        assert proc.returncode == 0, f"{where}: exit {proc.returncode}\nstdout:\n{out}\nstderr:\n{err}"
        printed.append(f"$ landscape {' '.join(args)}\n{out}{err}")
    return printed


@pytest.mark.parametrize("block", [b for b in EXAMPLES if b.lang == "sh"], ids=str)
def test_sh_example_runs(block: Block, tmp_path: Path) -> None:
    ws = Workspace(tmp_path)
    ws.write_files(block.doc)
    controller = start_controller(Path(ws.pty))
    printed: list[str] = []
    try:
        for lineno, line in enumerate(block.text.splitlines(), 1):
            if line.strip() and not line.lstrip().startswith("#"):
                printed += run_sh_line(ws, block, lineno, line)
    finally:
        # whatever the block left running: its session (from the block's own environment)
        subprocess.run([str(CLI), "session", "stop"], cwd=ws.cwd, env=ws.env, capture_output=True, timeout=60)
        code = controller.stop()
        print("\n".join(printed))
    assert code == 0, controller.log.read_text(errors="replace")[-4000:]


@pytest.mark.parametrize("block", [b for b in EXAMPLES if b.lang == "python"], ids=str)
def test_python_example_runs(block: Block, tmp_path: Path) -> None:
    ws = Workspace(tmp_path)
    ws.write_files(block.doc)
    controller = start_controller(Path(ws.pty))
    try:
        r = subprocess.run([sys.executable, "-c", ws.here(block.text)], cwd=ws.cwd, env=ws.env,
                           capture_output=True, text=True, timeout=120)
    finally:
        code = controller.stop()
    assert r.returncode == 0, f"{block}: exit {r.returncode}\n{r.stdout}\n{r.stderr}"
    assert code == 0


def test_every_example_kind_is_run() -> None:
    """No example block is silently skipped: each is a file, an sh block or a python block."""
    for b in EXAMPLES:
        assert b.file is not None or b.lang in ("sh", "python"), f"{b}: the test does not know how to run {b.lang!r}"
