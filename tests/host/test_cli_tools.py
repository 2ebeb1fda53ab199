"""`landscape path`, `record`, `plot`, `demo` and the python-can configuration, against the fake device."""
from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest
from click.testing import CliRunner, Result

from fake_device import FakeDevice
from landscape import cli_tools, ls
from landscape.cli import cli
from landscape.mcap_log import URDF_ATTACHMENT
from landscape.paths import build_path_load_requests, load_path_file
from landscape.urdf import urdf_text

CORNERS = ("x,y,z,roll,pitch,yaw,tag_name,tag_index\n"
           "0.03,0,0,0,0,0,c1,1\n0.03,0.06,0,0,0,0,c2,2\n-0.03,0.06,0,0,0,0,,\n-0.03,0,0,0,0,0,c4,4\n")


def run(channel: str, *args: str, **kw: object) -> Result:
    return CliRunner().invoke(cli, ["--interface", "virtual", "--channel", channel, *args], **kw)  # type: ignore[arg-type]


def single_error(r: Result) -> str:
    assert "Traceback" not in r.stderr + r.stdout
    lines = r.stderr.splitlines()
    assert len(lines) == 1, r.stderr
    return lines[0]


def big_csv(tmp_path: Path, n: int) -> Path:
    f = tmp_path / "big.csv"
    rows = ["j1,j2,j3,j4,j5,j6,tag_name,tag_index,aux"]
    rows += [f"{i * 0.001},0,0,0,0,0,t{i},{i},dio {i % 8} on;wait 0.1" for i in range(n)]
    f.write_text("\n".join(rows) + "\n")
    return f


# ---------------------------------------------------------------- path


def test_path_load_text(channel: str, device: FakeDevice, tmp_path: Path) -> None:
    device.state = ls.UNLOCKED
    f = big_csv(tmp_path, 70)
    script = tmp_path / "s.ls"
    script.write_text(f"lock\npath load {f} --name big\n")
    r = run(channel, "run", str(script))
    assert r.exit_code == 0, r.stderr
    out = r.stdout.splitlines()
    assert out[out.index("path load: CMD_EXEC_OK") + 1:] == [
        "  path_name: big", "  frame: JOINT_FRAME", "  motion_type: JOINT_MOTION", "  offset_type: ABSOLUTE_DATA",
        "  points_sent: 70", "  messages: 3", "  points_in_path: 70"]
    loads = [q.path_load for q in device.requests if q.WhichOneof("cmd") == "path_load"]
    assert [len(pl.tags) for pl in loads] == [32, 32, 6]
    assert [t.tag_index for pl in loads for t in pl.tags] == list(range(70))
    assert list(loads[0].tags[3].aux_commands) == ["dio 3 on", "wait 0.1"]
    assert max(device.uplink_sizes) <= 4095
    assert "loading" not in r.stdout  # stdout is not a terminal: no progress bar


@pytest.mark.parametrize("json_out", [True, False])
def test_path_load_progress_only_on_a_terminal_without_json(channel: str, device: FakeDevice, tmp_path: Path,
                                                            monkeypatch: pytest.MonkeyPatch, json_out: bool) -> None:
    monkeypatch.setattr(cli_tools, "_stdout_is_tty", lambda: True)
    f = big_csv(tmp_path, 40)
    script = tmp_path / "s.ls"
    script.write_text(f"lock\npath load {f}\n")
    r = run(channel, *(["--json"] if json_out else []), "run", str(script))
    assert r.exit_code == 0, r.stderr
    if json_out:
        objs = [json.loads(line) for line in r.stdout.splitlines()]  # nothing but JSON lines
        assert objs[1] == {"command": "path load", "ret_code": 0, "ret_name": "CMD_EXEC_OK", "ret_msg": "",
                           "result": {"path_name": "big", "frame": "JOINT_FRAME", "motion_type": "JOINT_MOTION",
                                      "offset_type": "ABSOLUTE_DATA", "points_sent": 40, "messages": 2,
                                      "points_in_path": 40}, "notices": []}
    else:
        assert "loading big" in r.stdout and "40/40" in r.stdout and "\x1b[" in r.stdout


