"""The design pool's settings: `DesignPoolConfig` (``configs/design_pool.yaml``)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal, get_args

from configs import ConfigError, check_field_types, load_config
from configs.checks import check_fields, checked
from envs.errors import EnvError

StartMethod = Literal["spawn", "forkserver"]
START_METHODS: tuple[str, ...] = get_args(StartMethod)
"""Allowed ``start_method`` values (never ``fork``: a forked worker can hang in EGL)."""


class DesignPoolError(EnvError, ValueError):
    """A bad design pool configuration (names the key and what is allowed)."""


@dataclass(frozen=True)
class DesignPoolConfig:
    """Settings of the design pool (``configs/design_pool.yaml``).

    Attributes:
        ahead: Designs prepared ahead at most, ready or in work [count].
        build_cells: Also build each design's cell (its compiled MuJoCo model, tiles, layout)
            in the worker; False: only the design is drawn there.
        max_entry_mb: A prepared entry (design, cell) larger than this is dropped [MB]. The
            pool's memory bound is ``ahead x max_entry_mb`` (`max_mb`).
        wait_s: Longest wait at a reset for the design the worker is preparing [s]; then the
            env draws it itself.
        start_method: How the worker process starts, one of `START_METHODS`.
    """

    ahead: int = checked(4, ge=1, integer=True)
    build_cells: bool = True
    max_entry_mb: float = checked(16.0, gt=0)
    wait_s: float = checked(30.0, gt=0)
    start_method: StartMethod = checked("spawn", choices=START_METHODS)

    def __post_init__(self) -> None:
        try:
            check_field_types(self)
        except ConfigError as exc:
            raise DesignPoolError(str(exc)) from exc
        check_fields(self, DesignPoolError)

    @property
    def max_mb(self) -> float:
        """Most memory the prepared entries hold together [MB]."""
        return self.ahead * self.max_entry_mb


def load_pool_config(name_or_path: str | Path, **overrides: Any) -> DesignPoolConfig:
    """The pool configuration of a bundled name (``"design_pool"``) or a path, with overrides.

    Raises:
        DesignPoolError: Missing file, unknown key or a value out of range (named).
    """
    try:
        return load_config(DesignPoolConfig, name_or_path, **overrides)
    except ConfigError as exc:
        raise DesignPoolError(f"design_pool {str(name_or_path)!r}: {exc}") from exc


__all__ = [
    "START_METHODS",
    "DesignPoolConfig",
    "DesignPoolError",
    "StartMethod",
    "load_pool_config",
]
