"""Where the cell's parts are: belt centre lines, working areas and heights, the mesh sheet.

World layout (see `LayoutConfig`): robot base at the origin; the input belt's centre line at
y = +belt_separation/2 and the output belt's at y = -belt_separation/2, both running along +x;
the working areas are centred at x = work_x.

The mesh sheet is the design's mesh: `cell_geometry` takes its size once, checks it against
the largest the cell takes (``output_belt.max_mesh_size``) and derives what depends on it
(the sheet, the on-mesh area, the place area and the output camera's height), so the sheet's
size has this one home in a built cell (`CellGeometry.mesh_size`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from envs.cell.config import CellConfig
from envs.errors import MeshSizeError
from spatial.units import MM_PER_M


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
        mesh_size: (x, y) size of the mesh sheet, shape (2,): the design's mesh.
        output_camera_height: Height of the output camera above the mesh sheet's top: its
            configured ``height_above_belt``, or higher when the mesh would not fit its view
            with ``output_belt.frame_margin`` beyond each edge.
    """

    input_centre: np.ndarray
    output_centre: np.ndarray
    input_belt_end: float
    input_belt_start: float
    input_y: float
    belt_top: float
    mesh_top: float
    mesh_size: np.ndarray
    output_camera_height: float

    @property
    def midline_y(self) -> float:
        """Y of the midline between the belts' centre lines [m] (see `Cell.input_half`)."""
        return float(self.output_centre[1] + self.input_centre[1]) / 2

    @property
    def mesh_lo(self) -> np.ndarray:
        """World (x, y) of the mesh sheet's lower corner, shape (2,)."""
        return np.asarray(self.output_centre[:2] - self.mesh_size / 2, dtype=np.float64)

    @property
    def mesh_hi(self) -> np.ndarray:
        """World (x, y) of the mesh sheet's upper corner, shape (2,)."""
        return np.asarray(self.output_centre[:2] + self.mesh_size / 2, dtype=np.float64)


def check_mesh_size(cfg: CellConfig, mesh_size: Sequence[float]) -> np.ndarray:
    """``mesh_size`` [m] as an array (2,), once checked against the cell's largest mesh.

    Raises:
        MeshSizeError: A side not positive, or larger than ``output_belt.max_mesh_size``;
            the message names the largest mesh that fits.
    """
    size = np.asarray(mesh_size, dtype=np.float64).reshape(-1)
    top = np.asarray(cfg.output_belt.max_mesh_size, dtype=np.float64)
    w, h = (float(v) * MM_PER_M for v in top)
    if size.shape != (2,) or not np.all(np.isfinite(size)) or np.any(size <= 0.0):
        raise MeshSizeError(f"mesh size must be two positive numbers [m], got {mesh_size!r}")
    if np.any(size > top + 1e-12):
        raise MeshSizeError(
            f"the design's {size[0] * MM_PER_M:g} x {size[1] * MM_PER_M:g} mm mesh does not "
            f"fit this cell: the largest mesh it takes is {w:g} x {h:g} mm "
            "(output_belt.max_mesh_size: what the output belt holds and the arm reaches)"
        )
    return size


def cell_geometry(cfg: CellConfig, mesh_size: Sequence[float] | None = None) -> CellGeometry:
    """Positions of the belts and working areas from the configuration and the mesh.

    Args:
        cfg: The cell configuration.
        mesh_size: (x, y) of the design's mesh [m]; None: ``output_belt.max_mesh_size``.

    Raises:
        MeshSizeError: A mesh larger than ``output_belt.max_mesh_size`` (`check_mesh_size`).
    """
    lay = cfg.layout
    top = lay.belt_top_z
    y_in, y_out = lay.belt_separation / 2, -lay.belt_separation / 2
    end = lay.work_x + cfg.input_belt.end_offset
    mesh_top = top + cfg.output_belt.mesh_thickness
    size = check_mesh_size(cfg, cfg.output_belt.max_mesh_size if mesh_size is None else mesh_size)
    return CellGeometry(
        input_centre=np.array([lay.work_x, y_in, top]),
        output_centre=np.array([lay.work_x, y_out, mesh_top]),
        input_belt_end=end,
        input_belt_start=end - cfg.input_belt.length,
        input_y=y_in,
        belt_top=top,
        mesh_top=mesh_top,
        mesh_size=size,
        output_camera_height=framing_height(cfg, size),
    )


def framing_height(cfg: CellConfig, mesh_size: np.ndarray) -> float:
    """Output camera height above the sheet [m]: configured, or what frames the mesh.

    The mesh plus ``output_belt.frame_margin`` on every side fits the picture (vertical field
    of view ``fovy_deg``, horizontal from the picture's aspect) at the returned height.
    """
    cam = cfg.output_camera
    half = mesh_size / 2 + cfg.output_belt.frame_margin + np.abs(np.asarray(cam.offset, float))
    tan_y = math.tan(math.radians(cam.fovy_deg) / 2)
    tan_x = tan_y * cam.width / cam.height
    need = max(float(half[0]) / tan_x, float(half[1]) / tan_y)
    return max(float(cam.height_above_belt), need)


__all__ = ["CellGeometry", "cell_geometry", "check_mesh_size", "framing_height"]
