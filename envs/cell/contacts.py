"""Contact classes and stiffness of the cell's MuJoCo scene: who touches whom, and how hard."""

from __future__ import annotations

# Contact bit masks: world/belts 1, tiles 2, arm 4 (the arm's classes set contype 4,
# conaffinity 1 in irb140.xml), support hulls 8. Tiles touch everything; the arm touches world
# and tiles. A tile made of several convex pieces touches the world (belts, mesh sheet, floor,
# bin) with one convex hull instead (`SUPPORT_CONTYPE`), its pieces only tiles and the arm.
WORLD_CONTYPE, WORLD_CONAFFINITY = 1, 1
TILE_CONTYPE, TILE_CONAFFINITY = 2, 7
PIECE_CONAFFINITY = TILE_CONAFFINITY & ~WORLD_CONTYPE
"""Pieces of a tile with a support hull: tiles and arm, not the world."""
SUPPORT_CONTYPE, SUPPORT_CONAFFINITY = 8, WORLD_CONTYPE
"""Support hull of a tile of several pieces: the world only."""
CONTACT_SOLREF = (0.004, 1.0)
"""Contact time constant [s] and damping ratio of tiles and belts: stiff (2x the default
timestep) so a tile crushed by the arm sinks at most a few mm into a belt (0.02 s: ~19 mm)."""
WELD_SOLREF = (0.004, 1.0)
"""Time constant [s] and damping ratio of the suction weld (stiff: 2x the default timestep)."""


__all__ = [
    "CONTACT_SOLREF",
    "PIECE_CONAFFINITY",
    "SUPPORT_CONAFFINITY",
    "SUPPORT_CONTYPE",
    "TILE_CONAFFINITY",
    "TILE_CONTYPE",
    "WELD_SOLREF",
    "WORLD_CONAFFINITY",
    "WORLD_CONTYPE",
]
