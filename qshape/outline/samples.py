"""Outlines as uniform arc-length samples, a whole batch in one array, and array steps on them."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qshape.geometry import BoolArray, FloatArray


def norm(x: FloatArray, y: FloatArray) -> FloatArray:
    """Length of the vectors (x, y), elementwise, as ``np.hypot`` to a unit in the last place.

    About three times faster; coordinates are at most `MAX_COORDINATE`, so nothing overflows.
    """
    return np.asarray(np.sqrt(x * x + y * y))


def row_medians(a: FloatArray) -> FloatArray:
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


def roll_last(a: FloatArray, shift: int) -> FloatArray:
    """``np.roll(a, shift, axis=-1)``: the same values, in one concatenation.

    Several times faster than `np.roll` on the (F, n) and (2, F, n) arrays of a batch.
    """
    k = shift % a.shape[-1]
    return np.concatenate([a[..., a.shape[-1] - k :], a[..., : a.shape[-1] - k]], axis=-1)


@dataclass(frozen=True)
class Moments:
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
class Samples:
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


def resampled_many(pts: list[FloatArray], n: int) -> tuple[FloatArray, FloatArray]:
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
    seg[1:] = norm(d[:, 0], d[:, 1])
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


__all__ = ["Moments", "Samples", "norm", "resampled_many", "roll_last", "row_medians"]
