"""The runs between corners as relevant points.

Straight runs give their corner, curved ones their maximum-curvature points (split into pieces
that turn at most `OutlineParams.max_curve_turn_deg`); a corner between two straight runs moves
to where their fitted lines meet.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from qshape.geometry import BoolArray, FloatArray, cross2
from qshape.outline.fit import (
    range_sums,
)
from qshape.outline.params import OutlineParams
from qshape.outline.samples import Moments, Samples


def _closed_loop(g: Samples, f: int, p: OutlineParams, half: int) -> tuple[FloatArray, BoolArray]:
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


@dataclass(frozen=True)
class _Runs:
    """The runs of the outlines that have corners, all in flat arrays.

    Each outline's samples are rotated so that its first corner is sample 0; run r covers
    samples ``starts[r] .. ends[r]`` of row ``owner[r]`` (the last one ends at sample n =
    sample 0).

    Attributes:
        outlines: The outlines with corners (their index f). fo: The same as an array (G,).
        m: (G,) runs per outline. c0: (G,) each outline's first corner (sample index).
        starts, ends: (R,) first and last sample of each run, local to its rolled outline.
        owner: (R,) row of ``fo`` of each run. first_run, last_run: (G,) each row's runs.
    """

    outlines: list[int]
    fo: np.ndarray
    m: np.ndarray
    c0: np.ndarray
    starts: np.ndarray
    ends: np.ndarray
    owner: np.ndarray
    first_run: np.ndarray
    last_run: np.ndarray

    @classmethod
    def of(cls, corners: list[np.ndarray], with_c: list[int], n: int) -> _Runs:
        """The runs of outlines ``with_c`` (each with at least one corner) of n samples."""
        fo = np.array(with_c)
        m = np.array([len(corners[f]) for f in with_c])  # runs per outline
        c0 = np.array([int(corners[f][0]) for f in with_c])
        starts = np.concatenate([corners[f] - corners[f][0] for f in with_c])  # local
        owner = np.repeat(np.arange(len(fo)), m)  # row of fo of each run
        first_run = np.concatenate([[0], np.cumsum(m)[:-1]])
        last_run = first_run + m - 1
        ends = np.append(starts[1:], 0)
        ends[last_run] = n
        return cls(with_c, fo, m, c0, starts, ends, owner, first_run, last_run)


def polylines(
    g: Samples,
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
    runs = _Runs.of(corners, with_c, n)
    # Gathers with np.take, x and y apart: numpy handles (k, 2) rows far slower.
    at = (runs.fo * n)[:, None] + (runs.c0[:, None] + np.arange(n + 1)[None, :]) % n
    rx, ry = np.take(g.planes[0], at), np.take(g.planes[1], at)  # rolled samples (G, n + 1)
    straight, points = _chord_tests(g, p, runs, (rx, ry))
    if p.refine_corners:
        prev = np.arange(len(runs.starts)) - 1
        prev[runs.first_run] = runs.last_run
        _refine_all(
            (rx, ry),
            (runs.owner, runs.starts, runs.ends, prev),
            straight & (runs.m >= 2)[runs.owner],
            points,
            trim=max(1, round(p.refine_trim_fraction * n)) if p.refine_trim_fraction > 0.0 else w,
            reach=p.corner_window * g.perimeter[runs.fo],
            min_sin=math.sin(math.radians(p.corner_angle_deg)),
            fitted=None
            if frame is None
            else Moments(frame[0], runs.fo, runs.c0, frame[1], frame[2]),
        )
    _emit_outlines(g, p, runs, (straight, points), half, results)
    return results


def _chord_tests(
    g: Samples, p: OutlineParams, runs: _Runs, rolled: tuple[FloatArray, FloatArray]
) -> tuple[BoolArray, FloatArray]:
    """Which runs are straight (R,), and each run's first corner (R, 2), all runs at once.

    ``rolled``: x and y of each outline's samples from its first corner on, (G, n + 1) each.
    """
    rx, ry = rolled
    n = rx.shape[1] - 1
    owner, starts, ends = runs.owner, runs.starts, runs.ends
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
    straight = dev_max <= np.maximum(p.straight_sagitta_ratio * length, g.noise[runs.fo][owner])
    return straight, np.stack([ax, ay], axis=1)


def _emit_outlines(  # noqa: PLR0917
    g: Samples,
    p: OutlineParams,
    runs: _Runs,
    tested: tuple[BoolArray, FloatArray],
    half: int,
    results: list[tuple[FloatArray, BoolArray]],
) -> None:
    """Relevant points of each outline with corners (in place in ``results``).

    ``tested``: (straight (R,), corner points (R, 2)) of `_chord_tests` (corners refined).
    """
    straight, points = tested
    n = g.res.shape[1]
    all_straight = np.logical_and.reduceat(straight, runs.first_run).tolist()
    bounds = (runs.first_run + runs.m).tolist()
    for row, f in enumerate(runs.outlines):
        r0, r1 = bounds[row] - int(runs.m[row]), bounds[row]
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
            idx = (np.arange(int(runs.starts[r]), int(runs.ends[r]) + 1) + int(runs.c0[row])) % n
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
    if not closed_loop and straight_within(run, p.straight_sagitta_ratio, noise):
        out_pts.append(run[0])
        out_curve.append(False)
        return True
    if not closed_loop and p.missed_corner_ratio > 0.0 and len(run) >= 5:
        k = int(np.argmax(_chord_distance(run)))
        if 0 < k < len(run) - 1 and all(
            straight_within(half_run, p.missed_corner_ratio, noise)
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
    fitted: Moments | None = None,
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


def straight_within(run: FloatArray, ratio: float, noise: float) -> bool:
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


__all__ = ["polylines", "straight_within"]
