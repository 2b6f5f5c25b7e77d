"""Random non-overlapping layouts of tiles on the input belt's tile area.

Poses are (x, y, yaw) relative to the tile area's centre [m, m, rad]; tiles are kept apart by a
minimum gap between their outlines (or bounding circles).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import shapely
import shapely.ops
from shapely.geometry import Polygon

from envs.errors import CellError, LayoutError

OUTLINE_FILL = 0.5
"""Largest fraction of a tile area random placement of outlines is asked to fill."""


CIRCLE_FILL = 0.8
"""The same for bounding circles (no outlines given)."""


def layout_capacity(outlines: Sequence[np.ndarray], area_size: Sequence[float], gap: float) -> int:
    """How many of ``outlines``, taken in order, `sample_layout` can be asked to lay out.

    Args:
        outlines: Tile outlines in their own frames, each shape (k, 2) [m].
        area_size: (x, y) size of the rectangle [m].
        gap: Minimum clearance between tiles [m].

    Returns:
        The longest prefix whose area (each outline grown by ``gap / 2``) is within
        `OUTLINE_FILL` of the rectangle's.
    """
    need = np.cumsum([Polygon(o).buffer(gap / 2).area for o in outlines])
    return int(np.searchsorted(need, OUTLINE_FILL * area_size[0] * area_size[1], side="right"))


def sample_layout(
    radii: np.ndarray,
    area_size: tuple[float, ...],
    gap: float,
    attempts: int,
    rng: np.random.Generator,
    *,
    outlines: Sequence[np.ndarray] | None = None,
    occupied: np.ndarray | None = None,
    occupied_radii: np.ndarray | None = None,
    restarts: int = 1,
) -> np.ndarray:
    """Random non-overlapping poses for tiles in a rectangle.

    Tiles are placed largest first at uniform random positions and yaws. Two tiles whose
    bounding circles (plus ``gap``) do not overlap are accepted at once; with ``outlines``
    given, closer pairs are accepted when the actual outlines keep ``gap`` apart.

    Args:
        radii: Bounding radii about each tile's origin, shape (n,) [m].
        area_size: (length, width) of the rectangle centred at the origin [m].
        gap: Clearance between tiles [m].
        attempts: Tries per tile before giving up.
        rng: Random generator.
        outlines: Optional outline per tile in its own frame, each shape (k, 2) [m] (exact
            test, denser packing).
        occupied: Centres of circles already there, shape (k, 2) [m], optional.
        occupied_radii: Their radii, shape (k,) [m].
        restarts: Whole layouts tried before giving up (random sequential placement can jam
            near 50 % fill even when a layout exists; a fresh draw usually succeeds).

    Returns:
        Poses (x, y, yaw), shape (n, 3), in the rectangle's frame [m, m, rad].

    Raises:
        CellError: A tile does not fit (too large, or the area is too full).
    """
    radii = np.asarray(radii, dtype=float)
    half = np.asarray(area_size, dtype=float) / 2
    if outlines is not None:
        extent = np.array([_min_half_extent(o) for o in outlines])
    else:
        extent = radii
    if np.any(extent + gap / 2 > half.min()):
        k = int(np.argmax(extent))
        raise CellError(
            f"tile {k} (size {2 * extent[k] * 1000:.1f} mm) does not fit the tile area "
            f"{area_size[0] * 1000:.0f} x {area_size[1] * 1000:.0f} mm"
        )
    if outlines is not None:
        need = float(sum(Polygon(o).buffer(gap / 2).area for o in outlines))
        fill = OUTLINE_FILL
    else:
        need = float(np.sum(np.pi * (radii + gap / 2) ** 2))
        fill = CIRCLE_FILL
    have = float(area_size[0] * area_size[1])
    if need > fill * have:
        raise CellError(
            f"{len(radii)} tiles need about {need * 1e4:.0f} cm^2 of belt but the tile area is "
            f"{have * 1e4:.0f} cm^2 (random placement fills at most ~{fill:.0%}); use fewer "
            "tiles, a larger input_belt.tile_area, or feed='stream' or 'batch'"
        )

    def once() -> np.ndarray:
        return _layout_once(
            radii,
            half,
            gap,
            attempts,
            rng,
            outlines=outlines,
            occupied=occupied,
            occupied_radii=occupied_radii,
        )

    for _ in range(max(restarts, 1) - 1):
        try:
            return once()
        except CellError:
            continue
    return once()


def _layout_once(
    radii: np.ndarray,
    half: np.ndarray,
    gap: float,
    attempts: int,
    rng: np.random.Generator,
    *,
    outlines: Sequence[np.ndarray] | None,
    occupied: np.ndarray | None,
    occupied_radii: np.ndarray | None,
) -> np.ndarray:
    """One try of `sample_layout` (same arguments); raises CellError when it jams."""
    area_size = 2 * half
    centres = np.zeros((0, 2)) if occupied is None else np.asarray(occupied, float)
    rads = np.zeros(0) if occupied_radii is None else np.asarray(occupied_radii, float)
    n_fixed = len(centres)
    placed: list[Polygon] = []
    out = np.zeros((len(radii), 3))
    for i in np.argsort(-radii):
        lim = half - radii[i]
        lim = np.where(lim > 0, lim, 0.0)
        cand = rng.uniform(-lim, lim, size=(attempts, 2))
        yaws = rng.uniform(-np.pi, np.pi, attempts)
        if len(centres):
            d = np.linalg.norm(cand[:, None, :] - centres[None, :, :], axis=2)
            clear = d >= rads[None, :] + radii[i] + gap
        else:
            clear = np.ones((attempts, 0), bool)
        chosen = -1
        for c in range(attempts):
            poly = None
            if outlines is not None:
                poly = _posed(outlines[i], cand[c], yaws[c])
                if not _inside(poly, half):
                    continue
            if clear[c].all():
                chosen = c
            elif outlines is not None and not clear[c, :n_fixed].all():
                continue
            elif outlines is not None:
                near = [placed[k - n_fixed] for k in np.flatnonzero(~clear[c])]
                if np.all(shapely.distance(poly, near) >= gap):
                    chosen = c
            if chosen >= 0:
                if poly is not None:
                    placed.append(poly)
                break
        if chosen < 0:
            raise LayoutError(
                f"could not place {len(radii)} tiles without overlap in the tile area "
                f"{area_size[0] * 1000:.0f} x {area_size[1] * 1000:.0f} mm after {attempts} "
                "tries per tile; use fewer tiles, a larger area or feed='stream'"
            )
        out[i] = (cand[chosen, 0], cand[chosen, 1], yaws[chosen])
        centres = np.vstack([centres, cand[chosen]])
        rads = np.append(rads, radii[i])
    return out


def _posed(outline: np.ndarray, xy: np.ndarray, yaw: float) -> Polygon:
    c, s = np.cos(yaw), np.sin(yaw)
    return Polygon(outline @ np.array([[c, s], [-s, c]]) + xy)


def _inside(poly: Polygon, half: np.ndarray) -> bool:
    x0, y0, x1, y1 = poly.bounds
    return bool(x0 >= -half[0] and x1 <= half[0] and y0 >= -half[1] and y1 <= half[1])


def _min_half_extent(outline: np.ndarray) -> float:
    """Half the smallest width of an outline over rotations (it must fit some way) [m]."""
    hull = np.asarray(Polygon(outline).convex_hull.exterior.coords)[:-1]
    edges = np.roll(hull, -1, axis=0) - hull
    normals = np.stack([-edges[:, 1], edges[:, 0]], axis=1)
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    proj = hull @ normals.T
    return float(np.min(proj.max(axis=0) - proj.min(axis=0)) / 2)


__all__ = [
    "CIRCLE_FILL",
    "OUTLINE_FILL",
    "layout_capacity",
    "sample_layout",
]
