"""Corners from fits: drop the corners of a closed outline that one line or one arc explains.

The window measure of `qshape.outline.simplify` proposes corners from local turning, which a rough
edge
fools: a bump becomes a corner. Here every run between proposed corners is fitted by a straight
line (total least squares) and by a circle arc (algebraic fit), and a corner is dropped when the
two runs beside it fit *one* line, or one arc, about as well as they fit two: the increase of
the squared residual is compared with the outline's own measured roughness (its variance times
``fit_merge_chi2``). An arc is tried only where one of the two runs is itself significantly
curved, so the shallow real corners of a polygon are never rounded away into an arc. The fits of
any run come in constant time from prefix sums of the samples' moments. A run that two lines
meeting at a real corner fit better than its arc (a corner the window measure missed, or
placed off) is bent, not curved: it never lets an arc absorb its neighbours' corners, and it
gets its corner back where the two lines meet best. Last, an outline whose corners one circle
makes unnecessary (a rough circle cut into pieces) loses them all.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qshape.geometry import FloatArray

_MIN_ARC_SAMPLES = 5
"""Runs with fewer samples are fitted by a line only (an arc through them says nothing)."""

_SINGULAR = 1e-9
"""Circle fits whose normal equations' determinant is below this x sxx syy n are lines."""


def outline_moments(res: FloatArray, scale: FloatArray) -> FloatArray:
    """Prefix sums of the moments of closed outlines, shape (9, F, n + 1): one plane per moment.

    Planes: x, y, x x, x y, y y, z, z x, z y, z z with z = x x + y y, of each outline's
    samples centred on their mean and divided by its ``scale`` (well conditioned sums).
    Samples ``[i, j)`` of outline f walked twice round (0 <= i <= j <= 2 n) are summed by
    `range_sums`. Moment-major planes: numpy sums along contiguous rows many times faster
    than along an axis whose inner axis is only 9 wide (the same sums, in the same order).

    Args:
        res: Samples of F closed outlines, shape (F, n, 2).
        scale: Length unit of each outline's moments (e.g. its diameter), shape (F,), > 0.
    """
    mean = res.mean(axis=1)
    unit = scale[:, None]
    out = np.zeros((9, res.shape[0], res.shape[1] + 1))
    planes = out[:, :, 1:]
    x, y = planes[0], planes[1]
    np.divide(res[..., 0] - mean[:, 0:1], unit, out=x)
    np.divide(res[..., 1] - mean[:, 1:2], unit, out=y)
    np.multiply(x, x, out=planes[2])
    np.multiply(x, y, out=planes[3])
    np.multiply(y, y, out=planes[4])
    np.add(planes[2], planes[4], out=planes[5])
    np.multiply(planes[5], x, out=planes[6])
    np.multiply(planes[5], y, out=planes[7])
    np.multiply(planes[5], planes[5], out=planes[8])
    np.cumsum(planes, axis=2, out=planes)
    return out


def _samples(moments: FloatArray) -> int:
    """Samples n of each outline whose `outline_moments` these are."""
    return int(moments.shape[2]) - 1


def prefix_at(moments: FloatArray, f: np.ndarray, i: np.ndarray) -> FloatArray:
    """Sums of samples ``[0, i)`` of outlines f walked twice round, shape (k, 10).

    Columns: count, then the planes of `outline_moments`; ``i`` in [0, 2 n]. The result is
    the transpose of a (10, k) array, so that each column is contiguous.
    """
    n = _samples(moments)
    over = i > n
    flat = moments.reshape(9, -1)
    out = np.empty((10, len(f)))
    out[0] = i
    # np.take of whole planes: numpy's fancy indexing of rows is several times slower.
    np.take(flat, f * (n + 1) + np.where(over, i - n, i), axis=1, out=out[1:])
    if over.any():
        at = np.flatnonzero(over)
        out[1:, at] += np.take(flat, np.take(f, at) * (n + 1) + n, axis=1)
    return out.T


