"""Observations of MosaicAssembly-v0: the sensors' Dict space, objects and perception rows."""

import importlib
import warnings
from typing import Any


def __getattr__(name: str) -> Any:
    """The old ``envs.observations`` module's names (now `envs.observations.spaces`)."""
    module = importlib.import_module("envs.observations.spaces")
    if not hasattr(module, name):
        raise AttributeError(f"module 'envs.observations' has no attribute {name!r}")
    warnings.warn(
        f"envs.observations.{name} moved to envs.observations.spaces.{name}; the old name loads "
        "until the next version",
        DeprecationWarning,
        stacklevel=2,
    )
    return getattr(module, name)
