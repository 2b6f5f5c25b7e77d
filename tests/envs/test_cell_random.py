"""Random controls for a simulated minute: no MuJoCo warning, no tile through a belt."""

from __future__ import annotations

import numpy as np
import pytest

from envs.cell.cell import Cell
from envs.cell.config import CellConfig, InputBeltConfig
from envs.cell.tiles.shapes import basic_shapes
from tests.envs.cell_motion import ArmIKFor, tool_down

CONTROL_STEPS = 5
SIM_SECONDS = 60.0


CRUSH_DEPTH = 0.005
"""A tile crushed into a belt by the arm (servo forces of kN) may sink this far [m]; deeper
means it is passing through."""


def _inside_slab(cell: Cell, pos: np.ndarray) -> np.ndarray:
    """Tiles whose centre is inside a belt slab (sunk below its top by more than CRUSH_DEPTH)."""
    cfg, geo = cell.cfg, cell.geometry
    t = cfg.tiles.thickness
    bad = np.zeros(len(pos), bool)
    belts = (
        (geo.input_belt_start, geo.input_belt_end, geo.input_y, cfg.input_belt),
        (
            geo.output_centre[0] - cfg.output_belt.length / 2,
            geo.output_centre[0] + cfg.output_belt.length / 2,
            geo.output_centre[1],
            cfg.output_belt,
        ),
    )
    for x0, x1, y, belt in belts:
        over = (pos[:, 0] > x0) & (pos[:, 0] < x1) & (np.abs(pos[:, 1] - y) < belt.width / 2)
        z_in = (pos[:, 2] < geo.belt_top + t / 2 - CRUSH_DEPTH) & (
            pos[:, 2] > geo.belt_top - belt.thickness - t
        )
        bad |= over & z_in
    return bad


@pytest.mark.parametrize("speed", [0.0, 0.05])
def test_random_controls_for_a_minute(speed: float, arm_ik: ArmIKFor) -> None:
    cfg = CellConfig(input_belt=InputBeltConfig(speed=speed))
    cell = Cell(cfg, basic_shapes() * 3, seed=11)
    rng = np.random.default_rng(12)
    lo, hi = cell.model.jnt_range[:6, 0], cell.model.jnt_range[:6, 1]
    vmax = cell.max_joint_speed
    ik = arm_ik(cell)
    # Half the targets scatter around a pose with the pad on the tiles, to stir them up.
    q_belt = ik.solve(cell.geometry.input_centre + [0, 0, 0.005], tool_down(0.0), cell.qpos)
    start = cell.tile_poses().pos
    try:
        target = cell.qpos
        steps = int(SIM_SECONDS / (cell.model.opt.timestep * CONTROL_STEPS))
        for k in range(steps):
            if k % 30 == 0:  # a new random target every 0.3 s, anywhere in the joint ranges
                if rng.random() < 0.5:
                    target = rng.uniform(lo, hi)
                else:
                    target = np.clip(q_belt + rng.normal(0, 0.12, 6), lo, hi)
                cell.vacuum(bool(rng.random() < 0.5))
            cell.set_servo(target, rng.uniform(-vmax, vmax) * 0.2)
            cell.step(CONTROL_STEPS)
            if k % 2 == 0:
                staged = cell.on_stage
                assert not np.any(_inside_slab(cell, cell.tile_poses().pos)[staged]), (
                    f"tile inside a belt at t={cell.time:.2f} s"
                )
            assert cell.warnings() == 0, f"MuJoCo warning at t={cell.time:.2f} s"
        assert np.all(np.isfinite(cell.data.qpos))
        moved = np.linalg.norm(cell.tile_poses().pos - start, axis=1)
        assert np.sum(moved > 0.005) >= (3 if speed == 0 else len(moved))  # the arm stirred tiles
    finally:
        cell.close()
