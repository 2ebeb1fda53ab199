"""The supervisor's typed commands: one method per schema command, each one request.

Argument names are the schema's field names, so units are in them (speed_pct, max_timeout_s,
polling_timeout_ms); tests/host/test_registry.py fails while a schema command has no method
here or a method's arguments differ from its request's fields. The CLI needs none of this (it
builds every command from the registry); `path_load_points` and `robot_urdf` are the ones
that send more than one request. A class of its own so that supervisor.py keeps the session: transport,
heartbeat, the answers' matching and the notices (Supervisor inherits these).
"""
from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any, Unpack

from . import urdf
from ._generated import landscape_pb2 as pb
from .description import DeviceDescription
from .drives import home_request
from .errors import error_for_code
from .paths import build_path_load_requests, request_fields
from .registry import Command
from .retval import CallOptions, Enum, RetVal


class Commands:
    """The typed commands, on top of `request` (Supervisor.request)."""

    #: What connect read (Supervisor's): `home` waits as long as its homing may take.
    description: DeviceDescription | None

    def request(self, command: str | Command, /, *, check: bool = True, timeout_s: float | None = None,
                **fields: Any) -> RetVal:
        raise NotImplementedError  # Supervisor's

    def lock(self, **opts: Unpack[CallOptions]) -> RetVal:
        return self.request("lock", **opts)

    def release(self, **opts: Unpack[CallOptions]) -> RetVal:
        return self.request("release", **opts)

    def activate(self, **opts: Unpack[CallOptions]) -> RetVal:
        return self.request("activate", **opts)

    def deactivate(self, **opts: Unpack[CallOptions]) -> RetVal:
        return self.request("deactivate", **opts)

    def set_speed(self, speed: float, *, attribute: Enum = pb.PERCENT_SPEED, **opts: Unpack[CallOptions]) -> RetVal:
        return self.request("set_speed", speed=speed, attribute=attribute, **opts)

    def set_acceleration(self, accel: float, *, attribute: Enum = pb.PERCENT_ACCEL,
                         **opts: Unpack[CallOptions]) -> RetVal:
        return self.request("set_acceleration", accel=accel, attribute=attribute, **opts)

    def set_tool_offset(self, offset: Sequence[float], **opts: Unpack[CallOptions]) -> RetVal:
        return self.request("set_tool_offset", offset=offset, **opts)

    def set_world_cartesian_frame(self, frame: Sequence[float], **opts: Unpack[CallOptions]) -> RetVal:
        return self.request("set_world_cartesian_frame", frame=frame, **opts)

    def set_units(self, *, linear: Enum = pb.METERS, angular: Enum = pb.RADIANS,
                  **opts: Unpack[CallOptions]) -> RetVal:
        return self.request("set_units", linear=linear, angular=angular, **opts)

    def get_units(self, **opts: Unpack[CallOptions]) -> RetVal:
        return self.request("get_units", **opts)

    def get_velocities(self, **opts: Unpack[CallOptions]) -> RetVal:
        return self.request("get_velocities", **opts)

    def get_accelerations(self, **opts: Unpack[CallOptions]) -> RetVal:
        return self.request("get_accelerations", **opts)

    def get_max_velocities(self, **opts: Unpack[CallOptions]) -> RetVal:
        return self.request("get_max_velocities", **opts)

    def get_max_accelerations(self, **opts: Unpack[CallOptions]) -> RetVal:
        return self.request("get_max_accelerations", **opts)

    def get_tool_offsets(self, **opts: Unpack[CallOptions]) -> RetVal:
        return self.request("get_tool_offsets", **opts)

    def get_robot_position(self, **opts: Unpack[CallOptions]) -> RetVal:
        return self.request("get_robot_position", **opts)

    def get_motion_control_state(self, **opts: Unpack[CallOptions]) -> RetVal:
        return self.request("get_motion_control_state", **opts)

    def get_tag_id(self, **opts: Unpack[CallOptions]) -> RetVal:
        return self.request("get_tag_id", **opts)

    def move_relative(self, point_name: str, values: Sequence[float], *, frame: Enum = pb.JOINT_FRAME,
                      speed_pct: float = 0.0, **opts: Unpack[CallOptions]) -> RetVal:
        return self.request("move_relative", point_name=point_name, values=values, frame=frame,
                            speed_pct=speed_pct, **opts)

    def move_absolute(self, point_name: str, values: Sequence[float], *, frame: Enum = pb.JOINT_FRAME,
                      speed_pct: float = 0.0, **opts: Unpack[CallOptions]) -> RetVal:
        return self.request("move_absolute", point_name=point_name, values=values, frame=frame,
                            speed_pct=speed_pct, **opts)

    def move_arc(self, point_name: str, arc_value: Sequence[float], goal_value: Sequence[float], *,
                 frame: Enum = pb.BASE_CARTESIAN_FRAME, offset_type: Enum = pb.ABSOLUTE_DATA,
                 **opts: Unpack[CallOptions]) -> RetVal:
        return self.request("move_arc", point_name=point_name, arc_value=arc_value, goal_value=goal_value,
                            frame=frame, offset_type=offset_type, **opts)

    def path_load(self, path_name: str, tags: Sequence[pb.TagPoint | Mapping[str, Any]], *,
                  frame: Enum = pb.JOINT_FRAME, motion_type: Enum = pb.JOINT_MOTION,
                  offset_type: Enum = pb.ABSOLUTE_DATA, number_of_points: int | None = None,
                  **opts: Unpack[CallOptions]) -> RetVal:
        """Append `tags` to path `path_name`; number_of_points defaults to len(tags)."""
        n = len(tags) if number_of_points is None else number_of_points
        return self.request("path_load", path_name=path_name, tags=tags, frame=frame, motion_type=motion_type,
                            offset_type=offset_type, number_of_points=n, **opts)

    def path_load_points(self, path_name: str, points: Sequence[pb.TagPoint | Mapping[str, Any]], *,
                         frame: Enum = pb.JOINT_FRAME, motion_type: Enum = pb.JOINT_MOTION,
                         offset_type: Enum = pb.ABSOLUTE_DATA,
                         progress: Callable[[int, int], None] | None = None,
                         **opts: Unpack[CallOptions]) -> RetVal:
        """Append any number of `points` to path `path_name`, split into as many pathLoad
        messages as needed (paths.build_path_load_requests), sent in order.

        progress(points_sent, points_total) is called after each message. Returns the last
        RetVal (result["points_in_path"]). When a message is refused the error (or, with
        check=False, its RetVal) says how many points were already loaded: pathClearPath
        starts over."""
        reqs = build_path_load_requests(path_name, points, frame=frame, motion_type=motion_type,
                                        offset_type=offset_type)
        check = opts.get("check", True)
        timeout_s = opts.get("timeout_s")
        total = sum(len(r.path_load.tags) for r in reqs)
        sent = 0
        rv: RetVal | None = None
        for i, req in enumerate(reqs):
            rv = self.request("path_load", check=False, timeout_s=timeout_s, **request_fields(req))
            if rv.ret_code < 0:
                rv.ret_msg = (f"{rv.ret_msg} (message {i + 1} of {len(reqs)}; {sent} of {total} points were "
                              f"loaded: pathClearPath {path_name} to start over)").lstrip()
                if check:
                    raise error_for_code(rv.name, rv.ret_code, rv.ret_msg)
                return rv
            sent += len(req.path_load.tags)
            if progress is not None:
                progress(sent, total)
        assert rv is not None  # build_path_load_requests returns at least one request
        return rv

    def path_clear_path(self, path_name: str, **opts: Unpack[CallOptions]) -> RetVal:
        return self.request("path_clear_path", path_name=path_name, **opts)

    def path_move(self, path_name: str, *, number_of_cycles: int | None = None,
                  **opts: Unpack[CallOptions]) -> RetVal:
        """Run a loaded path `number_of_cycles` times (None: left out, the device runs it once as
        seed 3.5.2 says; 0: a dry run without auxiliary commands, whose notices say dry_run=true)."""
        return self.request("path_move", path_name=path_name, number_of_cycles=number_of_cycles, **opts)

    def stop_motion(self, **opts: Unpack[CallOptions]) -> RetVal:
        return self.request("stop_motion", **opts)

    def resume_motion(self, **opts: Unpack[CallOptions]) -> RetVal:
        return self.request("resume_motion", **opts)

    def abort_motion(self, **opts: Unpack[CallOptions]) -> RetVal:
        return self.request("abort_motion", **opts)

    def get_sensor_reading(self, sensor_type: str, **opts: Unpack[CallOptions]) -> RetVal:
        return self.request("get_sensor_reading", sensor_type=sensor_type, **opts)

    def move_react(self, sensor_type: str, motion_offsets: Sequence[float], *, motion_speed_pct: float = 0.0,
                   compliance_speed_pct: float = 0.0, thresholds: Sequence[float] = (),
                   gains: Sequence[float] = (), envelope_min: Sequence[float] = (),
                   envelope_max: Sequence[float] = (), **opts: Unpack[CallOptions]) -> RetVal:
        return self.request("move_react", sensor_type=sensor_type, motion_offsets=motion_offsets,
                            motion_speed_pct=motion_speed_pct, compliance_speed_pct=compliance_speed_pct,
                            thresholds=thresholds, gains=gains, envelope_min=envelope_min,
                            envelope_max=envelope_max, **opts)

    def comply(self, sensor_type: str, thresholds: Sequence[float], *, max_timeout_s: float = 0.0,
               panic_stop_code: int = 0, max_travel: Sequence[float] = (),
               proportional_gains: Sequence[float] = (), differential_gains: Sequence[float] = (),
               speed_pct: float = 0.0, compliance_speed_pct: float = 0.0, envelope_min: Sequence[float] = (),
               envelope_max: Sequence[float] = (), **opts: Unpack[CallOptions]) -> RetVal:
        return self.request("comply", sensor_type=sensor_type, thresholds=thresholds, max_timeout_s=max_timeout_s,
                            panic_stop_code=panic_stop_code, max_travel=max_travel,
                            proportional_gains=proportional_gains, differential_gains=differential_gains,
                            speed_pct=speed_pct, compliance_speed_pct=compliance_speed_pct,
                            envelope_min=envelope_min, envelope_max=envelope_max, **opts)

    def manual_control(self, type: str, **opts: Unpack[CallOptions]) -> RetVal:  # noqa: A002 (schema name)
        return self.request("manual_control", type=type, **opts)

    def get_end_effector_state(self, **opts: Unpack[CallOptions]) -> RetVal:
        return self.request("get_end_effector_state", **opts)

    def get_tool(self, tool_id: str, **opts: Unpack[CallOptions]) -> RetVal:
        return self.request("get_tool", tool_id=tool_id, **opts)

    def put_tool(self, tool_id: str, **opts: Unpack[CallOptions]) -> RetVal:
        return self.request("put_tool", tool_id=tool_id, **opts)

    def activate_tool(self, tool_id: str, bit_field: int, **opts: Unpack[CallOptions]) -> RetVal:
        return self.request("activate_tool", tool_id=tool_id, bit_field=bit_field, **opts)

    def deactivate_tool(self, tool_id: str, bit_field: int, **opts: Unpack[CallOptions]) -> RetVal:
        return self.request("deactivate_tool", tool_id=tool_id, bit_field=bit_field, **opts)

    def set_digital_io(self, type: str, unit_id: int, *, bits_on: int = 0, bits_off: int = 0,  # noqa: A002
                       description: str = "", **opts: Unpack[CallOptions]) -> RetVal:
        return self.request("set_digital_io", type=type, unit_id=unit_id, bits_on=bits_on, bits_off=bits_off,
                            description=description, **opts)

    def get_digital_io(self, type: str, unit_id: int, *, description: str = "",  # noqa: A002
                       **opts: Unpack[CallOptions]) -> RetVal:
        return self.request("get_digital_io", type=type, unit_id=unit_id, description=description, **opts)

    def signal_digital_io(self, type: str, unit_id: int, bit_string: int, *,  # noqa: A002
                          polling_timeout_ms: int = 0, polling_cycle_time_ms: int = 0,
                          callback_type: Enum = pb.CB_EVENT, **opts: Unpack[CallOptions]) -> RetVal:
        return self.request("signal_digital_io", type=type, unit_id=unit_id, bit_string=bit_string,
                            polling_timeout_ms=polling_timeout_ms, polling_cycle_time_ms=polling_cycle_time_ms,
                            callback_type=callback_type, **opts)

    def send_command(self, input: str, **opts: Unpack[CallOptions]) -> RetVal:  # noqa: A002 (schema name)
        return self.request("send_command", input=input, **opts)

    def home(self, *joints: int, **opts: Unpack[CallOptions]) -> RetVal:
        """sendCommand home: the drives' own homing of `joints` (none: every joint that must
        be homed; docs/protocol.md "Drives"). Waits up to the device's homing time-out
        (describe) unless `timeout_s` says otherwise."""
        if "timeout_s" not in opts and self.description is not None and self.description.res.homing_timeout_ms:
            opts["timeout_s"] = self.description.res.homing_timeout_ms / 1000.0 + 2.0
        return self.send_command(home_request(joints), **opts)

    def describe(self, **opts: Unpack[CallOptions]) -> RetVal:
        """Read the device's description (limits, DIO map, sensors, tools, joints, workspace; SI).
        connect() already read it once for this session: see ``description``."""
        return self.request("describe", **opts)

    def describe_robot(self, *, offset: int = 0, **opts: Unpack[CallOptions]) -> RetVal:
        """One piece of the arm's URDF, from byte `offset` (describeRobot); robot_urdf() joins them all."""
        return self.request("describe_robot", offset=offset, **opts)

    def robot_urdf(self) -> str:
        """The URDF of the robot model the device runs (docs/protocol.md "Robot description")."""
        return urdf.robot_urdf(lambda offset: self.describe_robot(offset=offset, check=False))
