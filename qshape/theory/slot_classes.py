"""Slot classes: slots identical up to their pose, and assigning tiles to classes.

Most mosaics are mostly copies of a few tesserae. Slots that are the same figure (same node
codes, area, perimeter, colour and relevant points up to a rotation) match exactly the same
tiles with the same residual, so `qshape.assign` compares each tile with one representative
per class instead of with every slot, and solves a transportation problem (tiles to classes
with capacities) instead of a tiles x slots assignment. Within a class every slot is equally
good by shape; tiles go to its slots in index order (no secondary cost).

"Identical" is measured with ``Tolerances.tie_tolerance`` (a fraction of the figure's size):
relative area and perimeter, RGB distance, and the alignment residual of a member against the
representative (fraction of sqrt(area), as `qshape.Match.score`) must all stay within it.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linprog
from scipy.sparse import coo_matrix, vstack

from qshape.errors import MatchError
from qshape.geometry import FloatArray
from qshape.theory.description import Description
from qshape.theory.evaluator import evaluate_pairs
from qshape.theory.pack import Pack, pack, take
from qshape.theory.tolerances import Tolerances

IntArray = NDArray[np.int64]


def _least_rotation(codes: bytes) -> bytes:
    """The least cyclic rotation of a node-code string (start-point invariant), as bytes."""
    seq = np.frombuffer(codes, dtype=np.int64).tolist()
    best = min(tuple(seq[k:] + seq[:k]) for k in range(len(seq)))
    return np.asarray(best, dtype=np.int64).tobytes()


@dataclass(frozen=True)
class SlotClasses:
    """Slots partitioned into classes of identical figures.

    Attributes:
        members: Slot indices per class, each ascending; classes ordered by their first
            member, which is the class's representative.
        packs: Per class, its members' matching arrays (`qshape.theory.matching.Pack`), in member
            order.
    """

    members: tuple[IntArray, ...]
    packs: tuple[Pack, ...]


def _quantised(slots: Sequence[Description], step: float, use_color: bool) -> FloatArray:
    """(S, 5): log area, log perimeter and RGB of every slot in units of ``step``, rounded."""
    area = np.array([d.area for d in slots])
    perimeter = np.array([d.perimeter for d in slots])
    q = [np.log(np.maximum(area, 1e-300)), np.log(np.maximum(perimeter, 1e-300))]
    if use_color:
        nan3 = (np.nan, np.nan, np.nan)
        color = np.array([nan3 if d.color is None else d.color for d in slots])
        q += [np.nan_to_num(color, nan=-1.0)[:, k] for k in range(3)]  # unknown: its own value
    return np.round(np.stack(q, axis=1) / step)


def slot_classes(
    slots: Sequence[Description], tol: Tolerances, use_color: bool = True
) -> SlotClasses:
    """Partition slots into classes of identical figures (up to pose).

    Slots are first bucketed by node codes (with their admissible labels) up to the starting
    vertex, type flags, and area, perimeter and colour quantised to ``tol.tie_tolerance``;
    within a bucket, the members whose alignment residual against the first is within
    ``tol.tie_tolerance`` form its class, and the rest are split again.

    Args:
        slots: Slot descriptions.
        tol: Tolerances; ``tie_tolerance`` bounds what counts as identical.
        use_color: Colours must agree too (False: shape-only matching, colours ignored).
    """
    step = tol.tie_tolerance
    raw: dict[tuple[str, str, bytes, tuple[bytes, ...]], list[int]] = defaultdict(list)
    for i, d in enumerate(slots):
        holes = tuple(h.boundary.codes.tobytes() for h in d.holes)
        raw[(d.type_hole, d.type_curve, d.outer.codes.tobytes(), holes)].append(i)
    cyclic: dict[bytes, bytes] = {}

    def least(codes: bytes) -> bytes:
        if codes not in cyclic:
            cyclic[codes] = _least_rotation(codes)
        return cyclic[codes]

    shapes: dict[tuple[object, ...], list[int]] = defaultdict(list)
    for (hole_type, curve_type, outer, holes), members in raw.items():
        key = (hole_type, curve_type, least(outer), tuple(sorted(least(h) for h in holes)))
        shapes[key].extend(members)
    q = _quantised(slots, step, use_color)
    classes: list[tuple[IntArray, Pack]] = []
    for members in shapes.values():
        idx = np.sort(np.asarray(members, dtype=np.int64))
        _, inv = np.unique(q[idx], axis=0, return_inverse=True)
        for u in range(int(inv.max()) + 1):
            classes.extend(_split(slots, idx[inv.ravel() == u], tol, use_color))
    classes.sort(key=lambda c: int(c[0][0]))
    return SlotClasses(tuple(c[0] for c in classes), tuple(c[1] for c in classes))


def _split(
    slots: Sequence[Description], bucket: IntArray, tol: Tolerances, use_color: bool
) -> list[tuple[IntArray, Pack]]:
    """Classes of one bucket (ascending indices): members the same figure as their first."""
    group = pack([slots[i] for i in bucket.tolist()])
    out = []
    rest = np.arange(len(bucket))
    while len(rest):
        ok, score, _ = evaluate_pairs(
            take(group, np.full(len(rest), rest[0])), take(group, rest), tol, use_color
        )
        same = ok & (score <= tol.tie_tolerance)
        same[0] = True
        out.append((bucket[rest[same]], take(group, rest[same])))
        rest = rest[~same]
    return out


def transport(
    tile: IntArray, cls: IntArray, score: NDArray[np.float64], capacity: IntArray
) -> NDArray[np.bool_]:
    """Most tiles to classes within capacities, then the least total score.

    Args:
        tile: Tile index of each feasible (tile, class) edge, shape (E,).
        cls: Class index (0..C-1) of each edge, shape (E,).
        score: Residual of each edge, shape (E,).
        capacity: Slots per class, shape (C,).

    Returns:
        (E,) bool: the edges used. Each tile uses at most one edge, each class at most its
        capacity.

    Raises:
        MatchError: The solver failed (it should not: the problem is always feasible).
    """
    if len(tile) == 0:
        return np.zeros(0, dtype=bool)
    per_tile = np.bincount(tile)
    if per_tile.max() <= 1:  # each tile fits one class only: the best tiles per class
        order = np.lexsort((tile, score, cls))
        c_sorted = cls[order]
        starts = np.searchsorted(c_sorted, np.arange(len(capacity)))
        rank = np.arange(len(order)) - starts[c_sorted]
        used = np.zeros(len(tile), dtype=bool)
        used[order[rank < capacity[c_sorted]]] = True
        return used
    return _transport_lp(tile, cls, score, capacity)


def _transport_lp(
    tile: IntArray, cls: IntArray, score: NDArray[np.float64], capacity: IntArray
) -> NDArray[np.bool_]:
    """`transport` for tiles that fit several classes: two linear programmes (HiGHS simplex).

    The constraint matrix of a transportation problem is totally unimodular, so the simplex
    vertex is integral. First the most edges, then the least score at that count.
    """
    e = len(tile)
    tiles, t_row = np.unique(tile, return_inverse=True)
    ones = np.ones(e)
    a_tile = coo_matrix((ones, (t_row, np.arange(e))), shape=(len(tiles), e))
    a_cls = coo_matrix((ones, (cls, np.arange(e))), shape=(len(capacity), e))
    a_ub = vstack([a_tile, a_cls]).tocsr()
    b_ub = np.r_[np.ones(len(tiles)), capacity.astype(float)]
    most = linprog(-ones, A_ub=a_ub, b_ub=b_ub, bounds=(0.0, 1.0), method="highs-ds")
    if most.status != 0:
        raise MatchError(f"assignment to slot classes failed: {most.message}")
    count = round(-most.fun)
    best = linprog(
        score,
        A_ub=a_ub,
        b_ub=b_ub,
        A_eq=ones[None, :],
        b_eq=[float(count)],
        bounds=(0.0, 1.0),
        method="highs-ds",
    )
    if best.status != 0:
        raise MatchError(f"assignment to slot classes failed: {best.message}")
    return np.asarray(best.x > 0.5)


__all__ = ["SlotClasses", "slot_classes", "transport"]