def test_path_load_bad_file_sends_nothing(channel: str, device: FakeDevice, tmp_path: Path) -> None:
    f = tmp_path / "bad.yaml"
    f.write_text("- {j1: 0, j2: 1}\n- {j1: 0, j2: fast}\n")
    r = run(channel, "path", "load", str(f))
    assert r.exit_code == 2
    assert single_error(r) == f"landscape: error: {f}: points[1]: j2: 'fast' is not a number"
    # the session opened (the file is read with the device's points per path), no point was sent
    assert [q.WhichOneof("cmd") for q in device.requests] == ["connect", "describe", "disconnect"]


def test_path_load_refused_midway(channel: str, device: FakeDevice, tmp_path: Path) -> None:
    script = tmp_path / "s.ls"
    f = big_csv(tmp_path, 990)
    script.write_text(f"lock\npath load {f}\npath load {f}\n")
    r = run(channel, "run", str(script))
    assert r.exit_code == 3
    assert r.stderr.splitlines()[0] == (
        f"{script}:3: path load: CMD_NO_RESOURCES_ERR: a path holds at most 1000 points (message 1 of 31; 0 of "
        f"990 points were loaded: `landscape path clear big` to start over) (a table on the device is full "
        f"(supervisors, paths, points); free some)")
    assert len(device.paths["big"]) == 990


def test_path_run_prints_tags_and_waits(channel: str, device: FakeDevice, tmp_path: Path) -> None:
    f = tmp_path / "sq.csv"
    f.write_text(CORNERS)
    script = tmp_path / "s.ls"
    script.write_text(f"lock\nactivate\npath load {f} --offset-type relative\npath run sq --cycles 2\npath clear sq\n")
    r = run(channel, "run", str(script))
    assert r.exit_code == 0, r.stderr
    out = r.stdout.splitlines()
    start = out.index("path-move: CMD_STARTED_OK")
    tags = [line for line in out[start:] if "EVENT tag" in line]
    assert [t.split()[2] for t in tags] == ["tag=c1", "tag=c2", "tag=c4"] * 2
    assert tags[3].startswith("  EVENT tag tag=c1 index=1 cycle=2 path=sq (ref ")
    assert out[start + 7].startswith("  EVENT pathMoveComplete point=sq reason=complete (ref ")
    assert out[start + 7].endswith("final")
    assert "path-clear-path: CMD_EXEC_OK" in out and device.paths == {}
    pl = next(q.path_load for q in device.requests if q.WhichOneof("cmd") == "path_load")
    assert (pl.frame, pl.motion_type, pl.offset_type) == (ls.BASE_CARTESIAN_FRAME, ls.STRAIGHT_MOTION,
                                                          ls.RELATIVE_DATA)


def test_path_run_errors(channel: str, device: FakeDevice) -> None:
    r = run(channel, "path", "run", "nothing")
    assert r.exit_code == 3 and single_error(r).startswith("landscape: path-move: CMD_NOT_OWNER_ERR")
    r = run(channel, "path", "run", "x", "--cycles", "-1")
    assert r.exit_code == 2 and "Invalid value for '--cycles'" in single_error(r)


# ---------------------------------------------------------------- record, plot


