"""Exceptions of the `envs` package."""

from __future__ import annotations


class EnvError(Exception):
    """Base class of every error raised by `envs`."""


class CellError(EnvError, ValueError):
    """The simulated cell was given bad input (config, tiles, slots, commands).

    Raised before anything is simulated where possible; the message names what was wrong and
    what is allowed.
    """


class LayoutError(CellError):
    """The tiles did not fit the tile area in one random layout draw (another draw may fit)."""


class MeshSizeError(CellError):
    """A design's mesh is larger than the cell takes (the message names the largest that fits)."""


__all__ = ["CellError", "EnvError", "LayoutError", "MeshSizeError"]
