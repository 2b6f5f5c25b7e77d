"""Rendering the cell's pictures: multisampling (anti-aliased edges or not), small images
supersampled instead of multisampled, buffers sized per renderer (`CameraRig`)."""

from __future__ import annotations

import copy
import dataclasses

import gymnasium as gym
import mujoco
import numpy as np
import pytest

import envs
from envs.cell.cameras import CameraRig
from envs.cell.cell import CAMERAS, Cell
from envs.cell.config import load_cell_config


def test_samples_set_the_models_multisampling_and_smooth_edges() -> None:
    """Without multisampling an edge pixel takes one surface's colour: far fewer colours."""
    colours = {}
    for samples in (4, 0):
        env = gym.make(
            envs.ENV_ID,
            action_mode="pick_place_discrete",
            execution="kinematic",
            obs_mode="rgb",
            cell={"render": {"samples": samples}},
        )
        try:
            obs, _ = env.reset(seed=0)
            assert env.unwrapped.cell.model.vis.quality.offsamples == samples
            img = obs["input_camera"]
            colours[samples] = len(np.unique(img.reshape(-1, 3), axis=0))
        finally:
            env.close()
    assert colours[0] < colours[4] / 2


SMALL = (72, 96)
LARGE = (240, 320)  # over supersample_max_pixels: multisampled
MAX_MEAN_DIFF = 3.0
"""Largest mean absolute difference [grey levels] from the 4-sample multisampled image (about
1.3 measured; the same scene without anti-aliasing differs by about 3.6)."""


@pytest.fixture(scope="module")
def cell():
    """The default cell with tiles on the input belt and a few on the mesh, arm over the mesh.

    A 230 mm mesh (the bundled designs'): the output camera at its configured height.
    """
    c = Cell(load_cell_config(), seed=0, mesh_size=(0.23, 0.23))
    moved = np.arange(3)
    qadr = c.ids.tile_qpos_index[moved]
    c.data.qpos[qadr[:, 0]] = c.geometry.output_centre[0] + 0.04 * (moved - 1)
    c.data.qpos[qadr[:, 1]] = c.geometry.output_centre[1]
    c.data.qpos[qadr[:, 2]] = c.geometry.output_centre[2] + 0.01
    mujoco.mj_forward(c.model, c.data)
    yield c
    c.close()


def _rig(cell: Cell, **render: object) -> CameraRig:
    return CameraRig(cell.model, dataclasses.replace(cell.cfg.render, **render))


def test_default_supersamples_small_images(cell) -> None:
    cfg = cell.cfg.render
    assert cfg.supersample == 2 and cell.model.vis.quality.offsamples == 4
    assert SMALL[0] * SMALL[1] <= cfg.supersample_max_pixels < LARGE[0] * LARGE[1]


@pytest.mark.parametrize("camera", CAMERAS)
def test_supersampled_image_is_close_to_multisampled_and_smooth(cell, camera) -> None:
    """Against the 4-sample image: small mean difference, and far more edge colours than
    without anti-aliasing (stair-stepped edges have only the surfaces' colours)."""
    single = copy.deepcopy(cell.model)
    single.vis.quality.offsamples = 0  # the same scene without anti-aliasing
    ssaa, msaa = _rig(cell), _rig(cell, supersample=1)
    plain = CameraRig(single, dataclasses.replace(cell.cfg.render, supersample=1))
    try:
        img = ssaa.render(cell.data, camera, *SMALL)
        ref = msaa.render(cell.data, camera, *SMALL)
        aliased = plain.render(cell.data, camera, *SMALL)
    finally:
        ssaa.close()
        msaa.close()
        plain.close()
    assert img.shape == ref.shape == (*SMALL, 3) and img.dtype == np.uint8
    diff = np.abs(img.astype(int) - ref.astype(int)).mean()
    assert diff < MAX_MEAN_DIFF
    assert diff < np.abs(aliased.astype(int) - ref.astype(int)).mean() / 2

    def colours(a: np.ndarray) -> int:
        return len(np.unique(a.reshape(-1, 3), axis=0))

    assert colours(img) > 2 * colours(aliased)


def test_own_sized_buffer_renders_the_same_pixels(cell) -> None:
    """A large image (multisampled) from the rig's own-sized buffer equals MuJoCo's renderer
    with the model's buffer, RGB and depth."""
    rig = _rig(cell, cull=False)
    plain = mujoco.Renderer(cell.model, *LARGE)
    plain_depth = mujoco.Renderer(cell.model, *LARGE)
    plain_depth.enable_depth_rendering()
    try:
        for r in (plain, plain_depth):
            r.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = cell.cfg.render.shadows
            r.scene.flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = cell.cfg.render.reflections
        for camera in CAMERAS:
            plain.update_scene(cell.data, camera=camera)
            plain_depth.update_scene(cell.data, camera=camera)
            assert np.array_equal(rig.render(cell.data, camera, *LARGE), plain.render())
            depth = rig.render(cell.data, camera, *LARGE, depth=True)
            assert np.array_equal(depth, plain_depth.render())
            # depth of a small image is not supersampled (no averaging across edges)
            assert rig.render(cell.data, camera, *SMALL, depth=True).shape == SMALL
    finally:
        rig.close()
        plain.close()
        plain_depth.close()


def test_image_larger_than_the_model_buffer_is_refused(cell) -> None:
    from envs.errors import CellError  # noqa: PLC0415

    rig = _rig(cell)
    vis = cell.model.vis.global_
    try:
        with pytest.raises(CellError, match="offscreen render buffer"):
            rig.render(cell.data, CAMERAS[0], vis.offheight + 1, vis.offwidth)
    finally:
        rig.close()


def test_closing_one_envs_renderers_leaves_another_envs_pictures() -> None:
    """Two envs in one process: closing one (as a procedural reset does when it rebuilds its
    model) must not free the other's GL buffers. MuJoCo's own ``Renderer.close`` freed them in
    whatever context was current, and the other env's camera then showed the closed env's
    scene; this test failed then (the kept env's second picture was not its first)."""
    kwargs = {
        "action_mode": "pick_place_discrete",
        "obs_mode": "rgb",
        "image_size": [48, 64],
        "max_slots": 6,
        "cell": {"render": {"reuse_unchanged": False}},  # draw every picture
    }
    kept = gym.make(envs.ENV_ID, design="square_grid", **kwargs)
    other = gym.make(envs.ENV_ID, design="paper_mixed", **kwargs)
    try:
        first, _ = kept.reset(seed=3)
        other.reset(seed=4)  # the other env draws last: its context is current
        kept.unwrapped.cell.render("input_camera", 48, 64)  # now the kept env's is
        other.close()
        again, _ = kept.reset(seed=3)
        np.testing.assert_array_equal(again["input_camera"], first["input_camera"])
        np.testing.assert_array_equal(again["output_camera"], first["output_camera"])
    finally:
        kept.close()
        other.close()
