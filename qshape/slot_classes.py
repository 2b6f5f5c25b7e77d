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

import math
from collections import defaultdict
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linprog
from scipy.sparse import coo_matrix, vstack

from qshape.description import Description
from qshape.errors import MatchError
from qshape.matching import evaluate_pairs, pack
from qshape.tolerances import Tolerances

IntArray = NDArray[np.int64]


def _least_rotation(codes: bytes) -> bytes:
    """The least cyclic rotation of a node-code string (start-point invariant), as bytes."""
    seq = np.frombuffer(codes, dtype=np.int64).tolist()
    best = min(tuple(seq[k:] + seq[:k]) for k in range(len(seq)))
    return np.asarray(best, dtype=np.int64).tobytes()


def _bucket(
    d: Description, step: float, use_color: bool, cyclic: dict[bytes, bytes]
) -> tuple[object, ...]:
    """Hashable key that identical slots share, whatever their pose.

    Node codes (with their admissible labels) up to the starting vertex, hole codes likewise
    (sorted), type flags, and area, perimeter and colour quantised to ``step`` (relative).
    ``cyclic`` memoises `_least_rotation`.
    """

    def least(codes: bytes) -> bytes:
        if codes not in cyclic:
            cyclic[codes] = _least_rotation(codes)
        return cyclic[codes]

    holes = tuple(sorted(least(h.boundary.codes.tobytes()) for h in d.holes))
    color: tuple[object, ...] = ("any",)
    if use_color and d.color is not None:
        color = tuple(round(c / step) for c in d.color)
    return (
        d.type_hole,
        d.type_curve,
        least(d.outer.codes.tobytes()),
        holes,
        round(math.log(max(d.area, 1e-300)) / step),
        round(math.log(max(d.perimeter, 1e-300)) / step),
        color,
    )


def slot_classes(
    slots: Sequence[Description], tol: Tolerances, use_color: bool = True
) -> list[IntArray]:
    """Partition slots into classes of identical figures (up to pose).

    Args:
        slots: Slot descriptions.
        tol: Tolerances; ``tie_tolerance`` bounds what counts as identical.
        use_color: Colours must agree too (False: shape-only matching, colours ignored).

    Returns:
        Member indices per class, each ascending, classes ordered by their first member. The
        first member is the class's representative.
    """
    step = tol.tie_tolerance
    buckets: dict[tuple[object, ...], list[int]] = defaultdict(list)
    cyclic: dict[bytes, bytes] = {}
    for i, d in enumerate(slots):
        buckets[_bucket(d, step, use_color, cyclic)].append(i)
    out: list[IntArray] = []
    for members in buckets.values():
        rest = np.asarray(members, dtype=np.int64)
        while len(rest):
            same = _same_as_first(slots, rest, tol, use_color)
            out.append(rest[same])
            rest = rest[~same]
    out.sort(key=lambda m: int(m[0]))
    return out


def _same_as_first(
    slots: Sequence[Description], idx: IntArray, tol: Tolerances, use_color: bool
) -> NDArray[np.bool_]:
    """Which of ``slots[idx]`` are the same figure as ``slots[idx[0]]`` (the first: True)."""
    if len(idx) == 1:
        return np.ones(1, dtype=bool)
    group = pack([slots[i] for i in idx.tolist()])
    ref = pack([slots[int(idx[0])]] * len(idx))
    ok, score, _ = evaluate_pairs(ref, group, tol, use_color)
    same = ok & (score <= tol.tie_tolerance)
    same[0] = True
    return same


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


__all__ = ["slot_classes", "transport"]
