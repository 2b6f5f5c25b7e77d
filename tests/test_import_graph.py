"""The project's module graph has no import circles (type-only and function-level imports too).

The graph is read from the source with `ast`: every ``import``/``from ... import`` anywhere in
a module (``if TYPE_CHECKING:`` blocks and imports inside functions included) is an edge. A name
imported from a package (``from envs.cell import X``) is followed to the module the package's
``__init__`` takes it from, so a package that only re-exports is not itself a node of a circle.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("spatial", "qshape", "planners", "envs", "agents", "apps", "benchmarks", "configs")

KNOWN_CIRCLES: frozenset[frozenset[str]] = frozenset()
"""Circles allowed for now, each as its set of modules; the test fails on any other (none left)."""


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _sources() -> dict[str, Path]:
    return {_module_name(p): p for pkg in PACKAGES for p in sorted((ROOT / pkg).rglob("*.py"))}


def _is_package(name: str, modules: dict[str, Path]) -> bool:
    return name in modules and modules[name].name == "__init__.py"


def _absolute(module: str, node: ast.ImportFrom, modules: dict[str, Path]) -> str:
    """The absolute module name of a ``from`` import (relative ones resolved)."""
    if node.level == 0:
        return node.module or ""
    base = module if _is_package(module, modules) else module.rpartition(".")[0]
    for _ in range(node.level - 1):
        base = base.rpartition(".")[0]
    return f"{base}.{node.module}" if node.module else base


def _raw_imports(module: str, modules: dict[str, Path]) -> list[tuple[str, str | None]]:
    """(module, name or None) pairs of every import in ``module``'s source."""
    tree = ast.parse(modules[module].read_text(encoding="utf-8"))
    out: list[tuple[str, str | None]] = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            target = _absolute(module, node, modules)
            out.extend((target, a.name) for a in node.names)
        elif isinstance(node, ast.Import):
            out.extend((a.name, None) for a in node.names)
    return out


def _resolve(target: str, name: str | None, modules: dict[str, Path], seen: set[str]) -> str:
    """The module that really defines ``target.name`` (through package re-exports)."""
    if name is None or name == "*":
        return target
    if f"{target}.{name}" in modules:
        return f"{target}.{name}"
    if not _is_package(target, modules) or target in seen:
        return target
    for src, imported in _raw_imports(target, modules):
        if imported == name and src in modules:
            return _resolve(src, name, modules, {*seen, target})
    return target


def import_graph() -> dict[str, set[str]]:
    """Every project module -> the project modules it imports."""
    modules = _sources()
    graph: dict[str, set[str]] = {}
    for module in modules:
        deps = {_resolve(t, n, modules, set()) for t, n in _raw_imports(module, modules)}
        graph[module] = {d for d in deps if d in modules and d != module}
    return graph


def circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan), sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                found.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(found)


def test_the_graph_sees_type_only_and_relative_imports() -> None:
    graph = {
        "a": {"b"},
        "b": {"c"},
        "c": {"a"},
        "d": {"a"},
    }
    assert circles(graph) == [["a", "b", "c"]]
    real = import_graph()
    assert "envs.cell.config" in real["envs.cell.cell"]
    assert "spatial.angles" in real["envs.task"]


def test_no_import_circles() -> None:
    found = [c for c in circles(import_graph()) if frozenset(c) not in KNOWN_CIRCLES]
    assert not found, "import circles: " + "; ".join(" <-> ".join(c) for c in found)
