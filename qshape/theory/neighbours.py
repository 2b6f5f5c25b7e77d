"""Structural neighbours of a measured description: the same figure with one weak corner changed.

A measured outline is uncertain in its structure as well as in its labels. A corner that turns
little is found where the outline's direction changes by the simplification's corner angle, so
blur and rough edges can cut one corner into two (a chamfer), add a shallow corner, or place a
shallow rounded corner several pixels along its edge (its position along the edge is measured
far less well than a sharp corner's: the direction changes slowly there). `neighbours` lists the
descriptions one such change away, for `qshape.match_best` to try when the figure as measured
matches no reference:

- a weak corner (turning at most ``Tolerances.weak_turn_deg`` either way, both its edges
  straight) removed;
- two adjacent weak corners turning the same way, at most ``Tolerances.weak_pair_fraction`` of
  the perimeter apart, merged into one at the intersection of their outer edges (the corner a
  chamfer cut);
- a weak corner slid along the mean direction of its two edges by multiples of twice
  ``Tolerances.point_tolerance`` (each slid copy covers the point tolerance either side of it),
  up to ``Tolerances.weak_slide_fraction`` of the perimeter each way.

Holes, colour and curves are kept; the labels of each neighbour are measured afresh (`describe`),
so they stay qualitative. Only the outer boundary's straight-edged corners change.
"""

from __future__ import annotations

import math

import numpy as np

from qshape.errors import InvalidFigureError
from qshape.geometry import BoolArray, FloatArray, cross2
from qshape.theory.boundary import Boundary
from qshape.theory.description import Description, describe
from qshape.theory.figure import Figure
from qshape.theory.tolerances import Tolerances


def _turns(pts: FloatArray) -> FloatArray:
    """Signed direction change [deg] at each point of a closed polygon, shape (n,)."""
    u = pts - np.roll(pts, 1, axis=0)
    v = np.roll(pts, -1, axis=0) - pts
    dot = np.einsum("ij,ij->i", u, v)
    return np.asarray(np.degrees(np.arctan2(cross2(u, v), dot)))


def _straight_corners(mask: BoolArray) -> BoolArray:
    """(n,) True at vertices whose two edges are straight (no curve point beside them)."""
    return np.asarray(~mask & ~np.roll(mask, 1) & ~np.roll(mask, -1))


def _intersection(a: FloatArray, b: FloatArray, c: FloatArray, d: FloatArray) -> FloatArray | None:
    """Where the line a->b, continued past b, meets the line d->c continued past c; else None."""
    u = b - a
    w = c - d
    den = u[0] * w[1] - u[1] * w[0]
    if abs(den) <= 1e-12 * float(np.hypot(*u) * np.hypot(*w)):
        return None
    r = d - a
    s = (r[0] * w[1] - r[1] * w[0]) / den
    t = (r[0] * u[1] - r[1] * u[0]) / den
    if s <= 1.0 or t <= 1.0:  # the lines meet behind the cut's ends
        return None
    return np.asarray(a + s * u)


def _variants(
    pts: FloatArray, mask: BoolArray, perimeter: float, tol: Tolerances
) -> list[tuple[FloatArray, BoolArray]]:
    """Outer (points, curve mask) pairs one weak-corner change away."""
    n = len(pts)
    turn = _turns(pts)
    weak = (np.abs(turn) <= tol.weak_turn_deg) & _straight_corners(mask)
    out: list[tuple[FloatArray, BoolArray]] = []
    if n > 3:
        for i in np.flatnonzero(weak).tolist():
            out.append((np.delete(pts, i, axis=0), np.delete(mask, i)))
    for i in np.flatnonzero(weak).tolist():
        j = (i + 1) % n
        if n <= 3 or not weak[j] or np.sign(turn[i]) != np.sign(turn[j]):
            continue
        if float(np.hypot(*(pts[j] - pts[i]))) > tol.weak_pair_fraction * perimeter:
            continue
        corner = _intersection(pts[i - 1], pts[i], pts[j], pts[(j + 1) % n])
        if corner is None:
            continue
        merged = pts.copy()
        merged[i] = corner
        out.append((np.delete(merged, j, axis=0), np.delete(mask, j)))
    step = 2.0 * tol.point_tolerance
    reach = tol.weak_slide_fraction * perimeter
    if step > 0.0 and reach >= step:
        slides = np.arange(1, math.floor(reach / step) + 1) * step
        for i in np.flatnonzero(weak).tolist():
            before = pts[i] - pts[i - 1]
            after = pts[(i + 1) % n] - pts[i]
            tangent = before / np.hypot(*before) + after / np.hypot(*after)
            tangent /= np.hypot(*tangent)
            for t in np.concatenate([slides, -slides]).tolist():
                moved = pts.copy()
                moved[i] = pts[i] + t * tangent
                out.append((moved, mask))
    return out


def neighbours(desc: Description, tol: Tolerances) -> list[Description]:
    """The structural neighbours of ``desc`` (see the module), each described with ``tol``.

    Variants whose outline would be invalid (self-intersecting, a hole crossing it) are left
    out. Curved outer boundaries keep their curves; only straight-edged corners change.
    """
    out: list[Description] = []
    holes = tuple(Boundary.make(h.boundary.points, h.boundary.curve_mask) for h in desc.holes)
    for points, mask in _variants(desc.outer.points, desc.outer.curve_mask, desc.perimeter, tol):
        try:
            fig = Figure(points, mask, holes, desc.color)
        except InvalidFigureError:
            continue
        out.append(describe(fig, tol))
    return out


__all__ = ["neighbours"]
