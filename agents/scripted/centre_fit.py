"""A thin tile's centroid from its whole traced outline, the matched slot's shape fitted to it.

The centroid of a tile's relevant points is biased on a thin tile with a sharp tip: the
picture blunts the tip (a blurred, pixel-sampled wedge reaches half contrast short of its
apex), the tip vertex moves back along the tile by several tenths of a millimetre per degree of
sharpness lost, and the polygon's centroid with it. Once the tile is matched, its shape is
known: the slot's outline, turned as the tile lies, is slid onto the traced outline (every
edge point, point-to-edge least squares, the points farthest off trimmed), and its centroid
is the tile's. The tip's few blunted points hardly move that fit.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial import cKDTree

from agents.scripted.config import PlacementConfig
from qshape import Figure
from qshape.geometry import rotate
from spatial.units import MM_PER_M


def sharpest_corner_deg(figure: Figure) -> float:
    """The smallest interior angle of a figure's convex corners (straight edges), in [deg]."""
    pts = np.asarray(figure.outer.points, dtype=float)
    mask = np.asarray(figure.outer.curve_mask, dtype=bool)
    if len(pts) < 3:  # noqa: PLR2004
        return 180.0
    prev, nxt = np.roll(pts, 1, axis=0) - pts, np.roll(pts, -1, axis=0) - pts
    cos = np.sum(prev * nxt, axis=1) / (
        np.linalg.norm(prev, axis=1) * np.linalg.norm(nxt, axis=1) + 1e-12
    )
    ang = np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))
    plain = ~(mask | np.roll(mask, 1) | np.roll(mask, -1))  # corners between straight edges
    return float(ang[plain].min()) if plain.any() else 180.0


def fitted_centre(
    traced_mm: np.ndarray,
    slot: Figure,
    turn: float,
    start_mm: np.ndarray,
    *,
    step_mm: float,
    iterations: int,
    trim: float,
) -> np.ndarray:
    """The tile's area centroid [mm], shape (2,): the slot's outline slid onto the traced one.

    Args:
        traced_mm: The tile's traced outline on the plane of the tile tops, (k, 2) [mm].
        slot: The matched slot's figure [mm] (its area centroid is the reference).
        turn: The turn that takes the tile onto the slot [rad] (the tile lies turned by
            ``-turn`` from the slot).
        start_mm: Start of the search (the relevant points' centroid), (2,) [mm].
        step_mm: Sampling of the slot's outline [mm].
        iterations: Translation updates.
        trim: Traced points farther from the slot's outline than ``trim`` x the median
            distance are left out of each update.
    """
    dense = np.asarray(slot.outer.dense(), dtype=float)
    seg = np.roll(dense, -1, axis=0) - dense
    length = np.hypot(*seg.T)
    per = np.maximum(1, np.ceil(length / step_mm)).astype(int)
    t = np.concatenate([np.arange(n) / n for n in per])
    base = np.repeat(np.arange(len(dense)), per)
    model = dense[base] + seg[base] * t[:, None]
    normal = np.stack([seg[base, 1], -seg[base, 0]], axis=1) / length[base, None]
    model = rotate(model - np.asarray(slot.centroid, dtype=float), -turn)
    normal = rotate(normal, -turn)
    tree = cKDTree(model)
    centre = np.asarray(start_mm, dtype=float).copy()
    pts = np.asarray(traced_mm, dtype=float)
    for _ in range(iterations):
        dist, idx = tree.query(pts - centre)
        keep = dist <= trim * max(float(np.median(dist)), 1e-6)
        n = normal[idx[keep]]
        r = np.sum(n * (pts[keep] - centre - model[idx[keep]]), axis=1)
        a = n.T @ n
        if abs(np.linalg.det(a)) < 1e-9:
            break
        delta = np.linalg.solve(a, n.T @ r)
        centre += delta
        if math.hypot(*delta) < 1e-4:
            break
    return centre


def tile_centre(
    centre_m: np.ndarray, traced_mm: np.ndarray, slot: Figure, turn: float, cfg: PlacementConfig
) -> np.ndarray:
    """A tile's area centroid [m], shape (2,): fitted when its slot has a sharp corner.

    `fitted_centre` when the slot has a corner sharper than ``cfg.centre_fit_below_deg``;
    else ``centre_m`` (the relevant points' centroid).
    """
    if sharpest_corner_deg(slot) >= cfg.centre_fit_below_deg:
        return centre_m
    mm = fitted_centre(
        traced_mm,
        slot,
        turn,
        np.asarray(centre_m, dtype=float) * MM_PER_M,
        step_mm=cfg.centre_fit_step_mm,
        iterations=cfg.centre_fit_iterations,
        trim=cfg.centre_fit_trim,
    )
    return np.asarray(mm / MM_PER_M, dtype=float)


__all__ = ["fitted_centre", "sharpest_corner_deg", "tile_centre"]
