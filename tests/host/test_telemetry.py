"""Status codes are the DBC's value tables: cantools decodes them by name, and the
host's names for them come from the same tables."""
from __future__ import annotations

import cantools.database
import pytest

from landscape import telemetry as tm
from landscape.errors import ArgumentError


def test_cantools_decodes_status_codes_by_their_names() -> None:
    """A STATUS frame as the device packs it decodes, with cantools' choices, to the
    value-table names (docs/protocol.md "Broadcasts")."""
    frame = tm.encode("STATUS", 0x10, st_state=8, st_motion=5, st_control_mode=2, st_fault=1)
    db = tm.database()
    assert isinstance(db, cantools.database.can.Database)
    decoded = db.decode_message(frame.arbitration_id, bytes(frame.data), decode_choices=True)
    assert isinstance(decoded, dict)
    assert str(decoded["st_motion"]) == "robot_stopping"
    assert str(decoded["st_control_mode"]) == "controller_error"
    assert str(decoded["st_fault"]) == "latched"
    hb = tm.encode("HEARTBEAT", 0xF1, hb_role=1, hb_counter=3, hb_period_ms=200, hb_token=5)
    # a supervisor's id carries its own address: decode by name (the DBC's id has the device's)
    assert str(db.decode_message("HEARTBEAT", bytes(hb.data))["hb_role"]) == "supervisor"


def test_choice_value_is_the_table_number() -> None:
    assert tm.choice_value("STATUS", "st_motion", "running_trajectory") == 1
    assert tm.choice_value("STATUS", "st_control_mode", "power_on") == 1
    assert tm.choice_value("HEARTBEAT", "hb_role", "device") == 0
    assert tm.choice_name("STATUS", "st_motion", tm.choice_value("STATUS", "st_motion", "robot_paused")) == \
        "robot_paused"


def test_choice_value_refuses_an_unknown_name_and_lists_the_known_ones() -> None:
    with pytest.raises(ArgumentError, match="known: robot_at_rest, running_trajectory"):
        tm.choice_value("STATUS", "st_motion", "flying")
    with pytest.raises(ArgumentError, match="no value table"):
        tm.choice_value("STATUS", "st_overruns", "many")
