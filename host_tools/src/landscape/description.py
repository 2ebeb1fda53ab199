"""What the device says about itself (the `describe` command, docs/protocol.md
"Device description"), and the checks the library makes with it before sending.

The Supervisor reads the description once per session, right after connect; a
request that breaks one of the device's limits then fails here with an
ArgumentError naming the field and the limit, instead of a refusal from the
device. Pure: nothing here does I/O.
"""
from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

from google.protobuf.descriptor import Descriptor, FieldDescriptor
from google.protobuf.message import Message

from ._generated import landscape_pb2 as pb
from .errors import ArgumentError
from .limits import field_option
from .registry import COMMANDS, descriptor_of, field_message_type, is_repeated

#: The roots of FieldLimit paths: ls.Uplink (field_limits: what a supervisor sends) and
#: ls.Downlink (downlink_limits: the texts the device sends).
_UPLINK = descriptor_of(pb.Uplink)
_DOWNLINK = descriptor_of(pb.Downlink)
#: The description's own messages, whose strings downlink_limits leaves out (the
#: generator's DESCRIPTIONS: they are the description, not texts about a request).
_DESCRIPTIONS = ("DescribeRes", "DescribeRobotRes")
#: The field types whose size nanopb bounds with max_size.
_SIZED = (FieldDescriptor.TYPE_STRING, FieldDescriptor.TYPE_BYTES)


@dataclass(frozen=True)
class Limit:
    """The bound of one string or repeated field of what a supervisor sends, or of a text
    the device sends."""

    path: tuple[int, ...]   # field numbers from ls.Uplink (ls.Downlink) down
    name: str               # "pathLoad.tags.tag_name", "rsvpReply.data"; "notice.event_id"
    max_bytes: int          # strings: longest UTF-8 text in bytes; bytes fields: most bytes (else 0)
    max_count: int          # repeated fields: most items (0: not repeated)


def path_name(path: tuple[int, ...] | list[int], root: Descriptor = _UPLINK) -> str:
    """The readable name of a FieldLimit path: the command's seed name, then the field
    names ([1, 39, 6, 3] -> "pathLoad.tags.tag_name", [2, 3] -> "rsvpReply.data"; from
    ls.Downlink: [1, 34, 4] -> "getMotionControlState.fault", [2, 2] -> "notice.event_id").
    ArgumentError for a path this host tool's schema lacks."""
    fds: list[FieldDescriptor] = []
    desc: Descriptor | None = root
    for number in path:
        fd = desc.fields_by_number.get(number) if desc is not None else None
        if fd is None:
            raise ArgumentError(f"field path {list(path)} is not in this host tool's schema: update the host tool")
        fds.append(fd)
        desc = fd.message_type
    if not fds:
        raise ArgumentError("an empty field path")
    if fds[0].name in ("request", "response") and len(fds) > 1 and fds[1].name in COMMANDS:
        head, rest = COMMANDS[fds[1].name].name, fds[2:]
    else:
        first, *words = fds[0].name.split("_")
        head, rest = first + "".join(w.title() for w in words), fds[1:]
    return ".".join([head, *(f.name for f in rest)])


