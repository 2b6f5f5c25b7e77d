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
from numpy.typing import NDArray
from scipy.optimize import linear_sum_assignment
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from qshape.errors import MatchError
from qshape.geometry import FloatArray
from qshape.theory.description import Description, describe_many
from qshape.theory.evaluator import (
    Pack,
    cyclic_compat_by_offset,
    equivalent_entries,
    evaluate_block,
    evaluate_pairs,
    pack,
    prefilter,
    take,
)
from qshape.theory.figure import Figure
from qshape.theory.keys import canonical_key, canonical_keys, coarse_key
from qshape.theory.matching import as_description, check_match_inputs
from qshape.theory.slot_classes import SlotClasses, transport
from qshape.theory.slot_classes import slot_classes as find_slot_classes
from qshape.theory.tolerances import Tolerances

IntArray = NDArray[np.int64]

METHODS = ("optimal", "greedy")

_BLOCK_ELEMENTS = 4_000_000
"""Largest tiles x slots x nodes^2 evaluated at once (memory bound of one block, ~100 MB)."""


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


@dataclass(frozen=True)
class _Block:
    """Tiles and slots of one tile-group x slot-group pair linked by size and colour.

    Attributes:
        tiles: Global tile indices, ascending, shape (T,).
        slots: Global slot indices, ascending, shape (S,).
        tpack: The tiles' arrays.
        spack: The slots' arrays.
        base: (T, S) bool, size and colour agree.
    """

    tiles: IntArray
    slots: IntArray
    tpack: Pack
    spack: Pack
    base: NDArray[np.bool_]


def _groups(descs: Sequence[Description], tol: Tolerances) -> dict[str, tuple[list[int], set[str]]]:
    """Descriptions by canonical key: (members ascending, union of their admissible keys).

    Keys are generated once per distinct set of node codes (copies of a class mostly share
    them), not once per description.
    """
    raw: dict[bytes | tuple[bytes, ...], list[int]] = defaultdict(list)
    for i, d in enumerate(descs):
        if d.holes:
            raw[(d.outer.codes.tobytes(), *(h.boundary.codes.tobytes() for h in d.holes))].append(i)
        else:
            raw[d.outer.codes.tobytes()].append(i)
    out: dict[str, tuple[list[int], set[str]]] = {}
    for members in raw.values():
        rep = descs[members[0]]
        key = canonical_key(rep)
        if key in out:
            have, keys = out[key]
            have.extend(members)
            keys |= canonical_keys(rep, tol)
        else:
            out[key] = (members, set(canonical_keys(rep, tol)))
    for members, _ in out.values():
        members.sort()
    return out


def _blocks(
    tiles: Sequence[Description],
    slots: Sequence[Description],
    tol: Tolerances,
    use_color: bool,
) -> list[_Block]:
    """Blocks of candidate pairs, looked up through canonical-key buckets.

    Tiles and slots are grouped by the key of their measured labels; a tile group meets only the
    slot groups sharing one of its admissible keys (or its coarse key when too ambiguous to
    expand). Each such pair of groups splits into the connected components of its size/colour
    agreement (in practice one per tile class).
    """
    tile_groups = _groups(tiles, tol)
    slot_groups = _groups(slots, tol)
    slot_keys = list(slot_groups)
    by_key: dict[str, set[int]] = defaultdict(set)
    by_coarse: dict[str, set[int]] = defaultdict(set)
    for gi, key in enumerate(slot_keys):
        members, admissible = slot_groups[key]
        by_coarse[coarse_key(slots[members[0]])].add(gi)
        for k in admissible:
            by_key[k].add(gi)
    blocks: list[_Block] = []
    slot_packs: dict[int, Pack] = {}
    for members, keys in tile_groups.values():
        coarse = coarse_key(tiles[members[0]])
        found: set[int] = set(by_key.get(coarse, ()))
        if coarse in keys:  # too ambiguous to expand: every slot with the same coarse key
            found |= by_coarse.get(coarse, set())
        for k in keys:
            found |= by_key.get(k, set())
        t_idx = np.array(members)
        tpack = pack([tiles[m] for m in members])
        for gi in sorted(found):
            s_idx = np.array(slot_groups[slot_keys[gi]][0])
            if gi not in slot_packs:
                slot_packs[gi] = pack([slots[m] for m in s_idx])
            spack = slot_packs[gi]
            base = prefilter(spack, tpack, tol, use_color)
            bt, bs = np.nonzero(base)
            if len(bt) == 0:
                continue
            t_count, s_count = base.shape
            graph = coo_matrix(
                (np.ones(len(bt)), (bt, t_count + bs)), shape=(t_count + s_count, t_count + s_count)
            )
            _, comp = connected_components(graph, directed=False)
            for c in np.unique(comp[bt]).tolist():
                ct = np.flatnonzero(comp[:t_count] == c)
                cs = np.flatnonzero(comp[t_count:] == c)
                blocks.append(
                    _Block(
                        t_idx[ct], s_idx[cs], take(tpack, ct), take(spack, cs), base[np.ix_(ct, cs)]
                    )
                )
    return blocks


