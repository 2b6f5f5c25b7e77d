"""Fixtures shared by the test folders: the bundled picture and extraction parameters.

Loaded once per test module (frozen values: a test changes a copy, ``dataclasses.replace``).

Under mutation testing (mutmut sets ``MUTANT_UNDER_TEST`` to the mutant's name in the process
that runs its tests) a mutant's tests run file by file: first the files pyproject's
``[tool.mosaic-mutation.first_tests]`` names for the mutated module, then in the order of
``[tool.mutmut] pytest_add_cli_args_test_selection``, which lists the fast contract tests
first. mutmut stops at the first failure, so a killed mutant costs the cheapest test that
catches it. Ordinary runs keep pytest's order.
"""

from __future__ import annotations

import os
import tomllib
from pathlib import Path

import pytest

from qshape.synthetic.synth import SynthParams
from qshape.vision.params import ExtractParams

_ROOT = Path(__file__).resolve().parents[1]


def _file_order(mutant: str) -> list[str]:
    """Test files (or folders) in the order a mutant's tests should run."""
    try:
        tool = tomllib.loads((_ROOT / "pyproject.toml").read_text(encoding="utf-8"))["tool"]
    except (OSError, tomllib.TOMLDecodeError):
        return []
    selection = tool.get("mutmut", {}).get("pytest_add_cli_args_test_selection", [])
    first = tool.get("mosaic-mutation", {}).get("first_tests", {})
    module = mutant.split(".x", 1)[0]
    return [p.rstrip("/") for p in [*first.get(module, []), *selection]]


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Order a mutant's tests (mutation runs only; see the module docstring)."""
    mutant = os.environ.get("MUTANT_UNDER_TEST", "")
    if "__mutmut_" not in mutant:
        return
    order = _file_order(mutant)

    def key(item: pytest.Item) -> int:
        path = item.nodeid.split("::", 1)[0]
        for i, p in enumerate(order):
            if path == p or path.startswith(p + "/"):
                return i
        return len(order)

    items.sort(key=key)  # stable: a file's tests keep their order


@pytest.fixture(scope="module")
def synth_params() -> SynthParams:
    """The bundled synthetic-picture parameters (``configs/vision.yaml``, ``synth``)."""
    return SynthParams.load()


@pytest.fixture(scope="module")
def extract_params() -> ExtractParams:
    """The bundled extraction parameters (``configs/vision.yaml``, ``extract``)."""
    return ExtractParams.load()
