"""MCAP recording without a controller: McapRecorder fed with broadcasts encoded by the DBC, read
back with the `mcap` reader; the URDF chain; plots of an MCAP."""
from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import can
import numpy as np
import pytest
from mcap.reader import make_reader

from landscape import telemetry as tm
from landscape._generated import landscape_pb2 as pb
from landscape.errors import ArgumentError
from landscape.mcap_log import CHANNELS, McapError, McapRecorder, read_mcap
from landscape.plotting import plot
from landscape.record_files import read_recording
from landscape.urdf import ArmChain, UrdfError, quaternion_xyzw, rpy_matrix

DEV = 0x10


#: Commanded minus measured joint positions of every cycle of _cycle [rad].
LAG = [0.002, -0.001, 0.0, 0.0005, 0.0, -0.003]


def _cycle(rec: McapRecorder, t_s: float, dev_ms: int, q: list[float]) -> None:
    """One telemetry cycle in the device's order, as frames through telemetry.decode; the commanded positions
    lead the measured ones by LAG."""
    c = [a + b for a, b in zip(q, LAG, strict=True)]
    frames = [tm.encode("STATUS", DEV, st_state=3),
              tm.encode("JOINTS_12", DEV, j1=q[0], j2=q[1]), tm.encode("JOINTS_34", DEV, j3=q[2], j4=q[3]),
              tm.encode("JOINTS_56", DEV, j5=q[4], j6=q[5]),
              tm.encode("JOINTS_CMD_12", DEV, j1_cmd=c[0], j2_cmd=c[1]),
              tm.encode("JOINTS_CMD_34", DEV, j3_cmd=c[2], j4_cmd=c[3]),
              tm.encode("JOINTS_CMD_56", DEV, j5_cmd=c[4], j6_cmd=c[5]),
              tm.encode("TOOL_POS", DEV, tool_x=0.5, tool_y=-0.1, tool_z=0.7, tool_time_ms=dev_ms & 0xFFFF),
              tm.encode("TOOL_RPY", DEV, tool_roll=0.1, tool_pitch=0.2, tool_yaw=0.3),
              tm.encode("DIO", DEV, dio_inputs=5, dio_outputs=2)]
    for f in frames:
        f.timestamp = t_s
        rec.frame(f)
        b = tm.decode(f)
        assert b is not None
        b.timestamp = t_s
        rec.broadcast(b)


def _record(path: Path, n: int = 20) -> McapRecorder:
    with McapRecorder(path, start_s=0.0) as rec:
        for k in range(n):
            # joint 1 at 0.5 rad/s on the device clock (20 ms per cycle), across a 16-bit wrap
            _cycle(rec, 100.0 + 0.02 * k, 65500 + 20 * k, [0.01 * k, 0.2, 0.3, 0.0, 0.9, -0.1])
        n_tag = pb.Notice(kind=pb.EVENT, event_id="tag", data=["tag=p2", "path=demo"], ref_seq=7)
        rec.notice(n_tag, 100.1)
        rec.notice(pb.Notice(kind=pb.ALARM, event_id="moveAbsoluteFailed", data=["reason=fault"], ref_seq=8,
                             final=True), 100.2)
    return rec


