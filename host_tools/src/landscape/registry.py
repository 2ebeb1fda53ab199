"""The command registry, derived at import time from the schema's descriptors.

Nothing here lists commands: every entry comes from a field of the `Request.cmd`
oneof and the `(ls.cmd)` CommandSpec option of its message, exactly as
protocol/gen_registry.py derives the firmware's dispatch table. A command is
known by three names: the oneof field (``move_absolute``), the seed's name
(``moveAbsolute``) and the CLI name (``move-absolute``).

``build_request`` is the one pure builder: it turns keyword arguments into a
``ls.Request`` without any I/O, so it can be tested and reused by the CLI, the
Supervisor and scripts that only want the bytes.
"""
from __future__ import annotations

import hashlib
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from importlib import resources
from typing import TYPE_CHECKING, Any, cast

from google.protobuf import json_format
from google.protobuf.descriptor import Descriptor, EnumDescriptor, FieldDescriptor
from google.protobuf.message import Message

from ._generated import landscape_pb2 as pb
from .errors import ArgumentError

if TYPE_CHECKING:
    from google.protobuf.descriptor_pb2 import EnumValueOptions, FieldOptions, MessageOptions
    from google.protobuf.internal.extension_dict import _ExtensionFieldDescriptor

# protoc's .pyi declares the schema's extensions as plain FieldDescriptors; the protobuf stubs
# index Extensions[] by a typed extension handle. These casts state what the schema says.
_CMD_OPTION = cast("_ExtensionFieldDescriptor[MessageOptions, pb.CommandSpec]", pb.cmd)
_ABSENT_MEANS_OPTION = cast("_ExtensionFieldDescriptor[FieldOptions, str]", pb.absent_means)
_REQUIRED_OPTION = cast("_ExtensionFieldDescriptor[FieldOptions, bool]", pb.required)
_SYMBOL_OPTION = cast("_ExtensionFieldDescriptor[EnumValueOptions, str]", pb.symbol)


def descriptor_of(msg: Message | type[Message]) -> Descriptor:
    """`msg.DESCRIPTOR` as the descriptor API the rest of the package is typed against.

    The stubs declare DESCRIPTOR as the union of the pure-Python and the upb (C) descriptor
    classes, which are unrelated there although they have the same interface; protobuf picks
    one at import time. This is the one place that states it.
    """
    return cast(Descriptor, msg.DESCRIPTOR)

#: The schema hash (docs/protocol.md, "Schema hash"): the first 4 bytes, big-endian, of the
#: SHA-256 of protoc's descriptor set of landscape.proto, committed as _generated/landscape.desc
#: (tests/host/test_generated.py checks it against a fresh protoc run).
SCHEMA_HASH: int = int.from_bytes(
    hashlib.sha256(resources.files("landscape._generated").joinpath("landscape.desc").read_bytes()).digest()[:4],
    "big")
PROTOCOL_VERSION: int = pb.PROTOCOL_VERSION

_WORD = re.compile(r"[A-Z]+(?![a-z])|[A-Z]?[a-z0-9]+")


def kebab(seed_name: str) -> str:
    """CLI name of a seed name: moveAbsolute -> move-absolute, setDigitalIO -> set-digital-io."""
    return "-".join(w.lower() for w in _WORD.findall(seed_name))


@dataclass(frozen=True)
class Command:
    """One command of the schema, as its descriptors declare it."""

    field: str                 # Request.cmd oneof field, e.g. "move_absolute"
    number: int                # field number = command id on the wire
    name: str                  # the seed's name, e.g. "moveAbsolute"
    cli_name: str              # "move-absolute"
    states: tuple[int, ...]    # ls.State values in which it is valid
    blocking: bool             # False: CMD_STARTED_OK, then one final notice
    owner_only: bool
    query: bool                # reads and changes nothing (docs/protocol.md "Security")
    host_timeout_ms: int
    seed_section: str
    summary: str
    request_type: Descriptor
    response_type: Descriptor

    @property
    def state_names(self) -> tuple[str, ...]:
        return tuple(pb.State.Name(s) for s in self.states)

    def fields(self) -> tuple[FieldDescriptor, ...]:
        """The request message's fields in schema order."""
        return tuple(self.request_type.fields)

    def contract(self, non_blocking: str) -> str:
        """Where the seed has it, in which states it is valid, how it answers (`non_blocking`
        says how this front end follows a non-blocking one) and whether it is the owner's."""
        kind = "blocking" if self.blocking else non_blocking
        return (f"Seed command {self.name} ({self.seed_section}); valid in {', '.join(self.state_names)}; {kind}"
                + ("; owner only" if self.owner_only else "") + ".")


