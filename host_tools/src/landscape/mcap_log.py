"""Recording to MCAP (what Foxglove and ROS 2 bags use) and reading it back.

Channels, JSON-encoded, each with a JSON schema (Foxglove's well-known schemas where one fits):

==================  ========================  ===============================================================
topic               schema                    what
==================  ========================  ===============================================================
/joint_states       landscape.JointState      one per telemetry cycle: joint positions [rad] (JOINTS_12/34/56),
                                              velocities [rad/s] derived from consecutive positions over the
                                              device clock (TOOL_POS.tool_time_ms), the device time [ms], the
                                              commanded positions [rad] (JOINTS_CMD_12/34/56) and the following
                                              error (commanded minus measured) [rad], null from a device that
                                              does not send JOINTS_CMD
/tf                 foxglove.FrameTransforms  one transform per URDF joint at those positions (a 3D panel with
                                              the device's URDF, `landscape urdf`, draws the arm)
/tool_pose          foxglove.PoseInFrame      the tool tip (TOOL_POS + TOOL_RPY) in frame base_link
/status             landscape.Status          the STATUS broadcast
/dio                landscape.DigitalIO       the DIO broadcast (input and output bit masks)
/notices            foxglove.Log              every notice (events, alarms, RSVP), name = event_id
/can                landscape.CanFrame        every CAN frame received (id, flags, data as hex)
==================  ========================  ===============================================================

Log times are the host's wall clock (ns since the epoch) of arrival. A recording of a device that sent
its URDF (describeRobot) carries it as the attachment `robot.urdf` (URDF_ATTACHMENT).
"""
from __future__ import annotations

import abc
import json
import math
import threading
import time
from pathlib import Path
from typing import IO, Any

import can

from . import telemetry as tm
from ._generated import landscape_pb2 as pb
from .errors import LandscapeError
from .recording import Recording
from .urdf import BASE_FRAME, ArmChain, rpy_matrix

JOINT_NAMES: tuple[str, ...] = tuple(f"joint{i}" for i in range(1, 7))
JOINT_SIGNALS: dict[str, tuple[str, ...]] = {"JOINTS_12": ("j1", "j2"), "JOINTS_34": ("j3", "j4"),
                                             "JOINTS_56": ("j5", "j6")}
COMMAND_SIGNALS: dict[str, tuple[str, ...]] = {"JOINTS_CMD_12": ("j1_cmd", "j2_cmd"),
                                               "JOINTS_CMD_34": ("j3_cmd", "j4_cmd"),
                                               "JOINTS_CMD_56": ("j5_cmd", "j6_cmd")}
URDF_ATTACHMENT = "robot.urdf"
LOG_LEVEL = {pb.EVENT: 2, pb.EVENT_RSVP: 2, pb.ALARM: 3, pb.ALARM_RSVP: 3}  # foxglove.Log: INFO, WARNING

_TIME = {"type": "object", "title": "time", "properties": {"sec": {"type": "integer", "minimum": 0},
                                                            "nsec": {"type": "integer", "minimum": 0}}}
_VEC3 = {"type": "object", "properties": {k: {"type": "number"} for k in "xyz"}}
_QUAT = {"type": "object", "properties": {k: {"type": "number"} for k in "xyzw"}}
_POSE = {"type": "object", "properties": {"position": _VEC3, "orientation": _QUAT}}
_NUMS = {"type": "array", "items": {"type": ["number", "null"]}}
_NUMS_OR_NULL = {"type": ["array", "null"], "items": {"type": "number"}}