def test_every_channel_has_a_schema_and_plausible_messages(tmp_path: Path) -> None:
    rec = _record(tmp_path / "r.mcap")
    with (tmp_path / "r.mcap").open("rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        assert summary is not None
        topics = {c.topic: summary.schemas[c.schema_id] for c in summary.channels.values()}
        assert set(topics) == set(CHANNELS)
        for topic, schema in topics.items():
            assert schema.name == CHANNELS[topic] and schema.encoding == "jsonschema"
            json.loads(schema.data)
    msgs = read_mcap(tmp_path / "r.mcap")
    assert {t: len(v) for t, v in msgs.items()} == {"/joint_states": 20, "/tf": 20, "/tool_pose": 20,
                                                    "/status": 20, "/dio": 20, "/notices": 2, "/can": 200}
    assert rec.counts["/can"] == rec.frames == 200
    js = [m for _, m in msgs["/joint_states"]]
    assert js[0]["velocity_rad_s"] == [None] * 6
    assert [m["device_time_ms"] for m in js] == [65500 + 20 * k for k in range(20)]  # unwrapped past 65535
    for m in js[1:]:
        assert m["velocity_rad_s"][0] == pytest.approx(0.5, abs=1e-3)
        assert m["velocity_rad_s"][1] == pytest.approx(0.0, abs=1e-3)
    assert js[-1]["position_rad"][0] == pytest.approx(0.19, abs=1e-6)
    assert js[-1]["command_rad"][0] == pytest.approx(0.192, abs=1e-6)
    for m in js:
        assert m["following_error_rad"] == pytest.approx(LAG, abs=2e-6)  # the DBC's scale: 1e-6 rad
    tf = msgs["/tf"][-1][1]["transforms"]
    assert len(tf) == 12 and tf[0]["parent_frame_id"] == "base_link" and tf[-1]["child_frame_id"] == "flange"
    rot = tf[0]["rotation"]  # joint 1 about z by q1
    assert (rot["z"], rot["w"]) == pytest.approx((math.sin(0.19 / 2), math.cos(0.19 / 2)), abs=1e-6)
    pose = msgs["/tool_pose"][0][1]
    assert pose["frame_id"] == "base_link" and pose["pose"]["position"]["z"] == pytest.approx(0.7, abs=1e-4)
    q = pose["pose"]["orientation"]
    assert [q[k] for k in "xyzw"] == pytest.approx(list(quaternion_xyzw(rpy_matrix(0.1, 0.2, 0.3))), abs=1e-4)
    assert msgs["/dio"][0][1]["inputs"] == 5 and msgs["/dio"][0][1]["outputs"] == 2
    logs = [m for _, m in msgs["/notices"]]
    assert [(m["name"], m["level"]) for m in logs] == [("tag", 2), ("moveAbsoluteFailed", 3)]
    assert "tag=p2" in logs[0]["message"] and logs[0]["data"] == ["tag=p2", "path=demo"]
    assert msgs["/can"][1][1]["id"] == tm.frame_id("JOINTS_12", DEV) and msgs["/can"][1][1]["extended"]


def test_plots_of_an_mcap(tmp_path: Path) -> None:
    _record(tmp_path / "r.mcap")
    rec = read_recording(tmp_path / "r.mcap")
    assert rec.notices[0][1:] == ("tag", {"tag": "p2", "path": "demo"})
    assert len(rec.series["TOOL_POS"]) == 20 and len(rec.joint_states) == 20
    for kind in ("joints", "velocity", "following", "path"):
        out = plot(rec, tmp_path / f"{kind}.png", kind)
        assert out.stat().st_size > 10_000, kind


def test_velocity_from_a_csv_is_differenced_over_time(tmp_path: Path) -> None:
    from landscape.plotting import joint_samples
    from landscape.recording import Recorder

    with Recorder(tmp_path / "r.csv", start_s=0.0) as rec:
        for k in range(5):
            for name, sig in (("JOINTS_12", {"j1": 0.1 * k, "j2": 0.0}), ("JOINTS_34", {"j3": 0.0, "j4": 0.0}),
                              ("JOINTS_56", {"j5": 0.5, "j6": 0.0})):
                rec.broadcast(tm.Broadcast(name, DEV, sig, timestamp=0.1 * k))
    samples = joint_samples(read_recording(tmp_path / "r.csv"))
    assert len(samples) == 5 and samples[-1][2][0] == pytest.approx(1.0)
    plot(read_recording(tmp_path / "r.csv"), tmp_path / "v.png", "velocity")


def test_unreadable_inputs_say_what_to_do(tmp_path: Path) -> None:
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(b"not an mcap file at all")
    with pytest.raises(McapError, match="landscape record"):
        read_mcap(bad)
    with pytest.raises(ArgumentError, match="unknown recording type.*use .mcap"):
        read_recording(tmp_path / "x.bag")
    with pytest.raises(UrdfError, match="not XML"):
        ArmChain("<robot")
    with pytest.raises(UrdfError, match="ends at"):
        ArmChain('<robot name="x"><link name="base_link"/></robot>')


def test_chain_fk_is_the_dh_product() -> None:
    """landscape.urdf's chain of the packaged URDF against the DH product of the model's table
    (the firmware's FK is checked against the running controller in tests/integration/test_urdf.py)."""
    chain = ArmChain()
    assert chain.movable == [f"joint{i}" for i in range(1, 7)]
    q = [0.3, -0.4, 0.5, 1.0, -0.7, 2.0]
    dh = [(0.05, -math.pi / 2, 0.4, 0.0), (0.4, 0.0, 0.0, -math.pi / 2), (0.04, -math.pi / 2, 0.0, 0.0),
          (0.0, math.pi / 2, 0.38, 0.0), (0.0, -math.pi / 2, 0.0, 0.0), (0.0, 0.0, 0.08, 0.0)]
    T = np.eye(4)
    for (a, al, d, off), qi in zip(dh, q, strict=True):
        th = qi + off
        T = T @ np.array([[math.cos(th), -math.sin(th) * math.cos(al), math.sin(th) * math.sin(al), a * math.cos(th)],
                          [math.sin(th), math.cos(th) * math.cos(al), -math.cos(th) * math.sin(al), a * math.sin(th)],
                          [0, math.sin(al), math.cos(al), d], [0, 0, 0, 1]])
    assert np.allclose(chain.fk(q), T, atol=1e-12)


def test_frames_without_a_timestamp_get_the_host_clock(tmp_path: Path) -> None:
    with McapRecorder(tmp_path / "f.mcap") as rec:
        rec.frame(can.Message(arbitration_id=0x123, is_extended_id=False, data=b"\x01\x02"))
    (_, m), = read_mcap(tmp_path / "f.mcap")["/can"]
    assert m == {**m, "id": 0x123, "extended": False, "data": "0102", "dlc": 2}


def _joint_rows(rec: Any, k: int, t: float, commands: bool) -> None:
    q = [0.1 * k, 0.0, 0.2, 0.0, 0.5, 0.0]
    for name, sig in (("JOINTS_12", {"j1": q[0], "j2": q[1]}), ("JOINTS_34", {"j3": q[2], "j4": q[3]}),
                      ("JOINTS_56", {"j5": q[4], "j6": q[5]})):
        rec.broadcast(tm.Broadcast(name, DEV, sig, timestamp=t))
    if commands:
        c = [a + b for a, b in zip(q, LAG, strict=True)]
        for name, sig in (("JOINTS_CMD_12", {"j1_cmd": c[0], "j2_cmd": c[1]}),
                          ("JOINTS_CMD_34", {"j3_cmd": c[2], "j4_cmd": c[3]}),
                          ("JOINTS_CMD_56", {"j5_cmd": c[4], "j6_cmd": c[5]})):
            rec.broadcast(tm.Broadcast(name, DEV, sig, timestamp=t))


@pytest.mark.parametrize("suffix", [".csv", ".jsonl", ".mcap"])
def test_following_error_is_commanded_minus_measured_of_each_cycle(tmp_path: Path, suffix: str) -> None:
    """plot --kind following from every recording type: commanded minus measured of the same cycle (the
    commanded frames come after the measured ones, at the same host time or later), one trace per joint."""
    from landscape.plotting import following_samples, plot_following
    from landscape.record_files import open_recorder

    path = tmp_path / f"r{suffix}"
    if suffix == ".mcap":
        _record(path, n=8)
    else:
        with open_recorder(path, start_s=0.0) as rec:
            for k in range(8):
                _joint_rows(rec, k, 0.02 * k, commands=True)
    recording = read_recording(path)
    samples = following_samples(recording)
    assert len(samples) == 8
    for _, err in samples:
        assert err == pytest.approx(LAG, abs=2e-6)
    out = plot_following(recording, tmp_path / "f.png")
    assert out.stat().st_size > 10_000
    import matplotlib.figure

    captured: list[Any] = []
    orig = matplotlib.figure.Figure.savefig

    def grab(self: Any, *a: Any, **kw: Any) -> Any:
        captured.append(self)
        return orig(self, *a, **kw)
    matplotlib.figure.Figure.savefig = grab  # type: ignore[method-assign]
    try:
        plot(recording, tmp_path / "g.png", "following")
    finally:
        matplotlib.figure.Figure.savefig = orig  # type: ignore[method-assign]
    fig = captured[0]
    ax = fig.axes[0]
    traces = [ln for ln in ax.get_lines() if not ln.get_label().startswith("_")]  # tags are unlabelled lines
    assert [ln.get_label() for ln in traces] == [f"joint {j}" for j in range(1, 7)]
    assert list(traces[5].get_ydata()) == pytest.approx([LAG[5]] * 8, abs=2e-6)
    assert ax.get_ylabel() == "following error [rad]"
    assert [a.get_ylabel() for a in ax.child_axes] == ["following error [deg]"]  # the right axis, in degrees
    assert "following error" in ax.get_title()
    # the legend hides no tag label (the MCAP recording has one)
    renderer = fig._get_renderer()  # the renderer of its last savefig (the figure has no pyplot canvas)
    legend = ax.get_legend().get_window_extent(renderer)
    tags = [t for t in ax.texts if t.get_text() == "p2"]
    assert len(tags) == (1 if suffix == ".mcap" else 0)
    assert all(not legend.overlaps(t.get_window_extent(renderer)) for t in tags)


def test_following_error_without_commanded_positions_is_refused_with_the_reason(tmp_path: Path) -> None:
    from landscape.record_files import open_recorder
    from landscape.recording import RecordingError

    with open_recorder(tmp_path / "old.csv", start_s=0.0) as rec:
        for k in range(3):
            _joint_rows(rec, k, 0.02 * k, commands=False)
    with pytest.raises(RecordingError, match=r"old.csv: no commanded positions \(JOINTS_CMD_12/34/56\)"):
        plot(read_recording(tmp_path / "old.csv"), tmp_path / "f.png", "following")
    with open_recorder(tmp_path / "empty.csv", start_s=0.0):
        pass
    with pytest.raises(RecordingError, match="no joint telemetry"):
        plot(read_recording(tmp_path / "empty.csv"), tmp_path / "f.png", "following")
