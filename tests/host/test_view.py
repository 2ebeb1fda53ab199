"""The live Foxglove view without a controller: LiveView fed with the same broadcasts, notices and frames as
an McapRecorder publishes the same channels (schemas byte for byte) and the same messages to a WebSocket
client; it serves the URDF the layout loads; a taken port is one line. The layout file: Foxglove's
layout shape, checked against foxglove-sdk's own layout types, naming only published topics and fields."""
from __future__ import annotations

import dataclasses
import json
import re
import socket
import subprocess
import sys
import time
import types
import typing
from pathlib import Path
from typing import Any

import foxglove.layouts as fl
import pytest

from foxglove_client import FoxgloveClient
from landscape._generated import landscape_pb2 as pb
from landscape.mcap_log import CHANNELS, SCHEMAS, McapRecorder, channel_schemas, read_mcap
from landscape.urdf import urdf_text
from landscape.view import (
    LAYOUT_NAME,
    LEGACY_SUBPROTOCOL,
    SUBPROTOCOL,
    URDF_URI,
    LiveView,
    ViewError,
    layout_text,
)
from test_mcap import _cycle

ROOT = Path(__file__).resolve().parents[2]
LAYOUT_FILE = ROOT / "host_tools" / "src" / "landscape" / "data" / LAYOUT_NAME


class Both:
    """Feeds two channel writers alike."""

    def __init__(self, *writers: Any) -> None:
        self.writers = writers

    def frame(self, msg: Any) -> None:
        for w in self.writers:
            w.frame(msg)

    def broadcast(self, b: Any) -> None:
        for w in self.writers:
            w.broadcast(b)

    def notice(self, n: Any, ts: float | None = None) -> None:
        for w in self.writers:
            w.notice(n, ts)


def _no_stamps(v: Any) -> Any:
    """A message without its log-time stamps (the two writers' wall-clock offsets differ by microseconds)."""
    if isinstance(v, dict):
        return {k: _no_stamps(x) for k, x in v.items() if k != "timestamp"}
    if isinstance(v, list):
        return [_no_stamps(x) for x in v]
    return v


def test_the_live_view_publishes_the_channels_and_messages_of_the_mcap_recording(tmp_path: Path) -> None:
    with LiveView(port=0) as view:
        assert view.port > 0 and view.url == f"ws://127.0.0.1:{view.port}"
        with FoxgloveClient(view.url) as client:
            client.handshake(len(CHANNELS))
            # the advertised channels are the recording's: topic, schema name, schema text, encoding
            assert {t: (c["schemaName"], c["schemaEncoding"], c["schema"], c["encoding"])
                    for t, c in client.channels.items()} == \
                {t: (name, "jsonschema", data.decode(), "json") for t, name, data in channel_schemas()}
            client.subscribe(*CHANNELS)
            client.messages(0.3)  # the subscriptions take effect
            assert view.clients == 1
            with McapRecorder(tmp_path / "r.mcap", start_s=0.0) as rec:
                both = Both(view, rec)
                for k in range(10):
                    _cycle(both, 100.0 + 0.02 * k, 1000 + 20 * k, [0.01 * k, 0.2, 0.3, 0.0, 0.9, -0.1])  # type: ignore[arg-type]
                both.notice(pb.Notice(kind=pb.EVENT, event_id="tag", data=["tag=p1"], ref_seq=3), 100.1)
            got = client.messages(1.0)
            status, err, urdf = client.fetch_asset(URDF_URI)
            missing = client.fetch_asset("package://landscape/nothing.urdf")
    live: dict[str, list[Any]] = {}
    for m in got:
        live.setdefault(m.topic, []).append(_no_stamps(m.json()))
    recorded = {t: [_no_stamps(m) for _, m in v] for t, v in read_mcap(tmp_path / "r.mcap").items()}
    assert {t: len(v) for t, v in live.items()} == {t: len(v) for t, v in recorded.items()}
    assert live == recorded
    assert live["/joint_states"][-1]["position_rad"][0] == pytest.approx(0.09)
    assert (status, err, urdf.decode()) == (0, "", urdf_text())
    assert missing[0] == 1
    assert view.messages == sum(len(v) for v in recorded.values())


VIEWER_CLIENT = ROOT / "tests" / "viewer" / "client.mjs"  # @foxglove/ws-protocol's client (npm), set up by .ci/setup


