"""`landscape view` against the running landscaped: a Foxglove WebSocket client connects to the live
server while another invocation moves the arm through the background session, and receives joint
states that follow the move and the move's final notice; the channels it advertises are the MCAP
recording's; Ctrl-C ends the view with a summary line, and the session's owner was not disturbed."""
from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from conftest import CLI, Controller
from landscape import telemetry as tm
from landscape._generated import landscape_pb2 as pb
from landscape.mcap_log import CHANNELS, channel_schemas

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "host"))
from foxglove_client import FoxgloveClient  # noqa: E402

TARGET = [0.6, -0.2, 0.3, 0.0, 0.5, 0.4]


@pytest.fixture
def session(controller: Controller, tmp_path: Path) -> Iterator[Controller]:
    os.environ["XDG_RUNTIME_DIR"] = str(tmp_path)
    r = controller.cli("session", "start")
    assert r.returncode == 0, r.stderr
    try:
        for cmd in (["lock"], ["activate"], ["set-speed", "percent", "--speed", "30"]):
            r = controller.cli(*cmd)
            assert r.returncode == 0, (cmd, r.stdout, r.stderr)
        yield controller
    finally:
        controller.cli("session", "stop")
        os.environ.pop("XDG_RUNTIME_DIR", None)


def test_a_websocket_client_follows_a_move_on_the_live_view(session: Controller) -> None:
    view = subprocess.Popen([str(CLI), "--interface", "slcan", "--channel", session.pty, "view", "--port", "0"],
                            stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert view.stdout is not None
        first = view.stdout.readline()
        m = re.match(r"view: (ws://127\.0\.0\.1:\d+) serving device 0x10 on slcan:\S+ \(via the session\);", first)
        assert m, first + (view.stderr.read() if view.poll() is not None and view.stderr else "")
        with FoxgloveClient(m.group(1)) as client:
            client.handshake(len(CHANNELS))
            assert {t: (c["schemaName"], c["schema"]) for t, c in client.channels.items()} == \
                {t: (name, data.decode()) for t, name, data in channel_schemas()}
            client.subscribe("/joint_states", "/tf", "/notices", "/status")
            before = [r.json() for r in client.messages(0.5) if r.topic == "/joint_states"]
            assert before, "no joint state within 0.5 s of subscribing (50 Hz telemetry)"
            q0 = before[-1]["position_rad"]
            move = subprocess.Popen([str(CLI), "--interface", "slcan", "--channel", session.pty, "move-absolute", "p",
                                     "JOINT_FRAME", *map(str, TARGET)],
                                    stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
            got = []
            deadline = time.monotonic() + 60
            while move.poll() is None and time.monotonic() < deadline:
                got += client.messages(0.2)
            out, err = move.communicate(timeout=60)
            assert move.returncode == 0, (out, err)
            got += client.messages(0.5)
    finally:
        if view.poll() is None:
            view.send_signal(signal.SIGINT)
        v_out, v_err = view.communicate(timeout=30)
    js = [r.json() for r in got if r.topic == "/joint_states"]
    assert len(js) > 20, len(js)
    j1 = [m["position_rad"][0] for m in js]
    # the live joint states follow the move from where it started to its target
    assert j1[0] == pytest.approx(q0[0], abs=0.05)
    assert js[-1]["position_rad"] == pytest.approx(TARGET, abs=2e-3)
    assert max(abs(v) for m in js for v in m["velocity_rad_s"] if v is not None) > 0.05
    assert max(abs(e) for m in js for e in m["following_error_rad"]) > 1e-5  # commanded minus measured, live
    # one /tf per joint state, with its time stamp; the two are sent back to back, so a
    # collecting window may end between them: at most the first and the last may lack a partner
    def stamp(m: dict[str, Any]) -> tuple[int, int]:
        return int(m["timestamp"]["sec"]), int(m["timestamp"]["nsec"])
    js_stamps = [stamp(m) for m in js]
    tf_stamps = [stamp(r.json()["transforms"][0]) for r in got if r.topic == "/tf"]
    lo, hi = max(js_stamps[0], tf_stamps[0]), min(js_stamps[-1], tf_stamps[-1])
    assert [t for t in tf_stamps if lo <= t <= hi] == [t for t in js_stamps if lo <= t <= hi]
    assert len([t for t in tf_stamps if not lo <= t <= hi]) <= 1
    assert len([t for t in js_stamps if not lo <= t <= hi]) <= 1
    assert any(r.json()["name"] == "moveAbsoluteComplete" for r in got if r.topic == "/notices")
    assert any(r.json()["signals"]["st_motion"] == 1 for r in got if r.topic == "/status")
    # Ctrl-C ends the view: exit 0, a summary line, no traceback
    assert view.returncode == 0, v_err
    assert "Traceback" not in v_err
    last = v_out.strip().splitlines()[-1]
    assert re.match(rf"view: served \d+ messages on {len(CHANNELS)} channels \(\d+ broadcasts, \d+ notices, "
                    r"0 CAN frames\) to 1 clients in [\d.]+ s at ws://127\.0\.0\.1:\d+$", last), last
    # the owner kept the device all along
    r = session.cli("session", "status")
    assert r.returncode == 0 and "connected: True  owner: True" in r.stdout, r.stdout


def test_without_a_session_the_view_opens_its_own_and_serves_the_can_frames(controller: Controller) -> None:
    """No background session: the view connects a session of its own, so the raw frames reach /can;
    --json prints the URL first and the counts per channel at the end."""
    view = subprocess.Popen([str(CLI), "--json", "--interface", "slcan", "--channel", controller.pty, "view", "--port",
                             "0", "--duration", "4"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert view.stdout is not None
    head = json.loads(view.stdout.readline())
    assert head["command"] == "view" and head["device"] == 0x10
    with FoxgloveClient(head["url"]) as client:
        client.handshake(len(CHANNELS))
        client.subscribe("/can", "/joint_states")
        got = client.messages(1.5)
    out, err = view.communicate(timeout=30)
    assert view.returncode == 0, err
    frames = [r.json() for r in got if r.topic == "/can"]
    assert len(frames) >= 7 * len([r for r in got if r.topic == "/joint_states"]) > 0
    joints_12 = tm.frame_id("JOINTS_12", pb.DEFAULT_DEVICE_ADDRESS)
    assert any(f["id"] == joints_12 and f["extended"] for f in frames)
    res = json.loads(out.strip().splitlines()[-1])["result"]
    assert res["clients"] == 1 and res["frames"] > 0 and set(res["channels"]) == set(CHANNELS)
