"""One closed boundary of a figure (outer or hole) by its relevant points, validated and measured.

A boundary is walked clockwise as seen; curve segments are marked at their maximum-curvature
point (`Boundary.curve_mask`) and drawn as circular arcs through it (`densify`).
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import shapely
from numpy.typing import ArrayLike

from qshape import geometry as geo
from qshape.errors import FigureLimitError, InvalidFigureError, InvalidHoleError
from qshape.geometry import MAX_COORDINATE, BoolArray, FloatArray
from qshape.limits import default_limits

_REL_EPS = 1e-12
"""Numerical precision: lengths below this fraction of the figure size count as zero."""


_ARC_SAMPLES = 16
"""Samples per arc when curved boundaries are densified for containment checks."""


def _as_points(points: ArrayLike, what: str, cap: str = "max_points") -> FloatArray:
    """Convert to a finite float64 (n, 2) array with n >= 3 distinct points, or raise.

    Real numbers only (no strings, booleans or complex numbers); at most ``Limits.<cap>`` rows.
    """
    try:
        raw = np.asarray(points)
        kind = raw.dtype.kind
        if kind == "O":  # mixed Python objects: real numbers only
            if not all(
                isinstance(v, numbers.Real) and not isinstance(v, bool | np.bool_)
                for v in raw.ravel()
            ):
                raise TypeError("points hold values that are not real numbers")
            raw = raw.astype(np.float64)
            kind = "f"
    except (TypeError, ValueError) as exc:
        raise InvalidFigureError(f"{what}: points must be numbers of shape (n, 2): {exc}") from exc
    if kind not in "iuf":
        named = {"c": "complex numbers", "b": "booleans", "U": "strings", "S": "bytes"}
        raise InvalidFigureError(
            f"{what}: points must be real numbers of shape (n, 2), got "
            f"{named.get(kind, raw.dtype.name)}"
        )
    if raw.ndim != 2 or raw.shape[1] != 2:
        raise InvalidFigureError(f"{what}: points must have shape (n, 2), got {raw.shape}")
    default_limits().check_count(len(raw), cap, f"{what}: points", FigureLimitError)
    arr = np.array(raw, dtype=np.float64)
    if not np.all(np.isfinite(arr)):
        bad = np.flatnonzero(~np.all(np.isfinite(arr), axis=1)).tolist()
        raise InvalidFigureError(f"{what}: points must be finite; NaN or inf at rows {bad[:10]}")
    if np.abs(arr).max(initial=0.0) > MAX_COORDINATE:
        raise FigureLimitError(
            f"{what}: coordinates must be at most {MAX_COORDINATE:g} in magnitude (so that areas "
            "stay finite)"
        )
    if len(arr) >= 2 and np.array_equal(arr[0], arr[-1]):
        arr = arr[:-1]  # an explicitly closed ring: the closing copy of the first point
    if len(arr) < 3:
        raise InvalidFigureError(
            f"{what}: a closed boundary needs at least 3 distinct points, got {len(arr)}"
        )
    return arr


def _strictly_convex(pts: FloatArray) -> bool:
    """True for a strictly convex polygon: every turn has the same sign, total turn 2 pi.

    Such a polygon is simple and its points are distinct, so the O(n^2) self-intersection
    and duplicate checks can be skipped (a cheap vectorised test that most tiles pass).
    """
    e = np.concatenate([pts[1:], pts[:1]]) - pts
    en = np.concatenate([e[1:], e[:1]])
    cr = e[:, 0] * en[:, 1] - e[:, 1] * en[:, 0]
    if not (bool((cr > 0.0).all()) or bool((cr < 0.0).all())):
        return False
    turn = float(np.arctan2(cr, e[:, 0] * en[:, 0] + e[:, 1] * en[:, 1]).sum())
    return abs(abs(turn) - 2.0 * math.pi) < 1e-6


def _validate_boundary(pts: FloatArray, mask: BoolArray, what: str) -> float:
    """Check range, distinct points, non-zero area, simple polygon, curve mask; signed area.

    O(n log n): duplicates by sorting, simplicity by a sweep (GEOS).
    """
    size = float(np.ptp(pts, axis=0).max())
    if size <= 0.0:
        raise InvalidFigureError(f"{what}: all points coincide; a figure needs a non-zero area")
    default_limits().check_range(float(np.abs(pts).max()), size, what)
    convex = _strictly_convex(pts)
    if not convex:
        order = np.lexsort((pts[:, 1], pts[:, 0]))
        same = np.all(pts[order][1:] == pts[order][:-1], axis=1)
        if same.any():
            k = int(np.flatnonzero(same)[0])
            i, j = sorted((int(order[k]), int(order[k + 1])))
            raise InvalidFigureError(
                f"{what}: repeated point {pts[i].tolist()} at indices {i} and {j}; "
                "every relevant point must be distinct"
            )
    rel = pts - pts[0]
    far = rel[int(np.argmax(np.abs(rel).sum(axis=1)))]
    if np.abs(geo.cross2(rel, far)).max() <= _REL_EPS * size * size:
        raise InvalidFigureError(f"{what}: zero area (all points collinear); a figure needs area")
    if not convex and geo.self_intersects(pts):
        raise InvalidFigureError(
            f"{what}: the boundary crosses or touches itself; only simple closed boundaries are "
            "allowed"
        )
    area = geo.signed_area(pts)
    if abs(area) <= _REL_EPS * size * size:
        raise InvalidFigureError(f"{what}: zero area; a figure needs area")
    if mask.shape != (len(pts),):
        raise InvalidFigureError(
            f"{what}: curve_mask must have shape ({len(pts)},), got {mask.shape}"
        )
    if mask[0] & mask[-1] or np.any(mask[1:] & mask[:-1]):
        raise InvalidFigureError(
            f"{what}: two adjacent curve points; each curve point needs its curve's start and "
            "end (non-curve points) as neighbours"
        )
    return area


def _as_mask(curve_mask: ArrayLike | None, n: int, what: str) -> BoolArray:
    if curve_mask is None:
        return np.zeros(n, dtype=bool)
    mask = np.asarray(curve_mask)
    if mask.dtype != np.bool_:
        raise InvalidFigureError(f"{what}: curve_mask must be booleans, got dtype {mask.dtype}")
    return mask.copy()


def read_only(arr: np.ndarray) -> Any:
    """``arr`` made read-only, returned."""
    arr.setflags(write=False)
    return arr


def densify(points: FloatArray, curve_mask: BoolArray, per_arc: int = _ARC_SAMPLES) -> FloatArray:
    """Polygon following the boundary, with each arc sampled at ``per_arc`` points.

    Each curve point j is replaced by ``per_arc`` points on the circle through its neighbours
    and itself, strictly between the neighbours (vectorised over all arcs).

    Args:
        points: Relevant points (n, 2), any orientation, in a right-handed frame; or a stack
            (..., n, 2) of boundaries sharing one curve mask.
        curve_mask: (n,) bool; each curve point is the middle of the arc through its neighbours.
        per_arc: Samples per arc.

    Returns:
        Shape (m, 2) polygon (or (..., m, 2) for a stack).
    """
    if not curve_mask.any():
        return points
    n = points.shape[-2]
    j = np.flatnonzero(curve_mask)
    vi, vj, vk = points[..., (j - 1) % n, :], points[..., j, :], points[..., (j + 1) % n, :]
    d = 2.0 * geo.cross2(vj - vi, vk - vi)
    flat = d == 0.0
    safe_d = np.where(flat, 1.0, d)
    bi, bj, bk = (vi * vi).sum(-1), (vj * vj).sum(-1), (vk * vk).sum(-1)
    ux = (
        bi * (vj[..., 1] - vk[..., 1])
        + bj * (vk[..., 1] - vi[..., 1])
        + bk * (vi[..., 1] - vj[..., 1])
    )
    uy = (
        bi * (vk[..., 0] - vj[..., 0])
        + bj * (vi[..., 0] - vk[..., 0])
        + bk * (vj[..., 0] - vi[..., 0])
    )
    centre = np.stack([ux, uy], axis=-1) / safe_d[..., None]
    rel = vi - centre
    radius = np.hypot(rel[..., 0], rel[..., 1])
    ai = np.arctan2(vi[..., 1] - centre[..., 1], vi[..., 0] - centre[..., 0])
    ak = np.arctan2(vk[..., 1] - centre[..., 1], vk[..., 0] - centre[..., 0])
    two_pi = 2.0 * math.pi
    sweep = np.where(d > 0.0, (ak - ai) % two_pi, -((ai - ak) % two_pi))
    t = np.arange(1, per_arc + 1) / (per_arc + 1)
    ang = ai[..., None] + t * sweep[..., None]
    arcs = centre[..., None, :] + radius[..., None, None] * np.stack([np.cos(ang), np.sin(ang)], -1)
    line = vi[..., None, :] + t[:, None] * (vk - vi)[..., None, :]
    arcs = np.where(flat[..., None, None], line, arcs)
    size = np.where(curve_mask, per_arc, 1)
    start = np.concatenate([[0], np.cumsum(size)[:-1]])
    out = np.empty((*points.shape[:-2], int(size.sum()), 2))
    keep = ~curve_mask
    out[..., start[keep], :] = points[..., keep, :]
    out[..., (start[j][:, None] + np.arange(per_arc)).ravel(), :] = arcs.reshape(
        *points.shape[:-2], -1, 2
    )
    return out


@dataclass(frozen=True, eq=False)
class Boundary:
    """One closed boundary (outer or hole) by its relevant points.

    Attributes:
        points: Relevant points, shape (n, 2), in the figure's coordinates, walked clockwise as
            seen (clockwise in the y-up frame). Read-only.
        curve_mask: Shape (n,) bool: True at the maximum-curvature point of a curve segment,
            whose neighbours are the curve's start and end. Read-only.
        y_down: True when the coordinates are image pixels with y pointing down.
    """

    points: FloatArray
    curve_mask: BoolArray
    y_down: bool = False

    @classmethod
    def make(
        cls,
        points: ArrayLike,
        curve_mask: ArrayLike | None = None,
        *,
        y_down: bool = False,
        what: str = "boundary",
    ) -> Boundary:
        """Validate and normalise a boundary given in either orientation, any start point.

        Raises:
            InvalidFigureError: Fewer than 3 points, NaN/inf, repeated points, zero area,
                self-intersection or a malformed curve mask.
        """
        pts = _as_points(points, what)
        mask = _as_mask(curve_mask, len(pts), what)
        if len(mask) == len(pts) + 1:
            mask = mask[:-1]  # the closing point was dropped
        area = _validate_boundary(pts, mask, what)
        # Clockwise as seen: signed area < 0 in the y-up frame, i.e. > 0 in y-down coordinates.
        if (area > 0.0) != y_down:
            pts = pts[::-1].copy()
            mask = mask[::-1].copy()
        return cls(read_only(pts), read_only(mask), y_down)

    @classmethod
    def from_simplified(
        cls, points: FloatArray, curve_mask: BoolArray, *, y_down: bool, what: str
    ) -> Boundary:
        """`make` for the output of `qshape.outline.simplify.simplify_outlines`.

        The points are already a finite float64 (n >= 3, 2) array and the mask a bool (n,)
        array, so only the geometric checks run (cheaply for convex boundaries).
        """
        if len(points) < 3 or np.array_equal(points[0], points[-1]):
            return cls.make(points, curve_mask, y_down=y_down, what=what)
        area = _validate_boundary(points, curve_mask, what)
        if (area > 0.0) != y_down:
            points = points[::-1].copy()
            curve_mask = curve_mask[::-1].copy()
        return cls(read_only(points), read_only(curve_mask), y_down)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Boundary):
            return NotImplemented
        return (
            self.y_down == other.y_down
            and np.array_equal(self.points, other.points)
            and np.array_equal(self.curve_mask, other.curve_mask)
        )

    __hash__ = None  # type: ignore[assignment]

    def points_yup(self) -> FloatArray:
        """Relevant points in the right-handed y-up frame, shape (n, 2)."""
        if self.y_down:
            return np.asarray(self.points * np.array([1.0, -1.0]))
        return self.points

    def measures(self) -> tuple[float, FloatArray, float]:
        """(area, centroid (2,) in the figure's coordinates, perimeter), arcs included."""
        up = self.points_yup()[::-1]
        area, c, perim = geo.area_centroid_perimeter(up, self.curve_mask[::-1])
        if self.y_down:
            c = c * np.array([1.0, -1.0])
        return area, c, perim

    def dense(self) -> FloatArray:
        """Polygon following the boundary (arcs sampled), figure coordinates, shape (m, 2)."""
        return densify(self.points, self.curve_mask)


_AREA_MARGIN = 1e-10
"""A boundary takes the one-pass check only when its area is above this fraction of its size
squared (100 x the zero-area precision), so a near-degenerate one gets the exact checks."""


def boundaries_many(
    simple: Sequence[tuple[FloatArray, BoolArray]], *, y_down: bool, whats: Sequence[str]
) -> list[Boundary | InvalidFigureError]:
    """`Boundary.from_simplified` of many boundaries, the common case checked in one pass.

    Strictly convex boundaries with an area and coordinates in range (nearly every tile) are
    validated and oriented with numpy over all their points at once; every other boundary
    (concave, degenerate, out of range, a malformed curve mask) goes through
    `Boundary.from_simplified`, which checks it exactly and names what is wrong.

    Args:
        simple: Per boundary, (points (n_i, 2) float64, curve_mask (n_i,) bool) as
            `qshape.outline.simplify.simplify_outlines` gives them.
        y_down: Coordinates are image pixels with y pointing down.
        whats: Names used in error messages, one per boundary.

    Returns:
        Per boundary, the `Boundary` or the `InvalidFigureError` it raised.
    """
    out: list[Boundary | InvalidFigureError | None] = [None] * len(simple)
    lens = np.array([len(s[0]) for s in simple], dtype=np.intp)
    same = np.array([len(s[1]) == len(s[0]) for s in simple], dtype=bool)
    fast = np.flatnonzero((lens >= 3) & same)  # noqa: PLR2004 (a closed boundary has 3 points)
    if len(fast):
        n = lens[fast]
        pts = np.concatenate([simple[int(i)][0] for i in fast])
        mask = np.concatenate([simple[int(i)][1] for i in fast])
        start = np.zeros(len(fast), dtype=np.intp)
        np.cumsum(n[:-1], out=start[1:])
        last = start + n - 1
        nxt = np.arange(1, len(pts) + 1)
        nxt[last] = start
        e = pts[nxt] - pts
        en = e[nxt]
        cr = e[:, 0] * en[:, 1] - e[:, 1] * en[:, 0]
        turn = np.add.reduceat(np.arctan2(cr, e[:, 0] * en[:, 0] + e[:, 1] * en[:, 1]), start)
        ccw = np.logical_and.reduceat(cr > 0.0, start)
        convex = (ccw | np.logical_and.reduceat(cr < 0.0, start)) & (
            np.abs(np.abs(turn) - 2.0 * math.pi) < 1e-6  # noqa: PLR2004 (as _strictly_convex)
        )
        lo = np.minimum.reduceat(pts, start)
        size = (np.maximum.reduceat(pts, start) - lo).max(axis=1)
        magnitude = np.maximum.reduceat(np.abs(pts).max(axis=1), start)
        limits = default_limits()
        rel = pts - pts[np.repeat(start, n)]
        area = 0.5 * np.add.reduceat(rel[:, 0] * rel[nxt, 1] - rel[:, 1] * rel[nxt, 0], start)
        ok = (
            convex
            & ~np.all(pts[start] == pts[last], axis=1)
            & (size > 0.0)
            & (magnitude <= limits.max_coordinate)
            & (np.spacing(magnitude) <= limits.coordinate_resolution * size)
            & (np.abs(area) > _AREA_MARGIN * size * size)
            & ~np.logical_or.reduceat(mask & mask[nxt], start)
        )
        fast_at, ccw_at = fast.tolist(), ccw.tolist()
        for k in np.flatnonzero(ok).tolist():
            i = fast_at[k]
            points, curve_mask = simple[i]
            # Clockwise as seen: counter-clockwise in y-down coordinates (see Boundary.make).
            if ccw_at[k] != y_down:
                points = points[::-1].copy()
                curve_mask = curve_mask[::-1].copy()
            out[i] = Boundary(read_only(points), read_only(curve_mask), y_down)
    for i, s in enumerate(simple):
        if out[i] is None:
            try:
                out[i] = Boundary.from_simplified(s[0], s[1], y_down=y_down, what=whats[i])
            except InvalidFigureError as exc:
                out[i] = exc
    return [b for b in out if b is not None]


def measures_many(bounds: Sequence[Boundary]) -> list[tuple[float, FloatArray, float]]:
    """`Boundary.measures` of many boundaries, polygons without arcs in one numpy pass.

    Boundaries with arcs, far from the origin (see `qshape.geometry.reference_point`) or
    without area are measured one by one.
    """
    out: list[tuple[float, FloatArray, float] | None] = [None] * len(bounds)
    fast = [k for k, b in enumerate(bounds) if not b.curve_mask.any()]
    if fast:
        # Counter-clockwise in the y-up frame, as Boundary.measures walks it.
        pts = np.concatenate([bounds[k].points[::-1] for k in fast])
        n = np.array([len(bounds[k].points) for k in fast], dtype=np.intp)
        flip = np.repeat(np.array([bounds[k].y_down for k in fast]), n)
        pts[flip, 1] *= -1.0  # as Boundary.points_yup
        start = np.zeros(len(fast), dtype=np.intp)
        np.cumsum(n[:-1], out=start[1:])
        nxt = np.arange(1, len(pts) + 1)
        nxt[start + n - 1] = start
        size = (np.maximum.reduceat(pts, start) - np.minimum.reduceat(pts, start)).max(axis=1)
        near = np.maximum.reduceat(np.abs(pts).max(axis=1), start) <= geo._FAR_RATIO * size
        after = pts[nxt]
        w = pts[:, 0] * after[:, 1] - pts[:, 1] * after[:, 0]
        area = 0.5 * np.add.reduceat(w, start)
        moment = np.add.reduceat((pts + after) * w[:, None], start, axis=0) / 6.0
        step = after - pts
        perimeter = np.add.reduceat(np.hypot(step[:, 0], step[:, 1]), start)
        ok = near & (size > 0.0) & (area != 0.0)
        centroid = moment / np.where(ok, area, 1.0)[:, None]
        down = np.array([bounds[k].y_down for k in fast])
        centroid[down, 1] *= -1.0
        areas, perimeters = area.tolist(), perimeter.tolist()
        for j in np.flatnonzero(ok).tolist():
            out[fast[j]] = (areas[j], centroid[j].copy(), perimeters[j])
    return [b.measures() if m is None else m for b, m in zip(bounds, out, strict=True)]


def check_holes(outer: Boundary, holes: tuple[Boundary, ...]) -> None:
    """Raise `InvalidHoleError` unless every hole is strictly inside the parent, holes disjoint.

    O(N log N) in the total number of (arc-sampled) boundary points (GEOS, an R-tree for the
    hole pairs).
    """
    parent_pts = outer.dense()
    ref = parent_pts[0]
    parent = geo.polygon_of(parent_pts, ref)
    polys = []
    for k, h in enumerate(holes):
        hd = h.dense()
        poly = shapely.Polygon(hd - ref)
        if not parent.contains_properly(poly):
            if parent.disjoint(poly) and not poly.contains(shapely.Point(parent_pts[0] - ref)):
                raise InvalidHoleError(
                    f"hole {k} lies outside its parent figure; holes must be strictly inside"
                )
            raise InvalidHoleError(
                f"hole {k} touches or crosses its parent's boundary; holes must be strictly inside"
            )
        polys.append(poly)
    if len(polys) > 1:
        tree = shapely.STRtree(polys)
        a, b = tree.query(polys, predicate="intersects")
        pairs = sorted((int(i), int(j)) for i, j in zip(a, b, strict=True) if i < j)
        if pairs:
            i, j = pairs[0]
            raise InvalidHoleError(f"holes {i} and {j} overlap; holes must be disjoint")


__all__ = ["Boundary", "boundaries_many", "check_holes", "densify", "read_only", "measures_many"]