class DeviceDescription:
    """An ls.DescribeRes with lookups and the library's checks. `from_device` is False for
    the stand-in built from the host's copy of the schema's limits (``host_copy``)."""

    def __init__(self, res: pb.DescribeRes, *, from_device: bool = True) -> None:
        self.res = res
        self.from_device = from_device
        self.limits: dict[tuple[int, ...], Limit] = {}
        for fl in res.field_limits:
            path = tuple(fl.path)
            self.limits[path] = Limit(path, path_name(path), fl.max_bytes, fl.max_count)
        #: The texts the device sends (downlink_limits), by name ("notice.event_id").
        self.downlink: dict[str, Limit] = {}
        for fl in res.downlink_limits:
            path = tuple(fl.path)
            lim = Limit(path, path_name(path, _DOWNLINK), fl.max_bytes, fl.max_count)
            self.downlink[lim.name] = lim

    @classmethod
    def host_copy(cls) -> DeviceDescription:
        """The field limits of the host's copy of protocol/landscape.options (what the firmware
        built from the same tree holds), without devices, tables or the robot model: the
        stand-in when the device's own description could not be read (a lossy link)."""
        res = pb.DescribeRes()
        for path, owner, fd in _bounded(_UPLINK, ()):
            size = field_option(owner, fd.name, "max_size") if fd.type in _SIZED else None
            count = field_option(owner, fd.name, "max_count") if is_repeated(fd) else None
            if size is not None and fd.type == FieldDescriptor.TYPE_STRING:
                size -= 1  # nanopb's max_size counts a string's terminating zero
            if size is not None or count is not None:
                res.field_limits.add(path=list(path), max_bytes=size or 0, max_count=count or 0)
        for path, owner, fd in _bounded(_DOWNLINK, (), skip=_DESCRIPTIONS):
            size = field_option(owner, fd.name, "max_size") if fd.type == FieldDescriptor.TYPE_STRING else None
            if size is not None:
                count = field_option(owner, fd.name, "max_count") if is_repeated(fd) else None
                res.downlink_limits.add(path=list(path), max_bytes=size - 1, max_count=count or 0)
        return cls(res, from_device=False)

    def downlink_bytes(self, name: str) -> int:
        """The longest text the device sends in field `name` ("notice.event_id",
        "response.ret_msg"), in bytes of UTF-8. ArgumentError when it publishes none."""
        lim = self.downlink.get(name)
        if lim is None:
            raise ArgumentError(f"the device publishes no limit for the text '{name}'; it has: "
                                f"{', '.join(sorted(self.downlink))}")
        return lim.max_bytes

    # ------------------------------------------------------------ lookups (completion hooks)

    def limit(self, name: str) -> Limit:
        """The limit of field `name` ("pathLoad.tags", "connect.client_name")."""
        for lim in self.limits.values():
            if lim.name == name:
                return lim
        raise ArgumentError(f"the device publishes no limit for '{name}'; it has: "
                            f"{', '.join(sorted(x.name for x in self.limits.values()))}")

    @property
    def sensors(self) -> dict[str, list[tuple[str, str]]]:
        """Sensor name -> [(component, SI unit)], in the order of its readings."""
        return {s.name: [(c.name, c.unit) for c in s.components] for s in self.res.sensors}

    @property
    def tools(self) -> list[str]:
        return list(self.res.tools)

    def choices(self, command: str, field: str) -> list[str]:
        """The values the device accepts for string field `field` of `command`, where it
        publishes them (sensor names, tool ids; empty: free text). For shell completion."""
        if field == "sensor_type":
            return list(self.sensors)
        if field == "tool_id":
            return self.tools
        return []

    # ------------------------------------------------------------ checks before sending

    def check_request(self, req: pb.Request) -> None:
        """ArgumentError naming the first field of `req` that breaks a published size limit
        (text too long, too many items): such a request would not even decode on the device.
        The Supervisor calls it before sending every request."""
        which = req.WhichOneof("cmd")
        if which is None:
            return
        sub = getattr(req, which)
        for path, fd, value in _walk(sub, (1, COMMANDS[which].number)):
            lim = self.limits.get(path)
            if lim is None:
                continue
            if is_repeated(fd) and lim.max_count and len(value) > lim.max_count:
                raise ArgumentError(f"{lim.name} has {len(value)} items; the device holds at most "
                                    f"{lim.max_count} (describe){_split_hint(lim)}")
            if fd.type == FieldDescriptor.TYPE_STRING and lim.max_bytes:
                for text in (value if is_repeated(fd) else [value]):
                    n = len(text.encode("utf-8"))
                    if n > lim.max_bytes:
                        raise ArgumentError(f"{lim.name} is {n} bytes of UTF-8 ('{text[:24]}...'); the device "
                                            f"holds at most {lim.max_bytes} (describe): shorten it")
            if fd.type == FieldDescriptor.TYPE_BYTES and lim.max_bytes and len(value) > lim.max_bytes:
                raise ArgumentError(f"{lim.name} is {len(value)} bytes; the device holds at most "
                                    f"{lim.max_bytes} (describe)")

    def check_values(self, req: pb.Request) -> None:
        """ArgumentError when `req` names what the device does not have: an unknown sensor or
        tool, a DIO unit it lacks, output bits that are inputs (and the reverse for watches).
        A hook for front ends (the CLI, completion): the Supervisor leaves these to the device,
        whose refusal says the same."""
        which = req.WhichOneof("cmd")
        if which is None:
            return
        sub = getattr(req, which)
        name = COMMANDS[which].name
        if isinstance(sub, (pb.GetSensorReadingReq, pb.MoveReactReq, pb.ComplyReq)) and self.res.sensors:
            if sub.sensor_type not in self.sensors:
                raise ArgumentError(f"{name}: the device has no sensor '{sub.sensor_type}'; it has "
                                    f"{', '.join(self.sensors)} (describe)")
        if isinstance(sub, (pb.GetToolReq, pb.PutToolReq)) and self.res.tools:
            if sub.tool_id not in self.tools:
                raise ArgumentError(f"{name}: the rack holds no tool '{sub.tool_id}'; it holds "
                                    f"{', '.join(self.tools)} (describe)")
        if isinstance(sub, (pb.SetDigitalIOReq, pb.GetDigitalIOReq, pb.SignalDigitalIOReq)) \
                and sub.HasField("unit_id"):
            units = {u.unit_id: u for u in self.res.dio_units}
            unit = units.get(sub.unit_id)
            if unit is None:
                have = ", ".join(str(u) for u in units) or "none"
                raise ArgumentError(f"{name}: the device has no DIO unit {sub.unit_id}; its units: {have} "
                                    f"(describe)")
            if isinstance(sub, pb.SetDigitalIOReq):
                bad = (sub.bits_on | sub.bits_off) & ~unit.output_mask & 0xFFFFFFFF
                if bad:
                    raise ArgumentError(f"{name}: bits 0x{bad:08X} of unit {unit.unit_id} are not outputs "
                                        f"(outputs 0x{unit.output_mask:08X}, describe)")
            if isinstance(sub, pb.SignalDigitalIOReq):  # a watch takes inputs and outputs alike
                lines = unit.input_mask | unit.output_mask
                bad = sub.bit_string & ~lines & 0xFFFFFFFF
                if bad:
                    raise ArgumentError(f"{name}: bits 0x{bad:08X} are not lines of unit {unit.unit_id} "
                                        f"(inputs 0x{unit.input_mask:08X}, outputs 0x{unit.output_mask:08X}, "
                                        f"describe)")

    # ------------------------------------------------------------ text

    def lines(self) -> Iterator[str]:
        """The description as text, for `landscape describe` (SI units)."""
        r = self.res
        yield (f"tables: {r.max_sessions} sessions, {r.max_paths} paths of {r.max_points_per_path} points, "
               f"{r.max_dio_watches} DIO watches, pathMove up to {r.max_cycles} cycles")
        yield (f"rates: {r.min_rate_pct:g} % to 100 % of the maximum; frame angles within "
               f"+-{r.frame_angle_max_rad:g} rad; translations within {r.reach_m:g} m")
        if r.max_answer_bytes:
            yield (f"texts: answers up to {r.max_answer_bytes} bytes, notice data up to "
                   f"{r.max_notice_datum_bytes} bytes each (longer ones end after a word with ' \u2026')")
        for u in r.dio_units:
            yield f"dio unit {u.unit_id}: inputs 0x{u.input_mask:08X} outputs 0x{u.output_mask:08X}"
        for s in r.sensors:
            comps = " ".join(f"{c.name}[{c.unit}]" for c in s.components)
            yield f"sensor {s.name}: {comps}"
        yield "tools: " + (", ".join(r.tools) if r.tools else "(no tool changer)")
        if r.joints:
            yield f"robot model: {r.robot_model}"
            for j, joint in enumerate(r.joints, 1):
                yield (f"joint {j}: [{joint.min_rad:.4g}, {joint.max_rad:.4g}] rad, "
                       f"{joint.max_velocity_rad_s:.4g} rad/s, {joint.max_accel_rad_s2:.4g} rad/s^2")
            yield (f"cartesian: {r.max_linear_speed_m_s:g} m/s, {r.max_angular_speed_rad_s:g} rad/s, "
                   f"{r.max_linear_accel_m_s2:g} m/s^2, {r.max_angular_accel_rad_s2:g} rad/s^2")
            if r.homing:
                need = [str(j) for j, h in enumerate(r.homing, 1) if h.required]
                states = " ".join(f"{j}={pb.HomeState.Name(h.state).removeprefix('HOME_').lower()}"
                                  for j, h in enumerate(r.homing, 1))
                yield (f"homing: joints that must be homed: {', '.join(need) or 'none'}; {states}; "
                       f"sendCommand home within {r.homing_timeout_ms / 1000:g} s")
            lo = ", ".join(f"{v:g}" for v in r.workspace_min_m)
            hi = ", ".join(f"{v:g}" for v in r.workspace_max_m)
            yield f"workspace (tool tip, base frame): min ({lo}) m, max ({hi}) m"
        for lim in sorted(self.limits.values(), key=lambda x: x.name):
            parts = []
            if lim.max_count:
                parts.append(f"{lim.max_count} items")
            if lim.max_bytes:
                parts.append(f"{lim.max_bytes} bytes")
            yield f"limit {lim.name}: " + ", ".join(parts)
        for lim in sorted(self.downlink.values(), key=lambda x: x.name):
            items = f"{lim.max_count} items of " if lim.max_count else ""
            yield f"sends {lim.name}: {items}{lim.max_bytes} bytes"


