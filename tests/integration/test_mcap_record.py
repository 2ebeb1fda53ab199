"""`landscape record FILE.mcap` and `landscape demo --record FILE.mcap` against the running
landscaped: the recording read back with the `mcap` reader has every channel, with values that
agree with the run (the final notices of the joint moves, getRobotPosition at the end, FK of the
URDF for the tool pose)."""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader

from conftest import Controller
from landscape import telemetry as tm
from landscape.mcap_log import CHANNELS, read_mcap
from landscape.urdf import ArmChain


def _notice_joints(message: dict[str, object]) -> list[float] | None:
    for item in message.get("data", []):  # type: ignore[attr-defined]
        k, _, v = str(item).partition("=")
        if k == "joints":
            return [float(x) for x in v.split(",")]
    return None


def test_demo_recorded_to_mcap(controller: Controller, tmp_path: Path) -> None:
    rec, png = tmp_path / "demo.mcap", tmp_path / "demo.png"
    r = controller.cli("demo", "--record", str(rec), "--plot", str(png), timeout=180)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "0 failed" in r.stdout
    assert png.stat().st_size > 10_000 and (tmp_path / "demo-path.png").stat().st_size > 10_000
    where = controller.cli("--json", "get-robot-position")
    assert where.returncode == 0, where.stderr
    final_q = [float(v) for v in json.loads(where.stdout.splitlines()[0])["result"]["joints"]]

    with rec.open("rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None
    schemas = {c.topic: summary.schemas[c.schema_id].name for c in summary.channels.values()}
    assert schemas == CHANNELS
    counts = summary.statistics.channel_message_counts if summary.statistics else {}
    by_topic = {summary.channels[cid].topic: n for cid, n in counts.items()}
    assert all(by_topic.get(t, 0) > 0 for t in CHANNELS), by_topic

    msgs = read_mcap(rec)
    js = msgs["/joint_states"]
    assert len(js) > 50
    chain = ArmChain()
    lims = [(-3.0, 3.0), (-1.95, 1.95), (-1.95, 2.7), (-3.3, 3.3), (-2.2, 2.2), (-6.2, 6.2)]
    for _, m in js:
        assert m["name"] == [f"joint{i}" for i in range(1, 7)]
        assert all(lo < q < hi for q, (lo, hi) in zip(m["position_rad"], lims, strict=True))
        assert all(v is None or abs(v) < 6.5 for v in m["velocity_rad_s"])  # under the fastest joint's limit
    dev = [m["device_time_ms"] for _, m in js]
    assert dev == sorted(dev) and len(set(dev)) == len(dev)
    # the arm moved, and the recorded velocity shows it
    assert max(abs(v) for _, m in js for v in m["velocity_rad_s"] if v is not None) > 0.05

    # every joint move's final notice: the joint state recorded just before it is where the move ended
    finals = [(t, m) for t, m in msgs["/notices"] if m["name"] in ("moveAbsoluteComplete", "moveRelativeComplete")]
    assert len(finals) >= 3
    for t, m in finals:
        q_notice = _notice_joints(m)
        assert q_notice is not None, m
        before = [s for s in js if s[0] <= t]
        assert before, "no joint state before the final notice"
        assert before[-1][1]["position_rad"] == pytest.approx(q_notice, abs=2e-3), m["message"]
    assert any(m["name"] == "tag" for _, m in msgs["/notices"])
    # the end of the recording is where getRobotPosition says the arm is
    assert js[-1][1]["position_rad"] == pytest.approx(final_q, abs=1e-5)
    # commanded positions (JOINTS_CMD_12/34/56) in every joint state; the following error is their difference
    # from the measured ones: small on the simulated arm (about -velocity x 1 ms), nonzero while it moves
    for _, m in js:
        assert m["following_error_rad"] == pytest.approx(
            [c - q for c, q in zip(m["command_rad"], m["position_rad"], strict=True)], abs=1e-9)
    fe = [abs(e) for _, m in js for e in m["following_error_rad"]]
    assert 1e-5 < max(fe) < 0.01, max(fe)
    assert js[-1][1]["command_rad"] == pytest.approx(final_q, abs=1e-4)
    fol = tmp_path / "following.png"
    r = controller.cli("plot", str(rec), "-o", str(fol), "--kind", "following")
    assert r.returncode == 0 and r.stdout.strip() == f"plot: wrote {fol} (following)", r.stderr
    assert fol.stat().st_size > 10_000

    # /tf composes to the URDF FK of the same joints, and the tool pose agrees with it (TOOL_POS: 0.1 mm steps)
    t_last, tf = msgs["/tf"][-1]
    q_last = [m for t, m in js if t == t_last][0]["position_rad"]
    T = np.eye(4)
    for x in tf["transforms"]:
        tr, rq = x["translation"], x["rotation"]
        qx, qy, qz, qw = rq["x"], rq["y"], rq["z"], rq["w"]
        M = np.eye(4)
        M[:3, :3] = [[1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)],
                     [2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)],
                     [2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)]]
        M[:3, 3] = [tr["x"], tr["y"], tr["z"]]
        T = T @ M
    assert np.allclose(T, chain.fk(q_last), atol=1e-9)
    pos = msgs["/tool_pose"][-1][1]["pose"]["position"]
    assert [pos["x"], pos["y"], pos["z"]] == pytest.approx(list(chain.fk(final_q)[:3, 3]), abs=2e-4)

    st = msgs["/status"][-1][1]["signals"]
    assert {"st_state", "st_motion", "st_fault"} <= st.keys() and st["st_fault"] == 0
    assert all(isinstance(m["inputs"], int) and isinstance(m["outputs"], int) for _, m in msgs["/dio"])
    ids = {m["id"] for _, m in msgs["/can"]}
    assert len(msgs["/can"]) >= 9 * len(js)  # 10 telemetry frames per cycle, plus ISO-TP
    assert any(i & tm.ID_MASK == tm.frame_id("JOINTS_12", 0) for i in ids)


def test_record_command_writes_mcap_with_a_summary(controller: Controller, tmp_path: Path) -> None:
    out = tmp_path / "idle.mcap"
    r = controller.cli("record", str(out), "--duration", "1.5", timeout=60)
    assert r.returncode == 0, r.stderr
    line = r.stdout.strip().splitlines()[-1]
    assert line.startswith("record: ") and "CAN frames" in line and f"on {len(CHANNELS)} channels" in line
    msgs = read_mcap(out)
    n = len(msgs["/joint_states"])
    assert 30 <= n <= 100, n  # 50 Hz telemetry for 1.5 s
    assert len(msgs["/tf"]) == n and len(msgs["/can"]) >= 10 * n - 10
    q = msgs["/joint_states"][-1][1]["position_rad"]
    assert all(math.isfinite(v) for v in q)
    j = controller.cli("--json", "record", str(tmp_path / "j.mcap"), "--duration", "0.5")
    res = json.loads(j.stdout.splitlines()[-1])["result"]
    assert res["frames"] > 0 and set(res["channels"]) == set(CHANNELS)
