"""Rotation-invariant canonical keys of descriptions, for constant-time candidate lookup.

The key of a boundary is the least rotation of its cyclic string of node labels (Booth's
algorithm, linear time), plus a signature of its holes. Two descriptions whose outer boundaries
are label-compatible at some cyclic offset share at least one key of `canonical_keys`, which
expands the admissible labels near band edges.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from functools import lru_cache

import numpy as np

from qshape.theory import labels as lb
from qshape.theory.description import Description
from qshape.theory.tolerances import Tolerances, resolve_tolerances


def least_rotation_start(seq: Sequence[int]) -> int:
    """Start index of the lexicographically least rotation of a cyclic sequence (Booth, O(n))."""
    n = len(seq)
    doubled = list(seq) * 2
    fail = [-1] * (2 * n)
    k = 0
    for j in range(1, 2 * n):
        sj = doubled[j]
        i = fail[j - k - 1]
        while i != -1 and sj != doubled[k + i + 1]:
            if sj < doubled[k + i + 1]:
                k = j - i - 1
            i = fail[i]
        if sj != doubled[k + i + 1]:  # i == -1
            if sj < doubled[k]:
                k = j
            fail[j - k] = -1
        else:
            fail[j - k] = i + 1
    return k


def _least_rotation(seq: tuple[int, ...]) -> tuple[int, ...]:
    k = least_rotation_start(seq)
    return seq[k:] + seq[:k]


_TOKENS_A = "rao"
_TOKENS_C = "xv"
_TOKENS_L = "sEb"
_TOKENS_T = "pSa"


def _token(code: int) -> str:
    is_curve, (a, _), (c, _), (t, _) = lb.decode(code)
    if is_curve:
        return "~" + _TOKENS_C[c] + _TOKENS_T[t]
    return _TOKENS_A[a] + _TOKENS_C[c] + _TOKENS_L[t]


@lru_cache(maxsize=65536)
def _kinds_key(kinds: bytes) -> str:
    seq = tuple(np.frombuffer(kinds, dtype=np.int64).tolist())
    return "".join("c" if k else "v" for k in _least_rotation(seq))


def _hole_signature(d: Description) -> str:
    if not d.holes:
        return "H0"
    parts = sorted(_kinds_key((h.boundary.codes & lb.KIND_BIT).tobytes()) for h in d.holes)
    return "H" + str(len(d.holes)) + "[" + "|".join(parts) + "]"


def coarse_key(d: Description) -> str:
    """Key on the never-ambiguous parts: node kinds (least rotation) and hole signature."""
    return "K:" + _kinds_key((d.outer.codes & lb.KIND_BIT).tobytes()) + ":" + _hole_signature(d)


def canonical_key(description: Description) -> str:
    """Rotation-invariant key of the measured (primary) labels.

    The least rotation of the cyclic string of primary node labels, plus the hole signature
    (count and node kinds of each hole). Two descriptions with equal keys are label-compatible
    at some cyclic offset; near band edges use `canonical_keys`, which expands admissible labels.
    Colour and size are not in the key (they are continuous); `assign` checks them, and the
    holes' positions and labels, after the lookup.
    """
    return _primary_key(description.outer.codes.tobytes()) + ":" + _hole_signature(description)


@lru_cache(maxsize=65536)
def _primary_key(codes: bytes) -> str:
    prim = lb.primary_code(np.frombuffer(codes, dtype=np.int64))
    return "".join(_token(c) for c in _least_rotation(tuple(prim.tolist())))


def _alternatives(code: int) -> list[int]:
    is_curve, (a, am), (c, cm), (t, tm) = lb.decode(code)
    out = []
    a_opts = [a] if is_curve else [k for k in range(3) if am >> k & 1]
    for aa in a_opts:
        for cc in (k for k in range(2) if cm >> k & 1):
            for tt in (k for k in range(3) if tm >> k & 1):
                out.append(lb.encode(is_curve, (aa, 1 << aa), (cc, 1 << cc), (tt, 1 << tt)))
    return out


def canonical_keys(
    description: Description, tolerances: Tolerances | None = None
) -> frozenset[str]:
    """Every canonical key over the admissible labels (see `canonical_key`).

    Two descriptions whose outer boundaries are compatible at some offset share at least one
    key. When a figure admits more than ``tolerances.max_key_variants`` combinations, the set is
    its `coarse_key` alone (prefixed ``K:``), which lookups must also consult.
    """
    tol = resolve_tolerances(tolerances)
    return _keys(
        description.outer.codes.tobytes(), _hole_signature(description), tol.max_key_variants
    )


@lru_cache(maxsize=65536)
def _keys(codes: bytes, holes: str, cap: int) -> frozenset[str]:
    code_list = np.frombuffer(codes, dtype=np.int64).tolist()
    options = [_alternatives(c) for c in code_list]
    if math.prod(len(o) for o in options) > cap:
        kinds = np.asarray(code_list, dtype=np.int64) & lb.KIND_BIT
        return frozenset({"K:" + _kinds_key(kinds.tobytes()) + ":" + holes})
    return frozenset(
        "".join(_token(c) for c in _least_rotation(combo)) + ":" + holes
        for combo in itertools.product(*options)
    )


def clear_key_caches() -> None:
    """Empty the memoised key computations (for cold-start timings)."""
    _kinds_key.cache_clear()
    _primary_key.cache_clear()
    _keys.cache_clear()


__all__ = [
    "canonical_key",
    "canonical_keys",
    "clear_key_caches",
    "coarse_key",
    "least_rotation_start",
]
