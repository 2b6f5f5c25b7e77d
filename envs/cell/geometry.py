"""Where the cell's parts are: belt centre lines, working areas and heights, from the config.

World layout (see `LayoutConfig`): robot base at the origin; the input belt's centre line at
y = +belt_separation/2 and the output belt's at y = -belt_separation/2, both running along +x;
the working areas are centred at x = work_x.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from envs.cell.config import CellConfig


@dataclass(frozen=True)
class CellGeometry:
    """Derived positions of the cell's parts [m] (all in the world frame).

    Attributes:
        input_centre: Centre of the input tile area on the belt top, shape (3,).
        output_centre: Centre of the mesh sheet's top, shape (3,).
        input_belt_end: x of the input belt's downstream end.
        input_belt_start: x of the input belt's upstream end.
        input_y: y of the input belt's centre line.
        belt_top: z of both belts' top faces.
        mesh_top: z of the mesh sheet's top face.
    """

    input_centre: np.ndarray
    output_centre: np.ndarray
    input_belt_end: float
    input_belt_start: float
    input_y: float
    belt_top: float
    mesh_top: float

    @property
    def midline_y(self) -> float:
        """Y of the midline between the belts' centre lines [m] (see `Cell.input_half`)."""
        return float(self.output_centre[1] + self.input_centre[1]) / 2


def cell_geometry(cfg: CellConfig) -> CellGeometry:
    """Positions of the belts and working areas from the configuration."""
    lay = cfg.layout
    top = lay.belt_top_z
    y_in, y_out = lay.belt_separation / 2, -lay.belt_separation / 2
    end = lay.work_x + cfg.input_belt.end_offset
    mesh_top = top + cfg.output_belt.mesh_thickness
    return CellGeometry(
        input_centre=np.array([lay.work_x, y_in, top]),
        output_centre=np.array([lay.work_x, y_out, mesh_top]),
        input_belt_end=end,
        input_belt_start=end - cfg.input_belt.length,
        input_y=y_in,
        belt_top=top,
        mesh_top=mesh_top,
    )


__all__ = ["CellGeometry", "cell_geometry"]
