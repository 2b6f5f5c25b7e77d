"""Checkerboard calibration of the cell's cameras from rendered images."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from agents.errors import CalibrationError
from agents.scripted.calibration import calibrate, find_corners
from agents.scripted.config import CalibrationConfig, load_agents_config
from agents.scripted.perception import perceive_tiles
from benchmarks.design_cell import build_design_cell, nearest_tile
from envs.cell.calibration_board import render_calibration_views
from envs.cell.config import load_cell_config
from envs.errors import CellError
from envs.task_spec import work_areas
from qshape.design import Design


@pytest.fixture(scope="module")
def cfg() -> CalibrationConfig:
    return load_agents_config().calibration


@pytest.fixture(scope="module")
def views(cfg):
    return render_calibration_views(load_cell_config(), "input_camera", cfg.target)


@pytest.fixture(scope="module")
def result(views, cfg):
    return calibrate(views, cfg)


def test_reprojection_and_focal(result):
    assert result.reprojection_px < 0.5
    assert result.pnp_reprojection_px < 0.5
    assert abs(result.focal_error_pct) < 1.0
    assert result.principal_point_error_px < 2.0
    assert result.position_error_mm < 5.0
    assert result.angle_error_deg < 0.1
    assert result.views_used >= 5


def test_corner_order_matches_the_board(views, cfg, result):
    """Projected world corners of the flat view land on the detected ones (no flip)."""
    corners = find_corners(views.flat, cfg)
    assert corners is not None
    world = cfg.target.corners() + views.flat_pose
    np.testing.assert_allclose(views.true_camera.project(world), corners, atol=0.5)


def test_calibrated_camera_locates_tiles_within_2mm(result, design: Design):
    cell, _ = build_design_cell(design, seed=0)
    try:
        cell.step(100)
        per = perceive_tiles(
            cell.render("input_camera"), result.camera, work_areas(cell)[0].tile_top_z
        )
        assert len(per.tiles) == len(design.slots)
        for t in per.tiles:
            assert nearest_tile(cell, t.centre)[1] < 0.002
    finally:
        cell.close()


def test_too_few_views_is_an_error(views, cfg):
    blank = np.zeros_like(views.flat)
    bad = type(views)((blank,) * 6, blank, views.flat_pose, views.true_camera)
    with pytest.raises(CalibrationError, match="board found in 0"):
        calibrate(bad, cfg)


def test_unknown_camera(cfg):
    with pytest.raises(CellError, match="allowed"):
        render_calibration_views(load_cell_config(), "top_camera", cfg.target)


BARREL = (-0.1, 0.08, 0.0, 0.0, 0.0)
"""A mild barrel lens (OpenCV's k1, k2, p1, p2, k3)."""


def test_the_camera_pose_through_a_barrel_lens_is_solved_with_the_lens(cfg):
    """The belt plane's pose comes out within 0.8 mm only if the estimated lens is used."""
    cell_cfg = load_cell_config()
    cam = dataclasses.replace(cell_cfg.input_camera, distortion=BARREL)
    views = render_calibration_views(
        dataclasses.replace(cell_cfg, input_camera=cam), "input_camera", cfg.target
    )
    result = calibrate(views, cfg)
    assert result.distortion[0] < -0.05  # barrel found
    assert result.pnp_reprojection_px < 0.5
    assert result.position_error_mm < 0.8
    assert result.angle_error_deg < 0.05
