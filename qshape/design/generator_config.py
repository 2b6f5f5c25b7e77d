"""Parameters of the procedural design generator: `GeneratorConfig` and its vocabularies.

Bundled values: ``configs/design_generator.yaml``; the generator is `qshape.design.generator`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from configs import ConfigError, check_field_types, load_config
from configs.checks import check_fields, checked
from qshape.design.values import parse_color
from qshape.errors import DesignError, GeneratorError

BASE_FAMILIES = ("regular", "convex", "concave", "named", "arcs", "rounded", "bite")
"""The families drawn by default (a `GeneratorConfig` without ``families``)."""
SHAPE_FAMILIES = (*BASE_FAMILIES, "thin")
"""Shape families a class is drawn from (see `qshape.design.generator`'s docstring)."""
HOLE_KINDS = ("circle", "square", "rectangle", "triangle", "pentagon", "hexagon")
"""Hole shapes."""
NAMED = ("parallelogram", "trapezoid", "kite", "arrow", "star", "quarter_disc", "ell")
"""Shapes of the ``named`` family."""
DEFAULT_PALETTE = (
    "#c0392b",
    "#2e6fd1",
    "#e8c33a",
    "#2aa39a",
    "#e07b2a",
    "#3f9e4d",
    "#8e4fb5",
    "#f2f2ee",
    "#d96aa7",
)
"""Colours of the bundled designs and a few more, '#rrggbb'. No near-black: the input belt is
near-black (RGB 0.12), and a tile of its colour is not seen on it."""
CONFIG_NAME = "design_generator"
"""Bundled parameter file, ``configs/design_generator.yaml``."""
_PRE = "GeneratorConfig."


@dataclass(frozen=True)
class GeneratorConfig:
    """Parameters of `DesignGenerator` (lengths in [mm], ranges inclusive ``(low, high)``).

    Attributes:
        mesh_mm: Mesh (width, height), in [mm].
        joint_mm: Joint between tiles, in [mm].
        margin_mm: Border of the mesh left empty, in [mm].
        tiles: Range of the number of slots of a design.
        classes: Range of the number of shape-and-colour classes (at most the slots drawn;
            slots beyond it are further copies of the classes).
        size_mm: Range of a tile's size: twice its largest distance from its area centroid,
            in [mm]. The mesh is cut into cells of ``size_mm[1] + joint_mm``.
        min_feature_mm: Smallest straight edge, arc chord, hole size (inscribed diameter) and
            material between a hole and the outline or another hole, in [mm].
        min_sagitta_mm: Smallest depth of an arc off its chord, in [mm].
        min_arc_chord_mm: Smallest chord of an arc, in [mm] (arcs turning less than 180 deg).
        max_sagitta_ratio: Largest arc sagitta / chord of the ``arcs`` and ``bite`` families
            (dimensionless; 0.5 is a half circle).
        families: Weight of each of `SHAPE_FAMILIES` (missing: 0; at least one > 0; the
            default: 1 for each of `BASE_FAMILIES`).
        hole_probability: Chance that a class has holes.
        two_hole_probability: Chance that a holed class has a second hole.
        centred_hole_probability: Chance that a class's first hole is centred.
        recolor_probability: Chance that a new class repeats an earlier class's shape in
            another colour.
        turns_deg: Slot turns are drawn uniform in [0, turns_deg) (0: every slot at 0 deg).
        palette: Colours, '#rrggbb' (at least one).
        grout_color: Joint colour, '#rrggbb'.
        max_tries: Draws of one shape (or one design) before giving up with `GeneratorError`.
    """

    mesh_mm: tuple[float, float] = checked((230.0, 230.0), gt=0)
    joint_mm: float = checked(2.0, gt=0)
    margin_mm: float = checked(3.0, ge=0)
    tiles: tuple[int, int] = checked((6, 16), ge=1)
    classes: tuple[int, int] = checked((3, 9), ge=1)
    size_mm: tuple[float, float] = (30.0, 50.0)
    min_feature_mm: float = checked(6.0, gt=0)
    min_sagitta_mm: float = checked(5.0, gt=0)
    min_arc_chord_mm: float = checked(20.0, gt=0)
    max_sagitta_ratio: float = checked(0.3, gt=0, le=0.5)
    families: dict[str, float] = field(default_factory=lambda: dict.fromkeys(BASE_FAMILIES, 1.0))
    hole_probability: float = checked(0.3, ge=0, le=1)
    two_hole_probability: float = checked(0.2, ge=0, le=1)
    centred_hole_probability: float = checked(0.5, ge=0, le=1)
    recolor_probability: float = checked(0.2, ge=0, le=1)
    turns_deg: float = checked(360.0, ge=0, le=360)
    palette: tuple[str, ...] = DEFAULT_PALETTE
    grout_color: str = "#d9d4c7"
    max_tries: int = checked(200, ge=1)

    def __post_init__(self) -> None:
        """Raise `GeneratorError` naming the parameter and what is allowed."""
        try:
            check_field_types(self)
        except ConfigError as exc:
            raise GeneratorError(str(exc)) from exc
        check_fields(self, GeneratorError, qualify=True)
        self._check_lengths()
        self._check_counts()
        self._check_draws()
        self._check_colours()
        self._check_mesh_holds_the_tiles()

    def _check_lengths(self) -> None:
        lo_s, hi_s = self.size_mm
        least = 4.0 * self.min_feature_mm
        if not least <= lo_s <= hi_s:
            raise GeneratorError(
                f"{_PRE}size_mm must be (low, high) with 4 x min_feature_mm ({least:g}) <= low "
                f"<= high, got {self.size_mm}"
            )
        if self.min_sagitta_mm > self.max_sagitta_ratio * lo_s:
            raise GeneratorError(
                f"{_PRE}min_sagitta_mm {self.min_sagitta_mm} is deeper than max_sagitta_ratio x "
                f"size_mm[0] ({self.max_sagitta_ratio * lo_s:g} mm) allows"
            )

    def _check_counts(self) -> None:
        for name in ("tiles", "classes"):
            lo, hi = getattr(self, name)
            if not lo <= hi:
                raise GeneratorError(f"{_PRE}{name} must be (low, high) with low <= high")
        if self.classes[0] > self.tiles[1]:
            raise GeneratorError(
                f"{_PRE}classes: the least number of classes ({self.classes[0]}) exceeds the "
                f"most slots ({self.tiles[1]}); allowed: classes[0] <= tiles[1]"
            )

    def _check_draws(self) -> None:
        unknown = sorted(set(self.families) - set(SHAPE_FAMILIES))
        if unknown:
            raise GeneratorError(
                f"{_PRE}families: unknown {unknown}; allowed: {list(SHAPE_FAMILIES)}"
            )
        weights = list(self.families.values())
        if any(not (math.isfinite(w) and w >= 0.0) for w in weights) or not sum(weights) > 0:
            raise GeneratorError(
                f"{_PRE}families: weights must be >= 0 with one > 0, got {dict(self.families)}"
            )

    def _check_colours(self) -> None:
        if not self.palette:
            raise GeneratorError(f"{_PRE}palette must hold at least one '#rrggbb' colour")
        try:
            for c in (*self.palette, self.grout_color):
                parse_color(c, f"{_PRE}palette")
        except DesignError as exc:
            raise GeneratorError(str(exc)) from exc

    def _check_mesh_holds_the_tiles(self) -> None:
        cells = self.cells()
        if self.tiles[1] > cells[0] * cells[1]:
            raise GeneratorError(
                f"{_PRE}tiles: a {self.mesh_mm[0]:g} x {self.mesh_mm[1]:g} mm mesh (margin "
                f"{self.margin_mm:g} mm) holds at most {cells[0] * cells[1]} tiles of size_mm up "
                f"to {self.size_mm[1]:g} at a {self.joint_mm:g} mm joint; asked for up to "
                f"{self.tiles[1]}: lower tiles or size_mm, or enlarge mesh_mm"
            )

    @classmethod
    def load(
        cls, name_or_path: str | Path | None = CONFIG_NAME, **overrides: Any
    ) -> GeneratorConfig:
        """Load the bundled ``configs/design_generator.yaml`` (or another file) strictly.

        Raises:
            configs.ConfigError: Unknown key or wrong type.
            GeneratorError: A value out of range.
        """
        return load_config(cls, name_or_path, **overrides)

    def cells(self) -> tuple[int, int]:
        """(columns, rows) of the mesh's cells, one tile each."""
        pitch = self.size_mm[1] + self.joint_mm
        usable = [m - 2.0 * self.margin_mm + self.joint_mm for m in self.mesh_mm]
        return (max(0, int(usable[0] // pitch)), max(0, int(usable[1] // pitch)))


__all__ = [
    "CONFIG_NAME",
    "DEFAULT_PALETTE",
    "HOLE_KINDS",
    "NAMED",
    "BASE_FAMILIES",
    "SHAPE_FAMILIES",
    "GeneratorConfig",
]
