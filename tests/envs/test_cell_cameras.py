"""Cameras: intrinsics/extrinsics, projection against rendered pixels, renderer life cycle."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import mujoco
import numpy as np
import pytest

from envs.cell.cameras import CameraRig, camera_model
from envs.cell.cell import Cell
from envs.cell.config import CellConfig, RenderConfig
from envs.cell.scene import cell_geometry
from envs.cell.tiles.shapes import basic_shapes
from envs.errors import CellError


def _red_centroid(img: np.ndarray) -> np.ndarray:
    r, g, b = (img[..., k].astype(int) for k in range(3))
    mask = (r > 120) & (g < 60) & (b < 60)
    assert mask.sum() > 10, "marker not visible"
    rows, cols = np.nonzero(mask)
    return np.array([cols.mean(), rows.mean()])


@pytest.mark.parametrize("camera", ["input_camera", "output_camera"])
@pytest.mark.parametrize("offset", [(0.0, 0.0), (0.1, 0.07), (-0.13, -0.09), (0.05, -0.1)])
def test_projection_matches_rendered_marker(marker_scene, camera, offset) -> None:
    model, data, mocap = marker_scene
    geo = cell_geometry(CellConfig())
    centre = geo.input_centre if camera == "input_camera" else geo.output_centre
    point = centre + [offset[0], offset[1], 0.004]
    data.mocap_pos[mocap] = point
    mujoco.mj_forward(model, data)
    cid = model.camera(camera).id
    h, w = 492, 656
    cam = camera_model(model, data, cid, w, h)
    rig = CameraRig(model, RenderConfig())
    try:
        img = rig.render(data, camera, h, w)
    finally:
        rig.close()
    got = _red_centroid(img)
    want = cam.project(point)
    err = float(np.linalg.norm(got - want))
    print(f"{camera} {offset}: projection error {err:.3f} px")
    assert err < 1.0


def test_matrices_and_inverse_projection() -> None:
    cell = Cell(None, basic_shapes()[:1], seed=0, mesh_size=(0.23, 0.23))
    try:
        for name in ("input_camera", "output_camera"):
            cam = cell.camera_model(name)
            assert cam.K.shape == (3, 3) and cam.world_to_camera.shape == (4, 4)
            r = cam.world_to_camera[:3, :3]
            assert np.allclose(r @ r.T, np.eye(3), atol=1e-9)
            assert np.allclose(cam.world_to_camera[3], [0, 0, 0, 1])
            uv = np.array([[10.0, 20.0], [328.0, 246.0], [600.0, 480.0]])
            pts = cam.unproject_to_plane(uv, z=cell.geometry.belt_top)
            assert np.allclose(cam.project(pts), uv, atol=1e-6)
            # A 20 mm tile on the belt spans >= 40 px.
            c = cell.geometry.input_centre
            span = np.diff(cam.project(np.array([c, c + [0.02, 0, 0]])), axis=0)
            assert np.linalg.norm(span) >= 40
    finally:
        cell.close()


def test_renderers_reused_and_closed() -> None:
    cell = Cell(None, basic_shapes()[:2], seed=0)
    a = cell.render("input_camera", 128, 128)
    b = cell.render("output_camera", 128, 128)
    assert a.shape == b.shape == (128, 128, 3) and a.dtype == np.uint8
    assert len(cell.cameras._renderers) == 1
    full = cell.render("input_camera")
    assert full.shape == (492, 656, 3)
    depth = cell.render("input_camera", 64, 64, depth=True)
    assert depth.shape == (64, 64)
    assert depth[32, 32] == pytest.approx(CellConfig().input_camera.height_above_belt, abs=0.01)
    out = np.zeros((128, 128, 3), np.uint8)
    assert cell.render("input_camera", 128, 128, out=out) is out
    with pytest.raises(CellError, match="allowed"):
        cell.render("side_camera")
    cell.close()
    cell.close()
    with pytest.raises(CellError, match="closed"):
        cell.render("input_camera")


UNCLOSED = """
import numpy as np
from envs.cell.cell import Cell
from envs.mosaic_env import MosaicAssemblyEnv
cell = Cell(seed=0)
cell.render("input_camera", 32, 32)
cell.render("output_camera", 32, 32, depth=True)
env = MosaicAssemblyEnv(action_mode="joint", obs_mode="rgb", max_slots=2, image_size=32)
env.reset(seed=0)
env.step(np.zeros(7, np.float32))
print("stepped")
"""


def test_unclosed_renderers_exit_quietly() -> None:
    """A script that never closes its cell or env exits without EGL teardown noise."""
    root = Path(__file__).resolve().parents[2]
    env = {**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl"), "PYTHONPATH": str(root)}
    run = subprocess.run(
        [sys.executable, "-c", UNCLOSED],
        cwd=root,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert run.returncode == 0 and "stepped" in run.stdout, run.stderr
    assert "Exception ignored" not in run.stderr, run.stderr
    assert "Traceback" not in run.stderr, run.stderr
