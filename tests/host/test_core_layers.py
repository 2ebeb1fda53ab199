"""firmware/core's files call one way: types -> services -> handlers -> sessions, dispatch
and tick (docs/architecture.md "Core layers").

A module is a file's stem (`ls_run` is ls_run.h with ls_run.c), except the core's interface
to the rest of the firmware, ls_core.h, a module of its own (it declares what the whole top
layer defines). Module A depends on B when one of A's files includes B's header or A's .c
file calls a function B's .c file defines. Every module
has a layer (LAYERS below, the one home of that table); a module may depend on its own layer
and the ones below it, never on one above, and the dependencies have no cycle, within a
layer neither. A file that no layer names fails the test until it is placed.

See the picture with the project's own tools:

    python3 tests/host/test_core_layers.py          # the layers and every dependency
    python3 tests/host/test_core_layers.py --dot    # the same as a Graphviz graph
"""
from __future__ import annotations

import fnmatch
import re
import sys
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
CORE = ROOT / "firmware" / "core"

#: Bottom to top. Patterns match module names (file stems).
LAYERS: list[tuple[str, tuple[str, ...]]] = [
    ("types", ("ls_core_limits", "ls_core_state", "ls_core_types", "ls_units", "ls_utf8", "ls_wire")),
    ("services", ("ls_send", "ls_log", "ls_rsvp", "ls_run", "ls_fault", "ls_core_services")),
    ("handlers", ("cmd_*", "ls_core_events")),
    ("sessions, dispatch and tick", ("ls_session", "ls_dispatch", "ls_core", "ls_core_loop")),
]

#: Headers that are modules of their own rather than half of their stem's.
INTERFACES = ("ls_core.h",)

Edges = dict[str, dict[str, set[str]]]


def _code_only(text: str) -> str:
    """The text with comments and string literals blanked (line breaks kept)."""
    text = re.sub(r"/\*.*?\*/", lambda m: re.sub(r"[^\n]", " ", m.group()), text, flags=re.S)
    text = re.sub(r"//[^\n]*", "", text)
    return re.sub(r'"(?:\\.|[^"\\\n])*"', '""', text)


def layer_of(module: str) -> int | None:
    for i, (_name, patterns) in enumerate(LAYERS):
        if any(fnmatch.fnmatchcase(module.removesuffix(".h"), p) for p in patterns):
            return i
    return None


def modules() -> dict[str, list[Path]]:
    out: dict[str, list[Path]] = defaultdict(list)
    for path in sorted(CORE.iterdir()):
        if path.suffix in (".c", ".h"):
            out[path.name if path.name in INTERFACES else path.stem].append(path)
    return dict(out)


def dependencies() -> Edges:
    """module -> module it depends on -> why (the functions called, the headers included)."""
    mods = modules()
    defined: dict[str, str] = {}
    text: dict[Path, str] = {}
    for mod, paths in mods.items():
        for path in paths:
            raw = path.read_text()
            text[path] = _code_only(raw)
            if path.suffix == ".c":
                # a function definition starts at column 0 and is not static
                for m in re.finditer(r"^(?!static\b)[A-Za-z_][\w \t*]*?\b(\w+)\s*\([^;{]*\)\s*\{",
                                     text[path], flags=re.M):
                    defined[m.group(1)] = mod
    edges: Edges = defaultdict(lambda: defaultdict(set))
    for mod, paths in mods.items():
        for path in paths:
            for name in re.findall(r'^\s*#\s*include\s+"([\w.]+\.h)"', path.read_text(), flags=re.M):
                target = name if name in INTERFACES else name.removesuffix(".h")
                if target in mods and target != mod:
                    edges[mod][target].add(f"#include {name}")
            if path.suffix != ".c":
                continue  # a header declares; only code calls
            for fn in re.findall(r"\b(\w+)\s*\(", text[path]):
                if defined.get(fn, mod) != mod:
                    edges[mod][defined[fn]].add(f"{fn}()")
    return {a: dict(b) for a, b in edges.items()}


def find_cycle(edges: Edges) -> list[str] | None:
    """One cycle of the dependency graph, as the modules along it, or None."""
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(m: str) -> list[str] | None:
        state[m] = 1
        stack.append(m)
        for n in sorted(edges.get(m, {})):
            if state.get(n) == 1:
                return stack[stack.index(n):] + [n]
            if n not in state:
                found = visit(n)
                if found:
                    return found
        stack.pop()
        state[m] = 2
        return None

    for m in sorted(edges):
        if m not in state:
            found = visit(m)
            if found:
                return found
    return None


def test_every_core_file_has_a_layer() -> None:
    unplaced = [m for m in modules() if layer_of(m) is None]
    assert not unplaced, (f"firmware/core files without a layer: {', '.join(unplaced)}: add each to LAYERS in "
                          "tests/host/test_core_layers.py (docs/architecture.md \"Core layers\" says which)")


def test_no_core_file_depends_on_a_layer_above_it() -> None:
    upward = []
    for a, targets in dependencies().items():
        for b, why in targets.items():
            la, lb = layer_of(a), layer_of(b)
            if la is not None and lb is not None and lb > la:
                upward.append(f"{a} ({LAYERS[la][0]}) -> {b} ({LAYERS[lb][0]}): {', '.join(sorted(why))}")
    assert not upward, ("firmware/core calls go types -> services -> handlers -> sessions/dispatch/tick; these go "
                        "up (move the code down, or hand the work up through the layer above):\n" + "\n".join(upward))


def test_the_core_files_depend_on_each_other_without_a_cycle() -> None:
    cycle = find_cycle(dependencies())
    assert cycle is None, "firmware/core files that depend on each other in a circle: " + " -> ".join(cycle or [])


def _print(dot: bool) -> None:
    deps = dependencies()
    if dot:
        print("digraph core {\n  rankdir=BT;")
        for i, (name, _p) in enumerate(LAYERS):
            mods = sorted(m for m in modules() if layer_of(m) == i)
            print(f'  subgraph cluster_{i} {{ label="{name}"; ' + " ".join(f'"{m}";' for m in mods) + " }")
        for a in sorted(deps):
            for b in sorted(deps[a]):
                print(f'  "{a}" -> "{b}";')
        print("}")
        return
    for i, (name, _p) in reversed(list(enumerate(LAYERS))):
        print(f"{name}:")
        for m in sorted(m for m in modules() if layer_of(m) == i):
            print(f"  {m}")
            for b in sorted(deps.get(m, {}), key=lambda x: (-(layer_of(x) or 0), x)):
                print(f"    -> {b}: {', '.join(sorted(deps[m][b]))}")


if __name__ == "__main__":
    _print("--dot" in sys.argv[1:])
