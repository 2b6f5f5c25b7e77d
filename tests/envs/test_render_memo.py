"""Render only what changed (`envs.cell.render_memo`): a camera whose scene did not change
returns its last picture again, pixel for pixel what a fresh render draws; a moved tile, a
recoloured geom, a dimmed light or a moved camera is drawn anew; the pictures kept are bounded."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import replace

import mujoco
import numpy as np
import pytest

from envs.cell.cell import CAMERAS, Cell
from envs.cell.config import load_cell_config
from envs.cell.render_memo import MAX_PICTURES, LastPictures

SIZE = (72, 96)


@pytest.fixture(scope="module")
def cells() -> Iterator[tuple[Cell, Cell]]:
    """The default cell twice (seed 0): reusing unchanged pictures, and drawing every one."""
    cfg = load_cell_config()
    fresh_cfg = replace(cfg, render=replace(cfg.render, reuse_unchanged=False))
    reuse, fresh = Cell(cfg, seed=0), Cell(fresh_cfg, seed=0)
    yield reuse, fresh
    reuse.close()
    fresh.close()


def _both(cells: tuple[Cell, Cell], camera: str) -> tuple[np.ndarray, np.ndarray]:
    return tuple(c.render(camera, *SIZE) for c in cells)  # type: ignore[return-value]


def _hits(cell: Cell) -> int:
    return cell.views.rig.pictures.hits


@pytest.mark.parametrize("camera", CAMERAS)
def test_an_unchanged_scene_returns_the_same_pixels_as_a_fresh_render(
    cells: tuple[Cell, Cell], camera: str
) -> None:
    reuse, fresh = cells
    first, _ = _both(cells, camera)
    hits = _hits(reuse)
    again, drawn = _both(cells, camera)
    assert _hits(reuse) == hits + 1
    np.testing.assert_array_equal(again, drawn)
    np.testing.assert_array_equal(again, first)
    again[:] = 0  # a fresh array: the kept picture is not shared
    np.testing.assert_array_equal(reuse.render(camera, *SIZE), drawn)


def _move_tile(cell: Cell, dx: float) -> None:
    adr = cell.ids.tile_qpos_index[0]
    cell.data.qpos[adr[0]] += dx
    mujoco.mj_forward(cell.model, cell.data)


def _recolour(cell: Cell, rgb: tuple[float, float, float]) -> None:
    g = int(cell.ids.tile_geom_start[0])
    cell.model.geom_rgba[g : g + int(cell.ids.tile_geom_count[0]), :3] = rgb


def _dim(cell: Cell, f: float) -> None:
    cell.model.light_diffuse[:] *= f


def _move_camera(cell: Cell, dz: float) -> None:
    cell.data.cam_xpos[cell.ids.input_camera, 2] += dz  # as the camera jitter moves it


@pytest.mark.parametrize(
    ("change", "arg"),
    [(_move_tile, 0.004), (_recolour, (0.1, 0.9, 0.2)), (_dim, 0.6), (_move_camera, 0.01)],
)
def test_a_changed_scene_is_drawn_anew(cells: tuple[Cell, Cell], change, arg) -> None:  # type: ignore[no-untyped-def]
    before, _ = _both(cells, CAMERAS[0])
    for c in cells:
        change(c, arg)
    after, drawn = _both(cells, CAMERAS[0])
    np.testing.assert_array_equal(after, drawn)
    assert not np.array_equal(after, before)


def test_the_pictures_kept_are_bounded() -> None:
    kept = LastPictures()
    for k in range(3 * MAX_PICTURES):
        kept.put(("camera", k), b"key", np.zeros((2, 2, 3), np.uint8))
    assert len(kept) == MAX_PICTURES
    assert kept.get(("camera", 0), b"key") is None
    assert kept.get(("camera", 3 * MAX_PICTURES - 1), b"key") is not None
    assert kept.get(("camera", 3 * MAX_PICTURES - 1), b"other key") is None


def test_joint_steps_observe_the_same_pictures_with_and_without_reuse() -> None:
    """Random joint moves (the arm in and out of the cameras' views), one env reusing pictures
    and one drawing every picture: the same observations at every step."""
    import gymnasium as gym  # noqa: PLC0415

    import envs  # noqa: PLC0415

    kw = {"action_mode": "joint", "obs_mode": "rgb", "image_size": SIZE}
    a = gym.make(envs.ENV_ID, **kw)
    b = gym.make(envs.ENV_ID, cell={"render": {"reuse_unchanged": False}}, **kw)
    try:
        for env in (a, b):
            env.reset(seed=3)
        rng = np.random.default_rng(0)
        for k in range(40):
            if k == 20:  # the arm over the input belt, in the input camera's view
                for env in (a, b):
                    u = env.unwrapped
                    g = u.cell.geometry
                    over = np.array([*g.input_centre[:2], g.belt_top + 0.08])
                    u.cell.set_qpos(u.ik.solve(over, 0.0).q)
            action = rng.uniform(-1.0, 1.0, a.action_space.shape).astype(np.float32)
            oa, ob = a.step(action)[0], b.step(action)[0]
            for camera in CAMERAS:
                np.testing.assert_array_equal(oa[camera], ob[camera])
        kept = a.unwrapped.cell.views.rig.pictures
        assert kept.hits > 0 and kept.misses > len(CAMERAS)
    finally:
        a.close()
        b.close()
