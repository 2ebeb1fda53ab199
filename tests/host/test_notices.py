"""Event ids and their data keys have one home, enum ls.EventId of the schema: the host
reads them from the generated Python, the fake device sends nothing else."""
from __future__ import annotations

from fake_device import FakeDevice
from landscape._generated import landscape_pb2 as pb
from landscape.notices import AUX_NAMED_KEYS, EVENT_KEYS, TAG_EVENT, undeclared


def test_the_schema_declares_the_final_notices_of_every_non_blocking_command() -> None:
    from landscape.registry import COMMANDS

    started = [c.name for c in COMMANDS.values() if not c.blocking]
    assert {"moveAbsolute", "pathMove", "moveReact", "comply"} <= set(started)
    for name in started:
        for suffix in ("Complete", "Aborted", "Failed"):
            assert name + suffix in EVENT_KEYS, f"{name}{suffix} is not in enum EventId"
    assert EVENT_KEYS["moveAbsoluteComplete"][:2] == ("point", "reason")
    assert TAG_EVENT == "tag" and "tag" in EVENT_KEYS[TAG_EVENT]
    assert AUX_NAMED_KEYS == ("path", "point") and "AUX_NAMED_EVENT" not in EVENT_KEYS
    assert "EVENT_ID_NONE" not in EVENT_KEYS


def test_undeclared_names_what_the_schema_lacks() -> None:
    assert undeclared("moveAbsoluteComplete", ["point=p", "reason=complete", "joints=0,0,0,0,0,0"]) is None
    assert undeclared("moveComplete", ["point=p"]) == \
        "event id 'moveComplete' is not declared in protocol/landscape.proto enum EventId"
    why = undeclared("tag", ["tag=a", "rsvp=default"])
    assert why is not None and "data 'rsvp=default' has no key the schema declares" in why
    assert undeclared("tag", ["no equals sign"]) is not None
    assert undeclared("confirmMove", ["point=p1"], path_event=True) is None
    assert undeclared("confirmMove", ["point=p1"]) is not None


def test_the_fake_device_refuses_a_notice_the_schema_does_not_declare(device: FakeDevice) -> None:
    device.notify(0xF1, kind=pb.EVENT, event_id="moveComplete", data=["point=p"])
    assert device.undeclared == ["event id 'moveComplete' is not declared in protocol/landscape.proto enum EventId"]
    device.undeclared.clear()  # the fixture fails a test that leaves any
