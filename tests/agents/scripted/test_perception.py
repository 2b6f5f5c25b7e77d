"""Perception on real renders of the cell (default design): recognition and world positions."""

from __future__ import annotations

import numpy as np
import pytest

from agents.errors import PerceptionError
from agents.scripted.config import PerceptionConfig
from agents.scripted.perception import (
    balance_colors,
    perceive_tiles,
    slot_targets,
)
from agents.scripted.white_balance import color_gain
from benchmarks.design_cell import build_design_cell, nearest_tile
from benchmarks.recognition.cell_renders import bench
from envs.errors import CellError
from envs.task_spec import work_areas, world_slots

POS_TOL = 0.002  # m


@pytest.fixture(scope="module")
def scene(design):
    cell, _ = build_design_cell(design, seed=0)
    cell.step(100)
    img = cell.render("input_camera")
    cam = cell.camera_model("input_camera")
    slots = slot_targets(world_slots(cell, design))
    per = perceive_tiles(img, cam, work_areas(cell)[0].tile_top_z)
    per, gain = balance_colors(per, np.array([s.color for s in slots]))
    yield cell, design, cam, slots, per, gain
    cell.close()


def test_every_tile_recognised_within_2mm(scene):
    cell, design, _, _, per, _ = scene
    assert len(per.tiles) == len(design.slots) == int(cell.on_stage.sum())
    assert not per.partial and not per.unrecognised
    seen = set()
    for t in per.tiles:
        i, d = nearest_tile(cell, t.centre)
        assert d < POS_TOL, (i, d)
        assert np.linalg.norm(cell.tile_poses().pos[i, :2] - t.centre_ray) < POS_TOL
        seen.add(i)
    assert len(seen) == len(per.tiles)


def test_grasp_point_inside_material(scene):
    _, _, _, _, per, _ = scene
    ring = [t for t in per.tiles if t.figure.holes and abs(t.figure.area) > 0]
    assert ring
    for t in per.tiles:
        assert np.linalg.norm(t.grasp - t.centre) < 0.03


def test_slots_match_cell_slot_poses(scene):
    cell, _, _, slots, _, _ = scene
    want = cell.slot_poses_world()
    got = np.array([s.pose for s in slots])
    np.testing.assert_allclose(got, want, atol=1e-9)


def test_unproject_project_round_trip(scene):
    _, _, cam, _, _, _ = scene
    uv = np.array([[0.0, 0.0], [655.0, 491.0], [300.5, 200.25]])
    pts = cam.unproject_to_plane(uv, 0.205)
    np.testing.assert_allclose(cam.project(pts), uv, atol=1e-9)
    np.testing.assert_allclose(pts[:, 2], 0.205)
    with pytest.raises(CellError, match="not in front"):
        cam.unproject_to_plane(uv, 5.0)  # plane above the camera


def test_a_plane_behind_the_camera_is_a_perception_error(scene):
    cell, _, cam, _, _, _ = scene
    with pytest.raises(PerceptionError, match="not in front"):
        perceive_tiles(cell.render("input_camera"), cam, 5.0)  # plane above the camera


def test_white_balance_in_perception_equals_balancing_after(scene):
    """Balancing while perceiving describes once and gives what re-describing gave."""
    cell, _, cam, slots, per, gain = scene
    z = per.plane_z
    once = perceive_tiles(cell.render("input_camera"), cam, z, white_balance=lambda _: gain)
    assert len(once.tiles) == len(per.tiles)
    for a, b in zip(once.tiles, per.tiles, strict=True):
        assert a.color == b.color and a.figure.color == b.figure.color
        assert a.description == b.description
        np.testing.assert_allclose(a.centre, b.centre)


def test_color_gain_recovers_a_known_gain():
    rng = np.random.default_rng(0)
    palette = rng.uniform(0.1, 0.7, (6, 3))
    true = np.array([1.2, 1.1, 0.9])
    measured = np.clip(palette[rng.integers(0, 6, 20)] / true, 0, 1)
    np.testing.assert_allclose(color_gain(measured, palette, PerceptionConfig()), true, rtol=1e-6)


def test_one_tile_snaps_to_its_nearest_colour_and_a_history_does_not():
    # paper_mixed's red and orange, and a red tile as the moving-belt camera measured it
    # (brighter in every channel, most in green): nearer orange than red.
    red, orange = np.array([0.753, 0.224, 0.169]), np.array([0.878, 0.482, 0.165])
    palette = np.array([red, orange, [0.18, 0.435, 0.82], [0.247, 0.62, 0.302]])
    gain = np.array([1.0 / 1.17, 1.0 / 1.47, 1.0 / 1.32])
    tile = red / gain
    alone = np.clip(tile * color_gain(tile[None], palette, PerceptionConfig()), 0, 1)
    np.testing.assert_allclose(alone, orange, atol=1e-9)  # wrong: fitted on one tile
    history = np.vstack([palette[[0, 1, 2, 3, 1, 2]] / gain, tile])
    fitted = np.clip(tile * color_gain(history, palette, PerceptionConfig()), 0, 1)
    np.testing.assert_allclose(fitted, red, atol=1e-6)
    # Alone, one brightness gain keeps the hue: the tile stays nearest red.
    scaled = tile * color_gain(tile[None], palette, PerceptionConfig(), per_channel=False)
    assert np.argmin(np.linalg.norm(palette - scaled, axis=1)) == 0
    # An orange tile measured with its red channel saturated (nearer yellow as measured).
    yellow = np.array([0.91, 0.765, 0.227])
    palette = np.vstack([palette, yellow])
    sat = np.array([1.0, 0.604, 0.247])
    assert np.argmin(np.linalg.norm(palette - sat, axis=1)) == 4
    scaled = sat * color_gain(sat[None], palette, PerceptionConfig(), per_channel=False)
    assert np.argmin(np.linalg.norm(palette - scaled, axis=1)) == 1


def test_color_balance_gain_is_moderate(scene):
    *_, gain = scene
    assert np.all((gain > 0.7) & (gain < 1.3))


def test_perception_takes_qshape_figures_as_they_are(scene):
    # Shape fixes (corner threshold, circles, cut-off corners) live in qshape's extraction:
    # the world figure has exactly the pixel figure's relevant points and curve marks.
    *_, per, _ = scene
    for t in per.tiles:
        assert len(t.figure.outer.points) == len(t.figure_px.outer.points)
        assert t.figure.outer.curve_mask.tolist() == t.figure_px.outer.curve_mask.tolist()
        assert [len(h.points) for h in t.figure.holes] == [len(h.points) for h in t.figure_px.holes]


@pytest.mark.slow
def test_twenty_layouts_all_recognised():
    r = bench(20, true_camera=False)
    assert r["assigned_to_own_class"] == r["tiles"] == 320
    assert r["pick_error_mm_max"] < 2.0 and r["yaw_error_deg_max"] < 2.0
