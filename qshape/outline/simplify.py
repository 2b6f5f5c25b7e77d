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

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from qshape.errors import InvalidFigureError
from qshape.geometry import MAX_COORDINATE, BoolArray, FloatArray
from qshape.outline.corners import FULL_TURN_OVER_WINDOWS, hole_windows, window_corners
from qshape.outline.fit import (
    flat_corner_outlines,
    outline_moments,
)
from qshape.outline.params import OutlineParams, default_outline_params
from qshape.outline.rough import corners_from_fits, roughness, verified_corners, with_flat_corners
from qshape.outline.rounding import closed_perimeter, merge_chamfers, snap_circles, with_chamfers
from qshape.outline.runs import polylines
from qshape.outline.samples import Samples, resampled_many, roll_last


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


@dataclass(frozen=True)
class _Frame:
    """Where a batch of resampled outlines lies.

    Attributes:
        planes: Samples as x and y planes, (2, F, n). mean: (F, 2) centres.
        centred: ``planes`` less each outline's centre, (2, F, n).
        diameter: (F,) largest extent along x or y. area2: (F,) twice the signed area.
        flat: (F,) outlines of (numerically) zero area. sign: (F,) +1 counter-clockwise.
    """

    planes: FloatArray
    mean: FloatArray
    centred: FloatArray
    diameter: FloatArray
    area2: FloatArray
    flat: BoolArray
    sign: FloatArray

    @property
    def unit(self) -> FloatArray:
        """(F,) each outline's diameter, 1 where it is 0 (the unit of its fits)."""
        return np.where(self.diameter > 0.0, self.diameter, 1.0)


def _frame(res: FloatArray) -> _Frame:
    """The `_Frame` of resampled outlines ``res`` (F, n, 2)."""
    # Sums along the samples run over x and y apart (2, F, n): numpy reduces an axis whose
    # inner axis has only two entries (the coordinates) many times slower.
    planes = np.ascontiguousarray(res.transpose(2, 0, 1))
    mean = planes.mean(axis=2).T  # (F, 2)
    centred = planes - mean.T[:, :, None]
    diameter = np.maximum(np.ptp(planes[0], axis=1), np.ptp(planes[1], axis=1))
    nxt = roll_last(centred, -1)
    area2 = (centred[0] * nxt[1] - centred[1] * nxt[0]).sum(axis=1)
    flat = (diameter <= 0.0) | (np.abs(area2) <= 1e-12 * diameter * diameter)
    sign = np.where(area2 > 0.0, 1.0, -1.0)  # +1: counter-clockwise in the given frame
    return _Frame(planes, mean, centred, diameter, area2, flat, sign)


def _smoothed(fr: _Frame, half: int) -> FloatArray:
    """Circular moving average over 2 ``half`` + 1 samples (prefix sums), planes (2, F, n)."""
    n = fr.planes.shape[2]
    width = 2 * half + 1
    centred = fr.centred
    padded = np.concatenate([centred[..., -half:], centred, centred[..., :half]], axis=2)
    csum = np.zeros((2, centred.shape[1], n + 2 * half + 1))
    np.cumsum(padded, axis=2, out=csum[..., 1:])
    return np.asarray((csum[..., width:] - csum[..., :-width]) / width + fr.mean.T[:, :, None])


def _hole_corners(  # noqa: PLR0917
    smooth_xy: FloatArray,
    fr: _Frame,
    p: OutlineParams,
    holes: dict[int, np.ndarray],
    spacing: int,
    corners: list[np.ndarray],
) -> None:
    """Corners of the holes measured over their own, wider windows (in place)."""
    n = p.resample_points
    for wh, rows in holes.items():
        # Over the hole's longer window the corner angle rises by the turning a circle adds
        # (`FULL_TURN_OVER_WINDOWS` x the extra fraction of the perimeter): a round hole's
        # steady turning stays below it as over ``corner_window``.
        extra = max(0.0, wh / n - p.corner_window)
        angle = p.corner_angle_deg + FULL_TURN_OVER_WINDOWS * extra
        found, _ = window_corners(smooth_xy[:, rows], wh, fr.flat[rows], p, angle, max(wh, spacing))
        for f, c in zip(rows.tolist(), found, strict=True):
            corners[f] = c


