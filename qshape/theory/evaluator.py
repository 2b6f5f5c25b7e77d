"""Vectorised matching of many descriptions at once: packs, the block evaluator, symmetries.

Descriptions with the same node count and hole signature are stacked into a `Pack`;
`evaluate_block` matches every candidate of one pack against every reference of another for
every cyclic offset in a few array operations (label compatibility, size and colour prefilter,
the 2D Procrustes alignment of all pairs as one matrix product, holes). `match` and `assign`
are built on it.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from qshape.geometry import FloatArray
from qshape.theory import labels as lb
from qshape.theory.description import Description, hole_angles_many
from qshape.theory.tolerances import Tolerances

_CONE_DEG = 45.0
_N_CONES = 8
_CENTRE_BIT = 1 << _N_CONES
_MAX_PERMUTED_HOLES = 4
"""Holes up to this count are paired by trying every permutation (4! = 24)."""


@dataclass(frozen=True)
class Pack:
    """Arrays of a group of descriptions with the same node count and hole signature."""

    codes: NDArray[np.int64]  # (G, n)
    pts: FloatArray  # (G, n, 2)
    sumsq: FloatArray  # (G,)
    area: FloatArray  # (G,)
    perimeter: FloatArray  # (G,)
    color: FloatArray  # (G, 3), NaN when unknown
    north: FloatArray  # (G,) angle [rad] of the first vertex (CCW from +x)
    hole_codes: tuple[NDArray[np.int64], ...]  # per hole (G, m_h)
    hole_centroid: FloatArray  # (G, H, 2)
    hole_interval: FloatArray  # (G, H, 2) CCW angle interval [deg]; NaN when around centroid
    self_residual: FloatArray  # (G, n) `self_residuals` of the outer points


def take(p: Pack, idx: NDArray[np.int64]) -> Pack:
    """Sub-pack of the members ``idx``."""
    return Pack(
        codes=p.codes[idx],
        pts=p.pts[idx],
        sumsq=p.sumsq[idx],
        area=p.area[idx],
        perimeter=p.perimeter[idx],
        color=p.color[idx],
        north=p.north[idx],
        hole_codes=tuple(h[idx] for h in p.hole_codes),
        hole_centroid=p.hole_centroid[idx],
        hole_interval=p.hole_interval[idx],
        self_residual=p.self_residual[idx],
    )


def self_residuals(pts: FloatArray, area: FloatArray) -> FloatArray:
    """Residual of each member's points against themselves shifted cyclically: (G, n).

    Entry (g, d): RMS distance between point i and point i + d best turned onto it (about
    the centroid), divided by sqrt(area), as `Match.score` measures it. Column 0 is 0; a
    small value at d is a rotational symmetry of the figure (a square's every column).

    Args:
        pts: Centred relevant points, shape (G, n, 2).
        area: Areas, shape (G,).
    """
    n = pts.shape[1]
    shifted = pts[:, (np.arange(n)[:, None] + np.arange(n)[None, :]) % n]  # (G, d, i, 2)
    dot = np.einsum("gdik,gik->gd", shifted, pts)
    crs = np.einsum("gdi,gi->gd", shifted[..., 0], pts[..., 1]) - np.einsum(
        "gdi,gi->gd", shifted[..., 1], pts[..., 0]
    )
    rss = 2.0 * np.einsum("gik,gik->g", pts, pts)[:, None] - 2.0 * np.hypot(dot, crs)
    return np.asarray(np.sqrt(np.maximum(rss, 0.0) / (n * np.maximum(area, 1e-300))[:, None]))


def prefilter(ref: Pack, cand: Pack, tol: Tolerances, use_color: bool) -> NDArray[np.bool_]:
    """(T, S) bool: qualitative size and colour agree (the paper's first checks)."""
    base = np.ones((cand.codes.shape[0], ref.codes.shape[0]), dtype=bool)
    if tol.check_size:
        thr = (
            tol.size_area_threshold
            if tol.size_area_threshold is not None
            else tol.joint_width * 0.5 * (cand.perimeter[:, None] + ref.perimeter[None, :])
        )
        gap = np.subtract(cand.area[:, None], ref.area[None, :])
        np.abs(gap, out=gap)
        base &= gap <= thr
    if use_color:  # in place: two (T, S) buffers in all
        dist2 = np.subtract(cand.color[:, None, 0], ref.color[None, :, 0])
        np.multiply(dist2, dist2, out=dist2)
        diff = np.empty_like(dist2)
        for ch in (1, 2):
            np.subtract(cand.color[:, None, ch], ref.color[None, :, ch], out=diff)
            np.multiply(diff, diff, out=diff)
            dist2 += diff
        base &= ~(dist2 > tol.color_distance**2)  # unknown colour (NaN) matches any
    return base


def _hole_order(d: Description) -> list[int]:
    """Holes in a canonical order (node count, then kinds), so packs stack consistently."""
    return sorted(
        range(len(d.holes)),
        key=lambda h: (
            len(d.holes[h].boundary.codes),
            int((d.holes[h].boundary.codes & lb.KIND_BIT).sum()),
        ),
    )


def pack(descs: Sequence[Description]) -> Pack:
    """Stack descriptions that share node count and hole node counts into arrays."""
    nholes = len(descs[0].holes)
    if nholes > 1:
        descs = [
            d
            if (order := _hole_order(d)) == sorted(order)
            else Description(
                d.type_hole,
                d.type_curve,
                d.color,
                d.area,
                d.perimeter,
                d.outer,
                tuple(d.holes[h] for h in order),
            )
            for d in descs
        ]
    g = len(descs)
    n = len(descs[0].outer.codes)
    # concatenate + reshape: several times faster than np.stack for many small arrays.
    codes = np.concatenate([d.outer.codes for d in descs]).reshape(g, n)
    pts = np.concatenate([d.outer.points for d in descs]).reshape(g, n, 2)
    hole_codes = tuple(
        np.concatenate([d.holes[h].boundary.codes for d in descs]).reshape(g, -1)
        for h in range(nholes)
    )
    hc = np.zeros((len(descs), nholes, 2))
    hi = np.full((len(descs), nholes, 2), np.nan)
    for h in range(nholes):  # every description's hole h at once
        hp = np.concatenate([d.holes[h].boundary.points for d in descs]).reshape(g, -1, 2)
        hc[:, h] = hp.mean(axis=1)
        kinds, inv = np.unique(hole_codes[h] & lb.KIND_BIT, axis=0, return_inverse=True)
        inv = inv.ravel()
        for u in range(len(kinds)):
            sel = inv == u
            hi[sel, h] = hole_angles_many(hp[sel], kinds[u] == 1)
    nan3 = (np.nan, np.nan, np.nan)
    colors = np.array([nan3 if d.color is None else d.color for d in descs])
    area = np.array([d.area for d in descs])
    return Pack(
        codes=codes,
        pts=pts,
        sumsq=np.einsum("gnd,gnd->g", pts, pts),
        area=area,
        perimeter=np.array([d.perimeter for d in descs]),
        color=colors,
        north=np.arctan2(pts[:, 0, 1], pts[:, 0, 0]),
        hole_codes=hole_codes,
        hole_centroid=hc,
        hole_interval=hi,
        self_residual=self_residuals(pts, area),
    )


def _cyclic_compat(ref: NDArray[np.int64], cand: NDArray[np.int64]) -> NDArray[np.bool_]:
    """Label compatibility for every cyclic offset: ref (S, n), cand (T, n) -> (T, S, n).

    Offset k pairs reference node i with candidate node (i + k) % n. Computed over unique rows.
    """
    n = ref.shape[1]
    ur, inv_r = np.unique(ref, axis=0, return_inverse=True)
    uc, inv_c = np.unique(cand, axis=0, return_inverse=True)
    idx = (np.arange(n)[None, :] + np.arange(n)[:, None]) % n  # (k, i)
    rolled = uc[:, idx]  # (Uc, k, i)
    ok = np.asarray(lb.compatible(rolled[:, None, :, :], ur[None, :, None, :]).all(axis=-1))
    return np.asarray(ok[inv_c.ravel()][:, inv_r.ravel()])


def cyclic_compat_by_offset(ref: NDArray[np.int64], cand: NDArray[np.int64]) -> NDArray[np.bool_]:
    """`_cyclic_compat` laid out (T, n, S): candidate, offset, reference.

    Computed over unique rows (noisy copies of a class mostly share their labels).
    """
    n = ref.shape[1]
    ur, inv_r = np.unique(ref, axis=0, return_inverse=True)
    uc, inv_c = np.unique(cand, axis=0, return_inverse=True)
    idx = (np.arange(n)[None, :] + np.arange(n)[:, None]) % n  # (k, i)
    rolled = uc[:, idx]  # (Uc, k, i)
    ok = np.asarray(lb.compatible(rolled[:, :, None, :], ur[None, None, :, :]).all(axis=-1))
    return np.asarray(ok[inv_c.ravel()][:, :, inv_r.ravel()])


def _cone_bits(lo: FloatArray, hi: FloatArray, widen: float) -> NDArray[np.int64]:
    """Bit k set when the bearing interval [lo, hi] (deg, widened by ``widen``) meets cone k.

    Cone k covers bearings (45 k - 22.5, 45 k + 22.5), k = 0 (N) ... 7 (NW). NaN intervals
    (a hole around the centroid) give the centre bit. A negative ``widen`` that empties the
    interval gives 0 (no constraint).
    """
    centre = np.isnan(lo)
    a = np.where(centre, 0.0, lo - widen)
    b = np.where(centre, 0.0, hi + widen)
    empty = a > b
    first = np.floor((a + _CONE_DEG / 2) / _CONE_DEG).astype(np.int64)
    last = np.floor((b + _CONE_DEG / 2) / _CONE_DEG).astype(np.int64)
    span = np.clip(last - first + 1, 0, _N_CONES)
    run = (np.left_shift(1, span) - 1) << (first % _N_CONES)
    full = (1 << _N_CONES) - 1
    bits = (run | (run >> _N_CONES)) & full
    bits = np.where(empty, 0, bits)
    return np.asarray(np.where(centre, _CENTRE_BIT, bits))


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
    """

    ti: NDArray[np.int64]
    si: NDArray[np.int64]
    k: NDArray[np.int64]
    score: FloatArray
    dot: FloatArray
    cross: FloatArray

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
    compat = _cyclic_compat(ref.codes, cand.codes)  # (T, S, n)
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
    if ref.hole_codes:
        ok, hole_score = _holes(ref, cand, (ti, si, np.arctan2(crs, dot)), tol)
        sc = sc + hole_score
        ti, si, k, sc, dot, crs = ti[ok], si[ok], k[ok], sc[ok], dot[ok], crs[ok]
    return BlockResult(ti, si, k, sc, dot, crs)


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


def turn_sums(
    ref: Pack,
    cand: Pack,
    entries: tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.int64]],
    tol: Tolerances,
    plain: tuple[FloatArray, FloatArray],
) -> tuple[FloatArray, FloatArray]:
    """Sums whose angle atan2(cross, dot) is the rotation `qshape.match` returns, per entry.

    A curve's maximum-curvature point lies on a flat maximum: its place along the curve is
    measured far less well than a corner's, so it weighs ``tol.curve_point_weight`` in the
    least-squares rotation of the relevant points (vertices 1). With
    ``tol.rotation_corner_share`` below 1 the rotation also fits the candidate's edges to
    the reference's edge lines (`edge_rotation`). The residual score stays unweighted.

    Args:
        ref: Reference pack.
        cand: Candidate pack.
        entries: (candidate index, reference index, cyclic offset), each shape (E,).
        tol: ``curve_point_weight`` and ``rotation_corner_share``.
        plain: The unweighted (dot, cross) sums of the entries, returned as they are when
            every point weighs alike and the edges take no share.

    Returns:
        (dot, cross), each shape (E,).
    """
    ti, si, k = entries
    curve = (ref.codes[si] & lb.KIND_BIT) == 1  # (E, n)
    edges_used = tol.rotation_corner_share < 1.0 and len(ti) > 0
    if not edges_used and (tol.curve_point_weight == 1.0 or not curve.any()):
        return plain
    n = ref.codes.shape[1]
    w = np.where(curve, tol.curve_point_weight, 1.0)
    cp = cand.pts[ti[:, None], (np.arange(n)[None, :] + k[:, None]) % n]  # (E, n, 2)
    rp = ref.pts[si]
    wp = rp * w[..., None]
    dot = np.einsum("end,end->e", cp, wp)
    crs = np.einsum("en,en->e", cp[..., 0], wp[..., 1]) - np.einsum(
        "en,en->e", cp[..., 1], wp[..., 0]
    )
    if not edges_used:
        return dot, crs
    theta = edge_rotation(rp, cp, w, np.arctan2(crs, dot), tol.rotation_corner_share)
    size = np.hypot(dot, crs)
    return size * np.cos(theta), size * np.sin(theta)


_NEWTON_STEPS = 3
"""Newton steps of `edge_rotation` from the points' rotation (quadratic convergence: the
third step changes the angle by less than 1e-5 deg on measured tiles)."""


def edge_rotation(
    ref_pts: FloatArray,
    cand_pts: FloatArray,
    weight: FloatArray,
    start: FloatArray,
    corner_share: float,
) -> FloatArray:
    """Rotation fitting corresponding points and the candidate's edges onto the reference's.

    Minimises over the angle t (about the centroids, as the points are given)
    ``corner_share`` x sum_i w_i |R(t) c_i - r_i|^2 / sum_i w_i + (1 - ``corner_share``) x
    sum_e w_e L_e int_0^1 (n_e . (R(t) c(s) - r_e))^2 ds / sum_e L_e, where edge e runs from
    point e to point e + 1 (c(s) along the candidate's edge, L_e its length, n_e the unit
    normal of the reference's edge e through r_e, w_e the smaller weight of its two ends: a
    chord of a curve weighs as its curve point). With R(t) c = cos t c + sin t Jc (J: a
    quarter turn) the misfit is a trigonometric quadratic in t whose coefficients are exact
    sums over the points and, in closed form, over the straight edges (the distance is
    linear along an edge); Newton steps on it from ``start``.

    Args:
        ref_pts: Reference points, shape (E, n, 2), centred.
        cand_pts: Corresponding candidate points, shape (E, n, 2), centred.
        weight: Per point weight, shape (E, n).
        start: Starting angles [rad], shape (E,) (the points' weighted Procrustes).
        corner_share: In [0, 1] (`Tolerances.rotation_corner_share`).

    Returns:
        Angles [rad], shape (E,).
    """
    tiny = np.finfo(np.float64).tiny
    nxt = np.roll(np.arange(ref_pts.shape[1]), -1)
    edge = ref_pts[:, nxt] - ref_pts
    normal = np.stack([-edge[..., 1], edge[..., 0]], axis=-1)
    normal /= np.maximum(np.hypot(normal[..., 0], normal[..., 1]), tiny)[..., None]
    length = np.hypot(*(cand_pts[:, nxt] - cand_pts).transpose(2, 0, 1))  # (E, n)
    w_edge = (1.0 - corner_share) * np.minimum(weight, weight[:, nxt]) * length
    w_edge /= np.maximum(length.sum(axis=1), tiny)[:, None]
    w_point = corner_share * weight / np.maximum(weight.sum(axis=1), tiny)[:, None]
    quarter = np.stack([-cand_pts[..., 1], cand_pts[..., 0]], axis=-1)  # J c
    # Points: sum w |R c - r|^2 = const - 2 (p cos t + q sin t).
    p = np.einsum("en,end,end->e", w_point, ref_pts, cand_pts)
    q = np.einsum("en,end,end->e", w_point, ref_pts, quarter)
    # Edges: distance n . (R c(s) - r) = A(s) cos t + B(s) sin t - D, A and B linear in s.
    a0 = np.einsum("end,end->en", normal, cand_pts)
    a1 = np.einsum("end,end->en", normal, cand_pts[:, nxt])
    b0 = np.einsum("end,end->en", normal, quarter)
    b1 = np.einsum("end,end->en", normal, quarter[:, nxt])
    dist = np.einsum("end,end->en", normal, ref_pts)
    kaa = np.einsum("en,en->e", w_edge, (a0 * a0 + a0 * a1 + a1 * a1) / 3.0)
    kbb = np.einsum("en,en->e", w_edge, (b0 * b0 + b0 * b1 + b1 * b1) / 3.0)
    kab = np.einsum("en,en->e", w_edge, (2 * a0 * b0 + a0 * b1 + a1 * b0 + 2 * a1 * b1) / 6.0)
    p += np.einsum("en,en->e", w_edge, dist * (a0 + a1) / 2.0)
    q += np.einsum("en,en->e", w_edge, dist * (b0 + b1) / 2.0)
    theta = np.asarray(start, dtype=np.float64).copy()
    for _ in range(_NEWTON_STEPS):
        c, s = np.cos(theta), np.sin(theta)
        c2, s2 = c * c - s * s, 2.0 * s * c
        slope = 0.5 * (kbb - kaa) * s2 + kab * c2 + p * s - q * c
        curvature = (kbb - kaa) * c2 - 2.0 * kab * s2 + p * c + q * s
        theta -= slope / np.where(curvature > tiny, curvature, np.inf)
    return theta


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
    if ref.hole_codes:
        hok, hole_score = _holes(ref, cand, (pi, pi, theta), tol)
        pi, k, sc, theta = pi[hok], k[hok], (sc + hole_score)[hok], theta[hok]
    ok = np.zeros(count, dtype=bool)
    ok[pi] = True
    equiv = equivalent_entries(pi, k, sc, ref.self_residual, tol)
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
) -> NDArray[np.bool_]:
    """Entries equivalent to their pair's best one: a symmetry of the reference apart.

    Args:
        pair: (E,) pair of each entry, also the row of ``self_residual`` (its reference).
        k: (E,) cyclic offset of each entry.
        score: (E,) residual of each entry.
        self_residual: (P, n) `self_residuals` of each pair's reference.
        tol: ``symmetry_residual`` and ``symmetry_tolerance``.

    Returns:
        (E,) True where the score is within ``symmetry_residual`` of the pair's best and the
        reference is symmetric (``symmetry_tolerance``) under the shift from the best offset.
    """
    if len(pair) == 0:
        return np.zeros(0, dtype=bool)
    order = np.lexsort((score, pair))  # per pair, its best entry first
    first = order[np.r_[True, pair[order][1:] != pair[order][:-1]]]
    best_of = np.zeros(int(pair.max()) + 1, dtype=np.int64)
    best_of[pair[first]] = first
    b = best_of[pair]
    n = self_residual.shape[1]
    shift = (k - k[b]) % n
    return np.asarray(
        (score <= score[b] + tol.symmetry_residual)
        & (self_residual[pair, shift] <= tol.symmetry_tolerance)
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
                _cyclic_compat(ref.hole_codes[h], cand.hole_codes[g]).any(axis=-1)
            )
            ok &= labels_ok[ti, si]
            # Candidate hole's CCW angle interval turned by theta; both as bearings (clockwise
            # from the reference's north, its first vertex).
            # The reference's cone sets depend on the reference alone: once per reference.
            riv = ref.hole_interval[:, h, :]
            r_lo, r_hi = north_ref - riv[:, 1], north_ref - riv[:, 0]
            rs = _cone_bits(r_lo, r_hi, -margin)[si]
            rl = _cone_bits(r_lo, r_hi, margin)[si]
            civ = cand.hole_interval[ti, g, :] + theta_deg[:, None]
            c_lo, c_hi = north - civ[:, 1], north - civ[:, 0]
            cs = _cone_bits(c_lo, c_hi, -margin)
            cl = _cone_bits(c_lo, c_hi, margin)
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


__all__ = [
    "BlockResult",
    "Pack",
    "cyclic_compat_by_offset",
    "equivalent_entries",
    "evaluate_block",
    "evaluate_pairs",
    "loose_codes",
    "pack",
    "prefilter",
    "relaxed_entries",
    "self_residuals",
    "take",
    "turn_sums",
    "edge_rotation",
]
