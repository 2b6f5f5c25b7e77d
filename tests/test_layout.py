"""The layout says what is in it: folders split by kind, no folder of many sibling modules."""

from __future__ import annotations

import importlib
import sys
from pathlib import Path

import pytest

from agents.moved import MOVED

ROOT = Path(__file__).resolve().parents[1]
MOST_MODULES = {"agents": 10, "apps": 14, "benchmarks": 14, "envs": 16}
"""At most this many modules directly in each folder; more go into subpackages by kind."""


@pytest.mark.parametrize(("folder", "most"), sorted(MOST_MODULES.items()))
def test_folders_hold_few_modules_directly(folder: str, most: int) -> None:
    modules = sorted(p.name for p in (ROOT / folder).glob("*.py"))
    assert len(modules) <= most, f"{folder}/ holds {len(modules)} modules: {modules}"


def test_old_agent_module_names_load_the_moved_modules() -> None:
    """Checkpoints pickle classes by dotted path: an old name loads the moved module, warning."""
    for old, new in sorted(MOVED.items()):
        sys.modules.pop(old, None)
        with pytest.warns(DeprecationWarning, match=new.replace(".", r"\.")):
            module = importlib.import_module(old)
        assert module is importlib.import_module(new), old
    pair = importlib.import_module("agents.pair_policy")
    assert pair.PairScorerPolicy.__module__ == "agents.pair.maskable_policy"