@pytest.mark.parametrize("subprotocol", [LEGACY_SUBPROTOCOL, SUBPROTOCOL])
def test_a_viewer_may_ask_for_either_name_of_the_protocol(subprotocol: str) -> None:
    """Lichtblick and Foxglove before the SDK ask for foxglove.websocket.v1, the Foxglove app for
    foxglove.sdk.v1 (docs/host-tool.md "view"): both get the same server; a client asking for
    neither is refused, as by foxglove-sdk's server."""
    from websockets.exceptions import InvalidStatus
    from websockets.sync.client import connect

    with LiveView(port=0) as view:
        with connect(view.url, subprotocols=[subprotocol], open_timeout=5) as ws:  # type: ignore[list-item]
            assert ws.subprotocol == subprotocol
            assert json.loads(ws.recv(timeout=5))["op"] == "serverInfo"
        with pytest.raises(InvalidStatus, match="400"):
            connect(view.url, subprotocols=["foxglove.websocket.v2"], open_timeout=5)  # type: ignore[list-item]


def test_the_ws_protocol_client_from_npm_sees_the_channels_messages_and_urdf() -> None:
    """The published client of the protocol's first name (@foxglove/ws-protocol, under node),
    which no one here wrote, against the live view: handshake, advertise, a message, the URDF."""
    assert (VIEWER_CLIENT.parent / "node_modules" / "@foxglove" / "ws-protocol").is_dir(), \
        "the npm client is not installed: run bash .ci/setup"
    with LiveView(port=0) as view:
        proc = subprocess.Popen(["node", str(VIEWER_CLIENT), view.url, "/notices", URDF_URI],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        try:
            deadline = time.monotonic() + 15
            k = 0
            while proc.poll() is None and time.monotonic() < deadline:  # until it has subscribed and got one
                view.notice(pb.Notice(kind=pb.EVENT, event_id="tag", data=[f"tag=p{k}"], ref_seq=3), 100.0 + k)
                k += 1
                time.sleep(0.05)
            out, err = proc.communicate(timeout=15)
        finally:
            if proc.poll() is None:
                proc.kill()
    assert proc.returncode == 0, err
    got = json.loads(out)
    assert got["subprotocol"] == LEGACY_SUBPROTOCOL and got["server"] == "landscape"
    assert set(got["topics"]) == set(CHANNELS)
    assert json.loads(got["message"])["name"] == "tag"
    assert got["asset_bytes"] == len(urdf_text().encode())


def test_a_taken_port_is_one_line_before_the_bus_is_opened() -> None:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        port = s.getsockname()[1]
        with pytest.raises(ViewError, match=rf"127.0.0.1:{port}: .*in use.*--port"):
            LiveView(port=port)
        cli = Path(sys.executable).parent / "landscape"
        r = subprocess.run([str(cli), "--interface", "slcan", "--channel", "/nonexistent/pty", "view", "--port",
                            str(port)], capture_output=True, text=True, timeout=60)
    assert r.returncode == 1, r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in r.stderr
    assert re.search(rf"cannot serve the live view on 127.0.0.1:{port}: .*in use.*pass --port N", lines[0]), lines


def test_write_layout_writes_the_packaged_layout(tmp_path: Path) -> None:
    cli = Path(sys.executable).parent / "landscape"
    r = subprocess.run([str(cli), "view", "--write-layout", str(tmp_path / "l.json")], capture_output=True,
                       text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "l.json").read_text() == layout_text() == LAYOUT_FILE.read_text()


# ---------------------------------------------------------------- the layout file

#: The panel types of the layout and the foxglove-sdk config type of each (the SDK's layout types are
#: generated from the app's panel settings; ids in an exported layout are "<panel type>!<id>", the Log
#: panel's type is RosOut).
PANEL_CONFIGS: dict[str, type] = {"3D": fl.ThreeDeeConfig, "Plot": fl.PlotConfig, "RosOut": fl.LogConfig}
LAYERS: dict[str, type] = {"foxglove.Grid": fl.BaseRendererGridLayerSettings,
                           "foxglove.Urdf": fl.BaseRendererUrdfLayerSettings}


def _camel(name: str) -> str:
    head, *rest = name.split("_")
    return head + "".join(w[:1].upper() + w[1:] for w in rest)


def _check(obj: dict[str, Any], cls: type, where: str, skip: frozenset[str] = frozenset()) -> None:
    """Every key of obj is a field of the SDK type cls (as the SDK serialises it), every value of a Literal
    field one of its values; nested SDK types are checked the same way."""
    hints = typing.get_type_hints(cls, vars(fl))
    fields = {_camel(f.name): f.name for f in dataclasses.fields(cls)}
    for key, value in obj.items():
        if key in skip:
            continue
        assert key in fields, f"{where}: '{key}' is not a setting of {cls.__name__} ({sorted(fields)})"
        _check_value(value, hints[fields[key]], f"{where}.{key}")


def _check_value(value: Any, hint: Any, where: str) -> None:
    options = typing.get_args(hint) if typing.get_origin(hint) in (typing.Union, types.UnionType) else (hint,)
    literals = [a for o in options if typing.get_origin(o) is typing.Literal for a in typing.get_args(o)]
    if literals and isinstance(value, str):
        assert value in literals, f"{where}: '{value}' is not one of {literals}"
    for o in options:
        if dataclasses.is_dataclass(o) and isinstance(value, dict):
            _check(value, o, where)  # type: ignore[arg-type]
        elif typing.get_origin(o) is list and isinstance(value, list):
            (item,) = typing.get_args(o)
            if dataclasses.is_dataclass(item):
                for i, v in enumerate(value):
                    _check(v, item, f"{where}[{i}]")  # type: ignore[arg-type]


def _leaves(node: Any) -> list[str]:
    if isinstance(node, str):
        return [node]
    assert set(node) <= {"direction", "first", "second", "splitPercentage"} and node["direction"] in ("row", "column")
    return _leaves(node["first"]) + _leaves(node["second"])


def _field_exists(topic: str, path: str) -> bool:
    """`position_rad[0]` exists in the JSON schema of the topic."""
    node: Any = SCHEMAS[CHANNELS[topic]]
    for part in path.split("."):
        name = re.sub(r"\[\d+\]$", "", part)
        node = node.get("properties", {}).get(name)
        if node is None:
            return False
        if part != name:
            node = node.get("items", {})
    return True


def test_the_layout_has_foxglove_s_shape_and_names_only_published_topics() -> None:
    layout = json.loads(LAYOUT_FILE.read_text())
    # an exported layout (Layouts > Export): what Layouts > Import from file reads
    assert set(layout) == {"configById", "globalVariables", "userNodes", "linkedGlobalVariables", "playbackConfig",
                           "layout"}
    assert sorted(_leaves(layout["layout"])) == sorted(layout["configById"])
    topics: set[str] = set()
    fields: list[tuple[str, str]] = []
    kinds = set()
    for panel_id, cfg in layout["configById"].items():
        kind = panel_id.split("!", 1)[0]
        kinds.add(kind)
        assert kind in PANEL_CONFIGS, panel_id
        _check(cfg, PANEL_CONFIGS[kind], panel_id, skip=frozenset({"layers", "topics"}) if kind == "3D" else
               frozenset())
        if kind == "3D":
            for lid, layer in cfg["layers"].items():
                _check(layer, LAYERS[layer["layerId"]], f"{panel_id}.layers.{lid}")
            for topic, settings in cfg["topics"].items():
                assert CHANNELS[topic] == "foxglove.PoseInFrame", topic
                _check(settings, fl.BaseRendererPoseTopicSettings, f"{panel_id}.topics.{topic}")
                topics.add(topic)
            urdf = [layer for layer in cfg["layers"].values() if layer["layerId"] == "foxglove.Urdf"]
            assert [u["url"] for u in urdf] == [URDF_URI] and cfg["followTf"] == "base_link"
        elif kind == "Plot":
            for p in cfg["paths"]:
                topic, _, path = p["value"].partition(".")
                topics.add(topic)
                fields.append((topic, path))
        elif kind == "RosOut":
            topics.add(cfg["topicToRender"])
    assert kinds == {"3D", "Plot", "RosOut"}  # the 3D arm, joint plots, the event log
    assert topics <= set(CHANNELS), topics - set(CHANNELS)
    assert {"/joint_states", "/notices", "/tool_pose"} <= topics
    missing = [f"{t}.{p}" for t, p in fields if not _field_exists(t, p)]
    assert not missing, f"plot paths naming no field of the channel's schema: {missing}"
    # the 3D panel's transforms come from /tf (foxglove.FrameTransforms), which the server publishes
    assert CHANNELS["/tf"] == "foxglove.FrameTransforms"


def test_the_layout_check_catches_a_wrong_setting() -> None:
    """The checks above fail on a misspelt setting and an unknown value (they are not vacuous)."""
    with pytest.raises(AssertionError, match="'topicToRendr' is not a setting"):
        _check({"topicToRendr": "/notices"}, fl.LogConfig, "RosOut!x")
    with pytest.raises(AssertionError, match="'follow-nothing' is not one of"):
        _check({"followMode": "follow-nothing"}, fl.ThreeDeeConfig, "3D!x")
    with pytest.raises(AssertionError, match="'labl' is not a setting"):
        _check({"paths": [{"value": "/joint_states.position_rad[0]", "labl": "x"}]}, fl.PlotConfig, "Plot!x")
    assert not _field_exists("/joint_states", "position[0]")
    assert _field_exists("/joint_states", "position_rad[0]")


def test_without_foxglove_sdk_the_view_says_what_to_install(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "foxglove", None)  # import foxglove raises ImportError
    with pytest.raises(ViewError, match=r"needs the Python package foxglove-sdk: pip install 'landscape\[view\]'"):
        LiveView(port=0)
