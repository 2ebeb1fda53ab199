"""A small fake landscaped for the host tests: the same wire protocol, a tiny state machine.

It speaks ISO-TP (can-isotp, normal fixed 29-bit addressing) to a fixed set of
supervisor addresses and implements: connect/disconnect with version and hash
checks and one client per address (a connect with another client_nonce on a live
session's address is refused), heartbeat tracking (only a heartbeat carrying the
session's token keeps it; a session ends when they stop for longer than the
time-out; an owner's lock goes with it), lock,
release, activate, deactivate, get-motion-control-state, seq caching (a
retransmitted seq is answered from the cache, never executed twice), pathLoad
and pathClearPath (named paths, at most 32 points per message as the firmware),
describe (the limits of the committed landscape.options, no devices), describeRobot
(the packaged URDF of the default arm, in pieces of the size landscape.options gives) and two
non-blocking commands: moveAbsolute, which sends a tag event, an RSVP named
as a path's own `rsvp confirmMove` would be, and then its final event or alarm
(moveAbsoluteComplete, moveAbsoluteFailed, moveAbsoluteAborted), and pathMove,
which sends one tag event per tagged point and cycle, then pathMoveComplete.
Every notice carries an event id and data keys the schema declares (enum
ls.EventId, landscape.notices.undeclared); one that does not is refused, not
sent, and recorded in `undeclared` (the `device` fixture fails the test). It broadcasts HEARTBEAT, STATUS,
JOINTS_12/34/56, TOOL_POS (with a device time stamp), TOOL_RPY and DIO every
50 ms. Every other command answers CMD_NOT_IMPLEMENTED_ERR. Test knobs:
`drop_responses`, `silent`, `force_codes`, `version`, `schema_hash`,
`refuse_mismatch`, `point_time_s`.
"""
from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field
from typing import Any

import can
import isotp

from landscape import telemetry as tm
from landscape._generated import landscape_pb2 as pb
from landscape.bus import ISOTP_PARAMS
from landscape.limits import max_count, max_string_bytes
from landscape.notices import undeclared
from landscape.registry import PROTOCOL_VERSION, SCHEMA_HASH
from landscape.urdf import urdf_text

#: HEARTBEAT hb_role of a device and of a supervisor (the DBC's value table)
DEVICE_ROLE = tm.choice_value("HEARTBEAT", "hb_role", "device")
SUPERVISOR_ROLE = tm.choice_value("HEARTBEAT", "hb_role", "supervisor")


@dataclass
class Session:
    host: int
    last_seq: int = 0
    cached: bytes | None = None
    last_heartbeat: float = 0.0
    heartbeats: list[dict[str, Any]] = field(default_factory=list)
    notice_seq: int = 0
    nonce: int = 0       # ConnectReq.client_nonce: who this session is
    token: int = 0       # ConnectRes.heartbeat_token: what its heartbeats must carry


