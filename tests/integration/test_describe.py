"""docs/protocol.md "Device description" against the running controller: the device describes itself, the host
library reads it once per session and checks requests against it before sending, names and
tags of 63 bytes go through whole, and `landscape describe` prints it."""
from __future__ import annotations

import can
import pytest

from conftest import Controller
from landscape import errors
from landscape.supervisor import Supervisor, notice_data

HOME = [0.0, 0.3, 0.3, 0.0, 0.9, 0.0]
NAME63 = "path-" + "n" * 53 + "-end."  # 63 bytes
TAG63 = "tag-" + "\u00e9" * 27 + "-end."  # 63 bytes of UTF-8, 36 characters


def executed(sup: Supervisor) -> int:
    """Requests the device executed for this session (sendCommand status)."""
    text = sup.send_command("status").result["result"]
    line = next(x for x in text.splitlines() if x.startswith(f"session 0x{sup.source_address:02X}"))
    return int(line.split("executed=")[1].split()[0])


def test_the_description_read_at_connect(bus: can.BusABC) -> None:
    assert len(NAME63.encode()) == 63 and len(TAG63.encode()) == 63
    with Supervisor(bus, client_name="describe-" + "c" * 54) as sup:  # a 63-byte client name connects
        d = sup.description
        assert d is not None
        r = d.res
        assert (r.max_sessions, r.max_paths, r.max_points_per_path, r.max_dio_watches) == (4, 8, 256, 8)
        assert [(u.unit_id, u.input_mask, u.output_mask) for u in r.dio_units] == [(0, 0x0000FFFF, 0xFFFF0000)]
        assert d.sensors["force_sensor"] == [("Fx", "N"), ("Fy", "N"), ("Fz", "N"), ("Tx", "Nm"), ("Ty", "Nm"),
                                             ("Tz", "Nm")]
        assert d.sensors["laser_standoff_sensor"] == [("distance", "m")]
        assert d.tools == ["gripper", "probe"]
        assert r.robot_model and len(r.joints) == 6 and all(j.min_rad < j.max_rad for j in r.joints)
        assert r.max_linear_speed_m_s > 0 and len(r.workspace_max_m) == 3
        for name in ("connect.client_name", "pathLoad.path_name", "pathLoad.tags.tag_name", "moveAbsolute.point_name",
                     "getTool.tool_id", "getSensorReading.sensor_type"):
            assert d.limit(name).max_bytes == 63, name
        assert d.limit("pathLoad.tags").max_count == 32
        assert d.limit("pathLoad.tags.aux_commands").max_count == 4
        # the same answer when asked again, in another unit system
        again = sup.describe().message
        assert again == r


def test_limits_are_checked_before_sending_and_63_bytes_go_through(bus: can.BusABC) -> None:
    with Supervisor(bus, client_name="names") as sup:
        sup.lock()
        sup.activate()
        before = executed(sup)
        with pytest.raises(errors.ArgumentError, match=r"pathLoad.path_name is 64 bytes .* at most 63 \(describe\)"):
            sup.path_load(NAME63 + "x", [{"joints": HOME}])
        with pytest.raises(errors.ArgumentError, match=r"pathLoad.tags has 33 items"):
            sup.path_load("p", [{"joints": HOME}] * 33)
        assert executed(sup) == before + 1  # the status request itself: nothing else reached the device
        sup.wait_complete(sup.move_absolute("home", HOME), timeout_s=30)
        q1 = [HOME[0] + 0.2, *HOME[1:]]
        assert sup.path_load(NAME63, [{"joints": q1, "tag_name": TAG63}]).ok
        rv = sup.path_move(NAME63)  # number_of_cycles left out: one cycle
        final = sup.wait_complete(rv, timeout_s=30)
        assert notice_data(final)["point"] == NAME63 and "dry_run" not in notice_data(final)
        assert sup.get_tag_id().result == {"path_name": NAME63, "tag_id": TAG63}
        rv = sup.path_move(NAME63, number_of_cycles=0)
        assert "dry run" in rv.ret_msg
        final = sup.wait_complete(rv, timeout_s=30)
        assert notice_data(final)["dry_run"] == "true"
        sup.deactivate()
        sup.release()


