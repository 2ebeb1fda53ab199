"""How the host shows notices and units: one text form of a notice for the CLI, the
session log and `landscape events`, and the units a session speaks in.

Units: the device answers and reports every position in the units its session chose
with setUnits (getUnits names them: "meters", "millimeters", ..., "radians",
"degrees"); the DBC broadcasts (telemetry) are always SI (rad, m). Names, symbols and
factors are the schema's (enum LinearUnit, AngularUnit: (ls.text), (ls.symbol),
(ls.si_per_unit)), the same the firmware's conversions are generated from.
"""
from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, cast

from ._generated import landscape_pb2 as pb

if TYPE_CHECKING:
    from google.protobuf.descriptor import EnumDescriptor
    from google.protobuf.descriptor_pb2 import EnumValueOptions
    from google.protobuf.internal.extension_dict import _ExtensionFieldDescriptor

# protoc's .pyi declares the extensions as plain FieldDescriptors (see registry.py).
_NOTICE_KEYS_OPTION = cast("_ExtensionFieldDescriptor[EnumValueOptions, str]", pb.notice_keys)
_TEXT_OPTION = cast("_ExtensionFieldDescriptor[EnumValueOptions, str]", pb.text)
_SYMBOL_OPTION = cast("_ExtensionFieldDescriptor[EnumValueOptions, str]", pb.symbol)
_SI_PER_UNIT_OPTION = cast("_ExtensionFieldDescriptor[EnumValueOptions, float]", pb.si_per_unit)


def _units(enum: EnumDescriptor) -> dict[str, float]:
    """SI per unit by the name getUnits answers (the values' (ls.text) and (ls.si_per_unit))."""
    return {v.GetOptions().Extensions[_TEXT_OPTION]: v.GetOptions().Extensions[_SI_PER_UNIT_OPTION]
            for v in enum.values}


def _symbols(*enums: EnumDescriptor) -> dict[str, str]:
    return {v.GetOptions().Extensions[_TEXT_OPTION]: v.GetOptions().Extensions[_SYMBOL_OPTION]
            for enum in enums for v in enum.values}


#: Metres per linear unit and radians per angular unit, by the names getUnits answers.
METERS_PER: dict[str, float] = _units(pb.LinearUnit.DESCRIPTOR)
RADIANS_PER: dict[str, float] = _units(pb.AngularUnit.DESCRIPTOR)
SYMBOL: dict[str, str] = _symbols(pb.LinearUnit.DESCRIPTOR, pb.AngularUnit.DESCRIPTOR)
#: The reason= of each way a started motion can end (enum MotionEnd's (ls.text)).
MOTION_END_REASONS: tuple[str, ...] = tuple(v.GetOptions().Extensions[_TEXT_OPTION]
                                            for v in pb.MotionEnd.DESCRIPTOR.values)


@dataclass(frozen=True)
class Units:
    """The linear and angular units of a session (names as getUnits answers them)."""

    linear: str = "meters"
    angular: str = "radians"

    @classmethod
    def from_result(cls, result: dict[str, Any]) -> Units:
        """From a getUnits result; a name the host does not know is kept (shown, not converted)."""
        return cls(str(result.get("linear_units") or "meters"), str(result.get("angular_units") or "radians"))

    @property
    def linear_symbol(self) -> str:
        return SYMBOL.get(self.linear, self.linear)

    @property
    def angular_symbol(self) -> str:
        return SYMBOL.get(self.angular, self.angular)

    def describe(self) -> str:
        return f"{self.linear} and {self.angular}"

    def from_m(self, v: float) -> float:
        """A length in metres (telemetry) in the session's linear unit."""
        return v / METERS_PER.get(self.linear, 1.0)

    def from_rad(self, v: float) -> float:
        """An angle in radians (telemetry) in the session's angular unit."""
        return v / RADIANS_PER.get(self.angular, 1.0)


SI = Units()


def format_notice(n: pb.Notice) -> str:
    """One line for a notice: `KIND event_id key=value ... (ref SEQ) [rsvp ...] final`."""
    kind = pb.NoticeKind.Name(n.kind)
    extra = f" (ref {n.ref_seq})" if n.ref_seq else ""
    if n.kind in (pb.EVENT_RSVP, pb.ALARM_RSVP):
        extra += f" [rsvp {n.rsvp_id}: default '{n.rsvp_default}' after {n.rsvp_timeout_ms} ms]"
    return f"{kind} {n.event_id}" + "".join(f" {d}" for d in n.data) + extra + (" final" if n.final else "")


def _declared_events() -> dict[str, tuple[str, ...]]:
    out: dict[str, tuple[str, ...]] = {}
    for v in pb.EventId.DESCRIPTOR.values:
        if v.number != pb.EVENT_ID_NONE:
            out[v.name] = tuple(v.GetOptions().Extensions[_NOTICE_KEYS_OPTION].split())
    return out


_DECLARED = _declared_events()
#: The data keys a path's own `event NAME` / `rsvp NAME` carries (ls.EventId AUX_NAMED_EVENT).
AUX_NAMED_KEYS: tuple[str, ...] = _DECLARED.pop(pb.EventId.Name(pb.AUX_NAMED_EVENT))
#: Every event id the device sends (enum ls.EventId of protocol/landscape.proto, by the name
#: Notice.event_id carries) and the data keys its notices may carry (ls.notice_keys).
EVENT_KEYS: dict[str, tuple[str, ...]] = _DECLARED
#: The non-final event of a tagged path point.
TAG_EVENT: str = pb.EventId.Name(pb.tag)


def undeclared(event_id: str, data: Iterable[str], *, path_event: bool = False) -> str | None:
    """What in a notice the schema does not declare, as a sentence, or None when all is declared.
    `path_event`: the name is a path's own (`event NAME`, `rsvp NAME`), judged by AUX_NAMED_KEYS."""
    if path_event:
        keys = AUX_NAMED_KEYS
    elif event_id in EVENT_KEYS:
        keys = EVENT_KEYS[event_id]
    else:
        return f"event id {event_id!r} is not declared in protocol/landscape.proto enum EventId"
    for item in data:
        key, eq, _ = item.partition("=")
        if not eq or key not in keys:
            return f"notice {event_id!r}: data {item!r} has no key the schema declares for it ({', '.join(keys)})"
    return None
