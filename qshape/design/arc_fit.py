"""Curves that are not circular arcs (Beziers, ellipses, splines) as circular arcs (bulges).

A design's outline is straight edges and circular arcs (`qshape.design.paths.Loop`): the
qualitative description takes each arc's middle as its curve point. A drawn curve of another
kind is sampled densely and covered, from its start, by the longest arcs (or straight edges)
that keep every sample within a tolerance: `fit_arcs`. `three_point_bulge` gives the bulge of
the arc through a start, a point on the arc and an end.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from qshape.geometry import FloatArray


def three_point_bulge(p0: ArrayLike, pm: ArrayLike, p1: ArrayLike) -> float:
    """Bulge (tan of a quarter of the turn) of the arc from ``p0`` through ``pm`` to ``p1``.

    Positive for an arc turning counter-clockwise (y up; the DXF convention of
    `qshape.design.paths.Loop`), 0 for three collinear points.
    """
    a, m, b = (np.asarray(p, dtype=np.float64) for p in (p0, pm, p1))
    chord = b - a
    c = float(np.hypot(*chord))
    cross = float(chord[0] * (m - a)[1] - chord[1] * (m - a)[0])
    if c == 0.0 or cross == 0.0:
        return 0.0
    # Inscribed angle at m subtends the chord: the arc a->m->b turns 2 * (pi - angle(a m b)).
    u, v = a - m, b - m
    ang = float(np.arctan2(abs(u[0] * v[1] - u[1] * v[0]), float(u @ v)))
    turn = 2.0 * (np.pi - ang)
    # m right of a->b (cross < 0): the arc a->m->b turns counter-clockwise.
    return float(np.tan(turn / 4.0)) * (1.0 if cross < 0.0 else -1.0)


def _circle(p0: FloatArray, pm: FloatArray, p1: FloatArray) -> tuple[FloatArray, float] | None:
    """Centre and radius of the circle through three points (None: collinear)."""
    ax, ay = p0
    bx, by = pm
    cx, cy = p1
    d = 2.0 * (ax * (by - cy) + bx * (cy - ay) + cx * (ay - by))
    if d == 0.0:
        return None
    a2, b2, c2 = ax * ax + ay * ay, bx * bx + by * by, cx * cx + cy * cy
    ux = (a2 * (by - cy) + b2 * (cy - ay) + c2 * (ay - by)) / d
    uy = (a2 * (cx - bx) + b2 * (ax - cx) + c2 * (bx - ax)) / d
    centre = np.array([ux, uy])
    return centre, float(np.hypot(*(p0 - centre)))


def _fits(pts: FloatArray, tol: float) -> float | None:
    """The bulge of one arc (or 0 for a straight edge) through ``pts`` within ``tol``, or None."""
    p0, p1 = pts[0], pts[-1]
    chord = p1 - p0
    c = float(np.hypot(*chord))
    if c == 0.0:
        return None
    rel = pts - p0
    off = (chord[0] * rel[:, 1] - chord[1] * rel[:, 0]) / c
    if float(np.max(np.abs(off))) <= tol:
        return 0.0
    pm = pts[len(pts) // 2]
    circle = _circle(p0, pm, p1)
    if circle is None:
        return None
    centre, radius = circle
    dev = np.abs(np.hypot(*(pts - centre).T) - radius)
    if float(np.max(dev)) > tol:
        return None
    bulge = three_point_bulge(p0, pm, p1)
    return bulge if abs(bulge) <= 1.0 else None  # at most a half circle per arc


def fit_arcs(points: ArrayLike, tol: float) -> tuple[FloatArray, FloatArray]:
    """Circular arcs and straight edges within ``tol`` of a densely sampled open curve.

    Greedy from the start: each piece is the longest run of samples one arc (through its
    first, middle and last sample, at most a half circle) or one straight edge keeps within
    ``tol`` (a doubling then a bisection search, so O(m log m) for m samples).

    Args:
        points: The curve's samples in order, shape (m, 2), m >= 2; first and last are kept.
        tol: Largest distance of a sample from its piece [same unit as ``points``].

    Returns:
        (vertices (k, 2): each piece's start, bulges (k,): each piece's bulge); the curve's
        last point is the next piece's start (not included).
    """
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    verts: list[FloatArray] = []
    bulges: list[float] = []
    i, last = 0, len(pts) - 1
    while i < last:
        good, bulge = i + 1, 0.0  # two samples always make a straight edge
        step = 2
        bad = None
        while bad is None:  # doubling: find a run that fails (or the end)
            j = min(i + step, last)
            b = _fits(pts[i : j + 1], tol)
            if b is None:
                bad = j
            else:
                good, bulge = j, b
                if j == last:
                    break
                step *= 2
        if bad is not None:
            lo, hi = good, bad
            while hi - lo > 1:  # bisection between the last fit and the first failure
                mid = (lo + hi) // 2
                b = _fits(pts[i : mid + 1], tol)
                if b is None:
                    hi = mid
                else:
                    lo, bulge = mid, b
            good = lo
        verts.append(pts[i])
        bulges.append(bulge if good > i + 1 else 0.0)
        i = good
    return np.array(verts).reshape(-1, 2), np.array(bulges)


def _arc_circle(p0: FloatArray, p1: FloatArray, bulge: float) -> tuple[FloatArray, float]:
    """Centre and radius of the arc from p0 to p1 with a (DXF) bulge != 0."""
    d = p1 - p0
    c = float(np.hypot(*d))
    right = np.array([d[1], -d[0]]) / c
    sag = bulge * c / 2.0  # signed: positive bows to the right of p0 -> p1
    radius = c * (1.0 + bulge * bulge) / (4.0 * abs(bulge))
    centre = 0.5 * (p0 + p1) + right * (sag - np.sign(bulge) * radius)
    return centre, radius


def merge_arcs(vertices: ArrayLike, bulges: ArrayLike, tol: float) -> tuple[FloatArray, FloatArray]:
    """A closed outline with neighbouring arcs of one circle joined, up to half circles.

    A circle drawn as four quarter arcs (SVG, or four Beziers fitted by `fit_arcs`) becomes
    two half circles, as a design's ``circle`` is: the description's relevant points are
    those of the circle, not of how it was drawn.

    Args:
        vertices: Shape (n, 2), the outline's vertices in order.
        bulges: Shape (n,), DXF bulges (edge i from vertex i to vertex i + 1).
        tol: Largest difference of centres and radii of arcs on one circle.

    Returns:
        (vertices (k, 2), bulges (k,)), k <= n.
    """
    v = [np.asarray(p, dtype=np.float64) for p in np.asarray(vertices, dtype=np.float64)]
    b = [float(x) for x in np.asarray(bulges, dtype=np.float64)]
    changed = True
    while changed and len(v) > 2:
        changed = False
        n = len(v)
        for i in range(n):
            j, k = (i + 1) % n, (i + 2) % n
            if b[i] == 0.0 or b[j] == 0.0 or (b[i] > 0.0) != (b[j] > 0.0):
                continue
            turn = 4.0 * (math.atan(abs(b[i])) + math.atan(abs(b[j])))
            if turn > math.pi + 1e-9:
                continue
            ci, ri = _arc_circle(v[i], v[j], b[i])
            cj, rj = _arc_circle(v[j], v[k], b[j])
            if float(np.hypot(*(ci - cj))) > tol or abs(ri - rj) > tol:
                continue
            b[i] = math.copysign(math.tan(turn / 4.0), b[i])
            del v[j], b[j]
            changed = True
            break
    return np.array(v).reshape(-1, 2), np.array(b)


__all__ = ["fit_arcs", "merge_arcs", "three_point_bulge"]
