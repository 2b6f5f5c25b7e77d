"""The cell's tolerances: how exactly a tile must lie in its slot, how far a made tile deviates.

The one home of these facts; every other place reads them from here (the env's configuration
defaults, the design rules, the cell's tile noise, the benchmarks' tolerance lines).

- The placement tolerance: a tile is placed when its centre lies within 1.5 mm of its slot's
  and its turn within 2 deg of the slot's, modulo the shape's rotational symmetry. A mosaic
  joint is 2-3 mm wide, so the tolerance is tighter than the joint (the kits benchmarks of
  Ravens and ManiSkill use 1-2 cm and 4-15 deg).
- The made tile's deviation: each vertex of a made (cut, pressed, fired) tile lies off its
  drawing by a normal deviation of this standard deviation; the design rules judge what the
  camera and the turn can fix under it, and the simulated cell builds its tiles with it.
"""

from __future__ import annotations

from spatial.units import MM_PER_M

PLACEMENT_POSITION_TOLERANCE_MM = 1.5
"""A placed tile's centre lies within this distance of its slot's [mm]."""
PLACEMENT_YAW_TOLERANCE_DEG = 2.0
"""A placed tile's turn lies within this angle of its slot's, modulo its symmetry [deg]."""
MADE_TILE_DEVIATION_MM = 0.2
"""Standard deviation of a made tile's vertices off its drawing, each axis [mm]."""

PLACEMENT_POSITION_TOLERANCE_M = PLACEMENT_POSITION_TOLERANCE_MM / MM_PER_M
"""`PLACEMENT_POSITION_TOLERANCE_MM` in world metres [m]."""
MADE_TILE_DEVIATION_M = MADE_TILE_DEVIATION_MM / MM_PER_M
"""`MADE_TILE_DEVIATION_MM` in world metres [m]."""

__all__ = [
    "MADE_TILE_DEVIATION_M",
    "MADE_TILE_DEVIATION_MM",
    "PLACEMENT_POSITION_TOLERANCE_M",
    "PLACEMENT_POSITION_TOLERANCE_MM",
    "PLACEMENT_YAW_TOLERANCE_DEG",
]
