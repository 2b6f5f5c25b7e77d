"""Shape mappings of design files built from geometry, for the procedural generator.

A mapping is what a design file holds for one tile or hole (``kind`` plus its lengths in [mm]);
`qshape.design.shapes.tile_path` compiles it.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import shapely

from qshape.design.shapes import tile_path

Shape = dict[str, Any]
"""A design file's shape mapping."""


def circumradius(hole: Shape) -> float:
    """Largest distance of a hole mapping's outline from its own centre, [mm]."""
    path = tile_path(hole, "generated hole")
    return float(np.max(np.hypot(*path.outer.dense(0.5).T)))


def inradius(poly: shapely.Polygon, c: np.ndarray) -> float:
    """Distance from the point ``c`` (2,) to the boundary of ``poly``, [mm]."""
    return float(poly.boundary.distance(shapely.Point(float(c[0]), float(c[1]))))


def hole_shape(kind: str, size: float, rng: np.random.Generator) -> Shape:
    """A hole of inscribed diameter ``size`` (the rectangle's short side)."""
    if kind == "circle":
        return {"kind": "circle", "radius": size / 2.0}
    if kind == "square":
        return {"kind": "square", "size": size}
    if kind == "rectangle":
        return {"kind": "rectangle", "width": size * float(rng.uniform(1.3, 2.0)), "height": size}
    if kind == "triangle":
        # Equilateral: inradius = circumradius / 2.
        return {"kind": "regular_polygon", "sides": 3, "radius": size}
    sides = 5 if kind == "pentagon" else 6
    return {
        "kind": "regular_polygon",
        "sides": sides,
        "radius": size / 2.0 / math.cos(math.pi / sides),
    }


def polygon_shape(vertices: Any, bulges: Any = None) -> Shape:
    """A ``polygon`` mapping of vertices (n, 2) [mm] with optional bulges (n,) (0: straight)."""
    v = np.asarray(vertices, dtype=float)
    b = np.zeros(len(v)) if bulges is None else np.asarray(bulges, dtype=float)
    rows = [
        [float(x), float(y), float(bb)] if bb != 0.0 else [float(x), float(y)]
        for (x, y), bb in zip(v, b, strict=True)
    ]
    return {"kind": "polygon", "vertices": rows}


def rounded_polygon_shape(v: np.ndarray, rho: float, which: np.ndarray) -> Shape:
    """A convex counter-clockwise polygon with some corners rounded.

    The corners ``which`` (bool per vertex) get a radius-``rho`` arc tangent to both edges.
    """
    n = len(v)
    verts: list[list[float]] = []
    for i in range(n):
        p, a, b = v[i], v[i - 1], v[(i + 1) % n]
        if not which[i]:
            verts.append(p.tolist())
            continue
        u0 = (a - p) / np.hypot(*(a - p))
        u1 = (b - p) / np.hypot(*(b - p))
        interior = math.acos(float(np.clip(np.dot(u0, u1), -1.0, 1.0)))
        d = rho / math.tan(interior / 2.0)
        turn = math.pi - interior
        verts.append([*(p + u0 * d).tolist(), math.tan(turn / 4.0)])
        verts.append((p + u1 * d).tolist())
    return {"kind": "polygon", "vertices": verts}


def scaled_shape(shape: Shape, s: float) -> Shape:
    """The shape mapping with every length scaled by ``s`` (bulges and angles kept)."""
    out: Shape = {}
    for k, val in shape.items():
        if k in ("radius", "size", "width", "height", "base", "inner_radius", "x", "y"):
            out[k] = float(val) * s
        elif k == "vertices":
            out[k] = [[r[0] * s, r[1] * s, *r[2:]] for r in val]
        elif k == "holes":
            out[k] = [scaled_shape(h, s) for h in val]
        else:
            out[k] = val
    return out


__all__ = [
    "Shape",
    "circumradius",
    "hole_shape",
    "inradius",
    "polygon_shape",
    "rounded_polygon_shape",
    "scaled_shape",
]
