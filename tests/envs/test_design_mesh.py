"""The design's mesh is the cell's mesh: sheet, slot marks, on-mesh test, place area, framing."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import envs  # noqa: F401  registers the env
from envs.cell.cell import Cell
from envs.cell.config import load_cell_config
from envs.cell.tiles.shapes import design_mesh_size, tile_shapes_from_design
from envs.errors import MeshSizeError
from qshape.design import Design

SQUARE = {"kind": "square", "size": 40.0}


def _corner_design(width: float, height: float) -> Design:
    """Four squares in the mesh's corners, 4 mm from its edges [mm]."""
    slots = [
        {"name": f"c{k}", "shape": SQUARE, "color": "#c0392b", "pose": {"x": x, "y": y}}
        for k, (x, y) in enumerate(
            [(24, 24), (width - 24, 24), (24, height - 24), (width - 24, height - 24)]
        )
    ]
    mesh = {"width": width, "height": height}
    return Design.from_dict({"name": "corners", "mesh": mesh, "joint": 2.0, "slots": slots})


def _cell(design: Design) -> Cell:
    shapes, slots = tile_shapes_from_design(design)
    return Cell(None, shapes, slots, seed=0, mesh_size=design_mesh_size(design))


def test_a_300_mm_mesh_sets_the_sheet_marks_and_framing() -> None:
    design = _corner_design(300.0, 300.0)
    cell = _cell(design)
    try:
        geo = cell.geometry
        assert geo.mesh_size == pytest.approx([0.3, 0.3])
        sheet = cell.model.geom("mesh_sheet")
        assert sheet.size[:2] == pytest.approx([0.15, 0.15])
        # The output camera rises until the mesh and its margin fill its view, no more.
        cam = cell.camera_model("output_camera")
        signs = np.array([[-1, -1, 0], [1, 1, 0], [-1, 1, 0], [1, -1, 0]])
        uv = cam.project(geo.output_centre + signs * [0.155, 0.155, 0])  # mesh + 5 mm margin
        assert np.all(uv >= -1.0)
        assert np.all(uv[:, 0] <= cam.width + 1) and np.all(uv[:, 1] <= cam.height + 1)
        assert min(uv[:, 1].min(), cam.height - uv[:, 1].max()) < 2.0  # framed tightly
        assert geo.output_camera_height > load_cell_config().output_camera.height_above_belt
    finally:
        cell.close()


def test_the_bundled_230_mm_designs_keep_todays_cell() -> None:
    design = Design.load("paper_mixed")
    cell = _cell(design)
    try:
        geo = cell.geometry
        assert geo.mesh_size == pytest.approx([0.23, 0.23])
        assert geo.output_camera_height == load_cell_config().output_camera.height_above_belt
    finally:
        cell.close()


def test_a_mesh_larger_than_the_cell_takes_names_the_largest() -> None:
    design = _corner_design(400.0, 300.0)
    with pytest.raises(MeshSizeError, match=r"400 x 300 mm mesh .* largest mesh it takes is 320"):
        _cell(design)


def test_the_env_places_and_scores_on_the_designs_mesh(tmp_path) -> None:
    path = tmp_path / "corners.yaml"
    _corner_design(300.0, 300.0).save(path)
    env = gym.make(
        "envs:MosaicAssembly-v1",
        design=str(path),
        action_mode="pick_place_discrete",
        obs_mode="state",
        tile_order="design",
        slot_order="design",
    )
    try:
        env.reset(seed=0)
        spec = env.unwrapped.task_spec
        half = (spec.place.hi - spec.place.lo) / 2
        assert half == pytest.approx([0.15 + env.unwrapped.config.place_margin] * 2)
        # A slot in the mesh's corner, 0.126 m from its centre, is on the mesh and placeable.
        xy = np.array([s.xy for s in spec.slots])
        assert np.max(np.abs(xy - spec.mesh_centre), axis=0) == pytest.approx([0.126, 0.126])
        info: dict = {}
        for k in range(4):  # every tile into its slot, the corner ones included
            _, _, _, _, info = env.step(env.unwrapped.expert_action(k, k))
        assert info["evaluation"]["slots"] == 4 and info["evaluation"]["correct"] == 4
    finally:
        env.close()
