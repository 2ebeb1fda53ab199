"""docs/conformance.md stays true to the schema and to what is implemented."""
from __future__ import annotations

import re
from pathlib import Path

from landscape._generated import landscape_pb2 as pb
from landscape.registry import COMMANDS

ROOT = Path(__file__).resolve().parents[2]


def _rows() -> dict[str, list[str]]:
    rows = {}
    for line in (ROOT / "docs" / "conformance.md").read_text().splitlines():
        m = re.match(r"\| `(\w+)` \|(.*)\|$", line)
        if m:
            rows[m.group(1)] = [c.strip() for c in m.group(2).split("|")]
    return rows


def test_conformance_table_matches_the_schema_and_the_firmware() -> None:
    rows = _rows()
    missing = set(re.findall(r'LS_NOT_IMPLEMENTED\(\w+, "(\w+)"\)',
                             (ROOT / "firmware" / "core" / "cmd_missing.c").read_text()))
    names = {c.name for c in COMMANDS.values()}
    assert set(rows) == names
    for cmd in COMMANDS.values():
        section, states, blocking, owner, status, *_ = rows[cmd.name]
        assert states == "/".join(pb.State.Name(s) for s in cmd.states), cmd.name
        assert blocking.startswith("yes" if cmd.blocking else "no"), cmd.name
        assert owner == ("yes" if cmd.owner_only else "no"), cmd.name
        assert ("not implemented" in status) == (cmd.name in missing), cmd.name
