"""The landscape CLI against the running simulated controller (docs/host-tool.md "CLI"): a
background session that locks, activates, loads a path from a CSV file, runs
it and prints the tag events; --json output; record and plot."""
from __future__ import annotations

import json
import os
import subprocess
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from conftest import CLI, Controller


@pytest.fixture
def session(controller: Controller, tmp_path: Path) -> Iterator[Controller]:
    os.environ["XDG_RUNTIME_DIR"] = str(tmp_path)  # the session socket lives in this test's directory
    r = controller.cli("session", "start")
    assert r.returncode == 0, r.stderr
    try:
        yield controller
    finally:
        controller.cli("session", "stop")
        os.environ.pop("XDG_RUNTIME_DIR", None)


def test_session_locks_activates_loads_a_csv_path_and_prints_its_tags(session: Controller, tmp_path: Path) -> None:
    for cmd in (["lock"], ["activate"], ["move-absolute", "ready", "JOINT_FRAME", "0", "-0.3", "0.6", "0", "0.9", "0"]):
        r = session.cli(*cmd)
        assert r.returncode == 0, (cmd, r.stdout, r.stderr)
    csv = tmp_path / "square.csv"
    csv.write_text("x,y,z,roll,pitch,yaw,tag_name,tag_index\n"
                   "0.02,0,0,0,0,0,a,1\n0,0.02,0,0,0,0,b,2\n-0.02,0,0,0,0,0,c,3\n0,-0.02,0,0,0,0,d,4\n")
    r = session.cli("path", "load", str(csv), "--name", "sq", "--frame", "BASE_CARTESIAN_FRAME",
                    "--motion-type", "STRAIGHT_MOTION", "--offset-type", "RELATIVE_DATA")
    assert r.returncode == 0, r.stderr
    r = session.cli("path", "run", "sq", "--cycles", "2")
    assert r.returncode == 0, r.stderr
    tags = [line for line in r.stdout.splitlines() if "tag=" in line]
    assert [t.split("tag=")[1].split()[0] for t in tags] == ["a", "b", "c", "d"] * 2
    assert "pathMoveComplete" in r.stdout
    # the lock lives on in the background session, across invocations
    r = session.cli("--json", "get-motion-control-state")
    result = json.loads(r.stdout.splitlines()[0])["result"]
    assert result["state"] == "RESTING" and result["owner"] is True
    for cmd in (["deactivate"], ["release"]):
        assert session.cli(*cmd).returncode == 0


def test_lock_again_in_the_session_that_holds_it_is_nothing_to_do(session: Controller) -> None:
    """A script that starts with `lock`, run twice in one kept session: the device refuses the
    second lock (the seed's lock is for an unlocked device); the tool says the session holds it
    already and goes on. Another client's lock stays a refusal."""
    assert session.cli("lock").returncode == 0
    r = session.cli("lock")
    assert r.returncode == 0, (r.stdout, r.stderr)
    assert r.stdout == "lock: this session holds the lock already: nothing to do\n" and r.stderr == ""
    r = session.cli("--json", "lock")
    assert r.returncode == 0 and json.loads(r.stdout)["note"].startswith("this session holds the lock"), r.stdout
    other = session.cli("--no-session", "-s", "0xf7", "lock")
    assert other.returncode != 0 and "holds the lock already" not in other.stdout, other.stdout
    assert session.cli("release").returncode == 0


def test_teach_appends_poses_that_path_load_reads_back_and_runs_to(session: Controller, tmp_path: Path) -> None:
    """docs/host-tool.md "teach": move there, teach it; the file loads and the path goes there, in the
    session's units (degrees here), joint values or the tool tip's world pose."""
    def ok(*cmd: str) -> str:
        r = session.cli(*cmd)
        assert r.returncode == 0, (cmd, r.stdout, r.stderr)
        return r.stdout

    for cmd in (["lock"], ["activate"], ["set-units", "meters", "degrees"]):
        ok(*cmd)
    joints, poses = tmp_path / "taught.csv", tmp_path / "taught.yaml"
    targets = ([0.0, -20.0, 30.0, 0.0, 45.0, 0.0], [15.0, -10.0, 40.0, 10.0, 30.0, 5.0])
    for i, q in enumerate(targets):
        ok("move-absolute", f"p{i}", "JOINT_FRAME", *map(str, q))
        assert f"teach: here{i} appended to {joints} (joint values in degrees; point {i + 1})" in \
            ok("teach", str(joints), f"here{i}")
        ok("teach", str(poses), f"here{i}", "--kind", "cartesian")
    assert joints.read_text().splitlines()[0] == "j1,j2,j3,j4,j5,j6,tag_name"
    assert "frame: WORLD_CARTESIAN_FRAME" in poses.read_text()
    ok("move-absolute", "home", "JOINT_FRAME", "0", "0", "0", "0", "0", "0")
    for f in (joints, poses):
        ok("path", "load", str(f), "--name", f.suffix[1:])
        out = ok("path", "run", f.suffix[1:])
        assert [t.split("tag=")[1].split()[0] for t in out.splitlines() if "tag=" in t] == ["here0", "here1"]
        at = json.loads(ok("--json", "get-robot-position").splitlines()[0])["result"]["joints"]
        assert at == pytest.approx(targets[1], abs=0.01)
        ok("move-absolute", "home", "JOINT_FRAME", "0", "0", "0", "0", "0", "0")
    # a Cartesian pose into a CSV file, which loads in the base frame: refused, nothing written
    r = session.cli("teach", str(joints), "there", "--kind", "cartesian")
    assert r.returncode == 2 and "holds joint points" in r.stderr and "Traceback" not in r.stderr, r.stderr
    assert len(joints.read_text().splitlines()) == 3


def test_events_says_when_another_terminal_changes_the_units(session: Controller) -> None:
    """docs/host-tool.md "Units": through the background session, a set-units from another terminal
    shows in a running `events` (and `monitor`) within a second, not only at its start."""
    assert session.cli("lock").returncode == 0  # set-units is the owner's
    events = subprocess.Popen([str(CLI), "--interface", "slcan", "--channel", session.pty, "events", "--duration",
                               "4"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        time.sleep(1.5)
        assert session.cli("set-units", "mm", "deg").returncode == 0
        out, err = events.communicate(timeout=30)
    finally:
        if events.poll() is None:
            events.kill()
    assert events.returncode == 0, err
    lines = out.splitlines()
    assert "positions in meters and radians" in lines[0], lines
    assert "events: positions now in millimeters and degrees (set-units)" in lines, lines


def test_json_output_parses_for_every_query(controller: Controller) -> None:
    for cmd in ("get-units", "get-velocities", "get-max-accelerations", "get-robot-position", "get-tool-offsets"):
        r = controller.cli("--json", cmd)
        assert r.returncode == 0, r.stderr
        obj = json.loads(r.stdout.splitlines()[0])
        assert obj["ret_code"] == 0 and obj["ret_name"] == "CMD_EXEC_OK" and isinstance(obj["result"], dict)


def test_demo_records_and_plots_the_path(controller: Controller, tmp_path: Path) -> None:
    rec, png = tmp_path / "demo.csv", tmp_path / "demo.png"
    r = controller.cli("demo", "--record", str(rec), "--plot", str(png), timeout=180)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "0 failed" in r.stdout
    import matplotlib.image as mpimg
    for picture in (png, tmp_path / "demo-path.png"):
        img = mpimg.imread(picture)
        assert img.shape[0] > 200 and img.shape[1] > 200
        assert float(img.std()) > 0.01  # not a blank canvas
    assert len(rec.read_text().splitlines()) > 50
