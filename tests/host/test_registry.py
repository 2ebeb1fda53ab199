"""The registry is derived from the schema: every Request command, its CLI command and typed method."""
from __future__ import annotations

import inspect
from typing import Any

import click
import pytest
from google.protobuf.descriptor import FieldDescriptor

from landscape import ArgumentError, Supervisor, build_request, ls
from landscape.cli import cli
from landscape.registry import COMMANDS, absent_means, enum_aliases, is_repeated, is_required, kebab, lookup, parse_enum

REQUEST_FIELDS = [f.name for f in ls.Request.DESCRIPTOR.oneofs_by_name["cmd"].fields]


def test_registry_covers_every_request_field_in_schema_order() -> None:
    assert list(COMMANDS) == REQUEST_FIELDS
    assert len(COMMANDS) == 45
    for f in ls.Request.DESCRIPTOR.oneofs_by_name["cmd"].fields:
        c = COMMANDS[f.name]
        spec = f.message_type.GetOptions().Extensions[ls.cmd]
        assert (c.number, c.name, c.blocking, c.owner_only, c.host_timeout_ms, c.summary) == \
            (f.number, spec.name, spec.blocking, spec.owner_only, spec.host_timeout_ms, spec.summary)
        assert c.states == tuple(spec.states) and c.states
        assert c.response_type is ls.Response.DESCRIPTOR.fields_by_number[f.number].message_type


@pytest.mark.parametrize("seed,cli_name", [
    ("moveAbsolute", "move-absolute"), ("setDigitalIO", "set-digital-io"), ("getTagId", "get-tag-id"),
    ("pathClearPath", "path-clear-path"), ("lock", "lock"), ("getDigitalIO", "get-digital-io"),
    ("setWorldCartesianFrame", "set-world-cartesian-frame"), ("signalDigitalIO", "signal-digital-io"),
])
def test_kebab_names(seed: str, cli_name: str) -> None:
    assert kebab(seed) == cli_name


def test_cli_names_are_unique_and_lookup_accepts_all_three_names() -> None:
    names = [c.cli_name for c in COMMANDS.values()]
    assert len(set(names)) == len(names)
    c = COMMANDS["set_digital_io"]
    assert lookup("set_digital_io") is c and lookup("setDigitalIO") is c and lookup("set-digital-io") is c
    with pytest.raises(ArgumentError, match="unknown command 'fly'"):
        lookup("fly")


def test_every_schema_command_has_a_cli_subcommand_with_its_fields() -> None:
    ctx = click.Context(cli)
    for c in COMMANDS.values():
        sub = cli.get_command(ctx, c.cli_name)
        assert sub is not None, c.cli_name
        if c.field == "connect":
            continue  # the session runs the handshake; the subcommand shows its result
        got = {p.name for p in sub.params} - {"_no_wait", "_wait_timeout", "help"}
        assert got == {f.name for f in c.fields()}, c.cli_name
        assert ("_no_wait" in {p.name for p in sub.params}) == (not c.blocking)


def test_cli_argument_rule_for_move_absolute_and_set_digital_io() -> None:
    ctx = click.Context(cli)
    ma = cli.get_command(ctx, "move-absolute")
    assert [(p.name, type(p).__name__, p.nargs) for p in ma.params if isinstance(p, click.Argument)] == \
        [("point_name", "Argument", 1), ("frame", "Argument", 1), ("values", "Argument", -1)]
    opt = {p.name: p for p in ma.params if isinstance(p, click.Option)}
    assert opt["speed_pct"].default == 0.0 and opt["speed_pct"].opts == ["--speed-pct"]
    sd = cli.get_command(ctx, "set-digital-io")
    assert [p.name for p in sd.params if isinstance(p, click.Argument)] == ["type", "description"]
    assert [p.opts[0] for p in sd.params if isinstance(p, click.Option)] == ["--unit-id", "--bits-on", "--bits-off"]
    mr = cli.get_command(ctx, "move-react")
    assert [p.name for p in mr.params if isinstance(p, click.Argument)] == ["sensor_type", "motion_offsets"]
    assert "--thresholds" in [p.opts[0] for p in mr.params if isinstance(p, click.Option)]


def test_every_typed_method_matches_its_request_fields() -> None:
    for c in COMMANDS.values():
        if c.field == "challenge":
            continue  # the first step of a signed connect() (docs/protocol.md "Security"), no method of its own
        method = getattr(Supervisor, c.field, None)
        assert callable(method), f"Supervisor has no typed method {c.field}"
        if c.field in ("connect", "disconnect"):
            continue
        sig = inspect.signature(method)
        params = [p for p in sig.parameters.values() if p.name != "self" and p.kind != p.VAR_KEYWORD]
        assert {p.name for p in params} == {f.name for f in c.fields()}, c.field
        for p in params:
            if p.default is not p.empty:
                assert p.kind == p.KEYWORD_ONLY, f"{c.field}({p.name}) optional arguments are keyword-only"