def _load() -> dict[str, Command]:
    req = descriptor_of(pb.Request)
    res = descriptor_of(pb.Response)
    out: dict[str, Command] = {}
    for f in req.oneofs_by_name["cmd"].fields:
        request_type = field_message_type(f)
        spec = request_type.GetOptions().Extensions[_CMD_OPTION]
        if not spec.name:
            raise ImportError(f"landscape: schema message {request_type.name} has no (ls.cmd) option")
        rf = res.fields_by_number.get(f.number)
        if rf is None or rf.name != f.name:
            raise ImportError(f"landscape: Response.result lacks field {f.number} '{f.name}'")
        out[f.name] = Command(
            field=f.name, number=f.number, name=spec.name, cli_name=kebab(spec.name),
            states=tuple(int(s) for s in spec.states), blocking=spec.blocking,
            owner_only=spec.owner_only, query=spec.query, host_timeout_ms=spec.host_timeout_ms,
            seed_section=spec.seed_section, summary=spec.summary,
            request_type=request_type, response_type=field_message_type(rf))
    return out


def field_message_type(fd: FieldDescriptor) -> Descriptor:
    """The message type of a message field (callers check fd.type first)."""
    if fd.message_type is None:
        raise TypeError(f"landscape: schema field {fd.full_name} is not a message")
    return fd.message_type


def field_enum_type(fd: FieldDescriptor) -> EnumDescriptor:
    """The enum type of an enum field (callers check fd.type first)."""
    if fd.enum_type is None:
        raise TypeError(f"schema field {fd.full_name} is not an enum")
    return fd.enum_type


#: Every command of the schema, keyed by its Request oneof field, in schema order.
COMMANDS: dict[str, Command] = _load()
_BY_ANY: dict[str, Command] = {}
for _c in COMMANDS.values():
    for _k in (_c.field, _c.name, _c.cli_name):
        _BY_ANY[_k.lower()] = _c


def lookup(name: str) -> Command:
    """The command called `name` (oneof field, seed name or CLI name, any case)."""
    try:
        return _BY_ANY[name.lower()]
    except KeyError:
        raise ArgumentError(f"unknown command '{name}': `landscape --help` lists the commands") from None


def by_number(number: int) -> Command | None:
    for c in COMMANDS.values():
        if c.number == number:
            return c
    return None


# ---------------------------------------------------------------- enums


def _common_affixes(names: list[str]) -> tuple[list[str], list[str]]:
    parts = [n.split("_") for n in names]
    prefix: list[str] = []
    for toks in zip(*parts, strict=False):
        if len(set(toks)) == 1:
            prefix.append(toks[0])
        else:
            break
    suffix: list[str] = []
    for toks in zip(*(list(reversed(p)) for p in parts), strict=False):
        if len(set(toks)) == 1:
            suffix.insert(0, toks[0])
        else:
            break
    if len(names) < 2 or any(len(p) <= len(prefix) + len(suffix) for p in parts):
        return [], []
    return prefix, suffix


def enum_aliases(enum: EnumDescriptor) -> dict[str, int]:
    """Accepted spellings (lower case) of each value: the full name, the name without the
    tokens every value shares (JOINT_FRAME -> joint, CB_EVENT -> event) and its (symbol)
    when the schema gives one (MILLIMETERS -> mm, DEGREES -> deg)."""
    names = [v.name for v in enum.values]
    prefix, suffix = _common_affixes(names)
    out: dict[str, int] = {}
    for v in enum.values:
        out[v.name.lower()] = v.number
        toks = v.name.split("_")
        short = "_".join(toks[len(prefix):len(toks) - len(suffix)])
        if short:
            out.setdefault(short.lower(), v.number)
            out.setdefault(short.lower().replace("_", "-"), v.number)
        if v.GetOptions().HasExtension(_SYMBOL_OPTION):
            out.setdefault(v.GetOptions().Extensions[_SYMBOL_OPTION].lower(), v.number)
    return out


