"""ls_eds against an independent reader: every object of the two vendor files
of LS_VENDOR_EDS_DIR, as the ls_eds_dump tool prints it, compared with
python-canopen's ``canopen.import_od(path, node_id)`` for several node ids.

Compared per object and sub-object: that both readers list it, its name, its
object kind (VAR, ARRAY, RECORD), and for every variable its data type,
access type, readable/writable, PDO mapping, DefaultValue, ParameterValue,
the power-on value (ParameterValue, else DefaultValue), LowLimit, HighLimit
and whether DefaultValue follows the node id; then the [DeviceInfo] identity.

python-canopen keeps a signed DefaultValue written in hex as the unsigned
number (0xFD in an INTEGER8 is 253 there, -3 here): signed integers are
compared modulo 2^bits.

Run through ctest (which sets LS_EDS_DUMP and LS_VENDOR_EDS_DIR), or by hand with DIR
the vendor EDS directory (LS_VENDOR_EDS_DIR in the build's CMakeCache.txt):
    LS_EDS_DUMP=build/bin/ls_eds_dump LS_VENDOR_EDS_DIR=DIR \\
        .venv/bin/python -m pytest tests/unit/eds/test_eds_vs_canopen.py
"""

from __future__ import annotations

import os
import shlex
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

import canopen
import pytest
from canopen.objectdictionary import ODArray, ODRecord, ODVariable, datatypes

FILES = {
    "epos4_50_15_can_ec90flat_gp52c_mile800_node1.dcf": 652,
    "ros2_canopen_cia402_slave.eds": 180,
}
NODES = [1, 0x23, 127]

Value = int | float | str | None


def _env_path(name: str, what: str) -> Path:
    value = os.environ.get(name)
    if not value:
        pytest.fail(f"{name} is not set: it names {what} (ctest sets it; see this file's docstring)")
    path = Path(value)
    if not path.exists():
        pytest.fail(f"{name}={value} does not exist: it names {what}")
    return path


@pytest.fixture(scope="module")
def dump_tool() -> Path:
    return _env_path("LS_EDS_DUMP", "the ls_eds_dump executable of the build")


@pytest.fixture(scope="module")
def eds_dir() -> Path:
    eds = _env_path("LS_VENDOR_EDS_DIR", "the directory that holds the vendor EDS/DCF files")
    for name in FILES:
        if not (eds / name).is_file():
            pytest.fail(f"{eds / name} is missing: configure with -DLS_VENDOR_EDS_DIR=DIR where DIR has the vendor "
                        "files")
    return eds


@dataclass
class Entry:
    """One line of ls_eds_dump."""

    index: int
    sub: int | None  # None: the object's own section
    kind: str
    data_type: str
    access: str
    fields: dict[str, Value] = field(default_factory=dict)
    nodeid: set[str] = field(default_factory=set)
    name: str = ""
    mappable: bool = False


def _parse_value(text: str) -> Value:
    if text == "-":
        return None
    if text.startswith("0x"):
        return int(text, 16)
    try:
        return int(text)
    except ValueError:
        pass
    try:
        return float(text)
    except ValueError:
        return text  # a text value (shlex took its quotes off)


def _dump(tool: Path, path: Path, node: int) -> tuple[dict[str, str], dict[tuple[int, int | None], Entry]]:
    run = subprocess.run([str(tool), str(path), str(node)], capture_output=True, text=True, timeout=60, check=False)
    assert run.returncode == 0, f"ls_eds_dump refused {path}: {run.stderr.strip()}"
    device: dict[str, str] = {}
    entries: dict[tuple[int, int | None], Entry] = {}
    for line in run.stdout.splitlines():
        tokens = shlex.split(line)
        if tokens[:2] == ["#", "device"]:
            device = dict(t.split("=", 1) for t in tokens[2:])
            continue
        where, kind, data_type, access, *rest = tokens
        index_text, _, sub_text = where.partition(":")
        e = Entry(int(index_text, 16), int(sub_text, 16) if sub_text else None, kind, data_type, access)
        for token in rest:
            key, _, value = token.partition("=")
            if key == "name":
                e.name = value
            elif key == "map":
                e.mappable = value == "1"
            elif key == "nodeid":
                e.nodeid = set(value.split(","))
            elif key in ("value", "default", "param", "low", "high"):
                e.fields[key] = _parse_value(value)
        entries[(e.index, e.sub)] = e
    return device, entries


def _theirs(od: canopen.ObjectDictionary) -> dict[tuple[int, int | None], ODVariable | ODArray | ODRecord]:
    out: dict[tuple[int, int | None], ODVariable | ODArray | ODRecord] = {}
    for index in od:
        obj = od[index]
        out[(index, None)] = obj
        if isinstance(obj, ODRecord | ODArray):
            for sub, var in obj.subindices.items():
                out[(index, sub)] = var
    return out