#: The annotation a typed method gives a field of each schema type (as written, with
#: `from __future__ import annotations`): a schema type change fails here first.
ANNOTATION_OF_TYPE = {
    FieldDescriptor.TYPE_STRING: "str",
    FieldDescriptor.TYPE_BOOL: "bool",
    FieldDescriptor.TYPE_ENUM: "Enum",
    FieldDescriptor.TYPE_DOUBLE: "float",
    FieldDescriptor.TYPE_FLOAT: "float",
    FieldDescriptor.TYPE_INT32: "int",
    FieldDescriptor.TYPE_INT64: "int",
    FieldDescriptor.TYPE_UINT32: "int",
    FieldDescriptor.TYPE_UINT64: "int",
    FieldDescriptor.TYPE_SINT32: "int",
}


def expected_annotation(fd: FieldDescriptor) -> str:
    if fd.type == FieldDescriptor.TYPE_MESSAGE:
        one = f"pb.{fd.message_type.name} | Mapping[str, Any]"
    else:
        one = ANNOTATION_OF_TYPE[fd.type]
    return f"Sequence[{one}]" if is_repeated(fd) else one


def test_every_typed_method_has_its_fields_types_and_defaults() -> None:
    """Types follow the schema's field types; a default says what the schema says absence
    means: a plain field's zero value, an optional field's (ls.absent_means) or None (left
    out). A field the device requires ((ls.required)) is always sent: a default there is the
    method's own choice, a value of the field's enum, or None when the method derives it
    from its other arguments (its docstring says how)."""
    checked = 0
    for c in COMMANDS.values():
        if c.field in ("connect", "disconnect", "challenge"):
            continue
        sig = inspect.signature(getattr(Supervisor, c.field))
        for fd in c.fields():
            p = sig.parameters[fd.name]
            optional = fd.containing_oneof is not None and fd.containing_oneof.name == "_" + fd.name
            want = expected_annotation(fd)
            if optional and p.default is None:
                want += " | None"
            assert p.annotation == want, f"{c.field}({fd.name}): {p.annotation}, the schema says {want}"
            checked += 1
            if p.default is p.empty:
                continue
            if optional and is_required(fd) and p.default is None:
                doc = getattr(Supervisor, c.field).__doc__ or ""
                assert fd.name in doc, f"{c.field}({fd.name}) defaults to None: its docstring must say how it is set"
            elif optional and is_required(fd):
                assert fd.type == FieldDescriptor.TYPE_ENUM, f"{c.field}({fd.name}) required, defaulted"
                assert p.default in {v.number for v in fd.enum_type.values}, f"{c.field}({fd.name})"
            elif optional:
                assert p.default in (None, absent_means(fd)), f"{c.field}({fd.name}) default {p.default!r}"
            elif is_repeated(fd):
                assert tuple(p.default) == (), f"{c.field}({fd.name}) default {p.default!r}"
            else:
                zero = "" if fd.type == FieldDescriptor.TYPE_STRING else 0
                assert p.default == zero, f"{c.field}({fd.name}) default {p.default!r}, absence means {zero!r}"
    assert checked >= 70


@pytest.mark.parametrize("spelling", ["JOINT_FRAME", "joint_frame", "joint", "Joint", 0])
def test_enum_spellings(spelling: object) -> None:
    assert parse_enum(ls.ReferenceFrame.DESCRIPTOR, spelling) == ls.JOINT_FRAME


def test_enum_short_names_strip_common_prefix_and_suffix() -> None:
    assert enum_aliases(ls.CallbackType.DESCRIPTOR)["event_rsvp"] == ls.CB_EVENT_RSVP
    assert enum_aliases(ls.SpeedType.DESCRIPTOR)["linear"] == ls.LINEAR_SPEED
    assert enum_aliases(ls.LinearUnit.DESCRIPTOR)["millimeters"] == ls.MILLIMETERS
    with pytest.raises(ArgumentError, match="choose one of JOINT_FRAME, BASE_CARTESIAN_FRAME"):
        parse_enum(ls.ReferenceFrame.DESCRIPTOR, "sideways")
    with pytest.raises(ArgumentError):
        parse_enum(ls.ReferenceFrame.DESCRIPTOR, 9)


@pytest.mark.parametrize(("enum", "spelling", "value"), [
    (ls.LinearUnit, "mm", ls.MILLIMETERS), (ls.LinearUnit, "M", ls.METERS), (ls.LinearUnit, "in", ls.INCHES),
    (ls.AngularUnit, "deg", ls.DEGREES), (ls.AngularUnit, "rad", ls.RADIANS)])
