"""Building the simulated cell for a design, and ground truth for reports and tests only.

The cell takes tile shapes and slots (`envs.tiles.tile_shapes_from_design` converts a design);
with the cell's random layout some seeds do not fit every tile on the belt, so the first seed
from ``seed`` on whose layout fits is used. Ground truth (`nearest_tile`) is for scoring, never
for the agent's decisions.
"""

from __future__ import annotations

import numpy as np

from agents.errors import AgentError
from envs.cell import Cell
from envs.cell_config import CellConfig, load_cell_config
from envs.errors import CellError
from envs.tiles import tile_shapes_from_design
from qshape.design import Design


def build_design_cell(
    design: Design, cfg: CellConfig | None = None, seed: int = 0, tries: int = 20
) -> tuple[Cell, int]:
    """The cell laid out with one tile per design slot.

    Args:
        design: The design.
        cfg: Cell configuration (bundled when None).
        seed: First layout seed tried.
        tries: Seeds tried.

    Returns:
        (cell, seed used).

    Raises:
        AgentError: No seed in ``[seed, seed + tries)`` fits the tiles on the belt.
    """
    shapes, slots = tile_shapes_from_design(design)
    cfg = cfg or load_cell_config()
    for k in range(tries):
        try:
            return Cell(cfg, shapes, slots, seed=seed + k), seed + k
        except CellError:
            continue
    raise AgentError(f"no layout seed in [{seed}, {seed + tries}) fits design {design.name!r}")


def nearest_tile(cell: Cell, xy: np.ndarray) -> tuple[int, float]:
    """Ground-truth tile nearest to a world point (scoring only): (index, distance [m])."""
    pos = cell.tile_poses().pos[:, :2]
    d = np.linalg.norm(pos - np.asarray(xy)[None], axis=1)
    d[~cell.on_stage] = np.inf
    i = int(np.argmin(d))
    return i, float(d[i])


def yaw_error(yaw: float, target: float, symmetry: int) -> float:
    """|yaw - target| modulo the symmetry (0: continuous, error 0) [rad]."""
    if symmetry == 0:
        return 0.0
    period = 2 * np.pi / symmetry
    return float(abs((yaw - target + period / 2) % period - period / 2))


__all__ = ["build_design_cell", "nearest_tile", "yaw_error"]
