"""The small features of a slot: arcs (bulges and bites) and straight edges, with their sizes.

An arc's size is its chord (the straight distance between its ends) and its sagitta (how far
its middle lies off the chord), both in [mm]; a straight edge's size is its length. The
generator keeps every feature above its smallest-feature parameters, and the design loader
warns about arcs the camera may not resolve (`small_arcs`).
"""

from __future__ import annotations

import warnings
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

import numpy as np

from qshape.design.paths import Loop
from qshape.design.rules import DesignRules
from qshape.design.slot import Slot
from qshape.errors import DesignError, SmallFeatureWarning


@dataclass(frozen=True)
class EdgeFeature:
    """One edge of a slot's outline or of one of its holes.

    Attributes:
        slot: Slot name.
        loop: ``"outline"`` or ``"hole k"``.
        edge: Edge index in that loop (edge i runs from vertex i to vertex i+1).
        chord_mm: Straight distance between the edge's ends, in [mm].
        sagitta_mm: Distance of the arc's middle from its chord, in [mm]; positive for an arc
            bowing out of the tile (a bulge), negative into it (a bite), 0 for a straight edge.
    """

    slot: str
    loop: str
    edge: int
    chord_mm: float
    sagitta_mm: float

    @property
    def curved(self) -> bool:
        """True for an arc."""
        return self.sagitta_mm != 0.0

    def describe(self) -> str:
        """E.g. ``"outline edge 2: bite, chord 12.0 mm, sagitta 3.0 mm"``."""
        if not self.curved:
            return f"{self.loop} edge {self.edge}: straight, {self.chord_mm:.1f} mm"
        kind = "bulge" if self.sagitta_mm > 0 else "bite"
        return (
            f"{self.loop} edge {self.edge}: {kind}, chord {self.chord_mm:.1f} mm, sagitta "
            f"{abs(self.sagitta_mm):.1f} mm"
        )


def _loop_edges(slot: str, name: str, loop: Loop) -> Iterator[EdgeFeature]:
    v = loop.vertices
    chords = np.hypot(*(np.roll(v, -1, axis=0) - v).T)
    # An edge bowing out of the tile bows into a hole: a hole's positive bulge is a bite.
    sign = 1.0 if name == "outline" else -1.0
    for i, (c, b) in enumerate(zip(chords.tolist(), loop.bulges.tolist(), strict=True)):
        yield EdgeFeature(slot, name, i, float(c), sign * float(b) * float(c) / 2.0)


def edge_features(slot: Slot) -> list[EdgeFeature]:
    """Every edge of the slot's outline and holes, in loop and edge order."""
    path = slot.local_path
    out = list(_loop_edges(slot.name, "outline", path.outer))
    for k, h in enumerate(path.holes):
        out.extend(_loop_edges(slot.name, f"hole {k}", h))
    return out


def small_arcs(slot: Slot, min_sagitta_mm: float, min_chord_mm: float) -> list[EdgeFeature]:
    """Arcs of the slot shallower than ``min_sagitta_mm`` or shorter than ``min_chord_mm``.

    Only arcs turning less than 180 deg count: arcs turning 180 deg or more (a semicircle, a
    circle's halves) are recognised as semicircles and circles, whatever their size.
    """
    return [
        f
        for f in edge_features(slot)
        if f.curved
        and abs(f.sagitta_mm) < f.chord_mm / 2.0 - 1e-9
        and (abs(f.sagitta_mm) < min_sagitta_mm or f.chord_mm < min_chord_mm)
    ]


def check_small_features(slots: Sequence[Slot], rules: DesignRules, pre: str = "") -> None:
    """Warn about (or refuse) slots with arcs below ``rules``' smallest recognised arc.

    Raises:
        DesignError: With ``rules.small_features == "refuse"``, naming the slot and the arc.
    """
    if rules.small_features == "ignore":
        return
    for slot in slots:
        small = small_arcs(slot, rules.min_arc_sagitta_mm, rules.min_arc_chord_mm)
        if not small:
            continue
        text = (
            f"{pre}slot {slot.name!r} has curved features below what the camera recognises "
            f"(arcs need a sagitta >= {rules.min_arc_sagitta_mm:g} mm and a chord >= "
            f"{rules.min_arc_chord_mm:g} mm): " + "; ".join(f.describe() for f in small)
        )
        if rules.small_features == "refuse":
            raise DesignError(f"{text} (small_features: refuse; 'warn' loads it anyway)")
        warnings.warn(text, SmallFeatureWarning, stacklevel=4)


__all__ = ["EdgeFeature", "check_small_features", "edge_features", "small_arcs"]
