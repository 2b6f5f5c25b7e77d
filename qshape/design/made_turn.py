"""How well a made tile's own outline fixes its turn, before any camera looks at it.

A made tile is not its drawing: each of its vertices (its corners, and points along its arcs,
`qshape.design.Loop.made_vertices`) sits off the drawing by a small deviation of its own. A
picture, however sharp, then shows the made outline, and the turn at which that outline fits
the drawing best (about their area centroids, as the cell's placement fits it) differs from the
tile's true turn. `made_turn_sd` gives the standard deviation of that difference for
independent deviations of one standard deviation at every vertex, to first order:

- a turn by ``w`` moves the boundary point ``p`` (about the centroid) along its outward normal
  ``n`` by ``w * n . (-p_y, p_x)``; the least-squares turn of a moved boundary weighs each
  point's normal move by that lever;
- a vertex deviation moves the two made edges beside it (linearly along each) and the area
  centroid (the fit is about the made tile's own centroid); both enter the fitted turn
  linearly, so its variance is the deviation's variance times the summed squared weights.

Most tiles come out at 0.2-0.45 deg for a 0.2 mm deviation. A thin crescent whose two arcs
share nearly one centre comes out at about 0.7 deg: turning it about that centre moves its
arcs along themselves, only its tips and short edge fix the turn, and the centroid (far from
the arcs' centre) moves with every vertex. A Monte-Carlo of made copies gives the same spread
(``tests/qshape/test_turn_cues.py``).
"""

from __future__ import annotations

import math

import numpy as np

from qshape import geometry as geo
from qshape.design.slot import Slot
from qshape.geometry import FloatArray

_H = 1e-4
"""Step of the centred differences of the area centroid, in [mm]."""


def _area_moment(loops: list[FloatArray]) -> tuple[FloatArray, FloatArray]:
    """Signed areas (...,) and first moments (..., 2) of polygons (..., n, 2), shoelace."""
    out_a, out_m = [], []
    for v in loops:
        w = np.roll(v, -1, axis=-2)
        cross = geo.cross2(v, w)
        out_a.append(0.5 * cross.sum(axis=-1))
        out_m.append(((v + w) * cross[..., None]).sum(axis=-2) / 6.0)
    return np.asarray(out_a), np.asarray(out_m)


def _centroid_gradients(
    loops: list[FloatArray], areas: FloatArray, moments: FloatArray
) -> list[FloatArray]:
    """Per loop, d(area centroid)/d(vertex), shape (n, 2 [vertex axis], 2 [centroid axis]).

    The region is the first loop less the others (every loop counter-clockwise); ``areas`` and
    ``moments`` are the loops' own (`_area_moment`).
    """
    sign = np.array([1.0] + [-1.0] * (len(loops) - 1))
    area = float(np.dot(sign, areas))
    moment = sign @ moments
    grads = []
    for k, v in enumerate(loops):
        n = len(v)
        g = np.zeros((n, 2, 2))
        for axis in range(2):
            step = np.zeros((n, n, 2))
            step[np.arange(n), np.arange(n), axis] = _H
            (a_up,), (m_up,) = _area_moment([v[None] + step])
            (a_dn,), (m_dn,) = _area_moment([v[None] - step])
            a0, m0 = areas[k], moments[k]
            for a_new, m_new, half in ((a_up, m_up, 1.0), (a_dn, m_dn, -1.0)):
                c = (moment + sign[k] * (m_new - m0)) / (area + sign[k] * (a_new - a0))[:, None]
                g[:, axis, :] += half * c / (2.0 * _H)
        grads.append(g)
    return grads


def made_turn_sd(slot: Slot, *, arc_step_mm: float, spacing_mm: float) -> float:
    """Std of a made tile's best-fit turn per 1 mm std of vertex deviation, in [deg/mm].

    Args:
        slot: The slot (its shape about its area centroid).
        arc_step_mm: Largest distance between a made tile's vertices along an arc [mm].
        spacing_mm: Largest distance between the boundary points fitted [mm].

    Returns:
        The standard deviation in [deg] for independent deviations of 1 mm standard deviation
        along each axis at every vertex (it scales linearly with the deviation); inf for a
        shape no turn moves (a circle).
    """
    path = slot.local_path
    loops = [path.outer.made_vertices(arc_step_mm)]
    loops += [h.made_vertices(arc_step_mm) for h in path.holes]
    sign = np.array([1.0] + [-1.0] * (len(loops) - 1))
    areas, moments = _area_moment(loops)
    centre = (sign @ moments) / float(np.dot(sign, areas))
    v = loops[0] - centre
    n = len(v)
    nxt = np.roll(v, -1, axis=0)
    edge = nxt - v
    length = np.hypot(edge[:, 0], edge[:, 1])
    count = np.maximum(1, np.ceil(length / spacing_mm)).astype(int)
    which = np.repeat(np.arange(n), count)
    t = (np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count) + 0.5) / np.repeat(
        count, count
    )
    p = v[which] + t[:, None] * edge[which]
    normal = np.stack([edge[:, 1], -edge[:, 0]], axis=1)[which] / length[which, None]
    weight = (length / count)[which]
    lever = normal[:, 0] * -p[:, 1] + normal[:, 1] * p[:, 0]
    spread = float(np.sum(weight * lever * lever))
    if spread <= 1e-12 * float(np.sum(weight)) * float(np.max(np.hypot(*v.T))) ** 2:
        return math.inf
    # Fitted turn = sum_j coef_j * n_j . (u_j - dc): u_j from the edge's two vertices, dc from all.
    coef = (-weight * lever / spread)[:, None] * normal
    grad = [np.zeros((len(lp), 2)) for lp in loops]
    np.add.at(grad[0], which, (1.0 - t)[:, None] * coef)
    np.add.at(grad[0], (which + 1) % n, t[:, None] * coef)
    pull = coef.sum(axis=0)
    for k, g in enumerate(_centroid_gradients(loops, areas, moments)):
        grad[k] -= g @ pull
    return math.degrees(math.sqrt(sum(float(np.sum(g * g)) for g in grad)))


__all__ = ["made_turn_sd"]