def _type_code(name: str) -> int:
    code = getattr(datatypes, name, None)
    assert isinstance(code, int), f"{name} is not a python-canopen data type"
    return code


def _bits(data_type: int) -> int:
    return {
        datatypes.INTEGER8: 8,
        datatypes.INTEGER16: 16,
        datatypes.INTEGER24: 24,
        datatypes.INTEGER32: 32,
        datatypes.INTEGER40: 40,
        datatypes.INTEGER48: 48,
        datatypes.INTEGER56: 56,
        datatypes.INTEGER64: 64,
    }[data_type]


def _same(ours: Value, theirs: object, data_type: int) -> bool:
    if theirs is None or ours is None:
        if ours is None and theirs is None:
            return True
        # python-canopen drops what int() cannot read; ls_eds reads no such value in these files
        return False
    if isinstance(theirs, bytes):
        return isinstance(ours, str) and bytes.fromhex(ours) == theirs
    if isinstance(theirs, bool):
        return ours == int(theirs)
    if isinstance(theirs, int) and isinstance(ours, int):
        if data_type in datatypes.SIGNED_TYPES:
            return (ours - theirs) % (1 << _bits(data_type)) == 0
        return ours == theirs
    return ours == theirs


def _kind_of(obj: ODVariable | ODArray | ODRecord) -> str:
    if isinstance(obj, ODRecord):
        return "RECORD"
    if isinstance(obj, ODArray):
        return "ARRAY"
    return "VAR"


@pytest.mark.parametrize("node", NODES)
@pytest.mark.parametrize("file_name", sorted(FILES))
def test_every_object_reads_as_python_canopen_reads_it(
    dump_tool: Path, eds_dir: Path, file_name: str, node: int
) -> None:
    path = eds_dir / file_name
    _, ours = _dump(dump_tool, path, node)
    theirs = _theirs(canopen.import_od(str(path), node))
    assert len(ours) == FILES[file_name]
    assert sorted(ours, key=str) == sorted(theirs, key=str)
    problems: list[str] = []
    for key, obj in theirs.items():
        e = ours[key]
        where = f"{file_name} node {node} 0x{key[0]:04X}" + (f":{key[1]:02X}" if key[1] is not None else "")

        def check(what: str, ok: bool, mine: object, python: object, where: str = where) -> None:
            if not ok:
                problems.append(f"{where} {what}: ls_eds {mine!r}, python-canopen {python!r}")

        check("name", e.name == obj.name, e.name, obj.name)
        check("object", e.kind == _kind_of(obj), e.kind, _kind_of(obj))
        if not isinstance(obj, ODVariable):
            continue
        dt = obj.data_type
        assert dt is not None
        check("data type", _type_code(e.data_type) == dt, e.data_type, dt)
        check("access", e.access == obj.access_type, e.access, obj.access_type)
        readable = e.access in ("ro", "rw", "rwr", "rww", "const")
        writable = e.access in ("wo", "rw", "rwr", "rww")
        check("readable", readable == obj.readable, readable, obj.readable)
        check("writable", writable == obj.writable, writable, obj.writable)
        check("PDO mapping", e.mappable == obj.pdo_mappable, e.mappable, obj.pdo_mappable)
        check("DefaultValue", _same(e.fields["default"], obj.default, dt), e.fields["default"], obj.default)
        check("ParameterValue", _same(e.fields["param"], obj.value, dt), e.fields["param"], obj.value)
        power_on = obj.value if obj.value is not None else obj.default
        check("power-on value", _same(e.fields["value"], power_on, dt), e.fields["value"], power_on)
        check("LowLimit", _same(e.fields["low"], obj.min, dt), e.fields["low"], obj.min)
        check("HighLimit", _same(e.fields["high"], obj.max, dt), e.fields["high"], obj.max)
        check("$NODEID", ("default" in e.nodeid) == obj.relative, sorted(e.nodeid), obj.relative)
    assert not problems, f"{len(problems)} differences:\n" + "\n".join(problems[:40])


@pytest.mark.parametrize("file_name", sorted(FILES))
def test_the_identity_reads_as_python_canopen_reads_it(dump_tool: Path, eds_dir: Path, file_name: str) -> None:
    path = eds_dir / file_name
    device, _ = _dump(dump_tool, path, 1)
    info = canopen.import_od(str(path), 1).device_information
    assert device["vendor_name"] == info.vendor_name
    assert device["product_name"] == info.product_name
    for key, theirs in (
        ("vendor_number", info.vendor_number),
        ("product_number", info.product_number),
        ("revision_number", info.revision_number),
    ):
        mine = device.get(key)
        assert (int(mine, 16) if mine is not None else None) == theirs, key
