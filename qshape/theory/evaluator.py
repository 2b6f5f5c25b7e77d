"""Vectorised matching of many descriptions at once: packs, the block evaluator, symmetries.

Descriptions with the same node count and hole signature are stacked into a `Pack`;
`evaluate_block` matches every candidate of one pack against every reference of another for
every cyclic offset in a few array operations (label compatibility, size and colour prefilter,
the 2D Procrustes alignment of all pairs as one matrix product, holes). `match` and `assign`
are built on it.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from qshape.geometry import FloatArray
from qshape.theory import labels as lb
from qshape.theory.pack import Pack, cone_bits, cyclic_compat, prefilter
from qshape.theory.rotation_fit import turn_sums
from qshape.theory.tolerances import Tolerances

_MAX_PERMUTED_HOLES = 4
"""Holes up to this count are paired by trying every permutation (4! = 24)."""


@dataclass(frozen=True)
class BlockResult:
    """Matching (candidate, reference, offset) entries of a block, ordered by (t, s, k).

    Attributes:
        ti: (P,) candidate index in the candidate pack.
        si: (P,) reference index in the reference pack.
        k: (P,) cyclic offset: reference node i corresponds to candidate node (i + k) % n.
        score: (P,) residual score (see `Match.score`).
        dot: (P,) sum of dot products of corresponding centred points.
        cross: (P,) sum of cross products; the rotation is atan2(cross, dot).
        hole_turn: (P,) `hole_turn_residuals` of each entry (0 without straight-edged holes).
    """

    ti: NDArray[np.int64]
    si: NDArray[np.int64]
    k: NDArray[np.int64]
    score: FloatArray
    dot: FloatArray
    cross: FloatArray
    hole_turn: FloatArray | None = None

    @property
    def theta(self) -> FloatArray:
        """(P,) rotation [rad] turning the candidate onto the reference, in (-pi, pi]."""
        return np.asarray(np.arctan2(self.cross, self.dot))


def _alignment_score(
    sumsq: FloatArray, dot: FloatArray, crs: FloatArray, norm: FloatArray
) -> FloatArray:
    """Residual of the best rotation of corresponding centred points, as `Match.score`.

    ``sumsq``: the two point sets' summed squared norms; ``dot``, ``crs``: their dot and cross
    sums under the correspondence; ``norm``: node count x the reference's area. The squared
    residual of the least-squares rotation is ``sumsq - 2 |(dot, crs)|``.
    """
    rss = sumsq - 2.0 * np.sqrt(dot * dot + crs * crs)
    return np.asarray(np.sqrt(np.maximum(rss, 0.0) / norm))


def evaluate_block(
    ref: Pack,
    cand: Pack,
    tol: Tolerances,
    use_color: bool,
    base: NDArray[np.bool_] | None = None,
    *,
    measured: bool = False,
) -> BlockResult:
    """Match every candidate against every reference of two packs, vectorised.

    Both packs must have the same node count, hole count and hole node counts; ``base`` is
    `prefilter`'s result when already known. The alignment of all pairs and offsets is one
    matrix product; scores and holes are computed only for label-compatible entries. With
    ``measured`` (`qshape.match`: candidates measured from pictures), pairs without a
    label-compatible offset get `relaxed_entries` (the point tolerance), and rotations weigh
    curve points by ``tol.curve_point_weight`` (`turn_sums`); `qshape.assign` leaves it off.
    """
    n = ref.codes.shape[1]
    s_count = ref.codes.shape[0]
    compat = cyclic_compat(ref.codes, cand.codes)  # (T, S, n)
    if base is None:
        base = prefilter(ref, cand, tol, use_color)
    compat &= base[:, :, None]
    offsets = np.flatnonzero(compat.any(axis=(0, 1)))
    k_count = len(offsets)
    ti, si, kk = np.nonzero(compat[:, :, offsets])
    idx = (np.arange(n)[None, :] + offsets[:, None]) % n  # (K, n)
    cp = cand.pts[:, idx, :].reshape(-1, 2 * n)  # (T*K, 2n)
    r = ref.pts.reshape(s_count, 2 * n)
    r_perp = np.stack([ref.pts[..., 1], -ref.pts[..., 0]], axis=-1).reshape(s_count, 2 * n)
    prod = cp @ np.concatenate([r, r_perp]).T  # (T*K, 2S): dot and cross products
    row = ti * k_count + kk
    dot = prod[row, si]
    crs = prod[row, s_count + si]
    sc = _alignment_score(cand.sumsq[ti] + ref.sumsq[si], dot, crs, n * ref.area[si])
    k = offsets[kk]
    if measured and tol.point_tolerance > 0.0:
        strict = np.zeros(base.shape, dtype=bool)
        strict[ti, si] = True
        rt, rs = np.nonzero(base & ~strict)
        if len(rt):
            extra = relaxed_entries(ref, cand, rs, rt, tol)
            order = np.lexsort((np.r_[k, extra.k], np.r_[si, extra.si], np.r_[ti, extra.ti]))
            ti, si, k = (
                np.r_[ti, extra.ti][order],
                np.r_[si, extra.si][order],
                np.r_[k, extra.k][order],
            )
            sc, dot, crs = (
                np.r_[sc, extra.score][order],
                np.r_[dot, extra.dot][order],
                np.r_[crs, extra.cross][order],
            )
    if measured:
        dot, crs = turn_sums(ref, cand, (ti, si, k), tol, (dot, crs))
    turn = np.zeros(len(ti))
    if ref.hole_codes:
        theta = np.arctan2(crs, dot)
        ok, hole_score = _holes(ref, cand, (ti, si, theta), tol)
        sc = sc + hole_score
        turn = hole_turn_residuals(ref, cand, (ti, si, theta))
        ti, si, k, sc, dot, crs, turn = (ti[ok], si[ok], k[ok], sc[ok], dot[ok], crs[ok], turn[ok])
    return BlockResult(ti, si, k, sc, dot, crs, turn)


def loose_codes(cand: Pack, rows: NDArray[np.int64], tol: Tolerances) -> NDArray[np.int64]:
    """Node codes of candidates ``rows`` whose labels also admit what their points allow.

    A measured tile's relevant points may lie ``tol.point_tolerance`` from where its design
    puts them (manufacturing, edge roughness, pixels); each label then also admits its
    neighbouring label when its measurement lies within the configured margin plus the
    change such a displacement causes (`_sensitivity`: larger between short edges). Kind and
    convexity are unchanged.

    Returns:
        Shape (len(rows), n) node codes.
    """
    values, gain = _sensitivity(cand.pts[rows])
    g, n, _ = values.shape
    extra = tol.point_tolerance * gain
    masks = lb.widened_masks(values.reshape(-1, 3).T, extra.reshape(-1, 3).T, tol).reshape(3, g, n)
    codes = cand.codes[rows]
    curve = (codes & lb.KIND_BIT) == 1
    a_mask = np.where(curve, (codes & lb.A_MASK) >> lb.A_MASK_SHIFT, masks[0])
    t_mask = np.where(curve, masks[2], masks[1])
    return np.asarray(
        (codes & ~(lb.A_MASK | lb.T_MASK))
        | (a_mask << lb.A_MASK_SHIFT)
        | (t_mask << lb.T_MASK_SHIFT),
        dtype=np.int64,
    )


def relaxed_entries(
    ref: Pack,
    cand: Pack,
    si: NDArray[np.int64],
    ti: NDArray[np.int64],
    tol: Tolerances,
) -> BlockResult:
    """Entries of label-incompatible pairs that the point tolerance admits.

    For each pair (reference ``si[p]``, candidate ``ti[p]``) and cyclic offset, the
    candidate's relevant points are aligned onto the reference's (2D Procrustes); entries
    whose residual (as `Match.score`) is at most ``tol.uncertainty_residual`` are kept when
    the candidate's `loose_codes` are compatible with the reference's codes. Holes are
    checked by the caller.

    Returns:
        The admitted entries, ordered by (candidate, reference, offset).
    """
    n = ref.codes.shape[1]
    idx = (np.arange(n)[None, :] + np.arange(n)[:, None]) % n  # (k, i)
    cp = cand.pts[ti][:, idx]  # (P, k, n, 2)
    rp = ref.pts[si]  # (P, n, 2)
    dot = np.einsum("pknd,pnd->pk", cp, rp)
    crs = np.einsum("pkn,pn->pk", cp[..., 0], rp[..., 1]) - np.einsum(
        "pkn,pn->pk", cp[..., 1], rp[..., 0]
    )
    sc = _alignment_score(
        (cand.sumsq[ti] + ref.sumsq[si])[:, None], dot, crs, (n * ref.area[si])[:, None]
    )
    p, k = np.nonzero(sc <= tol.uncertainty_residual)
    if len(p) == 0:
        empty = np.zeros(0, dtype=np.int64)
        return BlockResult(empty, empty, empty, np.zeros(0), np.zeros(0), np.zeros(0))
    t, s = ti[p], si[p]
    used, local = np.unique(t, return_inverse=True)
    loose = loose_codes(cand, used, tol)[local[:, None], idx[k]]  # (E, n)
    ok = np.asarray(lb.compatible(loose, ref.codes[s]).all(axis=1))
    p, k = p[ok], k[ok]
    return BlockResult(ti[p], si[p], k, sc[p, k], dot[p, k], crs[p, k])


def evaluate_pairs(
    ref: Pack, cand: Pack, tol: Tolerances, use_color: bool
) -> tuple[NDArray[np.bool_], FloatArray, FloatArray]:
    """Match candidate p against reference p for aligned packs of equal length P.

    Returns:
        (ok, score, rotation), each shape (P,). For symmetric shapes the rotation is the
        equivalent one (score within ``tol.symmetry_residual`` of the best, and the reference
        symmetric under the turn between them) of least magnitude.
    """
    count, n = ref.codes.shape
    base = np.ones(count, dtype=bool)
    if tol.check_size:
        thr = (
            tol.size_area_threshold
            if tol.size_area_threshold is not None
            else tol.joint_width * 0.5 * (cand.perimeter + ref.perimeter)
        )
        base &= np.abs(cand.area - ref.area) <= thr
    if use_color:
        diff = cand.color - ref.color
        base &= ~(np.einsum("pd,pd->p", diff, diff) > tol.color_distance**2)
    idx = (np.arange(n)[None, :] + np.arange(n)[:, None]) % n  # (k, i)
    compat = lb.compatible(cand.codes[:, idx], ref.codes[:, None, :]).all(axis=-1)  # (P, k)
    compat &= base[:, None]
    pi, k = np.nonzero(compat)
    cp = cand.pts[pi[:, None], idx[k]]  # (E, n, 2)
    rp = ref.pts[pi]
    dot = np.einsum("end,end->e", cp, rp)
    crs = np.einsum("en,en->e", cp[..., 0], rp[..., 1]) - np.einsum(
        "en,en->e", cp[..., 1], rp[..., 0]
    )
    sc = _alignment_score(cand.sumsq[pi] + ref.sumsq[pi], dot, crs, n * ref.area[pi])
    theta = np.arctan2(crs, dot)
    turn = None
    if ref.hole_codes:
        hok, hole_score = _holes(ref, cand, (pi, pi, theta), tol)
        turn = hole_turn_residuals(ref, cand, (pi, pi, theta))[hok]
        pi, k, sc, theta = pi[hok], k[hok], (sc + hole_score)[hok], theta[hok]
    ok = np.zeros(count, dtype=bool)
    ok[pi] = True
    equiv = equivalent_entries(pi, k, sc, ref.self_residual, tol, hole_turn=turn)
    mag = np.where(equiv, np.abs(theta), np.inf)
    low = np.full(count, np.inf)
    np.minimum.at(low, pi, mag)
    rotation = np.zeros(count)
    score = np.full(count, np.inf)
    hit = mag == low[pi]
    rotation[pi[hit]] = theta[hit]
    score[pi[hit]] = sc[hit]
    return ok, score, rotation


def equivalent_entries(
    pair: NDArray[np.int64],
    k: NDArray[np.int64],
    score: FloatArray,
    self_residual: FloatArray,
    tol: Tolerances,
    *,
    hole_turn: FloatArray | None = None,
) -> NDArray[np.bool_]:
    """Entries equivalent to their pair's best one: a symmetry of the whole figure apart.

    The qualitative description leaves a turn open where the outline is symmetric and a hole
    sits at the centre (its qualitative position, the centre, is the same at every turn): the
    hole's own orientation then decides (``hole_turn``, a quantitative step after the
    description's match). An entry's turn counts as a symmetry only when the outline is
    symmetric under it and the holes fit as well as at the best entry.

    Args:
        pair: (E,) pair of each entry, also the row of ``self_residual`` (its reference).
        k: (E,) cyclic offset of each entry.
        score: (E,) residual of each entry.
        self_residual: (P, n) `self_residuals` of each pair's reference.
        tol: ``symmetry_residual`` and ``symmetry_tolerance``.
        hole_turn: (E,) `hole_turn_residuals` of each entry (None: no holes to compare).

    Returns:
        (E,) True where the score is within ``symmetry_residual`` of the pair's best, the
        reference's outline is symmetric (``symmetry_tolerance``) under the shift from the best
        offset, and the holes' turn residual within ``symmetry_tolerance`` of the best's. The
        best entry is the one of least score plus hole turn residual.
    """
    if len(pair) == 0:
        return np.zeros(0, dtype=bool)
    turn = np.zeros(len(pair)) if hole_turn is None else hole_turn
    order = np.lexsort((score + turn, pair))  # per pair, its best entry first
    first = order[np.r_[True, pair[order][1:] != pair[order][:-1]]]
    best_of = np.zeros(int(pair.max()) + 1, dtype=np.int64)
    best_of[pair[first]] = first
    b = best_of[pair]
    n = self_residual.shape[1]
    shift = (k - k[b]) % n
    return np.asarray(
        (score <= score[b] + tol.symmetry_residual)
        & (self_residual[pair, shift] <= tol.symmetry_tolerance)
        & (turn <= turn[b] + tol.symmetry_tolerance)
    )


def hole_turn_residuals(
    ref: Pack,
    cand: Pack,
    entries: tuple[NDArray[np.int64], NDArray[np.int64], FloatArray],
) -> FloatArray:
    """How far a candidate's holes, turned by each entry's rotation, lie from the reference's.

    Per (candidate ti, reference si, rotation theta) entry: the RMS distance between the
    relevant points of each hole of the candidate, turned by theta about the centroid, and
    those of the reference's hole in the same place (best cyclic correspondence), over the
    holes with straight edges only, divided by sqrt(reference area). A hole with a curve (a
    circle) gives no orientation and is left out; 0 where no hole is compared.

    Returns:
        (E,) residual, as `Match.score` measures it.
    """
    ti, si, theta = entries
    total = np.zeros(theta.shape)
    used = np.zeros(theta.shape)
    c, s = np.cos(theta), np.sin(theta)
    for h in range(min(len(ref.hole_pts), len(cand.hole_pts))):
        rp, cp = ref.hole_pts[h][si], cand.hole_pts[h][ti]  # (E, m, 2)
        m = rp.shape[1]
        if cp.shape[1] != m or m == 0:
            continue
        straight = ~(
            ((ref.hole_codes[h][si] & lb.KIND_BIT) != 0).any(axis=1)
            | ((cand.hole_codes[h][ti] & lb.KIND_BIT) != 0).any(axis=1)
        )
        turned = np.stack(
            [
                c[:, None] * cp[..., 0] - s[:, None] * cp[..., 1],
                s[:, None] * cp[..., 0] + c[:, None] * cp[..., 1],
            ],
            axis=-1,
        )
        idx = (np.arange(m)[:, None] + np.arange(m)[None, :]) % m  # (shift, i)
        diff = turned[:, idx, :] - rp[:, None, :, :]  # (E, shift, m, 2)
        sq = np.einsum("esmd,esmd->es", diff, diff).min(axis=1) / m
        total += np.where(straight, sq, 0.0)
        used += straight
    return np.asarray(
        np.sqrt(total / np.maximum(used, 1.0)) / np.sqrt(np.maximum(ref.area[si], 1e-300))
    )


def _holes(
    ref: Pack,
    cand: Pack,
    entries: tuple[NDArray[np.int64], NDArray[np.int64], FloatArray],
    tol: Tolerances,
) -> tuple[NDArray[np.bool_], FloatArray]:
    """Hole agreement and residual for (candidate ti, reference si, rotation theta) entries.

    Tries every pairing of holes (up to 4 holes; beyond, the holes' canonical order), and
    keeps the agreeing pairing of least residual. Returns (ok, score), each of shape (P,).
    """
    ti, si, theta = entries
    nholes = len(ref.hole_codes)
    best_ok = np.zeros(theta.shape, dtype=bool)
    best_score = np.full(theta.shape, np.inf)
    perms = (
        list(itertools.permutations(range(nholes)))
        if nholes <= _MAX_PERMUTED_HOLES
        else [tuple(range(nholes))]
    )
    scale = np.sqrt(ref.area[si])
    c, s = np.cos(theta), np.sin(theta)
    north_ref = np.degrees(ref.north)
    north = north_ref[si]
    theta_deg = np.degrees(theta)
    margin = tol.cone_margin_deg
    for perm in perms:
        ok = np.ones(theta.shape, dtype=bool)
        sq = np.zeros(theta.shape)
        for h, g in enumerate(perm):
            if ref.hole_codes[h].shape[1] != cand.hole_codes[g].shape[1]:
                ok[:] = False
                break
            labels_ok = np.asarray(
                cyclic_compat(ref.hole_codes[h], cand.hole_codes[g]).any(axis=-1)
            )
            ok &= labels_ok[ti, si]
            # Candidate hole's CCW angle interval turned by theta; both as bearings (clockwise
            # from the reference's north, its first vertex).
            # The reference's cone sets depend on the reference alone: once per reference.
            riv = ref.hole_interval[:, h, :]
            r_lo, r_hi = north_ref - riv[:, 1], north_ref - riv[:, 0]
            rs = cone_bits(r_lo, r_hi, -margin)[si]
            rl = cone_bits(r_lo, r_hi, margin)[si]
            civ = cand.hole_interval[ti, g, :] + theta_deg[:, None]
            c_lo, c_hi = north - civ[:, 1], north - civ[:, 0]
            cs = cone_bits(c_lo, c_hi, -margin)
            cl = cone_bits(c_lo, c_hi, margin)
            ok &= ((rs & ~cl) == 0) & ((cs & ~rl) == 0)  # strict of each within loose of the other
            hc = cand.hole_centroid[ti, g, :]
            rc = ref.hole_centroid[si, h, :]
            rx = c * hc[:, 0] - s * hc[:, 1]
            ry = s * hc[:, 0] + c * hc[:, 1]
            sq = sq + (rx - rc[:, 0]) ** 2 + (ry - rc[:, 1]) ** 2
        perm_score = np.sqrt(sq / nholes) / scale
        better = ok & (perm_score < best_score)
        best_ok |= ok
        best_score = np.where(better, perm_score, best_score)
    return best_ok, np.where(best_ok, best_score, 0.0)


def _sensitivity(pts: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Label measurements of packed boundaries and how much a point's error moves them.

    Args:
        pts: Relevant points, shape (G, n, 2), y-up, clockwise as seen.

    Returns:
        (values, gain), each shape (G, n, 3): per node the angle [deg], the length ratio and
        half-chord / sagitta (`qshape.theory.labels.measure`), and their change per unit of point
        displacement: [deg / unit] for the angle, relative change per unit for the ratios
        (sqrt(1/a^2 + 1/b^2) for the two lengths a, b each measurement divides).
    """
    g, n, _ = pts.shape
    flat = pts.reshape(-1, 2)
    prev, nxt = lb.ring_index(n)
    row = (np.arange(g)[:, None] * n).repeat(n, axis=1).ravel()
    before = flat[row + np.tile(prev, g)]
    after = flat[row + np.tile(nxt, g)]
    angle, _, ratio, chord_ratio = lb.measure(flat, before, after)
    l1 = np.hypot(*(flat - before).T)
    l2 = np.hypot(*(after - flat).T)
    da = 0.5 * np.hypot(*(after - before).T)
    db = np.hypot(*(flat - 0.5 * (before + after)).T)
    tiny = np.finfo(np.float64).tiny
    inv_l = np.sqrt(1.0 / np.maximum(l1, tiny) ** 2 + 1.0 / np.maximum(l2, tiny) ** 2)
    inv_c = np.sqrt(1.0 / np.maximum(da, tiny) ** 2 + 1.0 / np.maximum(db, tiny) ** 2)
    values = np.stack([angle, ratio, chord_ratio], axis=-1).reshape(g, n, 3)
    gain = np.stack([np.degrees(inv_l), inv_l, inv_c], axis=-1).reshape(g, n, 3)
    return values, gain


__all__ = [
    "BlockResult",
    "equivalent_entries",
    "evaluate_block",
    "evaluate_pairs",
    "hole_turn_residuals",
    "loose_codes",
    "relaxed_entries",
]
