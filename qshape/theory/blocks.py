"""Candidate pairs of tiles and slots, in blocks matched in one vectorised evaluation each.

Tiles and slots are grouped by canonical key; the size/colour filter splits each pair of groups
into blocks, and blocks sharing a tile or a slot are merged (see `qshape.theory.assign`).
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from qshape.geometry import FloatArray
from qshape.theory.description import Description
from qshape.theory.evaluator import equivalent_entries, evaluate_block
from qshape.theory.keys import canonical_key, canonical_keys, coarse_key
from qshape.theory.pack import Pack, cyclic_compat_by_offset, pack, prefilter, take
from qshape.theory.tolerances import Tolerances

IntArray = NDArray[np.int64]


_BLOCK_ELEMENTS = 4_000_000
"""Largest tiles x slots x nodes^2 evaluated at once (memory bound of one block, ~100 MB)."""


@dataclass(frozen=True)
class Block:
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


def candidate_blocks(
    tiles: Sequence[Description],
    slots: Sequence[Description],
    tol: Tolerances,
    use_color: bool,
) -> list[Block]:
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
    blocks: list[Block] = []
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
                    Block(
                        t_idx[ct], s_idx[cs], take(tpack, ct), take(spack, cs), base[np.ix_(ct, cs)]
                    )
                )
    return blocks


def dense_scores(block: Block, tol: Tolerances) -> tuple[FloatArray, FloatArray, FloatArray]:
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


def concat_parts(parts: list[_Pairs]) -> _Pairs:
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


def block_pairs(
    block: Block, tol: Tolerances, use_color: bool
) -> tuple[IntArray, IntArray, FloatArray, FloatArray]:
    """Every matching pair of a block: (tile, slot, score, rotation), global indices."""
    if not block.tpack.hole_codes:
        score, dot, crs = dense_scores(block, tol)
        ti, si = np.nonzero(np.isfinite(score))
        theta = np.arctan2(crs[ti, si], dot[ti, si])
        return block.tiles[ti], block.slots[si], score[ti, si], theta
    return _evaluate_entries(block, tol, use_color)


def _evaluate_entries(
    block: Block, tol: Tolerances, use_color: bool
) -> tuple[IntArray, IntArray, FloatArray, FloatArray]:
    """`block_pairs` through `evaluate_block`'s matching entries (blocks with holes)."""
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
            group,
            res.k,
            res.score,
            block.spack.self_residual[res.si[starts]],
            tol,
            hole_turn=res.hole_turn,
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
    return concat_parts(parts)


def merged_groups(blocks: list[Block], n_tiles: int, n_slots: int) -> list[list[int]]:
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


__all__ = [
    "Block",
    "IntArray",
    "block_pairs",
    "candidate_blocks",
    "concat_parts",
    "dense_scores",
    "merged_groups",
]
