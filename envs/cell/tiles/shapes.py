"""Where tile shapes come from: a mosaic design (one tile per slot) or the built-in test set.

Design millimetres (mesh origin at a corner) become metres relative to the mesh centre here,
once; `envs.task_spec.world_slots` adds the mesh's world position.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from envs.cell.tiles.tile import SlotSpec, TileShape
from envs.errors import CellError
from spatial.units import M_PER_MM


def tile_shapes_from_design(
    design: Any, arc_step_mm: float | None = None
) -> tuple[tuple[TileShape, ...], tuple[SlotSpec, ...]]:
    """Tile shapes and slots of a `qshape.design.Design` (mm, mesh origin at a corner).

    One tile per slot. Shapes are named by the slot's shape-and-colour class
    (``Slot.class_key``), so tiles and slots of a class share a name. Slot poses are moved to
    the mesh centre and converted to metres and radians.

    Args:
        design: A loaded design (``Design.load("paper_mixed")``).
        arc_step_mm: Largest distance between vertices along arcs [mm] (straight edges keep
            only their ends; `qshape.design.Loop.made_vertices`). None: the design rules'
            ``made_arc_step_mm``, the tile the design's turn checks assume.

    Returns:
        ``(shapes, slots)``, in the design's slot order.
    """
    if arc_step_mm is None:
        arc_step_mm = float(design.rules.made_arc_step_mm)
    if not arc_step_mm > 0:
        raise CellError(f"arc_step_mm must be positive, got {arc_step_mm}")
    mm = M_PER_MM
    width, height = design.mesh_size
    shapes, slots = [], []
    by_class: dict[str, TileShape] = {}  # the slots of a class share one shape (built once)
    for slot in design.slots:
        shape = by_class.get(slot.class_key)
        if shape is None:
            path = slot.local_path
            shape = by_class[slot.class_key] = TileShape(
                path.outer.made_vertices(arc_step_mm) * mm,
                holes=tuple(h.made_vertices(arc_step_mm) * mm for h in path.holes),
                color=tuple(slot.color),
                name=slot.class_key,
                symmetry=int(slot.symmetry),
            )
        pose = ((slot.x - width / 2) * mm, (slot.y - height / 2) * mm, math.radians(slot.angle))
        shapes.append(shape)
        slots.append(SlotSpec(shape, pose, slot.name))
    return tuple(shapes), tuple(slots)


def design_mesh_size(design: Any) -> tuple[float, float]:
    """The (x, y) size of a `qshape.design.Design`'s mesh in metres: the cell's sheet."""
    width, height = design.mesh_size
    return (float(width) * M_PER_MM, float(height) * M_PER_MM)


def _circle(r: float, n: int, start: float = 0.0, stop: float = 2 * np.pi) -> np.ndarray:
    t = np.linspace(start, stop, n, endpoint=False)
    return np.stack([r * np.cos(t), r * np.sin(t)], axis=1)


@dataclass(frozen=True)
class BasicShapes:
    """Sizes of the built-in test shapes [m]."""

    size: float = 0.02
    samples: int = 32
    colors: dict[str, tuple[float, float, float]] = field(
        default_factory=lambda: {
            "square": (0.85, 0.15, 0.12),
            "rectangle": (0.15, 0.45, 0.85),
            "triangle": (0.95, 0.8, 0.1),
            "l_shape": (0.2, 0.7, 0.3),
            "circle": (0.95, 0.5, 0.1),
            "semicircle": (0.6, 0.25, 0.7),
            "ring": (0.1, 0.75, 0.8),
        }
    )


def basic_shapes(spec: BasicShapes | None = None) -> tuple[TileShape, ...]:
    """Square, rectangle, right triangle, L (concave), circle, semicircle, ring (with a hole).

    Args:
        spec: Sizes and colours; default 20 mm tiles.
    """
    spec = spec or BasicShapes()
    s, n, c = spec.size, spec.samples, spec.colors
    sq = np.array([[0, 0], [s, 0], [s, s], [0, s]])
    return (
        TileShape(sq, color=c["square"], name="square", symmetry=4),
        TileShape(sq * [2, 1], color=c["rectangle"], name="rectangle", symmetry=2),
        TileShape(np.array([[0, 0], [s, 0], [0, s]]), color=c["triangle"], name="triangle"),
        TileShape(
            np.array(
                [[0, 0], [2 * s, 0], [2 * s, s / 2], [s / 2, s / 2], [s / 2, 2 * s], [0, 2 * s]]
            )
            * 0.75,
            color=c["l_shape"],
            name="l_shape",
        ),
        TileShape(_circle(s / 2, n), color=c["circle"], name="circle", symmetry=0),
        TileShape(
            np.vstack([_circle(s / 2, n // 2 + 1, 0.0, np.pi * (1 + 2 / n))[: n // 2 + 1]]),
            color=c["semicircle"],
            name="semicircle",
        ),
        TileShape(
            _circle(s * 0.6, n),
            holes=(_circle(s * 0.25, n // 2)[::-1],),
            color=c["ring"],
            name="ring",
            symmetry=0,
        ),
    )


__all__ = [
    "BasicShapes",
    "basic_shapes",
    "design_mesh_size",
    "tile_shapes_from_design",
]
