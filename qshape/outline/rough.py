"""Corners of rough edges: the outline's own roughness, and corners kept only where fits need them.

A chipped, ground tile traced by a camera has bumps a window measure takes for corners. The
roughness of each outline is measured from the outline itself; a proposed corner stays only where
the runs beside it need two lines (or arcs) rather than one (`qshape.outline.fit`), and corners
between straight runs meeting too flat (`OutlineParams.min_corner_deg`) are dropped.
"""

from __future__ import annotations

import math

import numpy as np

from qshape.geometry import BoolArray, FloatArray
from qshape.outline.fit import (
    BendTest,
    circle_outlines,
    merge_fitted_corners,
)
from qshape.outline.params import OutlineParams
from qshape.outline.runs import straight_within
from qshape.outline.samples import norm, roll_last, row_medians


def corners_from_fits(  # noqa: PLR0913, PLR0917
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


def roughness(planes: FloatArray, w: int) -> tuple[FloatArray, FloatArray]:
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
    length = norm(chord[0], chord[1])
    rel = planes - a
    dist = (chord[0] * rel[1] - chord[1] * rel[0]) / np.maximum(length, 1e-12)
    k = min(2 * w, (n - 1) // 2)
    ext = np.concatenate([dist[:, -k:], dist, dist[:, :k]], axis=1)
    csum = np.zeros((planes.shape[1], n + 2 * k + 1))
    np.cumsum(ext, axis=1, out=csum[:, 1:])
    local = (csum[:, 2 * k + 1 :] - csum[:, :n]) / (2 * k + 1)
    detrended = dist - local
    sigma = _MAD_TO_SIGMA * row_medians(np.abs(detrended)) * math.sqrt(2.0 / 3.0)
    lag = (detrended * roll_last(detrended, 1)).sum(axis=1)
    rho = np.clip(lag / np.maximum((detrended * detrended).sum(axis=1), 1e-300), 0.0, _MAX_RHO)
    return np.asarray(sigma), np.asarray((1.0 + rho) / (1.0 - rho))


_MAX_RHO = 0.99
"""Largest lag-1 autocorrelation used (a correlation factor of at most 199 samples)."""


_MAD_TO_SIGMA = 1.4826
"""Median absolute deviation of a normal sample x this = its standard deviation."""


def with_flat_corners(
    res: FloatArray, corners: list[np.ndarray], min_deg: float, trim: int
) -> np.ndarray:
    """Outlines with a corner whose neighbouring runs' fitted lines meet below ``min_deg``.

    All runs of all outlines at once (prefix sums of the moments), straight or not: a
    superset of the outlines `verified_corners` changes.
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


def verified_corners(
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
            if straight_within(r, p.straight_sagitta_ratio, noise)
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


__all__ = ["corners_from_fits", "roughness", "verified_corners", "with_flat_corners"]
