#!/usr/bin/env python3
"""Derive the firmware's command table from protocol/landscape.proto.

Input is the Python module protoc generated from the schema (so the custom
options are read exactly as protoc parsed them) and the descriptor set protoc
wrote beside it (landscape.desc, the schema hash's input). Output:

  ls_cmd_table.h / ls_cmd_table.c   the dispatch table: id, name, valid-state
                                    mask, flags, host time-out and handler of
                                    every command, plus the schema hash, and
                                    the names of string and message fields
                                    (ls_field_name) for errors naming a field,
                                    and the event ids' data keys
                                    (ls_event_find, ls_event_key_declared),
                                    and the text the schema gives enum values
                                    (ls_linear_unit, ls_angular_unit,
                                    ls_motion_end_text, ls_motion_end_suffix).

The host reads the same options from the same descriptors at import time
(host_tools/src/landscape/registry.py), so there is no second list.

and, with --index, the committed command index (docs/handlers.md): each
command from its name on the wire to its handler, the file that defines it
and its final notices, so that a grep for a wire name or a notice's event id
leads to the code (tests/host/test_generated.py fails while it is stale).

Usage: gen_registry.py GEN_DIR OUT_DIR   (GEN_DIR holds landscape_pb2.py and landscape.desc)
       gen_registry.py --index GEN_DIR CORE_DIR OUT_FILE   (CORE_DIR: firmware/core)
"""
from __future__ import annotations

import hashlib
import importlib.util
import re
import sys
from pathlib import Path


def load_pb2(pb2_dir: Path):
    spec = importlib.util.spec_from_file_location("landscape_pb2", pb2_dir / "landscape_pb2.py")
    if spec is None or spec.loader is None:
        raise SystemExit(f"gen_registry: no landscape_pb2.py in {pb2_dir}")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def schema_hash(desc: bytes) -> int:
    """The schema hash: the first 4 bytes, big-endian, of the SHA-256 of the file
    `protoc --descriptor_set_out` writes for landscape.proto (the recipe in
    docs/protocol.md, "Schema hash").

    Without --include_source_info the set carries no comments, so a comment
    change does not change the hash; any change of a message, field, enum or
    option does. The host hashes its committed copy of the same file.
    """
    return int.from_bytes(hashlib.sha256(desc).digest()[:4], "big")


#: How a non-blocking command's final notices end, in ls_cmd_finals_t's order.
FINAL_SUFFIXES = ("Complete", "Aborted", "Failed", "Envelope", "Timeout", "PanicStop")


def snake(name: str) -> str:
    return re.sub(r"(?<!^)(?=[A-Z])", "_", name).lower().replace("digital_i_o", "digital_io")


def commands(pb2):
    req = pb2.DESCRIPTOR.message_types_by_name["Request"]
    res = pb2.DESCRIPTOR.message_types_by_name["Response"]
    out = []
    for field in req.oneofs_by_name["cmd"].fields:
        spec = field.message_type.GetOptions().Extensions[pb2.cmd]
        if not spec.name:
            raise SystemExit(f"gen_registry: {field.message_type.name} has no (ls.cmd) option")
        rfield = res.fields_by_number.get(field.number)
        if rfield is None or rfield.name != field.name:
            raise SystemExit(f"gen_registry: Response.result has no field {field.number} '{field.name}' "
                             f"matching Request.cmd; the two oneofs must mirror each other")
        mask = 0
        for s in spec.states:
            mask |= s
        if mask == 0:
            raise SystemExit(f"gen_registry: command {spec.name} lists no states")
        out.append((field.number, field.name, spec, mask))
    return out


def is_proto3_optional(f) -> bool:
    """A scalar declared `optional` in proto3 (it sits in a synthetic oneof "_name")."""
    o = f.containing_oneof
    return o is not None and o.name == "_" + f.name and f.type != f.TYPE_MESSAGE


def ext(f, pb2, name):
    return f.GetOptions().Extensions[getattr(pb2, name)]


def c_literal(f, text: str) -> str:
    """The C value of an (ls.absent_means) text for field f."""
    if f.type == f.TYPE_ENUM:
        enum = f.enum_type
        if text in enum.values_by_name:
            return f"ls_{enum.name}_{text}"
        return f"(ls_{enum.name}){int(text, 0)}"
    if f.type in (f.TYPE_DOUBLE, f.TYPE_FLOAT):
        return repr(float(text))
    if f.type == f.TYPE_BOOL:
        if text not in ("true", "false"):
            raise SystemExit(f"gen_registry: {f.full_name}: absent_means of a bool is true or false")
        return text
    value = int(text, 0)
    return f"{value}" + ("u" if f.type in (f.TYPE_UINT32, f.TYPE_FIXED32) else "")


