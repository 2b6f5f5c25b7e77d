"""Shape kinds of design files compiled to a `TilePath` in the tile-local frame.

Kinds: ``polygon`` (vertices with optional bulges), ``rectangle``, ``square``,
``regular_polygon``, ``triangle_right``, ``triangle_isosceles``, ``circle``, ``semicircle``,
``ring``; every kind takes optional ``holes``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from qshape.design.paths import Loop, TilePath
from qshape.design.values import number as _number
from qshape.errors import DesignError
from qshape.limits import default_limits

SHAPE_KEYS: dict[str, tuple[str, ...]] = {
    "polygon": ("vertices",),
    "rectangle": ("width", "height"),
    "square": ("size",),
    "regular_polygon": ("sides", "radius"),
    "triangle_right": ("width", "height"),
    "triangle_isosceles": ("base", "height"),
    "circle": ("radius",),
    "semicircle": ("radius",),
    "ring": ("radius", "inner_radius"),
}
"""Shape kinds and their required parameters (every kind also takes optional ``holes``)."""

_HOLE_POSE_KEYS = ("x", "y", "angle")


def _circle_loop(r: float) -> Loop:
    return Loop.make([[-r, 0.0], [r, 0.0]], [1.0, 1.0])


def _shape_loop(spec: Mapping[str, Any], where: str) -> Loop:
    """Compile one shape mapping (without holes) to its local `Loop`.

    Raises:
        DesignError: Unknown kind (the message lists the kinds), missing/unknown keys, bad values.
    """
    if not isinstance(spec, Mapping):
        raise DesignError(f"{where}: a shape must be a mapping with a 'kind', got {spec!r}")
    kind = spec.get("kind")
    if kind not in SHAPE_KEYS:
        raise DesignError(f"{where}: unknown shape kind {kind!r}; allowed: {sorted(SHAPE_KEYS)}")
    need = SHAPE_KEYS[kind]
    allowed = {"kind", "holes", *need}
    unknown = sorted(set(spec) - allowed)
    if unknown:
        raise DesignError(
            f"{where}: unknown key(s) {unknown} for {kind}; allowed: {sorted(allowed)}"
        )
    missing = [k for k in need if k not in spec]
    if missing:
        raise DesignError(f"{where}: {kind} needs {missing}")
    try:
        if kind == "polygon":
            rows = spec["vertices"]
            if not isinstance(rows, list) or not all(
                isinstance(r, list) and len(r) in (2, 3) for r in rows
            ):
                raise DesignError(f"{where}: vertices must be a list of [x, y] or [x, y, bulge]")
            v = [[_number(r[0], where, False), _number(r[1], where, False)] for r in rows]
            b = [_number(r[2], where, False) if len(r) == 3 else 0.0 for r in rows]
            return Loop.make(v, b)
        if kind in ("rectangle", "square"):
            w = _number(spec["width" if kind == "rectangle" else "size"], f"{where}.width/size")
            h = _number(spec["height"], f"{where}.height") if kind == "rectangle" else w
            return Loop.make([[-w / 2, -h / 2], [w / 2, -h / 2], [w / 2, h / 2], [-w / 2, h / 2]])
        if kind == "regular_polygon":
            n = spec["sides"]
            if isinstance(n, bool) or not isinstance(n, int) or n < 3:
                raise DesignError(f"{where}.sides: an integer >= 3, got {n!r}")
            r = _number(spec["radius"], f"{where}.radius")
            t = math.pi / 2 + 2 * math.pi * np.arange(n) / n
            return Loop.make(r * np.stack([np.cos(t), np.sin(t)], axis=1))
        if kind == "triangle_right":
            w, h = (
                _number(spec["width"], f"{where}.width"),
                _number(spec["height"], f"{where}.height"),
            )
            return Loop.make([[-w / 2, -h / 2], [w / 2, -h / 2], [-w / 2, h / 2]])
        if kind == "triangle_isosceles":
            w, h = (
                _number(spec["base"], f"{where}.base"),
                _number(spec["height"], f"{where}.height"),
            )
            return Loop.make([[-w / 2, -h / 2], [w / 2, -h / 2], [0.0, h / 2]])
        if kind == "circle":
            return _circle_loop(_number(spec["radius"], f"{where}.radius"))
        if kind == "semicircle":
            r = _number(spec["radius"], f"{where}.radius")
            return Loop.make([[r, 0.0], [-r, 0.0]], [1.0, 0.0])
        # ring: outer circle here; the concentric hole is added by _tile_path.
        return _circle_loop(_number(spec["radius"], f"{where}.radius"))
    except DesignError as exc:
        if str(exc).startswith(where):
            raise
        raise DesignError(f"{where}: {exc}") from exc


def _tile_path(spec: Mapping[str, Any], where: str) -> TilePath:
    """Compile a shape mapping with its holes (tile-local frame, before recentring)."""
    outer = _shape_loop(spec, where)
    holes: list[Loop] = []
    if spec.get("kind") == "ring":
        ro = _number(spec["radius"], f"{where}.radius")
        ri = _number(spec["inner_radius"], f"{where}.inner_radius")
        if ri >= ro:
            raise DesignError(f"{where}: inner_radius {ri} must be < radius {ro}")
        holes.append(_circle_loop(ri))
    raw_holes = spec.get("holes", [])
    if not isinstance(raw_holes, list):
        raise DesignError(f"{where}.holes: must be a list of shapes")
    for k, h in enumerate(raw_holes):
        hw = f"{where}.holes[{k}]"
        if not isinstance(h, Mapping):
            raise DesignError(f"{hw}: must be a mapping")
        pose = {key: h[key] for key in _HOLE_POSE_KEYS if key in h}
        body = {key: v for key, v in h.items() if key not in _HOLE_POSE_KEYS}
        if "holes" in body:
            raise DesignError(f"{hw}: a hole cannot have holes")
        loop = _shape_loop(body, hw)
        ang = math.radians(_number(pose.get("angle", 0.0), f"{hw}.angle", False))
        shift = (
            _number(pose.get("x", 0.0), f"{hw}.x", False),
            _number(pose.get("y", 0.0), f"{hw}.y", False),
        )
        holes.append(loop.transformed(ang, shift))
    return TilePath(outer, tuple(holes))


def tile_path(spec: Mapping[str, Any], where: str) -> TilePath:
    """Compile a shape mapping (``kind``, parameters, optional ``holes``) to its `TilePath`.

    Raises:
        DesignError: Unknown kind (the message lists the kinds), missing/unknown keys, bad values.
        DesignLimitError: An outline longer than the ``max_design_mm`` cap (checked before
            the outline is sampled).
    """
    path = _tile_path(spec, where)
    length = sum(float(loop.edge_lengths().sum()) for loop in (path.outer, *path.holes))
    default_limits().check_length(length, f"{where}: outline length")
    return path


__all__ = ["SHAPE_KEYS", "tile_path"]
