"""Vectorised polygon helpers (all vertices at once, no per-vertex Python loops).

Points are arrays of shape (n, 2), in any length unit, in a right-handed frame unless stated.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

MAX_COORDINATE = 1e100
"""Largest accepted coordinate magnitude: products of coordinates must not overflow."""


def cross2(a: FloatArray, b: FloatArray) -> FloatArray:
    """Z component of the cross product of 2D vectors (broadcasting over leading axes)."""
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def signed_area(points: FloatArray) -> float:
    """Shoelace area of a closed polygon, positive when counter-clockwise. Shape (n, 2)."""
    x, y = points[:, 0], points[:, 1]
    return 0.5 * float(np.dot(x[:-1], y[1:]) + x[-1] * y[0] - np.dot(x[1:], y[:-1]) - x[0] * y[-1])


def polygon_centroid(points: FloatArray) -> FloatArray:
    """Centroid of the polygon area (not of the vertices). Shape (n, 2) -> (2,).

    Raises:
        ZeroDivisionError: Never; a zero-area polygon returns the vertex mean instead.
    """
    nxt = np.roll(points, -1, axis=0)
    w = cross2(points, nxt)
    a = w.sum()
    if a == 0.0:
        return np.asarray(points.mean(axis=0), dtype=np.float64)
    return np.asarray(((points + nxt) * w[:, None]).sum(axis=0) / (3.0 * a), dtype=np.float64)


def is_counter_clockwise(points: FloatArray) -> bool:
    """True when the polygon is walked counter-clockwise in its own (right-handed) frame."""
    return signed_area(points) > 0.0


def _segment_pairs_cross(
    a0: FloatArray, a1: FloatArray, b0: FloatArray, b1: FloatArray
) -> BoolArray:
    """Which segments a (m, 2) properly or improperly intersect segments b (k, 2). -> (m, k)."""
    da = (a1 - a0)[:, None, :]
    db = (b1 - b0)[None, :, :]
    o1 = cross2(da, b0[None, :, :] - a0[:, None, :])
    o2 = cross2(da, b1[None, :, :] - a0[:, None, :])
    o3 = cross2(db, a0[:, None, :] - b0[None, :, :])
    o4 = cross2(db, a1[:, None, :] - b0[None, :, :])
    proper = (o1 * o2 < 0.0) & (o3 * o4 < 0.0)

    # Touching / collinear overlap: an endpoint lies on the other segment.
    def on_seg(p: FloatArray, q0: FloatArray, q1: FloatArray, o: FloatArray) -> BoolArray:
        lo = np.minimum(q0, q1)
        hi = np.maximum(q0, q1)
        inside = np.all((p >= lo) & (p <= hi), axis=-1)
        out: BoolArray = (o == 0.0) & inside
        return out

    touch = (
        on_seg(b0[None, :, :], a0[:, None, :], a1[:, None, :], o1)
        | on_seg(b1[None, :, :], a0[:, None, :], a1[:, None, :], o2)
        | on_seg(a0[:, None, :], b0[None, :, :], b1[None, :, :], o3)
        | on_seg(a1[:, None, :], b0[None, :, :], b1[None, :, :], o4)
    )
    return np.asarray(proper | touch)


def self_intersects(points: FloatArray) -> bool:
    """True when two non-adjacent edges of the closed polygon touch or cross. Shape (n, 2)."""
    n = len(points)
    if n < 4:
        return False
    nxt = np.roll(points, -1, axis=0)
    hit = _segment_pairs_cross(points, nxt, points, nxt)
    i, j = np.triu_indices(n, k=2)
    keep = ~((i == 0) & (j == n - 1))
    return bool(np.any(hit[i[keep], j[keep]]))


def boundaries_cross(a: FloatArray, b: FloatArray) -> bool:
    """True when any edge of closed polygon a touches or crosses any edge of closed polygon b."""
    hit = _segment_pairs_cross(a, np.roll(a, -1, axis=0), b, np.roll(b, -1, axis=0))
    return bool(np.any(hit))


def points_in_polygon(query: FloatArray, polygon: FloatArray) -> BoolArray:
    """Even-odd test of points (m, 2) against a closed polygon (n, 2). -> (m,) bool."""
    p0 = polygon[None, :, :]
    p1 = np.roll(polygon, -1, axis=0)[None, :, :]
    qx = query[:, None, 0]
    qy = query[:, None, 1]
    straddle = (p0[..., 1] > qy) != (p1[..., 1] > qy)
    dy = p1[..., 1] - p0[..., 1]
    safe_dy = np.where(dy == 0.0, 1.0, dy)
    x_at = p0[..., 0] + (qy - p0[..., 1]) * (p1[..., 0] - p0[..., 0]) / safe_dy
    crossings = straddle & (qx < x_at)
    return np.asarray(np.count_nonzero(crossings, axis=1) % 2 == 1)


def arc_segments(
    points: FloatArray, curve_mask: BoolArray
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Circular-arc corrections for the curve segments of a boundary.

    Each curve point j (``curve_mask[j]``) with neighbours i = j - 1 and k = j + 1 is taken as
    the circular arc through V_i, V_j, V_k. The polygon of relevant points already contains the
    triangle (V_i, V_j, V_k); this returns what the arc adds beyond it.

    Args:
        points: Relevant points, shape (n, 2), walked counter-clockwise.
        curve_mask: Shape (n,) bool.

    Returns:
        (extra_area, extra_centroid, arc_length, chord_length) for the m curve points: shapes
        (m,), (m, 2), (m,), (m,). extra_area is signed (negative for an arc bowing inwards).
    """
    j = np.flatnonzero(curve_mask)
    n = len(points)
    vi, vj, vk = points[(j - 1) % n], points[j], points[(j + 1) % n]
    chord = vk - vi
    c = np.hypot(chord[:, 0], chord[:, 1])
    a = 0.5 * c
    mid = 0.5 * (vi + vk)
    safe_c = np.where(c > 0.0, c, 1.0)
    # Outward normal of a counter-clockwise boundary is on the right of the chord.
    normal = np.stack([chord[:, 1], -chord[:, 0]], axis=1) / safe_c[:, None]
    h_signed = np.einsum("ij,ij->i", vj - mid, normal)
    h = np.abs(h_signed)
    side = np.where(h_signed >= 0.0, 1.0, -1.0)
    flat = h <= 0.0
    safe_h = np.where(flat, 1.0, h)
    radius = (a * a + safe_h * safe_h) / (2.0 * safe_h)
    theta = 2.0 * np.arctan2(a, radius - safe_h)
    seg_area = 0.5 * radius * radius * (theta - np.sin(theta))
    tri_area = a * safe_h
    denom = np.where(theta - np.sin(theta) > 0.0, theta - np.sin(theta), 1.0)
    seg_dist = 4.0 * radius * np.sin(theta / 2.0) ** 3 / (3.0 * denom)
    centre = mid + normal * (side * (safe_h - radius))[:, None]
    seg_centroid = centre + normal * (side * seg_dist)[:, None]
    tri_centroid = (vi + vj + vk) / 3.0
    extra = seg_area - tri_area
    safe_extra = np.where(np.abs(extra) > 0.0, extra, 1.0)
    extra_centroid = (
        seg_centroid * seg_area[:, None] - tri_centroid * tri_area[:, None]
    ) / safe_extra[:, None]
    extra = np.where(flat, 0.0, extra * side)
    extra_centroid = np.where(flat[:, None], tri_centroid, extra_centroid)
    arc_len = np.where(flat, c, radius * theta)
    return extra, extra_centroid, arc_len, c


