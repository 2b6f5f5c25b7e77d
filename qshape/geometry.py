"""Plane geometry of qshape: angles, rotations, polygon measures and simplicity tests.

One home per fact: 2D rotation (`rotate`, `rotation_matrix`), signed area and area centroid
(`signed_area`, `polygon_centroid`, `area_centroid_perimeter`). Angle wrapping and the yaw error
modulo a rotational symmetry live in `spatial.angles` (shared with planners and envs); qshape's
names for them here (`wrap_angle`, `wrap_angles`: qshape's (-pi, pi] convention; `yaw_error`,
`yaw_errors`) call it.

Points are arrays of shape (n, 2), in any length unit, in a right-handed frame unless stated.
Areas and centroids of a polygon far from the origin are computed relative to a reference point
near it, so it keeps the precision of its own size (a 40 mm square at 1e11 mm has area 1600).
Simplicity and crossing tests use GEOS through shapely (O(n log n)), never n x n arrays.
"""

from __future__ import annotations

import math

import numpy as np
import shapely
from numpy.typing import ArrayLike, NDArray

from spatial import angles

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

MAX_COORDINATE = 1e100
"""Hard bound on coordinate magnitude: products of coordinates must not overflow float64.

The documented, tighter cap is ``Limits.max_coordinate`` (``configs/qshape.yaml``)."""

TWO_PI = angles.TWO_PI


# ------------------------------------------------------------------------------ angles
def wrap_angle(angle: float) -> float:
    """Angle wrapped to (-pi, pi], in [rad] (`spatial.angles.wrap_angle` with ``include_pi``)."""
    return float(angles.wrap_angle(float(angle), include_pi=True))


def wrap_angles(values: ArrayLike) -> FloatArray:
    """`wrap_angle` element-wise: any shape, [rad] -> (-pi, pi] [rad]."""
    return angles.wrap_angles(values, include_pi=True)


def yaw_error(yaw: float, target: float, symmetry: int) -> float:
    """|yaw - target| modulo the rotational symmetry, in [rad], in [0, pi / symmetry].

    Args:
        yaw: Measured yaw [rad].
        target: Wanted yaw [rad].
        symmetry: Rotational symmetry order (1: none, 4: a square, 0: continuous, error 0).
    """
    return float(angles.yaw_error(yaw, target, symmetry))


def yaw_errors(yaw: ArrayLike, target: ArrayLike, symmetry: ArrayLike) -> FloatArray:
    """`yaw_error` element-wise (broadcasting), in [rad]."""
    err = angles.yaw_error(
        np.asarray(yaw, dtype=np.float64),
        np.asarray(target, dtype=np.float64),
        np.asarray(symmetry, dtype=np.int64),
    )
    return np.asarray(err, dtype=np.float64)


