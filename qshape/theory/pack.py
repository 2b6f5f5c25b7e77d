"""Descriptions stacked into arrays, and the cheap tests that rule pairs out before alignment.

A `Pack` holds the descriptions of one node count and hole signature; label compatibility per
cyclic offset, size and colour prefilter pairs before the alignment of `qshape.theory.evaluator`.
"""

from __future__ import annotations

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
    hole_pts: tuple[FloatArray, ...] = ()  # per hole (G, m_h, 2), centred as ``pts``


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
        hole_pts=tuple(h[idx] for h in p.hole_pts),
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
    hole_pts = []
    for h in range(nholes):  # every description's hole h at once
        hp = np.concatenate([d.holes[h].boundary.points for d in descs]).reshape(g, -1, 2)
        hole_pts.append(hp)
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
        hole_pts=tuple(hole_pts),
    )


def cyclic_compat(ref: NDArray[np.int64], cand: NDArray[np.int64]) -> NDArray[np.bool_]:
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
    """`cyclic_compat` laid out (T, n, S): candidate, offset, reference.

    Computed over unique rows (noisy copies of a class mostly share their labels).
    """
    n = ref.shape[1]
    ur, inv_r = np.unique(ref, axis=0, return_inverse=True)
    uc, inv_c = np.unique(cand, axis=0, return_inverse=True)
    idx = (np.arange(n)[None, :] + np.arange(n)[:, None]) % n  # (k, i)
    rolled = uc[:, idx]  # (Uc, k, i)
    ok = np.asarray(lb.compatible(rolled[:, :, None, :], ur[None, None, :, :]).all(axis=-1))
    return np.asarray(ok[inv_c.ravel()][:, :, inv_r.ravel()])


def cone_bits(lo: FloatArray, hi: FloatArray, widen: float) -> NDArray[np.int64]:
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


__all__ = [
    "Pack",
    "cone_bits",
    "cyclic_compat",
    "cyclic_compat_by_offset",
    "pack",
    "prefilter",
    "self_residuals",
    "take",
]
