#!/usr/bin/env python3
"""Derive the simulated drive's object dictionary from its EDS (CiA 306).

ls-simdrive.eds is the one home of the drive's objects: which exist, their
data types, access, PDO mapping, default values and value limits. This
generator turns it into a static C table (sd_od_table.c / sd_od_table.h)
that the drive's SDO server, PDOs and CiA 402 logic use, so the EDS a
master reads and the behaviour on the bus cannot disagree.

Only the standard library (configparser): it runs at build time on the
build machine's python3. Every rule it enforces fails the build with one
line naming the section and what to fix:

  - object sections are [XXXX] (VAR 0x7, ARRAY 0x8, RECORD 0x9), sub-objects
    [XXXXsubN]; SubNumber counts the sub-objects present;
  - every object is listed in [MandatoryObjects], [OptionalObjects] or
    [ManufacturerObjects] and every listed object has a section;
  - data types: UNSIGNED8/16/32, INTEGER8/16/32, VISIBLE_STRING (at most
    STRING_MAX bytes); access ro, wo, rw, rwr, rww, const;
  - DefaultValue, LowLimit, HighLimit parse as numbers within the type
    (signed types also as two's complement hex, as python-canopen reads
    them), low <= default <= high; "$NODEID+" only in UNSIGNED32 defaults.

Usage: gen_od.py EDS OUT_DIR
"""
from __future__ import annotations

import configparser
import re
import sys
from dataclasses import dataclass
from pathlib import Path

STRING_MAX = 32

# CiA 306 data type -> (C name of ls_canopen.h, bits, signed); strings: bits 0.
TYPES = {
    0x0002: ("LS_CO_TYPE_INTEGER8", 8, True),
    0x0003: ("LS_CO_TYPE_INTEGER16", 16, True),
    0x0004: ("LS_CO_TYPE_INTEGER32", 32, True),
    0x0005: ("LS_CO_TYPE_UNSIGNED8", 8, False),
    0x0006: ("LS_CO_TYPE_UNSIGNED16", 16, False),
    0x0007: ("LS_CO_TYPE_UNSIGNED32", 32, False),
    0x0009: ("LS_CO_TYPE_VISIBLE_STRING", 0, False),
}
ACCESS = {
    "ro": "SD_OD_ACCESS_RO",
    "wo": "SD_OD_ACCESS_WO",
    "rw": "SD_OD_ACCESS_RW",
    "rwr": "SD_OD_ACCESS_RWR",
    "rww": "SD_OD_ACCESS_RWW",
    "const": "SD_OD_ACCESS_CONST",
}
VAR, ARRAY, RECORD = 0x7, 0x8, 0x9


class EdsError(Exception):
    pass


@dataclass
class Entry:
    index: int
    sub: int
    name: str
    dtype: int
    access: str
    pdo: bool
    nodeid: bool
    default: int
    default_str: str
    low: int
    high: int


def parse_int(text: str, bits: int, signed: bool, where: str) -> int:
    try:
        v = int(text.strip(), 0)
    except ValueError:
        raise EdsError(f"{where}: '{text}' is not a number (decimal or 0x hex)") from None
    if signed and v >= 1 << (bits - 1) and text.strip().lower().startswith("0x"):
        v -= 1 << bits  # two's complement hex, as python-canopen reads it
    lo, hi = (-(1 << (bits - 1)), (1 << (bits - 1)) - 1) if signed else (0, (1 << bits) - 1)
    if not lo <= v <= hi:
        raise EdsError(f"{where}: {v} does not fit the data type ({lo}..{hi})")
    return v


def build_entry(eds: configparser.ConfigParser, section: str, index: int, sub: int) -> Entry:
    s = eds[section]
    for key in ("ParameterName", "DataType", "AccessType"):
        if key not in s:
            raise EdsError(f"[{section}]: {key} is missing")
    try:
        dtype = int(s["DataType"], 0)
    except ValueError:
        raise EdsError(f"[{section}]: DataType '{s['DataType']}' is not a number") from None
    if dtype not in TYPES:
        raise EdsError(f"[{section}]: DataType 0x{dtype:04X} is not one the simulated drive implements "
                       f"({', '.join(f'0x{t:04X}' for t in TYPES)})")
    _, bits, signed = TYPES[dtype]
    access = s["AccessType"].strip().lower()
    if access not in ACCESS:
        raise EdsError(f"[{section}]: AccessType '{access}' is not one of {', '.join(ACCESS)}")
    pdo = s.get("PDOMapping", "0").strip() not in ("0", "")
    if pdo and bits == 0:
        raise EdsError(f"[{section}]: a string cannot be PDO-mapped; set PDOMapping=0")
    if "DefaultValue" not in s:
        raise EdsError(f"[{section}]: DefaultValue is missing (the simulated drive starts from it)")
    raw = s["DefaultValue"]
    if bits == 0:
        if len(raw.encode()) > STRING_MAX:
            raise EdsError(f"[{section}]: the default string is longer than {STRING_MAX} bytes")
        if not raw:
            raise EdsError(f"[{section}]: an empty default string cannot be read back by SDO; give it text")
        return Entry(index, sub, s["ParameterName"], dtype, access, False, False, 0, raw, 0, 0)
    nodeid = "$NODEID" in raw.upper()
    if nodeid:
        if dtype != 0x0007:
            raise EdsError(f"[{section}]: $NODEID only in UNSIGNED32 defaults (COB-IDs, serial numbers)")
        raw = re.sub(r"\+?\$NODEID\+?", "", raw, flags=re.IGNORECASE)
    lo_t, hi_t = (-(1 << (bits - 1)), (1 << (bits - 1)) - 1) if signed else (0, (1 << bits) - 1)
    default = parse_int(raw, bits, signed, f"[{section}] DefaultValue")
    low = parse_int(s["LowLimit"], bits, signed, f"[{section}] LowLimit") if "LowLimit" in s else lo_t
    high = parse_int(s["HighLimit"], bits, signed, f"[{section}] HighLimit") if "HighLimit" in s else hi_t
    if low > high:
        raise EdsError(f"[{section}]: LowLimit {low} is above HighLimit {high}")
    if not nodeid and not low <= default <= high:
        raise EdsError(f"[{section}]: DefaultValue {default} is outside LowLimit..HighLimit ({low}..{high})")
    return Entry(index, sub, s["ParameterName"], dtype, access, pdo, nodeid, default, "", low, high)