SCHEMAS: dict[str, dict[str, Any]] = {
    "landscape.JointState": {
        "type": "object", "title": "landscape.JointState",
        "description": "Joint positions of one telemetry cycle; velocities derived on the host; commanded "
                       "positions and the following error (commanded minus measured) where the device sends them",
        "properties": {"timestamp": _TIME, "device_time_ms": {"type": "integer"},
                       "name": {"type": "array", "items": {"type": "string"}},
                       "position_rad": _NUMS, "velocity_rad_s": _NUMS, "command_rad": _NUMS_OR_NULL,
                       "following_error_rad": _NUMS_OR_NULL}},
    "foxglove.FrameTransforms": {
        "type": "object", "title": "foxglove.FrameTransforms",
        "properties": {"transforms": {"type": "array", "items": {
            "type": "object", "title": "foxglove.FrameTransform",
            "properties": {"timestamp": _TIME, "parent_frame_id": {"type": "string"},
                           "child_frame_id": {"type": "string"}, "translation": _VEC3, "rotation": _QUAT}}}}},
    "foxglove.PoseInFrame": {
        "type": "object", "title": "foxglove.PoseInFrame",
        "properties": {"timestamp": _TIME, "frame_id": {"type": "string"}, "pose": _POSE}},
    "landscape.Status": {
        "type": "object", "title": "landscape.Status", "description": "The STATUS broadcast (protocol/landscape.dbc)",
        "properties": {"timestamp": _TIME, "signals": {"type": "object"}}},
    "landscape.DigitalIO": {
        "type": "object", "title": "landscape.DigitalIO", "description": "The DIO broadcast: bit masks",
        "properties": {"timestamp": _TIME, "inputs": {"type": "integer"}, "outputs": {"type": "integer"}}},
    "foxglove.Log": {
        "type": "object", "title": "foxglove.Log",
        "properties": {"timestamp": _TIME, "level": {"type": "integer", "description": "0 unknown .. 5 fatal"},
                       "message": {"type": "string"}, "name": {"type": "string"}, "file": {"type": "string"},
                       "line": {"type": "integer"},
                       "data": {"type": "array", "items": {"type": "string"},
                                "description": "landscape: the notice's key=value data"}}},
    "landscape.CanFrame": {
        "type": "object", "title": "landscape.CanFrame", "description": "A raw CAN frame as received",
        "properties": {"timestamp": _TIME, "id": {"type": "integer"}, "extended": {"type": "boolean"},
                       "remote": {"type": "boolean"}, "error": {"type": "boolean"}, "dlc": {"type": "integer"},
                       "data": {"type": "string", "description": "hex"}}},
}
CHANNELS: dict[str, str] = {"/joint_states": "landscape.JointState", "/tf": "foxglove.FrameTransforms",
                            "/tool_pose": "foxglove.PoseInFrame", "/status": "landscape.Status",
                            "/dio": "landscape.DigitalIO", "/notices": "foxglove.Log", "/can": "landscape.CanFrame"}


class McapError(LandscapeError):
    """An MCAP recording cannot be written or read."""


