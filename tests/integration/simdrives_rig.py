"""Start the built ls-simdrives (the simulated arm behind CiA 402 drives, an SLCAN pty
link) and tell it to misbehave through its control socket (hal/sim/drives/hal_sim_drives.h)."""
from __future__ import annotations

import signal
import socket
import subprocess
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import canopen

from conftest import ROOT, start_simdrives, stop_process, wait_for_path

#: the drive's EDS as the repository has it (the build installs a copy beside the URDF)
EDS = ROOT / "hal" / "sim" / "drives" / "ls-simdrive.eds"


@dataclass
class SimDrives:
    pty: str
    control_path: str
    proc: subprocess.Popen[bytes]
    log: Path

    def control(self, command: str, settle_s: float = 0.05) -> None:
        """One command on the control socket (one datagram), then a pause: the socket and
        the bus are two channels, and a frame sent right after the command could be
        handled before it."""
        with socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM) as s:
            s.sendto(command.encode(), self.control_path)
        time.sleep(settle_s)

    def stop(self, sig: int = signal.SIGTERM) -> int:
        return stop_process(self.proc, "ls-simdrives", sig)

    def log_text(self) -> str:
        return self.log.read_text(errors="replace")


@contextmanager
def running_simdrives(tmp: Path, *extra: str) -> Iterator[SimDrives]:
    """ls-simdrives for a test; it must exit 0 on SIGTERM, with no sanitizer report."""
    pty = tmp / "drives0"
    proc, control = start_simdrives(pty, *extra)  # conftest's: the pty, then the socket
    wait_for_path(control, proc)
    sd = SimDrives(str(pty), str(control), proc, pty.with_name(pty.name + ".log"))
    try:
        yield sd
    finally:
        code = sd.stop()
        log = sd.log_text()
        assert code == 0, f"ls-simdrives exited with {code}:\n{log[-4000:]}"
        assert "Sanitizer" not in log, log[-4000:]


@contextmanager
def canopen_network(pty: str) -> Iterator[canopen.Network]:
    """python-canopen on the pty through python-can's slcan interface."""
    net = canopen.Network()
    net.connect(interface="slcan", channel=pty, bitrate=1000000, sleep_after_open=0)
    try:
        yield net
    finally:
        net.disconnect()


def reset_and_wait_for_bootup(node: canopen.RemoteNode, timeout_s: float = 3.0) -> None:
    """NMT reset node and wait for its boot-up. The callback is in place before the
    command: the simulator answers faster than nmt.wait_for_bootup() starts listening."""
    booted = threading.Event()

    def on_state(state: int) -> None:
        if state == 0:
            booted.set()

    node.nmt.add_heartbeat_callback(on_state)
    node.nmt.send_command(0x81)
    assert booted.wait(timeout_s), f"node 0x{node.id:02X} sent no boot-up within {timeout_s} s of NMT reset node"
