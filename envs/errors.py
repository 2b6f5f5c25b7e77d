"""Exceptions of the `envs` package."""

from __future__ import annotations


class EnvError(Exception):
    """Base class of every error raised by `envs`."""


class CellError(EnvError, ValueError):
    """The simulated cell was given bad input (config, tiles, slots, commands).

    Raised before anything is simulated where possible; the message names what was wrong and
    what is allowed.
    """


__all__ = ["CellError", "EnvError"]
