"""Corners by slope comparison: the direction change over a window, strongest first.

An outline's resampled, smoothed samples turn by more than `OutlineParams.corner_angle_deg` over
`OutlineParams.corner_window` at a corner; one corner is kept per window, strongest first. A hole
is measured over its own, wider window (`OutlineParams.hole_corner_window`).
"""

from __future__ import annotations

import functools

import numpy as np

from qshape.geometry import BoolArray, FloatArray
from qshape.outline.params import OutlineParams
from qshape.outline.samples import roll_last


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


def hole_windows(
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


def window_corners(  # noqa: PLR0917
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
    return corners_many(change, angle, spacing), ext


FULL_TURN_OVER_WINDOWS = 720.0
"""Direction change [deg] of a circle measured over windows of its whole perimeter per
unit of window fraction: 2 windows x 360 deg (a 3.25 % window: 23.4 deg)."""


def _excess_turning(change: FloatArray, w: int, arc_deg: float) -> FloatArray:
    """``change`` (F, n) less the turning beside each point that lies inside an arc.

    Each side's turning is the mean change 2 and 3 windows ``w`` away; where the smaller
    side turns by ``arc_deg`` or more, it is subtracted (see `OutlineParams.arc_turning_deg`).
    """
    before = roll_last(change, 2 * w) + roll_last(change, 3 * w)
    after = roll_last(change, -2 * w) + roll_last(change, -3 * w)
    side = 0.5 * np.minimum(before, after)
    return np.asarray(change - np.where(side >= arc_deg, side, 0.0))


@functools.cache
def _circular_band(n: int, spacing: int) -> BoolArray:
    """(n, n) read-only: row i marks the samples within ``spacing`` of sample i, circularly."""
    d = np.abs(np.arange(n)[None, :] - np.arange(n)[:, None])
    band: BoolArray = np.minimum(d, n - d) <= spacing
    band.setflags(write=False)
    return band


def corners_many(change: FloatArray, threshold: float, spacing: int) -> list[np.ndarray]:
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


__all__ = ["FULL_TURN_OVER_WINDOWS", "corners_many", "hole_windows", "window_corners"]
