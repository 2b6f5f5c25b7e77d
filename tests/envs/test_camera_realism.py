"""A camera closer to a real one: exposure, lens distortion, belt motion blur, pose jitter."""

from __future__ import annotations

import dataclasses

import gymnasium as gym
import mujoco
import numpy as np
import pytest

import envs  # noqa: F401  (registers MosaicAssembly-v0)
from agents.scripted.calibration import calibrate
from agents.scripted.config import load_agents_config
from agents.scripted.perception import perceive_tiles
from benchmarks.design_cell import build_design_cell, nearest_tile
from benchmarks.recognition.camera_model import glaze_colours
from envs.cell.calibration_board import render_calibration_views
from envs.cell.cameras import CameraModel, CameraRig, camera_model, distort_normalised
from envs.cell.cell import Cell
from envs.cell.config import (
    CameraConfig,
    CellConfig,
    RenderConfig,
    SceneryConfig,
    load_cell_config,
)
from envs.cell.scene import cell_geometry
from envs.cell.tiles.shapes import basic_shapes
from envs.errors import CellError
from envs.task_spec import work_areas
from qshape.design import Design

LENS = (-0.1, 0.08, 0.0, 0.0, 0.0)
"""A mild barrel lens (OpenCV's k1, k2, p1, p2, k3)."""
LENS_TANGENTIAL = (-0.1, 0.08, 0.001, -0.0008, 0.02)
SIZE = (492, 656)


def _with_lens(cfg: CellConfig, lens: tuple[float, ...], exposure: float = 0.0) -> CellConfig:
    cam = dataclasses.replace(cfg.input_camera, distortion=lens, exposure_time=exposure)
    return dataclasses.replace(cfg, input_camera=cam)


def _red_centroid(img: np.ndarray) -> np.ndarray:
    r, g, b = (img[..., k].astype(int) for k in range(3))
    rows, cols = np.nonzero((r > 120) & (g < 60) & (b < 60))
    assert len(rows) > 10, "marker not visible"
    return np.array([cols.mean(), rows.mean()])


@pytest.mark.parametrize("lens", [LENS, LENS_TANGENTIAL])
@pytest.mark.parametrize("offset", [(0.0, 0.0), (0.1, 0.07), (-0.13, -0.09), (0.14, -0.1)])
def test_distorted_render_matches_the_lens_model(marker_scene, lens, offset) -> None:
    """A marker in the warped image sits where OpenCV's model puts it, not at the pinhole's."""
    model, data, mocap = marker_scene
    point = cell_geometry(CellConfig()).input_centre + [offset[0], offset[1], 0.004]
    data.mocap_pos[mocap] = point
    mujoco.mj_forward(model, data)
    cid = model.camera("input_camera").id
    h, w = SIZE
    lensed = camera_model(model, data, cid, w, h, distortion=lens)
    pinhole = camera_model(model, data, cid, w, h)
    rig = CameraRig(model, RenderConfig(), {"input_camera": CameraConfig(distortion=lens)})
    try:
        img = rig.render(data, "input_camera", h, w)
    finally:
        rig.close()
    got = _red_centroid(img)
    err = float(np.linalg.norm(got - lensed.project(point)))
    assert err < 0.75  # a sphere's image centroid is not exactly its centre's projection
    if offset != (0.0, 0.0):  # read as a pinhole it is off by more: the test can fail
        assert np.linalg.norm(got - pinhole.project(point)) > err + 0.5


def test_lens_projection_round_trip() -> None:
    cell = Cell(_with_lens(load_cell_config(), LENS_TANGENTIAL), basic_shapes()[:1], seed=0)
    try:
        cam = cell.camera_model("input_camera")
        np.testing.assert_allclose(cam.distortion, LENS_TANGENTIAL)
        uv = np.array([[3.0, 4.0], [328.0, 246.0], [650.0, 488.0], [100.0, 400.0]])
        z = cell.geometry.belt_top
        np.testing.assert_allclose(cam.project(cam.unproject_to_plane(uv, z)), uv, atol=1e-3)
        # Without the lens the same pixels land elsewhere on the belt (by millimetres).
        ideal = CameraModel(cam.name, cam.width, cam.height, cam.K, cam.world_to_camera)
        gap = np.linalg.norm(
            ideal.unproject_to_plane(uv, z) - cam.unproject_to_plane(uv, z), axis=1
        )
        assert gap.max() > 1e-3
        xy = np.array([[0.1, -0.2]])
        assert not np.allclose(distort_normalised(xy, np.zeros(5)), distort_normalised(xy, LENS))
    finally:
        cell.close()


@pytest.mark.slow
def test_calibration_estimates_the_lens_and_perception_removes_it() -> None:
    """Checkerboard calibration through a barrel lens: tiles located within 1.5 mm."""
    cfg = load_agents_config().calibration
    cell_cfg = _with_lens(load_cell_config(), LENS)
    result = calibrate(render_calibration_views(cell_cfg, "input_camera", cfg.target), cfg)
    assert result.reprojection_px < 0.5
    assert result.distortion[0] < -0.05  # barrel found
    design = Design.load("paper_mixed")
    cell, _ = build_design_cell(design, cell_cfg, seed=0)
    try:
        cell.step(100)
        z = work_areas(cell)[0].tile_top_z
        image = cell.render("input_camera")
        per = perceive_tiles(image, result.camera, z)
        assert len(per.tiles) == len(design.slots)
        errors = [nearest_tile(cell, t.centre)[1] for t in per.tiles]
        assert max(errors) < 0.0015
        # The same picture read as a pinhole puts tiles near the corners further off.
        pinhole = CameraModel(
            *[getattr(result.camera, f) for f in ("name", "width", "height")],
            result.camera.K,
            result.camera.world_to_camera,
        )
        naive = [nearest_tile(cell, t.centre)[1] for t in perceive_tiles(image, pinhole, z).tiles]
        assert max(naive) > max(errors) + 0.0005
    finally:
        cell.close()