@pytest.mark.parametrize("suffix", [".csv", ".jsonl"])
def test_record_writes_rows(channel: str, device: FakeDevice, tmp_path: Path, suffix: str) -> None:
    out = tmp_path / f"rec{suffix}"
    r = run(channel, "record", str(out), "--duration", "0.5")
    assert r.exit_code == 0, r.stderr
    assert r.stdout.startswith("record: ") and r.stdout.rstrip().endswith(f"to {out}")
    if suffix == ".csv":
        with out.open() as fh:
            rows = list(csv.DictReader(fh))
        header = list(rows[0].keys())
        assert header[:6] == ["host_monotonic_s", "t_s", "device_time_ms", "kind", "name", "sender"]
        names = {row["name"] for row in rows}
        j12 = [row for row in rows if row["name"] == "JOINTS_12"]
        tool = [row for row in rows if row["name"] == "TOOL_POS"]
        # signal columns carry their DBC unit; a name that ends with its unit keeps it once
        assert {"j1_rad", "tool_x_m", "tool_roll_rad", "tool_time_ms", "st_cycle_us", "st_motion"} <= set(header)
        assert (float(j12[0]["j1_rad"]), float(j12[0]["j2_rad"]), j12[0]["tool_x_m"], j12[0]["device_time_ms"]) == \
            (0.5, -0.25, "", "")
        dev = [int(row["device_time_ms"]) for row in tool]
        t = [float(row["t_s"]) for row in rows]
    else:
        objs = [json.loads(line) for line in out.read_text().splitlines()]
        names = {o["name"] for o in objs}
        j12 = [o for o in objs if o["name"] == "JOINTS_12"]
        assert j12[0]["signals"] == {"j1_rad": 0.5, "j2_rad": -0.25} and j12[0]["sender"] == 0x10
        dev = [o["device_time_ms"] for o in objs if o["name"] == "TOOL_POS"]
        t = [o["t_s"] for o in objs]
    assert names == {"JOINTS_12", "JOINTS_34", "JOINTS_56", "TOOL_POS", "TOOL_RPY", "STATUS", "DIO"}
    assert len(j12) >= 5 and dev == sorted(dev) and len(set(dev)) == len(dev)
    assert t == sorted(t) and 0 <= t[0] and t[-1] < 1.0


def test_urdf_is_the_devices_own_joined_from_its_pieces(channel: str, device: FakeDevice, tmp_path: Path) -> None:
    """`landscape urdf` asks the device (describeRobot) from offset 0 until it has the whole text; --packaged
    prints the default arm's copy without a bus."""
    r = run(channel, "urdf", "-o", str(tmp_path / "arm.urdf"))
    assert r.exit_code == 0, r.stderr
    assert (tmp_path / "arm.urdf").read_text() == urdf_text()
    offsets = [q.describe_robot.offset for q in device.requests if q.WhichOneof("cmd") == "describe_robot"]
    assert len(offsets) > 1 and offsets[0] == 0 and offsets == sorted(offsets)
    r = CliRunner().invoke(cli, ["urdf", "--packaged"])
    assert r.exit_code == 0 and r.stdout == urdf_text()


def test_an_mcap_recording_carries_the_devices_urdf(channel: str, device: FakeDevice, tmp_path: Path) -> None:
    from mcap.reader import make_reader

    out = tmp_path / "rec.mcap"
    assert run(channel, "record", str(out), "--duration", "0.3").exit_code == 0
    with out.open("rb") as f:
        attachments = list(make_reader(f).iter_attachments())
    assert [(a.name, a.media_type) for a in attachments] == [(URDF_ATTACHMENT, "application/xml")]
    assert attachments[0].data.decode() == urdf_text()


def test_record_unknown_suffix_exit_2(channel: str, tmp_path: Path) -> None:
    r = run(channel, "record", str(tmp_path / "x.txt"), "--duration", "0.1")
    assert r.exit_code == 2
    assert single_error(r) == (f"landscape: error: {tmp_path / 'x.txt'}: unknown recording type '.txt': use .mcap, "
                               f".csv or .jsonl (also .json, .ndjson)")


def _check_png(path: Path, shape: tuple[int, int]) -> None:
    import matplotlib.image

    assert path.stat().st_size > 0
    img = matplotlib.image.imread(str(path))
    assert img.shape[:2] == shape
    assert float(img[..., :3].std()) > 0.01  # not blank


