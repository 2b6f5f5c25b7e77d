"""Slope-comparison simplification of a dense closed outline to relevant points.

The outline (e.g. a traced image contour) is resampled uniformly by arc length and lightly
smoothed; a point is a corner where the direction of the outline changes by more than
`OutlineParams.corner_angle_deg` over a short window (slope comparison), keeping one corner per
window. Between consecutive corners the outline is a straight edge when it stays close to its
chord, otherwise a curve segment, whose maximum-curvature point is the one farthest from the
chord; curves turning more than `OutlineParams.max_curve_turn_deg` are split into equal pieces.
Three optional steps serve traced image contours (``configs/vision.yaml``): corners measured
against an arc's own turning, round outlines snapped to two equal semicircles, and corners cut
off or rounded by the pixel grid merged back into one. On rough edges (a chipped, ground tile
traced by a camera) corners come from fits (`qshape.outline.fit`,
``OutlineParams.fit_merge_chi2``): a
proposed corner stays only where the runs beside it need two lines (or arcs) rather than one,
judged against the outline's own measured roughness, a run that two edges fit better than an arc
gets back the corner the window measure missed, and edge lines are fitted over whole edges.
Every length parameter is a fraction of the outline's own size, so the same parameters serve
millimetres and pixels. Cost is linear in the number of outline points.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from qshape.errors import InvalidFigureError, ToleranceError
from qshape.geometry import MAX_COORDINATE, BoolArray, FloatArray, cross2
from qshape.outline.fit import (
    BendTest,
    circle_outlines,
    flat_corner_outlines,
    merge_fitted_corners,
    outline_moments,
    range_sums,
)
from qshape.theory.tolerances import _load_section

MIN_RESAMPLE_POINTS = 16
"""Fewest uniform samples an outline is resampled to (`OutlineParams.resample_points`)."""


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
        arc_turning_deg: A point whose outline turns by at least this much on both sides
            (the direction change measured 2 and 3 windows away, mean per side) lies inside an
            arc: only its change in excess of the smaller side's counts towards a corner, in
            [deg] (0: off). An arc turns by several degrees over every window and noise adds
            to that, while a corner's turning is concentrated: so the pixel staircase of a
            20 mm arc at 2 px/mm stays below ``corner_angle_deg``, and a shallow corner
            between straight edges keeps its full angle.
        circle_residual: An outline with a curve whose samples stay within this RMS radial
            distance of a fitted circle, as a fraction of its radius, is a circle: two equal
            semicircle arcs (dimensionless; 0: off). Where a traced closed curve is split
            depends on its noise, and two unequal halves label one arc acute and the other
            plane (a ring's hole seen through a thick tile, whose visible inner wall dents
            the outline, even gets shallow corners).
        chamfer_fraction: Two neighbouring corners joined by a straight edge shorter than
            this fraction of the perimeter are one corner cut off by noise: they become the
            intersection of the edges before and after them (dimensionless; 0: off).
        missed_corner_ratio: A run that is not straight but splits, at its sample farthest
            from the chord, into two halves each within this fraction of its own chord (or the
            noise floor) is two straight edges meeting at a corner the window measure missed
            (a shallow concave corner beside a pixel staircase), not a curve (dimensionless;
            0: off). Keep it below the halves of the shallowest arc that is not straight:
            with ``straight_sagitta_ratio`` 0.1 those are 0.049.
        roughness_sigmas: The noise floor of an outline is at least this many times its
            measured edge roughness (robust standard deviation of each sample's distance
            from the chord of its neighbours one corner window away, less the local mean
            that an arc's own sagitta gives), so a chipped, ground edge stays straight
            (dimensionless; 0: off).
        min_corner_deg: A corner between two straight runs whose fitted lines (total least
            squares over each run) meet at less than this angle is roughness on one edge,
            not a corner, and is dropped, weakest first, in [deg] (0: off). The lines are fitted
            over whole edges, so this holds where the window measure of
            ``corner_angle_deg`` is fooled by a rough edge; keep it below the shallowest real
            corner of the tiles (33 degrees in the bundled trencadis).
        fit_merge_chi2: Corners from fits (`qshape.outline.fit`), dimensionless, 0: off. A corner
            is dropped when the runs on both sides fit one line (or one arc, where a run is
            itself curved) with a squared residual at most this many times the outline's
            roughness variance per independent sample above their separate fits; the kept
            corners then move to the sample that best splits their runs, and an outline that
            one circle fits as well as its runs keeps no corner (a closed curve). The
            roughness is `roughness_sigmas`' measure, and one independent sample spans
            (1 + rho) / (1 - rho) samples for the lag-1 autocorrelation rho of the measure
            (a correlated bump counts once, however densely it is sampled).
        fit_split_turn_deg: With ``fit_merge_chi2``, a run between corners that is not
            straight is two edges meeting at a corner the window measure missed (or placed
            off, so the run took in part of the next edge) when two lines split at one of its
            samples (at least the corner spacing from its ends) fit it better than its arc
            and their directions differ by at least this, in [deg] (0: off). Such a run never
            lets an arc absorb its neighbours' corners (a rough hexagon merged side by side
            into a circle) and gets its corner back at the best split. Keep it well above
            the turn between a short arc piece's two chords (half the arc's turn): a longer
            arc is fitted far better by its arc than by two chords.
        fit_sigma_floor: Smallest roughness the fits assume, fraction of the outline's
            diameter (a clean traced outline still carries its pixel staircase).
        refine_trim_fraction: With ``refine_corners``, the samples left out at each end of
            a run before its line is fitted, fraction of the outline's samples (at least one
            sample; 0: ``corner_window``). A short trim fits the line to nearly the whole
            edge, which averages a rough edge's bumps out: keep it just above the rounding
            of a corner by blur.
        hole_corner_window: ``corner_window`` of an outline lying in another (a hole, see
            `simplify_outlines`' ``parents``), fraction of its own perimeter, but at most
            the figure outline's window in length (dimensionless; 0: ``corner_window``).
            Blur and rough edges round a small hole's corner over as many millimetres as
            the figure's, a larger share of the hole's short perimeter: over the figure's
            fraction the rounded corner turned twice, a corner gained.
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
    arc_turning_deg: float = 0.0
    circle_residual: float = 0.0
    chamfer_fraction: float = 0.0
    missed_corner_ratio: float = 0.0
    roughness_sigmas: float = 0.0
    min_corner_deg: float = 0.0
    fit_merge_chi2: float = 0.0
    fit_sigma_floor: float = 0.0
    fit_split_turn_deg: float = 0.0
    refine_trim_fraction: float = 0.0
    hole_corner_window: float = 0.0

    def __post_init__(self) -> None:
        """Validate ranges.

        Raises:
            ToleranceError: Naming the field and the allowed range.
        """
        if self.resample_points < MIN_RESAMPLE_POINTS:
            raise ToleranceError(
                f"resample_points must be >= {MIN_RESAMPLE_POINTS}, got {self.resample_points}"
            )
        for name in (
            "smooth_fraction",
            "corner_window",
            "straight_sagitta_ratio",
            "noise_fraction",
            "merge_fraction",
            "circle_residual",
            "chamfer_fraction",
            "missed_corner_ratio",
            "fit_sigma_floor",
            "refine_trim_fraction",
            "hole_corner_window",
        ):
            v = getattr(self, name)
            if not (math.isfinite(v) and 0.0 <= v < 0.5):
                raise ToleranceError(f"{name} must be in [0, 0.5), got {v!r}")
        if self.corner_window <= 0.0:
            raise ToleranceError("corner_window must be > 0")
        if not (math.isfinite(self.roughness_sigmas) and 0.0 <= self.roughness_sigmas <= 20.0):  # noqa: PLR2004
            raise ToleranceError(
                f"roughness_sigmas must be in [0, 20], got {self.roughness_sigmas}"
            )
        if not (math.isfinite(self.fit_merge_chi2) and 0.0 <= self.fit_merge_chi2 <= 1e4):  # noqa: PLR2004
            raise ToleranceError(f"fit_merge_chi2 must be in [0, 1e4], got {self.fit_merge_chi2}")
        if not 0.0 <= self.min_corner_deg < 90.0:  # noqa: PLR2004
            raise ToleranceError(f"min_corner_deg must be in [0, 90), got {self.min_corner_deg}")
        if not 0.0 <= self.fit_split_turn_deg < 180.0:  # noqa: PLR2004
            raise ToleranceError(
                f"fit_split_turn_deg must be in [0, 180), got {self.fit_split_turn_deg}"
            )
        if not 0.0 <= self.arc_turning_deg < 180.0:
            raise ToleranceError(f"arc_turning_deg must be in [0, 180), got {self.arc_turning_deg}")
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


@functools.cache
def default_outline_params() -> OutlineParams:
    """Bundled outline parameters, loaded once."""
    return OutlineParams.load()


def _norm(x: FloatArray, y: FloatArray) -> FloatArray:
    """Length of the vectors (x, y), elementwise, as ``np.hypot`` to a unit in the last place.

    About three times faster; coordinates are at most `MAX_COORDINATE`, so nothing overflows.
    """
    return np.asarray(np.sqrt(x * x + y * y))


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
    moved = (d[:, 0] != 0.0) | (d[:, 1] != 0.0)
    if not moved.all():
        pts = pts[moved]  # drop consecutive repeats (and the closing copy)
    if len(pts) < 3:
        raise InvalidFigureError(
            f"{what}: a closed outline needs at least 3 distinct points, got {len(pts)}"
        )
    return pts


def _clean_many(
    dense: Sequence[ArrayLike], names: Sequence[str]
) -> list[FloatArray | InvalidFigureError]:
    """`_clean` of many outlines (the returned arrays are read, never written).

    The common case (finite (k, 2) float points in range, no point repeated) is checked in one
    pass over all of them; every other outline goes through `_clean`, which names the fault.
    """
    arrays: list[FloatArray | None] = []
    for d in dense:
        a = np.asarray(d, dtype=np.float64) if isinstance(d, np.ndarray) else None
        arrays.append(a if a is not None and a.ndim == 2 and a.shape[1] == 2 else None)  # noqa: PLR2004
    parts = [a for a in arrays if a is not None and len(a) >= 3]  # noqa: PLR2004
    fast = [k for k, a in enumerate(arrays) if a is not None and len(a) >= 3]  # noqa: PLR2004
    ok = np.zeros(len(arrays), dtype=bool)
    if fast:
        pts: FloatArray = np.concatenate(parts)
        sizes = np.array([len(a) for a in parts])
        start = np.cumsum(sizes) - sizes
        nxt = np.arange(1, len(pts) + 1)
        nxt[start + sizes - 1] = start
        d = np.take(pts, nxt, axis=0) - pts
        moved = (d[:, 0] != 0.0) | (d[:, 1] != 0.0)
        # NaN fails both comparisons: such an outline goes to `_clean` for its message.
        inside = np.maximum(np.abs(pts[:, 0]), np.abs(pts[:, 1])) <= MAX_COORDINATE
        good = np.logical_and.reduceat(moved & inside, start)
        ok[np.array(fast)[good]] = True
    out: list[FloatArray | InvalidFigureError] = []
    for k, d in enumerate(dense):
        a = arrays[k]
        if ok[k] and a is not None:
            out.append(a)
            continue
        try:
            out.append(_clean(d, names[k]))
        except InvalidFigureError as exc:
            out.append(exc)
    return out


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
    (out,) = simplify_outlines([dense], params, whats=[what])
    if isinstance(out, InvalidFigureError):
        raise out
    return out


def simplify_outlines(
    dense: Sequence[ArrayLike],
    params: OutlineParams | None = None,
    *,
    whats: Sequence[str] | None = None,
    parents: Sequence[int | None] | None = None,
) -> list[tuple[FloatArray, BoolArray] | InvalidFigureError]:
    """`simplify_outline` of many outlines at once (vectorised over all of them).

    Args:
        dense: Closed outlines, each of shape (k_i, 2).
        params: Simplification parameters; None: the bundled defaults.
        whats: Names used in error messages, one per outline (default "outline i").
        parents: Per outline, the index in ``dense`` of the outline it lies in (a hole's
            figure outline) or None. A hole's cut-off corners are judged at its figure's
            size (``OutlineParams.chamfer_fraction`` of the parent's perimeter): the blur and
            roughness that cut a corner are as long on a small hole as on the figure.

    Returns:
        Per outline, (points, curve_mask) or the `InvalidFigureError` it raised.
    """
    p = default_outline_params() if params is None else params
    names = [f"outline {i}" for i in range(len(dense))] if whats is None else list(whats)
    out: list[tuple[FloatArray, BoolArray] | InvalidFigureError | None] = []
    good: list[int] = []
    cleaned: list[FloatArray] = []
    for i, c in enumerate(_clean_many(dense, names)):
        if isinstance(c, InvalidFigureError):
            out.append(c)
            continue
        cleaned.append(c)
        out.append(None)
        good.append(i)
    if good:
        row = {i: f for f, i in enumerate(good)}
        up = [None if parents is None else _row_of(parents[i], row) for i in good]
        _simplify_clean(cleaned, p, [names[i] for i in good], out, good, parents=up)
    return [x for x in out if x is not None]


def _row_of(index: int | None, row: dict[int, int]) -> int | None:
    """Cleaned row of outline ``index`` (None: no outline, or one that failed cleaning)."""
    return None if index is None else row.get(index)


def _simplify_clean(
    cleaned: list[FloatArray],
    p: OutlineParams,
    names: list[str],
    out: list[tuple[FloatArray, BoolArray] | InvalidFigureError | None],
    slots: list[int],
    *,
    parents: list[int | None],
) -> None:
    """Simplify cleaned outlines, writing each result (or error) to ``out[slots[f]]``.

    ``parents[f]``: the cleaned outline outline f lies in (see `simplify_outlines`), or None.
    """
    n = p.resample_points
    res, perimeter = _resampled_many(cleaned, n)  # (F, n, 2), (F,)
    # Sums along the samples run over x and y apart (2, F, n): numpy reduces an axis whose
    # inner axis has only two entries (the coordinates) many times slower.
    planes = np.ascontiguousarray(res.transpose(2, 0, 1))
    mean = planes.mean(axis=2).T  # (F, 2)
    centred = planes - mean.T[:, :, None]
    diameter = np.maximum(np.ptp(planes[0], axis=1), np.ptp(planes[1], axis=1))
    nxt = _roll_last(centred, -1)
    area2 = (centred[0] * nxt[1] - centred[1] * nxt[0]).sum(axis=1)
    flat = (diameter <= 0.0) | (np.abs(area2) <= 1e-12 * diameter * diameter)
    sign = np.where(area2 > 0.0, 1.0, -1.0)  # +1: counter-clockwise in the given frame

    # Circular moving average (prefix sums of the wrapped, centred samples).
    half = max(1, round(p.smooth_fraction * n))
    width = 2 * half + 1
    padded = np.concatenate([centred[..., -half:], centred, centred[..., :half]], axis=2)
    csum = np.zeros((2, len(cleaned), n + 2 * half + 1))
    np.cumsum(padded, axis=2, out=csum[..., 1:])
    smooth_xy = (csum[..., width:] - csum[..., :-width]) / width + mean.T[:, :, None]

    w = max(1, round(p.corner_window * n))
    spacing = max(w, round(p.merge_fraction * n))
    corners, ext = _window_corners(smooth_xy, w, flat, p, p.corner_angle_deg, spacing)
    holes = (
        _hole_windows(p, perimeter, np.abs(area2) / 2.0, parents, w)
        if p.hole_corner_window > 0.0
        else {}
    )
    for wh, rows in holes.items():
        # Over the hole's longer window the corner angle rises by the turning a circle adds
        # (`_FULL_TURN_OVER_WINDOWS` x the extra fraction of the perimeter): a round hole's
        # steady turning stays below it as over ``corner_window``.
        extra = max(0.0, wh / n - p.corner_window)
        angle = p.corner_angle_deg + _FULL_TURN_OVER_WINDOWS * extra
        found, _ = _window_corners(smooth_xy[:, rows], wh, flat[rows], p, angle, max(wh, spacing))
        for f, c in zip(rows.tolist(), found, strict=True):
            corners[f] = c
    noise = p.noise_fraction * diameter
    mom: FloatArray | None = None
    if p.roughness_sigmas > 0.0 or p.fit_merge_chi2 > 0.0:
        rough, corr = _roughness(planes, w)
        for wh, rows in holes.items():  # a hole's roughness over its own window
            rough[rows], corr[rows] = _roughness(planes[:, rows], wh)
        if p.roughness_sigmas > 0.0:
            noise = np.maximum(noise, p.roughness_sigmas * rough)
        if p.fit_merge_chi2 > 0.0:
            # The x/y planes seen as (F, n, 2): numpy then sums along contiguous memory.
            mom = outline_moments(
                planes.transpose(1, 2, 0), np.where(diameter > 0.0, diameter, 1.0)
            )
            _corners_from_fits(
                mom, corners, p, rough * np.sqrt(corr), diameter, flat, (half, spacing)
            )
    if p.min_corner_deg > 0.0:
        if mom is None:
            suspects = _with_flat_corners(res, corners, p.min_corner_deg, half)
        else:
            suspects = flat_corner_outlines(mom, corners, p.min_corner_deg, half)
        for f in suspects.tolist():
            if not flat[f]:
                corners[f] = _verified_corners(res[f], corners[f], p, float(noise[f]), half)
    ring = ext[..., w - 1 : w + n + 1].transpose(1, 2, 0)
    geom = _Samples(res, planes, smooth_xy.transpose(1, 2, 0), ring, sign, noise, perimeter, flat)
    frame = None if mom is None else (mom, mean, np.where(diameter > 0.0, diameter, 1.0))
    results = _polylines(geom, corners, p, (half, w), frame)
    if p.chamfer_fraction > 0.0:
        # Outer outlines first: a hole's limit is its parent's perimeter once merged.
        outer = [f for f in range(len(results)) if parents[f] is None]
        for f in _with_chamfers(results, p.chamfer_fraction, outer):
            points, mask = results[f]
            results[f] = _merge_chamfers(points, mask, p.chamfer_fraction)
        inner = [f for f in range(len(results)) if parents[f] is not None]
        if inner:
            scale = {
                f: max(_perimeter(results[f][0]), _perimeter(results[q][0]))
                for f in inner
                if (q := parents[f]) is not None
            }
            for f in _with_chamfers(results, p.chamfer_fraction, inner, list(scale.values())):
                points, mask = results[f]
                results[f] = _merge_chamfers(points, mask, p.chamfer_fraction, scale[f])
    if p.circle_residual > 0.0:
        _snap_circles(res, sign, results, p.circle_residual)
    for f, i in enumerate(slots):
        what = names[f]
        if flat[f]:
            out[i] = InvalidFigureError(f"{what}: zero area (the outline is a line or a point)")
            continue
        points, mask = results[f]
        if len(points) < 3:
            out[i] = InvalidFigureError(
                f"{what}: simplified to {len(points)} relevant points; a figure needs at least 3"
            )
            continue
        out[i] = (points, mask)


def _direction_change(smooth_xy: FloatArray, w: int) -> tuple[FloatArray, FloatArray]:
    """Direction change [deg] over ``w`` samples each side of every sample, shape (F, n).

    Also returns the wrapped samples it used, ``ext[:, :, i + w] = smooth_xy[:, :, i]``,
    shape (2, F, n + 2 w).
    """
    n = smooth_xy.shape[2]
    ext = np.concatenate([smooth_xy[..., -w:], smooth_xy, smooth_xy[..., :w]], axis=2)
    back = smooth_xy - ext[..., :n]
    fwd = ext[..., 2 * w :] - smooth_xy
    bx, by, fx, fy = back[0], back[1], fwd[0], fwd[1]
    return np.degrees(np.arctan2(np.abs(bx * fy - by * fx), bx * fx + by * fy)), ext


def _hole_windows(
    p: OutlineParams,
    perimeter: FloatArray,
    area: FloatArray,
    parents: list[int | None],
    w: int,
) -> dict[int, np.ndarray]:
    """Outlines lying in another, grouped by their wider corner window in samples (> ``w``).

    A hole's window is ``hole_corner_window`` of its own samples, but never longer than the
    window of its figure's outline (``corner_window`` x the figure's perimeter) nor than half
    the hole's width (2 x area / perimeter: a slit's two ends stay two corners each).
    """
    n = p.resample_points
    groups: dict[int, list[int]] = {}
    for f, q in enumerate(parents):
        if q is None or perimeter[f] <= 0.0:
            continue
        own = float(perimeter[f])
        frac = min(
            p.hole_corner_window,
            p.corner_window * float(perimeter[q]) / own,
            float(area[f]) / (own * own),  # half the width 2 area / perimeter
        )
        wh = round(frac * n)
        if wh > w:
            groups.setdefault(wh, []).append(f)
    return {wh: np.array(rows, dtype=np.int64) for wh, rows in groups.items()}


def _window_corners(  # noqa: PLR0917
    smooth_xy: FloatArray, w: int, flat: BoolArray, p: OutlineParams, angle: float, spacing: int
) -> tuple[list[np.ndarray], FloatArray]:
    """Window-measure corners of outlines (x and y planes (2, F, n)) over a window of ``w``.

    A corner turns by at least ``angle`` [deg] over the window; corners closer than
    ``spacing`` samples are one. Flat outlines have none. Also returns the wrapped samples of
    `_direction_change`.
    """
    change, ext = _direction_change(smooth_xy, w)
    change[flat] = 0.0
    if p.arc_turning_deg > 0.0:
        change = _excess_turning(change, w, p.arc_turning_deg)
    return _corners_many(change, angle, spacing), ext


_FULL_TURN_OVER_WINDOWS = 720.0
"""Direction change [deg] of a circle measured over windows of its whole perimeter per
unit of window fraction: 2 windows x 360 deg (a 3.25 % window: 23.4 deg)."""


def _corners_from_fits(  # noqa: PLR0913, PLR0917
    mom: FloatArray,
    corners: list[np.ndarray],
    p: OutlineParams,
    sigma: FloatArray,
    diameter: FloatArray,
    skip: BoolArray,
    spans: tuple[int, int],
) -> None:
    """Corners (in place) dropped where one fit explains the runs beside them.

    `qshape.outline.fit.merge_fitted_corners`; then an outline one circle fits as well as its runs
    loses them all (`qshape.outline.fit.circle_outlines`: a closed curve), and in any other outline
    (with ``fit_split_turn_deg``) a run that is two edges gets its corner back. ``mom``:
    the outlines' `qshape.outline.fit.outline_moments` in units of their diameter; ``sigma`` (F,):
    each outline's roughness per independent sample; ``spans``: samples left out at a run's
    far end, and the spacing kept between corners.
    """
    rows = np.flatnonzero(~skip & (np.array([len(c) for c in corners]) > 1))
    if len(rows) == 0:
        return
    trim, spacing = spans
    scale = np.where(diameter > 0.0, diameter, 1.0)
    sig = np.maximum(sigma, p.fit_sigma_floor * diameter) / scale
    limit = p.fit_merge_chi2 * sig * sig
    bend = BendTest(p.fit_split_turn_deg, spacing) if p.fit_split_turn_deg > 0.0 else None
    splits = merge_fitted_corners(mom, corners, rows, limit, trim, bend=bend)
    circles = circle_outlines(mom, corners, rows, limit).tolist()
    for f in circles:
        corners[f] = np.zeros(0, dtype=np.int64)
    for f in set(splits) - set(circles):
        corners[f] = np.sort(np.concatenate((corners[f], splits[f])))


def _roughness(planes: FloatArray, w: int) -> tuple[FloatArray, FloatArray]:
    """Robust edge roughness of outlines given as x and y planes (2, F, n) -> (F,), in their unit.

    Each sample's signed distance from the chord of its neighbours ``w`` samples away, less
    its moving mean over 4 w + 1 samples (an arc's sagitta, constant along it), scaled by the
    normal-consistency factor of the median absolute deviation and by sqrt(2/3) (the chord's
    ends carry noise too).

    Returns:
        (roughness (F,), correlation (F,)): the second is how many consecutive samples one
        independent sample of that roughness spans, (1 + rho) / (1 - rho) for the lag-1
        autocorrelation rho of those distances (>= 1; a bump spread over many samples is one).
    """
    n = planes.shape[2]
    ext = np.concatenate([planes[..., -w:], planes, planes[..., :w]], axis=2)
    a, b = ext[..., :n], ext[..., 2 * w :]  # samples w before and w after, circularly
    chord = b - a
    length = _norm(chord[0], chord[1])
    rel = planes - a
    dist = (chord[0] * rel[1] - chord[1] * rel[0]) / np.maximum(length, 1e-12)
    k = min(2 * w, (n - 1) // 2)
    ext = np.concatenate([dist[:, -k:], dist, dist[:, :k]], axis=1)
    csum = np.zeros((planes.shape[1], n + 2 * k + 1))
    np.cumsum(ext, axis=1, out=csum[:, 1:])
    local = (csum[:, 2 * k + 1 :] - csum[:, :n]) / (2 * k + 1)
    detrended = dist - local
    sigma = _MAD_TO_SIGMA * _row_medians(np.abs(detrended)) * math.sqrt(2.0 / 3.0)
    lag = (detrended * _roll_last(detrended, 1)).sum(axis=1)
    rho = np.clip(lag / np.maximum((detrended * detrended).sum(axis=1), 1e-300), 0.0, _MAX_RHO)
    return np.asarray(sigma), np.asarray((1.0 + rho) / (1.0 - rho))


_MAX_RHO = 0.99
"""Largest lag-1 autocorrelation used (a correlation factor of at most 199 samples)."""


_MAD_TO_SIGMA = 1.4826
"""Median absolute deviation of a normal sample x this = its standard deviation."""


def _with_flat_corners(
    res: FloatArray, corners: list[np.ndarray], min_deg: float, trim: int
) -> np.ndarray:
    """Outlines with a corner whose neighbouring runs' fitted lines meet below ``min_deg``.

    All runs of all outlines at once (prefix sums of the moments), straight or not: a
    superset of the outlines `_verified_corners` changes.
    """
    count, n = res.shape[:2]
    m = np.array([len(c) for c in corners])
    rows = np.flatnonzero(m > 3)  # noqa: PLR2004 (a figure's fewest corners)
    if len(rows) == 0:
        return rows
    mm = m[rows]
    owner = np.repeat(np.arange(len(rows)), mm)
    starts = np.concatenate([corners[f] for f in rows.tolist()]).astype(np.int64)
    first = np.concatenate([[0], np.cumsum(mm)[:-1]])
    nxt = np.arange(len(starts)) + 1
    nxt[first + mm - 1] = first
    ends = starts[nxt] + np.where(starts[nxt] <= starts, n, 0)  # unwrapped
    long = ends - starts + 1 > 2 * trim + 4
    lo = np.where(long, starts + trim, starts)
    hi = np.where(long, ends - trim + 1, ends + 1)
    sub = res[rows]
    origin = sub[:, 0, :]
    q = np.concatenate([sub, sub], axis=1) - origin[:, None, :]  # twice round: unwrapped runs
    x, y = q[..., 0], q[..., 1]
    sums = np.zeros((len(rows), 2 * n + 1, 5))
    np.cumsum(np.stack([x, y, x * x, y * y, x * y], axis=-1), axis=1, out=sums[:, 1:])
    tot = sums[owner, hi] - sums[owner, lo]
    cnt = (hi - lo).astype(np.float64)
    mx, my = tot[:, 0] / cnt, tot[:, 1] / cnt
    phi = 0.5 * np.arctan2(
        2.0 * (tot[:, 4] - cnt * mx * my), (tot[:, 2] - cnt * mx * mx) - (tot[:, 3] - cnt * my * my)
    )
    d = np.stack([np.cos(phi), np.sin(phi)], axis=1)
    chord = q[owner, ends] - q[owner, starts]
    d *= np.where((d * chord).sum(axis=1) >= 0.0, 1.0, -1.0)[:, None]
    prev = np.arange(len(starts)) - 1
    prev[first] = first + mm - 1
    ang = np.degrees(np.arccos(np.clip((d * d[prev]).sum(axis=1), -1.0, 1.0)))
    return np.asarray(rows[np.unique(owner[ang < min_deg])])


def _verified_corners(
    res: FloatArray, corners: np.ndarray, p: OutlineParams, noise: float, trim: int
) -> np.ndarray:
    """``corners`` (sample indices) less those between two straight runs meeting too flat.

    Repeatedly drops the corner whose neighbouring runs are both straight (within
    ``straight_sagitta_ratio`` x chord or ``noise``) and whose fitted lines meet at the
    smallest angle, while that angle is below ``min_corner_deg``.
    """
    n = len(res)
    c = [int(x) for x in corners]
    while len(c) > 3:  # noqa: PLR2004 (a figure's fewest corners)
        runs = [_run(res, c[i], c[(i + 1) % len(c)], n) for i in range(len(c))]
        dirs = [
            _line_direction(r, trim)
            if _straight_within(r, p.straight_sagitta_ratio, noise)
            else None
            for r in runs
        ]
        best: tuple[float, int] | None = None
        for i in range(len(c)):
            d0, d1 = dirs[i - 1], dirs[i]
            if d0 is None or d1 is None:
                continue
            ang = math.degrees(math.acos(max(-1.0, min(1.0, float(d0 @ d1)))))
            if ang < p.min_corner_deg and (best is None or ang < best[0]):
                best = (ang, i)
        if best is None:
            break
        del c[best[1]]
    return np.array(c, dtype=np.int64)


def _run(res: FloatArray, a: int, b: int, n: int) -> FloatArray:
    """Samples from index a to b inclusive, circularly."""
    return res[(a + np.arange((b - a) % n + 1)) % n]


def _line_direction(run: FloatArray, trim: int) -> FloatArray:
    """Unit direction (2,) of the total-least-squares line of a run (ends trimmed if long)."""
    core = run[trim : len(run) - trim] if len(run) > 2 * trim + 4 else run  # noqa: PLR2004
    q = core - core.mean(axis=0)
    sxx, syy, sxy = float(q[:, 0] @ q[:, 0]), float(q[:, 1] @ q[:, 1]), float(q[:, 0] @ q[:, 1])
    phi = 0.5 * math.atan2(2.0 * sxy, sxx - syy)
    d = np.array([math.cos(phi), math.sin(phi)])
    return d if float(d @ (run[-1] - run[0])) >= 0.0 else -d


def _row_medians(a: FloatArray) -> FloatArray:
    """``np.median(a, axis=1)`` of finite (F, n) values, the same numbers without its overhead.

    The middle order statistic, or the mean of the two middle ones (their sum halved, as
    numpy's mean of two).
    """
    n = a.shape[1]
    mid = n // 2
    if n % 2:
        return np.asarray(np.partition(a, mid, axis=1)[:, mid])
    part = np.partition(a, (mid - 1, mid), axis=1)
    return np.asarray((part[:, mid - 1] + part[:, mid]) / 2.0)


def _roll_last(a: FloatArray, shift: int) -> FloatArray:
    """``np.roll(a, shift, axis=-1)``: the same values, in one concatenation.

    Several times faster than `np.roll` on the (F, n) and (2, F, n) arrays of a batch.
    """
    k = shift % a.shape[-1]
    return np.concatenate([a[..., a.shape[-1] - k :], a[..., : a.shape[-1] - k]], axis=-1)


def _excess_turning(change: FloatArray, w: int, arc_deg: float) -> FloatArray:
    """``change`` (F, n) less the turning beside each point that lies inside an arc.

    Each side's turning is the mean change 2 and 3 windows ``w`` away; where the smaller
    side turns by ``arc_deg`` or more, it is subtracted (see `OutlineParams.arc_turning_deg`).
    """
    before = _roll_last(change, 2 * w) + _roll_last(change, 3 * w)
    after = _roll_last(change, -2 * w) + _roll_last(change, -3 * w)
    side = 0.5 * np.minimum(before, after)
    return np.asarray(change - np.where(side >= arc_deg, side, 0.0))


def _snap_circles(
    res: FloatArray,
    sign: FloatArray,
    results: list[tuple[FloatArray, BoolArray]],
    tol: float,
) -> None:
    """Replace, in place, each curved result whose samples fit a circle by two semicircles.

    Algebraic (Kasa) circle fits of all outlines at once: x^2 + y^2 + D x + E y + F = 0.
    The new points start at the result's first point's bearing and keep the orientation.
    """
    curved = np.array([len(m) > 0 and bool(m.any()) for _, m in results])
    if not curved.any():
        return
    idx = np.flatnonzero(curved)
    pts = res[idx]  # (C, n, 2)
    c0 = np.stack([pts[..., 0].mean(axis=1), pts[..., 1].mean(axis=1)], axis=1)[:, None, :]
    q = pts - c0  # centred: better conditioned
    a = np.concatenate([q, np.ones(q.shape[:2] + (1,))], axis=2)  # (C, n, 3)
    b = -(q**2).sum(axis=2)  # (C, n)
    ata = np.einsum("cni,cnj->cij", a, a)
    atb = np.einsum("cni,cn->ci", a, b)
    sol = np.linalg.solve(ata, atb[..., None])[..., 0]  # (C, 3)
    centre = -0.5 * sol[:, :2]
    r2 = (centre**2).sum(axis=1) - sol[:, 2]
    r = np.sqrt(np.maximum(r2, 0.0))
    dev = _norm(q[..., 0] - centre[:, None, 0], q[..., 1] - centre[:, None, 1]) - r[:, None]
    rms = np.sqrt((dev**2).mean(axis=1))
    good = (r2 > 0.0) & (rms <= tol * r)
    steps = np.arange(_CIRCLE_POINTS) * (2.0 * math.pi / _CIRCLE_POINTS)
    for j in np.flatnonzero(good).tolist():
        f = int(idx[j])
        cen = centre[j] + c0[j, 0]
        first = results[f][0][0] - cen
        ang = math.atan2(first[1], first[0]) + sign[f] * steps
        new = cen + r[j] * np.column_stack([np.cos(ang), np.sin(ang)])
        results[f] = (new, np.arange(_CIRCLE_POINTS) % 2 == 1)


_CIRCLE_POINTS = 4
"""A circle as relevant points: start, middle, end of two semicircle arcs."""

_PARALLEL_SIN = 1e-3
"""Edges whose unit directions' cross product is below this are parallel."""


def _perimeter(points: FloatArray) -> float:
    """Perimeter of closed relevant points (k, 2) (0 for none)."""
    if len(points) == 0:
        return 0.0
    step = _roll_last(points.T, -1) - points.T
    return float(_norm(step[0], step[1]).sum())


def _with_chamfers(
    results: list[tuple[FloatArray, BoolArray]],
    fraction: float,
    which: list[int],
    scale: list[float] | None = None,
) -> list[int]:
    """Indices (among ``which``) of the results `_merge_chamfers` would change, all at once.

    ``scale``: per entry of ``which``, the perimeter the fraction applies to (default: the
    result's own).
    """
    chosen = [results[f] for f in which]
    sizes = np.array([len(m) for _, m in chosen], dtype=np.int64)
    if sizes.sum() == 0:
        return []
    pts = np.concatenate([q.reshape(-1, 2) for q, _ in chosen])
    mask = np.concatenate([m for _, m in chosen])
    start = np.repeat(np.cumsum(sizes) - sizes, sizes)
    size = np.repeat(sizes, sizes)
    local = np.arange(len(mask)) - start
    nxt1 = start + (local + 1) % size
    nxt2 = start + (local + 2) % size
    d1 = np.hypot(*(pts[nxt1] - pts).T)
    d2 = np.hypot(*(pts[nxt2] - pts).T)
    owner = np.repeat(np.arange(len(chosen)), sizes)
    per = np.bincount(owner, d1, minlength=len(chosen)) if scale is None else np.array(scale)
    limit = fraction * per[owner]
    corner = ~mask
    one = corner & corner[nxt1] & (d1 < limit) & (size > 3)  # noqa: PLR2004
    two = corner & mask[nxt1] & corner[nxt2] & (d2 < limit) & (size > 4)  # noqa: PLR2004
    return [which[k] for k in np.unique(owner[one | two]).tolist()]


def _merge_chamfers(
    pts: FloatArray, mask: BoolArray, fraction: float, perimeter: float | None = None
) -> tuple[FloatArray, BoolArray]:
    """Merge neighbouring corners closer than ``fraction`` x perimeter (see `OutlineParams`).

    ``perimeter``: the length the fraction applies to (default: the points' own perimeter).

    Two corners count as neighbours when joined by one edge (a cut-off corner) or by one short
    curve (a rounded one). The pair (and the curve point between) becomes the point where
    the edge before meets the edge after when both are straight and not parallel, else the
    pair's midpoint (an arc's chord says little about its tangent).
    """
    while len(pts) > 3:  # noqa: PLR2004 (a figure's fewest points)
        n = len(pts)
        steps = np.roll(pts, -1, axis=0) - pts
        own = float(np.hypot(steps[:, 0], steps[:, 1]).sum())
        limit = fraction * (own if perimeter is None else perimeter)
        best: tuple[float, int, int] | None = None
        corners = np.flatnonzero(~mask)
        for a, b in zip(corners.tolist(), np.roll(corners, -1).tolist(), strict=True):
            gap = (b - a) % n
            if gap not in (1, 2) or n - gap < 3:  # noqa: PLR2004
                continue
            dist = float(np.hypot(*(pts[b] - pts[a])))
            if dist < limit and (best is None or dist < best[0]):
                best = (dist, a, gap)
        if best is None:
            break
        _, a, gap = best
        b = (a + gap) % n
        a0, da = pts[(a - 1) % n], pts[a] - pts[(a - 1) % n]
        b0, db = pts[b], pts[(b + 1) % n] - pts[b]
        cross = float(da[0] * db[1] - da[1] * db[0])
        straight = not (mask[(a - 1) % n] or mask[(b + 1) % n])
        if straight and abs(cross) > _PARALLEL_SIN * float(np.hypot(*da) * np.hypot(*db)):
            t = float((b0 - a0)[0] * db[1] - (b0 - a0)[1] * db[0]) / cross
            new = a0 + t * da
        else:
            new = 0.5 * (pts[a] + b0)
        gone = {(a + k) % n for k in range(gap + 1)}
        keep = np.array([k for k in range(n) if k not in gone])
        at = int(np.searchsorted(keep, a))  # where the pair was, in the kept order
        pts = np.insert(pts[keep], at, new, axis=0)
        mask = np.insert(mask[keep], at, False)
    return pts, mask


@dataclass(frozen=True)
class _Moments:
    """Prefix sums of moments of some runs' outlines (`qshape.outline.fit.outline_moments`).

    Attributes:
        moments: (9, F, n + 1) in units of ``scale``, centred on ``mean``.
        rows: (G,) outline of each row of the rolled samples. first: (G,) its sample 0.
        mean: (F, 2) centre of each outline. scale: (F,) its unit.
    """

    moments: FloatArray
    rows: np.ndarray
    first: np.ndarray
    mean: FloatArray
    scale: FloatArray


@dataclass(frozen=True)
class _Samples:
    """Resampled outlines, all of ``n`` samples.

    Attributes:
        res: Samples, shape (F, n, 2). planes: The same as x and y planes, (2, F, n).
        smooth: Their moving average, (F, n, 2).
        ring: ``ring[:, i + 1] = smooth[:, i]``, wrapped, shape (F, n + 2, 2).
        sign: (F,) +1 for counter-clockwise outlines. noise: (F,) chord noise floor.
        perimeter: (F,) outline lengths. skip: (F,) degenerate outlines (no result).
    """

    res: FloatArray
    planes: FloatArray
    smooth: FloatArray
    ring: FloatArray
    sign: FloatArray
    noise: FloatArray
    perimeter: FloatArray
    skip: BoolArray

    def turning(self, f: int) -> FloatArray:
        """Local signed turning [deg] at each smoothed sample of outline f, shape (n,)."""
        sm, ring = self.smooth[f], self.ring[f]
        d1 = sm - ring[:-2]
        d2 = ring[2:] - sm
        crs = d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]
        dot = d1[:, 0] * d2[:, 0] + d1[:, 1] * d2[:, 1]
        return np.asarray(np.degrees(np.arctan2(crs, dot)) * self.sign[f])


def _resampled_many(pts: list[FloatArray], n: int) -> tuple[FloatArray, FloatArray]:
    """``n`` uniform arc-length samples of each closed polygon -> (F, n, 2), perimeters (F,).

    One interpolation over all outlines: each one's arc length is offset past the previous.
    """
    lens = np.array([len(q) for q in pts])
    sizes = lens + 1
    first = np.concatenate([[0], np.cumsum(sizes)[:-1]])
    # Every outline with its first point repeated at the end, taken from all points at once.
    row = np.arange(int(sizes.sum())) - np.repeat(first, sizes)
    row[first + lens] = 0
    row += np.repeat(first - np.arange(len(pts)), sizes)
    closed = np.take(np.concatenate(pts), row, axis=0)
    seg = np.zeros(len(closed))
    d = closed[1:] - closed[:-1]
    seg[1:] = _norm(d[:, 0], d[:, 1])
    seg[first] = 0.0  # no length between one outline and the next
    cum = np.cumsum(seg)
    start = cum[first]
    perimeter = np.append(start[1:], cum[-1]) - start
    # Outline f spans [start_f + f, start_f + f + perimeter_f]: a gap of 1 between outlines.
    gap = np.arange(len(pts), dtype=np.float64)
    xp = cum + np.repeat(gap, sizes)
    s = (start + gap)[:, None] + np.arange(n)[None, :] * (perimeter / n)[:, None]
    res = np.empty((len(pts), n, 2))
    res[:, :, 0] = np.interp(s.ravel(), xp, closed[:, 0]).reshape(len(pts), n)
    res[:, :, 1] = np.interp(s.ravel(), xp, closed[:, 1]).reshape(len(pts), n)
    return res, perimeter


def _closed_loop(g: _Samples, f: int, p: OutlineParams, half: int) -> tuple[FloatArray, BoolArray]:
    """Relevant points of an outline without corners (a closed curve)."""
    out_pts: list[FloatArray] = []
    out_curve: list[bool] = []
    _emit_run(
        g.res[f],
        g.turning(f),
        np.arange(g.res.shape[1]),
        p=p,
        noise=float(g.noise[f]),
        out_pts=out_pts,
        out_curve=out_curve,
        closed_loop=True,
        guard=half,
    )
    return np.array(out_pts, dtype=np.float64), np.array(out_curve, dtype=bool)


def _polylines(  # noqa: PLR0914
    g: _Samples,
    corners: list[np.ndarray],
    p: OutlineParams,
    windows: tuple[int, int],
    frame: tuple[FloatArray, FloatArray, FloatArray] | None = None,
) -> list[tuple[FloatArray, BoolArray]]:
    """Relevant points of every outline: all runs' chord tests and line fits at once.

    Each outline's samples are rotated so that its first corner is sample 0; run r covers
    samples ``c[r] .. c[r + 1]`` (the last one ends at sample n = sample 0). Straight runs
    emit their corner; curved runs, and outlines without corners, go through `_emit_run`.
    ``windows`` is (smoothing half-width, corner window) in samples; ``frame`` (moments, mean,
    scale) the outlines' summed moments when already known (`qshape.outline.fit.outline_moments`).
    """
    half, w = windows
    count, n = g.res.shape[:2]
    empty = (np.zeros((0, 2)), np.zeros(0, dtype=bool))
    results: list[tuple[FloatArray, BoolArray]] = [empty] * count
    with_c: list[int] = []
    for f in range(count):
        if g.skip[f]:
            continue
        if len(corners[f]):
            with_c.append(f)
        else:
            results[f] = _closed_loop(g, f, p, half)
    if not with_c:
        return results
    fo = np.array(with_c)
    m = np.array([len(corners[f]) for f in with_c])  # runs per outline
    c0 = np.array([int(corners[f][0]) for f in with_c])
    starts = np.concatenate([corners[f] - corners[f][0] for f in with_c])  # local
    owner = np.repeat(np.arange(len(fo)), m)  # row of fo of each run
    first_run = np.concatenate([[0], np.cumsum(m)[:-1]])
    last_run = first_run + m - 1
    ends = np.append(starts[1:], 0)
    ends[last_run] = n
    # Gathers with np.take, x and y apart: numpy handles (k, 2) rows far slower.
    at = (fo * n)[:, None] + (c0[:, None] + np.arange(n + 1)[None, :]) % n
    rx, ry = np.take(g.planes[0], at), np.take(g.planes[1], at)  # rolled samples (G, n + 1)
    i0, i1 = owner * (n + 1) + starts, owner * (n + 1) + ends
    ax, ay = np.take(rx, i0), np.take(ry, i0)
    chx, chy = np.take(rx, i1) - ax, np.take(ry, i1) - ay
    length = np.hypot(chx, chy)
    # Every sample of every run (its start included, its end left out: distance 0 there):
    # the runs of an outline tile its samples 0 .. n - 1 in order.
    lens = ends - starts
    seg_start = np.concatenate([[0], np.cumsum(lens)[:-1]])
    rel_x = rx[:, :n].ravel() - np.repeat(ax, lens)
    rel_y = ry[:, :n].ravel() - np.repeat(ay, lens)
    dev = np.abs(np.repeat(chx, lens) * rel_y - np.repeat(chy, lens) * rel_x)
    dev_max = np.maximum.reduceat(dev, seg_start)
    zero = length == 0.0
    if zero.any():  # degenerate chord: distance from the run's start
        dist0 = np.maximum.reduceat(np.hypot(rel_x, rel_y), seg_start)
        dev_max = np.where(zero, dist0, dev_max / np.where(zero, 1.0, length))
    else:
        dev_max = dev_max / length
    straight = dev_max <= np.maximum(p.straight_sagitta_ratio * length, g.noise[fo][owner])
    points = np.stack([ax, ay], axis=1)
    if p.refine_corners:
        prev = np.arange(len(starts)) - 1
        prev[first_run] = last_run
        _refine_all(
            (rx, ry),
            (owner, starts, ends, prev),
            straight & (m >= 2)[owner],
            points,
            trim=max(1, round(p.refine_trim_fraction * n)) if p.refine_trim_fraction > 0.0 else w,
            reach=p.corner_window * g.perimeter[fo],
            min_sin=math.sin(math.radians(p.corner_angle_deg)),
            fitted=None if frame is None else _Moments(frame[0], fo, c0, frame[1], frame[2]),
        )
    all_straight = np.logical_and.reduceat(straight, first_run).tolist()
    bounds = (first_run + m).tolist()
    for row, f in enumerate(with_c):
        r0, r1 = bounds[row] - int(m[row]), bounds[row]
        if all_straight[row]:
            results[f] = (points[r0:r1], np.zeros(r1 - r0, dtype=bool))
            continue
        turn = g.turning(f)
        out_pts: list[FloatArray] = []
        out_curve: list[bool] = []
        for r in range(r0, r1):
            if straight[r]:
                out_pts.append(points[r])
                out_curve.append(False)
                continue
            idx = (np.arange(int(starts[r]), int(ends[r]) + 1) + int(c0[row])) % n
            _emit_run(
                g.res[f],
                turn,
                idx,
                p=p,
                noise=float(g.noise[f]),
                out_pts=out_pts,
                out_curve=out_curve,
                closed_loop=False,
                guard=half,
            )
        results[f] = (np.array(out_pts, dtype=np.float64), np.array(out_curve, dtype=bool))
    return results


@functools.cache
def _circular_band(n: int, spacing: int) -> BoolArray:
    """(n, n) read-only: row i marks the samples within ``spacing`` of sample i, circularly."""
    d = np.abs(np.arange(n)[None, :] - np.arange(n)[:, None])
    band: BoolArray = np.minimum(d, n - d) <= spacing
    band.setflags(write=False)
    return band


def _corners_many(change: FloatArray, threshold: float, spacing: int) -> list[np.ndarray]:
    """Corners of each row of ``change`` (F, n), all rows at once.

    Greedy, as the slope comparison wants: the strongest remaining sample above ``threshold``
    (the first of equal values) is a corner, and the samples within ``spacing`` of it
    (circularly) are no longer candidates. Each round does this for every row.
    """
    count, n = change.shape
    above = change > threshold
    rows = np.flatnonzero(above.any(axis=1))  # rows still holding a candidate
    vals = np.where(above[rows], change[rows], -np.inf)
    band = _circular_band(n, spacing)
    found_rows: list[np.ndarray] = []
    found_at: list[np.ndarray] = []
    while len(rows):
        i = np.argmax(vals, axis=1)
        live = np.take(vals, i + n * np.arange(len(rows))) > -np.inf  # vals[r, i[r]]
        if not live.all():
            rows, vals, i = rows[live], vals[live], i[live]
            if len(rows) == 0:
                break
        found_rows.append(rows)
        found_at.append(i)
        np.copyto(vals, -np.inf, where=np.take(band, i, axis=0))
    if not found_rows:
        return [np.zeros(0, dtype=np.int64) for _ in range(count)]
    row = np.concatenate(found_rows)
    at = np.concatenate(found_at).astype(np.int64)
    order = np.lexsort((at, row))
    ends = np.cumsum(np.bincount(row, minlength=count)).tolist()
    flat = at[order]
    return [flat[a:b] for a, b in zip([0, *ends[:-1]], ends, strict=True)]  # np.split, faster


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
    if not closed_loop and _straight_within(run, p.straight_sagitta_ratio, noise):
        out_pts.append(run[0])
        out_curve.append(False)
        return True
    if not closed_loop and p.missed_corner_ratio > 0.0 and len(run) >= 5:
        k = int(np.argmax(_chord_distance(run)))
        if 0 < k < len(run) - 1 and all(
            _straight_within(half_run, p.missed_corner_ratio, noise)
            for half_run in (run[: k + 1], run[k:])
        ):
            out_pts.extend((run[0], run[k]))
            out_curve.extend((False, False))
            return False
    pieces = max(1, math.ceil(total / p.max_curve_turn_deg))
    if closed_loop:
        pieces = max(pieces, 2)
    if closed_loop:
        # A closed curve has no natural split point: equal arc lengths (the samples are
        # uniform in arc length). Equal turning would put the split where the outline's
        # noise puts it: a traced circle would come out as two unequal arcs, labelled
        # acute and plane instead of semicircle.
        bounds = [round(k * (len(idx) - 1) / pieces) for k in range(pieces + 1)]
    else:
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


def _refine_all(
    rolled: tuple[FloatArray, FloatArray],
    runs: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    straight: BoolArray,
    points: FloatArray,
    *,
    trim: int,
    reach: FloatArray,
    min_sin: float,
    fitted: _Moments | None = None,
) -> None:
    """Move each corner between two straight runs to the intersection of their fitted lines.

    Smoothing and the sample spacing round a corner off; the lines through the middles of the
    adjacent edges meet at the true corner. Kept only when the lines cross at a corner angle
    (sine of the angle between them >= ``min_sin``) within ``reach`` of the detected corner.
    Lines are total-least-squares fits of each run (its ends trimmed by ``trim`` samples when
    long enough), all runs of all outlines at once from prefix sums. ``rolled``: x and y of
    each outline's samples from its first corner on, (G, n + 1) each. ``runs`` is (owner,
    starts, ends, prev): run r covers samples ``starts[r] .. ends[r]`` of row ``owner[r]``,
    ``prev[r]`` is the run before it; ``points[r]`` (its corner) is updated in place.
    ``fitted``: the outlines' moments when already summed (the same fits, without summing
    again).
    """
    owner, starts, ends, prev = runs
    both = straight & straight[prev]
    if not both.any():
        return
    long = ends - starts + 1 > 2 * trim + 2
    lo = np.where(long, starts + trim, starts)
    hi = np.where(long, ends - trim + 1, ends + 1)  # exclusive
    cnt = (hi - lo).astype(np.float64)
    if fitted is None:
        xy = np.stack(rolled, axis=-1)  # (G, n + 1, 2)
        origin = xy[:, 0, :]
        q = xy - origin[:, None, :]
        x, y = q[..., 0], q[..., 1]
        sums = np.zeros((q.shape[0], q.shape[1] + 1, 5))
        np.cumsum(np.stack([x, y, x * x, x * y, y * y], axis=-1), axis=1, out=sums[:, 1:])
        tot = sums[owner, hi] - sums[owner, lo]
        unit = np.ones(len(owner))
    else:
        g, first = fitted.rows[owner], fitted.first[owner]
        tot = range_sums(fitted.moments, g, first + lo, first + hi)[:, 1:6]
        origin, unit = fitted.mean, fitted.scale[g]
        owner = g
    mx, my = tot[:, 0] / cnt, tot[:, 1] / cnt
    sxx = tot[:, 2] - cnt * mx * mx
    sxy = tot[:, 3] - cnt * mx * my
    syy = tot[:, 4] - cnt * my * my
    phi = 0.5 * np.arctan2(2.0 * sxy, sxx - syy)  # principal direction of each run
    dx, dy = np.cos(phi), np.sin(phi)
    pdx, pdy, pmx, pmy = dx[prev], dy[prev], mx[prev], my[prev]
    den = pdx * dy - pdy * dx
    ok = both & (np.abs(den) >= min_sin)
    safe = np.where(ok, den, 1.0)
    t = ((mx - pmx) * dy - (my - pmy) * dx) / safe
    cx = (pmx + t * pdx) * unit + origin[owner, 0]
    cy = (pmy + t * pdy) * unit + origin[owner, 1]
    ok &= np.hypot(cx - points[:, 0], cy - points[:, 1]) <= reach[runs[0]]
    points[ok, 0] = cx[ok]
    points[ok, 1] = cy[ok]


def _straight_within(run: FloatArray, ratio: float, noise: float) -> bool:
    """``run`` stays within ``ratio`` x its chord (or ``noise``) of its chord."""
    chord = float(np.hypot(*(run[-1] - run[0])))
    return float(_chord_distance(run).max(initial=0.0)) <= max(ratio * chord, noise)


def _chord_distance(run: FloatArray) -> FloatArray:
    """Distance of each point of a run from the chord joining its ends (or from its start)."""
    chord = run[-1] - run[0]
    length = float(np.hypot(*chord))
    rel = run - run[0]
    if length == 0.0:
        return np.asarray(np.hypot(rel[:, 0], rel[:, 1]))
    return np.asarray(np.abs(cross2(np.broadcast_to(chord, rel.shape), rel)) / length)


__all__ = ["OutlineParams", "default_outline_params", "simplify_outline", "simplify_outlines"]
