"""Matching one candidate against one reference: `match` and its result `Match`.

A reference and a candidate match when (as in the paper) their qualitative sizes and colours
agree, their type flags agree, their outer node strings are equal cyclically, and their holes
agree in position and boundary. Here "equal" means compatible: every label component has a
common admissible label, so measurements near a band edge still match (see `qshape.theory.labels`).

A measured tile is not its design: its relevant points may lie up to
``Tolerances.point_tolerance`` away (manufacturing, rough edges, pixels), and between short
edges that moves an angle or a length ratio further than the configured margins. So when a
pair has no label-compatible offset, each candidate label also admits its neighbouring label
when its measurement lies within the configured margin plus the change that displacement
causes (computed per node from the candidate's own edge lengths); such a pair matches only if
its alignment residual is at most ``Tolerances.uncertainty_residual``. Labels and bands stay
qualitative; only the admissible neighbours widen, and only as far as the tolerance reaches.
`qshape.assign` looks tiles up by their exact labels' canonical keys and does not use it.

The cyclic comparison also gives the correspondence, hence the rotation that turns the candidate
onto the reference: the least-squares rotation (2D Procrustes, no reflection) of the candidate's
relevant points onto the reference's under that correspondence, a curve's maximum-curvature
point weighing ``Tolerances.curve_point_weight`` (its place along a flat maximum is measured far
less well than a corner's), refined by fitting the candidate's edges to the reference's edge
lines too (``Tolerances.rotation_corner_share``: a measured corner is the intersection of lines
fitted over whole edges, and a misfitted short edge slides its corners along the long ones;
`qshape.assign` weighs every point alike and fits points alone). Holes are compared after
that
rotation, in the reference's cardinal frame; a hole boundary is compared cyclically (a deliberate
robustness change from the paper's fixed start vertex, which a noisy vertex can move).

`match_best` picks the reference a measured figure matches best. When the figure as measured
matches none, its structure may be what is off (a corner cut in two, added, or placed along its
edge): it tries the figure's structural neighbours (`qshape.theory.neighbours`), each under the
stricter
``Tolerances.neighbour_residual``, and answers only when exactly one reference is reached so.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import TypeVar

import numpy as np

from qshape.errors import MatchError
from qshape.geometry import wrap_angle
from qshape.theory import labels as lb
from qshape.theory.description import ONLY_CURVES, Description, describe
from qshape.theory.evaluator import BlockResult, equivalent_entries, evaluate_block, evaluate_pairs
from qshape.theory.figure import Figure
from qshape.theory.keys import canonical_key, canonical_keys, clear_key_caches, coarse_key
from qshape.theory.labels import CodeArray
from qshape.theory.neighbours import neighbours
from qshape.theory.pack import Pack, cyclic_compat_by_offset, pack, prefilter, self_residuals, take
from qshape.theory.tolerances import Tolerances, resolve_tolerances

K = TypeVar("K")


@dataclass(frozen=True)
class Match:
    """Result of a successful `match`.

    Attributes:
        rotation: Rotation in [rad], counter-clockwise in the y-up frame, in (-pi, pi], that
            turns the candidate (about its centroid) onto the reference: the best fit, or of
            the rotations a symmetry of the reference apart from it (its geometry decides,
            ``Tolerances.symmetry_tolerance``, not its labels), the one of smallest magnitude.
            For y_down (image) figures a CCW rotation in y-up is clockwise in pixel
            coordinates' math sense, i.e. counter-clockwise as seen on screen.
        rotations: `rotation` first, then every other rotation whose residual is within
            ``Tolerances.symmetry_residual`` of the best, smallest magnitude first: the
            shape's symmetries (a square 4 values, an equilateral triangle 3) and, for a
            nearly symmetric shape, the turns its fit can barely tell apart.
        score: Alignment residual: RMS distance between corresponding relevant points after the
            rotation, divided by sqrt(reference area), plus the same measure for hole centroids.
            Dimensionless; 0 is perfect, lower is better.
        correspondence: For each reference node i, the index of the corresponding candidate node.
        offset: Candidate node index corresponding to the reference's first node (the paper's
            ``vertex02``).
        continuous: True when both shapes are rotationally continuous (circles, concentric
            rings): every rotation fits; `rotation` is then just the fitted one.
        neighbour: None when the candidate matched as measured; else the structural
            neighbour of it that matched (`match_best`), whose nodes ``correspondence`` and
            ``offset`` index.
    """

    rotation: float
    rotations: tuple[float, ...]
    score: float
    correspondence: tuple[int, ...]
    offset: int
    continuous: bool = False
    neighbour: Description | None = None


def as_description(obj: Description | Figure, tol: Tolerances) -> Description:
    """A `Description` from a description or a figure.

    Raises:
        MatchError: Anything else.
    """
    if isinstance(obj, Description):
        return obj
    if isinstance(obj, Figure):
        return describe(obj, tol)
    raise MatchError(f"expected a qshape Description or Figure, got {type(obj).__name__}")


def check_flag(value: object, name: str) -> None:
    """Raise `MatchError` unless ``value`` is a bool (``use_color=`` and the like)."""
    if not isinstance(value, bool | np.bool_):
        raise MatchError(f"{name} must be True or False, got {value!r}")


def check_match_inputs(
    tiles: object, slots: object, tolerances: object, use_color: object
) -> Tolerances:
    """Validate `assign`'s inputs; return the tolerances to use (None: bundled defaults).

    Raises:
        MatchError: ``tiles`` or ``slots`` not a sequence of descriptions or figures, or a
            non-bool ``use_color``.
        ToleranceError: ``tolerances`` not a `Tolerances` (or None).
    """
    check_items(tiles, "tiles")
    check_items(slots, "slots")
    check_flag(use_color, "use_color")
    return resolve_tolerances(tolerances)


def check_items(items: object, name: str) -> None:
    """Raise `MatchError` unless ``items`` is a sequence of descriptions or figures."""
    if not isinstance(items, Sequence) or isinstance(items, str | bytes):
        raise MatchError(
            f"{name} must be a sequence of qshape Descriptions or Figures, got "
            f"{type(items).__name__}"
        )
    for k, x in enumerate(items):
        if not isinstance(x, Description | Figure):
            raise MatchError(
                f"{name}[{k}] must be a qshape Description or Figure, got {type(x).__name__}"
            )


def _signature(d: Description) -> tuple[int, ...]:
    return (len(d.outer.codes), *(len(h.boundary.codes) for h in d.holes))


def is_continuous(d: Description) -> bool:
    """True for rotationally continuous figures: circles, with only concentric circular holes."""

    def circle(codes: CodeArray) -> bool:
        if len(codes) != 4:
            return False
        curve = (codes & lb.KIND_BIT) == 1
        semi = ((codes >> lb.T_MASK_SHIFT) >> lb.SEMICIRCLE) & 1 == 1
        return bool(curve.sum() == 2 and np.all(semi[curve]))

    if d.type_curve != ONLY_CURVES or not circle(d.outer.codes):
        return False
    return all(h.position == ("C",) and circle(h.boundary.codes) for h in d.holes)


def match(
    reference: Description | Figure,
    candidate: Description | Figure,
    tolerances: Tolerances | None = None,
    use_color: bool = True,
) -> Match | None:
    """Match a candidate against a reference.

    Args:
        reference: Reference description (or figure, described with ``tolerances``).
        candidate: Candidate description (or figure).
        tolerances: Bands, margins and thresholds; None: bundled defaults.
        use_color: Compare colours (a figure without colour matches any colour).

    Returns:
        A `Match`, or None when size, colour, type, nodes or holes disagree.

    Raises:
        MatchError: Reference or candidate not a description or figure, or a non-bool flag.
        ToleranceError: ``tolerances`` not a `Tolerances`.
    """
    tol = resolve_tolerances(tolerances)
    check_flag(use_color, "use_color")
    ref = as_description(reference, tol)
    cand = as_description(candidate, tol)
    if _signature(ref) != _signature(cand) and sorted(_signature(ref)[1:]) != sorted(
        _signature(cand)[1:]
    ):
        return None
    if len(ref.outer.codes) != len(cand.outer.codes) or len(ref.holes) != len(cand.holes):
        return None
    if ref.type_hole != cand.type_hole or ref.type_curve != cand.type_curve:
        return None
    ref_pack = pack([ref])
    res = evaluate_block(ref_pack, pack([cand]), tol, use_color, measured=True)
    if len(res.k) == 0:
        return None
    scores = res.score
    thetas = [wrap_angle(float(t)) for t in res.theta]
    same = equivalent_entries(
        np.zeros(len(scores), dtype=np.int64),
        res.k,
        scores,
        ref_pack.self_residual,
        tol,
        hole_turn=res.hole_turn,
    )
    chosen = min(np.flatnonzero(same).tolist(), key=lambda j: abs(thetas[j]))
    # Listed too: rotations the residual barely tells from it (a nearly symmetric shape).
    near = [j for j in range(len(scores)) if scores[j] <= scores.min() + tol.symmetry_residual]
    equivalent = [chosen, *sorted((j for j in near if j != chosen), key=lambda j: abs(thetas[j]))]
    n = len(ref.outer.codes)
    k = int(res.k[chosen])
    return Match(
        rotation=thetas[chosen],
        rotations=tuple(thetas[j] for j in equivalent),
        score=float(scores[chosen]),
        correspondence=tuple((i + k) % n for i in range(n)),
        offset=k,
        continuous=is_continuous(ref) and is_continuous(cand),
    )


def match_best(
    references: Mapping[K, Description | Figure],
    candidate: Description | Figure,
    tolerances: Tolerances | None = None,
    use_color: bool = True,
) -> tuple[K, Match] | None:
    """The reference a measured candidate matches best, trying its structural neighbours.

    First the candidate as measured: of the references it matches (`match`), the one with
    the lowest score (the first listed on a tie). When it matches none, its structural
    neighbours (`qshape.theory.neighbours`: one weak corner removed, a chamfer merged, or a weak
    corner slid along its edges) are tried; a neighbour's match counts only when its score is
    at most ``Tolerances.neighbour_residual``, and the result stands only when exactly one
    reference is matched so (ambiguity is no match). The returned `Match` then carries the
    neighbour. ``neighbour_residual`` 0 turns the neighbours off.

    Args:
        references: Reference descriptions (or figures) by key.
        candidate: Candidate description (or figure), typically measured from a picture.
        tolerances: Bands, margins and thresholds; None: bundled defaults.
        use_color: Compare colours.

    Returns:
        (key, match), or None when no reference (or more than one, through neighbours) matches.

    Raises:
        MatchError: A reference or the candidate not a description or figure, a non-bool
            flag, or ``references`` not a mapping.
        ToleranceError: ``tolerances`` not a `Tolerances`.
    """
    tol = resolve_tolerances(tolerances)
    check_flag(use_color, "use_color")
    if not isinstance(references, Mapping):
        raise MatchError(
            f"references must be a mapping of key -> Description or Figure, got "
            f"{type(references).__name__}"
        )
    refs = {key: as_description(ref, tol) for key, ref in references.items()}
    cand = as_description(candidate, tol)
    best: tuple[K, Match] | None = None
    for key, ref in refs.items():
        m = match(ref, cand, tol, use_color)
        if m is not None and (best is None or m.score < best[1].score):
            best = (key, m)
    if best is not None or tol.neighbour_residual <= 0.0:
        return best
    found: dict[K, Match] = {}
    for variant in neighbours(cand, tol):
        for key, ref in refs.items():
            m = match(ref, variant, tol, use_color)
            if m is None or m.score > tol.neighbour_residual:
                continue
            if key not in found or m.score < found[key].score:
                found[key] = replace(m, neighbour=variant)
    if len(found) != 1:
        return None
    ((key, m),) = found.items()
    return key, m


__all__ = [
    "BlockResult",
    "Match",
    "Pack",
    "as_description",
    "check_flag",
    "check_items",
    "check_match_inputs",
    "canonical_key",
    "canonical_keys",
    "clear_key_caches",
    "coarse_key",
    "cyclic_compat_by_offset",
    "evaluate_block",
    "equivalent_entries",
    "evaluate_pairs",
    "is_continuous",
    "match",
    "match_best",
    "pack",
    "prefilter",
    "self_residuals",
    "take",
]
