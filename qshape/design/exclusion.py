"""Tile classes a drawn design must not hold: `ClassExclusion` and `draw_excluding`.

A procedural design drawn for training must not show a held-out design's tiles, or evaluating
on that design would no longer test unseen shapes. "The same tile class" is decided by the
theory that matches tiles to slots: two classes are equal when `qshape.match` matches one's
figure (outline, holes and colour, described qualitatively with the bundled tolerances of
``configs/qshape.yaml``) to the other's, in either direction, colours compared
(``use_color=True``), as a tile of the one would be accepted into a slot of the other. Pose and
size within a qualitative size band do not tell classes apart; a colour does.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from qshape.design.generator import DesignGenerator
from qshape.design.model import Design
from qshape.design.slot import Slot
from qshape.errors import DesignError, ExcludedClassError
from qshape.theory.description import Description, describe
from qshape.theory.matching import match
from qshape.theory.tolerances import Tolerances


@dataclass(frozen=True)
class ExcludedClass:
    """One shape-and-colour class of an excluded design.

    Attributes:
        design: The excluded design's name.
        slot: Name of the class's first slot in that design.
        description: The slot's qualitative description (design millimetres).
    """

    design: str
    slot: str
    description: Description


@dataclass(frozen=True)
class Clash:
    """A drawn slot whose class equals an excluded class.

    Attributes:
        slot: The drawn slot's name.
        excluded: The class it equals.
    """

    slot: str
    excluded: ExcludedClass

    def __str__(self) -> str:
        ex = self.excluded
        return f"slot {self.slot!r} is the class of {ex.design!r} slot {ex.slot!r}"


def _representatives(design: Design) -> list[Slot]:
    """One slot per shape-and-colour class, in slot order."""
    seen: dict[str, Slot] = {}
    for slot in design.slots:
        seen.setdefault(slot.class_key, slot)
    return list(seen.values())


class ClassExclusion:
    """The tile classes of some designs, to keep out of drawn designs (see the module docstring).

    Args:
        designs: The excluded designs.
        tolerances: Description and matching tolerances (None: the bundled ones).
    """

    def __init__(self, designs: Sequence[Design], tolerances: Tolerances | None = None) -> None:
        self.tolerances = tolerances
        self.designs = tuple(d.name for d in designs)
        self.classes = tuple(
            ExcludedClass(d.name, s.name, describe(s.figure(), tolerances))
            for d in designs
            for s in _representatives(d)
        )

    def clashes(self, design: Design) -> list[Clash]:
        """Every class of ``design`` equal to an excluded class (one clash per drawn class)."""
        out = []
        for slot in _representatives(design):
            drawn = describe(slot.figure(), self.tolerances)
            for ex in self.classes:
                if self._equal(ex.description, drawn):
                    out.append(Clash(slot.name, ex))
                    break
        return out

    def _equal(self, a: Description, b: Description) -> bool:
        tol = self.tolerances
        return (match(a, b, tol, use_color=True) is not None) or (
            match(b, a, tol, use_color=True) is not None
        )


def draw_excluding(
    generator: DesignGenerator,
    rng: np.random.Generator,
    exclusion: ClassExclusion,
    tries: int,
    name: str = "procedural",
) -> Design:
    """A design from ``generator`` holding no excluded class, drawn again until one does.

    Raises:
        ExcludedClassError: Every one of ``tries`` draws held an excluded class (names the
            last clash and the excluded designs).
        GeneratorError: The generator's own failure.
        DesignError: ``tries`` < 1.
    """
    if not isinstance(tries, int) or tries < 1:
        raise DesignError(f"tries must be an int >= 1, got {tries!r}")
    last: list[Clash] = []
    for _ in range(tries):
        design = generator.draw(rng, name)
        last = exclusion.clashes(design)
        if not last:
            return design
    raise ExcludedClassError(
        f"every one of {tries} drawn designs held a tile class of the excluded designs "
        f"{list(exclusion.designs)} (last: {last[0]}); widen the generator's families, sizes "
        f"or palette, or allow more tries"
    )


__all__ = ["Clash", "ClassExclusion", "ExcludedClass", "draw_excluding"]
