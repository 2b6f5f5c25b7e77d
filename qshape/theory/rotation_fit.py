"""The rotation of a match: weighted point sums, and the fit of edges onto the reference's lines.

Curve points weigh `Tolerances.curve_point_weight`; with `Tolerances.rotation_corner_share` below 1
the candidate's edges are also fitted to the reference's edge lines (`edge_rotation`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from qshape.geometry import FloatArray
from qshape.theory import labels as lb
from qshape.theory.pack import Pack
from qshape.theory.tolerances import Tolerances


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


__all__ = ["edge_rotation", "turn_sums"]
