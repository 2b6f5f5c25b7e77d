"""`DesignRules`: how design outlines are sampled and designs validated.

Bundled values: the ``design`` section of ``configs/vision.yaml``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from qshape.config_sections import load_section
from qshape.errors import DesignError
from spatial.tolerance import MADE_TILE_DEVIATION_MM, PLACEMENT_YAW_TOLERANCE_DEG


@dataclass(frozen=True)
class DesignRules:
    """How outlines are sampled and designs validated.

    Attributes:
        outline_step_mm: Largest distance between consecutive samples of a dense outline, in
            [mm] (straight edges and arcs alike).
        max_arc_deg: Arcs turning more than this are split into equal arcs, each with its own
            maximum-curvature point, in [deg]. 240 keeps (noisy) semicircles whole and splits
            circles given as one arc (the rule of ``OutlineParams.max_curve_turn_deg``).
        check_step_mm: Outline sampling used for the self-crossing, gap and mesh checks, in
            [mm] (vertices are always samples, so straight edges are exact).
        min_gap_fraction: Two slots closer than this fraction of the joint width overlap
            (dimensionless; 0.5 accepts joints narrowed by rounding in a design image).
        mesh_margin_mm: Slots must stay at least this far inside the mesh outline, in [mm]
            (negative values let tiles overhang).
        symmetry_tolerance: A rotation is a symmetry when every rotated outline sample lies
            within this fraction of sqrt(area) of the outline (dimensionless).
        max_symmetry_order: Largest finite rotational symmetry order looked for.
        symmetry_samples: Outline samples used for the symmetry test.
        min_arc_sagitta_mm: Smallest arc depth (sagitta) the cell's camera recognises, in
            [mm]; arcs turning less than 180 deg only (circles and semicircles are recognised
            as such). Measured at the default input camera (2.05 px/mm on the tile tops):
            ``docs/random_designs.md``.
        min_arc_chord_mm: Smallest arc chord the camera recognises, in [mm] (as above).
        turn_tolerance_deg: The placement tolerance on a tile's turn, in [deg]: the turn
            shift below is measured at this turn.
        min_turn_shift_mm: Smallest mean move of a slot's boundary under a turn of
            ``turn_tolerance_deg`` from which the camera fixes the turn within that
            tolerance, in [mm] (`qshape.design.turn_cues`; nearly round tiles move less).
        min_asymmetry_mm: Smallest mean move of the boundary under a turn that is not a
            symmetry of the slot from which the camera tells the two turns apart, in [mm].
        min_hole_turn_mm: Smallest move of the holes' relevant points between turns of the
            outline onto itself that only the holes tell apart, in [mm].
        made_arc_step_mm: A made tile's vertices lie at its corners and at most this far
            apart along its arcs, in [mm] (`qshape.design.Loop.made_vertices`; the cell builds
            its tile meshes so).
        tile_deviation_mm: Standard deviation of a made tile's vertices off its drawing, each
            on its own, in [mm] (manufacturing; by default `spatial.tolerance`'s made-tile
            deviation, which the simulated cell also builds its tiles with).
        min_turn_capability: Smallest turn capability of a slot: ``turn_tolerance_deg`` over
            three standard deviations of the turn at which a made tile fits its drawing best
            (`qshape.design.made_turn.made_turn_sd`), dimensionless. Below 1, the tile's own
            deviation puts its best fit outside the tolerance more often than 3 in 1,000
            tiles, whatever the camera.
        turn_window_deg: Turns closer than this to a symmetry count as it, in [deg].
        turn_step_deg: Turns tried for the asymmetry, this far apart, in [deg] (the lowest
            three are refined between their neighbours).
        small_features: What loading does with a slot holding a smaller arc, or whose turn
            the camera may not fix (the cues above): ``warn`` (a `SmallFeatureWarning` per
            slot naming the slot and the feature), ``refuse`` (a `DesignError`) or ``ignore``.
    """

    outline_step_mm: float = 0.25
    max_arc_deg: float = 240.0
    check_step_mm: float = 1.0
    min_gap_fraction: float = 0.5
    mesh_margin_mm: float = 0.0
    symmetry_tolerance: float = 0.01
    max_symmetry_order: int = 12
    symmetry_samples: int = 512
    min_arc_sagitta_mm: float = 5.0
    min_arc_chord_mm: float = 20.0
    turn_tolerance_deg: float = PLACEMENT_YAW_TOLERANCE_DEG
    min_turn_shift_mm: float = 0.1
    min_asymmetry_mm: float = 0.3
    min_hole_turn_mm: float = 1.5
    made_arc_step_mm: float = 2.0
    tile_deviation_mm: float = MADE_TILE_DEVIATION_MM
    min_turn_capability: float = 1.0
    turn_window_deg: float = 10.0
    turn_step_deg: float = 6.0
    small_features: Literal["warn", "refuse", "ignore"] = "warn"

    def __post_init__(self) -> None:
        """Raise `DesignError` on out-of-range values."""
        if not (self.outline_step_mm > 0.0 and self.check_step_mm > 0.0):
            raise DesignError("outline_step_mm and check_step_mm must be > 0")
        if not 90.0 <= self.max_arc_deg < 360.0:
            raise DesignError(f"max_arc_deg must be in [90, 360), got {self.max_arc_deg}")
        if not 0.0 <= self.min_gap_fraction <= 1.0:
            raise DesignError(f"min_gap_fraction must be in [0, 1], got {self.min_gap_fraction}")
        if not self.symmetry_tolerance > 0.0:
            raise DesignError("symmetry_tolerance must be > 0")
        if self.max_symmetry_order < 1 or self.symmetry_samples < 16:
            raise DesignError("max_symmetry_order must be >= 1 and symmetry_samples >= 16")
        if not (self.min_arc_sagitta_mm >= 0.0 and self.min_arc_chord_mm >= 0.0):
            raise DesignError("min_arc_sagitta_mm and min_arc_chord_mm must be >= 0")
        turn = (self.min_turn_shift_mm, self.min_asymmetry_mm, self.min_hole_turn_mm)
        if not (min(turn) >= 0.0 and self.turn_tolerance_deg > 0.0):
            raise DesignError(
                "min_turn_shift_mm, min_asymmetry_mm and min_hole_turn_mm must be >= 0 and "
                "turn_tolerance_deg > 0"
            )
        made = (self.made_arc_step_mm, self.tile_deviation_mm, self.min_turn_capability)
        if not (made[0] > 0.0 and made[1] >= 0.0 and made[2] >= 0.0):
            raise DesignError(
                "made_arc_step_mm must be > 0, tile_deviation_mm and min_turn_capability >= 0; "
                f"got {made[0]}, {made[1]} and {made[2]}"
            )
        if not (0.0 <= self.turn_window_deg < 90.0 and 0.0 < self.turn_step_deg <= 30.0):
            raise DesignError("turn_window_deg must be in [0, 90) and turn_step_deg in (0, 30]")
        if self.small_features not in ("warn", "refuse", "ignore"):
            raise DesignError(
                f"small_features {self.small_features!r}; allowed: 'warn', 'refuse', 'ignore'"
            )

    @classmethod
    def load(cls, name_or_path: str | Path | None = None, **overrides: Any) -> DesignRules:
        """Load the ``design`` section of ``configs/vision.yaml`` (or another file).

        Raises:
            configs.ConfigError: Unknown key or wrong type.
        """
        return load_section(cls, "design", name_or_path, overrides, default="vision")


__all__ = ["DesignRules"]
