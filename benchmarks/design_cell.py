"""Benchmark helper: the simulated cell of a design, and its ground truth (for scoring only).

The cell takes tile shapes and slots (`envs.cell.tiles.shapes.tile_shapes_from_design` converts a
design);
with the cell's random layout some seeds do not fit every tile on the belt, so the first seed
from ``seed`` on whose layout fits is used. Ground truth (`nearest_tile`) is for scoring, never
for the agent's decisions.
"""

from __future__ import annotations

import numpy as np

from envs.cell.cell import Cell
from envs.cell.config import CellConfig, load_cell_config
from envs.cell.tiles.shapes import design_mesh_size, tile_shapes_from_design
from envs.episode_setup import build_cell
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
        LayoutError: No seed in ``[seed, seed + tries)`` fits the tiles on the belt.
    """
    shapes, slots = tile_shapes_from_design(design)
    cfg = cfg or load_cell_config()
    cell = build_cell(cfg, shapes, slots, seed, tries, mesh_size=design_mesh_size(design))
    return cell, seed if cell.layout_seed is None else cell.layout_seed


def nearest_tile(cell: Cell, xy: np.ndarray) -> tuple[int, float]:
    """Ground-truth tile nearest to a world point (scoring only): (index, distance [m])."""
    pos = cell.tile_poses().pos[:, :2]
    d = np.linalg.norm(pos - np.asarray(xy)[None], axis=1)
    d[~cell.on_stage] = np.inf
    i = int(np.argmin(d))
    return i, float(d[i])


__all__ = ["build_design_cell", "nearest_tile"]
