"""Stable-baselines3 (and sb3-contrib) algorithm classes by name, for training and loading."""

from __future__ import annotations

from typing import Any

from configs import ConfigError


class AlgorithmError(ConfigError):
    """No stable-baselines3 or sb3-contrib algorithm has the name asked for (lists the known)."""


def algorithm_class(name: str) -> type[Any]:
    """The SB3 (or sb3_contrib) algorithm class called ``name``.

    Raises:
        AlgorithmError: No such algorithm (lists the known ones).
    """
    import stable_baselines3 as sb3  # noqa: PLC0415 - heavy import
    from stable_baselines3.common.base_class import BaseAlgorithm  # noqa: PLC0415

    modules: list[Any] = [sb3]
    try:
        import sb3_contrib  # noqa: PLC0415 - optional

        modules.append(sb3_contrib)
    except ImportError:
        pass
    known = []
    for module in modules:
        for attr in dir(module):
            obj = getattr(module, attr)
            if isinstance(obj, type) and issubclass(obj, BaseAlgorithm):
                known.append(attr)
                if attr.lower() == name.lower():
                    return obj
    raise AlgorithmError(f"unknown algorithm {name!r}; known: {sorted(set(known))}")


__all__ = ["AlgorithmError", "algorithm_class"]