def _rough_edges(  # noqa: PLR0917
    fr: _Frame,
    p: OutlineParams,
    holes: dict[int, np.ndarray],
    windows: tuple[int, int, int],
    corners: list[np.ndarray],
) -> tuple[FloatArray, FloatArray | None]:
    """The chord noise floor (F,) with the edges' roughness, corners from fits (in place).

    ``windows``: (smoothing half-width, corner window, corner spacing) in samples. Also returns
    the outlines' moments (`qshape.outline.fit.outline_moments`) when fits were made, else None.
    """
    half, w, spacing = windows
    noise = p.noise_fraction * fr.diameter
    mom: FloatArray | None = None
    if p.roughness_sigmas > 0.0 or p.fit_merge_chi2 > 0.0:
        rough, corr = roughness(fr.planes, w)
        for wh, rows in holes.items():  # a hole's roughness over its own window
            rough[rows], corr[rows] = roughness(fr.planes[:, rows], wh)
        if p.roughness_sigmas > 0.0:
            noise = np.maximum(noise, p.roughness_sigmas * rough)
        if p.fit_merge_chi2 > 0.0:
            # The x/y planes seen as (F, n, 2): numpy then sums along contiguous memory.
            mom = outline_moments(fr.planes.transpose(1, 2, 0), fr.unit)
            corners_from_fits(
                mom, corners, p, rough * np.sqrt(corr), fr.diameter, fr.flat, (half, spacing)
            )
    return noise, mom


def _drop_flat_corners(  # noqa: PLR0917
    res: FloatArray,
    fr: _Frame,
    p: OutlineParams,
    noise: FloatArray,
    mom: FloatArray | None,
    half: int,
    corners: list[np.ndarray],
) -> None:
    """Corners between straight runs meeting below ``min_corner_deg`` dropped (in place)."""
    if mom is None:
        suspects = with_flat_corners(res, corners, p.min_corner_deg, half)
    else:
        suspects = flat_corner_outlines(mom, corners, p.min_corner_deg, half)
    for f in suspects.tolist():
        if not fr.flat[f]:
            corners[f] = verified_corners(res[f], corners[f], p, float(noise[f]), half)


def _merge_all_chamfers(
    results: list[tuple[FloatArray, BoolArray]], fraction: float, parents: list[int | None]
) -> None:
    """Cut-off corners merged (in place): outer outlines first, then holes at their size."""
    # Outer outlines first: a hole's limit is its parent's perimeter once merged.
    outer = [f for f in range(len(results)) if parents[f] is None]
    for f in with_chamfers(results, fraction, outer):
        points, mask = results[f]
        results[f] = merge_chamfers(points, mask, fraction)
    inner = [f for f in range(len(results)) if parents[f] is not None]
    if inner:
        scale = {
            f: max(closed_perimeter(results[f][0]), closed_perimeter(results[q][0]))
            for f in inner
            if (q := parents[f]) is not None
        }
        for f in with_chamfers(results, fraction, inner, list(scale.values())):
            points, mask = results[f]
            results[f] = merge_chamfers(points, mask, fraction, scale[f])


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
    res, perimeter = resampled_many(cleaned, n)  # (F, n, 2), (F,)
    fr = _frame(res)
    half = max(1, round(p.smooth_fraction * n))
    smooth_xy = _smoothed(fr, half)
    w = max(1, round(p.corner_window * n))
    spacing = max(w, round(p.merge_fraction * n))
    corners, ext = window_corners(smooth_xy, w, fr.flat, p, p.corner_angle_deg, spacing)
    holes = (
        hole_windows(p, perimeter, np.abs(fr.area2) / 2.0, parents, w)
        if p.hole_corner_window > 0.0
        else {}
    )
    _hole_corners(smooth_xy, fr, p, holes, spacing, corners)
    noise, mom = _rough_edges(fr, p, holes, (half, w, spacing), corners)
    if p.min_corner_deg > 0.0:
        _drop_flat_corners(res, fr, p, noise, mom, half, corners)
    ring = ext[..., w - 1 : w + n + 1].transpose(1, 2, 0)
    geom = Samples(
        res, fr.planes, smooth_xy.transpose(1, 2, 0), ring, fr.sign, noise, perimeter, fr.flat
    )
    frame = None if mom is None else (mom, fr.mean, fr.unit)
    results = polylines(geom, corners, p, (half, w), frame)
    if p.chamfer_fraction > 0.0:
        _merge_all_chamfers(results, p.chamfer_fraction, parents)
    if p.circle_residual > 0.0:
        snap_circles(res, fr.sign, results, p.circle_residual)
    for f, i in enumerate(slots):
        out[i] = _checked(results[f], names[f], bool(fr.flat[f]))


def _checked(
    result: tuple[FloatArray, BoolArray], what: str, flat: bool
) -> tuple[FloatArray, BoolArray] | InvalidFigureError:
    """One outline's result, or the error saying why it makes no figure."""
    if flat:
        return InvalidFigureError(f"{what}: zero area (the outline is a line or a point)")
    points, _ = result
    if len(points) < 3:  # noqa: PLR2004 (a figure's fewest points)
        return InvalidFigureError(
            f"{what}: simplified to {len(points)} relevant points; a figure needs at least 3"
        )
    return result


__all__ = ["simplify_outline", "simplify_outlines"]
