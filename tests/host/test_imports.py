"""The host package's modules import one another without a cycle.

Every import counts, at module level or inside a function: an import moved
into a function body to dodge a cycle at load time still ties the two modules
together.
"""
from __future__ import annotations

import ast
from pathlib import Path

import landscape

PACKAGE = Path(landscape.__file__).parent


def imports_of(source: str, modules: set[str]) -> set[str]:
    """The package's own modules that `source` imports."""
    out: set[str] = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.ImportFrom):
            if node.level == 1:
                names = [node.module.split(".")[0]] if node.module else [a.name for a in node.names]
            elif node.level == 0 and node.module is not None and node.module.startswith("landscape."):
                names = [node.module.split(".")[1]]
            else:
                names = []
            out.update(n for n in names if n in modules)
        elif isinstance(node, ast.Import):
            out.update(a.name.split(".")[1] for a in node.names
                       if a.name.startswith("landscape.") and a.name.split(".")[1] in modules)
    return out


def import_graph() -> dict[str, set[str]]:
    files = {p.stem: p for p in PACKAGE.glob("*.py")}
    modules = set(files) - {"__init__", "__main__"}
    return {m: imports_of(files[m].read_text(encoding="utf-8"), modules) - {m} for m in sorted(modules)}


def find_cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    cycles: list[list[str]] = []
    state: dict[str, int] = {}  # 1 on the stack, 2 done

    def visit(node: str, stack: list[str]) -> None:
        state[node] = 1
        stack.append(node)
        for dep in sorted(graph[node]):
            if state.get(dep) == 1:
                cycles.append(stack[stack.index(dep):] + [dep])
            elif dep not in state:
                visit(dep, stack)
        stack.pop()
        state[node] = 2

    for node in graph:
        if node not in state:
            visit(node, [])
    return cycles


def test_the_finder_sees_a_cycle() -> None:
    assert find_cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == [["a", "b", "c", "a"]]
    assert imports_of("def f():\n    from .b import x\n", {"b"}) == {"b"}


def test_the_package_has_no_import_cycle() -> None:
    graph = import_graph()
    assert {"cli", "cli_core", "cli_tools", "recording", "mcap_log"} <= set(graph)
    cycles = find_cycles(graph)
    assert cycles == [], "import cycles: " + "; ".join(" -> ".join(c) for c in cycles)
