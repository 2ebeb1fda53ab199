"""Path files (CSV, YAML, JSON), their checks, and the pathLoad chunking."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from fake_device import FakeDevice
from landscape import ArgumentError, ls, paths
from landscape.limits import max_count, max_string_bytes
from landscape.paths import (
    PathFileError,
    build_path_load_requests,
    load_path_file,
    parse_path_text,
    resolve_settings,
    uplink_size,
)
from landscape.supervisor import Supervisor

CSV_POSE = ("x,y,z,roll,pitch,yaw,tag_name,tag_index,time_delay_s,transition_speed_pct,speed_pct,accel_pct,aux\n"
            "0.4,0,0.5,0,1.5,0,start,1,0.5,10,50,40,dio 1 on; wait 0.2\n"
            "0.45,0.05,0.5,0,1.5,0,,,,,,,\n")


def test_limits_come_from_the_options_file() -> None:
    assert (max_count("PathLoadReq", "tags"), max_count("TagPoint", "joints"), max_count("TagPoint", "aux_commands"),
            max_string_bytes("TagPoint", "tag_name"), max_string_bytes("TagPoint", "aux_commands"),
            max_string_bytes("GetUnitsRes", "linear")) == (32, 24, 4, 63, 47, 15)
    assert max_count("TagPoint", "tag_name") is None
    assert paths.PATH_LOAD_MAX_POINTS == 32


def test_csv_cartesian_all_fields() -> None:
    pf = parse_path_text(CSV_POSE, "csv", "sq.csv")
    assert pf.kind == "cartesian" and pf.locations == ["line 2", "line 3"]
    a, b = pf.points
    assert list(a.pose) == [0.4, 0, 0.5, 0, 1.5, 0] and list(a.joints) == []
    assert (a.tag_name, a.tag_index, a.time_delay_s, a.transition_speed_pct, a.speed_pct, a.accel_pct) == \
        ("start", 1, 0.5, 10.0, 50.0, 40.0)
    assert list(a.aux_commands) == ["dio 1 on", "wait 0.2"]
    assert b == ls.TagPoint(pose=[0.45, 0.05, 0.5, 0, 1.5, 0])


def test_csv_joints_blank_lines_and_any_column_order() -> None:
    pf = parse_path_text("tag_name,j2,j1,j3\n\na,0.2,0.1,0.3\n,1,2,3\n", "csv", "j.csv")
    assert pf.kind == "joint"
    assert [list(p.joints) for p in pf.points] == [[0.1, 0.2, 0.3], [2, 1, 3]]
    assert [p.tag_name for p in pf.points] == ["a", ""] and pf.locations == ["line 3", "line 4"]


YAML_TREE = """
path: square
frame: base_cartesian
motion_type: STRAIGHT_MOTION
offset_type: relative
points:
  - {x: 0.05, y: 0, z: 0, roll: 0, pitch: 0, yaw: 0, tag_name: c1, aux: [dio 1 on, wait 0.1]}
  - {x: 0, y: 0.05, z: 0, roll: 0, pitch: 0, yaw: 0, aux: "dio 1 off"}