class FakeDevice:
    def __init__(self, bus: can.BusABC, notifier: can.Notifier, *, address: int = 0x10,
                 hosts: tuple[int, ...] = (0xF1,), heartbeat_timeout_ms: int = 1000,
                 move_time_s: float = 0.05, rsvp_timeout_ms: int = 300) -> None:
        self.bus = bus
        self.notifier = notifier
        self.address = address
        self.heartbeat_timeout_ms = heartbeat_timeout_ms
        self.move_time_s = move_time_s
        self.rsvp_timeout_ms = rsvp_timeout_ms
        # knobs
        self.version = PROTOCOL_VERSION
        self.schema_hash = SCHEMA_HASH
        self.refuse_mismatch = False     # answer CMD_VERSION_MISMATCH_ERR instead of a ConnectRes
        self.drop_responses = 0          # execute, then lose this many responses
        self.silent = False              # never answer
        self.force_codes: dict[str, tuple[int, str]] = {}  # field -> (ret_code, ret_msg)
        self.rewrite: tuple[bytes, bytes] | None = None  # replace these bytes of every answer (bad UTF-8)
        # observable state
        self.state = pb.IDLE
        self.owner: int | None = None
        self.executions: dict[str, int] = {}
        self.sessions: dict[int, Session] = {}
        self.heartbeats: dict[int, list[dict[str, Any]]] = {h: [] for h in hosts}
        self.rsvp_replies: list[pb.RsvpReply] = []
        self.rsvp_outcomes: list[str] = []  # per RSVP: "answered" in time, or "default"
        self.undeclared: list[str] = []     # notices refused: what the schema does not declare
        self.requests: list[pb.Request] = []
        self.uplink_sizes: list[int] = []   # bytes of every request message received
        self.hb_refused = 0                 # heartbeats without their session's token
        self._token_next = 0x0A0B01
        self.paths: dict[str, list[pb.TagPoint]] = {}
        self.max_points_per_path = 1000     # described (describe) and enforced alike
        self.point_time_s = 0.01
        self._t0 = time.monotonic()
        self._rsvp_waiters: dict[int, threading.Event] = {}
        self._rsvp_next = 1
        self._lock = threading.RLock()
        self._stop = threading.Event()
        self.stacks: dict[int, isotp.NotifierBasedCanStack] = {}
        for h in hosts:
            addr = isotp.Address(isotp.AddressingMode.NormalFixed_29bits, source_address=address,
                                 target_address=h)
            self.stacks[h] = isotp.NotifierBasedCanStack(bus, notifier, address=addr, params=dict(ISOTP_PARAMS))
        self._threads: list[threading.Thread] = []

    # ---------------------------------------------------------------- life cycle

    def start(self) -> FakeDevice:
        for h, s in self.stacks.items():
            s.start()
            t = threading.Thread(target=self._serve, args=(h, s), daemon=True)
            t.start()
            self._threads.append(t)
        self.notifier.add_listener(self._on_frame)
        t = threading.Thread(target=self._housekeeping, daemon=True)
        t.start()
        self._threads.append(t)
        return self

    def stop(self) -> None:
        self._stop.set()
        try:
            self.notifier.remove_listener(self._on_frame)
        except ValueError:
            pass
        for s in self.stacks.values():
            s.stop()
        for t in self._threads:
            t.join(2.0)

    def __enter__(self) -> FakeDevice:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    # ---------------------------------------------------------------- broadcasts

    def _on_frame(self, frame: can.Message) -> None:
        b = tm.decode(frame)
        if b is None or b.name != "HEARTBEAT" or b.signals.get("hb_role") != SUPERVISOR_ROLE:
            return
        with self._lock:
            if b.sender in self.heartbeats:
                self.heartbeats[b.sender].append(dict(b.signals))
            s = self.sessions.get(b.sender)
            if s is not None and b.signals.get("hb_token") == s.token:
                s.last_heartbeat = time.monotonic()
            elif s is not None:
                self.hb_refused += 1

    def _housekeeping(self) -> None:
        counter = 0
        while not self._stop.wait(0.05):
            with self._lock:
                now = time.monotonic()
                for h, s in list(self.sessions.items()):
                    if now - s.last_heartbeat > self.heartbeat_timeout_ms / 1000.0:
                        self._drop(h)
                state = self.state
                owner = self.owner or 0
            try:
                self.bus.send(tm.encode("HEARTBEAT", self.address, hb_role=DEVICE_ROLE, hb_counter=counter & 0xFF,
                                        hb_state=state, hb_owner=owner, hb_supervisors=len(self.sessions)))
                self.bus.send(tm.encode("STATUS", self.address, st_state=state, st_cycle_us=1000))
                self.bus.send(tm.encode("JOINTS_12", self.address, j1=0.5, j2=-0.25))
                k = counter % 100
                self.bus.send(tm.encode("JOINTS_34", self.address, j3=0.01 * k, j4=-0.02 * k))
                self.bus.send(tm.encode("JOINTS_56", self.address, j5=0.3, j6=0.001 * k))
                now_ms = int((time.monotonic() - self._t0) * 1000) & 0xFFFF
                self.bus.send(tm.encode("TOOL_POS", self.address, tool_x=0.4 + 0.001 * k, tool_y=0.002 * k,
                                        tool_z=0.6 - 0.001 * k, tool_time_ms=now_ms))
                self.bus.send(tm.encode("TOOL_RPY", self.address, tool_roll=0.1, tool_pitch=0.2, tool_yaw=0.3))
                self.bus.send(tm.encode("DIO", self.address, dio_inputs=0x5, dio_outputs=0xA0))
            except can.CanError:
                pass
            counter += 1

    def _drop(self, host: int) -> None:
        self.sessions.pop(host, None)
        if self.owner == host:
            self.owner = None
            self.state = pb.UNLOCKED
        if not self.sessions:
            self.state = pb.IDLE

    # ---------------------------------------------------------------- requests

    def _serve(self, host: int, stack: isotp.NotifierBasedCanStack) -> None:
        while not self._stop.is_set():
            data = stack.recv(block=True, timeout=0.05)
            if data is None:
                continue
            up = pb.Uplink()
            up.ParseFromString(bytes(data))
            if up.WhichOneof("msg") == "rsvp_reply":
                r = up.rsvp_reply
                with self._lock:
                    self.rsvp_replies.append(r)
                    ev = self._rsvp_waiters.get(r.rsvp_id)
                    fresh = ev is not None and not ev.is_set()
                if fresh:
                    assert ev is not None
                    ev.set()
                    ack = pb.RsvpAck(rsvp_id=r.rsvp_id, ret_code=pb.CMD_EXEC_OK,
                                     action="continue" if r.ret_code >= 0 else "refuse",
                                     ret_msg=f"rsvp {r.rsvp_id}: taken")
                else:  # as the firmware: every reply is acknowledged or refused with the reason
                    ack = pb.RsvpAck(rsvp_id=r.rsvp_id, ret_code=pb.CMD_PARAM_ERR,
                                     ret_msg=f"rsvp {r.rsvp_id}: unknown or already answered")
                stack.send(pb.Downlink(rsvp_ack=ack).SerializeToString())
                continue
            req = up.request
            with self._lock:
                self.requests.append(req)
                self.uplink_sizes.append(len(data))
                if self.silent:
                    continue
                s = self.sessions.get(host)
                if s is not None and req.seq == s.last_seq and s.cached is not None:
                    out = s.cached  # retransmission: answer the cache, do not execute again
                else:
                    resp = self._execute(host, req)
                    out = pb.Downlink(response=resp).SerializeToString()
                    s = self.sessions.get(host)
                    if s is not None:
                        s.last_seq = req.seq
                        s.cached = out
                if self.rewrite is not None:
                    out = out.replace(*self.rewrite)
                if self.drop_responses > 0:
                    self.drop_responses -= 1
                    continue
            stack.send(out)

    def _execute(self, host: int, req: pb.Request) -> pb.Response:
        which = req.WhichOneof("cmd") or ""
        self.executions[which] = self.executions.get(which, 0) + 1
        resp = pb.Response(seq=req.seq)

        def answer(code: int, msg: str = "") -> pb.Response:
            resp.ret_code = code
            resp.ret_msg = msg
            return resp

        if which in self.force_codes:
            code, msg = self.force_codes[which]
            return answer(code, msg)
        if which == "connect":
            c = req.connect
            res = pb.ConnectRes(protocol_version=self.version, schema_hash=self.schema_hash,
                                device_name="fake", joint_count=6, firmware_version="fake-1",
                                heartbeat_timeout_ms=self.heartbeat_timeout_ms, state=self.state,
                                owner=self.owner == host, client_nonce=c.client_nonce)
            if self.refuse_mismatch and (c.protocol_version != self.version or c.schema_hash != self.schema_hash):
                resp.connect.CopyFrom(res)
                return answer(pb.CMD_VERSION_MISMATCH_ERR,
                              f"device protocol {self.version} schema {self.schema_hash:08X}")
            live = self.sessions.get(host)
            if live is not None and live.nonce != c.client_nonce:  # as the firmware: one client per address
                resp.connect.CopyFrom(res)
                return answer(pb.CMD_NOT_OWNER_ERR, f"connect: address 0x{host:02X} is in use by another client")
            self._token_next += 1
            self.sessions[host] = Session(host, last_heartbeat=time.monotonic(), nonce=c.client_nonce,
                                          token=self._token_next & 0xFFFFFF)
            res.heartbeat_token = self._token_next & 0xFFFFFF
            if self.state == pb.IDLE:
                self.state = pb.UNLOCKED
            res.state = self.state
            resp.connect.CopyFrom(res)
            return answer(pb.CMD_EXEC_OK)
        if host not in self.sessions:
            return answer(pb.CMD_NOT_CONNECTED_ERR, "send connect first")
        if which == "disconnect":
            self._drop(host)
            resp.disconnect.SetInParent()
            return answer(pb.CMD_EXEC_OK)
        if which == "describe":
            r = resp.describe
            r.max_sessions, r.max_paths, r.max_points_per_path = len(self.sessions) or 1, 8, self.max_points_per_path
            tags = max_count("PathLoadReq", "tags")
            name = max_string_bytes("PathLoadReq", "path_name")
            tag = max_string_bytes("TagPoint", "tag_name")
            assert tags is not None and name is not None and tag is not None
            n_load = pb.Request.DESCRIPTOR.fields_by_name["path_load"].number
            r.field_limits.add(path=[1, n_load, 1], max_bytes=name)
            r.field_limits.add(path=[1, n_load, 6], max_count=tags)
            r.field_limits.add(path=[1, n_load, 6, 3], max_bytes=tag)
            return answer(pb.CMD_EXEC_OK)
        if which == "describe_robot":
            text, at = urdf_text().encode(), req.describe_robot.offset
            if at > len(text):
                return answer(pb.CMD_PARAM_OUT_OF_RANGE_ERR, f"offset {at} is past the end of the URDF")
            piece = max_string_bytes("DescribeRobotRes", "urdf")
            assert piece is not None
            rr = resp.describe_robot
            rr.urdf, rr.offset, rr.total_bytes = text[at:at + piece].decode(), at, len(text)
            rr.robot_model, rr.ik_class = "ls-sim6", "spherical_wrist"
            return answer(pb.CMD_EXEC_OK)
        if which == "get_motion_control_state":
            r = resp.get_motion_control_state
            r.motion_control_state = "robot_at_rest"
            r.control_mode = "power_on" if self.state in (pb.RESTING, pb.MOVING) else "power_off"
            r.state = self.state
            r.owner = self.owner == host
            return answer(pb.CMD_EXEC_OK)
        if which == "lock":
            if self.owner is not None and self.owner != host:
                return answer(pb.CMD_NOT_OWNER_ERR, f"supervisor {self.owner:#04x} owns the device")
            if self.state != pb.UNLOCKED:
                return answer(pb.CMD_WRONG_STATE_ERR,
                              f"lock is valid in UNLOCKED, the device is {pb.State.Name(self.state)}")
            self.owner, self.state = host, pb.LOCKED
            resp.lock.SetInParent()
            return answer(pb.CMD_EXEC_OK)
        if which in ("release", "activate", "deactivate", "move_absolute", "path_load", "path_clear_path",
                     "path_move"):
            if self.owner != host:
                return answer(pb.CMD_NOT_OWNER_ERR, "lock first")
        if which == "release":
            if self.state != pb.LOCKED:
                return answer(pb.CMD_WRONG_STATE_ERR, "release is valid in LOCKED")
            self.owner, self.state = None, pb.UNLOCKED
            resp.release.SetInParent()
            return answer(pb.CMD_EXEC_OK)
        if which == "activate":
            if self.state != pb.LOCKED:
                return answer(pb.CMD_WRONG_STATE_ERR, "activate is valid in LOCKED")
            self.state = pb.RESTING
            resp.activate.SetInParent()
            return answer(pb.CMD_EXEC_OK)
        if which == "deactivate":
            if self.state != pb.RESTING:
                return answer(pb.CMD_WRONG_STATE_ERR, "deactivate is valid in RESTING")
            self.state = pb.LOCKED
            resp.deactivate.SetInParent()
            return answer(pb.CMD_EXEC_OK)
        if which == "path_load":
            pl = req.path_load
            if self.state not in (pb.LOCKED, pb.RESTING):
                return answer(pb.CMD_WRONG_STATE_ERR, "pathLoad is valid in LOCKED and RESTING")
            if not pl.path_name:
                return answer(pb.CMD_PARAM_ERR, "path_name: empty")
            if len(pl.tags) > 32:
                return answer(pb.CMD_PARAM_ERR, f"tags: {len(pl.tags)} points, at most 32 per message")
            if pl.number_of_points != len(pl.tags):
                return answer(pb.CMD_PARAM_ERR, f"number_of_points {pl.number_of_points} != {len(pl.tags)} tags")
            if len(self.paths.get(pl.path_name, [])) + len(pl.tags) > self.max_points_per_path:
                return answer(pb.CMD_NO_RESOURCES_ERR, f"a path holds at most {self.max_points_per_path} points")
            self.paths.setdefault(pl.path_name, []).extend(pl.tags)
            resp.path_load.points_in_path = len(self.paths[pl.path_name])
            return answer(pb.CMD_EXEC_OK)
        if which == "path_clear_path":
            if self.paths.pop(req.path_clear_path.path_name, None) is None:
                return answer(pb.CMD_PARAM_ERR, f"no path '{req.path_clear_path.path_name}'")
            resp.path_clear_path.SetInParent()
            return answer(pb.CMD_EXEC_OK)
        if which == "path_move":
            pm = req.path_move
            if self.state != pb.RESTING:
                return answer(pb.CMD_WRONG_STATE_ERR, "pathMove is valid in RESTING: activate first")
            if pm.path_name not in self.paths:
                return answer(pb.CMD_PARAM_ERR, f"no path '{pm.path_name}': pathLoad it first")
            if pm.number_of_cycles < 0:
                return answer(pb.CMD_PARAM_OUT_OF_RANGE_ERR, "number_of_cycles: must be >= 0")
            cycles = pm.number_of_cycles if pm.HasField("number_of_cycles") else 1  # seed 3.5.2
            self.state = pb.MOVING
            threading.Thread(target=self._run_path, args=(host, req.seq, pm.path_name, cycles,
                                                          list(self.paths[pm.path_name])), daemon=True).start()
            resp.path_move.SetInParent()
            return answer(pb.CMD_STARTED_OK)
        if which == "move_absolute":
            if self.state != pb.RESTING:
                return answer(pb.CMD_WRONG_STATE_ERR, "moveAbsolute is valid in RESTING: activate first")
            m = req.move_absolute
            if len(m.values) != 6:
                return answer(pb.CMD_PARAM_ERR, f"values: expected 6 numbers, got {len(m.values)}")
            self.state = pb.MOVING
            threading.Thread(target=self._run_move, args=(host, req.seq, m.point_name, list(m.values)),
                             daemon=True).start()
            resp.move_absolute.SetInParent()
            return answer(pb.CMD_STARTED_OK)
        return answer(pb.CMD_NOT_IMPLEMENTED_ERR, f"{which} is not in the fake device")

    # ---------------------------------------------------------------- the non-blocking command

    def notify(self, host: int, *, path_event: bool = False, **kw: Any) -> None:
        """Send a notice; `path_event`: its name is a path's own (`event NAME`, `rsvp NAME`)."""
        problem = undeclared(str(kw.get("event_id", "")), list(kw.get("data", [])), path_event=path_event)
        if problem is not None:
            self.undeclared.append(problem)
            return
        with self._lock:
            s = self.sessions.get(host)
            if s is None:
                return
            s.notice_seq += 1
            n = pb.Notice(notice_seq=s.notice_seq, **kw)
        self.stacks[host].send(pb.Downlink(notice=n).SerializeToString())

    def _run_path(self, host: int, seq: int, path: str, cycles: int, points: list[pb.TagPoint]) -> None:
        for cycle in range(1, max(cycles, 1) + 1):
            for p in points:
                time.sleep(self.point_time_s)
                if p.tag_name:
                    self.notify(host, kind=pb.EVENT, event_id="tag", ref_seq=seq,
                                data=[f"tag={p.tag_name}", f"index={p.tag_index}", f"cycle={cycle}", f"path={path}"])
        with self._lock:
            self.state = pb.RESTING
        self.notify(host, kind=pb.EVENT, event_id="pathMoveComplete", data=[f"point={path}", "reason=complete"],
                    ref_seq=seq, final=True)

    def _run_move(self, host: int, seq: int, point: str, values: list[float]) -> None:
        time.sleep(self.move_time_s)
        self.notify(host, kind=pb.EVENT, event_id="tag", data=[f"tag={point}", "path="], ref_seq=seq)
        with self._lock:
            rsvp_id = self._rsvp_next
            self._rsvp_next += 1
            ev = threading.Event()
            self._rsvp_waiters[rsvp_id] = ev
        self.notify(host, path_event=True, kind=pb.EVENT_RSVP, event_id="confirmMove", data=[f"point={point}"],
                    ref_seq=seq, rsvp_id=rsvp_id, rsvp_timeout_ms=self.rsvp_timeout_ms, rsvp_default="continue")
        answered = ev.wait(self.rsvp_timeout_ms / 1000.0)
        with self._lock:
            reply = next((r for r in self.rsvp_replies if r.rsvp_id == rsvp_id), None)
            self.rsvp_outcomes.append("answered" if answered else "default")
            self.state = pb.RESTING
        if values[0] > 3.0:
            self.notify(host, kind=pb.ALARM, event_id="moveAbsoluteFailed",
                        data=[f"point={point}", "reason=fault", f"fault=joint 1 beyond its limit ({values[0]} rad)"],
                        ref_seq=seq, final=True)
        elif answered and reply is not None and reply.ret_code < 0:
            self.notify(host, kind=pb.ALARM, event_id="moveAbsoluteAborted",
                        data=[f"point={point}", "reason=rsvpDeclined", f"answer={reply.ret_code}"],
                        ref_seq=seq, final=True)
        else:
            self.notify(host, kind=pb.EVENT, event_id="moveAbsoluteComplete",
                        data=[f"point={point}", "reason=complete", "joints=" + ",".join(f"{v:g}" for v in values)],
                        ref_seq=seq, final=True)
