"""Matching descriptions: `match`, `Match`, canonical keys, and a vectorised block evaluator.

A reference and a candidate match when (as in the paper) their qualitative sizes and colours
agree, their type flags agree, their outer node strings are equal cyclically, and their holes
agree in position and boundary. Here "equal" means compatible: every label component has a
common admissible label, so measurements near a band edge still match (see `qshape.labels`).

The cyclic comparison also gives the correspondence, hence the rotation that turns the candidate
onto the reference: the least-squares rotation (2D Procrustes, no reflection) of the candidate's
relevant points onto the reference's under that correspondence. Holes are compared after that
rotation, in the reference's cardinal frame; a hole boundary is compared cyclically (a deliberate
robustness change from the paper's fixed start vertex, which a noisy vertex can move).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

from qshape import labels as lb
from qshape.description import (
    ONLY_CURVES,
    Description,
    default_tolerances,
    describe,
    hole_angles_many,
)
from qshape.errors import MatchError
from qshape.figure import Figure
from qshape.geometry import FloatArray
from qshape.labels import CodeArray
from qshape.tolerances import Tolerances

_CONE_DEG = 45.0
_N_CONES = 8
_CENTRE_BIT = 1 << _N_CONES
_MAX_PERMUTED_HOLES = 4
"""Holes up to this count are paired by trying every permutation (4! = 24)."""


@dataclass(frozen=True)
class Match:
    """Result of a successful `match`.

    Attributes:
        rotation: Rotation in [rad], counter-clockwise in the y-up frame, in (-pi, pi], that
            turns the candidate (about its centroid) onto the reference: the best fit, or of
            the rotations a symmetry of the reference apart from it (its geometry decides,
            ``Tolerances.symmetry_tolerance``, not its labels), the one of smallest magnitude.
            For y_down (image) figures a CCW rotation in y-up is clockwise in pixel
            coordinates' math sense, i.e. counter-clockwise as seen on screen.
        rotations: `rotation` first, then every other rotation whose residual is within
            ``Tolerances.symmetry_residual`` of the best, smallest magnitude first: the
            shape's symmetries (a square 4 values, an equilateral triangle 3) and, for a
            nearly symmetric shape, the turns its fit can barely tell apart.
        score: Alignment residual: RMS distance between corresponding relevant points after the
            rotation, divided by sqrt(reference area), plus the same measure for hole centroids.
            Dimensionless; 0 is perfect, lower is better.
        correspondence: For each reference node i, the index of the corresponding candidate node.
        offset: Candidate node index corresponding to the reference's first node (the paper's
            ``vertex02``).
        continuous: True when both shapes are rotationally continuous (circles, concentric
            rings): every rotation fits; `rotation` is then just the fitted one.
    """

    rotation: float
    rotations: tuple[float, ...]
    score: float
    correspondence: tuple[int, ...]
    offset: int
    continuous: bool = False


def as_description(obj: Description | Figure, tol: Tolerances) -> Description:
    """A `Description` from a description or a figure.

    Raises:
        MatchError: Anything else.
    """
    if isinstance(obj, Description):
        return obj
    if isinstance(obj, Figure):
        return describe(obj, tol)
    raise MatchError(f"expected a qshape Description or Figure, got {type(obj).__name__}")


# ------------------------------------------------------------------------- canonical keys
def _least_rotation(seq: tuple[int, ...]) -> tuple[int, ...]:
    n = len(seq)
    return min(seq[i:] + seq[:i] for i in range(n))


_TOKENS_A = "rao"
_TOKENS_C = "xv"
_TOKENS_L = "sEb"
_TOKENS_T = "pSa"


def _token(code: int) -> str:
    is_curve, (a, _), (c, _), (t, _) = lb.decode(code)
    if is_curve:
        return "~" + _TOKENS_C[c] + _TOKENS_T[t]
    return _TOKENS_A[a] + _TOKENS_C[c] + _TOKENS_L[t]


@lru_cache(maxsize=65536)
def _kinds_key(kinds: bytes) -> str:
    seq = tuple(np.frombuffer(kinds, dtype=np.int64).tolist())
    return "".join("c" if k else "v" for k in _least_rotation(seq))


def _hole_signature(d: Description) -> str:
    if not d.holes:
        return "H0"
    parts = sorted(_kinds_key((h.boundary.codes & lb.KIND_BIT).tobytes()) for h in d.holes)
    return "H" + str(len(d.holes)) + "[" + "|".join(parts) + "]"


def coarse_key(d: Description) -> str:
    """Key on the never-ambiguous parts: node kinds (least rotation) and hole signature."""
    return "K:" + _kinds_key((d.outer.codes & lb.KIND_BIT).tobytes()) + ":" + _hole_signature(d)


def canonical_key(description: Description) -> str:
    """Rotation-invariant key of the measured (primary) labels.

    The least rotation of the cyclic string of primary node labels, plus the hole signature
    (count and node kinds of each hole). Two descriptions with equal keys are label-compatible
    at some cyclic offset; near band edges use `canonical_keys`, which expands admissible labels.
    Colour and size are not in the key (they are continuous); `assign` checks them, and the
    holes' positions and labels, after the lookup.
    """
    return _primary_key(description.outer.codes.tobytes()) + ":" + _hole_signature(description)


@lru_cache(maxsize=65536)
def _primary_key(codes: bytes) -> str:
    prim = lb.primary_code(np.frombuffer(codes, dtype=np.int64))
    return "".join(_token(c) for c in _least_rotation(tuple(prim.tolist())))


def _alternatives(code: int) -> list[int]:
    is_curve, (a, am), (c, cm), (t, tm) = lb.decode(code)
    out = []
    a_opts = [a] if is_curve else [k for k in range(3) if am >> k & 1]
    for aa in a_opts:
        for cc in (k for k in range(2) if cm >> k & 1):
            for tt in (k for k in range(3) if tm >> k & 1):
                out.append(lb.encode(is_curve, (aa, 1 << aa), (cc, 1 << cc), (tt, 1 << tt)))
    return out


def canonical_keys(
    description: Description, tolerances: Tolerances | None = None
) -> frozenset[str]:
    """Every canonical key over the admissible labels (see `canonical_key`).

    Two descriptions whose outer boundaries are compatible at some offset share at least one
    key. When a figure admits more than ``tolerances.max_key_variants`` combinations, the set is
    its `coarse_key` alone (prefixed ``K:``), which lookups must also consult.
    """
    tol = default_tolerances() if tolerances is None else tolerances
    return _keys(
        description.outer.codes.tobytes(), _hole_signature(description), tol.max_key_variants
    )


@lru_cache(maxsize=65536)
def _keys(codes: bytes, holes: str, cap: int) -> frozenset[str]:
    code_list = np.frombuffer(codes, dtype=np.int64).tolist()
    options = [_alternatives(c) for c in code_list]
    if math.prod(len(o) for o in options) > cap:
        kinds = np.asarray(code_list, dtype=np.int64) & lb.KIND_BIT
        return frozenset({"K:" + _kinds_key(kinds.tobytes()) + ":" + holes})
    return frozenset(
        "".join(_token(c) for c in _least_rotation(combo)) + ":" + holes
        for combo in itertools.product(*options)
    )


def clear_key_caches() -> None:
    """Empty the memoised key computations (for cold-start timings)."""
    _kinds_key.cache_clear()
    _primary_key.cache_clear()
    _keys.cache_clear()


# ---------------------------------------------------------------------- block evaluation
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


def _positions_agree(ref_iv: FloatArray, cand_iv: FloatArray, margin: float) -> NDArray[np.bool_]:
    """Cone positions agree within the margin: strict of each within loose of the other."""
    rs, rl = (
        _cone_bits(ref_iv[..., 0], ref_iv[..., 1], -margin),
        _cone_bits(ref_iv[..., 0], ref_iv[..., 1], margin),
    )
    cs, cl = (
        _cone_bits(cand_iv[..., 0], cand_iv[..., 1], -margin),
        _cone_bits(cand_iv[..., 0], cand_iv[..., 1], margin),
    )
    return np.asarray(((rs & ~cl) == 0) & ((cs & ~rl) == 0))


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


def evaluate_block(
    ref: Pack,
    cand: Pack,
    tol: Tolerances,
    use_color: bool,
    base: NDArray[np.bool_] | None = None,
) -> BlockResult:
    """Match every candidate against every reference of two packs, vectorised.

    Both packs must have the same node count, hole count and hole node counts; ``base`` is
    `prefilter`'s result when already known. The alignment of all pairs and offsets is one
    matrix product; scores and holes are computed only for label-compatible entries.
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
    rss = cand.sumsq[ti] + ref.sumsq[si] - 2.0 * np.sqrt(dot * dot + crs * crs)
    sc = np.sqrt(np.maximum(rss, 0.0) / (n * ref.area[si]))
    k = offsets[kk]
    if ref.hole_codes:
        ok, hole_score = _holes(ref, cand, (ti, si, np.arctan2(crs, dot)), tol)
        sc = sc + hole_score
        ti, si, k, sc, dot, crs = ti[ok], si[ok], k[ok], sc[ok], dot[ok], crs[ok]
    return BlockResult(ti, si, k, sc, dot, crs)


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
    rss = cand.sumsq[pi] + ref.sumsq[pi] - 2.0 * np.sqrt(dot * dot + crs * crs)
    sc = np.sqrt(np.maximum(rss, 0.0) / (n * ref.area[pi]))
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
            ok &= ((rs & ~cl) == 0) & ((cs & ~rl) == 0)  # as `_positions_agree`
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