def presence_rules(pb2, cmds):
    """(command field, [(field, 'required'|'default', C value)]) of every command whose
    request has proto3 `optional` fields; every optional field must carry exactly one of
    (ls.required) and (ls.absent_means) (docs/protocol.md "Absent fields")."""
    out = []
    req = pb2.DESCRIPTOR.message_types_by_name["Request"]
    for num, fname, _spec, _mask in cmds:
        mdesc = req.fields_by_number[num].message_type
        rules = []
        for f in mdesc.fields:
            required = ext(f, pb2, "required")
            absent = ext(f, pb2, "absent_means")
            if not is_proto3_optional(f):
                if required or absent:
                    raise SystemExit(f"gen_registry: {f.full_name} has (ls.required)/(ls.absent_means) but is not "
                                     f"`optional`: declare it optional so that its absence can be seen")
                continue
            if bool(required) == bool(absent):
                raise SystemExit(f"gen_registry: optional field {f.full_name} needs exactly one of (ls.required) "
                                 f"and (ls.absent_means)")
            rules.append((f.name, "required" if required else "default", None if required else c_literal(f, absent)))
        if rules:
            out.append((fname, rules))
    return out


#: Entries of FieldLimit.path (landscape.options) and of ls_field_limit_t.path.
FIELD_PATH_MAX = 4


def uplink_limits(pb2):
    """Every bounded (string, bytes or repeated) field reachable from ls.Uplink, as
    (path of field numbers, C message type, field name, "string" | "bytes" | "", is repeated)."""
    return bounded_fields(pb2, "Uplink", strings_only=False)


#: The description's own messages: their strings are the description (names the
#: HAL and the model give), not texts about a request; downlink_limits leaves them out.
DESCRIPTIONS = ("DescribeRes", "DescribeRobotRes")


def downlink_limits(pb2):
    """Every string field reachable from ls.Downlink outside the description itself (the
    texts the device sends: answers, notices, acknowledgements, query results), as
    uplink_limits gives them: what a client may expect whole (describe)."""
    return bounded_fields(pb2, "Downlink", strings_only=True)


def bounded_fields(pb2, root, *, strings_only):
    out = []

    def walk(mdesc, path, depth):
        if strings_only and mdesc.name in DESCRIPTIONS:
            return
        if depth >= FIELD_PATH_MAX:
            raise SystemExit(f"gen_registry: ls.{root} nests deeper than FieldLimit.path holds")
        for f in mdesc.fields:
            repeated = f.label == f.LABEL_REPEATED
            if f.type == f.TYPE_MESSAGE:
                if repeated and not strings_only:
                    out.append((path + [f.number], mdesc.name, f.name, False, True))
                walk(f.message_type, path + [f.number], depth + 1)
            elif strings_only:
                if f.type == f.TYPE_STRING:
                    out.append((path + [f.number], mdesc.name, f.name, "string", repeated))
            elif f.type in (f.TYPE_STRING, f.TYPE_BYTES) or repeated:
                if f.type == f.TYPE_BYTES and repeated:
                    raise SystemExit(f"gen_registry: {f.full_name}: repeated bytes fields are not described")
                if is_proto3_optional(f) and mdesc.name not in top_requests:
                    raise SystemExit(f"gen_registry: {f.full_name}: optional fields are handled in requests only")
                kind = "string" if f.type == f.TYPE_STRING else "bytes" if f.type == f.TYPE_BYTES else ""
                out.append((path + [f.number], mdesc.name, f.name, kind, repeated))
            elif is_proto3_optional(f) and mdesc.name not in top_requests:
                raise SystemExit(f"gen_registry: {f.full_name}: optional fields are handled in requests only")

    req = pb2.DESCRIPTOR.message_types_by_name["Request"]
    top_requests = {f.message_type.name for f in req.oneofs_by_name["cmd"].fields}
    walk(pb2.DESCRIPTOR.message_types_by_name[root], [], 0)
    return out


