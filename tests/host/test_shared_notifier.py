"""bus.SharedNotifier: a listener leaving while a frame is delivered must not make another
listener miss that frame (the gateway's sessions join and leave one Notifier; a missed ISO-TP
flow control stalled a session's request for three tries: fc24)."""
from __future__ import annotations

import threading
from collections.abc import Iterator

import can
import pytest

from landscape.bus import SharedNotifier


@pytest.fixture
def buses() -> Iterator[tuple[can.BusABC, can.BusABC]]:
    channel = f"fc24-{id(object())}"
    a = can.Bus(interface="virtual", channel=channel)
    b = can.Bus(interface="virtual", channel=channel)
    try:
        yield a, b
    finally:
        a.shutdown()
        b.shutdown()


def test_a_listener_removed_during_a_delivery_costs_no_other_listener_its_frame(
        buses: tuple[can.BusABC, can.BusABC]) -> None:
    tx, rx = buses
    got_c = threading.Event()
    notifier = SharedNotifier(rx, [], timeout=0.01)
    try:
        def a(msg: can.Message) -> None:
            pass

        def b(msg: can.Message) -> None:
            notifier.remove_listener(a)  # a session leaving, from the delivery of this very frame

        def c(msg: can.Message) -> None:
            got_c.set()

        for listener in (a, b, c):
            notifier.add_listener(listener)
        tx.send(can.Message(arbitration_id=0x18DA10F8, data=b"\x30\x08\x00", is_extended_id=True))
        assert got_c.wait(2.0), "the listener after a removed one missed the frame being delivered"
        assert notifier.listeners == [b, c]
        with pytest.raises(ValueError):
            notifier.remove_listener(a)
    finally:
        notifier.stop()


def test_the_stock_notifier_drops_that_frame(buses: tuple[can.BusABC, can.BusABC]) -> None:
    """The defect SharedNotifier exists for; when python-can fixes it, SharedNotifier can go."""
    tx, rx = buses
    got_c = threading.Event()
    notifier = can.Notifier(rx, [], timeout=0.01)
    try:
        def a(msg: can.Message) -> None:
            pass

        def b(msg: can.Message) -> None:
            notifier.remove_listener(a)

        for listener in (a, b, lambda msg: got_c.set()):
            notifier.add_listener(listener)
        tx.send(can.Message(arbitration_id=0x18DA10F8, data=b"\x30\x08\x00", is_extended_id=True))
        assert not got_c.wait(0.5)
    finally:
        notifier.stop()