def test_a_unit_is_also_spelled_by_its_symbol(enum: Any, spelling: str, value: int) -> None:
    """The symbols the tool prints (`joints (deg)`, `0.5 mm`) are accepted back (set-units mm deg)."""
    assert parse_enum(enum.DESCRIPTOR, spelling) == value
    with pytest.raises(ArgumentError, match=r"choose one of METERS \(m\), MILLIMETERS \(mm\)"):
        parse_enum(ls.LinearUnit.DESCRIPTOR, "km")


def test_build_request_is_pure_and_exact() -> None:
    req = build_request("moveAbsolute", 7, point_name="p1", values=[0.1, -0.2], frame="world_cartesian", speed_pct=50)
    want = ls.Request(seq=7, move_absolute=ls.MoveAbsoluteReq(point_name="p1", values=[0.1, -0.2],
                                                              frame=ls.WORLD_CARTESIAN_FRAME, speed_pct=50.0))
    assert req == want
    assert req.SerializeToString() == want.SerializeToString()
    lock = build_request("lock", 1)
    assert lock.WhichOneof("cmd") == "lock" and lock.SerializeToString() == b"\x08\x01\x92\x01\x00"


def test_build_request_path_load_with_dict_tags() -> None:
    req = build_request("path-load", 3, path_name="a", tags=[{"joints": [1, 2], "tag_name": "t"}],
                        number_of_points=1)
    assert req.path_load.tags[0] == ls.TagPoint(joints=[1.0, 2.0], tag_name="t")


@pytest.mark.parametrize("fields,msg", [
    ({"nope": 1}, "no field 'nope'"),
    ({"values": 3.0}, "expected a sequence"),
    ({"values": ["x"]}, "'x' is not a valid number"),
    ({"point_name": 5}, "is not a valid string"),
    ({"frame": "up"}, r"^moveAbsolute\.frame: 'up' is not a ReferenceFrame value \(one of JOINT_FRAME, "),
    ({"frame": 9}, r"^moveAbsolute\.frame: 9 is not a ReferenceFrame value"),
    ({"frame": True}, r"^moveAbsolute\.frame: True is not a ReferenceFrame value"),
])
def test_build_request_rejects_bad_fields(fields: dict[str, object], msg: str) -> None:
    with pytest.raises(ArgumentError, match=msg):
        build_request("move_absolute", **fields)


def test_integer_ranges() -> None:
    with pytest.raises(ArgumentError, match="outside 0..4294967295"):
        build_request("set_digital_io", bits_on=-1)
    assert build_request("set_digital_io", bits_on="0x0F").set_digital_io.bits_on == 15
    with pytest.raises(ArgumentError, match="not a valid integer"):
        build_request("set_digital_io", unit_id=1.5)


def test_repeated_fields_detected() -> None:
    f = ls.MoveAbsoluteReq.DESCRIPTOR.fields_by_name
    assert is_repeated(f["values"]) and not is_repeated(f["point_name"])


def test_absent_fields_stay_absent_and_the_schema_says_what_absent_means() -> None:
    """docs/protocol.md "Absent fields": the host sends what the caller gives; the device
    applies (ls.absent_means) and refuses a request without an (ls.required) field."""
    from landscape.registry import absent_means, build_request, missing_required, required_fields
    pm = build_request("pathMove", path_name="p").path_move
    assert not pm.HasField("number_of_cycles")
    assert absent_means(ls.PathMoveReq.DESCRIPTOR.fields_by_name["number_of_cycles"]) == 1
    zero = build_request("pathMove", path_name="p", number_of_cycles=0).path_move
    assert zero.HasField("number_of_cycles") and zero.number_of_cycles == 0  # 0 is sent: the dry run
    assert [f.name for f in required_fields("moveAbsolute")] == ["frame"]
    assert missing_required(build_request("moveAbsolute", point_name="p")) == ["frame"]
    assert missing_required(build_request("moveAbsolute", point_name="p", frame="joint")) == []
    assert missing_required(build_request("pathLoad", path_name="p")) == ["frame", "motion_type", "offset_type",
                                                                           "number_of_points"]
    assert build_request("moveAbsolute", point_name="p").move_absolute.speed_pct == 0.0


def test_every_optional_request_field_says_what_its_absence_means() -> None:
    """The generator's rule, seen from the host: an `optional` field is required or has a default."""
    from landscape.registry import COMMANDS, absent_means, is_required
    seen = 0
    for cmd in COMMANDS.values():
        for fd in cmd.fields():
            o = fd.containing_oneof
            if o is not None and o.name == "_" + fd.name:
                seen += 1
                assert is_required(fd) != (absent_means(fd) is not None), fd.full_name
    assert seen >= 20
