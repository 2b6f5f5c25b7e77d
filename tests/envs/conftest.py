"""Shared fixtures of the envs tests: the kinematic pick_place env, the IK of a cell's arm, and a
cell scene with a red marker the cameras can see.

Each is built once per test module (compiling a model costs up to a second); the motions that
use the IK are in `tests.envs.cell_motion`.
"""

from __future__ import annotations

from collections.abc import Iterator

import gymnasium as gym
import mujoco
import pytest

import envs
from envs.cell.cell import Cell
from envs.cell.config import CellConfig
from envs.cell.scene import build_spec
from tests.envs.cell_motion import ArmIK, ArmIKFor

MARKER_RADIUS = 0.003
"""Radius of the red marker sphere [m]."""


@pytest.fixture(scope="module")
def marker_scene() -> tuple[mujoco.MjModel, mujoco.MjData, int]:
    """The default cell's scene with a red, contact-free mocap sphere: (model, data, mocap id)."""
    spec = build_spec(CellConfig())
    body = spec.worldbody.add_body(name="marker", mocap=True)
    g = body.add_geom(name="marker", type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[MARKER_RADIUS, 0, 0])
    g.rgba = [1, 0, 0, 1]
    g.contype = g.conaffinity = 0
    model = spec.compile()
    return model, mujoco.MjData(model), model.body("marker").mocapid[0]


@pytest.fixture(scope="module")
def arm_ik() -> ArmIKFor:
    """The IK of a cell's arm: compiled on first use per cell configuration, then shared.

    The IK keeps no state between solves (each starts from its seeds), so sharing it between
    tests changes no result.
    """
    made: dict[CellConfig, ArmIK] = {}

    def of(cell: Cell) -> ArmIK:
        if cell.cfg not in made:
            made[cell.cfg] = ArmIK(cell)
        return made[cell.cfg]

    return of


@pytest.fixture(scope="module")
def kinematic_env() -> Iterator[gym.Env]:
    """``MosaicAssembly-v0``: pick_place actions, kinematic execution, state observations.

    Reset with seed 0; tests that need another start reset it themselves.
    """
    env = gym.make(envs.ENV_ID, action_mode="pick_place", obs_mode="state", execution="kinematic")
    env.reset(seed=0)
    try:
        yield env
    finally:
        env.close()


@pytest.fixture(scope="module")
def decision6_env() -> Iterator[gym.Env]:
    """``MosaicDecision6-v1``: 6 tiles and slots of paper_mixed (symmetries 4, 4, 2, round, 1,
    1), ``pick_place_discrete`` actions, kinematic execution, state observations.

    Reset with seed 0; tests that need another start reset it themselves.
    """
    env = gym.make("MosaicDecision6-v1")
    env.reset(seed=0)
    try:
        yield env
    finally:
        env.close()
