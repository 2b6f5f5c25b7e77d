"""Assigning tiles to slots: the paper's greedy loop and an optimal assignment.

Both methods look candidates up through canonical keys (`qshape.theory.matching.canonical_keys`):
tiles and slots are grouped by the key of their measured labels, and a tile group is compared
only with the slot groups sharing one of its admissible keys (or its coarse key, for figures
with too many ambiguous labels to expand). Within such a pair of groups, the size/colour filter
splits the candidates into blocks (in practice one per tile class); blocks sharing a tile or a
slot are merged. Then, per group:

* "greedy" (the paper's loop): if the k-th tile matches the k-th slot for every k, that is the
  loop's result and nothing else is evaluated; otherwise every pair of the group is matched in
  one vectorised block and the loop runs over the matching pairs.
* "optimal": every pair of the group is matched in one vectorised block
  (`qshape.theory.matching.evaluate_block`) and scipy's linear_sum_assignment picks the most
  matches,
  then the least total residual.

No Python loop ever runs over tile x slot pairs.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

from qshape.errors import MatchError
from qshape.geometry import FloatArray
from qshape.theory.blocks import (
    Block,
    IntArray,
    block_pairs,
    candidate_blocks,
    concat_parts,
    dense_scores,
    merged_groups,
)
from qshape.theory.description import Description, describe_many
from qshape.theory.evaluator import evaluate_pairs
from qshape.theory.figure import Figure
from qshape.theory.matching import as_description, check_match_inputs
from qshape.theory.pack import take
from qshape.theory.slot_classes import SlotClasses, transport
from qshape.theory.slot_classes import slot_classes as find_slot_classes
from qshape.theory.tolerances import Tolerances

METHODS = ("optimal", "greedy")


@dataclass(frozen=True)
class Assignment:
    """One tile placed in one slot.

    Attributes:
        tile: Index into the tiles list.
        slot: Index into the slots list.
        rotation: Rotation [rad], CCW in the y-up frame, turning the tile onto the slot (the
            equivalent rotation of smallest magnitude for symmetric shapes).
        score: Alignment residual of the pair (see `qshape.Match.score`); lower is better.
    """

    tile: int
    slot: int
    rotation: float
    score: float


def _diagonal(block: Block, tol: Tolerances, use_color: bool) -> list[Assignment] | None:
    """The greedy loop's result when the k-th tile matches the k-th slot for every k.

    Then each tile in order finds its first free matching slot at once, as in the paper's loop,
    so only these pairs are evaluated. None when some diagonal pair does not match.
    """
    m = min(len(block.tiles), len(block.slots))
    rows = np.arange(m)
    if not block.base[rows, rows].all():
        return None
    ok, score, rotation = evaluate_pairs(
        take(block.spack, rows), take(block.tpack, rows), tol, use_color
    )
    if not ok.all():
        return None
    return [
        Assignment(int(t), int(s), float(r), float(c))
        for t, s, r, c in zip(
            block.tiles[:m].tolist(),
            block.slots[:m].tolist(),
            rotation.tolist(),
            score.tolist(),
            strict=True,
        )
    ]


def feasible_pairs(
    tiles: Sequence[Description],
    slots: Sequence[Description],
    tol: Tolerances,
    use_color: bool,
) -> tuple[IntArray, IntArray, FloatArray, FloatArray]:
    """Every matching (tile, slot) pair, found through canonical-key buckets.

    Returns:
        (tile, slot, score, rotation) arrays of equal length, in no particular order.
    """
    parts = [block_pairs(b, tol, use_color) for b in candidate_blocks(tiles, slots, tol, use_color)]
    return concat_parts(parts)


def _descriptions(items: Sequence[Description | Figure], tol: Tolerances) -> list[Description]:
    if all(type(x) is Description for x in items):  # the usual case: nothing to describe
        return list(items)  # type: ignore[arg-type]
    figs = [x for x in items if isinstance(x, Figure)]
    if not figs:
        return [as_description(x, tol) for x in items]
    described = iter(describe_many(figs, tol))
    return [next(described) if isinstance(x, Figure) else as_description(x, tol) for x in items]


def assign(
    tiles: Sequence[Description | Figure],
    slots: Sequence[Description | Figure],
    tolerances: Tolerances | None = None,
    method: str = "optimal",
    use_color: bool = True,
    *,
    slot_classes: bool = True,
) -> list[Assignment]:
    """Assign tiles to slots; unmatched tiles are left out.

    Args:
        tiles: Tile descriptions (or figures).
        slots: Slot descriptions (or figures).
        tolerances: Bands and thresholds; None: bundled defaults.
        method: "greedy": the paper's loop (each tile in order takes the first unmatched slot
            that matches it). "optimal": as many matched tiles as possible, then the least total
            residual score (scipy's linear_sum_assignment per connected group of candidates).
        use_color: Compare colours.
        slot_classes: Compare each tile with one slot per class of identical slots (see
            `qshape.theory.slot_classes`); False: with every slot it may match (slower on large
            designs of few classes; among identical slots the choice may differ).

    Returns:
        Assignments sorted by tile index.

    Raises:
        MatchError: Unknown method, or arguments that are not descriptions or figures.
    """
    if method not in METHODS:
        raise MatchError(f"unknown assign method {method!r}; allowed: {', '.join(METHODS)}")
    tol = check_match_inputs(tiles, slots, tolerances, use_color)
    td = _descriptions(tiles, tol)
    sd = _descriptions(slots, tol)
    if not td or not sd:
        return []
    if not slot_classes:
        return _assign_pairwise(td, sd, tol, method, use_color)
    found = find_slot_classes(sd, tol, use_color)
    classes = found.members
    if len(classes) == len(sd):  # no two slots alike: compare with every slot
        return _assign_pairwise(td, sd, tol, method, use_color)
    reps = [sd[int(m[0])] for m in classes]
    blocks = candidate_blocks(td, reps, tol, use_color)
    out: list[Assignment] = []
    for group in merged_groups(blocks, len(td), len(reps)):
        g_tiles = np.unique(np.concatenate([blocks[b].tiles for b in group]))
        g_classes = np.unique(np.concatenate([blocks[b].slots for b in group]))
        g_slots = np.sort(np.concatenate([classes[c] for c in g_classes.tolist()]))
        if len(g_slots) == len(g_classes):  # only single slots: the pairwise path
            out.extend(_subset(td, sd, g_tiles, g_slots, tol, method, use_color))
            continue
        parts = [block_pairs(blocks[b], tol, use_color) for b in group]
        t, c, score, _ = concat_parts(parts)
        if len(t) == 0:
            continue
        if method == "greedy":
            pt, pc = _greedy_classes(t, c, classes)
        else:
            pt, pc = _optimal_classes(t, c, score, classes, g_classes)
        placed = _finish([blocks[b] for b in group], found, pt, pc, tol, use_color)
        if placed is None:  # a member differs from its representative at a threshold
            placed = _subset(td, sd, g_tiles, g_slots, tol, method, use_color)
        out.extend(placed)
    out.sort(key=lambda x: x.tile)
    return out


def _subset(  # noqa: PLR0913, PLR0917
    td: Sequence[Description],
    sd: Sequence[Description],
    tiles: IntArray,
    slots: IntArray,
    tol: Tolerances,
    method: str,
    use_color: bool,
) -> list[Assignment]:
    """`_assign_pairwise` on some tiles and slots (ascending), in the full lists' indices."""
    part = _assign_pairwise(
        [td[i] for i in tiles.tolist()], [sd[i] for i in slots.tolist()], tol, method, use_color
    )
    return [Assignment(int(tiles[a.tile]), int(slots[a.slot]), a.rotation, a.score) for a in part]


def _greedy_classes(
    t: IntArray, c: IntArray, classes: Sequence[IntArray]
) -> tuple[IntArray, IntArray]:
    """The paper's loop over slot classes: each tile in order takes the first free slot.

    A tile matching a class matches every slot of it, so the first free matching slot is the
    least next-free member over the tile's classes (one pointer per class); classes fill in
    member order.

    Returns:
        (tile, class) of the pairs made, tiles ascending.
    """
    order = np.lexsort((c, t))
    tl, cl = t[order].tolist(), c[order].tolist()
    taken: dict[int, int] = defaultdict(int)
    members = {k: classes[k].tolist() for k in set(cl)}
    out_t: list[int] = []
    out_c: list[int] = []
    i, n = 0, len(tl)
    while i < n:
        tile, best, best_slot = tl[i], -1, -1
        while i < n and tl[i] == tile:
            k = cl[i]
            p = taken[k]
            if p < len(members[k]) and (best < 0 or members[k][p] < best_slot):
                best, best_slot = k, members[k][p]
            i += 1
        if best >= 0:
            taken[best] += 1
            out_t.append(tile)
            out_c.append(best)
    return np.asarray(out_t, dtype=np.int64), np.asarray(out_c, dtype=np.int64)


def _optimal_classes(
    t: IntArray,
    c: IntArray,
    score: FloatArray,
    classes: Sequence[IntArray],
    g_classes: IntArray,
) -> tuple[IntArray, IntArray]:
    """Most tiles, then least total residual, over slot classes (see `transport`).

    Returns:
        (tile, class) of the pairs made, tiles ascending.
    """
    local = np.searchsorted(g_classes, c)
    capacity = np.array([len(classes[k]) for k in g_classes.tolist()], dtype=np.int64)
    used = transport(t, local, score, capacity)
    return t[used], c[used]


def _finish(  # noqa: PLR0913, PLR0917
    blocks: Sequence[Block],
    found: SlotClasses,
    t: IntArray,
    c: IntArray,
    tol: Tolerances,
    use_color: bool,
) -> list[Assignment] | None:
    """Assignments of (tile, class) pairs, each with its own rotation and residual.

    Within a class, the tiles (ascending) take its slots in index order. Pairs are matched in
    one vectorised pass per block and class, from the blocks' tile arrays and the classes' slot
    arrays. None when some pair does not match after all (a slot told apart from its class's
    representative only at a threshold).
    """
    order = np.lexsort((t, c))
    t, c = t[order], c[order]
    first = np.searchsorted(c, c, side="left")
    rank = np.arange(len(t)) - first  # position of the pair within its class
    done = np.zeros(len(t), dtype=bool)
    out: list[Assignment] = []
    for block in blocks:
        sel = ~done & np.isin(c, block.slots) & np.isin(t, block.tiles)
        done |= sel
        for k in np.unique(c[sel]).tolist():
            e = np.flatnonzero(sel & (c == k))
            slots = found.members[k][rank[e]]
            ok, score, rotation = evaluate_pairs(
                take(found.packs[k], rank[e]),
                take(block.tpack, np.searchsorted(block.tiles, t[e])),
                tol,
                use_color,
            )
            if not ok.all():
                return None
            out.extend(
                Assignment(a, b, r, q)
                for a, b, r, q in zip(
                    t[e].tolist(), slots.tolist(), rotation.tolist(), score.tolist(), strict=True
                )
            )
    return out


def _assign_pairwise(
    td: Sequence[Description],
    sd: Sequence[Description],
    tol: Tolerances,
    method: str,
    use_color: bool,
) -> list[Assignment]:
    """`assign` comparing each tile with every slot it may match (through canonical keys)."""
    blocks = candidate_blocks(td, sd, tol, use_color)
    out: list[Assignment] = []
    for group in merged_groups(blocks, len(td), len(sd)):
        if method == "greedy" and len(group) == 1:
            fast = _diagonal(blocks[group[0]], tol, use_color)
            if fast is not None:
                out.extend(fast)
                continue
        if len(group) == 1 and not blocks[group[0]].tpack.hole_codes:
            out.extend(_single(blocks[group[0]], tol, method, len(sd)))
            continue
        parts = [block_pairs(blocks[b], tol, use_color) for b in group]
        t = np.concatenate([p[0] for p in parts])
        if len(t) == 0:
            continue
        s = np.concatenate([p[1] for p in parts])
        score = np.concatenate([p[2] for p in parts])
        theta = np.concatenate([p[3] for p in parts])
        if method == "greedy":
            out.extend(_greedy(t, s, score, theta, n_slots=len(sd)))
        else:
            members_t = [blocks[b].tiles for b in group]
            members_s = [blocks[b].slots for b in group]
            out.extend(
                _solve(
                    t,
                    s,
                    score,
                    theta,
                    tiles=members_t[0] if len(group) == 1 else np.unique(np.concatenate(members_t)),
                    slots=members_s[0] if len(group) == 1 else np.unique(np.concatenate(members_s)),
                )
            )
    out.sort(key=lambda x: x.tile)
    return out


def _single(block: Block, tol: Tolerances, method: str, n_slots: int) -> list[Assignment]:
    """Assign within one hole-free block from its dense score matrix."""
    score, dot, crs = dense_scores(block, tol)
    feasible = np.isfinite(score)
    if method == "greedy":
        ti, si = np.nonzero(feasible)
        theta = np.arctan2(crs[ti, si], dot[ti, si])
        return _greedy(block.tiles[ti], block.slots[si], score[ti, si], theta, n_slots=n_slots)
    if not feasible.any():
        return []
    big = (min(score.shape) + 1.0) * (float(score[feasible].max()) + 1.0)
    cost = np.where(feasible, score, big)
    rows, cols = linear_sum_assignment(cost)
    keep = feasible[rows, cols]
    rows, cols = rows[keep], cols[keep]
    theta = np.arctan2(crs[rows, cols], dot[rows, cols])
    return [
        Assignment(int(t), int(s), float(r), float(c))
        for t, s, r, c in zip(
            block.tiles[rows].tolist(),
            block.slots[cols].tolist(),
            theta.tolist(),
            score[rows, cols].tolist(),
            strict=True,
        )
    ]


def _solve(
    t: IntArray,
    s: IntArray,
    score: FloatArray,
    theta: FloatArray,
    *,
    tiles: IntArray,
    slots: IntArray,
) -> list[Assignment]:
    """linear_sum_assignment on one component: most matches, then least total score.

    ``tiles`` and ``slots`` are the component's members, ascending; infeasible pairs cost more
    than any set of feasible ones, so the count of matches is maximised first.
    """
    ti = np.searchsorted(tiles, t)
    si = np.searchsorted(slots, s)
    big = (min(len(tiles), len(slots)) + 1.0) * (float(score.max()) + 1.0)
    cost = np.full((len(tiles), len(slots)), big)
    cost[ti, si] = score
    edge = np.full((len(tiles), len(slots)), -1, dtype=np.int64)
    edge[ti, si] = np.arange(len(t))
    rows, cols = linear_sum_assignment(cost)
    keep = cost[rows, cols] < big
    return [
        Assignment(int(t[k]), int(s[k]), float(theta[k]), float(score[k]))
        for k in edge[rows[keep], cols[keep]].tolist()
    ]


def _greedy(
    t: IntArray, s: IntArray, score: FloatArray, theta: FloatArray, *, n_slots: int
) -> list[Assignment]:
    """The paper's loop: each tile in order takes the first free matching slot."""
    order = np.argsort(t * n_slots + s)
    t, s, score, theta = t[order], s[order], score[order], theta[order]
    taken = np.zeros(n_slots, dtype=bool)
    starts = np.flatnonzero(np.r_[True, t[1:] != t[:-1]])
    ends = np.r_[starts[1:], len(t)]
    out = []
    for a, b in zip(starts.tolist(), ends.tolist(), strict=True):
        free = np.flatnonzero(~taken[s[a:b]])
        if len(free):
            e = a + int(free[0])
            taken[s[e]] = True
            out.append(Assignment(int(t[e]), int(s[e]), float(theta[e]), float(score[e])))
    return out


__all__ = ["Assignment", "METHODS", "assign", "feasible_pairs"]