def parse_enum(enum: EnumDescriptor, value: Any) -> int:
    """An enum value from its number, its name (any case) or its short name."""
    if isinstance(value, bool):
        raise ArgumentError(f"{enum.name}: expected one of {enum_choices(enum)}, got {value!r}")
    if isinstance(value, int):
        if value not in enum.values_by_number:
            raise ArgumentError(f"{enum.name}: {value} is not a value; choose one of {enum_choices(enum)}")
        return value
    if isinstance(value, str):
        got = enum_aliases(enum).get(value.strip().lower())
        if got is not None:
            return got
    raise ArgumentError(f"{enum.name}: '{value}' is not a value; choose one of {enum_choices(enum)}")


def enum_choices(enum: EnumDescriptor) -> str:
    """The values' names, each with its (symbol) when it has one: `MILLIMETERS (mm)`."""
    def one(v: Any) -> str:
        opts = v.GetOptions()
        return f"{v.name} ({opts.Extensions[_SYMBOL_OPTION]})" if opts.HasExtension(_SYMBOL_OPTION) else str(v.name)

    return ", ".join(one(v) for v in enum.values)


# ---------------------------------------------------------------- builders


def is_repeated(fd: FieldDescriptor) -> bool:
    """True for a repeated field (protobuf 5+ spells it is_repeated, older ones label)."""
    flag = getattr(fd, "is_repeated", None)
    if flag is not None:
        return bool(flag)
    return bool(getattr(fd, "label", None) == FieldDescriptor.LABEL_REPEATED)


def _set_field(msg: Message, fd: FieldDescriptor, value: Any, where: str) -> None:
    repeated = is_repeated(fd)
    if repeated:
        if isinstance(value, (str, bytes)) or not isinstance(value, Iterable):
            raise ArgumentError(f"{where}.{fd.name}: expected a sequence, got {value!r}")
        items = list(value)
        container = getattr(msg, fd.name)
        del container[:]
        for item in items:
            if fd.type == FieldDescriptor.TYPE_MESSAGE:
                sub = container.add()
                _fill_message(sub, item, f"{where}.{fd.name}")
            else:
                container.append(_scalar(fd, item, where))
        return
    if fd.type == FieldDescriptor.TYPE_MESSAGE:
        _fill_message(getattr(msg, fd.name), value, f"{where}.{fd.name}")
        return
    setattr(msg, fd.name, _scalar(fd, value, where))


def _scalar(fd: FieldDescriptor, value: Any, where: str) -> Any:
    t = fd.type
    try:
        if t == FieldDescriptor.TYPE_ENUM:
            enum = field_enum_type(fd)
            try:
                return parse_enum(enum, value)
            except ArgumentError:  # parse_enum names the type only: say which argument it was
                raise ArgumentError(f"{where}.{fd.name}: {value!r} is not a {enum.name} value (one of "
                                    f"{enum_choices(enum)})") from None
        if t in (FieldDescriptor.TYPE_DOUBLE, FieldDescriptor.TYPE_FLOAT):
            if isinstance(value, bool):
                raise TypeError
            return float(value)
        if t == FieldDescriptor.TYPE_BOOL:
            if not isinstance(value, bool):
                raise TypeError
            return value
        if t == FieldDescriptor.TYPE_STRING:
            if not isinstance(value, str):
                raise TypeError
            return value
        if t == FieldDescriptor.TYPE_BYTES:
            return bytes(value)
        # integers: accept ints and integral strings ("0x0F")
        if isinstance(value, bool):
            raise TypeError
        v = int(value, 0) if isinstance(value, str) else int(value)
        if isinstance(value, float) and v != value:
            raise TypeError
        unsigned = t in (FieldDescriptor.TYPE_UINT32, FieldDescriptor.TYPE_UINT64,
                         FieldDescriptor.TYPE_FIXED32, FieldDescriptor.TYPE_FIXED64)
        bits = 64 if t in (FieldDescriptor.TYPE_INT64, FieldDescriptor.TYPE_UINT64,
                           FieldDescriptor.TYPE_SINT64, FieldDescriptor.TYPE_FIXED64,
                           FieldDescriptor.TYPE_SFIXED64) else 32
        lo, hi = (0, 2**bits - 1) if unsigned else (-(2**(bits - 1)), 2**(bits - 1) - 1)
        if not lo <= v <= hi:
            raise ArgumentError(f"{where}.{fd.name}: {v} is outside {lo}..{hi}")
        return v
    except ArgumentError:
        raise
    except (TypeError, ValueError):
        raise ArgumentError(f"{where}.{fd.name}: {value!r} is not a valid {_type_name(fd)}") from None