def _stamp(ns: int) -> dict[str, int]:
    return {"sec": ns // 1_000_000_000, "nsec": ns % 1_000_000_000}


def _quat_from_rpy(roll: float, pitch: float, yaw: float) -> dict[str, float]:
    from .urdf import quaternion_xyzw

    x, y, z, w = quaternion_xyzw(rpy_matrix(roll, pitch, yaw))
    return {"x": x, "y": y, "z": z, "w": w}


def channel_schemas() -> list[tuple[str, str, bytes]]:
    """(topic, schema name, JSON schema as bytes) of every channel, in CHANNELS order: what the MCAP file
    registers and what the live view (view.py) advertises, byte for byte."""
    return [(topic, schema, json.dumps(SCHEMAS[schema]).encode()) for topic, schema in CHANNELS.items()]


class ChannelWriter(abc.ABC):
    """Turns broadcasts, notices and CAN frames into the messages of the channels above (thread-safe) and
    hands each to `_write` as (topic, log time in ns since the epoch, JSON bytes). The one encoder of
    McapRecorder (a file) and view.LiveView (a Foxglove WebSocket server). The same calls as
    recording.Recorder (broadcast, notice, close) plus frame(). A context manager."""

    def __init__(self, *, start_s: float | None = None, chain: ArmChain | None = None) -> None:
        self.start_s = time.monotonic() if start_s is None else start_s
        self._epoch_offset_s = time.time() - time.monotonic()
        self.chain = chain or ArmChain()
        self.urdf: str | None = None  # the device's, once use_robot() had it
        self.counts: dict[str, int] = dict.fromkeys(CHANNELS, 0)
        self.broadcasts = 0
        self.notices = 0
        self.frames = 0
        self._lock = threading.Lock()
        self._q: dict[str, float] = {}
        self._q_cmd: dict[str, float] = {}
        self._last: tuple[int, list[float]] | None = None  # (device ms, q) of the previous joint state
        self._dev_last: int | None = None
        self._dev_wraps = 0
        self._tool_pos: dict[str, float] | None = None
        self._closed = False

    def use_robot(self, urdf: str) -> None:
        """Publish the transforms of this URDF's chain (the device's, Supervisor.robot_urdf) from now on.
        UrdfError when it is not a serial arm; call it before feeding anything."""
        self.chain = ArmChain(urdf)
        self.urdf = urdf

    def __enter__(self) -> ChannelWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    @property
    def messages(self) -> int:
        return sum(self.counts.values())

    @abc.abstractmethod
    def _write(self, topic: str, ns: int, data: bytes, sequence: int) -> None:
        """Deliver one message (called with the lock held): each sink's own."""

    @abc.abstractmethod
    def _finish(self) -> None:
        """Close the sink (called once, with the lock held): each sink's own."""

    def close(self) -> None:
        with self._lock:
            if self._closed:
                return
            self._closed = True
            self._finish()

    def _ns(self, monotonic_s: float) -> int:
        return int((monotonic_s + self._epoch_offset_s) * 1e9)

    def _put(self, topic: str, ns: int, obj: dict[str, Any]) -> None:
        self._write(topic, ns, json.dumps(obj, allow_nan=False).encode(), self.counts[topic])
        self.counts[topic] += 1

    def _device_ms(self, raw: Any) -> int:
        ms = int(raw) & 0xFFFF
        if self._dev_last is not None and ms < self._dev_last:
            self._dev_wraps += 1
        self._dev_last = ms
        return ms + self._dev_wraps * 0x10000

    def broadcast(self, b: tm.Broadcast) -> None:
        """A decoded broadcast: joints are gathered until TOOL_POS closes the cycle (the device sends
        STATUS, JOINTS_12/34/56, JOINTS_CMD_12/34/56, TOOL_POS, TOOL_RPY, DIO from one snapshot)."""
        with self._lock:
            if self._closed:
                return
            ns, s = self._ns(b.timestamp), b.signals
            if b.name in JOINT_SIGNALS:
                for sig in JOINT_SIGNALS[b.name]:
                    self._q[sig] = float(s[sig])
            elif b.name in COMMAND_SIGNALS:
                for sig in COMMAND_SIGNALS[b.name]:
                    self._q_cmd[sig] = float(s[sig])
            elif b.name == "TOOL_POS":
                self._tool_pos = {k: float(s[k]) for k in ("tool_x", "tool_y", "tool_z")}
                dev = self._device_ms(s["tool_time_ms"])
                if len(self._q) == 6:
                    cmd = [self._q_cmd[f"j{i}_cmd"] for i in range(1, 7)] if len(self._q_cmd) == 6 else None
                    self._joint_state(ns, dev, [self._q[f"j{i}"] for i in range(1, 7)], cmd)
                self._q = {}
                self._q_cmd = {}
            elif b.name == "TOOL_RPY" and self._tool_pos is not None:
                p = self._tool_pos
                self._put("/tool_pose", ns, {
                    "timestamp": _stamp(ns), "frame_id": BASE_FRAME,
                    "pose": {"position": {"x": p["tool_x"], "y": p["tool_y"], "z": p["tool_z"]},
                             "orientation": _quat_from_rpy(float(s["tool_roll"]), float(s["tool_pitch"]),
                                                           float(s["tool_yaw"]))}})
                self._tool_pos = None
            elif b.name == "STATUS":
                self._put("/status", ns, {"timestamp": _stamp(ns), "signals": {k: int(v) for k, v in s.items()}})
            elif b.name == "DIO":
                self._put("/dio", ns, {"timestamp": _stamp(ns), "inputs": int(s["dio_inputs"]),
                                       "outputs": int(s["dio_outputs"])})
            else:
                return
            self.broadcasts += 1

    def _joint_state(self, ns: int, dev_ms: int, q: list[float], cmd: list[float] | None) -> None:
        vel: list[float | None] = [None] * 6
        if self._last is not None and dev_ms > self._last[0]:
            dt_s = (dev_ms - self._last[0]) / 1000.0
            vel = [(a - b) / dt_s for a, b in zip(q, self._last[1], strict=True)]
        self._last = (dev_ms, q)
        self._put("/joint_states", ns, {"timestamp": _stamp(ns), "device_time_ms": dev_ms, "name": list(JOINT_NAMES),
                                        "position_rad": q, "velocity_rad_s": vel, "command_rad": cmd,
                                        "following_error_rad": None if cmd is None else
                                        [c - m for c, m in zip(cmd, q, strict=True)]})
        self._put("/tf", ns, {"transforms": [
            {"timestamp": _stamp(ns), "parent_frame_id": t.parent, "child_frame_id": t.child,
             "translation": dict(zip("xyz", t.translation_m, strict=True)),
             "rotation": dict(zip("xyzw", t.rotation_xyzw, strict=True))} for t in self.chain.transforms(q)]})

    def notice(self, n: pb.Notice, timestamp: float | None = None) -> None:
        ts = time.monotonic() if timestamp is None else timestamp
        with self._lock:
            if self._closed:
                return
            ns = self._ns(ts)
            kind = pb.NoticeKind.Name(n.kind)
            text = f"{kind} {n.event_id}" + (f": {' '.join(n.data)}" if n.data else "")
            if n.ref_seq:
                text += f" (request {n.ref_seq}{', final' if n.final else ''})"
            if n.kind in (pb.EVENT_RSVP, pb.ALARM_RSVP):
                text += f" rsvp_id={n.rsvp_id} timeout={n.rsvp_timeout_ms} ms"
            self._put("/notices", ns, {"timestamp": _stamp(ns), "level": LOG_LEVEL.get(n.kind, 0), "message": text,
                                       "name": n.event_id, "file": "", "line": 0, "data": list(n.data)})
            self.notices += 1

    def frame(self, msg: can.Message) -> None:
        """A raw CAN frame as received (a can.Listener-style callback)."""
        ts = msg.timestamp if msg.timestamp and msg.timestamp < time.monotonic() + 1 else time.monotonic()
        with self._lock:
            if self._closed:
                return
            ns = self._ns(ts)
            self._put("/can", ns, {"timestamp": _stamp(ns), "id": int(msg.arbitration_id),
                                   "extended": bool(msg.is_extended_id), "remote": bool(msg.is_remote_frame),
                                   "error": bool(msg.is_error_frame), "dlc": int(msg.dlc),
                                   "data": bytes(msg.data).hex()})
            self.frames += 1



class McapRecorder(ChannelWriter):
    """Writes the channels above to an MCAP file (zstd chunks) as broadcasts, notices and frames arrive."""

    def __init__(self, path: str | Path, *, start_s: float | None = None, chain: ArmChain | None = None) -> None:
        from mcap.writer import CompressionType, Writer

        super().__init__(start_s=start_s, chain=chain)
        self.path = Path(path)
        try:
            self._f: IO[bytes] = self.path.open("wb")
        except OSError as exc:
            raise McapError(f"cannot write {path}: {exc.strerror or exc}") from None
        self._w = Writer(self._f, compression=CompressionType.ZSTD)
        self._w.start(profile="", library="landscape")
        self._chan: dict[str, int] = {}
        for topic, schema, data in channel_schemas():
            sid = self._w.register_schema(name=schema, encoding="jsonschema", data=data)
            self._chan[topic] = self._w.register_channel(topic=topic, message_encoding="json", schema_id=sid)

    def __enter__(self) -> McapRecorder:
        return self

    def use_robot(self, urdf: str) -> None:
        super().use_robot(urdf)
        ns = time.time_ns()
        self._w.add_attachment(create_time=ns, log_time=ns, name=URDF_ATTACHMENT, media_type="application/xml",
                               data=urdf.encode("utf-8"))

    def _write(self, topic: str, ns: int, data: bytes, sequence: int) -> None:
        self._w.add_message(channel_id=self._chan[topic], log_time=ns, publish_time=ns, data=data, sequence=sequence)

    def _finish(self) -> None:
        try:
            self._w.finish()  # type: ignore[no-untyped-call]  # mcap 1.6 leaves it unannotated
        finally:
            self._f.close()


def read_mcap(path: str | Path) -> dict[str, list[tuple[int, dict[str, Any]]]]:
    """Every message of a recording, by topic: (log_time ns, decoded JSON) in log-time order."""
    from mcap.exceptions import McapError as ReaderError
    from mcap.reader import make_reader

    p = Path(path)
    out: dict[str, list[tuple[int, dict[str, Any]]]] = {}
    try:
        f = p.open("rb")
    except OSError as exc:
        raise McapError(f"cannot read {p}: {exc.strerror or exc}") from None
    with f:
        try:
            reader = make_reader(f)
            for _schema, channel, message in reader.iter_messages(log_time_order=True):
                if channel.message_encoding != "json":
                    continue
                out.setdefault(channel.topic, []).append((message.log_time, json.loads(message.data)))
        except (ReaderError, ValueError, EOFError) as exc:
            raise McapError(f"{p}: not a readable MCAP file ({exc}): record one with `landscape record FILE.mcap`") \
                from None
    return out


def finite(v: Any) -> float | None:
    """A JSON number as float, None for null (a velocity with no previous sample)."""
    return None if v is None or not math.isfinite(float(v)) else float(v)


def recording_from_mcap(path: str | Path) -> Recording:
    """A recording of McapRecorder as a recording.Recording (t_s from its first message), for plotting."""
    p = Path(path)
    msgs = read_mcap(p)
    if not any(topic in msgs for topic in CHANNELS):
        raise McapError(f"{p}: no channel of `landscape record` ({', '.join(CHANNELS)}) in it")
    t0 = min(v[0][0] for v in msgs.values() if v)
    rec = Recording(p)
    try:
        for ns, m in msgs.get("/joint_states", []):
            t = (ns - t0) / 1e9
            q = [float(v) for v in m["position_rad"]]
            rec.joint_states.append((t, q, [finite(v) for v in m["velocity_rad_s"]]))
            for name, sigs in JOINT_SIGNALS.items():
                rec.series.setdefault(name, []).append((t, {sig: q[int(sig[1]) - 1] for sig in sigs}))
            cmd = m.get("command_rad")
            if cmd is not None:
                for name, sigs in COMMAND_SIGNALS.items():
                    rec.series.setdefault(name, []).append((t, {sig: float(cmd[int(sig[1]) - 1]) for sig in sigs}))
        for ns, m in msgs.get("/tool_pose", []):
            pos = m["pose"]["position"]
            rec.series.setdefault("TOOL_POS", []).append(
                ((ns - t0) / 1e9, {"tool_x": float(pos["x"]), "tool_y": float(pos["y"]), "tool_z": float(pos["z"])}))
        for ns, m in msgs.get("/notices", []):
            data: dict[str, str] = {}
            for item in m.get("data", []):
                k, _, v = str(item).partition("=")
                data[k] = v
            rec.notices.append(((ns - t0) / 1e9, str(m["name"]), data))
    except (KeyError, TypeError, ValueError, IndexError) as exc:
        raise McapError(f"{p}: a message does not have the layout of `landscape record` ({exc})") from None
    return rec