# ------------------------------------------------------------------------------ match
def _signature(d: Description) -> tuple[int, ...]:
    return (len(d.outer.codes), *(len(h.boundary.codes) for h in d.holes))


def is_continuous(d: Description) -> bool:
    """True for rotationally continuous figures: circles, with only concentric circular holes."""

    def circle(codes: CodeArray) -> bool:
        if len(codes) != 4:
            return False
        curve = (codes & lb.KIND_BIT) == 1
        semi = ((codes >> lb.T_MASK_SHIFT) >> lb.SEMICIRCLE) & 1 == 1
        return bool(curve.sum() == 2 and np.all(semi[curve]))

    if d.type_curve != ONLY_CURVES or not circle(d.outer.codes):
        return False
    return all(h.position == ("C",) and circle(h.boundary.codes) for h in d.holes)


def _wrap(a: float) -> float:
    w = math.remainder(a, 2.0 * math.pi)
    return math.pi if w == -math.pi else w


def match(
    reference: Description | Figure,
    candidate: Description | Figure,
    tolerances: Tolerances | None = None,
    use_color: bool = True,
) -> Match | None:
    """Match a candidate against a reference.

    Args:
        reference: Reference description (or figure, described with ``tolerances``).
        candidate: Candidate description (or figure).
        tolerances: Bands, margins and thresholds; None: bundled defaults.
        use_color: Compare colours (a figure without colour matches any colour).

    Returns:
        A `Match`, or None when size, colour, type, nodes or holes disagree.

    Raises:
        MatchError: Arguments of the wrong type.
    """
    tol = default_tolerances() if tolerances is None else tolerances
    ref = as_description(reference, tol)
    cand = as_description(candidate, tol)
    if _signature(ref) != _signature(cand) and sorted(_signature(ref)[1:]) != sorted(
        _signature(cand)[1:]
    ):
        return None
    if len(ref.outer.codes) != len(cand.outer.codes) or len(ref.holes) != len(cand.holes):
        return None
    if ref.type_hole != cand.type_hole or ref.type_curve != cand.type_curve:
        return None
    ref_pack = pack([ref])
    res = evaluate_block(ref_pack, pack([cand]), tol, use_color)
    if len(res.k) == 0:
        return None
    scores = res.score
    thetas = [_wrap(float(t)) for t in res.theta]
    same = equivalent_entries(
        np.zeros(len(scores), dtype=np.int64), res.k, scores, ref_pack.self_residual, tol
    )
    chosen = min(np.flatnonzero(same).tolist(), key=lambda j: abs(thetas[j]))
    # Listed too: rotations the residual barely tells from it (a nearly symmetric shape).
    near = [j for j in range(len(scores)) if scores[j] <= scores.min() + tol.symmetry_residual]
    equivalent = [chosen, *sorted((j for j in near if j != chosen), key=lambda j: abs(thetas[j]))]
    n = len(ref.outer.codes)
    k = int(res.k[chosen])
    return Match(
        rotation=thetas[chosen],
        rotations=tuple(thetas[j] for j in equivalent),
        score=float(scores[chosen]),
        correspondence=tuple((i + k) % n for i in range(n)),
        offset=k,
        continuous=is_continuous(ref) and is_continuous(cand),
    )


__all__ = [
    "BlockResult",
    "Match",
    "canonical_key",
    "canonical_keys",
    "clear_key_caches",
    "coarse_key",
    "cyclic_compat_by_offset",
    "evaluate_block",
    "equivalent_entries",
    "evaluate_pairs",
    "is_continuous",
    "match",
    "pack",
    "prefilter",
    "self_residuals",
    "take",
]