def events(pb2, cmds):
    """(name, number, [keys]) of every EventId value but EVENT_ID_NONE. Every non-blocking
    command must declare its final notices <name>Complete, <name>Aborted, <name>Failed
    (docs/protocol.md "Motion lifecycle")."""
    enum = pb2.DESCRIPTOR.enum_types_by_name["EventId"]
    out = []
    for v in enum.values:
        if v.number == 0:
            continue
        keys = v.GetOptions().Extensions[pb2.notice_keys].split()
        if not keys:
            raise SystemExit(f"gen_registry: EventId {v.name} declares no (ls.notice_keys)")
        out.append((v.name, v.number, keys))
    names = {e[0] for e in out}
    for _num, _fname, spec, _mask in cmds:
        if spec.blocking:
            continue
        for suffix in ("Complete", "Aborted", "Failed"):
            if spec.name + suffix not in names:
                raise SystemExit(f"gen_registry: non-blocking command {spec.name} ends with {spec.name}{suffix}: "
                                 f"declare it in enum EventId")
    return out


def enum_texts(pb2, enum_name: str, options: tuple[str, ...]):
    """[(C enum constant, {option: value})] of every value of `enum_name`; each one must
    carry every option in `options` (the schema is their one home)."""
    enum = pb2.DESCRIPTOR.enum_types_by_name[enum_name]
    out = []
    for v in enum.values:
        opts = {}
        for o in options:
            ext_field = getattr(pb2, o)
            if not v.GetOptions().HasExtension(ext_field):
                raise SystemExit(f"gen_registry: {enum_name}.{v.name} has no ({o}) option")
            opts[o] = v.GetOptions().Extensions[ext_field]
        out.append((f"ls_{enum_name}_{v.name}", opts))
    return out


def c_string(text: str) -> str:
    if any(c in text for c in '"\\\n'):
        raise SystemExit(f"gen_registry: {text!r}: quotes, backslashes and line breaks are not written to C")
    return f'"{text}"'


def handler_index(pb2, core_dir: Path) -> str:
    """The command index (docs/handlers.md) as Markdown."""
    cmds = commands(pb2)
    evs = {e[0] for e in events(pb2, cmds)}
    defined: dict[str, str] = {}
    for path in sorted(core_dir.glob("*.c")):
        for m in re.finditer(r"^int32_t (ls_h_\w+)\(", path.read_text(), flags=re.M):
            defined[m.group(1)] = f"firmware/core/{path.name}"
    lines = [
        "# Command index",
        "",
        "Generated by `protocol/gen_registry.py --index` from `protocol/landscape.proto` and the",
        "handlers in `firmware/core`; `sh host_tools/update_generated.sh` rewrites it and",
        "`tests/host/test_generated.py` fails while it is stale. Do not edit.",
        "",
        "Each command from its name on the wire to the code that runs it: the dispatcher",
        "(`firmware/core/ls_dispatch.c`) finds the handler in the generated `ls_cmd_table` by the",
        "request's field number, checks the valid states and the owner rule, then calls it",
        "(docs/architecture.md \"Core layers\"). A non-blocking command ends with exactly one of",
        "its final notices (docs/protocol.md \"Motion lifecycle\"), the `ls_EventId_*` values of",
        "its `ls_cmd_finals_t`.",
        "",
        "| command | id | handler | defined in | final notices |",
        "|---|---|---|---|---|",
    ]
    for num, fname, spec, _mask in cmds:
        handler = f"ls_h_{fname}"
        where = defined.get(handler)
        if where is None:
            raise SystemExit(f"gen_registry: {handler} ({spec.name}) is defined in no {core_dir}/*.c")
        finals = "" if spec.blocking else ", ".join(
            f"`{spec.name}{sfx}`" for sfx in FINAL_SUFFIXES if spec.name + sfx in evs)
        lines.append(f"| `{spec.name}` | {num} | `{handler}` | `{where}` | {finals} |")
    return "\n".join(lines) + "\n"


