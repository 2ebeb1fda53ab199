"""`landscape gateway` on the command line, before it serves: --hash-password on a terminal and from a
pipe, a configuration nobody could connect with, and a missing bus (docs/gateway.md)."""
from __future__ import annotations

import json
import os
import pty
import select
import signal
import sys
import time
from pathlib import Path

from click.testing import CliRunner, Result

from landscape.cli import cli
from landscape.gateway_config import verify_password

NO_BUS_ENV = {"CAN_INTERFACE": None, "CAN_CHANNEL": None, "CAN_BITRATE": None, "CAN_CONFIG": None}


def single_error(r: Result) -> str:
    assert "Traceback" not in r.stderr + r.stdout
    lines = r.stderr.splitlines()
    assert len(lines) == 1, r.stderr
    return lines[0]


def _read_until(fd: int, want: bytes, timeout_s: float) -> bytes:
    got = b""
    deadline = time.monotonic() + timeout_s
    while want not in got and time.monotonic() < deadline:
        ready, _, _ = select.select([fd], [], [], 0.1)
        if ready:
            try:
                chunk = os.read(fd, 1024)
            except OSError:  # the child closed the terminal (EIO)
                break
            if not chunk:
                break
            got += chunk
    return got


def test_hash_password_on_a_terminal_prompts_and_does_not_echo() -> None:
    pid, fd = pty.fork()
    if pid == 0:  # the child: the pty is its controlling terminal, as in an interactive shell
        os.execv(sys.executable, [sys.executable, "-m", "landscape", "gateway", "--hash-password"])
    try:
        before = _read_until(fd, b"password: ", 30.0)
        if b"password: " not in before:
            os.kill(pid, signal.SIGKILL)  # it waits for a line that no prompt asked for
        assert b"password: " in before, before
        os.write(fd, b"s3cret-pw\n")
        after = _read_until(fd, b"\"\r\n", 30.0)
    finally:
        _, status = os.waitpid(pid, 0)
        os.close(fd)
    assert os.waitstatus_to_exitcode(status) == 0, before + after
    assert b"s3cret-pw" not in after, after  # not echoed
    line = after.decode().strip().splitlines()[-1]
    assert verify_password("s3cret-pw", json.loads(line))


def test_hash_password_from_a_pipe_reads_one_line_without_a_prompt() -> None:
    r = CliRunner().invoke(cli, ["gateway", "--hash-password"], input="from-a-pipe\n")
    assert r.exit_code == 0, r.stderr
    assert "password" not in r.stdout
    assert verify_password("from-a-pipe", json.loads(r.stdout))


def test_anonymous_off_without_users_is_refused_before_serving(tmp_path: Path) -> None:
    cfg = tmp_path / "gw.toml"
    cfg.write_text("[server]\nallow_anonymous = false\n")
    r = CliRunner().invoke(cli, ["gateway", "--config", str(cfg)])
    assert r.exit_code == 2
    assert single_error(r).startswith(f"landscape: error: {cfg}: [server] allow_anonymous = false with no [users] "
                                      f"and no [[certificate_users]]: nobody could connect: add a user")


def test_no_usable_interface_names_the_configs_bus_section(tmp_path: Path) -> None:
    env = {"HOME": str(tmp_path), **NO_BUS_ENV}
    cfg = tmp_path / "gw.toml"
    cfg.write_text("[server]\nport = 1\n")  # never reached: the bus is checked before the server listens
    r = CliRunner().invoke(cli, ["gateway", "--config", str(cfg)], env=env)
    assert r.exit_code == 4, r.output
    line = single_error(r)
    assert line.startswith("landscape: no usable CAN interface (")
    assert f"write interface and channel under [bus] in {cfg}" in line
    assert "pass --interface and --channel" in line
    r = CliRunner().invoke(cli, ["gateway"], env=env)
    assert r.exit_code == 4
    assert "under [bus] in the gateway configuration (--config)" in single_error(r)
