"""The schema hash recipe in docs/protocol.md ("Schema hash") is exact. The test runs the
published command (read from the page, not copied here) with protoc and the shell alone,
and compares the result with the hash the firmware was built with and the host's."""
from __future__ import annotations

import re
import subprocess
from pathlib import Path

from conftest import BUILD

ROOT = Path(__file__).resolve().parents[2]


def _recipe() -> str:
    text = (ROOT / "docs" / "protocol.md").read_text()
    m = re.search(r"<!-- schema-hash-recipe -->\n```sh\n(.+?)\n```", text)
    assert m is not None, "docs/protocol.md lost its schema-hash recipe block (<!-- schema-hash-recipe -->)"
    return m.group(1)


def _firmware_hash() -> int:
    header = BUILD / "protocol" / "gen" / "ls_cmd_table.h"
    m = re.search(r"#define LS_SCHEMA_HASH 0x([0-9A-F]{8})u", header.read_text())
    assert m is not None, f"{header} has no LS_SCHEMA_HASH"
    return int(m.group(1), 16)


def test_published_recipe_gives_the_firmware_and_host_hash() -> None:
    out = subprocess.run(["bash", "-o", "pipefail", "-c", _recipe()], cwd=ROOT, capture_output=True,
                         text=True, timeout=60)
    assert out.returncode == 0, f"the recipe failed: {out.stderr}"
    digits = out.stdout.strip()
    assert re.fullmatch(r"[0-9a-f]{8}", digits), f"the recipe printed {out.stdout!r}, not 8 hex digits"
    assert int(digits, 16) == _firmware_hash()

    from landscape.registry import SCHEMA_HASH
    assert int(digits, 16) == SCHEMA_HASH


def test_a_comment_does_not_change_the_hash_and_a_field_does(tmp_path: Path) -> None:
    """What the page says counts and what does not: a comment is not in the descriptor set,
    a renamed field is."""
    src = (ROOT / "protocol" / "landscape.proto").read_text()
    variants = {"same": src, "comment": "// a comment\n" + src,
                "field": src.replace("client_name", "client_nam", 1)}
    digests = {}
    for name, text in variants.items():
        d = tmp_path / name / "protocol"
        d.mkdir(parents=True)
        (d / "landscape.proto").write_text(text)
        out = subprocess.run(["bash", "-o", "pipefail", "-c", _recipe()], cwd=d.parent, capture_output=True,
                             text=True, timeout=60, check=True)
        digests[name] = out.stdout.strip()
    assert digests["same"] == digests["comment"]
    assert digests["same"] != digests["field"]