def _split_hint(lim: Limit) -> str:
    if lim.name == "pathLoad.tags":
        return ": split the points over several pathLoad messages (Supervisor.path_load_points does)"
    return ": send fewer"


def _bounded(desc: Descriptor, path: tuple[int, ...], skip: tuple[str, ...] = ()
             ) -> Iterator[tuple[tuple[int, ...], str, FieldDescriptor]]:
    """(path, message name, field) of every string, bytes and repeated field reachable from `desc`,
    the messages named in `skip` left out."""
    if desc.name in skip:
        return
    for fd in desc.fields:
        here = (*path, fd.number)
        if fd.type in _SIZED or is_repeated(fd):
            yield here, desc.name, fd
        if fd.type == FieldDescriptor.TYPE_MESSAGE:
            yield from _bounded(field_message_type(fd), here, skip)


def _walk(msg: Message, path: tuple[int, ...]) -> Iterator[tuple[tuple[int, ...], FieldDescriptor, Any]]:
    """(path, field, value) of every set field of `msg` and of the messages inside it."""
    for fd, value in msg.ListFields():
        here = (*path, fd.number)
        yield here, fd, value
        if fd.type == FieldDescriptor.TYPE_MESSAGE:
            for item in (value if is_repeated(fd) else [value]):
                yield from _walk(item, here)