@pytest.mark.parametrize("suffix", [".csv", ".jsonl", ".mcap"])
def test_plot_joints_and_path(channel: str, device: FakeDevice, tmp_path: Path, suffix: str) -> None:
    rec = tmp_path / f"rec{suffix}"
    assert run(channel, "record", str(rec), "--duration", "1.5").exit_code == 0  # 0.4 s caught no joints at load 15
    r = CliRunner().invoke(cli, ["plot", str(rec), "-o", str(tmp_path / "j.png")])
    assert r.exit_code == 0, r.stderr
    assert r.stdout == f"plot: wrote {tmp_path / 'j.png'} (joints)\n"
    _check_png(tmp_path / "j.png", (600, 1000))
    r = CliRunner().invoke(cli, ["plot", str(rec), "-o", str(tmp_path / "v.png"), "--kind", "velocity"])
    assert r.exit_code == 0, r.stderr
    _check_png(tmp_path / "v.png", (600, 1000))
    r = CliRunner().invoke(cli, ["plot", str(rec), "-o", str(tmp_path / "p.png"), "--kind", "path"])
    assert r.exit_code == 0, r.stderr
    _check_png(tmp_path / "p.png", (700, 750))


def test_plot_errors(tmp_path: Path) -> None:
    empty = tmp_path / "empty.csv"
    empty.write_text("host_monotonic_s,t_s,device_time_ms,kind,name,sender\n")
    r = CliRunner().invoke(cli, ["plot", str(empty), "-o", str(tmp_path / "x.png")])
    assert r.exit_code == 1
    assert single_error(r) == (f"landscape: {empty}: no joint telemetry (JOINTS_12/34/56) to plot: record while "
                               f"the controller broadcasts")
    other = tmp_path / "other.csv"
    other.write_text("a,b\n1,2\n")
    r = CliRunner().invoke(cli, ["plot", str(other), "-o", str(tmp_path / "x.png"), "--kind", "path"])
    assert r.exit_code == 1 and "not a recording of `landscape record`" in single_error(r)
    r = CliRunner().invoke(cli, ["plot", str(tmp_path / "none.csv"), "-o", str(tmp_path / "x.png")])
    assert r.exit_code == 1 and "cannot read" in single_error(r)


# ---------------------------------------------------------------- demo


