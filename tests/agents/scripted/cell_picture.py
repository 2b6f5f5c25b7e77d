"""Test helpers: four-slot designs and the input camera's picture of their tiles in the cell."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from benchmarks.design_cell import build_design_cell
from envs.task_spec import work_areas, world_slots
from qshape.design import Design


def four_slot_design(
    name: str,
    shapes: tuple[Any, Any],
    colors: tuple[str, str, str, str],
    *,
    start_mm: float,
    pitch_mm: float,
    turn_deg: float,
) -> Design:
    """A 230 mm mesh (2 mm joints) of four slots in a 2 x 2 grid, shapes alternating.

    Args:
        name: Design name.
        shapes: Shape mappings of the even and the odd slots.
        colors: '#rrggbb' of each slot.
        start_mm: x and y of the first slot's centre [mm].
        pitch_mm: Grid pitch [mm].
        turn_deg: Slot i is turned by i x this [deg].
    """
    start = start_mm
    slots = [
        {
            "name": f"t{i}",
            "shape": shapes[i % 2],
            "color": colors[i],
            "pose": {
                "x": start + pitch_mm * (i % 2),
                "y": start + pitch_mm * (i // 2),
                "angle": turn_deg * i,
            },
        }
        for i in range(4)
    ]
    mesh = {"width": 230, "height": 230}
    return Design.from_dict({"name": name, "mesh": mesh, "joint": 2.0, "slots": slots})


@dataclass(frozen=True)
class CellPicture:
    """The input camera's picture of a design's tiles, settled on the belt.

    Attributes:
        image: RGB picture, shape (H, W, 3).
        camera: The input camera's model.
        tile_top_z: Height of the tile tops [m].
        slots: The design's slots in the world (`envs.task_spec.world_slots`).
    """

    image: np.ndarray
    camera: Any
    tile_top_z: float
    slots: Any


def picture_of(design: Design) -> CellPicture:
    """Build the cell for ``design`` (seed 0), let the tiles settle and take the input picture."""
    cell, _ = build_design_cell(design, seed=0)
    try:
        cell.step(100)
        return CellPicture(
            cell.render("input_camera"),
            cell.camera_model("input_camera"),
            work_areas(cell)[0].tile_top_z,
            world_slots(cell, design),
        )
    finally:
        cell.close()
