"""Where the pad holds a tile best when it does not fit on the tile at the tile's centroid.

The vacuum pad (a disc) seals on the tile's material: the more of the pad lies on the tile,
the more of the vacuum holds it. On a thin tile (an arrowhead, a thin star) no point has the
whole pad on material; the pad then goes where the most of it does (`best_hold`): the point of
the tile maximising the area of the pad disc on the tile, the nearest such point to the
centroid among equals (less turning moment while the arm accelerates). The placement moves
the pad point with the tile (`agents.placement`), so the tile's centroid still lands on the
slot's.
"""

from __future__ import annotations

import numpy as np
import shapely
from shapely.geometry import Polygon


def pad_area_on_tile(tile: Polygon, points: np.ndarray, pad_radius: float) -> np.ndarray:
    """Area of the pad disc on the tile, per pad centre, shape (n,) [unit^2]."""
    discs = shapely.buffer(
        shapely.points(np.asarray(points, dtype=float)), pad_radius, quad_segs=32
    )
    return np.asarray(shapely.area(shapely.intersection(discs, tile)), dtype=float)


def best_hold(
    tile: Polygon, centre: np.ndarray, pad_radius: float, step: float, tolerance: float
) -> np.ndarray:
    """The pad centre with the most pad area on the tile, shape (2,) [the tile's unit].

    A grid of ``step`` over the tile, then finer grids about the best point down to
    ``tolerance``; among points within 0.5 % of the best area, the nearest to ``centre``.
    """
    lo_x, lo_y, hi_x, hi_y = tile.bounds
    xs = np.arange(lo_x + step / 2, hi_x, step)
    ys = np.arange(lo_y + step / 2, hi_y, step)
    grid = np.stack(np.meshgrid(xs, ys), axis=-1).reshape(-1, 2)
    inside = shapely.contains_xy(tile, grid[:, 0], grid[:, 1])
    cands = grid[inside] if inside.any() else np.asarray(centre, dtype=float)[None]
    best = _pick(tile, cands, centre, pad_radius)
    h = step
    while h > tolerance:
        h /= 3.0
        off = np.stack(np.meshgrid(*(np.arange(-3, 4) * h,) * 2), axis=-1).reshape(-1, 2)
        cands = best + off
        keep = shapely.contains_xy(tile, cands[:, 0], cands[:, 1])
        best = _pick(tile, cands[keep] if keep.any() else best[None], centre, pad_radius)
    return best


def _pick(tile: Polygon, cands: np.ndarray, centre: np.ndarray, r: float) -> np.ndarray:
    area = pad_area_on_tile(tile, cands, r)
    good = area >= area.max() * 0.995
    near = np.hypot(*(cands[good] - np.asarray(centre, dtype=float)).T)
    return np.asarray(cands[good][int(np.argmin(near))], dtype=float)


__all__ = ["best_hold", "pad_area_on_tile"]
