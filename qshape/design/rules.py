"""`DesignRules`: how design outlines are sampled and designs validated.

Bundled values: the ``design`` section of ``configs/vision.yaml``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal, get_args

from configs.checks import check_fields, checked
from qshape.config_sections import load_section
from qshape.errors import DesignError
from spatial.tolerance import MADE_TILE_DEVIATION_MM, PLACEMENT_YAW_TOLERANCE_DEG

SmallFeatures = Literal["warn", "refuse", "ignore"]
"""What loading does with a slot holding a feature the camera may miss."""


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

    outline_step_mm: float = checked(0.25, gt=0)
    max_arc_deg: float = checked(240.0, ge=90, lt=360)
    check_step_mm: float = checked(1.0, gt=0)
    min_gap_fraction: float = checked(0.5, ge=0, le=1)
    mesh_margin_mm: float = 0.0
    symmetry_tolerance: float = checked(0.01, gt=0)
    max_symmetry_order: int = checked(12, ge=1)
    symmetry_samples: int = checked(512, ge=16)
    min_arc_sagitta_mm: float = checked(5.0, ge=0)
    min_arc_chord_mm: float = checked(20.0, ge=0)
    turn_tolerance_deg: float = checked(PLACEMENT_YAW_TOLERANCE_DEG, gt=0)
    min_turn_shift_mm: float = checked(0.1, ge=0)
    min_asymmetry_mm: float = checked(0.3, ge=0)
    min_hole_turn_mm: float = checked(1.5, ge=0)
    made_arc_step_mm: float = checked(2.0, gt=0)
    tile_deviation_mm: float = checked(MADE_TILE_DEVIATION_MM, ge=0)
    min_turn_capability: float = checked(1.0, ge=0)
    turn_window_deg: float = checked(10.0, ge=0, lt=90)
    turn_step_deg: float = checked(6.0, gt=0, le=30)
    small_features: SmallFeatures = checked("warn", choices=get_args(SmallFeatures))

    def __post_init__(self) -> None:
        """Raise `DesignError` on out-of-range values."""
        check_fields(self, DesignError)

    @classmethod
    def load(cls, name_or_path: str | Path | None = None, **overrides: Any) -> DesignRules:
        """Load the ``design`` section of ``configs/vision.yaml`` (or another file).

        Raises:
            configs.ConfigError: Unknown key or wrong type.
        """
        return load_section(cls, "design", name_or_path, overrides, default="vision")


__all__ = ["DesignRules"]
