"""Test-run settings shared by every folder.

Under mutation testing (mutmut sets ``MUTANT_UNDER_TEST`` to the mutant's name in the process
that runs its tests) the tests of a mutant run file by file in the order of pyproject's
``[tool.mutmut] pytest_add_cli_args_test_selection``, which lists the fast contract tests
first: mutmut stops at the first failure, so a killed mutant costs the cheapest test that
catches it. Ordinary runs keep pytest's order.
"""

from __future__ import annotations

import os
import tomllib
from pathlib import Path

import pytest

_ROOT = Path(__file__).resolve().parents[1]


def _selection_rank() -> dict[str, int]:
    try:
        tool = tomllib.loads((_ROOT / "pyproject.toml").read_text(encoding="utf-8"))["tool"]
        paths = tool["mutmut"]["pytest_add_cli_args_test_selection"]
    except (OSError, KeyError, tomllib.TOMLDecodeError):
        return {}
    return {p.rstrip("/"): i for i, p in enumerate(paths)}


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Order a mutant's tests by the selection's file order (mutation runs only)."""
    if "__mutmut_" not in os.environ.get("MUTANT_UNDER_TEST", ""):
        return
    rank = _selection_rank()

    def key(item: pytest.Item) -> int:
        path = item.nodeid.split("::", 1)[0]
        for p, i in rank.items():
            if path == p or path.startswith(p + "/"):
                return i
        return len(rank)

    items.sort(key=key)  # stable: a file's tests keep their order
