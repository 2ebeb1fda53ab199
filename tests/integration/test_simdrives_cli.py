"""ls-simdrives as a program: bad input is one clear line and exit 2, a missing
SocketCAN says so, a stop signal ends it cleanly (hal/sim/drives/hal_sim_drives.h,
firmware/app/ls_simdrives_opts.c)."""
from __future__ import annotations

import signal
import subprocess
from pathlib import Path

import canopen
import pytest
from simdrives_rig import EDS, canopen_network, reset_and_wait_for_bootup, running_simdrives

from conftest import SIMDRIVES


def run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([str(SIMDRIVES), *args], capture_output=True, text=True, timeout=20)


@pytest.mark.parametrize("args, names", [
    ((), "--link"),
    (("--link", "can0"), "--link can0"),
    (("--link", "slcan:pty:/tmp/x", "--nodes", "0x21,0x99"), "--nodes"),
    (("--link", "slcan:pty:/tmp/x", "--counts-per-rad", "zero"), "--counts-per-rad"),
    (("--link", "slcan:pty:/tmp/x", "--position-offset-counts", "0x30=5"), "0x30"),
    (("--link", "slcan:pty:/tmp/x", "--bogus"), "--bogus"),
])
def test_a_bad_option_is_one_line_and_exit_2(args: tuple[str, ...], names: str) -> None:
    r = run(*args)
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and names in lines[0] and lines[0].startswith("<3>ls-simdrives: error: "), r.stderr
    assert "Traceback" not in r.stderr


def test_help_lists_every_option() -> None:
    r = run("--help")
    assert r.returncode == 0
    for opt in ("--link", "--nodes", "--first-node", "--count", "--counts-per-rad", "--position-offset-counts",
                "--control", "--link-faults"):
        assert opt in r.stdout


def test_socketcan_without_af_can_says_so_in_one_line() -> None:
    r = run("--link", "socketcan:vcan0")
    if r.returncode == 0:
        pytest.fail("ls-simdrives ran on socketcan:vcan0 without being stopped")
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 1 and len(lines) == 1 and "socketcan:vcan0" in lines[0], r.stderr


def test_position_offsets_put_the_counter_where_asked_and_sigint_ends_it(tmp_path: Path) -> None:
    with running_simdrives(tmp_path, "--first-node", "0x30", "--count", "2",
                           "--position-offset-counts", "2147483000",
                           "--position-offset-counts", "0x31=-2147483000") as sd:
        with canopen_network(sd.pty) as net:
            for node_id, offset in ((0x30, 2147483000), (0x31, -2147483000)):
                node = canopen.RemoteNode(node_id, str(EDS))
                net.add_node(node)
                reset_and_wait_for_bootup(node)
                assert abs(node.sdo[0x6064].raw - offset) <= 2
        assert sd.stop(signal.SIGINT) == 0
        assert "SIGINT received" in sd.log_text()


def test_the_fault_injector_works_on_the_drive_link(tmp_path: Path) -> None:
    """--link-faults as landscaped's (docs/reliability.md section 1): with every frame
    the drives send dropped, a master hears nothing, and the counters say why."""
    with running_simdrives(tmp_path, "--nodes", "0x21", "--link-faults", "tx.drop=100%") as sd:
        with canopen_network(sd.pty) as net:
            node = canopen.RemoteNode(0x21, str(EDS))
            net.add_node(node)
            with pytest.raises(canopen.SdoCommunicationError):
                node.sdo[0x1000].raw  # noqa: B018 (no answer)
        sd.stop()
        log = sd.log_text()
        assert "injecting faults tx.drop=100%" in log
        assert "faults: tx" in log
