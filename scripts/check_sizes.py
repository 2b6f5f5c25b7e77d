"""List source files over a line limit and functions over a line limit.

``python scripts/check_sizes.py [--file-lines 500] [--function-lines 80] [PACKAGE ...]`` prints
every ``.py`` file of the packages (default: every top-level package of the repository) longer
than ``--file-lines`` lines and every function or method longer than ``--function-lines`` lines
(its decorators excluded, its docstring included). The limits are a prompt for review, not a
reason to split or move code: a file that holds one concept may be long. It exits with status 0
(a warning) unless ``--strict`` is given, then 1 when anything is over.
"""

from __future__ import annotations

import argparse
import ast
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("qshape", "planners", "envs", "agents", "apps", "benchmarks", "configs")


def oversized(
    packages: list[str], file_lines: int, function_lines: int
) -> list[tuple[str, int, str]]:
    """(kind, lines, where) of each file and function over its limit, largest first."""
    found: list[tuple[str, int, str]] = []
    for package in packages:
        for path in sorted((ROOT / package).rglob("*.py")):
            text = path.read_text(encoding="utf-8")
            where = str(path.relative_to(ROOT))
            lines = text.count("\n")
            if lines > file_lines:
                found.append(("file", lines, where))
            for node in ast.walk(ast.parse(text)):
                if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                    length = (node.end_lineno or node.lineno) - node.lineno + 1
                    if length > function_lines:
                        found.append(("function", length, f"{where}:{node.lineno} {node.name}"))
    return sorted(found, key=lambda row: (row[0], -row[1]))


def main(argv: list[str] | None = None) -> int:
    """Print what is over the limits (review prompts); with ``--strict`` 1 when anything is."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("packages", nargs="*", default=list(PACKAGES))
    ap.add_argument("--file-lines", type=int, default=500)
    ap.add_argument("--function-lines", type=int, default=80)
    ap.add_argument("--strict", action="store_true", help="exit 1 when anything is over")
    args = ap.parse_args(argv)
    found = oversized(args.packages, args.file_lines, args.function_lines)
    for kind, lines, where in found:
        print(f"{kind:8s} {lines:5d}  {where}")
    print(
        f"{len(found)} over the limits ({args.file_lines} lines a file, "
        f"{args.function_lines} a function)"
    )
    return 1 if found and args.strict else 0


if __name__ == "__main__":
    sys.exit(main())