def main() -> int:
    if len(sys.argv) == 5 and sys.argv[1] == "--index":
        Path(sys.argv[4]).write_text(handler_index(load_pb2(Path(sys.argv[2])), Path(sys.argv[3])))
        return 0
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    pb2 = load_pb2(Path(sys.argv[1]))
    out_dir = Path(sys.argv[2])
    out_dir.mkdir(parents=True, exist_ok=True)
    cmds = commands(pb2)
    rules = presence_rules(pb2, cmds)
    limits = uplink_limits(pb2)
    down_limits = downlink_limits(pb2)
    evs = events(pb2, cmds)
    linear = enum_texts(pb2, "LinearUnit", ("text", "symbol", "si_per_unit"))
    angular = enum_texts(pb2, "AngularUnit", ("text", "symbol", "si_per_unit"))
    ends = enum_texts(pb2, "MotionEnd", ("text", "final_suffix"))
    for _c, o in ends:
        if o["final_suffix"] not in ("Complete", "Failed", "Aborted"):
            raise SystemExit(f"gen_registry: MotionEnd final_suffix {o['final_suffix']!r}: Complete, Failed or Aborted")
    h = schema_hash((Path(sys.argv[1]) / "landscape.desc").read_bytes())

    hdr = [
        "/* Generated by protocol/gen_registry.py from protocol/landscape.proto. Do not edit. */",
        "#ifndef LS_CMD_TABLE_H",
        "#define LS_CMD_TABLE_H",
        "#include <stdbool.h>",
        "#include <stddef.h>",
        "#include <stdint.h>",
        '#include "landscape.pb.h"',
        "",
        f"#define LS_SCHEMA_HASH 0x{h:08X}u",
        f"#define LS_CMD_COUNT {len(cmds)}u",
        "",
        "/* Command flags (ls_cmd_desc_t.flags). */",
        "#define LS_CMD_F_BLOCKING   0x01u /* answers when done; else CMD_STARTED_OK then one event or alarm */",
        "#define LS_CMD_F_OWNER_ONLY 0x02u /* only the supervisor that locked may call it */",
        "#define LS_CMD_F_QUERY      0x04u /* reads and changes nothing (docs/protocol.md \"Security\") */",
        "",
        "struct ls_core;",
        "struct ls_call;",
        "/* A command handler. Runs in the dispatcher (never in the control loop).",
        " * It fills call->res and returns the ret_code, or LS_CALL_DEFERRED when the",
        " * response will be sent later by ls_core_finish_deferred(). */",
        "typedef int32_t (*ls_cmd_handler_fn)(struct ls_core *core, struct ls_call *call);",
        "",
        "/* The final notices of a non-blocking command (docs/protocol.md \"Motion",
        " * lifecycle\"): the schema's <name>Complete, <name>Aborted and <name>Failed and,",
        " * where it declares them (the sensor-guided moves), <name>Envelope,",
        " * <name>Timeout and <name>PanicStop; ls_EventId_EVENT_ID_NONE otherwise. */",
        "typedef struct {",
        "    ls_EventId complete;",
        "    ls_EventId aborted;",
        "    ls_EventId failed;",
        "    ls_EventId envelope;",
        "    ls_EventId timeout;",
        "    ls_EventId panic_stop;",
        "} ls_cmd_finals_t;",
        "",
        "typedef struct {",
        "    pb_size_t tag;            /* ls_Request.which_cmd == ls_Response.which_result */",
        "    const char *name;         /* the seed's name */",
        "    uint8_t states;           /* mask of ls_State values */",
        "    uint8_t flags;            /* LS_CMD_F_* */",
        "    uint32_t host_timeout_ms;",
        "    ls_cmd_handler_fn handler;",
        "    const ls_cmd_finals_t *finals; /* non-blocking commands; NULL for blocking ones */",
        "} ls_cmd_desc_t;",
        "",
        "extern const ls_cmd_desc_t ls_cmd_table[LS_CMD_COUNT];",
        "",
        "/* The descriptor of a command id, or NULL when the id is not in the schema. O(1). */",
        "const ls_cmd_desc_t *ls_cmd_find(pb_size_t tag);",
        "",
        "/* One handler per command: connect and disconnect in firmware/core/ls_session.c,",
        " * every other one in the firmware/core/cmd_*.c file of its group (docs/handlers.md",
        " * lists each command's handler and file). */",
    ]
    for _num, fname, _spec, _mask in cmds:
        hdr.append(f"int32_t ls_h_{fname}(struct ls_core *core, struct ls_call *call);")
    hdr += [
        "",
        "/* The schema's name of field `tag` of message `msg` (string, bytes, message",
        " * and repeated fields, for error messages naming a field), or NULL. */",
        "const char *ls_field_name(const pb_msgdesc_t *msg, uint32_t tag);",
        "",
        "/* Presence rules of the requests' `optional` fields (docs/protocol.md \"Absent",
        " * fields\"): returns the name of the first (ls.required) field of `rq` that is",
        " * absent (and changes nothing), else applies every absent field's",
        " * (ls.absent_means) to `rq` and returns NULL. Dispatcher only; O(fields). */",
        "const char *ls_request_presence(ls_Request *rq);",
        "",
        "/* The bound of one string or repeated field of ls.Uplink or ls.Downlink (describe). */",
        "typedef struct {",
        "    uint8_t depth;   /* entries of path */",
        f"    uint8_t path[{FIELD_PATH_MAX}]; /* field numbers from ls.Uplink (ls.Downlink) down */",
        "    uint32_t max_bytes; /* strings: longest UTF-8 text in bytes, else 0 */",
        "    uint32_t max_count; /* repeated: most items, else 0 */",
        "} ls_field_limit_t;",
        "",
        "/* Every bounded field of what a supervisor sends (describe: field_limits). */",
        f"#define LS_FIELD_LIMIT_COUNT {len(limits)}u",
        "extern const ls_field_limit_t ls_field_limits[LS_FIELD_LIMIT_COUNT];",
        "/* Every text the device sends (describe: downlink_limits). */",
        f"#define LS_DOWNLINK_LIMIT_COUNT {len(down_limits)}u",
        "extern const ls_field_limit_t ls_downlink_limits[LS_DOWNLINK_LIMIT_COUNT];",
        "",
        "/* Event ids (enum ls.EventId; the name on the wire is ls_EventId_name(id)). */",
        "/* The id whose name is `name`, or ls_EventId_EVENT_ID_NONE when the schema",
        " * declares no such event (a path's own `event NAME`). Dispatcher; O(ids). */",
        "ls_EventId ls_event_find(const char *name);",
        "/* True when the schema lets the notices of `id` carry data key `key` (the",
        " * first `len` bytes): its (ls.notice_keys). Any context; O(keys). */",
        "bool ls_event_key_declared(ls_EventId id, const char *key, size_t len);",
        "",
        "/* A unit of setUnits (enum LinearUnit, AngularUnit): its (ls.text), the name",
        " * getUnits answers, its (ls.symbol) and its (ls.si_per_unit), metres or",
        " * radians per unit. NULL for a value outside the enum. Any context; O(1). */",
        "typedef struct {",
        "    const char *text;",
        "    const char *symbol;",
        "    double si_per_unit;",
        "} ls_unit_desc_t;",
        "const ls_unit_desc_t *ls_linear_unit(ls_LinearUnit u);",
        "const ls_unit_desc_t *ls_angular_unit(ls_AngularUnit u);",
        "",
        "/* A motion's ending (enum MotionEnd): its (ls.text), the final notice's",
        " * reason=, and its (ls.final_suffix), how that notice's event id ends",
        " * (\"Complete\", \"Failed\", \"Aborted\"). \"unknown\" and \"Failed\" outside the",
        " * enum. Any context; O(1). */",
        "const char *ls_motion_end_text(ls_MotionEnd e);",
        "const char *ls_motion_end_suffix(ls_MotionEnd e);",
        "/* The final notice of a command with finals `f` that ends as `e`: the",
        " * member its (ls.final_suffix) names. EVENT_ID_NONE for f NULL. O(1). */",
        "ls_EventId ls_motion_end_final(const ls_cmd_finals_t *f, ls_MotionEnd e);",
        "",
        "#endif /* LS_CMD_TABLE_H */",
        "",
    ]

    lo = min(c[0] for c in cmds)
    hi = max(c[0] for c in cmds)
    src = [
        "/* Generated by protocol/gen_registry.py from protocol/landscape.proto. Do not edit. */",
        '#include "ls_cmd_table.h"',
        "#include <stddef.h>",
        "",
        "#include <string.h>",
        "",
    ]
    event_names = {e[0] for e in evs}
    for _num, fname, spec, _mask in cmds:
        if spec.blocking:
            continue
        ids = [f"ls_EventId_{spec.name}{sfx}" if spec.name + sfx in event_names else "ls_EventId_EVENT_ID_NONE"
               for sfx in FINAL_SUFFIXES]
        src.append(f"static const ls_cmd_finals_t k_finals_{fname} = {{ {', '.join(ids)} }};")
    src += [
        "",
        "const ls_cmd_desc_t ls_cmd_table[LS_CMD_COUNT] = {",
    ]
    for num, fname, spec, mask in cmds:
        flags = []
        if spec.blocking:
            flags.append("LS_CMD_F_BLOCKING")
        if spec.owner_only:
            flags.append("LS_CMD_F_OWNER_ONLY")
        if spec.query:
            if spec.owner_only or not spec.blocking:
                raise SystemExit(f"gen_registry: {spec.name} is a query: it can be neither owner-only nor non-blocking")
            flags.append("LS_CMD_F_QUERY")
        finals = "NULL" if spec.blocking else f"&k_finals_{fname}"
        src.append(f"    {{ {num}u, \"{spec.name}\", 0x{mask:02X}u, {' | '.join(flags) or '0u'}, "
                   f"{spec.host_timeout_ms}u, ls_h_{fname}, {finals} }},")
    src += [
        "};",
        "",
        "const ls_cmd_desc_t *ls_cmd_find(pb_size_t tag)",
        "{",
        f"    if (tag < {lo}u || tag > {hi}u) {{",
        "        return NULL;",
        "    }",
        f"    const ls_cmd_desc_t *d = &ls_cmd_table[tag - {lo}u];",
        "    return d->tag == tag ? d : NULL;",
        "}",
        "",
    ]
    # Field names for the string, bytes, message and repeated fields of every
    # message (nanopb's descriptors carry numbers only), and for the enum and
    # uint32 fields of what the device decodes (reachable from Uplink): a value
    # their C type cannot hold (a -1 for an enum) is refused naming them.
    names = []
    # option types (CommandSpec) are metadata that nanopb skips (landscape.options)
    meta = {e.message_type.name for e in pb2.DESCRIPTOR.extensions_by_name.values() if e.message_type}
    uplink: set[str] = set()
    todo = [pb2.DESCRIPTOR.message_types_by_name["Uplink"]]
    while todo:
        m = todo.pop()
        if m.name not in uplink:
            uplink.add(m.name)
            todo += [f.message_type for f in m.fields if f.message_type is not None]
    for mname, mdesc in sorted(pb2.DESCRIPTOR.message_types_by_name.items()):
        if mname in meta:
            continue
        if mdesc.nested_types:
            raise SystemExit(f"gen_registry: {mname} has nested message types; name them in ls_field_name")
        for f in mdesc.fields:
            if f.type in (f.TYPE_STRING, f.TYPE_BYTES, f.TYPE_MESSAGE) or f.label == f.LABEL_REPEATED or (
                    mname in uplink and f.type in (f.TYPE_ENUM, f.TYPE_UINT32)):
                names.append((mname, f.number, f.name))
    src += [
        "typedef struct {",
        "    const pb_msgdesc_t *msg;",
        "    uint32_t tag;",
        "    const char *name;",
        "} ls_field_name_t;",
        "",
        "static const ls_field_name_t k_field_names[] = {",
    ]
    for mname, num, fname in names:
        src.append(f"    {{ &ls_{mname}_msg, {num}u, \"{fname}\" }},")
    src += [
        "};",
        "",
        "const char *ls_field_name(const pb_msgdesc_t *msg, uint32_t tag)",
        "{",
        "    for (size_t i = 0; i < sizeof k_field_names / sizeof k_field_names[0]; i++) {",
        "        if (k_field_names[i].msg == msg && k_field_names[i].tag == tag) {",
        "            return k_field_names[i].name;",
        "        }",
        "    }",
        "    return NULL;",
        "}",
        "",
    ]
    src += [
        "const char *ls_request_presence(ls_Request *rq)",
        "{",
        "    switch (rq->which_cmd) {",
    ]
    for fname, frules in rules:
        src.append(f"    case ls_Request_{fname}_tag:")
        for name, kind, _v in frules:
            if kind == "required":
                src += [f"        if (!rq->cmd.{fname}.has_{name}) {{", f"            return \"{name}\";", "        }"]
        for name, kind, v in frules:
            if kind == "default":
                src += [f"        if (!rq->cmd.{fname}.has_{name}) {{",
                        f"            rq->cmd.{fname}.{name} = {v};", "        }"]
        src.append("        break;")
    src += [
        "    default: break;",
        "    }",
        "    return NULL;",
        "}",
        "",
    ]
    for table, count, rows in (("ls_field_limits", "LS_FIELD_LIMIT_COUNT", limits),
                               ("ls_downlink_limits", "LS_DOWNLINK_LIMIT_COUNT", down_limits)):
        src.append(f"const ls_field_limit_t {table}[{count}] = {{")
        for path, mname, fname, kind, rep in rows:
            ptxt = ", ".join(f"{n}u" for n in path)
            one = f"((ls_{mname} *)0)->{fname}"
            if kind == "string" and rep:
                mb = f"(uint32_t)(sizeof {one}[0] - 1u)"
            elif kind == "string":
                mb = f"(uint32_t)(sizeof {one} - 1u)"
            elif kind == "bytes":
                mb = f"(uint32_t)sizeof {one}.bytes"
            else:
                mb = "0u"
            mc = f"(uint32_t)pb_arraysize(ls_{mname}, {fname})" if rep else "0u"
            src.append(f"    {{ {len(path)}u, {{ {ptxt} }}, {mb}, {mc} }}, /* {mname}.{fname} */")
        src += ["};", ""]
    src += [
        "typedef struct {",
        "    ls_EventId id;",
        "    const char *name;",
        "    const char *const *keys; /* NULL-terminated */",
        "} ls_event_desc_t;",
        "",
    ]
    for name, _num, keys in evs:
        src.append(f"static const char *const k_keys_{name}[] = {{ " + ", ".join(f'"{k}"' for k in keys) + ", NULL };")
    src += ["", "static const ls_event_desc_t k_events[] = {"]
    for name, _num, _keys in evs:
        src.append(f"    {{ ls_EventId_{name}, \"{name}\", k_keys_{name} }},")
    src += [
        "};",
        "",
        "ls_EventId ls_event_find(const char *name)",
        "{",
        "    for (size_t i = 0; i < sizeof k_events / sizeof k_events[0]; i++) {",
        "        if (k_events[i].id != ls_EventId_AUX_NAMED_EVENT && strcmp(k_events[i].name, name) == 0) {",
        "            return k_events[i].id;",
        "        }",
        "    }",
        "    return ls_EventId_EVENT_ID_NONE;",
        "}",
        "",
        "bool ls_event_key_declared(ls_EventId id, const char *key, size_t len)",
        "{",
        "    for (size_t i = 0; i < sizeof k_events / sizeof k_events[0]; i++) {",
        "        if (k_events[i].id != id) {",
        "            continue;",
        "        }",
        "        for (const char *const *k = k_events[i].keys; *k != NULL; k++) {",
        "            if (strlen(*k) == len && strncmp(*k, key, len) == 0) {",
        "                return true;",
        "            }",
        "        }",
        "    }",
        "    return false;",
        "}",
        "",
    ]
    for fn, kind, units in (("ls_linear_unit", "ls_LinearUnit", linear), ("ls_angular_unit", "ls_AngularUnit", angular)):
        src += [f"const ls_unit_desc_t *{fn}({kind} u)", "{", "    static const ls_unit_desc_t k[] = {"]
        for const, o in units:
            src.append(f"        [{const}] = {{ {c_string(o['text'])}, {c_string(o['symbol'])}, {o['si_per_unit']!r} }},")
        src += ["    };",
                "    return (unsigned)u < sizeof k / sizeof k[0] && k[u].text != NULL ? &k[u] : NULL;",
                "}", ""]
    src += ["ls_EventId ls_motion_end_final(const ls_cmd_finals_t *f, ls_MotionEnd e)", "{",
            "    if (f == NULL) {", "        return ls_EventId_EVENT_ID_NONE;", "    }", "    switch (e) {"]
    for const, o in ends:
        src.append(f"    case {const}: return f->{o['final_suffix'].lower()};")
    src += ["    }", "    return f->failed;", "}", ""]
    for fn, opt, none in (("ls_motion_end_text", "text", "unknown"), ("ls_motion_end_suffix", "final_suffix", "Failed")):
        src += [f"const char *{fn}(ls_MotionEnd e)", "{", "    switch (e) {"]
        for const, o in ends:
            src.append(f"    case {const}: return {c_string(o[opt])};")
        src += ["    }", f"    return \"{none}\";", "}", ""]
    nums = [c[0] for c in cmds]
    if nums != list(range(lo, hi + 1)):
        raise SystemExit("gen_registry: command ids must be contiguous so that ls_cmd_find is O(1)")
    (out_dir / "ls_cmd_table.h").write_text("\n".join(hdr))
    (out_dir / "ls_cmd_table.c").write_text("\n".join(src))
    return 0


if __name__ == "__main__":
    sys.exit(main())
