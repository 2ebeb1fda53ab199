"""The device description on the host side (docs/protocol.md "Device description"):
field paths to names, the checks before sending, the completion hooks, the text."""
from __future__ import annotations

import pytest

from landscape import ArgumentError, build_request, ls
from landscape.description import DeviceDescription, path_name

LOAD = ls.Request.DESCRIPTOR.fields_by_name["path_load"].number


def description() -> DeviceDescription:
    r = ls.DescribeRes(max_sessions=4, max_paths=8, max_points_per_path=256, max_dio_watches=8, max_cycles=1000000,
                       min_rate_pct=0.1, frame_angle_max_rad=6.28, reach_m=1.3, robot_model="ls-sim6",
                       max_answer_bytes=335, max_notice_datum_bytes=95,
                       tools=["gripper", "probe"], workspace_min_m=[-1, -1, 0], workspace_max_m=[1, 1, 1.2])
    r.field_limits.add(path=[1, LOAD, 1], max_bytes=63)
    r.field_limits.add(path=[1, LOAD, 6], max_count=32)
    r.field_limits.add(path=[1, LOAD, 6, 9], max_bytes=47, max_count=4)
    r.field_limits.add(path=[2, 3], max_bytes=63, max_count=4)
    r.downlink_limits.add(path=[2, 2], max_bytes=31)
    r.downlink_limits.add(path=[1, 34, 4], max_bytes=95)
    r.dio_units.add(unit_id=0, input_mask=0x0000FFFF, output_mask=0xFFFF0000)
    s = r.sensors.add(name="force_sensor")
    for name, unit in (("Fx", "N"), ("Tz", "Nm")):
        s.components.add(name=name, unit=unit)
    r.joints.add(min_rad=-3, max_rad=3, max_velocity_rad_s=2.5, max_accel_rad_s2=10)
    return DeviceDescription(r)


def test_paths_name_fields_from_the_uplink_down() -> None:
    assert path_name([1, LOAD, 6, 3]) == "pathLoad.tags.tag_name"
    assert path_name([1, ls.Request.DESCRIPTOR.fields_by_name["connect"].number, 3]) == "connect.client_name"
    assert path_name([2, 3]) == "rsvpReply.data"
    with pytest.raises(ArgumentError, match="not in this host tool's schema"):
        path_name([1, 999])


def test_sizes_are_checked_with_the_field_and_the_limit_named() -> None:
    d = description()
    assert d.limit("pathLoad.tags").max_count == 32
    d.check_request(build_request("pathLoad", path_name="p" * 63, tags=[{"aux_commands": ["x" * 47] * 4}]))
    with pytest.raises(ArgumentError, match=r"pathLoad.path_name is 64 bytes of UTF-8 .* at most 63"):
        d.check_request(build_request("pathLoad", path_name="p" * 64))
    with pytest.raises(ArgumentError, match=r"pathLoad.tags.aux_commands has 5 items; .* at most 4"):
        d.check_request(build_request("pathLoad", path_name="p", tags=[{"aux_commands": ["x"] * 5}]))
    with pytest.raises(ArgumentError, match=r"pathLoad.tags.aux_commands is 48 bytes"):
        d.check_request(build_request("pathLoad", path_name="p", tags=[{"aux_commands": ["x" * 48]}]))
    with pytest.raises(ArgumentError, match=r"split the points"):
        d.check_request(build_request("pathLoad", path_name="p", tags=[{}] * 33))
    with pytest.raises(ArgumentError, match="no limit for 'nope'"):
        d.limit("nope")


def test_value_hooks_and_completion() -> None:
    d = description()
    assert d.choices("getSensorReading", "sensor_type") == ["force_sensor"]
    assert d.choices("getTool", "tool_id") == ["gripper", "probe"]
    assert d.choices("sendCommand", "input") == []
    assert d.sensors == {"force_sensor": [("Fx", "N"), ("Tz", "Nm")]}
    d.check_values(build_request("getSensorReading", sensor_type="force_sensor"))
    with pytest.raises(ArgumentError, match="no sensor 'sonar'; it has force_sensor"):
        d.check_values(build_request("getSensorReading", sensor_type="sonar"))
    with pytest.raises(ArgumentError, match="no tool 'hammer'; it holds gripper, probe"):
        d.check_values(build_request("getTool", tool_id="hammer"))
    with pytest.raises(ArgumentError, match="bits 0x00000001 of unit 0 are not outputs"):
        d.check_values(build_request("setDigitalIO", type="digital", unit_id=0, bits_on=1))
    # a watch takes outputs too (docs/protocol.md "Device description": dio_units)
    d.check_values(build_request("signalDigitalIO", type="digital", unit_id=0, bit_string=0x10001,
                                 callback_type="event"))
    d.res.dio_units[0].output_mask = 0x7FFF0000
    with pytest.raises(ArgumentError, match="bits 0x80000000 are not lines of unit 0 .inputs 0x0000FFFF, outputs "
                                            "0x7FFF0000"):
        d.check_values(build_request("signalDigitalIO", type="digital", unit_id=0, bit_string=0x80000001,
                                     callback_type="event"))
    with pytest.raises(ArgumentError, match="no DIO unit 2; its units: 0"):
        d.check_values(build_request("getDigitalIO", type="digital", unit_id=2))
    d.check_values(build_request("setDigitalIO", type="digital", unit_id=0, bits_on=0x10000))


def test_text_names_every_part() -> None:
    text = "\n".join(description().lines())
    for part in ("8 paths of 256 points", "dio unit 0: inputs 0x0000FFFF outputs 0xFFFF0000",
                 "sensor force_sensor: Fx[N] Tz[Nm]", "tools: gripper, probe", "joint 1: [-3, 3] rad",
                 "limit pathLoad.tags: 32 items", "limit rsvpReply.data: 4 items, 63 bytes",
                 "answers up to 335 bytes, notice data up to 95 bytes each",
                 "sends notice.event_id: 31 bytes", "sends getMotionControlState.fault: 95 bytes"):
        assert part in text, part


def test_the_host_copy_has_the_limits_of_the_options_file() -> None:
    """The stand-in when the device's description does not come through: the same field
    limits as the firmware built from this tree, nothing about devices."""
    d = DeviceDescription.host_copy()
    assert not d.from_device
    assert d.limit("pathLoad.tags").max_count == 32
    assert d.limit("pathLoad.tags.tag_name").max_bytes == 63
    assert (d.limit("pathLoad.tags.aux_commands").max_count, d.limit("pathLoad.tags.aux_commands").max_bytes) == (4, 47)
    assert d.limit("rsvpReply.data").max_bytes == 63
    assert d.sensors == {} and d.tools == [] and not d.res.joints
    # the texts the device sends, the description's own names left out
    assert d.downlink_bytes("notice.event_id") == 31 and d.downlink_bytes("response.ret_msg") == 335
    assert (d.downlink["notice.data"].max_count, d.downlink_bytes("notice.data")) == (10, 95)
    assert d.downlink_bytes("sendCommand.result") == 3711
    assert not any(name.startswith(("describe.", "describeRobot.")) for name in d.downlink)
    with pytest.raises(ArgumentError, match="no limit for the text 'notice.colour'"):
        d.downlink_bytes("notice.colour")
    with pytest.raises(ArgumentError, match="pathLoad.path_name is 64 bytes"):
        d.check_request(build_request("pathLoad", path_name="p" * 64))
