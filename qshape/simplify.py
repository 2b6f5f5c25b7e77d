"""Slope-comparison simplification of a dense closed outline to relevant points.

The outline (e.g. a traced image contour) is resampled uniformly by arc length and lightly
smoothed; a point is a corner where the direction of the outline changes by more than
`OutlineParams.corner_angle_deg` over a short window (slope comparison), keeping one corner per
window. Between consecutive corners the outline is a straight edge when it stays close to its
chord, otherwise a curve segment, whose maximum-curvature point is the one farthest from the
chord; curves turning more than `OutlineParams.max_curve_turn_deg` are split into equal pieces.
Every length parameter is a fraction of the outline's own size, so the same parameters serve
millimetres and pixels. Cost is linear in the number of outline points.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from qshape.errors import InvalidFigureError, ToleranceError
from qshape.geometry import MAX_COORDINATE, BoolArray, FloatArray, cross2
from qshape.tolerances import _load_section


@dataclass(frozen=True)
class OutlineParams:
    """Parameters of `simplify_outline`. Lengths are fractions of the outline's size.

    Attributes:
        resample_points: Number of uniform arc-length samples the outline is resampled to.
        smooth_fraction: Half-width of the circular moving average, fraction of perimeter.
        corner_window: Arc length on each side of a point over which its direction change is
            measured, fraction of perimeter. Also the spacing kept between two corners.
        corner_angle_deg: Direction change that makes a corner, in [deg]. A circle measured over
            the default window turns by about 14 degrees; a square corner by 90.
        straight_sagitta_ratio: A run between corners is straight when its largest distance from
            its chord is below this fraction of the chord (or below the noise floor).
        noise_fraction: Distance from a chord always treated as noise, fraction of the outline's
            diameter (largest extent).
        max_curve_turn_deg: A curve turning more than this is split into equal-turn pieces, in
            [deg]. A full circle (360) becomes two semicircles; 240 keeps a noisy semicircle
            (whose measured turning can exceed 180) whole.
        merge_fraction: Corners closer than this fraction of the perimeter are merged.
        refine_corners: Move each corner between two straight edges to the intersection of
            lines fitted to those edges (sub-sample accuracy on clean polygons; at very acute
            corners small line errors can push the corner outwards).
    """

    resample_points: int = 256
    smooth_fraction: float = 0.006
    corner_window: float = 0.02
    corner_angle_deg: float = 25.0
    straight_sagitta_ratio: float = 0.03
    noise_fraction: float = 0.006
    max_curve_turn_deg: float = 240.0
    merge_fraction: float = 0.02
    refine_corners: bool = False

    def __post_init__(self) -> None:
        """Validate ranges.

        Raises:
            ToleranceError: Naming the field and the allowed range.
        """
        if self.resample_points < 16:
            raise ToleranceError(f"resample_points must be >= 16, got {self.resample_points}")
        for name in (
            "smooth_fraction",
            "corner_window",
            "straight_sagitta_ratio",
            "noise_fraction",
            "merge_fraction",
        ):
            v = getattr(self, name)
            if not (math.isfinite(v) and 0.0 <= v < 0.5):
                raise ToleranceError(f"{name} must be in [0, 0.5), got {v!r}")
        if self.corner_window <= 0.0:
            raise ToleranceError("corner_window must be > 0")
        if not 0.0 < self.corner_angle_deg < 180.0:
            raise ToleranceError(
                f"corner_angle_deg must be in (0, 180), got {self.corner_angle_deg}"
            )
        if not 90.0 <= self.max_curve_turn_deg <= 360.0:
            raise ToleranceError(
                f"max_curve_turn_deg must be in [90, 360], got {self.max_curve_turn_deg}"
            )

    @classmethod
    def load(cls, name_or_path: str | Path | None = None, **overrides: Any) -> OutlineParams:
        """Load from YAML (section ``outline`` of ``configs/qshape.yaml`` by default).

        Raises:
            configs.ConfigError: Unknown key, wrong type or missing file.
            ToleranceError: Values out of range.
        """
        return _load_section(cls, "outline", name_or_path, overrides)


_DEFAULT: OutlineParams | None = None


def default_outline_params() -> OutlineParams:
    """Bundled outline parameters, loaded once."""
    global _DEFAULT  # noqa: PLW0603
    if _DEFAULT is None:
        _DEFAULT = OutlineParams.load()
    return _DEFAULT


def _clean(dense: ArrayLike, what: str) -> FloatArray:
    try:
        pts = np.array(dense, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidFigureError(f"{what}: points must be numbers of shape (k, 2): {exc}") from exc
    if pts.ndim != 2 or pts.shape[1] != 2:
        raise InvalidFigureError(f"{what}: points must have shape (k, 2), got {pts.shape}")
    if len(pts) == 0:
        raise InvalidFigureError(f"{what}: a closed outline needs at least 3 points, got 0")
    lo, hi = float(pts.min()), float(pts.max())
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise InvalidFigureError(f"{what}: points must be finite (no NaN or inf)")
    if max(-lo, hi) > MAX_COORDINATE:
        raise InvalidFigureError(
            f"{what}: coordinates must be at most {MAX_COORDINATE:g} in magnitude"
        )
    d = np.concatenate([pts[1:], pts[:1]]) - pts
    step = np.hypot(d[:, 0], d[:, 1])
    if not step.all():
        pts = pts[step > 0.0]  # drop consecutive repeats (and the closing copy)
    if len(pts) < 3:
        raise InvalidFigureError(
            f"{what}: a closed outline needs at least 3 distinct points, got {len(pts)}"
        )
    return pts


def _resampled(pts: FloatArray, n: int) -> tuple[FloatArray, float]:
    """``n`` uniform arc-length samples of a closed polygon (k, 2) and its perimeter."""
    closed = np.concatenate([pts, pts[:1]])
    d = closed[1:] - closed[:-1]
    cum = np.empty(len(closed))
    cum[0] = 0.0
    np.cumsum(np.hypot(d[:, 0], d[:, 1]), out=cum[1:])
    perimeter = float(cum[-1])
    s = np.arange(n) * (perimeter / n)
    res = np.empty((n, 2))
    res[:, 0] = np.interp(s, cum, closed[:, 0])
    res[:, 1] = np.interp(s, cum, closed[:, 1])
    return res, perimeter


def simplify_outline(
    dense: ArrayLike, params: OutlineParams | None = None, *, what: str = "outline"
) -> tuple[FloatArray, BoolArray]:
    """Relevant points and curve mask of a dense closed outline.

    Args:
        dense: Closed outline, shape (k, 2), k >= 3, any orientation and unit.
        params: Simplification parameters; None: the bundled defaults.
        what: Name used in error messages.

    Returns:
        (points (n, 2), curve_mask (n,)) in the outline's orientation and coordinates.

    Raises:
        InvalidFigureError: Fewer than 3 distinct points, NaN/inf, or zero length/area.
    """
    p = default_outline_params() if params is None else params
    pts = _clean(dense, what)
    n = p.resample_points
    res, perimeter = _resampled(pts, n)
    nxt = np.concatenate([res[1:], res[:1]])
    diameter = float(max(np.ptp(res[:, 0]), np.ptp(res[:, 1])))
    area2 = float(np.dot(res[:, 0], nxt[:, 1]) - np.dot(res[:, 1], nxt[:, 0]))
    if diameter <= 0.0 or abs(area2) <= 1e-12 * diameter * diameter:
        raise InvalidFigureError(f"{what}: zero area (the outline is a line or a point)")
    sign = 1.0 if area2 > 0.0 else -1.0  # +1: counter-clockwise in the given frame

    # Circular moving average (same sums as a 'valid' convolution of the wrapped samples).
    half = max(1, round(p.smooth_fraction * n))
    width = 2 * half + 1
    padded = np.concatenate([res[-half:], res, res[:half]])
    smooth = np.empty_like(res)
    for k in range(2):
        smooth[:, k] = np.convolve(padded[:, k], np.full(width, 1.0 / width), mode="valid")

    w = max(1, round(p.corner_window * n))
    ext = np.concatenate([smooth[-w:], smooth, smooth[:w]])  # ext[i + w] = smooth[i]
    back = smooth - ext[:n]
    fwd = ext[2 * w :] - smooth
    bx, by, fx, fy = back[:, 0], back[:, 1], fwd[:, 0], fwd[:, 1]
    change = np.degrees(np.arctan2(np.abs(bx * fy - by * fx), bx * fx + by * fy))
    corners = _corners(change, p.corner_angle_deg, w, max(w, round(p.merge_fraction * n)))
    noise = p.noise_fraction * diameter
    if len(corners) == 0:
        turn = _turning(smooth, ext[w - 1 : w + n + 1], sign)
        out_pts: list[FloatArray] = []
        out_curve: list[bool] = []
        _emit_run(
            res,
            turn,
            np.arange(n),
            p=p,
            noise=noise,
            out_pts=out_pts,
            out_curve=out_curve,
            closed_loop=True,
            guard=half,
        )
        points = np.array(out_pts, dtype=np.float64)
        mask = np.array(out_curve, dtype=bool)
    else:
        points, mask = _polyline(
            res, smooth, ext[w - 1 : w + n + 1], sign, corners, p, noise, half, w, perimeter
        )
    if len(points) < 3:
        raise InvalidFigureError(
            f"{what}: simplified to {len(points)} relevant points; a figure needs at least 3"
        )
    return points, mask


def _turning(smooth: FloatArray, ring: FloatArray, sign: float) -> FloatArray:
    """Local signed turning [deg] at each smoothed sample; ``ring[i + 1] = smooth[i]``."""
    d1 = smooth - ring[:-2]
    d2 = ring[2:] - smooth
    crs = d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]
    dot = d1[:, 0] * d2[:, 0] + d1[:, 1] * d2[:, 1]
    return np.asarray(np.degrees(np.arctan2(crs, dot)) * sign)


def _polyline(  # noqa: PLR0913, PLR0917
    res: FloatArray,
    smooth: FloatArray,
    ring: FloatArray,
    sign: float,
    corners: np.ndarray,
    p: OutlineParams,
    noise: float,
    half: int,
    w: int,
    perimeter: float,
) -> tuple[FloatArray, BoolArray]:
    """Relevant points of an outline with corners: all runs' chord tests at once.

    The samples are rotated so that the first corner is sample 0; run r covers samples
    ``c[r] .. c[r + 1]`` (the last one ends at sample n = sample 0). Straight runs emit their
    corner; curved runs go through `_emit_run`.
    """
    n = len(res)
    c0 = int(corners[0])
    rolled = np.concatenate([res[c0:], res[: c0 + 1]])  # (n + 1, 2), rolled[n] = rolled[0]
    starts = corners - c0
    ends = np.append(starts[1:], n)
    a, b = rolled[starts], rolled[ends]
    chord = b - a
    length = np.hypot(chord[:, 0], chord[:, 1])
    run_id = np.repeat(np.arange(len(starts)), ends - starts)
    rel = rolled[:n] - a[run_id]
    dev = np.abs(chord[run_id, 0] * rel[:, 1] - chord[run_id, 1] * rel[:, 0])
    dev_max = np.maximum.reduceat(dev, starts)
    zero = length == 0.0
    if zero.any():  # degenerate chord: distance from the run's start
        dist0 = np.maximum.reduceat(np.hypot(rel[:, 0], rel[:, 1]), starts)
        dev_max = np.where(zero, dist0, dev_max / np.where(zero, 1.0, length))
    else:
        dev_max = dev_max / length
    straight = dev_max <= np.maximum(p.straight_sagitta_ratio * length, noise)
    if straight.all():
        points = a.copy()
        mask = np.zeros(len(a), dtype=bool)
        run_start = np.arange(len(a))
    else:
        turn = _turning(smooth, ring, sign)
        out_pts: list[FloatArray] = []
        out_curve: list[bool] = []
        first: list[int] = []
        for r, (s, e) in enumerate(zip(starts.tolist(), ends.tolist(), strict=True)):
            first.append(len(out_pts))
            if straight[r]:
                out_pts.append(a[r])
                out_curve.append(False)
                continue
            idx = (np.arange(s, e + 1) + c0) % n
            _emit_run(
                res,
                turn,
                idx,
                p=p,
                noise=noise,
                out_pts=out_pts,
                out_curve=out_curve,
                closed_loop=False,
                guard=half,
            )
        points = np.array(out_pts, dtype=np.float64)
        mask = np.array(out_curve, dtype=bool)
        run_start = np.array(first)
    if p.refine_corners and len(starts) >= 2:
        _refine_corners(
            rolled,
            starts,
            ends,
            straight,
            points,
            run_start,
            trim=w,
            reach=p.corner_window * perimeter,
            min_sin=math.sin(math.radians(p.corner_angle_deg)),
        )
    return points, mask


def _corners(change: FloatArray, threshold: float, window: int, spacing: int) -> np.ndarray:
    """Indices of corners: local maxima of direction change above threshold, spaced apart.

    Greedy: the strongest remaining candidate is kept unless within ``spacing`` samples
    (circularly) of one already kept.
    """
    n = len(change)
    vals = np.where(change > threshold, change, -np.inf)
    keep: list[int] = []
    while True:  # one iteration per kept corner; argmax takes the first of equal values
        i = int(np.argmax(vals))
        if vals[i] == -np.inf:
            break
        keep.append(i)
        if 2 * spacing + 1 >= n:
            break
        lo, hi = i - spacing, i + spacing + 1
        vals[max(lo, 0) : min(hi, n)] = -np.inf
        if lo < 0:
            vals[n + lo :] = -np.inf
        if hi > n:
            vals[: hi - n] = -np.inf
    keep.sort()
    return np.array(keep, dtype=np.int64)


def _emit_run(
    res: FloatArray,
    turn: FloatArray,
    idx: np.ndarray,
    *,
    p: OutlineParams,
    noise: float,
    out_pts: list[FloatArray],
    out_curve: list[bool],
    closed_loop: bool,
    guard: int,
) -> bool:
    """Append the relevant points of one run (from corner idx[0] up to, not incl., idx[-1]).

    Returns:
        True when the run is one straight edge.
    """
    if closed_loop:
        idx = np.concatenate([idx, idx[:1]])
        inner = turn[idx[:-1]]
    else:
        # Leave out the corners' own turning, spread by the smoothing over `guard` samples.
        inner = turn[idx[guard + 1 : len(idx) - guard - 1]]
    total = max(float(inner.sum()), 0.0)
    run = res[idx]
    dev = _chord_distance(run)
    chord = float(np.hypot(*(run[-1] - run[0])))
    straight = (not closed_loop) and float(dev.max(initial=0.0)) <= max(
        p.straight_sagitta_ratio * chord, noise
    )
    if straight:
        out_pts.append(run[0])
        out_curve.append(False)
        return True
    pieces = max(1, math.ceil(total / p.max_curve_turn_deg))
    if closed_loop:
        pieces = max(pieces, 2)
    # Split at equal cumulative (signed, made monotonic) turning.
    cum = np.maximum.accumulate(np.concatenate([[0.0], np.cumsum(turn[idx[1:]])]))
    goal = float(cum[-1])
    bounds = [0]
    for k in range(1, pieces):
        bounds.append(int(np.clip(np.searchsorted(cum, goal * k / pieces), 1, len(idx) - 2)))
    bounds.append(len(idx) - 1)
    for a, b in zip(bounds[:-1], bounds[1:], strict=True):
        sub = run[a : b + 1]
        out_pts.append(sub[0])
        out_curve.append(False)
        if len(sub) > 2:
            d = _chord_distance(sub)
            j = int(np.argmax(d))
            if d[j] > noise and 0 < j < len(sub) - 1:
                out_pts.append(sub[j])
                out_curve.append(True)
    return False


def _refine_corners(  # noqa: PLR0913, PLR0917
    rolled: FloatArray,
    starts: np.ndarray,
    ends: np.ndarray,
    straight: BoolArray,
    points: FloatArray,
    run_start: np.ndarray,
    *,
    trim: int,
    reach: float,
    min_sin: float,
) -> None:
    """Move each corner between two straight runs to the intersection of their fitted lines.

    Smoothing and the sample spacing round a corner off; the lines through the middles of the
    adjacent edges meet at the true corner. Kept only when the lines cross at a corner angle
    (sine of the angle between them >= ``min_sin``) within ``reach`` of the detected corner.
    Lines are total-least-squares fits of each run (its ends trimmed by ``trim`` samples when
    long enough), all runs at once from prefix sums. ``points`` is updated in place.
    """
    prev = np.arange(len(starts)) - 1  # run r - 1 (index -1: the last run)
    both = straight & straight[prev]
    if not both.any():
        return
    long = ends - starts + 1 > 2 * trim + 2
    lo = np.where(long, starts + trim, starts)
    hi = np.where(long, ends - trim + 1, ends + 1)  # exclusive
    origin = rolled[0]
    q = rolled - origin
    x, y = q[:, 0], q[:, 1]
    sums = np.zeros((len(q) + 1, 5))
    np.cumsum(np.stack([x, y, x * x, y * y, x * y], axis=1), axis=0, out=sums[1:])
    tot = sums[hi] - sums[lo]
    cnt = (hi - lo).astype(np.float64)
    mx, my = tot[:, 0] / cnt, tot[:, 1] / cnt
    sxx = tot[:, 2] - cnt * mx * mx
    syy = tot[:, 3] - cnt * my * my
    sxy = tot[:, 4] - cnt * mx * my
    phi = 0.5 * np.arctan2(2.0 * sxy, sxx - syy)  # principal direction of each run
    dx, dy = np.cos(phi), np.sin(phi)
    # Line r - 1 (previous run) meets line r.
    pdx, pdy, pmx, pmy = dx[prev], dy[prev], mx[prev], my[prev]
    den = pdx * dy - pdy * dx
    ok = both & (np.abs(den) >= min_sin)
    safe = np.where(ok, den, 1.0)
    t = ((mx - pmx) * dy - (my - pmy) * dx) / safe
    cx = pmx + t * pdx + origin[0]
    cy = pmy + t * pdy + origin[1]
    at = run_start
    ok &= np.hypot(cx - points[at, 0], cy - points[at, 1]) <= reach
    points[at[ok], 0] = cx[ok]
    points[at[ok], 1] = cy[ok]


def _chord_distance(run: FloatArray) -> FloatArray:
    """Distance of each point of a run from the chord joining its ends (or from its start)."""
    chord = run[-1] - run[0]
    length = float(np.hypot(*chord))
    rel = run - run[0]
    if length == 0.0:
        return np.asarray(np.hypot(rel[:, 0], rel[:, 1]))
    return np.asarray(np.abs(cross2(np.broadcast_to(chord, rel.shape), rel)) / length)


__all__ = ["OutlineParams", "default_outline_params", "simplify_outline"]