def area_centroid_perimeter(
    points: FloatArray, curve_mask: BoolArray
) -> tuple[float, FloatArray, float]:
    """Area, area centroid and perimeter of a counter-clockwise boundary with arc segments.

    Args:
        points: Relevant points, shape (n, 2), counter-clockwise.
        curve_mask: Shape (n,) bool; see `arc_segments`.

    Returns:
        (area > 0, centroid (2,), perimeter), in the points' unit (squared for the area).
    """
    nxt = np.concatenate([points[1:], points[:1]])
    w = cross2(points, nxt)
    poly_area = 0.5 * float(w.sum())
    poly_moment = ((points + nxt) * w[:, None]).sum(axis=0) / 6.0
    edges = np.hypot(*(nxt - points).T)
    perimeter = float(edges.sum())
    if curve_mask.any():
        extra, extra_c, arc_len, _ = arc_segments(points, curve_mask)
        j = np.flatnonzero(curve_mask)
        n = len(points)
        # Replace the two polygon edges around each curve point by the arc.
        perimeter += float(arc_len.sum() - edges[j].sum() - edges[(j - 1) % n].sum())
        poly_moment = poly_moment + (extra_c * extra[:, None]).sum(axis=0)
        poly_area += float(extra.sum())
    if poly_area == 0.0:
        return 0.0, np.asarray(points.mean(axis=0), dtype=np.float64), perimeter
    return poly_area, np.asarray(poly_moment / poly_area, dtype=np.float64), perimeter


__all__ = [
    "MAX_COORDINATE",
    "area_centroid_perimeter",
    "arc_segments",
    "boundaries_cross",
    "cross2",
    "is_counter_clockwise",
    "points_in_polygon",
    "polygon_centroid",
    "self_intersects",
    "signed_area",
]