def test_the_device_publishes_every_text_it_sends_and_refuses_an_event_name_it_would_cut(bus: can.BusABC) -> None:
    """docs/protocol.md "Device description": downlink_limits bounds every text the device sends (answers,
    notices, acknowledgements, query results), as the host's copy of the schema's options says; a path's
    `event NAME` becomes a notice's event id, so pathLoad refuses a NAME longer than that id holds
    (within the 47 bytes of an auxiliary command), and one of exactly that length arrives whole."""
    from landscape.description import DeviceDescription

    with Supervisor(bus, client_name="downlink") as sup:
        d = sup.description
        assert d is not None and d.from_device
        host = DeviceDescription.host_copy()
        assert {k: (v.max_bytes, v.max_count) for k, v in d.downlink.items()} == \
            {k: (v.max_bytes, v.max_count) for k, v in host.downlink.items()}
        max_id = d.downlink_bytes("notice.event_id")
        assert max_id == 31 and d.downlink_bytes("response.ret_msg") == d.res.max_answer_bytes == 335
        assert d.downlink_bytes("notice.data") == d.res.max_notice_datum_bytes
        assert "sendCommand.result" in d.downlink and "rsvpAck.action" in d.downlink
        sup.lock()
        sup.activate()
        long_name, name = "e" * 41, "n" * max_id
        for aux in (f"event {long_name}", f"rsvp {long_name[:39]} 1"):
            rv = sup.path_load("named", [{"joints": HOME, "aux_commands": [aux]}], check=False)
            assert rv.ret_name == "CMD_PARAM_ERR", rv
            why = f"aux command '{aux}': NAME is {len(aux.split()[1])} bytes, a notice's event id holds at most 31"
            assert why in rv.ret_msg
        assert sup.path_load("named", [{"joints": HOME, "aux_commands": [f"event {name}"]}]).ok
        got = []
        sup.on_notice(got.append)
        sup.wait_complete(sup.path_move("named"), timeout_s=30)
        assert [n.event_id for n in got if n.event_id == name] == [name]
        sup.deactivate()
        sup.release()


def test_cli_describe(controller: Controller) -> None:
    out = controller.cli("describe")
    assert out.returncode == 0, out.stderr
    for part in ("dio unit 0: inputs 0x0000FFFF outputs 0xFFFF0000", "sensor force_sensor: Fx[N]",
                 "tools: gripper, probe", "limit pathLoad.tags: 32 items", "joint 6: [",
                 "sends notice.event_id: 31 bytes", "sends notice.data: 10 items of 95 bytes"):
        assert part in out.stdout, (part, out.stdout)


def test_shell_completion_offers_what_the_device_describes(bus: can.BusABC) -> None:
    """The shell completes sensor types and tool ids from the device's description (the
    tools of its rack, its sensors), not only from values typed before."""
    from prompt_toolkit.completion import CompleteEvent
    from prompt_toolkit.document import Document

    from landscape.backend import BusBackend
    from landscape.cli import published_choices, shell_completer

    with Supervisor(bus, client_name="completion") as sup:
        published = published_choices(BusBackend(sup))
        assert published("tool_id") == ["gripper", "probe"]
        assert published("sensor_type") == ["force_sensor", "laser_standoff_sensor"]
        assert published("path_name") == []  # free text: the device does not list it
        comp = shell_completer(["get-tool", "get-sensor-reading"], lambda: ["get-tool wrench"], published)

        def words(text: str) -> list[str]:
            return [c.text for c in comp.get_completions(Document(text), CompleteEvent(completion_requested=True))]
        assert words("get-tool ") == ["gripper", "probe", "wrench"]  # the rack's first, then typed before
        assert words("get-sensor-reading l") == ["laser_standoff_sensor"]
