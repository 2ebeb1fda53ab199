"""Shared set-up of the sensor, manual and tool tests: landscaped (sim HAL)
with the sim world's control socket, one owner that locked and activated."""
from __future__ import annotations

import math
import socket
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import can
import pytest

from conftest import Controller, start_controller
from landscape._generated import landscape_pb2 as pb
from landscape.supervisor import Supervisor

# hal/sim/world/hal_sim_world.h: the table top is z = 0.10 m (base frame)
TABLE_TOP_M = 0.10
# A joint pose from which the tool (flange z) points down over the table, and
# Cartesian poses of the flange above the table, tool pointing down.
Q_OVER_TABLE = [-0.2, 0.8, 0.45, 0.0, 0.3, 0.0]
MAX_LINEAR_SPEED = 1.0  # ls_robot_model_default


@dataclass
class Rig:
    controller: Controller
    sup: Supervisor
    sock: Path

    def send(self, msg: str) -> None:
        """A datagram to the sim world's control socket (inputs, jog)."""
        with socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM) as s:
            s.sendto(msg.encode(), str(self.sock))

    def move_tip_to(self, x: float, y: float, z: float) -> None:
        """Tool pointing down (roll pi), tip at x y z (m, base frame)."""
        rv = self.sup.move_absolute("over", [x, y, z, math.pi, 0.0, 0.0], frame=pb.BASE_CARTESIAN_FRAME)
        self.sup.wait_complete(rv, timeout_s=20)


@pytest.fixture
def rig(tmp_path: Path) -> Iterator[Rig]:
    sock = tmp_path / "sim.sock"
    c = start_controller(tmp_path / "ls0", "--dio-socket", str(sock))
    deadline = time.monotonic() + 10
    while not sock.exists():
        assert c.proc.poll() is None, "landscaped exited"
        assert time.monotonic() < deadline, "the sim control socket did not appear"
        time.sleep(0.02)
    bus = can.Bus(interface="slcan", channel=c.pty, bitrate=1000000, sleep_after_open=0)
    try:
        with Supervisor(bus, client_name="sensors") as sup:
            sup.lock()
            sup.activate()
            sup.wait_complete(sup.move_absolute("over_table", Q_OVER_TABLE), timeout_s=20)
            yield Rig(c, sup, sock)
    finally:
        bus.shutdown()
        c.stop()