@pytest.mark.parametrize("exposure", [1.0, 0.8])
def test_exposure_renders_glazes_at_their_colour(exposure) -> None:
    base = load_cell_config()
    cfg = dataclasses.replace(base, scenery=dataclasses.replace(base.scenery, exposure=exposure))
    cell = Cell(cfg, basic_shapes(), seed=0)
    try:
        got, want, _ = glaze_colours(cell)
        assert len(got) >= 4
        np.testing.assert_allclose(got, exposure * want, atol=2.5 / 255)
    finally:
        cell.close()


def test_belt_blur_smears_tiles_along_the_belt_only() -> None:
    """Blur length = speed x exposure x px/m along the belt; centroid and width kept."""
    shapes = [s for s in basic_shapes() if s.name == "square"][:1]
    exposure, speed = 0.02, 0.2
    sharp_cell = Cell(load_cell_config(), shapes, seed=3)
    blur_cell = Cell(_with_lens(load_cell_config(), (0.0,) * 5, exposure), shapes, seed=3)
    try:
        images = []
        for cell in (sharp_cell, blur_cell):
            cell.belt_speed = speed
            images.append(cell.render("input_camera").astype(float))
        cam = sharp_cell.camera_model("input_camera")
        c = sharp_cell.geometry.input_centre
        along = np.diff(cam.project(np.array([c, c + [1.0, 0, 0]])), axis=0)[0]
        axis = int(np.argmax(np.abs(along)))  # image axis of the belt (0: u, 1: v)
        length_px = speed * exposure * float(np.linalg.norm(along))
        profiles = []
        for img in images:
            lum = img.mean(axis=2)
            weight = np.clip(lum - np.median(lum), 0, None)
            rows, cols = np.indices(lum.shape)
            coords = (cols, rows)
            centre = [(weight * k).sum() / weight.sum() for k in coords]
            spread = [
                np.sqrt((weight * (k - m) ** 2).sum() / weight.sum())
                for k, m in zip(coords, centre, strict=True)
            ]
            profiles.append((np.array(centre), np.array(spread)))
        (c0, s0), (c1, s1) = profiles
        assert np.linalg.norm(c1 - c0) < 0.3  # exposure centred on the render time
        # A box of length L adds L^2 / 12 to the variance along the belt, nothing across.
        grown = np.sqrt(max(s1[axis] ** 2 - s0[axis] ** 2, 0.0))
        assert grown == pytest.approx(length_px / np.sqrt(12), rel=0.25)
        assert abs(s1[1 - axis] - s0[1 - axis]) < 0.15
        # A still belt gives the sharp picture.
        blur_cell.belt_speed = 0.0
        np.testing.assert_array_equal(blur_cell.render("input_camera"), images[0].astype(np.uint8))
    finally:
        sharp_cell.close()
        blur_cell.close()


def test_camera_pose_jitter_is_seeded_and_bounded() -> None:
    kw = {"image_size": (72, 96), "obs_mode": "rgb", "execution": "kinematic"}
    env = gym.make(
        "MosaicAssembly-v0", camera_position_jitter=0.005, camera_angle_jitter_deg=1.0, **kw
    )
    plain = gym.make("MosaicAssembly-v0", **kw)
    try:
        cell = env.unwrapped.cell
        cid = cell.ids.input_camera
        nominal = plain.unwrapped.cell.data.cam_xpos[cid].copy()
        seen = []
        for seed in (0, 1, 0):
            obs, _ = env.reset(seed=seed)
            pos = cell.data.cam_xpos[cid].copy()
            assert np.all(np.abs(pos - nominal) <= 0.005 + 1e-9)
            # The rendered pose is the drawn one (a static camera is not recomputed by stepping).
            np.testing.assert_allclose(pos, cell.model.cam_pos[cid], atol=1e-12)
            seen.append((pos, obs["input_camera"]))
        assert not np.allclose(seen[0][0], seen[1][0])
        np.testing.assert_array_equal(seen[0][1], seen[2][1])
        # Off: nothing drawn, the episode is the plain one.
        obs_plain, _ = plain.reset(seed=0)
        env_off = gym.make("MosaicAssembly-v0", camera_position_jitter=0.0, **kw)
        try:
            np.testing.assert_array_equal(
                env_off.reset(seed=0)[0]["input_camera"], obs_plain["input_camera"]
            )
        finally:
            env_off.close()
    finally:
        env.close()
        plain.close()


@pytest.mark.parametrize(
    ("section", "values"),
    [
        (CameraConfig, {"distortion": (0.1, 0.0)}),
        (CameraConfig, {"distortion": (float("nan"), 0.0, 0.0, 0.0, 0.0)}),
        (CameraConfig, {"exposure_time": -0.001}),
        (SceneryConfig, {"exposure": 0.0}),
        (SceneryConfig, {"exposure": 1.2}),
        (SceneryConfig, {"light_diffuse": 0.0, "headlight_ambient": 0.0, "headlight_diffuse": 0.0}),
    ],
)
def test_bad_camera_settings_are_named(section, values) -> None:
    with pytest.raises(CellError, match=next(iter(values))):
        section(**values)