def _dense(block: _Block, tol: Tolerances) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Best alignment of every (tile, slot) pair of a hole-free block, as matrices.

    Every cyclic offset of every pair is fitted at once (one matrix product per chunk of
    tiles); per pair, the offsets within ``tol.symmetry_residual`` of its least residual and
    a symmetry of the slot apart from it (``tol.symmetry_tolerance``) are equivalent, and the
    one of least rotation magnitude (largest cosine) is kept, as in `Match.rotation`.

    Returns:
        (score, dot, cross), each (T, S): the residual (inf where the pair does not match) and
        the kept offset's sums of dot and cross products; the rotation turning the tile onto
        the slot is ``arctan2(cross, dot)`` (computed only for the pairs that are used).
    """
    ref, cand = block.spack, block.tpack
    n = ref.codes.shape[1]
    t_count, s_count = len(block.tiles), len(block.slots)
    score = np.full((t_count, s_count), np.inf)
    dot_out = np.ones((t_count, s_count))
    crs_out = np.zeros((t_count, s_count))
    compat_all = cyclic_compat_by_offset(ref.codes, cand.codes)  # (T, n, S)
    r = ref.pts.reshape(s_count, 2 * n)
    r_perp = np.stack([ref.pts[..., 1], -ref.pts[..., 0]], axis=-1).reshape(s_count, 2 * n)
    rr = np.concatenate([r, r_perp]).T  # (2n, 2S)
    scale = n * ref.area
    chunk = max(1, _BLOCK_ELEMENTS // max(1, s_count * n * n))
    cols = np.arange(s_count)
    for a in range(0, t_count, chunk):
        rows = slice(a, min(a + chunk, t_count))
        compat = compat_all[rows] & block.base[rows, None, :]
        offsets = np.flatnonzero(compat.any(axis=(0, 2)))
        if len(offsets) == 0:
            continue
        k_count = len(offsets)
        m = compat.shape[0]
        ok = compat[:, offsets, :]  # (m, K, S)
        idx = (np.arange(n)[None, :] + offsets[:, None]) % n  # (K, n)
        cp = cand.pts[rows][:, idx, :].reshape(m * k_count, 2 * n)
        prod = (cp @ rr).reshape(m, k_count, 2 * s_count)
        dot, crs = prod[..., :s_count], prod[..., s_count:]
        mag = np.multiply(dot, dot)  # in place below: sqrt(dot^2 + cross^2)
        sq = np.multiply(crs, crs)
        mag += sq
        np.sqrt(mag, out=mag)
        # The residual falls as the fit magnitude grows: the best offset has the largest.
        np.putmask(mag, ~ok, -np.inf)  # incompatible: never the best, never equivalent
        kt = np.argmax(mag, axis=1)  # (m, S) index into offsets of the best fit
        top = np.take_along_axis(mag, kt[:, None, :], axis=1)[:, 0, :]  # (m, S)
        sums = cand.sumsq[rows, None] + ref.sumsq[None, :]
        best = np.sqrt(np.maximum(sums - 2.0 * top, 0.0) / scale)  # inf: nothing compatible
        # Equivalent offsets: residual within symmetry_residual of the best, i.e. a fit
        # magnitude of at least `floor`.
        bound = best + tol.symmetry_residual
        floor = 0.5 * (sums - bound * bound * scale)
        cosine = np.divide(dot, mag, out=sq, where=mag > 0.0)  # reuses the buffer
        np.putmask(cosine, mag == 0.0, 1.0)  # a zero fit: rotation 0
        np.putmask(cosine, mag < floor[:, None, :], -2.0)
        # ... and only a symmetry of the slot away from the best offset.
        shift = (offsets[None, :, None] - offsets[kt][:, None, :]) % n  # (m, K, S)
        sym = ref.self_residual[cols[None, None, :], shift] <= tol.symmetry_tolerance
        np.putmask(cosine, ~sym, -2.0)
        kb = np.argmax(cosine, axis=1)  # first of the least |rotation| (largest cosine)
        at = np.arange(m)[:, None] * k_count + kb  # (m, S) row of the kept offset
        mag_sel = mag.reshape(m * k_count, s_count)[at, cols]
        chosen = np.sqrt(np.maximum(sums - 2.0 * mag_sel, 0.0) / scale)
        chosen[top == -np.inf] = np.inf
        score[rows] = chosen
        flat_prod = prod.reshape(m * k_count, 2 * s_count)
        dot_out[rows] = flat_prod[at, cols]
        crs_out[rows] = flat_prod[at, s_count + cols]
    return score, dot_out, crs_out


_Pairs = tuple[IntArray, IntArray, FloatArray, FloatArray]
"""Matching pairs as parallel arrays: (tile, slot, score, rotation)."""


def _concat_parts(parts: list[_Pairs]) -> _Pairs:
    """Concatenate pair arrays from several blocks (empty arrays for none)."""
    if not parts:
        empty = np.zeros(0)
        return empty.astype(np.int64), empty.astype(np.int64), empty, empty
    tiles, slots, scores, rotations = zip(*parts, strict=True)
    return (
        np.concatenate(tiles),
        np.concatenate(slots),
        np.concatenate(scores),
        np.concatenate(rotations),
    )


def _evaluate(
    block: _Block, tol: Tolerances, use_color: bool
) -> tuple[IntArray, IntArray, FloatArray, FloatArray]:
    """Every matching pair of a block: (tile, slot, score, rotation), global indices."""
    if not block.tpack.hole_codes:
        score, dot, crs = _dense(block, tol)
        ti, si = np.nonzero(np.isfinite(score))
        theta = np.arctan2(crs[ti, si], dot[ti, si])
        return block.tiles[ti], block.slots[si], score[ti, si], theta
    return _evaluate_entries(block, tol, use_color)


def _evaluate_entries(
    block: _Block, tol: Tolerances, use_color: bool
) -> tuple[IntArray, IntArray, FloatArray, FloatArray]:
    """`_evaluate` through `evaluate_block`'s matching entries (blocks with holes)."""
    n = block.tpack.codes.shape[1]
    chunk = max(1, _BLOCK_ELEMENTS // max(1, len(block.slots) * n * n))
    parts: list[tuple[IntArray, IntArray, FloatArray, FloatArray]] = []
    for a in range(0, len(block.tiles), chunk):
        rows = np.arange(a, min(a + chunk, len(block.tiles)))
        res = evaluate_block(block.spack, take(block.tpack, rows), tol, use_color, block.base[rows])
        if len(res.k) == 0:
            continue
        pair = res.ti * len(block.slots) + res.si  # entries come ordered by pair
        starts = np.flatnonzero(np.r_[True, pair[1:] != pair[:-1]])
        counts = np.diff(np.r_[starts, len(pair)])
        group = np.repeat(np.arange(len(starts)), counts)
        equiv = equivalent_entries(
            group, res.k, res.score, block.spack.self_residual[res.si[starts]], tol
        )
        key = np.full(len(pair), np.inf)
        key[equiv] = np.abs(np.arctan2(res.cross[equiv], res.dot[equiv]))
        low = np.minimum.reduceat(key, starts)
        hit = np.flatnonzero(key == np.repeat(low, counts))
        first = hit[np.r_[True, pair[hit][1:] != pair[hit][:-1]]]
        parts.append(
            (
                block.tiles[rows[res.ti[first]]],
                block.slots[res.si[first]],
                res.score[first],
                np.arctan2(res.cross[first], res.dot[first]),
            )
        )
    return _concat_parts(parts)


def _diagonal(block: _Block, tol: Tolerances, use_color: bool) -> list[Assignment] | None:
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


def _merged(blocks: list[_Block], n_tiles: int, n_slots: int) -> list[list[int]]:
    """Blocks grouped so that no tile or slot lies in two groups (ambiguous keys link them)."""
    if not blocks:
        return []
    n_blocks = len(blocks)
    rows = np.r_[
        np.repeat(np.arange(n_blocks), [len(b.tiles) for b in blocks]),
        np.repeat(np.arange(n_blocks), [len(b.slots) for b in blocks]),
    ]
    cols = np.r_[
        n_blocks + np.concatenate([b.tiles for b in blocks]),
        n_blocks + n_tiles + np.concatenate([b.slots for b in blocks]),
    ]
    size = n_blocks + n_tiles + n_slots
    graph = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(size, size))
    _, label = connected_components(graph, directed=False)
    groups: dict[int, list[int]] = defaultdict(list)
    for b in range(n_blocks):
        groups[int(label[b])].append(b)
    return list(groups.values())


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
    parts = [_evaluate(b, tol, use_color) for b in _blocks(tiles, slots, tol, use_color)]
    return _concat_parts(parts)


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
    blocks = _blocks(td, reps, tol, use_color)
    out: list[Assignment] = []
    for group in _merged(blocks, len(td), len(reps)):
        g_tiles = np.unique(np.concatenate([blocks[b].tiles for b in group]))
        g_classes = np.unique(np.concatenate([blocks[b].slots for b in group]))
        g_slots = np.sort(np.concatenate([classes[c] for c in g_classes.tolist()]))
        if len(g_slots) == len(g_classes):  # only single slots: the pairwise path
            out.extend(_subset(td, sd, g_tiles, g_slots, tol, method, use_color))
            continue
        parts = [_evaluate(blocks[b], tol, use_color) for b in group]
        t, c, score, _ = _concat_parts(parts)
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
    blocks: Sequence[_Block],
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
    blocks = _blocks(td, sd, tol, use_color)
    out: list[Assignment] = []
    for group in _merged(blocks, len(td), len(sd)):
        if method == "greedy" and len(group) == 1:
            fast = _diagonal(blocks[group[0]], tol, use_color)
            if fast is not None:
                out.extend(fast)
                continue
        if len(group) == 1 and not blocks[group[0]].tpack.hole_codes:
            out.extend(_single(blocks[group[0]], tol, method, len(sd)))
            continue
        parts = [_evaluate(blocks[b], tol, use_color) for b in group]
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


def _single(block: _Block, tol: Tolerances, method: str, n_slots: int) -> list[Assignment]:
    """Assign within one hole-free block from its dense score matrix."""
    score, dot, crs = _dense(block, tol)
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


__all__ = ["METHODS", "Assignment", "assign", "feasible_pairs"]