def _type_name(fd: FieldDescriptor) -> str:
    if fd.type == FieldDescriptor.TYPE_ENUM:
        enum = field_enum_type(fd)
        return f"{enum.name} ({enum_choices(enum)})"
    return {FieldDescriptor.TYPE_DOUBLE: "number", FieldDescriptor.TYPE_FLOAT: "number",
            FieldDescriptor.TYPE_STRING: "string", FieldDescriptor.TYPE_BOOL: "bool"}.get(fd.type, "integer")


def _fill_message(msg: Message, value: Any, where: str) -> None:
    if isinstance(value, Message):
        if value.DESCRIPTOR is not msg.DESCRIPTOR:
            raise ArgumentError(f"{where}: expected {msg.DESCRIPTOR.name}, got {value.DESCRIPTOR.name}")
        msg.CopyFrom(value)
        return
    if not isinstance(value, Mapping):
        raise ArgumentError(f"{where}: expected {msg.DESCRIPTOR.name} or a dict, got {value!r}")
    set_fields(msg, value, where)


def set_fields(msg: Message, values: Mapping[str, Any], where: str = "") -> Message:
    """Set `values` on `msg` by field name, checking names, types, ranges and enums."""
    where = where or msg.DESCRIPTOR.name
    fields = descriptor_of(msg).fields_by_name
    for key, value in values.items():
        fd = fields.get(key)
        if fd is None:
            raise ArgumentError(f"{where}: no field '{key}'; it has: {', '.join(fields) or 'no fields'}")
        if value is None:
            continue
        _set_field(msg, fd, value, where)
    return msg


def absent_means(fd: FieldDescriptor) -> Any:
    """What the device applies when the `optional` field `fd` is absent: its schema
    (ls.absent_means) parsed to the field's type (pathMove number_of_cycles: 1), or None."""
    text = fd.GetOptions().Extensions[_ABSENT_MEANS_OPTION]
    if not text:
        return None
    if fd.type == FieldDescriptor.TYPE_ENUM:
        return parse_enum(field_enum_type(fd), text)
    return float(text) if fd.type in (FieldDescriptor.TYPE_DOUBLE, FieldDescriptor.TYPE_FLOAT) else int(text, 0)


def is_required(fd: FieldDescriptor) -> bool:
    """True for an `optional` field the device refuses a request without ((ls.required):
    its absence would otherwise read as 0, which is a real value such as JOINT_FRAME)."""
    return bool(fd.GetOptions().Extensions[_REQUIRED_OPTION])


def required_fields(command: str | Command) -> tuple[FieldDescriptor, ...]:
    """The fields a request of `command` must carry (docs/protocol.md "Absent fields")."""
    cmd = command if isinstance(command, Command) else lookup(command)
    return tuple(fd for fd in cmd.fields() if is_required(fd))


def build_request(command: str | Command, seq: int = 0, **fields: Any) -> pb.Request:
    """A ``ls.Request`` for `command` with `fields` set; pure (no I/O).

    Enum fields take numbers, names or short names; repeated fields take
    sequences; message fields take messages or dicts. Unknown fields and bad
    values raise ArgumentError naming the field. A field the caller leaves out
    stays absent: the device applies its (ls.absent_means) (pathMove cycles: 1)
    and refuses a request without an (ls.required) one, naming it
    (``missing_required`` says so before sending).
    """
    cmd = command if isinstance(command, Command) else lookup(command)
    req = pb.Request(seq=seq)
    sub = getattr(req, cmd.field)
    sub.SetInParent()
    set_fields(sub, fields, cmd.name)
    return req


def missing_required(req: pb.Request) -> list[str]:
    """The (ls.required) fields `req` lacks, by name (empty: none)."""
    which = req.WhichOneof("cmd")
    if which is None:
        return []
    sub = getattr(req, which)
    return [fd.name for fd in required_fields(COMMANDS[which]) if not sub.HasField(fd.name)]


def message_to_dict(msg: Message) -> dict[str, Any]:
    """Every field of `msg` (defaults included) with schema field names and enum names."""
    return json_format.MessageToDict(msg, always_print_fields_with_no_presence=True,
                                     preserving_proto_field_name=True)
