"""`envs.cell.view_culling`: culled scenes render the very same pixels, with fewer geoms."""

from __future__ import annotations

import gymnasium as gym
import mujoco
import numpy as np
import pytest

import envs
from envs.cell.cell import CAMERAS
from envs.cell.view_culling import ViewCuller

SIZES = ((72, 96), (120, 160), (492, 656))  # the last: frustum test only


@pytest.fixture(scope="module")
def pair():
    """Two identical envs, culling on and off, stepped side by side."""
    made = [
        gym.make(
            envs.ENV_ID,
            action_mode="pick_place_discrete",
            execution="kinematic",
            obs_mode="rgb",
            cell={"render": {"cull": cull}},
        )
        for cull in (True, False)
    ]
    yield made
    for env in made:
        env.close()


def _views(env, depth: bool = False) -> list[np.ndarray]:
    cell = env.unwrapped.cell
    return [cell.render(name, h, w, depth=depth) for name in CAMERAS for h, w in SIZES]


def test_culled_images_are_identical(pair) -> None:
    """Every camera, several sizes, RGB and depth, at reset and with tiles moved and the arm
    parked over the mesh."""
    for seed in (0,):
        for env in pair:
            env.reset(seed=seed)
        for step in range(2):
            if step:
                action = pair[0].unwrapped.index.encode(step, step)
                for env in pair:
                    env.step(action)
            for depth in (False, True):
                for a, b in zip(_views(pair[0], depth), _views(pair[1], depth), strict=True):
                    assert a.shape == b.shape
                    assert np.array_equal(a, b)


def test_culling_leaves_geoms_out(pair) -> None:
    """The input camera does not get the floor, the output belt or the mesh's tiles."""
    env = pair[0]
    env.reset(seed=1)
    cell = env.unwrapped.cell
    cam = cell.model.camera("input_camera").id
    renderer = mujoco.Renderer(cell.model, 72, 96)
    try:
        hidden = ViewCuller(cell.model).hidden(renderer, cell.data, cam)
    finally:
        renderer.close()
    assert hidden[cell.model.geom("floor").id]
    assert hidden[cell.model.geom("output_belt").id]
    assert not hidden[cell.model.geom("input_belt").id]
    visible_tiles = ~hidden[cell.ids.tile_visual[:, 1]]
    assert visible_tiles.sum() == len(cell.tiles)  # all tiles lie on the input belt at reset
