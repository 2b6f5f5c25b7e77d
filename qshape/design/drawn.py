"""Drawn outlines (from SVG or DXF files) to a design mapping: holes, shape classes, slots.

A drawing gives closed outlines in mesh millimetres (y up) with a fill colour each. Here they
become a design file mapping (`qshape.design.fileformat`): outlines nested in another are its
holes (`nest_loops`); each tile's shape is a ``polygon`` (bulges for arcs) about its area
centroid, and tiles whose outlines and holes coincide after a turn share one shape, each slot
with its own turn (`DrawnClasses`), so a factory's repeated tiles are one class whatever their
turn on the drawing.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import shapely

from qshape import geometry as geo
from qshape.design.arc_fit import merge_arcs
from qshape.design.paths import Loop, TilePath
from qshape.design.rules import DesignRules
from qshape.design.values import color_hex, round_mm
from qshape.errors import DesignError
from qshape.geometry import FloatArray


@dataclass(frozen=True)
class DrawnTile:
    """One tile as drawn: outline and holes on the mesh ([mm], y up), its colour and name."""

    name: str
    path: TilePath
    color: tuple[float, float, float]


def nest_loops(
    loops: Sequence[Loop], names: Sequence[str], step: float, keep: Sequence[bool] | None = None
) -> list[tuple[int, list[int]]]:
    """Tiles and their holes from closed outlines, by containment.

    An outline inside no other is a tile; one directly inside a tile is that tile's hole; one
    inside a hole is a tile again (an island), and so on. An outline with ``keep[i]`` False
    takes no part (a non-zero fill's inner outline of the same winding fills, it does not cut).

    Args:
        loops: The outlines.
        names: A name per outline, for errors.
        step: Sampling step of the containment test [mm].
        keep: Per outline, whether it counts (None: all).

    Returns:
        (tile outline index, hole outline indices) per tile, in outline order.

    Raises:
        DesignError: An outline crosses itself, or two overlap (neither holds the other),
            naming them.
    """
    kept = [i for i in range(len(loops)) if keep is None or keep[i]]
    if len(kept) == 1:
        return [(kept[0], [])]  # one outline: a tile (a crossing is the layout check's)
    dense = {i: loops[i].made_vertices(step) for i in kept}  # straight edges: their ends
    polys = {i: shapely.Polygon(dense[i]) for i in kept}
    for i in kept:
        if not polys[i].is_valid:
            raise DesignError(f"{names[i]!r}: its outline crosses itself; allowed: simple outlines")
    areas = {i: float(polys[i].area) for i in kept}
    order = sorted(kept, key=lambda i: -areas[i])
    tree = shapely.STRtree([polys[i] for i in order])
    parent: dict[int, int | None] = {}
    for i in order:
        probe = shapely.Point(dense[i][0])
        best: int | None = None
        for k in tree.query(probe, predicate="intersects"):
            j = order[int(k)]
            if j == i or areas[j] <= areas[i]:
                continue
            if best is None or areas[j] < areas[best]:
                best = j
        if best is not None and not polys[best].contains(polys[i]):
            raise DesignError(
                f"{names[i]!r} and {names[best]!r} overlap: the outlines cross (neither holds "
                "the other); allowed: tiles apart by a joint, holes wholly inside their tile"
            )
        parent[i] = best
    depth: dict[int, int] = {}
    for i in order:  # parents come first (larger)
        p = parent[i]
        depth[i] = 0 if p is None else depth[p] + 1
    out: dict[int, list[int]] = {i: [] for i in kept if depth[i] % 2 == 0}
    for i in kept:
        p = parent[i]
        if depth[i] % 2 == 1 and p is not None:
            out[p].append(i)
    return [(i, out[i]) for i in kept if i in out]


def _polygon_spec(loop: Loop, decimals: int) -> list[list[float]]:
    rows = []
    for (x, y), b in zip(loop.vertices, loop.bulges, strict=True):
        row = [round(float(x), decimals), round(float(y), decimals)]
        if b != 0.0:
            row.append(round(float(b), 9))
        rows.append(row)
    return rows


@dataclass
class _Class:
    """A shape class: its file shape, its path about its vertices' centroid, and sizes."""

    shape: dict[str, Any]
    local: TilePath
    area: float
    offset: FloatArray
    """The area centroid (`TilePath.area_centroid`) from the vertices' centroid [mm]."""


def _anchor(path: TilePath) -> tuple[float, FloatArray]:
    """Area and centroid of the outline's vertices as a polygon (cheap, pose-covariant)."""
    v = path.outer.vertices
    if len(v) < 3:
        return 0.0, v.mean(axis=0)
    return abs(geo.signed_area(v)), geo.polygon_centroid(v)


class DrawnClasses:
    """Shapes of drawn tiles, one per class of tiles equal after a turn.

    Args:
        rules: Sampling rules (the area centroid is the slots' own, `Slot.local_path`).
        tolerance: Largest vertex distance of two tiles of one class after the turn [mm].
        decimals: Digits of the written vertex coordinates.
    """

    def __init__(self, rules: DesignRules, tolerance: float, decimals: int) -> None:
        self.rules, self.tol, self.decimals = rules, tolerance, decimals
        self._by_key: dict[tuple[int, ...], list[_Class]] = {}

    def slot(self, tile: DrawnTile) -> dict[str, Any]:
        """The design file mapping of a drawn tile's slot (its class's shape and its turn).

        Raises:
            DesignError: Zero or negative area (holes as large as the tile).
        """
        v_area, anchor = _anchor(tile.path)
        local = tile.path.transformed(0.0, -anchor)
        key = (len(local.outer.vertices), *sorted(len(h.vertices) for h in local.holes))
        angle = 0.0
        found = None
        for cls in self._by_key.get(key, []):
            if abs(cls.area - v_area) > self.tol * 4.0 * math.sqrt(max(v_area, 1e-12)):
                continue
            turn = _turn_onto(cls.local, local, self.tol)
            if turn is not None:
                found, angle = cls, turn
                break
        if found is not None:
            c = anchor + geo.rotate(found.offset, angle)
        else:
            if geo.self_intersects(tile.path.outer.dense(self.rules.check_step_mm)):
                raise DesignError(
                    f"slot {tile.name!r}: its outline crosses itself; allowed: simple outlines"
                )
            area, c = tile.path.area_centroid(self.rules.outline_step_mm)
            if not area > 0.0:
                raise DesignError(f"slot {tile.name!r}: zero or negative area (holes too large?)")
            class_local = tile.path.transformed(0.0, -c)
            shape: dict[str, Any] = {
                "kind": "polygon",
                "vertices": _polygon_spec(class_local.outer, self.decimals),
            }
            if class_local.holes:
                shape["holes"] = [
                    {"kind": "polygon", "vertices": _polygon_spec(h, self.decimals)}
                    for h in class_local.holes
                ]
            found = _Class(shape, local, v_area, c - anchor)
            self._by_key.setdefault(key, []).append(found)
        return {
            "name": tile.name,
            "shape": found.shape,
            "color": color_hex(tile.color),
            "pose": {
                "x": round_mm(float(c[0])),
                "y": round_mm(float(c[1])),
                "angle": round(math.degrees(angle), 9),
            },
        }


def _turn_onto(ref: TilePath, new: TilePath, tol: float) -> float | None:
    """The turn [rad] that takes ``ref`` onto ``new`` (both about their centroids), or None."""
    rv, rb = ref.outer.vertices, ref.outer.bulges
    nv, nb = new.outer.vertices, new.outer.bulges
    n = len(rv)
    k = int(np.argmax(np.hypot(*rv.T)))
    for s in range(n):
        if not np.allclose(np.roll(nb, -s), rb, atol=1e-6):
            continue
        target = np.roll(nv, -s, axis=0)
        angle = math.atan2(target[k, 1], target[k, 0]) - math.atan2(rv[k, 1], rv[k, 0])
        if float(np.max(np.hypot(*(geo.rotate(rv, angle) - target).T))) > tol:
            continue
        if _holes_match(ref.holes, new.holes, angle, tol):
            return angle
    return None


def _holes_match(ref: Sequence[Loop], new: Sequence[Loop], angle: float, tol: float) -> bool:
    """Each of ``ref``'s holes turned by ``angle`` is one of ``new``'s (vertices within tol)."""
    free = list(new)
    for h in ref:
        rv = geo.rotate(h.vertices, angle)
        hit = None
        for q, cand in enumerate(free):
            if len(cand.vertices) != len(rv):
                continue
            for s in range(len(rv)):
                same_b = np.allclose(np.roll(cand.bulges, -s), h.bulges, atol=1e-6)
                moved = np.roll(cand.vertices, -s, axis=0) - rv
                if same_b and float(np.max(np.hypot(*moved.T))) <= tol:
                    hit = q
                    break
            if hit is not None:
                break
        if hit is None:
            return False
        free.pop(hit)
    return not free


def loop_from_nodes(
    vertices: FloatArray, bulges: FloatArray, where: str, tol: float = 1e-3
) -> Loop:
    """A closed `Loop` of vertices and DXF bulges, consecutive repeats merged.

    Neighbouring arcs of one circle (centres and radii within ``tol`` [mm]) are joined up
    to half circles (`qshape.design.arc_fit.merge_arcs`). ``bulges`` follow the DXF
    convention (positive: the arc turns counter-clockwise, y up),
    whichever way the outline runs; `Loop`'s bulges are positive bowing out of the tile, so
    they are negated for a clockwise outline before it is turned counter-clockwise.

    Raises:
        DesignError: Fewer than the vertices a closed outline needs, naming ``where``.
    """
    v = np.asarray(vertices, dtype=np.float64).reshape(-1, 2)
    b = np.asarray(bulges, dtype=np.float64).reshape(-1)
    if len(b) != len(v) or not (np.all(np.isfinite(v)) and np.all(np.isfinite(b))):
        raise DesignError(f"{where}: vertices and bulges must be finite, one bulge per vertex")
    nxt = np.concatenate([v[1:], v[:1]])
    keep = np.hypot(*(nxt - v).T) > 1e-9
    v, b = merge_arcs(v[keep], b[keep], tol)
    nxt = np.concatenate([v[1:], v[:1]])
    if len(v) < (2 if np.any(b != 0.0) else 3):
        raise DesignError(f"{where}: a closed outline needs at least 3 vertices, got {len(v)}")
    d = nxt - v
    right = np.stack([d[:, 1], -d[:, 0]], axis=1)  # chord length x right unit normal
    mids = 0.5 * (v + nxt) + right * (b / 2.0)[:, None]
    ring = np.stack([v, mids], axis=1).reshape(-1, 2)  # vertices and arc middles, in order
    x, y = ring[:, 0], ring[:, 1]
    x1, y1 = np.concatenate([x[1:], x[:1]]), np.concatenate([y[1:], y[:1]])
    if float(np.sum(x * y1 - x1 * y)) >= 0.0:
        return Loop(v, b)  # counter-clockwise: DXF bulges are outward bulges
    # Clockwise: run it the other way; edge (v_i+1 -> v_i) turns the other way round.
    return Loop(v[::-1].copy(), -np.concatenate([b[::-1][1:], b[::-1][:1]]))


__all__ = ["DrawnClasses", "DrawnTile", "loop_from_nodes", "nest_loops"]
