"""The working areas are reachable with the tool pointing straight down, in both layouts."""

from __future__ import annotations

import itertools

import mujoco
import numpy as np
import pytest

from envs.cell.cell import Cell
from envs.cell.config import CellConfig, InputBeltConfig, LayoutConfig
from envs.cell.tiles.shapes import basic_shapes
from tests.envs.cell_motion import ArmIK, tool_down

LAYOUTS = {
    "paper_1m": CellConfig(layout=LayoutConfig(belt_separation=1.0, work_x=0.0)),
    "compact_0.5m": CellConfig(
        layout=LayoutConfig(belt_separation=0.5, work_x=0.5),
        input_belt=InputBeltConfig(length=0.6),
    ),
}


@pytest.mark.parametrize("cfg", LAYOUTS.values(), ids=LAYOUTS.keys())
def test_tile_area_and_mesh_reachable_pointing_down(cfg: CellConfig) -> None:
    cell = Cell(cfg, basic_shapes()[:1], seed=0)
    ik = ArmIK(cell)
    geo = cell.geometry
    t = cfg.tiles.thickness
    try:
        areas = [
            (geo.input_centre + [0, 0, t], np.asarray(cfg.input_belt.tile_area) / 2),
            (geo.output_centre + [0, 0, t], np.asarray(cfg.output_belt.mesh_size) / 2),
        ]
        worst_sv = np.inf
        for centre, half in areas:
            for sx, sy, dz, yaw in itertools.product(
                (-1, 0, 1), (-1, 0, 1), (0.0, 0.1), (-np.pi / 2, 0.0, np.pi / 2, np.pi)
            ):
                p = centre + [sx * half[0], sy * half[1], dz]
                q = ik.solve(p, tool_down(yaw), np.asarray(cfg.robot.home))
                pos, rot = ik.fk(q)
                assert np.linalg.norm(pos - p) < 1e-4
                assert np.allclose(rot, tool_down(yaw), atol=1e-4)
                assert np.all(q >= ik.lo) and np.all(q <= ik.hi)
                jp, jr = np.zeros((3, 6)), np.zeros((3, 6))
                mujoco.mj_comPos(ik.model, ik.data)
                mujoco.mj_jacSite(ik.model, ik.data, jp, jr, ik.site)
                worst_sv = min(worst_sv, np.linalg.svd(np.vstack([jp, jr]), compute_uv=False)[-1])
        assert worst_sv > 0.02  # away from singularities everywhere in the working areas
    finally:
        cell.close()
