"""The cell inside the env's configuration: the flat keyword shortcuts and how cells merge.

`envs.env_config.EnvConfig` nests a `CellConfig` (``cell:``); these functions build it from the
env file's ``cell`` section, a ``cell`` keyword and the flat `CELL_KEYS` keywords.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict, replace
from pathlib import Path
from typing import Any

from configs import ConfigError, from_dict
from envs.cell.config import CellConfig, load_cell_config, section_names
from envs.errors import CellError, EnvError


class EnvConfigError(ConfigError, EnvError):
    """Bad environment configuration: unknown key or mode, or an invalid value."""


CELL_KEYS: dict[str, tuple[str, str]] = {
    "belt_speed": ("input_belt", "speed"),
    "feed": ("tiles", "feed"),
    "stream_period": ("tiles", "stream_period"),
    "stream_initial": ("tiles", "stream_initial"),
    "stream_start": ("tiles", "stream_start"),
    "batch_size": ("tiles", "batch_size"),
    "batch_index_time": ("tiles", "batch_index_time"),
    "distractor_rate": ("tiles", "distractor_rate"),
    "vertex_jitter": ("tiles", "vertex_jitter"),
    "tile_color_jitter": ("tiles", "color_jitter"),
    "tile_variants": ("tiles", "variants"),
}
"""Flat keyword overrides of the nested cell: keyword -> (cell section, key)."""
ENV_CELL_CHANGES: dict[str, dict[str, Any]] = {
    "tiles": {"variants": 8, "stream_period": 2.5, "stream_initial": 1},
}
"""The env's changes to the bundled cell (as ``configs/env.yaml`` states them)."""


def env_cell(base: str | Path | CellConfig, changes: Mapping[str, Mapping[str, Any]]) -> CellConfig:
    """The cell ``base`` (a `CellConfig`, bundled name or path) with sections changed key by key.

    Raises:
        EnvConfigError: Unknown section or key, or an invalid value (the message names it).
    """
    try:
        cell = base if isinstance(base, CellConfig) else load_cell_config(base)
        merged: dict[str, Any] = {}
        for section, values in changes.items():
            if section not in section_names():
                raise EnvConfigError(
                    f"unknown cell section {section!r}; allowed: {section_names()}"
                )
            if not isinstance(values, Mapping):
                raise EnvConfigError(f"cell.{section} must be a mapping, got {values!r}")
            merged[section] = {**asdict(getattr(cell, section)), **values}
        return (
            replace(
                cell,
                **{
                    k: from_dict(type(getattr(cell, k)), v, source=f"cell.{k}")
                    for k, v in merged.items()
                },
            )
            if merged
            else cell
        )
    except CellError as exc:
        raise EnvConfigError(str(exc)) from exc
    except ConfigError as exc:
        raise EnvConfigError(f"cell: {exc}") from exc


def merge_cell(file_cell: Any, given: Any) -> Any:
    """A ``cell`` keyword applied to the env file's ``cell`` section.

    A mapping without a ``config`` key changes the file's mapping section by section, key by
    key (so passing only a camera section keeps the env's tile settings); one that names its
    ``config``, a name, a path or a `CellConfig` starts afresh from that cell file.
    """
    if given is None:
        return file_cell
    if not (isinstance(given, Mapping) and isinstance(file_cell, Mapping)) or "config" in given:
        return given
    merged: dict[str, Any] = {
        k: dict(v) if isinstance(v, Mapping) else v for k, v in file_cell.items()
    }
    for key, value in given.items():
        if isinstance(value, Mapping) and isinstance(merged.get(key), Mapping):
            merged[key] = {**merged[key], **value}
        else:
            merged[key] = value
    return merged


def split_cell(raw: Any, flat: dict[str, Any]) -> CellConfig:
    """The nested cell of a YAML/keyword ``cell`` value plus the flat `CELL_KEYS` in ``flat``."""
    changes: dict[str, dict[str, Any]] = {}
    if isinstance(raw, CellConfig):
        base: str | Path | CellConfig = raw
    elif raw is None or isinstance(raw, str | Path):
        base = raw or "cell"
    elif isinstance(raw, Mapping):
        rest = dict(raw)
        base = rest.pop("config", "cell")
        changes = {k: dict(v) if isinstance(v, Mapping) else v for k, v in rest.items()}
    else:
        raise EnvConfigError(
            f"cell must be a bundled name, a path or a mapping {{config: ..., <section>: ...}}, "
            f"got {raw!r}"
        )
    given = {}
    for key in [k for k in flat if k in CELL_KEYS]:
        section, name = CELL_KEYS[key]
        changes.setdefault(section, {})[name] = flat.pop(key)
        given[key] = f"cell.{section}.{name}"
    try:
        return env_cell(base, changes)
    except EnvConfigError as exc:
        if not given:
            raise
        keys = ", ".join(f"{k} = {v}" for k, v in given.items())
        raise EnvConfigError(f"{exc} (flat keywords: {keys})") from exc


__all__ = [
    "CELL_KEYS",
    "ENV_CELL_CHANGES",
    "EnvConfigError",
    "env_cell",
    "merge_cell",
    "split_cell",
]