"""


def test_yaml_mapping_with_settings() -> None:
    pf = parse_path_text(YAML_TREE, "yaml", "sq.yaml")
    assert (pf.path_name, pf.frame, pf.motion_type, pf.offset_type) == \
        ("square", ls.BASE_CARTESIAN_FRAME, ls.STRAIGHT_MOTION, ls.RELATIVE_DATA)
    assert [list(p.aux_commands) for p in pf.points] == [["dio 1 on", "wait 0.1"], ["dio 1 off"]]
    assert pf.locations == ["points[0]", "points[1]"]
    s = resolve_settings(pf)
    assert (s.path_name, s.frame, s.motion_type, s.offset_type) == \
        ("square", ls.BASE_CARTESIAN_FRAME, ls.STRAIGHT_MOTION, ls.RELATIVE_DATA)
    s = resolve_settings(pf, path_name="other", frame="tool", motion_type="slew", offset_type="ABSOLUTE_DATA")
    assert (s.path_name, s.frame, s.motion_type, s.offset_type) == \
        ("other", ls.TOOL_FRAME, ls.SLEW_MOTION, ls.ABSOLUTE_DATA)


def test_json_list_and_defaults(tmp_path: Path) -> None:
    f = tmp_path / "home.json"
    f.write_text(json.dumps([{"j1": 0, "j2": 0.5, "j3": 0, "j4": 0, "j5": 0, "j6": 0, "tag_name": "h",
                              "tag_index": 3}]))
    pf = load_path_file(f)
    assert pf.points == [ls.TagPoint(joints=[0, 0.5, 0, 0, 0, 0], tag_name="h", tag_index=3)]
    s = resolve_settings(pf)
    assert (s.path_name, s.frame, s.motion_type, s.offset_type) == \
        ("home", ls.JOINT_FRAME, ls.JOINT_MOTION, ls.ABSOLUTE_DATA)
    cart = parse_path_text(CSV_POSE, "csv", "/x/sq.csv")
    s = resolve_settings(cart)
    assert (s.path_name, s.frame, s.motion_type) == ("sq", ls.BASE_CARTESIAN_FRAME, ls.STRAIGHT_MOTION)


POSE = "x,y,z,roll,pitch,yaw"


@pytest.mark.parametrize("fmt,text,message", [
    ("csv", "", "f: empty file: the first row names the columns"),
    ("csv", f"{POSE}\n", "f: no points below the header"),
    ("csv", f"{POSE},colour\n1,2,3,4,5,6,red\n", "f: line 1: colour: unknown column; columns are "
                                                 "x, y, z, roll, pitch, yaw, j1..j8, tag_name"),
    ("csv", "x,x,y,z,roll,pitch,yaw\n", "f: line 1: x: column named twice"),
    ("csv", "x,y,z,roll,pitch,yaw,j1\n", "f: line 1: j1: the file mixes Cartesian (x..yaw) and joint (j1..)"),
    ("csv", "tag_name,speed_pct\n", "f: line 1: no coordinates: name x, y, z, roll, pitch, yaw or j1..jN"),
    ("csv", "j1,j3\n", "f: line 1: j2: missing (joint values run j1..j3 without a gap)"),
    ("csv", "x,y,z,roll,pitch\n1,2,3,4,5\n", "f: line 2: yaw: missing (a Cartesian point needs x, y, z, roll,"),
    ("csv", f"{POSE}\n1,2,3,4,5,6\n1,2,,4,5,6\n", "f: line 3: z: missing"),
    ("csv", f"{POSE}\n1,2,3,4,5\n", "f: line 2: 5 cells, the header names 6 columns"),
    ("csv", f"{POSE}\n1,2,3,4,5,six\n", "f: line 2: yaw: 'six' is not a number"),
    ("csv", f"{POSE}\n1,2,3,4,5,nan\n", "f: line 2: yaw: 'nan' is not a finite number"),
    ("csv", f"{POSE},tag_index\n1,2,3,4,5,6,1.5\n", "f: line 2: tag_index: '1.5' is not an integer"),
    ("csv", f"{POSE},tag_index\n1,2,3,4,5,6,3000000000\n", "f: line 2: tag_index: 3000000000 is outside"),
    ("csv", f"{POSE},speed_pct\n1,2,3,4,5,6,101\n", "f: line 2: speed_pct: 101 is outside 0..100 (percent)"),
    ("csv", f"{POSE},accel_pct\n1,2,3,4,5,6,-1\n", "f: line 2: accel_pct: -1 is outside 0..100"),
    ("csv", f"{POSE},transition_speed_pct\n1,2,3,4,5,6,200\n", "f: line 2: transition_speed_pct: 200 is outside"),
    ("csv", f"{POSE},time_delay_s\n1,2,3,4,5,6,-0.5\n", "f: line 2: time_delay_s: -0.5 is negative"),
    ("csv", f"{POSE},tag_name\n1,2,3,4,5,6,{'t' * 64}\n", f"f: line 2: tag_name: '{'t' * 64}' is 64 bytes; the "
                                                         f"firmware holds at most 63"),
    ("csv", f"{POSE},aux\n1,2,3,4,5,6,a;b;c;d;e\n", "f: line 2: aux: 5 commands; the firmware holds at most 4 "
                                                    "per point"),
    ("csv", f"{POSE},aux\n1,2,3,4,5,6,{'a' * 48}\n", "f: line 2: aux: '" + "a" * 48 + "' is 48 bytes; the firmware "
                                                    "holds at most 47 per command"),
    ("json", "[1, 2", "f: line 1: not valid JSON: Expecting ',' delimiter"),
    ("json", "{\"points\": []}", "f: points: no points"),
    ("json", "{\"path\": \"p\"}", "f: points: missing: list the points under 'points'"),
    ("json", "{\"speed\": 1, \"points\": []}", "f: speed: unknown key; a path file has path, frame, motion_type, "
                                              "offset_type, points"),
    ("json", "{\"points\": {\"x\": 1}}", "f: points: expected a list of points"),
    ("json", "\"hello\"", "f: expected a list of points"),
    ("json", "[[1,2,3]]", "f: points[0]: [1, 2, 3] is not a mapping of point fields"),
    ("json", "{\"frame\": \"sideways\", \"points\": [{\"j1\": 0}]}",
     "f: frame: ReferenceFrame: 'sideways' is not a value"),
    ("json", "{\"motion_type\": 7, \"points\": [{\"j1\": 0}]}", "f: motion_type: MotionType: 7 is not a value"),
    ("json", "{\"path\": \"\", \"points\": [{\"j1\": 0}]}", "f: path: empty path name"),
    ("json", "{\"path\": 5, \"points\": [{\"j1\": 0}]}", "f: path: 5 is not text"),
    ("json", "[{\"j1\": 0, \"j2\": 1}, {\"j1\": 0}]", "f: points[1]: j2: missing (every point of this file "
                                                      "needs j1..j2)"),
    ("json", "[{\"j1\": 0}, {\"j1\": 0, \"j2\": 1}]", "f: points[1]: j2: unexpected: the points of this file have "
                                                      "j1..j1 only"),
    ("json", "[{\"j1\": 0}, {\"j1\": 0, \"x\": 1}]", "f: points[1]: x: unexpected"),
    ("json", "[{\"x\":1,\"y\":2,\"z\":3,\"roll\":4,\"pitch\":5,\"yaw\":6,\"j1\":1}]",
     "f: points[0]: j1: the file mixes Cartesian"),
    ("json", "[{\"j1\": true}]", "f: points[0]: j1: True is not a number"),
    ("json", "[{\"j1\": [1]}]", "f: points[0]: j1: [1] is not a number"),
    ("json", "[{\"j1\": 0, \"tag_name\": 7}]", "f: points[0]: tag_name: 7 is not text"),
    ("json", "[{\"j1\": 0, \"aux\": 7}]", "f: points[0]: aux: 7 is not a ';'-separated string or a list"),
    ("json", "[{\"j1\": 0, \"aux\": [\"a\", \"\"]}]", "f: points[0]: aux: an empty command"),
    ("json", "[{\"j1\": 0, \"aux\": [\"a\", 3]}]", "f: points[0]: aux: 3 is not a command (text)"),
    ("json", "[{\"j1\": 0, \"speed\": 3}]", "f: points[0]: speed: unknown field; a point has"),
    ("yaml", "points: [\n  - {x: 1\n", "f: line 2: not valid YAML: expected the node content, but found '-'"),
    ("yaml", "", "f: empty file: list the points"),
    ("yaml", "- {j1: 0, j25: 1}", "f: points[0]: j25: unknown field"),
    ("yaml", "- {j1: 0, j9: 1}", "f: points[0]: j9: unknown field"),
    ("csv", f"{POSE},aux\n1,2,3,4,5,6,event {'e' * 41}\n", f"f: line 2: aux: 'event {'e' * 41}': NAME is 41 bytes, "
                                                         f"a notice's event id holds at most 31 (describe: "
                                                         f"downlink_limits): use a shorter name"),
    ("csv", f"{POSE},aux\n1,2,3,4,5,6,rsvp {'e' * 32} 1\n", "f: line 2: aux: 'rsvp eeeeeeeeeeeeeeeeeeeeeeeeeeeeeeee "
                                                          "1': NAME is 32 bytes"),
])
def test_every_validation_error(fmt: str, text: str, message: str) -> None:
    with pytest.raises(PathFileError) as ei:
        parse_path_text(text, fmt, "f")
    assert str(ei.value).startswith(message), str(ei.value)
    assert "\n" not in str(ei.value)


def test_file_level_errors(tmp_path: Path) -> None:
    with pytest.raises(PathFileError, match=r"p\.txt: unknown file type '\.txt': use \.csv, \.yaml, \.yml or \.json"):
        load_path_file(tmp_path / "p.txt")
    with pytest.raises(PathFileError, match=r"none\.csv: cannot read it: No such file or directory"):
        load_path_file(tmp_path / "none.csv")
    bad = tmp_path / "bin.csv"
    bad.write_bytes(b"\xff\xfe\x00")
    with pytest.raises(PathFileError, match="not UTF-8 text"):
        load_path_file(bad)


def test_frame_must_match_the_coordinates() -> None:
    joints = parse_path_text("j1,j2\n0,0\n", "csv", "j.csv")
    with pytest.raises(PathFileError, match="j.csv: frame: TOOL_FRAME needs Cartesian points"):
        resolve_settings(joints, frame="tool")
    cart = parse_path_text(CSV_POSE, "csv", "c.csv")
    with pytest.raises(PathFileError, match="c.csv: frame: JOINT_FRAME needs joint values"):
        resolve_settings(cart, frame="joint")
    with pytest.raises(PathFileError, match="path name: '" + "n" * 64 + "' is 64 bytes"):
        resolve_settings(cart, path_name="n" * 64)


# ---------------------------------------------------------------- chunking


def _point(i: int, *, aux: int = 0) -> ls.TagPoint:
    return ls.TagPoint(pose=[0.001 * i, 0.25, 0.5, 0, 1.5, 0], tag_name=f"t{i}", tag_index=i,
                       aux_commands=[f"{k:02d}" + "a" * 45 for k in range(aux)])


def test_small_points_split_at_32_and_keep_order() -> None:
    pts = [_point(i) for i in range(70)]
    reqs = build_path_load_requests("p", pts, frame="base_cartesian", motion_type="straight")
    assert [len(r.path_load.tags) for r in reqs] == [32, 32, 6]
    assert [t.tag_index for r in reqs for t in r.path_load.tags] == list(range(70))
    for r in reqs:
        pl = r.path_load
        assert r.seq == 0 and pl.number_of_points == len(pl.tags)
        assert (pl.path_name, pl.frame, pl.motion_type, pl.offset_type) == \
            ("p", ls.BASE_CARTESIAN_FRAME, ls.STRAIGHT_MOTION, ls.ABSOLUTE_DATA)
        assert uplink_size(r) <= 4095


def test_big_points_split_by_bytes_exactly() -> None:
    pts = [_point(i, aux=4) for i in range(30)]
    one = uplink_size(build_path_load_requests("p", pts[:1])[0])
    reqs = build_path_load_requests("p", pts)
    sizes = [uplink_size(r) for r in reqs]
    counts = [len(r.path_load.tags) for r in reqs]
    assert sum(counts) == 30 and all(s <= 4095 for s in sizes)
    per_point = (sizes[0] - one) // (counts[0] - 1)  # every point here encodes to the same size
    assert counts[0] == 1 + (4095 - one) // per_point < 32
    assert counts[:-1] == [counts[0]] * (len(counts) - 1)
    # one point more would not have fitted
    assert uplink_size(build_path_load_requests("p", pts[:counts[0] + 1], max_message_bytes=10**6)[0]) > 4095
    # the message on the wire, with a real seq, is never larger than the sized one
    r = reqs[0]
    r.seq = 7
    assert ls.Uplink(request=r).ByteSize() <= sizes[0]


def test_limits_are_parameters() -> None:
    pts = [_point(i) for i in range(5)]
    assert [len(r.path_load.tags) for r in build_path_load_requests("p", pts, max_points=2)] == [2, 2, 1]
    alone = [uplink_size(build_path_load_requests("p", [p])[0]) for p in pts]
    # seq (5) + 6 packed doubles (50) + name, index (0: absent), envelope; frame, motion_type and
    # offset_type are sent also when 0 (required: docs/protocol.md "Absent fields")
    assert alone == [78, 80, 80, 80, 80]
    assert len(build_path_load_requests("p", pts, max_message_bytes=80)) == 5
    with pytest.raises(ArgumentError, match=r"point 0 alone needs 78 bytes, more than one message holds \(77\)"):
        build_path_load_requests("p", pts, max_message_bytes=77)
    with pytest.raises(ArgumentError, match="path 'p': no points to load"):
        build_path_load_requests("p", [])
    reqs = build_path_load_requests("p", [{"joints": [1, 2, 3, 4, 5, 6], "tag_name": "a"}])
    assert list(reqs[0].path_load.tags[0].joints) == [1, 2, 3, 4, 5, 6]
    with pytest.raises(ArgumentError, match="no field 'speed'"):
        build_path_load_requests("p", [{"joints": [1], "speed": 3}])


def test_supervisor_path_load_points(bus, notifier, device: FakeDevice) -> None:
    seen: list[tuple[int, int]] = []
    with Supervisor(bus, notifier=notifier, channel_name="virtual:test") as sup:
        sup.lock()
        rv = sup.path_load_points("big", [_point(i, aux=2) for i in range(75)], frame="base_cartesian",
                                  motion_type="straight", progress=lambda a, b: seen.append((a, b)))
        assert rv.result == {"points_in_path": 75}
    loads = [r for r in device.requests if r.WhichOneof("cmd") == "path_load"]
    assert [len(r.path_load.tags) for r in loads] == [len(s) for s in _chunks(75)]
    assert seen == list(zip(_cumulative(_chunks(75)), [75] * len(loads), strict=True))
    assert [t.tag_index for r in loads for t in r.path_load.tags] == list(range(75))
    assert [r.seq for r in loads] == list(range(4, 4 + len(loads)))  # after connect, describe, lock
    assert max(device.uplink_sizes) <= 4095
    assert device.paths["big"] == [t for r in loads for t in r.path_load.tags]


def _chunks(n: int) -> list[list[ls.TagPoint]]:
    return [list(r.path_load.tags) for r in build_path_load_requests("big", [_point(i, aux=2) for i in range(n)],
                                                                       frame="base_cartesian", motion_type="straight")]


def _cumulative(chunks: list[list[ls.TagPoint]]) -> list[int]:
    out, s = [], 0
    for c in chunks:
        s += len(c)
        out.append(s)
    return out


def test_supervisor_path_load_refused_midway(bus, notifier, device: FakeDevice) -> None:
    from landscape import NoResourcesError

    with Supervisor(bus, notifier=notifier, channel_name="virtual:test") as sup:
        sup.lock()
        sup.path_load_points("p", [_point(i) for i in range(980)])
        with pytest.raises(NoResourcesError) as ei:
            sup.path_load_points("p", [_point(i) for i in range(40)])
        assert str(ei.value).startswith("pathLoad: CMD_NO_RESOURCES_ERR: a path holds at most 1000 points "
                                        "(message 1 of 2; 0 of 40 points were loaded: pathClearPath p to start over)")
        rv = sup.path_load_points("p", [_point(i) for i in range(20)], check=False)
        assert rv.ret_code == 0 and rv.result == {"points_in_path": 1000}
        rv = sup.path_load_points("p", [_point(1)], check=False)
        assert rv.ret_code == ls.CMD_NO_RESOURCES_ERR and "0 of 1 points were loaded" in rv.ret_msg


def test_supervisor_path_load_points_forwards_call_options(bus, notifier, device: FakeDevice) -> None:
    """check= and timeout_s= of path_load_points reach every pathLoad message it sends: check
    decides whether a refusal raises, timeout_s is each message's per-try time-out."""
    from landscape import ControllerTimeoutError, NoResourcesError

    with Supervisor(bus, notifier=notifier, channel_name="virtual:test", retries=0) as sup:
        sup.lock()
        device.silent = True
        with pytest.raises(ControllerTimeoutError, match=r"to pathLoad \(seq 4, 1 tries of 0\.07 s\)"):
            sup.path_load_points("p", [_point(i) for i in range(3)], timeout_s=0.07, check=False)
        device.silent = False
        sup.path_load_points("p", [_point(i) for i in range(1000)], timeout_s=5.0)
        rv = sup.path_load_points("p", [_point(1)], timeout_s=5.0, check=False)
        assert rv.ret_code == ls.CMD_NO_RESOURCES_ERR and "0 of 1 points were loaded" in rv.ret_msg
        with pytest.raises(NoResourcesError, match="0 of 1 points were loaded"):
            sup.path_load_points("p", [_point(1)], timeout_s=5.0, check=True)
