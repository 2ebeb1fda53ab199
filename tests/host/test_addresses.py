"""The library's choice of a source address and its identity, against the fake device (which
refuses a second client on a live session's address, as the firmware does)."""
from __future__ import annotations

import threading
import time

import can
import pytest

from fake_device import FakeDevice
from landscape import AddressInUseError, Supervisor
from landscape import telemetry as tm
from landscape.bus import ADDRESS_LISTEN_S, HOST_POOL


def test_the_pool_is_the_schemas() -> None:
    assert HOST_POOL[0] == 0xF1 and HOST_POOL[-1] == 0xFE and len(HOST_POOL) == 14


def test_an_address_heard_is_skipped(channel: str, device: FakeDevice) -> None:
    other = can.Bus(interface="virtual", channel=channel)  # another bus object: its frames reach ours
    stop = threading.Event()

    def beat() -> None:  # a supervisor at 0xF1 beating every 100 ms
        k = 0
        while not stop.wait(0.1):
            other.send(tm.encode("HEARTBEAT", 0xF1, hb_role=1, hb_counter=k & 0xFF, hb_period_ms=100))
            k += 1
    t = threading.Thread(target=beat, daemon=True)
    t.start()
    try:
        with Supervisor(can.ThreadSafeBus(interface="virtual", channel=channel), owns_bus=True) as sup:
            assert sup.source_address == 0xF2 and not sup.address_pinned
        assert 0xF1 not in device.sessions  # never tried
    finally:
        stop.set()
        t.join(2)
        other.shutdown()


def test_a_refused_address_moves_on_and_the_owner_stays(bus: can.BusABC, notifier: can.Notifier,
                                                        device: FakeDevice) -> None:
    # one bus object does not hear its own frames: b takes 0xF1, is refused, moves to 0xF2
    with Supervisor(bus, notifier=notifier, client_name="a") as a:
        a.lock()
        t0 = time.monotonic()
        with Supervisor(bus, notifier=notifier, client_name="b") as b:
            assert time.monotonic() - t0 >= ADDRESS_LISTEN_S
            assert (a.source_address, b.source_address) == (0xF1, 0xF2)
            assert a.nonce != b.nonce
            assert set(device.sessions) == {0xF1, 0xF2} and device.owner == 0xF1
        assert device.owner == 0xF1 and 0xF1 in device.sessions
        assert device.hb_refused == 0  # every heartbeat carried its session's token


def test_a_pinned_address_in_use_is_refused_naming_what_to_do(bus: can.BusABC, notifier: can.Notifier,
                                                               device: FakeDevice) -> None:
    with Supervisor(bus, notifier=notifier, source_address=0xF1) as a:
        second = Supervisor(bus, notifier=notifier, source_address=0xF1)
        with pytest.raises(AddressInUseError, match="address 0xF1 is in use by another client"):
            second.open()
        assert not second.connected and second.source_address == 0xF1
        a.lock()  # still the session's
        # the same object connects again: the same client, accepted
        assert a.connect().device.owner
        assert device.owner == 0xF1


def test_the_pool_exhausted_is_one_error_naming_it(channel: str, bus: can.BusABC, notifier: can.Notifier) -> None:
    dev_bus = can.ThreadSafeBus(interface="virtual", channel=channel)
    dev_notifier = can.Notifier(dev_bus, [], timeout=0.02)
    device = FakeDevice(dev_bus, dev_notifier, hosts=HOST_POOL[:5]).start()
    device.force_codes["connect"] = (-5, "connect: address in use by another client")
    try:
        with pytest.raises(AddressInUseError) as exc:
            Supervisor(bus, notifier=notifier).open()
    finally:
        device.stop()
        dev_notifier.stop()
        dev_bus.shutdown()
    assert sum(1 for q in device.requests if q.WhichOneof("cmd") == "connect") == 4  # ADDRESS_TRIES
    msg = str(exc.value)
    assert "no free supervisor address" in msg and "refused 0xf1, 0xf2, 0xf3, 0xf4" in msg, msg
    assert "pin a free address with --source-address" in msg
