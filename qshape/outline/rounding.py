"""Round outlines and cut-off corners after simplification.

Curved outlines that fit a circle become two semicircles; corners cut off or rounded by the pixel
grid are merged back into one.
"""

from __future__ import annotations

import math

import numpy as np

from qshape.geometry import BoolArray, FloatArray
from qshape.outline.samples import norm, roll_last


def snap_circles(
    res: FloatArray,
    sign: FloatArray,
    results: list[tuple[FloatArray, BoolArray]],
    tol: float,
) -> None:
    """Replace, in place, each curved result whose samples fit a circle by two semicircles.

    Algebraic (Kasa) circle fits of all outlines at once: x^2 + y^2 + D x + E y + F = 0.
    The new points start at the result's first point's bearing and keep the orientation.
    """
    curved = np.array([len(m) > 0 and bool(m.any()) for _, m in results])
    if not curved.any():
        return
    idx = np.flatnonzero(curved)
    pts = res[idx]  # (C, n, 2)
    c0 = np.stack([pts[..., 0].mean(axis=1), pts[..., 1].mean(axis=1)], axis=1)[:, None, :]
    q = pts - c0  # centred: better conditioned
    a = np.concatenate([q, np.ones(q.shape[:2] + (1,))], axis=2)  # (C, n, 3)
    b = -(q**2).sum(axis=2)  # (C, n)
    ata = np.einsum("cni,cnj->cij", a, a)
    atb = np.einsum("cni,cn->ci", a, b)
    sol = np.linalg.solve(ata, atb[..., None])[..., 0]  # (C, 3)
    centre = -0.5 * sol[:, :2]
    r2 = (centre**2).sum(axis=1) - sol[:, 2]
    r = np.sqrt(np.maximum(r2, 0.0))
    dev = norm(q[..., 0] - centre[:, None, 0], q[..., 1] - centre[:, None, 1]) - r[:, None]
    rms = np.sqrt((dev**2).mean(axis=1))
    good = (r2 > 0.0) & (rms <= tol * r)
    steps = np.arange(_CIRCLE_POINTS) * (2.0 * math.pi / _CIRCLE_POINTS)
    for j in np.flatnonzero(good).tolist():
        f = int(idx[j])
        cen = centre[j] + c0[j, 0]
        first = results[f][0][0] - cen
        ang = math.atan2(first[1], first[0]) + sign[f] * steps
        new = cen + r[j] * np.column_stack([np.cos(ang), np.sin(ang)])
        results[f] = (new, np.arange(_CIRCLE_POINTS) % 2 == 1)


_CIRCLE_POINTS = 4
"""A circle as relevant points: start, middle, end of two semicircle arcs."""


_PARALLEL_SIN = 1e-3
"""Edges whose unit directions' cross product is below this are parallel."""


def closed_perimeter(points: FloatArray) -> float:
    """Perimeter of closed relevant points (k, 2) (0 for none)."""
    if len(points) == 0:
        return 0.0
    step = roll_last(points.T, -1) - points.T
    return float(norm(step[0], step[1]).sum())


def with_chamfers(
    results: list[tuple[FloatArray, BoolArray]],
    fraction: float,
    which: list[int],
    scale: list[float] | None = None,
) -> list[int]:
    """Indices (among ``which``) of the results `merge_chamfers` would change, all at once.

    ``scale``: per entry of ``which``, the perimeter the fraction applies to (default: the
    result's own).
    """
    chosen = [results[f] for f in which]
    sizes = np.array([len(m) for _, m in chosen], dtype=np.int64)
    if sizes.sum() == 0:
        return []
    pts = np.concatenate([q.reshape(-1, 2) for q, _ in chosen])
    mask = np.concatenate([m for _, m in chosen])
    start = np.repeat(np.cumsum(sizes) - sizes, sizes)
    size = np.repeat(sizes, sizes)
    local = np.arange(len(mask)) - start
    nxt1 = start + (local + 1) % size
    nxt2 = start + (local + 2) % size
    d1 = np.hypot(*(pts[nxt1] - pts).T)
    d2 = np.hypot(*(pts[nxt2] - pts).T)
    owner = np.repeat(np.arange(len(chosen)), sizes)
    per = np.bincount(owner, d1, minlength=len(chosen)) if scale is None else np.array(scale)
    limit = fraction * per[owner]
    corner = ~mask
    one = corner & corner[nxt1] & (d1 < limit) & (size > 3)  # noqa: PLR2004
    two = corner & mask[nxt1] & corner[nxt2] & (d2 < limit) & (size > 4)  # noqa: PLR2004
    return [which[k] for k in np.unique(owner[one | two]).tolist()]


def merge_chamfers(
    pts: FloatArray, mask: BoolArray, fraction: float, perimeter: float | None = None
) -> tuple[FloatArray, BoolArray]:
    """Merge neighbouring corners closer than ``fraction`` x perimeter (see `OutlineParams`).

    ``perimeter``: the length the fraction applies to (default: the points' own perimeter).

    Two corners count as neighbours when joined by one edge (a cut-off corner) or by one short
    curve (a rounded one). The pair (and the curve point between) becomes the point where
    the edge before meets the edge after when both are straight and not parallel, else the
    pair's midpoint (an arc's chord says little about its tangent).
    """
    while len(pts) > 3:  # noqa: PLR2004 (a figure's fewest points)
        n = len(pts)
        steps = np.roll(pts, -1, axis=0) - pts
        own = float(np.hypot(steps[:, 0], steps[:, 1]).sum())
        limit = fraction * (own if perimeter is None else perimeter)
        best: tuple[float, int, int] | None = None
        corners = np.flatnonzero(~mask)
        for a, b in zip(corners.tolist(), np.roll(corners, -1).tolist(), strict=True):
            gap = (b - a) % n
            if gap not in (1, 2) or n - gap < 3:  # noqa: PLR2004
                continue
            dist = float(np.hypot(*(pts[b] - pts[a])))
            if dist < limit and (best is None or dist < best[0]):
                best = (dist, a, gap)
        if best is None:
            break
        _, a, gap = best
        b = (a + gap) % n
        a0, da = pts[(a - 1) % n], pts[a] - pts[(a - 1) % n]
        b0, db = pts[b], pts[(b + 1) % n] - pts[b]
        cross = float(da[0] * db[1] - da[1] * db[0])
        straight = not (mask[(a - 1) % n] or mask[(b + 1) % n])
        if straight and abs(cross) > _PARALLEL_SIN * float(np.hypot(*da) * np.hypot(*db)):
            t = float((b0 - a0)[0] * db[1] - (b0 - a0)[1] * db[0]) / cross
            new = a0 + t * da
        else:
            new = 0.5 * (pts[a] + b0)
        gone = {(a + k) % n for k in range(gap + 1)}
        keep = np.array([k for k in range(n) if k not in gone])
        at = int(np.searchsorted(keep, a))  # where the pair was, in the kept order
        pts = np.insert(pts[keep], at, new, axis=0)
        mask = np.insert(mask[keep], at, False)
    return pts, mask


__all__ = ["merge_chamfers", "closed_perimeter", "snap_circles", "with_chamfers"]
