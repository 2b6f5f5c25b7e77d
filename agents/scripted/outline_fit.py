"""The last resort for a tile no description matches: its traced outline fitted to the slots'.

The scripted agent decides by the qualitative description and its cyclic match (the design's
description of each slot, then the seen one, then a finer simplification of the tile's
outline). A tile that matches none of them has a picture whose relevant points differ from
every slot's: a corner the picture's noise adds or drops near the corner angle, a corner
traced as a corner and a short curve, a label at a band edge. For such a tile only, this module
measures instead of describing: the tile's traced outline (every pixel of its boundary, cast
onto the tile tops, and its holes) is turned about its area centroid onto each open slot's
outline of its colour, at every turn, and the mean distance left decides. It is a quantitative
step where the qualitative description leaves the tile open, and it is kept tight enough that
it would rather leave a tile than set it down wrong:

- the fit must leave a mean distance (both ways: tile onto slot and slot onto tile) of at most
  ``fit_max_residual`` x sqrt(slot area);
- every turn of the slot that is not one of its symmetries (farther than ``fit_turn_window_deg``
  from each) must fit at least ``fit_margin`` times worse, so a nearly symmetric tile whose turn
  the outline cannot tell is left, not guessed;
- every slot of another class that fits too must fit at least ``fit_margin`` times worse.

The tiles so fitted are assigned to their slots by least residual (`scipy`'s linear sum
assignment); the rotation is the fit's, the tile's centre the traced outline's area centroid.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import shapely
from scipy.optimize import linear_sum_assignment, minimize_scalar
from scipy.spatial import cKDTree

from agents.scripted.config import PlacementConfig
from agents.scripted.perception import PerceivedTile, SlotTarget
from spatial.angles import rotate_xy, symmetry_period, wrap_angle

_COST_REFUSED = 1e9
"""Assignment cost of a (tile, slot) pair the fit refuses (never chosen as a pair)."""


@dataclass(frozen=True, eq=False)
class TileOutline:
    """A tile's traced boundaries on the plane of the tile tops.

    Attributes:
        outer: The traced outer boundary, world x, y [mm] (y up), shape (m, 2).
        holes: Its holes, world [mm], each shape (k, 2).
        color: Measured (balanced) RGB in [0, 1].
    """

    outer: np.ndarray
    holes: tuple[np.ndarray, ...]
    color: tuple[float, float, float]

    @classmethod
    def of(cls, tile: PerceivedTile) -> TileOutline | None:
        """The perceived tile's traced outline with its figure's holes (None: not traced)."""
        if tile.outline_mm is None:
            return None
        return cls(tile.outline_mm, tuple(h.dense() for h in tile.figure.holes), tile.color)


@dataclass(frozen=True)
class OutlineFit:
    """The best fit of one tile outline onto one slot outline.

    Attributes:
        rotation: Turn of the tile about its area centroid onto the slot, CCW [rad].
        centre: The tile's area centroid (traced outer boundary less its holes), world [mm].
        residual: Mean distance left, the worse of tile onto slot and slot onto tile, over
            sqrt(slot area) (dimensionless).
        runner_up: The least residual (tile onto slot) at a turn that is not a symmetry of
            the slot, over the best turn's (dimensionless; inf for a continuous slot).
    """

    rotation: float
    centre: np.ndarray
    residual: float
    runner_up: float


def boundary_points(boundaries: Sequence[np.ndarray], spacing: float) -> np.ndarray:
    """Points along closed boundaries (each (m, 2)) at most ``spacing`` apart, shape (k, 2)."""
    out = [
        shapely.get_coordinates(shapely.segmentize(shapely.linearrings(np.asarray(b)), spacing))
        for b in boundaries
    ]
    return np.vstack(out)


def area_centroid(outer: np.ndarray, holes: Sequence[np.ndarray]) -> np.ndarray:
    """Area centroid of the region inside ``outer`` (k, 2) and outside ``holes``, shape (2,).

    A self-touching traced boundary is first made valid (`shapely.make_valid`).
    """
    poly = shapely.Polygon(outer, [np.asarray(h) for h in holes])
    if not poly.is_valid:
        poly = shapely.make_valid(poly)
    return np.array([poly.centroid.x, poly.centroid.y])


def fit_outline(
    tile: TileOutline, slot: SlotTarget, cfg: PlacementConfig, spacing: float
) -> OutlineFit:
    """The turn of ``tile`` that lays its boundaries best onto ``slot``'s, and how well.

    Args:
        tile: The tile's traced boundaries (world mm).
        slot: The slot (its figure in mesh mm; the mesh's axes are the world's).
        cfg: ``fit_step_deg`` (the turns tried), ``fit_turn_window_deg`` (turns this close
            to a symmetry of the slot count as that symmetry).
        spacing: Largest distance between the points compared [mm].
    """
    centre = area_centroid(tile.outer, tile.holes)
    tpts = boundary_points([tile.outer, *tile.holes], spacing) - centre
    sfig = slot.figure
    spts = boundary_points([sfig.outer.dense(), *(h.dense() for h in sfig.holes)], spacing / 2.0)
    spts = spts - np.asarray(sfig.centroid)
    tree = cKDTree(spts)
    scale = math.sqrt(sfig.area)

    def cost(r: float) -> float:
        return float(np.mean(tree.query(rotate_xy(tpts, r))[0]))

    step = math.radians(cfg.fit_step_deg)
    turns = np.arange(0.0, 2.0 * math.pi, step)
    coarse = np.array([cost(float(r)) for r in turns])
    k = int(np.argmin(coarse))
    res = minimize_scalar(
        cost, bounds=(turns[k] - step, turns[k] + step), method="bounded", options={"xatol": 1e-4}
    )
    rot = float(res.x) if float(res.fun) <= coarse[k] else float(turns[k])
    back = float(np.mean(cKDTree(rotate_xy(tpts, rot)).query(spts)[0]))
    residual = max(cost(rot), back) / scale
    runner_up = math.inf
    if slot.symmetry != 0:
        period = symmetry_period(slot.symmetry)
        d = np.mod(turns - rot, period)
        off = np.minimum(d, period - d)
        other = off > math.radians(cfg.fit_turn_window_deg)
        if np.any(other):
            runner_up = float(np.min(coarse[other])) / max(cost(rot), 1e-12)
    return OutlineFit(float(wrap_angle(rot)), centre, residual, runner_up)


def fit_unmatched(
    tiles: Sequence[TileOutline],
    slots: Sequence[SlotTarget],
    cfg: PlacementConfig,
    color_distance: float,
    spacing: float,
) -> list[tuple[int, int, OutlineFit]]:
    """Assign tiles no description matched to open slots by fitting their outlines.

    Args:
        tiles: The tiles' traced boundaries.
        slots: The open slots left (no tile assigned to them).
        cfg: The ``fit_*`` thresholds (`agents.scripted.config.PlacementConfig`) and ``use_color``.
        color_distance: Largest RGB distance of a tile's colour from a slot's (qshape's
            ``Tolerances.color_distance``) when colour is matched.
        spacing: Largest distance between the points compared [mm].

    Returns:
        (tile position, slot position, fit) of each tile assigned, tiles in order.
    """
    if not tiles or not slots:
        return []
    cost = np.full((len(tiles), len(slots)), _COST_REFUSED)
    fits: dict[tuple[int, int], OutlineFit] = {}
    for i, t in enumerate(tiles):
        found: dict[int, OutlineFit] = {}
        for j, s in enumerate(slots):
            far = np.linalg.norm(np.subtract(t.color, s.color)) > color_distance
            if cfg.use_color and far:
                continue
            f = fit_outline(t, s, cfg, spacing)
            if f.residual <= cfg.fit_max_residual and f.runner_up >= cfg.fit_margin:
                found[j] = f
        if not found:
            continue
        best = min(found, key=lambda j: found[j].residual)
        rivals = [
            j
            for j, f in found.items()
            if slots[j].class_name != slots[best].class_name
            and f.residual < cfg.fit_margin * found[best].residual
        ]
        if rivals:
            continue
        for j, f in found.items():
            if slots[j].class_name == slots[best].class_name:
                cost[i, j] = f.residual
                fits[i, j] = f
    rows, cols = linear_sum_assignment(cost)
    return sorted(
        (int(i), int(j), fits[int(i), int(j)])
        for i, j in zip(rows, cols, strict=True)
        if cost[i, j] < _COST_REFUSED
    )


__all__ = [
    "OutlineFit",
    "TileOutline",
    "area_centroid",
    "boundary_points",
    "fit_outline",
    "fit_unmatched",
]