def test_demo_skips_not_implemented_and_exits_0(channel: str, device: FakeDevice, tmp_path: Path) -> None:
    r = run(channel, "demo", "--record", str(tmp_path / "d.csv"), "--plot", str(tmp_path / "d.png"))
    assert r.exit_code == 0, r.stdout + r.stderr
    out = r.stdout.splitlines()
    assert out[0] == "demo: device 'fake' (firmware fake-1, 6 joints), state UNLOCKED"
    heads = [line for line in out if line.startswith("[")]
    assert [h.split("] ", 1)[1] for h in heads] == [
        "take control (lock)", "enable the drives (activate)", "set the speed to 25 % (set-speed)",
        "joint move to the ready pose (move-absolute)", "joint move to one side (move-absolute)",
        "relative joint move back to the ready pose (move-relative)", "read the robot position (get-robot-position)",
        "clear any old path 'demo_square' (path-clear-path)", "load path 'demo_square' (5 tagged points) (path-load)",
        "run path 'demo_square' once (path-move)", "clear path 'demo_square' (path-clear-path)",
        "disable the drives (deactivate)", "give up control (release)"]
    assert out.count("    skipped: not implemented in this firmware") == 3
    assert "    nothing to do (CMD_PARAM_ERR: no path 'demo_square')" in out
    assert "    ok (points_in_path: 5)" in out
    run_at = out.index("[10/13] run path 'demo_square' once (path-move)")
    assert [line.split()[2] for line in out[run_at + 1:run_at + 6]] == \
        ["tag=corner1", "tag=corner2", "tag=corner3", "tag=corner4", "tag=back"]
    assert out[-3] == "demo: 10 steps ok, 3 skipped, 0 failed"
    assert device.owner is None and device.paths == {} and device.state == ls.IDLE
    _check_png(tmp_path / "d.png", (600, 1000))
    _check_png(tmp_path / "d-path.png", (700, 750))
    with (tmp_path / "d.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    assert [row["data"].split(";")[0] for row in rows if row["name"] == "tag"][-5:] == \
        ["tag=corner1", "tag=corner2", "tag=corner3", "tag=corner4", "tag=back"]


def test_demo_failure_cleans_up_and_exits_3(channel: str, device: FakeDevice) -> None:
    device.force_codes["path_move"] = (ls.CMD_FAULT_ERR, "e-stop input active")
    r = run(channel, "--json", "demo")
    assert r.exit_code == 3
    steps = [json.loads(line) for line in r.stdout.splitlines()]
    assert [(s["step"], s["status"]) for s in steps] == [
        ("lock", "ok"), ("activate", "ok"), ("speed", "skipped"), ("ready", "ok"), ("side", "ok"),
        ("back", "skipped"), ("where", "skipped"), ("clear_old", "tolerated"), ("load", "ok"), ("run", "failed"),
        ("deactivate", "ok"), ("release", "ok")]
    assert steps[3]["notices"][-1]["event_id"] == "moveAbsoluteComplete"
    assert single_error(r) == ("landscape: demo: step 'run path 'demo_square' once' failed: CMD_FAULT_ERR: "
                               "e-stop input active")
    assert device.owner is None


def test_demo_path_is_package_data() -> None:
    from landscape.demo import demo_path

    pf = demo_path()
    assert (pf.path_name, pf.frame, pf.offset_type) == ("demo_square", ls.BASE_CARTESIAN_FRAME, ls.RELATIVE_DATA)
    assert [p.tag_name for p in pf.points] == ["corner1", "corner2", "corner3", "corner4", "back"]
    assert len(build_path_load_requests("demo_square", pf.points)) == 1


# ---------------------------------------------------------------- python-can configuration


def test_bus_from_environment(channel: str, device: FakeDevice) -> None:
    r = CliRunner().invoke(cli, ["get-motion-control-state"], env={"CAN_INTERFACE": "virtual", "CAN_CHANNEL": channel})
    assert r.exit_code == 0, r.stderr
    r = CliRunner().invoke(cli, ["--can-context", "lab", "get-motion-control-state"],
                           env={"CAN_INTERFACE_lab": "virtual", "CAN_CHANNEL_lab": channel,
                                "CAN_INTERFACE": "slcan", "CAN_CHANNEL": "/nonexistent"})
    assert r.exit_code == 0, r.stderr


def test_bus_from_config_files(channel: str, device: FakeDevice, tmp_path: Path) -> None:
    (tmp_path / ".canrc").write_text(f"[default]\ninterface = virtual\nchannel = {channel}\n")
    env = {"HOME": str(tmp_path), "CAN_INTERFACE": None, "CAN_CHANNEL": None, "CAN_BITRATE": None}
    r = CliRunner().invoke(cli, ["get-motion-control-state"], env=env)
    assert r.exit_code == 0, r.stderr
    ini = tmp_path / "can.ini"
    ini.write_text(f"[default]\ninterface = slcan\nchannel = /nonexistent\n[lab]\ninterface = virtual\n"
                   f"channel = {channel}\n")
    r = CliRunner().invoke(cli, ["--can-config", str(ini), "--can-context", "lab", "get-motion-control-state"],
                           env=env)
    assert r.exit_code == 0, r.stderr
    r = CliRunner().invoke(cli, ["--can-config", str(tmp_path / "none.ini"), "lock"], env=env)
    assert r.exit_code == 4
    assert single_error(r).startswith("landscape: no usable CAN interface (config file ")
    (tmp_path / ".canrc").unlink()
    r = CliRunner().invoke(cli, ["lock"], env=env)
    assert r.exit_code == 4
    assert "set CAN_INTERFACE and CAN_CHANNEL, or write them in ~/.canrc" in single_error(r)


def test_command_line_overrides_environment(channel: str, device: FakeDevice) -> None:
    r = run(channel, "get-motion-control-state", env={"CAN_INTERFACE": "slcan", "CAN_CHANNEL": "/nonexistent"})
    assert r.exit_code == 0, r.stderr


def test_path_file_loader_used_by_cli(tmp_path: Path) -> None:
    f = tmp_path / "p.yml"
    f.write_text("path: p\npoints:\n  - {j1: 1}\n")
    assert load_path_file(f).path_name == "p"
