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
    hole_interval,
)
from qshape.errors import MatchError
from qshape.figure import Figure
from qshape.geometry import FloatArray
from qshape.labels import CodeArray
from qshape.tolerances import Tolerances

_CONE_DEG = 45.0
_N_CONES = 8
_CENTRE_BIT = 1 << _N_CONES


@dataclass(frozen=True)
class Match:
    """Result of a successful `match`.

    Attributes:
        rotation: Rotation in [rad], counter-clockwise in the y-up frame, in (-pi, pi], that
            turns the candidate (about its centroid) onto the reference; of the equivalent
            rotations of a symmetric shape, the one of smallest magnitude. For y_down (image)
            figures a CCW rotation in y-up is clockwise in pixel coordinates' math sense, i.e.
            counter-clockwise as seen on screen.
        rotations: Every equivalent rotation (symmetries of the shape), smallest magnitude
            first; `rotation` is the first. For a square 4 values, for an equilateral triangle 3.
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


def _hole_signature(d: Description) -> str:
    parts = sorted(
        "".join("c" if k else "v" for k in _least_rotation(tuple(
            int(x) for x in (h.boundary.codes & lb.KIND_BIT)
        )))
        for h in d.holes
    )
    return "H" + str(len(d.holes)) + ("[" + "|".join(parts) + "]" if parts else "")


def coarse_key(d: Description) -> str:
    """Key on the never-ambiguous parts: node kinds (least rotation) and hole signature."""
    kinds = tuple(int(x) for x in (d.outer.codes & lb.KIND_BIT))
    return "K:" + "".join("c" if k else "v" for k in _least_rotation(kinds)) + ":" + (
        _hole_signature(d)
    )


def _key_of(codes: tuple[int, ...], d: Description) -> str:
    return "".join(_token(c) for c in _least_rotation(codes)) + ":" + _hole_signature(d)


def canonical_key(description: Description) -> str:
    """Rotation-invariant key of the measured (primary) labels.

    The least rotation of the cyclic string of primary node labels, plus the hole signature
    (count and node kinds of each hole). Two descriptions with equal keys are label-compatible
    at some cyclic offset; near band edges use `canonical_keys`, which expands admissible labels.
    """
    prim = tuple(int(c) for c in lb.primary_code(np.asarray(description.outer.codes)))
    return _key_of(prim, description)


def _alternatives(code: int) -> list[int]:
    is_curve, (a, am), (c, cm), (t, tm) = lb.decode(code)
    out = []
    a_opts = [a] if is_curve else [k for k in range(3) if am >> k & 1]
    for aa in a_opts:
        for cc in (k for k in range(2) if cm >> k & 1):
            for tt in (k for k in range(3) if tm >> k & 1):
                out.append(lb.encode(is_curve, (aa, 1 << aa), (cc, 1 << cc), (tt, 1 << tt)))
    return out


def canonical_keys(description: Description, tolerances: Tolerances | None = None) -> frozenset[
    str
]:
    """Every canonical key over the admissible labels (see `canonical_key`).

    Two descriptions whose outer boundaries are compatible at some offset share at least one
    key. When a figure admits more than ``tolerances.max_key_variants`` combinations, the set is
    its `coarse_key` alone (prefixed ``K:``), which lookups must also consult.
    """
    tol = default_tolerances() if tolerances is None else tolerances
    return _keys_cached(tuple(int(c) for c in description.outer.codes),
                        _hole_signature(description), tol.max_key_variants,
                        coarse_key(description))


@lru_cache(maxsize=65536)
def _keys_cached(codes: tuple[int, ...], holes: str, cap: int, coarse: str) -> frozenset[str]:
    options = [_alternatives(c) for c in codes]
    total = math.prod(len(o) for o in options)
    if total > cap:
        return frozenset({coarse})
    return frozenset(
        "".join(_token(c) for c in _least_rotation(combo)) + ":" + holes
        for combo in itertools.product(*options)
    )


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


def _hole_order(d: Description) -> list[int]:
    """Holes in a canonical order (node count, then kinds), so packs stack consistently."""
    return sorted(range(len(d.holes)), key=lambda h: (
        len(d.holes[h].boundary.codes), int((d.holes[h].boundary.codes & lb.KIND_BIT).sum())))


def pack(descs: Sequence[Description]) -> Pack:
    """Stack descriptions that share node count and hole node counts into arrays."""
    orders = [_hole_order(d) for d in descs]
    descs = [
        d if order == sorted(order) else Description(
            d.type_hole, d.type_curve, d.color, d.area, d.perimeter, d.outer,
            tuple(d.holes[h] for h in order))
        for d, order in zip(descs, orders, strict=True)
    ]
    codes = np.stack([d.outer.codes for d in descs])
    pts = np.stack([d.outer.points for d in descs])
    nholes = len(descs[0].holes)
    hole_codes = tuple(np.stack([d.holes[h].boundary.codes for d in descs])
                       for h in range(nholes))
    hc = np.zeros((len(descs), nholes, 2))
    hi = np.full((len(descs), nholes, 2), np.nan)
    for g, d in enumerate(descs):
        for h, hole in enumerate(d.holes):
            hp = hole.boundary.points
            hc[g, h] = hp.mean(axis=0)
            iv = hole_interval(hp, hole.boundary.curve_mask, np.array([1.0, 0.0]))
            if iv is not None:
                # hole_interval gives clockwise bearings from +x; store CCW angles.
                hi[g, h] = (-iv[1], -iv[0])
    colors = np.array([d.color if d.color is not None else (np.nan,) * 3 for d in descs])
    return Pack(
        codes=codes,
        pts=pts,
        sumsq=np.einsum("gnd,gnd->g", pts, pts),
        area=np.array([d.area for d in descs]),
        perimeter=np.array([d.perimeter for d in descs]),
        color=colors,
        north=np.arctan2(pts[:, 0, 1], pts[:, 0, 0]),
        hole_codes=hole_codes,
        hole_centroid=hc,
        hole_interval=hi,
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


def _cone_bits(lo: FloatArray, hi: FloatArray, widen: float) -> NDArray[np.int64]:
    """Bit k set when the bearing interval [lo, hi] (deg, widened by ``widen``) meets cone k.

    NaN intervals (hole around the centroid) give the centre bit. A negative ``widen`` that
    empties the interval gives 0 (no constraint).
    """
    mid = 0.5 * (lo + hi)
    half = 0.5 * (hi - lo) + widen
    bits = np.zeros(np.shape(mid), dtype=np.int64)
    centre = np.isnan(mid)
    safe_mid = np.where(centre, 0.0, mid)
    safe_half = np.where(centre, -1.0, half)
    for k in range(_N_CONES):
        d = np.abs((k * _CONE_DEG - safe_mid + 180.0) % 360.0 - 180.0)
        bits |= np.where((safe_half >= 0.0) & (d < safe_half + _CONE_DEG / 2), 1 << k, 0)
    return np.asarray(bits | np.where(centre, _CENTRE_BIT, 0))


def _positions_agree(
    ref_iv: FloatArray, cand_iv: FloatArray, margin: float
) -> NDArray[np.bool_]:
    """Cone positions agree within the margin: strict of each within loose of the other."""
    rs, rl = _cone_bits(ref_iv[..., 0], ref_iv[..., 1], -margin), _cone_bits(
        ref_iv[..., 0], ref_iv[..., 1], margin)
    cs, cl = _cone_bits(cand_iv[..., 0], cand_iv[..., 1], -margin), _cone_bits(
        cand_iv[..., 0], cand_iv[..., 1], margin)
    return np.asarray(((rs & ~cl) == 0) & ((cs & ~rl) == 0))


@dataclass(frozen=True)
class BlockResult:
    """Pairwise results for T candidates x S references, per cyclic offset.

    Attributes:
        feasible: (T, S, K) bool: the pair matches at offset ``offsets[k]``.
        theta: (T, S, K) rotation [rad] turning the candidate onto the reference.
        score: (T, S, K) residual score (inf where infeasible).
        offsets: (K,) offsets evaluated (others are label-incompatible for every pair).
    """

    feasible: NDArray[np.bool_]
    theta: FloatArray
    score: FloatArray
    offsets: NDArray[np.int64]


def evaluate_block(ref: Pack, cand: Pack, tol: Tolerances, use_color: bool) -> BlockResult:
    """Match every candidate against every reference of two packs, vectorised.

    Both packs must have the same node count, hole count and hole node counts.
    """
    n = ref.codes.shape[1]
    compat = _cyclic_compat(ref.codes, cand.codes)  # (T, S, n)
    t_count, s_count = cand.codes.shape[0], ref.codes.shape[0]
    base = np.ones((t_count, s_count), dtype=bool)
    if tol.check_size:
        thr = (tol.size_area_threshold if tol.size_area_threshold is not None
               else tol.joint_width * 0.5 * (cand.perimeter[:, None] + ref.perimeter[None, :]))
        base &= np.abs(cand.area[:, None] - ref.area[None, :]) <= thr
    if use_color:
        diff = cand.color[:, None, :] - ref.color[None, :, :]
        dist = np.sqrt(np.einsum("tsd,tsd->ts", diff, diff))
        base &= ~(dist > tol.color_distance)  # unknown colour (NaN) matches any
    compat &= base[:, :, None]
    offsets = np.flatnonzero(compat.any(axis=(0, 1)))
    if len(offsets) == 0:
        empty = np.zeros((t_count, s_count, 0))
        return BlockResult(np.zeros(empty.shape, bool), empty, empty, offsets)
    idx = (np.arange(n)[None, :] + offsets[:, None]) % n  # (K, n)
    cp = cand.pts[:, idx, :]  # (T, K, n, 2)
    dot = np.einsum("tknd,snd->tsk", cp, ref.pts)
    crs = np.einsum("tkn,sn->tsk", cp[..., 0], ref.pts[..., 1]) - np.einsum(
        "tkn,sn->tsk", cp[..., 1], ref.pts[..., 0])
    theta = np.arctan2(crs, dot)
    rss = cand.sumsq[:, None, None] + ref.sumsq[None, :, None] - 2.0 * np.hypot(dot, crs)
    scale = np.sqrt(ref.area)[None, :, None]
    score = np.sqrt(np.maximum(rss, 0.0) / n) / scale
    feasible = compat[:, :, offsets]
    if ref.hole_codes:
        hole_ok, hole_score = _holes(ref, cand, theta, tol)
        feasible = feasible & hole_ok
        score = score + hole_score
    score = np.where(feasible, score, np.inf)
    return BlockResult(feasible, theta, score, offsets)


def _holes(
    ref: Pack, cand: Pack, theta: FloatArray, tol: Tolerances
) -> tuple[NDArray[np.bool_], FloatArray]:
    """Hole agreement and residual for every pair and offset: -> (T, S, K) bool and score."""
    nholes = len(ref.hole_codes)
    best_ok = np.zeros(theta.shape, dtype=bool)
    best_score = np.full(theta.shape, np.inf)
    perms = (list(itertools.permutations(range(nholes))) if nholes <= 4
             else [tuple(range(nholes))])
    scale = np.sqrt(ref.area)[None, :, None]
    c, s = np.cos(theta), np.sin(theta)
    ref_north_deg = np.degrees(ref.north)[None, :, None]
    theta_deg = np.degrees(theta)
    for perm in perms:
        ok = np.ones(theta.shape, dtype=bool)
        sq = np.zeros(theta.shape)
        for h, g in enumerate(perm):
            if ref.hole_codes[h].shape[1] != cand.hole_codes[g].shape[1]:
                ok[:] = False
                break
            labels_ok = np.asarray(
                _cyclic_compat(ref.hole_codes[h], cand.hole_codes[g]).any(axis=-1))
            ok &= labels_ok[:, :, None]
            # Rotate the candidate's hole angle interval, express both as bearings (cw from the
            # reference's north = its first vertex).
            civ = cand.hole_interval[:, g, :][:, None, None, :] + theta_deg[..., None]
            riv = np.broadcast_to(ref.hole_interval[None, :, h, None, :], civ.shape)
            rb = np.stack([ref_north_deg - riv[..., 1], ref_north_deg - riv[..., 0]], axis=-1)
            cb = np.stack([ref_north_deg - civ[..., 1], ref_north_deg - civ[..., 0]], axis=-1)
            rb = np.where(np.isnan(riv), np.nan, rb)
            cb = np.where(np.isnan(civ), np.nan, cb)
            ok &= _positions_agree(rb, cb, tol.cone_margin_deg)
            hc = cand.hole_centroid[:, g, :]
            rx = c * hc[:, None, None, 0] - s * hc[:, None, None, 1]
            ry = s * hc[:, None, None, 0] + c * hc[:, None, None, 1]
            rc = ref.hole_centroid[:, h, :]
            sq = sq + (rx - rc[None, :, None, 0]) ** 2 + (ry - rc[None, :, None, 1]) ** 2
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
    res = evaluate_block(pack([ref]), pack([cand]), tol, use_color)
    if not res.feasible.any():
        return None
    scores = res.score[0, 0]
    order = np.argsort(scores, kind="stable")
    best = int(order[0])
    n = len(ref.outer.codes)
    k = int(res.offsets[best])
    rotations = sorted(
        (_wrap(float(res.theta[0, 0, j])) for j in order
         if res.feasible[0, 0, j] and scores[j] <= scores[best] + tol.symmetry_residual),
        key=abs,
    )
    return Match(
        rotation=rotations[0],
        rotations=tuple(rotations),
        score=float(scores[best]),
        correspondence=tuple((i + k) % n for i in range(n)),
        offset=k,
        continuous=is_continuous(ref) and is_continuous(cand),
    )


__all__ = [
    "BlockResult",
    "Match",
    "canonical_key",
    "canonical_keys",
    "coarse_key",
    "evaluate_block",
    "is_continuous",
    "match",
    "pack",
]