def read_eds(path: Path) -> list[Entry]:
    eds = configparser.ConfigParser(interpolation=None, strict=True)
    eds.optionxform = str  # keys keep their case (CiA 306 spells them in CamelCase)
    try:
        with path.open(encoding="utf-8") as f:
            eds.read_file(f)
    except (OSError, configparser.Error) as e:
        raise EdsError(f"{path}: {e}") from None
    listed: set[int] = set()
    for group in ("MandatoryObjects", "OptionalObjects", "ManufacturerObjects"):
        if group not in eds:
            continue
        g = eds[group]
        n = int(g.get("SupportedObjects", "0"), 0)
        for k in range(1, n + 1):
            if str(k) not in g:
                raise EdsError(f"[{group}]: entry {k} of SupportedObjects={n} is missing")
            listed.add(int(g[str(k)], 0))
    entries: list[Entry] = []
    objects: set[int] = set()
    for section in eds.sections():
        if not re.fullmatch(r"[0-9A-Fa-f]{4}", section):
            continue
        index = int(section, 16)
        objects.add(index)
        s = eds[section]
        otype = int(s.get("ObjectType", "0x7"), 0)
        if otype == VAR:
            entries.append(build_entry(eds, section, index, 0))
            continue
        if otype not in (ARRAY, RECORD):
            raise EdsError(f"[{section}]: ObjectType 0x{otype:X} is not VAR (0x7), ARRAY (0x8) or RECORD (0x9)")
        subs = sorted(int(m.group(1), 16) for other in eds.sections()
                      if (m := re.fullmatch(rf"{section}sub([0-9A-Fa-f]+)", other, flags=re.IGNORECASE)))
        if "SubNumber" not in s or int(s["SubNumber"], 0) != len(subs):
            raise EdsError(f"[{section}]: SubNumber must count the {len(subs)} sub-objects present")
        if not subs or subs[0] != 0:
            raise EdsError(f"[{section}]: sub-index 0 (the highest sub-index supported) is missing")
        for sub in subs:
            e = build_entry(eds, f"{section}sub{sub:X}", index, sub)
            entries.append(e)
        if entries[-len(subs)].dtype != 0x0005:
            raise EdsError(f"[{section}sub0]: sub-index 0 must be UNSIGNED8")
    if listed != objects:
        missing = sorted(objects - listed)
        extra = sorted(listed - objects)
        raise EdsError("the object lists and the object sections disagree: "
                       f"not listed {[hex(i) for i in missing]}, listed without a section {[hex(i) for i in extra]}")
    entries.sort(key=lambda e: (e.index, e.sub))
    return entries


def c_str(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def emit(entries: list[Entry], eds_name: str, out: Path) -> None:
    n_str = sum(1 for e in entries if TYPES[e.dtype][1] == 0)
    h = [
        f"/* Generated by gen_od.py from {eds_name}: do not edit (edit the EDS).",
        " * Included by sd_od.h only, after sd_od_entry_t. */",
        "#ifndef SD_OD_TABLE_H",
        "#define SD_OD_TABLE_H",
        "",
        f"#define SD_OD_N_ENTRIES {len(entries)}",
        f"#define SD_OD_N_STRINGS {n_str}",
        "",
        "/* Sorted by index, then sub-index. */",
        "extern const sd_od_entry_t sd_od_table[SD_OD_N_ENTRIES];",
        "",
        "#endif",
        "",
    ]
    c = [
        f"/* Generated by gen_od.py from {eds_name}: do not edit (edit the EDS). */",
        '#include "sd_od.h"',
        "",
        "#include \"ls_canopen.h\"",
        "",
        "const sd_od_entry_t sd_od_table[SD_OD_N_ENTRIES] = {",
    ]
    slot = 0
    for e in entries:
        tname, bits, _ = TYPES[e.dtype]
        flags = " | ".join(f for f, on in (("SD_OD_F_PDO", e.pdo), ("SD_OD_F_NODEID", e.nodeid)) if on) or "0u"
        if bits == 0:
            str_slot, def_str = slot, c_str(e.default_str)
            slot += 1
        else:
            str_slot, def_str = 0, "NULL"
        c.append(
            f"    {{ 0x{e.index:04X}u, {e.sub}u, {ACCESS[e.access]}, {tname}, {flags}, {str_slot}u, "
            f"{e.default}LL, {e.low}LL, {e.high}LL, {def_str}, {c_str(e.name)} }},")
    c += ["};", ""]
    (out / "sd_od_table.h").write_text("\n".join(h), encoding="utf-8")
    (out / "sd_od_table.c").write_text("\n".join(c), encoding="utf-8")


def main(argv: list[str]) -> int:
    if len(argv) != 3:
        print("usage: gen_od.py EDS OUT_DIR", file=sys.stderr)
        return 2
    eds, out = Path(argv[1]), Path(argv[2])
    try:
        entries = read_eds(eds)
    except EdsError as e:
        print(f"gen_od: {e}", file=sys.stderr)
        return 1
    out.mkdir(parents=True, exist_ok=True)
    emit(entries, eds.name, out)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
