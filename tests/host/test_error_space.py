"""The C code has one error space (common/ls_err.h): every negative status is a named
LS_E* code, and every code has its name and its text in common/ls_err.c.

A bare negative literal returned or kept as a status (`return -1;`, `cond ? 0 : -2`,
`rc = -1`) is what made ls_err_name() print LS_EUNSUPPORTED for "already running".
An index that names nothing is a named constant of its module (LS_NO_SESSION,
LS_PATH_NONE, NO_FD for a descriptor), so this check needs no exceptions.
Run it alone: `python3 tests/host/test_error_space.py` lists every offending line.
"""
from __future__ import annotations

import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
# The C code ls_err.h governs: firmware, HAL, the shared headers and the benchmark tools.
TOPS = ("firmware", "hal", "common", "bench")
SUFFIXES = (".c", ".h", ".cpp", ".hpp")
# `return -1`, `return -(j + 2)`, `x ? 0 : -1`, `rc = -1`: an integer literal, not a float.
BARE = re.compile(r"\breturn\s*\(?\s*-\s*(?:\(|[0-9]+\b(?![.\deEfxX]))"
                  r"|[?:]\s*-\s*[0-9]+\b(?![.\deEfxX])"
                  r"|\b(?:rc|ret|r|st|status|err|res)\s*=\s*-\s*[0-9]+\b(?![.\deEfxX])")


def _code_only(text: str) -> str:
    """The text with comments and string literals blanked, line breaks kept."""
    text = re.sub(r"/\*.*?\*/", lambda m: re.sub(r"[^\n]", " ", m.group()), text, flags=re.S)
    text = re.sub(r"//[^\n]*", "", text)
    return re.sub(r'"(?:\\.|[^"\\\n])*"', '""', text)


def bare_negative_statuses() -> list[str]:
    hits = []
    for top in TOPS:
        for path in sorted((ROOT / top).rglob("*")):
            if path.suffix not in SUFFIXES or not path.is_file():
                continue
            text = path.read_text()
            code = _code_only(text)
            lines = text.splitlines()
            for m in BARE.finditer(code):
                n = code.count("\n", 0, m.start()) + 1
                hits.append(f"{path.relative_to(ROOT)}:{n}: {lines[n - 1].strip()}")
    return hits


def test_no_bare_negative_status_in_the_c_code() -> None:
    hits = bare_negative_statuses()
    assert not hits, ("negative statuses that are not common/ls_err.h codes (return an LS_E* name, or a "
                      "named constant of the module for an index that names nothing):\n" + "\n".join(hits))


def _codes() -> dict[str, int]:
    header = (ROOT / "common" / "ls_err.h").read_text()
    return {name: int(value) for name, value in re.findall(r"#define\s+(LS_E\w+)\s+\((-\d+)\)", header)}


def test_every_error_code_is_distinct_and_named() -> None:
    codes = _codes()
    assert codes, "common/ls_err.h defines no LS_E* codes"
    values = sorted(codes.values(), reverse=True)
    assert values == list(range(-1, -len(values) - 1, -1)), \
        f"common/ls_err.h: the codes must be -1, -2, ... without gaps or repeats: {sorted(codes.items())}"
    source = (ROOT / "common" / "ls_err.c").read_text()
    for func in ("ls_err_name", "ls_err_text"):
        body = source[source.index(f"const char *{func}("):]
        body = body[:body.index("\n}\n")]
        missing = [name for name in codes if f"case {name}:" not in body]
        assert not missing, f"common/ls_err.c {func}() has no case for {', '.join(missing)}"


if __name__ == "__main__":
    found = bare_negative_statuses()
    print("\n".join(found) if found else "no bare negative statuses")
    sys.exit(1 if found else 0)
