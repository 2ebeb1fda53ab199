"""Fixtures of the host tests: a python-can virtual bus per test, one shared Notifier, the fake device."""
from __future__ import annotations

import itertools
import os
import sys
import uuid
from collections.abc import Iterator
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SRC = ROOT / "host_tools" / "src"
# Test the package of this tree, even when another copy is installed in the venv.
sys.path.insert(0, str(SRC))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import can  # noqa: E402

from fake_device import FakeDevice  # noqa: E402

_counter = itertools.count()


@pytest.fixture
def channel() -> str:
    """A virtual channel no other test uses."""
    return f"lstest-{os.getpid()}-{next(_counter)}-{uuid.uuid4().hex[:6]}"


@pytest.fixture
def bus(channel: str) -> Iterator[can.BusABC]:
    b = can.ThreadSafeBus(interface="virtual", channel=channel)
    yield b
    b.shutdown()


@pytest.fixture
def notifier(bus: can.BusABC) -> Iterator[can.Notifier]:
    n = can.Notifier(bus, [], timeout=0.02)
    yield n
    n.stop()


@pytest.fixture
def device(channel: str) -> Iterator[FakeDevice]:
    """The fake device on its own bus object (the 'controller' side of the channel)."""
    b = can.ThreadSafeBus(interface="virtual", channel=channel)
    n = can.Notifier(b, [], timeout=0.02)
    dev = FakeDevice(b, n, hosts=(0xF1, 0xF2))
    dev.start()
    yield dev
    dev.stop()
    n.stop()
    b.shutdown()
    assert dev.undeclared == [], "the fake device was asked to send what the schema does not declare"
