"""Shared fixtures of the envs tests: a cell scene with a red marker the cameras can see.

Built once per test module (compiling the cell's scene costs about a second).
"""

from __future__ import annotations

import mujoco
import pytest

from envs.cell.config import CellConfig
from envs.cell.scene import build_spec

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
