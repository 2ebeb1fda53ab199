"""The drives' readouts as the host reads them (landscape.drives): what `sendCommand
drives N` and `drives bus` answer, parsed into typed values, the table of `landscape
drives`, and the sendCommand inputs they are asked with. The answers here are written as
the firmware's cmd_drives.c formats them (docs/protocol.md "Drives")."""
from __future__ import annotations

import pytest

from landscape.drives import (
    BUS_REQUEST,
    DrivesView,
    home_request,
    joint_request,
    parse_bus,
    parse_joint,
    view_from,
)
from landscape.errors import ProtocolError

FULL = """joint=2
node=0x22
state=OPERATION ENABLED
statusword=0x1637
mode=8
home=homed
home_required=yes
error=0x8611
error_name=following error
position_rad=0.05000
velocity_rad_s=-0.0123
torque_permille=-36
temperature_c=30.9
brake=released
sto=off
feedback_age_cycles=1
"""

BARE = """joint=1
node=0x21
state=SWITCH ON DISABLED
statusword=0x0240
mode=8
home=not_homed
home_required=no
error=0x0000
error_name=
position_rad=0.00000
feedback_age_cycles=3
"""


def test_a_joint_in_full_is_every_value_typed() -> None:
    d = parse_joint(FULL)
    assert (d.joint, d.node, d.state, d.statusword, d.mode) == (2, "0x22", "OPERATION ENABLED", "0x1637", 8)
    assert (d.home, d.home_required, d.error, d.error_name) == ("homed", True, "0x8611", "following error")
    assert (d.position_rad, d.velocity_rad_s, d.torque_permille, d.temperature_c) == (0.05, -0.0123, -36, 30.9)
    assert (d.brake, d.sto, d.feedback_age_cycles) == ("released", "off", 1)


def test_what_a_drive_does_not_publish_is_none() -> None:
    d = parse_joint(BARE)
    assert d.velocity_rad_s is None and d.torque_permille is None and d.temperature_c is None
    assert d.brake is None and d.sto is None
    assert d.error_name == "" and d.home_required is False


def test_an_answer_without_a_key_every_answer_carries_is_a_protocol_error() -> None:
    with pytest.raises(ProtocolError, match="update the host tool"):
        parse_joint(BARE.replace("mode=8\n", ""))
    with pytest.raises(ProtocolError):
        parse_joint(BARE.replace("mode=8", "mode=CSP"))
    with pytest.raises(ProtocolError):
        parse_bus("sync_sent=many\n")


def test_the_table_has_a_row_per_joint_and_the_bus_last() -> None:
    view = view_from({joint_request(1): BARE, joint_request(2): FULL, BUS_REQUEST: "sync_sent=12\nframes_in=80\n"}, 2)
    lines = list(view.lines())
    assert lines[0].split()[:5] == ["joint", "node", "state", "mode", "home"]
    assert "not_homed" in lines[1] and "*" not in lines[1]  # joint 1 need not be homed
    assert "homed" in lines[2] and "0x8611 following error" in lines[2]
    assert "-3.6 %" in lines[2] and "30.9 C" in lines[2]
    assert lines[-1] == "bus: sync_sent=12 frames_in=80"
    assert view.as_dict()["drives"][1]["torque_permille"] == -36
    assert DrivesView().as_dict() == {"drives": [], "bus": {}}


def test_the_inputs_are_the_firmwares_sub_commands() -> None:
    assert joint_request(3) == "drives 3"
    assert BUS_REQUEST == "drives bus"
    assert home_request() == "home"
    assert home_request((2, 3)) == "home 2 3"