def range_sums(moments: FloatArray, f: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> FloatArray:
    """Sums of samples ``[lo, hi)`` of outlines f (twice-round indices), shape (k, 10)."""
    k = len(f)
    at = prefix_at(moments, np.concatenate((f, f)), np.concatenate((hi, lo)))
    return at[:k] - at[k:]


def line_sse(s: FloatArray) -> FloatArray:
    """Squared residual of the total-least-squares line of each range, shape (k,).

    Args:
        s: `range_sums`, shape (k, 10). Result in units of the outline's ``scale`` squared
            (see `outline_moments`); 0 for fewer than 3 samples.
    """
    cnt = np.maximum(s[:, 0], 1.0)
    mx, my = s[:, 1] / cnt, s[:, 2] / cnt
    cxx = s[:, 3] - cnt * mx * mx
    cxy = s[:, 4] - cnt * mx * my
    cyy = s[:, 5] - cnt * my * my
    half = 0.5 * (cxx + cyy)
    lam = half - np.sqrt(np.maximum(0.25 * (cxx - cyy) ** 2 + cxy * cxy, 0.0))
    return np.asarray(np.maximum(lam, 0.0))


def arc_sse(s: FloatArray, line: FloatArray | None = None) -> FloatArray:
    """Squared geometric residual of the circle fitted to each range, shape (k,).

    Algebraic (Kasa) fit ``z + D x + E y + F = 0`` (normal equations solved by Cramer's
    rule); its algebraic residual divided by (2 r)^2 is the geometric one to first order.
    Never more than `line_sse` (a line is an arc of infinite radius, and a collinear range
    makes the equations singular); ranges under 5 samples get `line_sse`.

    Args:
        s: `range_sums`, shape (k, 10).
        line: `line_sse` of the same ranges when already known.
    """
    if line is None:
        line = line_sse(s)
    n, sx, sy, sxx, sxy, syy, sz, szx, szy, szz = s.T
    # M = [[sxx, sxy, sx], [sxy, syy, sy], [sx, sy, n]], M (D, E, F) = -(szx, szy, sz).
    c00 = syy * n - sy * sy
    c01 = sx * sy - sxy * n
    c02 = sxy * sy - syy * sx
    c11 = sxx * n - sx * sx
    c12 = sxy * sx - sxx * sy
    c22 = sxx * syy - sxy * sxy
    det = sxx * c00 + sxy * c01 + sx * c02
    ok = (n >= _MIN_ARC_SAMPLES) & (np.abs(det) > _SINGULAR * np.maximum(sxx * syy * n, 1e-300))
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    d = -(c00 * szx + c01 * szy + c02 * sz) * inv
    e = -(c01 * szx + c11 * szy + c12 * sz) * inv
    g = -(c02 * szx + c12 * szy + c22 * sz) * inv
    alg = np.maximum(szz + d * szx + e * szy + g * sz, 0.0)
    r2 = 0.25 * (d * d + e * e) - g
    good = ok & (r2 > 0.0)
    geo = np.where(good, alg / np.where(good, 4.0 * r2, 1.0), np.inf)
    return np.asarray(np.minimum(geo, line))


def _line_angles(s: FloatArray) -> FloatArray:
    """Direction [rad] of the total-least-squares line of each range (`range_sums`), (k,).

    Unsigned: in (-pi / 2, pi / 2].
    """
    cnt = np.maximum(s[:, 0], 1.0)
    mx, my = s[:, 1] / cnt, s[:, 2] / cnt
    cxy = s[:, 4] - cnt * mx * my
    spread = (s[:, 3] - cnt * mx * mx) - (s[:, 5] - cnt * my * my)
    return np.asarray(0.5 * np.arctan2(2.0 * cxy, spread))


def _line_directions(s: FloatArray) -> FloatArray:
    """Unit direction of the total-least-squares line of each range, shape (k, 2), unsigned."""
    phi = _line_angles(s)
    return np.stack([np.cos(phi), np.sin(phi)], axis=1)


@dataclass(frozen=True)
class BendTest:
    """When a run between corners is two straight edges meeting at a corner, not one arc.

    Attributes:
        min_turn_deg: The two lines' directions differ by at least this, in [deg] (> 0): a
            real corner, never the gentle bend of a rough edge or of a short arc piece.
        arm: Fewest samples on each side of the split (the corner spacing: a split nearer a
            run's end would sit on that end's corner).
    """

    min_turn_deg: float
    arm: int


def bent_runs(
    moments: FloatArray, f: np.ndarray, lo: np.ndarray, hi: np.ndarray, test: BendTest
) -> tuple[np.ndarray, np.ndarray]:
    """Runs ``[lo, hi)`` of outlines f (twice-round indices) that two lines fit better than one.

    Every sample at least ``test.arm`` from both ends is tried as the split; the run is bent
    when the best split's two total-least-squares lines fit it with a smaller squared
    residual than its own best fit (arc or line, `arc_sse`) and their directions differ by at
    least ``test.min_turn_deg``. The two models have about as many parameters (an arc 3, two
    lines 4 and the split), so the comparison needs no margin; the turn is what keeps arcs
    whole: two chords meeting at 45 deg stand for an arc turning 90 deg, whose chords bow
    from it by 8 % of its radius, far above what its arc leaves, and a shorter arc piece
    turns too little. A straight run has no turn. Cost linear in the runs' total length (one
    call per fit for all candidate splits).

    Returns:
        (bent (k,) bool, split (k,) sample index of the best split, twice-round; ``lo`` where
        the run is too short to split).
    """
    k = len(f)
    room = np.maximum(hi - lo - 2 * test.arm + 1, 0)
    split = lo.copy()
    bent = np.zeros(k, dtype=bool)
    total = int(room.sum())
    if total == 0:
        return bent, split
    run = np.repeat(np.arange(k), room)
    pos = np.arange(total) - np.repeat(np.cumsum(room) - room, room)  # candidate of its run
    s = lo[run] + test.arm + pos
    ends = prefix_at(moments, np.concatenate((f, f)), np.concatenate((lo, hi)))
    at = prefix_at(moments, f[run], s)
    halves = np.concatenate((at - ends[:k][run], ends[k:][run] - at))  # first, then second
    fits = line_sse(halves)
    grid = np.full((k, int(room.max())), np.inf)
    grid[run, pos] = fits[:total] + fits[total:]
    best = np.argmin(grid, axis=1)  # the cheapest split of each run (the first of equals)
    has = np.flatnonzero(room > 0)
    head = (np.cumsum(room) - room + best)[has]
    first, second = halves[:total], halves[total:]
    d1, d2 = _line_directions(first[head]), _line_directions(second[head])
    cnt1, cnt2 = np.maximum(first[head, 0], 1.0), np.maximum(second[head, 0], 1.0)
    step = second[head, 1:3] / cnt2[:, None] - first[head, 1:3] / cnt1[:, None]
    # Orient both lines along the walk (from the first half's centroid to the second's).
    d1 *= np.where((d1 * step).sum(axis=1) >= 0.0, 1.0, -1.0)[:, None]
    d2 *= np.where((d2 * step).sum(axis=1) >= 0.0, 1.0, -1.0)[:, None]
    turn = np.degrees(np.arccos(np.clip((d1 * d2).sum(axis=1), -1.0, 1.0)))
    split[has] = s[head]
    sharp = has[turn >= test.min_turn_deg]
    if len(sharp):  # only these can be bent: their own arcs fitted
        whole = arc_sse(ends[k:][sharp] - ends[:k][sharp])
        bent[sharp] = grid[sharp, best[sharp]] < whole
    return bent, split


@dataclass(frozen=True)
class _Ring:
    """Corners of many closed outlines, flat: outline f's are ``c[own == f]``, sorted.

    Attributes:
        c: Sample index of each corner, shape (k,). own: Its outline, shape (k,).
        prev, nxt: Index (into c) of the corner before and after it on its outline, (k,).
    """

    c: np.ndarray
    own: np.ndarray
    prev: np.ndarray
    nxt: np.ndarray

    @staticmethod
    def of(corners: list[np.ndarray], rows: np.ndarray) -> _Ring:
        """The corners of outlines ``rows`` (each sorted), flat."""
        counts = np.array([len(corners[f]) for f in rows.tolist()], dtype=np.int64)
        c = np.concatenate([np.asarray(corners[f], dtype=np.int64) for f in rows.tolist()])
        own = np.repeat(rows, counts)
        k = np.arange(len(c))
        first = np.repeat(np.cumsum(counts) - counts, counts)
        last = first + np.repeat(counts, counts) - 1
        return _Ring(c, own, np.where(k == first, last, k - 1), np.where(k == last, first, k + 1))

    def sides(self, n: int, trim: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Ranges of the runs before and after each corner: (lo, mid, hi), twice-round indices.

        Run before: ``[lo, mid)``, run after: ``[mid, hi)``; far ends trimmed by ``trim``
        samples (at most a quarter of the run). A lone pair of corners splits the walk in two.
        """
        len_a = (self.c - self.c[self.prev]) % n
        len_b = (self.c[self.nxt] - self.c) % n
        len_a[len_a == 0] = n
        len_b[len_b == 0] = n
        base = self.c[self.prev]
        lo = base + np.minimum(trim, len_a // 4)
        mid = base + len_a
        hi = mid + len_b - np.minimum(trim, len_b // 4)
        shift = np.where(lo >= n, n, 0)
        return lo - shift, mid - shift, hi - shift


def _side_fits(
    moments: FloatArray, f: np.ndarray, sides: tuple[np.ndarray, np.ndarray, np.ndarray]
) -> tuple[FloatArray, FloatArray]:
    """Line and arc residuals (3 k,) of the runs before, after and both beside k corners.

    ``f``: each corner's outline; ``sides``: (lo, mid, hi) sample bounds of `_Ring.sides`.
    """
    lo, mid, hi = sides
    k = len(f)
    # One call per fit over all ranges stacked (runs before, runs after, both): at a few
    # hundred corners numpy's cost is per call, not per element.
    at = prefix_at(moments, np.concatenate((f, f, f)), np.concatenate((lo, mid, hi)))
    s = np.empty((3 * k, 10))
    np.subtract(at[k:], at[:-k], out=s[: 2 * k])  # runs before, then runs after
    np.add(s[:k], s[k : 2 * k], out=s[2 * k :])  # both runs
    line = line_sse(s)
    arc = arc_sse(s, line)  # the union's arc is used only where a run is curved
    return line, arc


def _unbend(  # noqa: PLR0917
    moments: FloatArray,
    f: np.ndarray,
    sides: tuple[np.ndarray, np.ndarray, np.ndarray],
    curved: tuple[np.ndarray, np.ndarray],
    trim: int,
    bend: BendTest,
) -> tuple[np.ndarray, np.ndarray]:
    """Curved runs beside the corners that are two edges instead are no longer curved.

    ``curved``: (run before curved, run after curved) per corner, updated in place. Returns
    the corners whose run before is bent and that run's best split (sample index).
    """
    lo, mid, hi = sides
    curved_a, curved_b = curved
    ia, ib = np.flatnonzero(curved_a), np.flatnonzero(curved_b)
    # Near ends trimmed too: the corner's own rounding stays out of the split's lines.
    cut_a = np.minimum(trim, (mid[ia] - lo[ia]) // 4)
    cut_b = np.minimum(trim, (hi[ib] - mid[ib]) // 4)
    bent, split = bent_runs(
        moments,
        np.concatenate((f[ia], f[ib])),
        np.concatenate((lo[ia], mid[ib] + cut_b)),
        np.concatenate((mid[ia] - cut_a, hi[ib])),
        bend,
    )
    split_at, split = ia[bent[: len(ia)]], split[: len(ia)][bent[: len(ia)]]
    curved_a[split_at] = False
    curved_b[ib[bent[len(ia) :]]] = False
    return split_at, split


def merge_fitted_corners(  # noqa: PLR0913, PLR0917
    moments: FloatArray,
    corners: list[np.ndarray],
    rows: np.ndarray,
    limit: FloatArray,
    trim: int,
    min_corners: int = 2,
    bend: BendTest | None = None,
) -> dict[int, np.ndarray]:
    """Drop, in place, the corners of outlines ``rows`` that the runs beside them do not need.

    For each corner, the runs before and after it (far ends trimmed by ``trim`` samples, so a
    neighbouring corner's rounding stays out) are fitted apart and together. The cost of
    dropping it is the increase of the squared residual when fitted together by a line or,
    when one of the runs is itself curved (its arc fit beats its line fit by more than
    ``limit``, and with ``bend`` it is not `bent_runs`: two edges meeting at a corner the
    window measure missed also beat one line), by an arc. Each round drops, on every outline,
    its cheapest corner while that cost is at most ``limit`` and more than ``min_corners``
    corners remain; rounds repeat until none is dropped. All outlines at once.

    Args:
        moments: `outline_moments` of all outlines, shape (9, F, n + 1).
        corners: Sorted sample indices of each outline's corners; entries of ``rows`` are
            replaced.
        rows: Outlines to treat, shape (r,).
        limit: Per outline, the largest residual increase that drops a corner, in its
            ``scale`` squared (threshold x roughness variance), shape (F,).
        trim: Samples left out at the far end of each run.
        min_corners: Never fewer corners than this.
        bend: When a curved run is two straight edges instead (None: never).

    Returns:
        The corners the bent runs between each outline's final corners would get back
        (their best splits, sample indices, sorted), by outline; not inserted, so that the
        caller can first ask whether the outline is a closed curve (`circle_outlines`).
    """
    n = _samples(moments)
    rows = np.asarray([f for f in rows.tolist() if len(corners[f]) > min_corners], dtype=np.int64)
    splits: dict[int, list[int]] = {}  # corners given back to bent runs, per outline
    while len(rows):
        ring = _Ring.of(corners, rows)
        lo, mid, hi = ring.sides(n, trim)
        f = ring.own
        k = len(f)
        line, arc = _side_fits(moments, f, (lo, mid, hi))
        la, lb = line[:k], line[k : 2 * k]
        aa, ab = arc[:k], arc[k : 2 * k]
        lim = limit[f]
        curved_a, curved_b = la - aa > lim, lb - ab > lim
        split_at = split = np.zeros(0, dtype=np.int64)  # corners whose run before is bent
        if bend is not None and (curved_a.any() or curved_b.any()):
            split_at, split = _unbend(moments, f, (lo, mid, hi), (curved_a, curved_b), trim, bend)
        curved = curved_a | curved_b
        union = np.where(curved, arc[2 * k :], line[2 * k :])
        cost = union - aa - ab  # arc_sse <= line_sse: each run's best fit
        order = np.lexsort((cost, f))  # by outline, cheapest first
        head = order[np.r_[True, f[order][1:] != f[order][:-1]]]
        drop = head[cost[head] <= lim[head]]
        changed = np.unique(f[drop])
        # An outline that keeps its corners this round is final: its bent runs' splits hold.
        moved = set(changed.tolist())
        for g, at_ in zip(f[split_at].tolist(), (split % n).tolist(), strict=True):
            if g not in moved:
                splits.setdefault(g, []).append(at_)
        if len(drop) == 0:
            break
        keep = np.ones(len(f), dtype=bool)
        keep[drop] = False
        for g in changed.tolist():
            corners[g] = ring.c[keep & (f == g)]
        rows = np.asarray(
            [g for g in changed.tolist() if len(corners[g]) > min_corners], dtype=np.int64
        )
    return {g: np.sort(np.asarray(extra, dtype=np.int64)) for g, extra in splits.items()}


def circle_outlines(
    moments: FloatArray, corners: list[np.ndarray], rows: np.ndarray, limit: FloatArray
) -> np.ndarray:
    """Outlines of ``rows`` whose corners one circle makes unnecessary, shape (c,).

    The whole outline's circle fit is compared with the best fits (line or arc) of its runs
    between corners: when it is at most ``limit`` worse, no corner is needed (a rough circle
    whose bumps became corners).
    """
    n = _samples(moments)
    rows = np.asarray([f for f in rows.tolist() if len(corners[f]) >= 1], dtype=np.int64)
    if len(rows) == 0:
        return rows
    ring = _Ring.of(corners, rows)
    lo = ring.c
    hi = lo + (ring.c[ring.nxt] - ring.c) % n
    hi = np.where(hi == lo, lo + n, hi)
    k = len(lo)
    # The runs and the whole outlines fitted in one call (numpy's cost is per call here).
    fits = arc_sse(
        range_sums(
            moments,
            np.concatenate((ring.own, rows)),
            np.concatenate((lo, np.zeros(len(rows), dtype=np.int64))),
            np.concatenate((hi, np.full(len(rows), n, dtype=np.int64))),
        )
    )
    parts, whole = fits[:k], fits[k:]
    total = np.bincount(np.searchsorted(rows, ring.own), parts, minlength=len(rows))
    return np.asarray(rows[whole <= total + limit[rows]])


def flat_corner_outlines(
    moments: FloatArray, corners: list[np.ndarray], min_deg: float, trim: int
) -> np.ndarray:
    """Outlines with a corner whose runs' fitted lines (unoriented) meet below ``min_deg``.

    A cheap superset (an unoriented line cannot tell a flat corner from a hairpin) of the
    outlines with a corner between two nearly collinear runs: runs trimmed by ``trim``
    samples at both ends, directions from the moments, all outlines with 4 or more corners
    at once.
    """
    n = _samples(moments)
    rows = np.asarray([f for f, c in enumerate(corners) if len(c) > 3], dtype=np.int64)  # noqa: PLR2004
    if len(rows) == 0:
        return rows
    ring = _Ring.of(corners, rows)
    length = (ring.c[ring.nxt] - ring.c) % n
    cut = np.minimum(trim, length // 4)
    phi = _line_angles(range_sums(moments, ring.own, ring.c + cut, ring.c + length - cut))
    # Run i follows corner i; corner i sits between run prev(i) and run i.
    diff = np.abs(phi - phi[ring.prev]) % np.pi
    ang = np.degrees(np.minimum(diff, np.pi - diff))
    return np.asarray(np.unique(ring.own[ang < min_deg]))


__all__ = [
    "BendTest",
    "arc_sse",
    "bent_runs",
    "circle_outlines",
    "flat_corner_outlines",
    "line_sse",
    "merge_fitted_corners",
    "outline_moments",
    "prefix_at",
    "range_sums",
]
