"""Plain values of design files: checked numbers, colours, rounding and YAML-ready data."""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from qshape.errors import DesignError


def number(value: Any, where: str, positive: bool = True) -> float:
    """A finite real number (not a bool or a string), > 0 when ``positive``.

    Raises:
        DesignError: Naming ``where`` and the value.
    """
    if (
        isinstance(value, bool | np.bool_)
        or not isinstance(value, numbers.Real)
        or not math.isfinite(value)
    ):
        raise DesignError(f"{where}: expected a finite number, got {value!r}")
    if positive and value <= 0:
        raise DesignError(f"{where}: must be > 0, got {value!r}")
    return float(value)


def parse_color(value: Any, where: str) -> tuple[float, float, float]:
    """RGB floats in [0, 1] from ``[r, g, b]`` (floats in [0, 1]) or ``"#rrggbb"``."""
    if isinstance(value, str):
        s = value.lstrip("#")
        if len(s) != 6 or any(c not in "0123456789abcdefABCDEF" for c in s):
            raise DesignError(f"{where}: colour string must be '#rrggbb', got {value!r}")
        return (int(s[0:2], 16) / 255.0, int(s[2:4], 16) / 255.0, int(s[4:6], 16) / 255.0)
    if isinstance(value, list | tuple) and len(value) == 3:
        rgb = tuple(number(v, where, False) for v in value)
        if all(0.0 <= v <= 1.0 for v in rgb):
            return (rgb[0], rgb[1], rgb[2])
    raise DesignError(f"{where}: colour must be '#rrggbb' or [r, g, b] in [0, 1], got {value!r}")


def color_hex(rgb: Sequence[float]) -> str:
    """``"#rrggbb"`` of an RGB triple in [0, 1]."""
    r, g, b = (int(round(min(max(float(v), 0.0), 1.0) * 255)) for v in rgb)
    return f"#{r:02x}{g:02x}{b:02x}"


def round_mm(v: float) -> float:
    """``v`` rounded to 4 decimals (0.1 um for millimetres), as written in design files."""
    return float(round(float(v), 4))


def plain(value: Any) -> Any:
    """Plain Python (dicts, lists, floats) for YAML output and hashing."""
    if isinstance(value, Mapping):
        return {str(k): plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple | np.ndarray):
        return [plain(v) for v in value]
    if isinstance(value, np.integer | int) and not isinstance(value, bool):
        return int(value)
    if isinstance(value, np.floating | float):
        return round_mm(float(value))
    return value


__all__ = ["color_hex", "number", "parse_color", "plain", "round_mm"]