def rotation_matrix(angle: float) -> FloatArray:
    """2 x 2 matrix R turning column vectors counter-clockwise by ``angle`` [rad]: R @ p."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s], [s, c]])


def rotate(points: ArrayLike, angle: float) -> FloatArray:
    """Points (..., 2) turned counter-clockwise by ``angle`` [rad] about the origin."""
    return np.asarray(np.asarray(points, dtype=np.float64) @ rotation_matrix(angle).T)


# ---------------------------------------------------------------------- polygon measures
def cross2(a: FloatArray, b: FloatArray) -> FloatArray:
    """Z component of the cross product of 2D vectors (broadcasting over leading axes)."""
    return np.asarray(a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0])


_FAR_RATIO = 1e4
"""Offset / size ratio beyond which measures are taken relative to a reference point: up to
it, absolute coordinates lose at most ~1e-8 of an area (float64), and results stay bit-for-bit
those of the plain formulas."""


def reference_point(points: FloatArray) -> FloatArray:
    """Origin for precise measures of a polygon far from the origin. Shape (n, 2) -> (2,).

    Zero for a polygon within ``_FAR_RATIO`` sizes of the origin; otherwise its first point
    snapped to a power-of-two grid at least as coarse as its size (subtracting it is exact).
    """
    size = float(np.ptp(points, axis=0).max()) if len(points) else 0.0
    magnitude = float(np.abs(points).max()) if len(points) else 0.0
    if size <= 0.0 or magnitude <= _FAR_RATIO * size:
        return np.zeros(2)
    step = 2.0 ** math.ceil(math.log2(size))
    return np.asarray(np.round(points[0] / step) * step, dtype=np.float64)


def signed_area(points: FloatArray) -> float:
    """Shoelace area of a closed polygon, positive when counter-clockwise. Shape (n, 2).

    Far from the origin it is computed relative to `reference_point` (the precision of the
    polygon's size, not of its offset).
    """
    p = points - reference_point(points)
    x, y = p[:, 0], p[:, 1]
    return 0.5 * float(np.dot(x[:-1], y[1:]) + x[-1] * y[0] - np.dot(x[1:], y[:-1]) - x[0] * y[-1])


def polygon_centroid(points: FloatArray) -> FloatArray:
    """Centroid of the polygon area (not of the vertices). Shape (n, 2) -> (2,).

    A zero-area polygon returns the vertex mean instead. Relative to `reference_point`.
    """
    ref = reference_point(points)
    p = points - ref
    nxt = np.roll(p, -1, axis=0)
    w = cross2(p, nxt)
    a = w.sum()
    if a == 0.0:
        return np.asarray(points.mean(axis=0), dtype=np.float64)
    return np.asarray(ref + ((p + nxt) * w[:, None]).sum(axis=0) / (3.0 * a), dtype=np.float64)


def is_counter_clockwise(points: FloatArray) -> bool:
    """True when the polygon is walked counter-clockwise in its own (right-handed) frame."""
    return signed_area(points) > 0.0


# --------------------------------------------------------------------- simplicity tests
def _ring(points: FloatArray, ref: FloatArray) -> shapely.LinearRing:
    """Closed shapely ring of ``points - ref`` (relative coordinates keep precision)."""
    return shapely.LinearRing(points - ref)


def self_intersects(points: FloatArray) -> bool:
    """True when two edges of the closed polygon touch or cross away from their shared vertex.

    O(n log n) (GEOS). Shape (n, 2), n >= 3 distinct consecutive points.
    """
    if len(points) < 4:
        return False
    return not bool(_ring(points, points[0]).is_simple)


def boundaries_cross(a: FloatArray, b: FloatArray) -> bool:
    """True when any edge of closed polygon a touches or crosses any edge of closed polygon b."""
    return bool(_ring(a, a[0]).intersects(_ring(b, a[0])))


def points_in_polygon(query: FloatArray, polygon: FloatArray) -> BoolArray:
    """Even-odd test of points (m, 2) against a closed polygon (n, 2). -> (m,) bool.

    Points exactly on the boundary may fall either way. O((m + n) log n) (GEOS).
    """
    ref = polygon[0]
    poly = shapely.Polygon(polygon - ref)
    if not poly.is_valid:  # a self-crossing outline: fall back to the even-odd ray count
        return _points_in_polygon_even_odd(query, polygon)
    shapely.prepare(poly)
    rel = np.asarray(query, dtype=np.float64) - ref
    return np.asarray(shapely.contains_xy(poly, rel[:, 0], rel[:, 1]), dtype=bool)


def _points_in_polygon_even_odd(query: FloatArray, polygon: FloatArray) -> BoolArray:
    """Even-odd ray count (m x n work) for polygons GEOS calls invalid."""
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


def polygon_of(points: FloatArray, ref: FloatArray) -> shapely.Polygon:
    """Prepared shapely polygon of ``points - ref`` (for repeated containment queries)."""
    poly = shapely.Polygon(points - ref)
    shapely.prepare(poly)
    return poly


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
        Relative to `reference_point` (precision of the size, not of the offset).
    """
    ref = reference_point(points)
    points = points - ref
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
        return 0.0, np.asarray(ref + points.mean(axis=0), dtype=np.float64), perimeter
    return poly_area, np.asarray(ref + poly_moment / poly_area, dtype=np.float64), perimeter


__all__ = [
    "MAX_COORDINATE",
    "TWO_PI",
    "arc_segments",
    "area_centroid_perimeter",
    "boundaries_cross",
    "cross2",
    "is_counter_clockwise",
    "points_in_polygon",
    "polygon_centroid",
    "polygon_of",
    "reference_point",
    "rotate",
    "rotation_matrix",
    "self_intersects",
    "signed_area",
    "wrap_angle",
    "wrap_angles",
    "yaw_error",
    "yaw_errors",
]
