"""Count the tests' references to private names of the project's modules.

A reference is a private name (one leading underscore, not a dunder) either imported from a
project module (``from qshape.vision.extract import _canny``) or read as an attribute of a name
bound to a project module (``import qshape.vision.extract as ex; ex._canny``, also through
``importlib.import_module``).
Private attributes of objects (``cell._wake``) are listed apart: they are not module names.

Usage: ``python scripts/private_test_refs.py [--list]`` from the repository root; prints the
count (and each reference with ``--list``).
"""

from __future__ import annotations

import ast
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("agents", "apps", "benchmarks", "envs", "planners", "qshape")


def _is_private(name: str) -> bool:
    return name.startswith("_") and not name.startswith("__")


def _is_project(module: str) -> bool:
    return module.split(".", maxsplit=1)[0] in PACKAGES


def _is_module(dotted: str) -> bool:
    path = ROOT.joinpath(*dotted.split("."))
    return path.with_suffix(".py").is_file() or (path / "__init__.py").is_file()


def _dotted(node: ast.expr) -> str | None:
    if isinstance(node, ast.Name):
        return node.id
    if isinstance(node, ast.Attribute):
        base = _dotted(node.value)
        return None if base is None else f"{base}.{node.attr}"
    return None


def _imported(node: ast.expr) -> str | None:
    """The project module named by ``importlib.import_module("...")``, else None."""
    if (
        isinstance(node, ast.Call)
        and _dotted(node.func) in ("importlib.import_module", "import_module")
        and node.args
        and isinstance(node.args[0], ast.Constant)
        and isinstance(node.args[0].value, str)
        and _is_project(node.args[0].value)
    ):
        return node.args[0].value
    return None


def references(path: Path) -> tuple[list[str], list[str]]:
    """Module-private and object-private references in one test file, as ``line: text``."""
    tree = ast.parse(path.read_text(), str(path))
    modules: dict[str, str] = {}  # local name -> dotted project module
    found: list[str] = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if _is_project(alias.name):
                    local = alias.asname or alias.name.split(".")[0]
                    modules[local] = alias.name if alias.asname else local
        elif isinstance(node, ast.ImportFrom) and node.module and _is_project(node.module):
            for alias in node.names:
                dotted = f"{node.module}.{alias.name}"
                if _is_private(alias.name):
                    found.append(f"{node.lineno}: from {node.module} import {alias.name}")
                elif _is_module(dotted):
                    modules[alias.asname or alias.name] = dotted
        elif isinstance(node, ast.Assign) and _imported(node.value) is not None:
            for target in node.targets:
                if isinstance(target, ast.Name):
                    modules[target.id] = str(_imported(node.value))
    objects: list[str] = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and _is_private(node.attr):
            base = _dotted(node.value)
            head = None if base is None else base.split(".")[0]
            if head in modules and _is_module(modules[head] + base[len(head) :]):
                found.append(f"{node.lineno}: {base}.{node.attr}")
            elif head != "self":
                objects.append(f"{node.lineno}: {ast.unparse(node)}")
    return found, objects


def main() -> int:
    """Print the count of module-private references in ``tests/`` (each with ``--list``)."""
    show = "--list" in sys.argv[1:]
    total = other = 0
    for path in sorted((ROOT / "tests").rglob("*.py")):
        found, objects = references(path)
        total += len(found)
        other += len(objects)
        if show:
            rel = path.relative_to(ROOT)
            for ref in found:
                print(f"{rel}:{ref}")
            for ref in objects:
                print(f"{rel}:{ref}  (object attribute)")
    print(f"module-private references: {total}; private object attributes: {other}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
