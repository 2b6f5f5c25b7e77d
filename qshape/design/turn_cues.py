"""What tells a slot's turns apart, and by how much: the cues a picture must resolve.

A tile is set down right only when its picture fixes its turn to within the placement
tolerance, modulo the slot's symmetry. Three cues decide whether a picture can, each a
distance on the tile in [mm], so each can be compared with what the camera resolves; a fourth
whether the tile itself does:

- **turn shift**: how far the boundary moves, on average, when the tile turns by the placement
  tolerance (the loop that moves most: the outline or one hole, each probed against the whole
  boundary). A nearly round tile moves little: its picture fixes its turn only to a few
  degrees.
- **asymmetry**: the least such move over every turn that is not a symmetry of the slot
  (farther than a window from each): a tile two-fold symmetric to within a few tenths of a
  millimetre, though not exactly, cannot be told from its half turn. A centred hole of
  another symmetry than its outline's moves at the outline's turns, and keeps the tile apart.
- **hole turn gap** (`hole_turn_gap`): where the outline alone turns onto itself at a turn
  that is not a symmetry of the whole tile (a heptagon holding a hexagon hole), how far the
  holes' relevant points move between those turns: the holes alone tell them apart.
- **made turn spread** (`qshape.design.made_turn`): the standard deviation of the turn at which
  a made tile (its vertices off the drawing by the manufacturing deviation) fits its drawing
  best. No camera does better than the tile itself; its turn capability, the tolerance over
  three of these standard deviations, must reach the rules' ``min_turn_capability``.

The generator keeps every cue above its limits and the design loader warns about (or refuses)
slots below the loader's limits (`check_turn_cues`), naming the slot and the cue.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize_scalar
from scipy.spatial import cKDTree

from qshape import geometry as geo
from qshape.design.made_turn import made_turn_sd
from qshape.design.memo import BoundedMemo
from qshape.design.rules import DesignRules
from qshape.design.slot import Slot
from qshape.errors import DesignError, QShapeError, SmallFeatureWarning
from qshape.theory.description import describe
from qshape.theory.figure import Figure
from qshape.theory.matching import match
from qshape.theory.tolerances import Tolerances
from spatial.angles import symmetry_period

_FINE = 10
"""The boundary probed against is sampled this many times finer than the probes."""

_REFINED = 3
"""The lowest turns tried whose asymmetry is refined between their neighbours."""

_XATOL = {"xatol": math.radians(0.05)}
"""Precision of that refinement [rad]."""


@dataclass(frozen=True)
class TurnCues:
    """The cues that fix one slot's turn, in [mm] on the tile (inf: not needed).

    Attributes:
        turn_shift_mm: Mean move of the boundary under a turn of the placement tolerance
            (of the loop, outline or hole, that moves most).
        asymmetry_mm: Least such move under a turn that is not a symmetry of the slot (inf
            for a continuous slot).
        hole_gap_mm: `hole_turn_gap` (inf when the outline alone decides the turn).
        made_turn_sd_deg: Std of a made tile's best-fit turn at the given vertex deviation
            (`qshape.design.made_turn.made_turn_sd`), in [deg] (0: not measured, no deviation
            given or a continuous slot, which has no turn to fix).
    """

    turn_shift_mm: float
    asymmetry_mm: float
    hole_gap_mm: float
    made_turn_sd_deg: float = 0.0

    def capability(self, tolerance_deg: float) -> float:
        """The turn capability: ``tolerance_deg`` over 3 x ``made_turn_sd_deg`` (inf at 0)."""
        if self.made_turn_sd_deg <= 0.0:
            return math.inf
        return tolerance_deg / (3.0 * self.made_turn_sd_deg)


CUES_MEMO_SIZE = 4096
"""Shapes whose rule cues are remembered (`CUES_MEMO`); an entry is a key (the shape's
canonical text, about 0.1-1 kB, and the rules) and four floats: a few MB at most."""
CUES_MEMO: BoundedMemo[TurnCues] = BoundedMemo(CUES_MEMO_SIZE)
"""`rule_cues` by (shape text, rules): the design generator measures a drawn shape's cues
and the design loader measures them again when the drawn design is loaded."""


def _samples(slot: Slot, spacing_mm: float) -> list[np.ndarray]:
    """Samples of each loop (outline, then holes) about the area centroid, each (m, 2) [mm]."""
    loops = (slot.local_path.outer, *slot.local_path.holes)
    return [lp.dense(spacing_mm) for lp in loops]


def turn_cues(
    slot: Slot,
    *,
    tolerance_deg: float,
    window_deg: float,
    step_deg: float,
    spacing_mm: float,
    deviation_mm: float,
    arc_step_mm: float,
) -> TurnCues:
    """The turn cues of ``slot`` (`TurnCues`).

    Args:
        slot: The slot (its shape in its own frame, about its area centroid).
        tolerance_deg: The placement tolerance on the turn [deg].
        window_deg: Turns this close to a symmetry of the slot count as it [deg].
        step_deg: Turns tried for the asymmetry, this far apart [deg].
        spacing_mm: Largest distance between the boundary samples turned [mm].
        deviation_mm: Std of a made tile's vertices off the drawing [mm] (0: the made turn
            spread is not measured).
        arc_step_mm: A made tile's vertices along its arcs, at most this far apart [mm].
    """
    loops = _samples(slot, spacing_mm)
    pts = np.concatenate(loops)
    starts = np.cumsum([0, *(len(lp) for lp in loops[:-1])])
    sizes = np.array([len(lp) for lp in loops], dtype=float)
    # Probes ``spacing_mm`` apart against a boundary sampled far finer, so a probe's distance
    # is its distance from the boundary, not from the next sample.
    tree = cKDTree(np.concatenate(_samples(slot, spacing_mm / _FINE)))

    def moves(turns_rad: Sequence[float]) -> np.ndarray:
        """Per turn, the mean move of the loop that moves most, shape (len(turns_rad),) [mm]."""
        if not len(turns_rad):
            return np.full(0, math.inf)
        turned = np.concatenate([geo.rotate(pts, t) for t in turns_rad])
        dist = tree.query(turned)[0].reshape(len(turns_rad), len(pts))
        per_loop = np.add.reduceat(dist, starts, axis=1) / sizes
        return np.asarray(per_loop.max(axis=1))

    symmetry = slot.symmetry
    if symmetry == 0:
        return TurnCues(math.inf, math.inf, math.inf)
    tol = math.radians(tolerance_deg)
    shift = float(np.min(moves([tol, -tol])))
    period = symmetry_period(symmetry)
    window = math.radians(window_deg)
    step = math.radians(step_deg)
    turns = [
        t
        for t in np.arange(0.0, 2.0 * math.pi, step).tolist()
        if abs(math.remainder(t, period)) > window
    ]
    coarse = moves(turns)
    asym = float(np.min(coarse, initial=math.inf))
    # The least move lies between two turns tried: refine the lowest few.
    for k in np.argsort(coarse)[:_REFINED].tolist():
        lo, hi = turns[k] - step, turns[k] + step
        res = minimize_scalar(
            lambda t: float(moves([t])[0]), bounds=(lo, hi), method="bounded", options=_XATOL
        )
        if abs(math.remainder(float(res.x), period)) > window:
            asym = min(asym, float(res.fun))
    gap = hole_turn_gap(slot.figure(), symmetry, None)
    made = 0.0
    if deviation_mm > 0.0:
        made = deviation_mm * made_turn_sd(slot, arc_step_mm=arc_step_mm, spacing_mm=spacing_mm)
    return TurnCues(shift, asym, gap, made)


def rule_cues(slot: Slot, rules: DesignRules) -> TurnCues:
    """`turn_cues` of ``slot`` with the settings and tile deviation of ``rules``.

    Remembered by shape and rules (`CUES_MEMO`): the cues depend on nothing else (not the
    slot's pose, name or colour).
    """
    return CUES_MEMO.get(
        (slot.shape_text, rules),
        lambda: turn_cues(
            slot,
            tolerance_deg=rules.turn_tolerance_deg,
            window_deg=rules.turn_window_deg,
            step_deg=rules.turn_step_deg,
            spacing_mm=rules.check_step_mm,
            deviation_mm=rules.tile_deviation_mm,
            arc_step_mm=rules.made_arc_step_mm,
        ),
    )


def hole_turn_gap(figure: Figure, symmetry: int, tolerances: Tolerances | None) -> float:
    """How far the holes' relevant points move between turns only the holes tell apart [unit].

    A turn of the outline onto itself (its description's cyclic matches) that is not a
    symmetry of the whole figure (``symmetry``: 1 none, 0 continuous) is told from the right
    turn by the holes alone. Per such turn, the RMS distance between the holes' relevant points
    turned about the figure's centroid and the unturned ones (best cyclic correspondence,
    all holes together); the least over those turns. A heptagon holding a centred hexagon hole
    is set apart from its next turn only by the hole's 8.6 deg misfit, under a millimetre on a
    6 mm hole. inf when there is no such turn (no holes, or the outline decides alone).
    """
    if not figure.holes or symmetry == 0:
        return math.inf
    try:
        outer = Figure.from_polygon(
            figure.outer.points, [], figure.color, curve_mask=figure.outer.curve_mask
        )
        d = describe(outer, tolerances)
        itself = match(d, d, tolerances)
    except QShapeError:
        return math.inf
    if itself is None or itself.continuous:
        return math.inf
    period = symmetry_period(symmetry)
    c = np.asarray(figure.centroid)
    gap = math.inf
    for r in itself.rotations:
        off = math.remainder(r, period)
        if abs(off) < math.radians(1.0):
            continue  # a symmetry of the whole figure
        sq, count = 0.0, 0
        for h in figure.holes:
            p = np.asarray(h.points) - c
            t = geo.rotate(p, r)
            m = len(p)
            best = min(float(np.sum((np.roll(t, k, axis=0) - p) ** 2)) for k in range(m))
            sq += best
            count += m
        gap = min(gap, math.sqrt(sq / max(count, 1)))
    return gap


def weak_cues(cues: TurnCues, rules: DesignRules) -> list[str]:
    """The cues of one slot below ``rules``' limits, each described in a phrase."""
    out = []
    if cues.turn_shift_mm < rules.min_turn_shift_mm:
        out.append(
            f"a {rules.turn_tolerance_deg:g} deg turn moves its outline {cues.turn_shift_mm:.2f} "
            f"mm on average (the camera fixes the turn from >= {rules.min_turn_shift_mm:g} mm)"
        )
    if cues.asymmetry_mm < rules.min_asymmetry_mm:
        out.append(
            f"a turn that is not one of its symmetries moves its outline only "
            f"{cues.asymmetry_mm:.2f} mm on average (nearly symmetric; the camera tells turns "
            f"apart from >= {rules.min_asymmetry_mm:g} mm)"
        )
    if cues.hole_gap_mm < rules.min_hole_turn_mm:
        out.append(
            f"only its holes tell its outline's turns apart, by {cues.hole_gap_mm:.2f} mm "
            f"(the camera needs >= {rules.min_hole_turn_mm:g} mm)"
        )
    capability = cues.capability(rules.turn_tolerance_deg)
    if capability < rules.min_turn_capability:
        out.append(
            f"a tile whose vertices deviate {rules.tile_deviation_mm:g} mm (std) from the drawing "
            f"fits it best {cues.made_turn_sd_deg:.2f} deg (std) off its turn, whatever the "
            f"camera: turn "
            f"capability {capability:.2f} (the {rules.turn_tolerance_deg:g} deg tolerance over "
            f"3 std; >= {rules.min_turn_capability:g} needed)"
        )
    return out


def check_turn_cues(slots: Sequence[Slot], rules: DesignRules, pre: str = "") -> None:
    """Warn about (or refuse) slots whose turn the camera cannot fix (`weak_cues`).

    Slots of one shape are measured once.

    Raises:
        DesignError: With ``rules.small_features == "refuse"``, naming the slot and the cue.
    """
    if rules.small_features == "ignore":
        return
    known: dict[str, list[str]] = {}
    for slot in slots:
        if slot.shape_key not in known:
            known[slot.shape_key] = weak_cues(rule_cues(slot, rules), rules)
        weak = known[slot.shape_key]
        if not weak:
            continue
        text = f"{pre}slot {slot.name!r}: its turn may not be fixed: " + "; ".join(weak)
        if rules.small_features == "refuse":
            raise DesignError(f"{text} (small_features: refuse; 'warn' loads it anyway)")
        warnings.warn(text, SmallFeatureWarning, stacklevel=4)


__all__ = [
    "CUES_MEMO",
    "CUES_MEMO_SIZE",
    "TurnCues",
    "check_turn_cues",
    "hole_turn_gap",
    "rule_cues",
    "turn_cues",
    "weak_cues",
]
