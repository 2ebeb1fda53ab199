"""Docs and comments name files of this repository only, and the paths the docs name exist
(docs/contributing.md "Style": a reference a reader cannot follow is a bug)."""
from __future__ import annotations

import itertools
import os
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
TOP = ("firmware/", "hal/", "protocol/", "host_tools/", "tests/", "docs/", "bench/", ".ci/")
# Names of files outside the repository (the project brief and notes beside it).
OUTSIDE = re.compile(r"DESIGN\.md|\.\./shared|house-style\.md|notes/environment\.md")
# The one exception: the directory of the vendor EDS/DCF files the drive tests read,
# third-party files that must stay outside. Its default is named once, where
# tests/CMakeLists.txt sets LS_VENDOR_EDS_DIR; everything else says "the vendor EDS
# directory (LS_VENDOR_EDS_DIR)" and takes its value from there.
VENDOR_EDS_DEFAULT = ("tests/CMakeLists.txt",
                      re.compile(r'^set\(LS_VENDOR_EDS_DIR "\$\{CMAKE_SOURCE_DIR\}/\.\./shared/eds"'))


def _tracked() -> list[str]:
    """The project's files, by walking the tree: a fresh root or an exported tree has no
    git (the fresh-root tier found a `git ls-files` here). Build trees, virtual
    environments and caches are not the project's."""
    out = ["README.md", "CMakeLists.txt"]
    for top in TOP:
        for dirpath, dirnames, filenames in os.walk(ROOT / top):
            dirnames[:] = [d for d in dirnames if not d.startswith((".", "build", "__pycache__"))
                           and not d.endswith(".egg-info")]
            out += [str(Path(dirpath, f).relative_to(ROOT)) for f in filenames]
    return [f for f in out if (ROOT / f).is_file()]


def _expand(ref: str) -> list[str]:
    """`a/b.{h,c}` -> `a/b.h`, `a/b.c`."""
    parts = re.split(r"\{([^}]*)\}", ref)
    choices = [[p] if i % 2 == 0 else p.split(",") for i, p in enumerate(parts)]
    return ["".join(c) for c in itertools.product(*choices)]


def test_nothing_names_a_file_outside_the_repository() -> None:
    hits = []
    for name in _tracked():
        path = ROOT / name
        if name.startswith("tests/host/test_repo_refs.py") or path.suffix not in (
                ".md", ".c", ".h", ".cpp", ".hpp", ".py", ".sh", ".txt", ".toml", ".proto") and \
                not name.startswith(".ci/") and path.name != "CMakeLists.txt":
            continue
        for n, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
            if OUTSIDE.search(line) and not (name == VENDOR_EDS_DEFAULT[0] and VENDOR_EDS_DEFAULT[1].match(line)):
                hits.append(f"{name}:{n}: {line.strip()}")
    assert not hits, "references to files outside the repository:\n" + "\n".join(hits)


def test_paths_in_the_docs_exist() -> None:
    missing = []
    docs = [n for n in _tracked() if n.endswith(".md")]
    for name in docs:
        text = (ROOT / name).read_text()
        for ref in re.findall(r"`([^`\s]+)`", text):
            ref = ref.rstrip(".,:;")
            if not ref.startswith(TOP) or "<" in ref or "*" in ref or "$" in ref:
                continue
            for one in _expand(ref.split(":")[0]):
                # a module may be named without its extension (`hal/sim/slcan_pty`)
                if not any((ROOT / (one + ext)).exists() for ext in ("", ".c", ".h", ".py")):
                    missing.append(f"{name}: `{ref}`")
    assert not missing, "paths named in the docs that the repository does not have:\n" + "\n".join(missing)
