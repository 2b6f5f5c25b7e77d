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
    if not np.all(np.isfinite(pts)):
        raise InvalidFigureError(f"{what}: points must be finite (no NaN or inf)")
    if len(pts) == 0:
        raise InvalidFigureError(f"{what}: a closed outline needs at least 3 points, got 0")
    if np.abs(pts).max() > MAX_COORDINATE:
        raise InvalidFigureError(
            f"{what}: coordinates must be at most {MAX_COORDINATE:g} in magnitude"
        )
    step = np.hypot(*(np.roll(pts, -1, axis=0) - pts).T)
    pts = pts[step > 0.0]  # drop consecutive repeats (and the closing copy)
    if len(pts) < 3:
        raise InvalidFigureError(
            f"{what}: a closed outline needs at least 3 distinct points, got {len(pts)}"
        )
    return pts


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
    seg = np.hypot(*(np.roll(pts, -1, axis=0) - pts).T)
    cum = np.concatenate([[0.0], np.cumsum(seg)])
    perimeter = float(cum[-1])
    n = p.resample_points
    s = np.arange(n) * (perimeter / n)
    closed = np.vstack([pts, pts[:1]])
    res = np.stack([np.interp(s, cum, closed[:, 0]), np.interp(s, cum, closed[:, 1])], axis=1)
    diameter = float(np.ptp(res, axis=0).max())
    area2 = float(cross2(res, np.roll(res, -1, axis=0)).sum())
    if diameter <= 0.0 or abs(area2) <= 1e-12 * diameter * diameter:
        raise InvalidFigureError(f"{what}: zero area (the outline is a line or a point)")
    sign = 1.0 if area2 > 0.0 else -1.0  # +1: counter-clockwise in the given frame

    half = max(1, round(p.smooth_fraction * n))
    kernel = np.ones(2 * half + 1) / (2 * half + 1)
    padded = np.concatenate([res[-half:], res, res[:half]])
    smooth = np.stack([np.convolve(padded[:, k], kernel, mode="valid") for k in range(2)], axis=1)

    w = max(1, round(p.corner_window * n))
    back = smooth - np.roll(smooth, w, axis=0)
    fwd = np.roll(smooth, -w, axis=0) - smooth
    change = np.degrees(np.arctan2(np.abs(cross2(back, fwd)), np.einsum("ij,ij->i", back, fwd)))
    # Local turning (signed, in the walk's sense) for curve splitting.
    d1 = smooth - np.roll(smooth, 1, axis=0)
    d2 = np.roll(smooth, -1, axis=0) - smooth
    turn = np.degrees(np.arctan2(cross2(d1, d2), np.einsum("ij,ij->i", d1, d2))) * sign

    corners = _corners(change, p.corner_angle_deg, w, max(w, round(p.merge_fraction * n)))
    noise = p.noise_fraction * diameter
    out_pts: list[FloatArray] = []
    out_curve: list[bool] = []
    if len(corners) == 0:
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
    else:
        runs: list[tuple[int, bool, FloatArray]] = []
        for a, b in zip(corners, np.roll(corners, -1), strict=True):
            idx = np.arange(a, b + (n if b <= a else 0) + 1) % n
            start = len(out_pts)
            straight = _emit_run(
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
            runs.append((start, straight, res[idx]))
        if p.refine_corners:
            _refine_corners(
                runs,
                out_pts,
                trim=w,
                reach=p.corner_window * perimeter,
                min_sin=math.sin(math.radians(p.corner_angle_deg)),
            )
    points = np.array(out_pts, dtype=np.float64)
    mask = np.array(out_curve, dtype=bool)
    if len(points) < 3:
        raise InvalidFigureError(
            f"{what}: simplified to {len(points)} relevant points; a figure needs at least 3"
        )
    return points, mask


def _corners(change: FloatArray, threshold: float, window: int, spacing: int) -> np.ndarray:
    """Indices of corners: local maxima of direction change above threshold, spaced apart."""
    order = np.argsort(-change, kind="stable")
    order = order[change[order] > threshold]
    n = len(change)
    taken = np.zeros(n, dtype=bool)
    keep: list[int] = []
    for i in order.tolist():  # few candidates: only points above the corner threshold
        if taken[i]:
            continue
        keep.append(i)
        taken[np.arange(i - spacing, i + spacing + 1) % n] = True
    return np.array(sorted(keep), dtype=np.int64)


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


def _fit_line(run: FloatArray, trim: int) -> tuple[FloatArray, FloatArray]:
    """Total-least-squares line (point, unit direction) through a run, its ends trimmed."""
    inner = run[trim : len(run) - trim] if len(run) > 2 * trim + 2 else run
    centre = inner.mean(axis=0)
    _, vecs = np.linalg.eigh(np.cov((inner - centre).T))
    return centre, vecs[:, -1]


def _refine_corners(
    runs: list[tuple[int, bool, FloatArray]],
    out_pts: list[FloatArray],
    *,
    trim: int,
    reach: float,
    min_sin: float,
) -> None:
    """Move each corner between two straight runs to the intersection of their fitted lines.

    Smoothing and the sample spacing round a corner off; the lines through the middles of the
    adjacent edges meet at the true corner. Kept only when the lines cross at a corner angle
    (sine of the angle between them >= ``min_sin``) within ``reach`` of the detected corner.
    """
    for r, (start, straight, run) in enumerate(runs):
        _, prev_straight, prev_run = runs[r - 1]
        if not (straight and prev_straight) or len(runs) < 2:
            continue
        m1, d1 = _fit_line(prev_run, trim)
        m2, d2 = _fit_line(run, trim)
        den = float(d1[0] * d2[1] - d1[1] * d2[0])
        if abs(den) < min_sin:
            continue
        diff = m2 - m1
        t = float(diff[0] * d2[1] - diff[1] * d2[0]) / den
        corner = m1 + t * d1
        if float(np.hypot(*(corner - out_pts[start]))) <= reach:
            out_pts[start] = corner


def _chord_distance(run: FloatArray) -> FloatArray:
    """Distance of each point of a run from the chord joining its ends (or from its start)."""
    chord = run[-1] - run[0]
    length = float(np.hypot(*chord))
    rel = run - run[0]
    if length == 0.0:
        return np.asarray(np.hypot(rel[:, 0], rel[:, 1]))
    return np.asarray(np.abs(cross2(np.broadcast_to(chord, rel.shape), rel)) / length)


__all__ = ["OutlineParams", "default_outline_params", "simplify_outline"]
