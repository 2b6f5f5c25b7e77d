"""The scripted cell: perception, calibration, placement and the agent that drives the env."""

import importlib
import warnings
from typing import Any


def __getattr__(name: str) -> Any:
    """Names of the old ``agents.scripted`` module (now `agents.scripted.agent`), one version."""
    module = importlib.import_module("agents.scripted.agent")
    if not hasattr(module, name):
        raise AttributeError(f"module 'agents.scripted' has no attribute {name!r}")
    warnings.warn(
        f"agents.scripted.{name} moved to agents.scripted.agent.{name}; the old name loads until "
        "the next version",
        DeprecationWarning,
        stacklevel=2,
    )
    return getattr(module, name)
