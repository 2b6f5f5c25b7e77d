"""Convex decomposition of tile outlines (with holes) for MuJoCo's convex collision meshes.

Ear-clipping triangulation (bridging holes into the outline), merged into convex pieces by
Hertel-Mehlhorn. Units: metres; outlines counter-clockwise.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache

import numpy as np
import shapely
import shapely.ops
from shapely.geometry import Polygon

from envs.errors import CellError
from qshape.geometry import signed_area

_EPS = 1e-12


def _is_convex(poly: np.ndarray, tol: float = 1e-12) -> bool:
    d1 = np.roll(poly, -1, axis=0) - poly
    d2 = np.roll(d1, -1, axis=0)
    cross = d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]
    return bool(np.all(cross >= -tol))


def _hertel_mehlhorn(points: np.ndarray, tris: list[list[int]]) -> list[list[int]]:
    """Merge counter-clockwise triangles (vertex indices) into convex polygons."""
    pieces: dict[int, list[int]] = dict(enumerate(tris))
    changed = True
    while changed:
        changed = False
        edge_owner = {}
        for pid, poly in pieces.items():
            for k in range(len(poly)):
                edge_owner[(poly[k], poly[(k + 1) % len(poly)])] = pid
        for pid in sorted(pieces):
            poly = pieces[pid]
            for k in range(len(poly)):
                a, b = poly[k], poly[(k + 1) % len(poly)]
                qid = edge_owner.get((b, a))
                if qid is None or qid == pid:
                    continue
                q = pieces[qid]
                ib = poly.index(b)
                p_rot = poly[ib:] + poly[:ib]  # starts at b, ends at a
                ia = q.index(a)
                q_rot = q[ia:] + q[:ia]  # starts at a, ends at b
                merged = p_rot + q_rot[1:-1]
                if _is_convex(points[merged]):
                    pieces[pid] = merged
                    del pieces[qid]
                    changed = True
                    break
            if changed:
                break
    return list(pieces.values())


def convex_decomposition(
    outline: np.ndarray, holes: Sequence[np.ndarray] = ()
) -> tuple[np.ndarray, tuple[list[int], ...]]:
    """Split a polygon (with holes) into convex pieces.

    Constrained Delaunay triangulation (shapely) followed by Hertel-Mehlhorn merging, so the
    pieces share the polygon's own vertices.

    Args:
        outline: Outer boundary, shape (n, 2), counter-clockwise.
        holes: Holes, each shape (m, 2).

    Returns:
        ``(points, pieces)``: all vertices, shape (n + sum m, 2), outline first then holes in
        order; and each convex piece as a counter-clockwise list of indices into ``points``.
    """
    points = np.vstack([outline, *holes]) if holes else np.asarray(outline)
    if not holes and _is_convex(points):
        return points, (list(range(len(points))),)
    index = {(round(float(x), 12), round(float(y), 12)): i for i, (x, y) in enumerate(points)}
    tris_geom = shapely.constrained_delaunay_triangles(Polygon(outline, list(holes)))
    tris: list[list[int]] = []
    for tri in tris_geom.geoms:
        coords = np.asarray(tri.exterior.coords)[:3]
        try:
            ids = [index[(round(float(x), 12), round(float(y), 12))] for x, y in coords]
        except KeyError as exc:  # pragma: no cover - shapely adds no Steiner points
            raise CellError("convex decomposition produced a vertex not in the polygon") from exc
        if signed_area(points[ids]) < 0:
            ids = ids[::-1]
        if abs(signed_area(points[ids])) > _EPS * 1e-3:
            tris.append(ids)
    return points, tuple(_hertel_mehlhorn(points, tris))


@lru_cache(maxsize=256)
def _decompose_cached(key: bytes, n_out: int, hole_sizes: tuple[int, ...]) -> tuple:
    flat = np.frombuffer(key, dtype=float).reshape(-1, 2)
    outline = flat[:n_out]
    holes, start = [], n_out
    for m in hole_sizes:
        holes.append(flat[start : start + m])
        start += m
    return convex_decomposition(outline, holes)


def decompose(outline: np.ndarray, holes: Sequence[np.ndarray]) -> tuple:
    """`convex_decomposition` of an outline and holes, cached by their exact coordinates."""
    flat = np.vstack([outline, *holes]).astype(float)
    return _decompose_cached(flat.tobytes(), len(outline), tuple(len(h) for h in holes))


__all__ = [
    "convex_decomposition",
    "decompose",
]
