"""qshape.design.mural: the bundled mural, the file format, splitting, validation, the generator."""

from __future__ import annotations

import math
from dataclasses import replace

import gymnasium as gym
import numpy as np
import pytest
import yaml

from apps import make_designs
from configs import CONFIG_DIR
from envs.cell.config import load_cell_config
from qshape import Design
from qshape.design.mural import MURAL_SUBDIR, Mural, MuralError, bundled_murals


@pytest.fixture(scope="module")
def sunset() -> Mural:
    return Mural.load("sunset")


def test_bundled_mural_is_large_realistic_and_fits_the_cell(sunset):
    assert "sunset" in bundled_murals()
    assert sunset.tiles >= 1000 and len(sunset.meshes) >= 5
    cell = load_cell_config()
    width, height = (v * 1000.0 for v in cell.output_belt.max_mesh_size)
    sunset.check_fits(width, height)
    assert 2.0 <= sunset.joint <= 3.0
    colours = set()
    for m in sunset.meshes:
        assert m.design.joint == sunset.joint
        for s in m.design.slots:
            side = math.sqrt(s.area)
            assert 15.0 <= side <= 25.0  # tesserae of ~20 mm
            colours.add(s.color)
    assert 3 <= len(colours) <= 8


def test_joints_are_equal_across_mesh_cuts(sunset):
    whole = sunset.design()
    assert len(whole.slots) == sunset.tiles
    centres = np.array([[s.x, s.y] for s in whole.slots])
    d = np.hypot(*(centres[:, None] - centres[None, :]).transpose(2, 0, 1))
    np.fill_diagonal(d, np.inf)
    pitch = math.sqrt(whole.slots[0].area) + sunset.joint
    np.testing.assert_allclose(d.min(axis=1), pitch, atol=1e-6)  # inside meshes and across cuts
    mesh = {s.name.split("/")[0] for s in whole.slots}
    assert mesh == {m.name for m in sunset.meshes}


@pytest.mark.slow
def test_split_save_load_round_trip(tmp_path, sunset):
    whole = sunset.design()
    again = Mural.split(replace(whole, name="copy"), sunset.meshes[0].design.mesh_size)
    assert [m.name for m in again.meshes] == [m.name for m in sunset.meshes]
    assert [(m.x, m.y) for m in again.meshes] == [(m.x, m.y) for m in sunset.meshes]
    path = tmp_path / "copy.yaml"
    again.save(path, "a test")
    loaded = Mural.load(path)
    assert loaded.tiles == sunset.tiles
    for a, b in zip(loaded.meshes, sunset.meshes, strict=True):
        assert a.source.endswith(f"copy/{a.name}.yaml")
        assert [(s.x, s.y, s.color) for s in a.design.slots] == [
            (s.x, s.y, s.color) for s in b.design.slots
        ]


def test_split_rejects_a_tile_across_a_cut(sunset):
    whole = sunset.design()
    with pytest.raises(MuralError, match="mesh r0c0"):
        Mural.split(whole, (215.0, 220.0))  # a cut through the tenth column of tesserae


def _write(tmp_path, data, meshes=("r0c0", "r0c1")):
    src = CONFIG_DIR / MURAL_SUBDIR / "sunset"
    (tmp_path / "m").mkdir(exist_ok=True)
    for name in meshes:
        (tmp_path / "m" / f"{name}.yaml").write_text((src / f"{name}.yaml").read_text())
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def _meshes(dx=220.0):
    return [
        {"name": "a", "design": "m/r0c0.yaml", "x": 0.0, "y": 0.0},
        {"name": "b", "design": "m/r0c1.yaml", "x": dx, "y": 0.0},
    ]


def test_loads_a_valid_file_and_rejects_bad_ones(tmp_path):
    good = {"name": "two", "joint": 2.0, "meshes": _meshes()}
    assert Mural.load(_write(tmp_path, good)).tiles == 200
    cases = [
        ({**good, "colour": 1}, "unknown key"),
        ({"name": "x", "meshes": _meshes()}, "missing key 'joint'"),
        ({**good, "meshes": []}, "non-empty"),
        ({**good, "meshes": _meshes(100.0)}, "overlap"),
        ({**good, "joint": 3.0}, "joint"),
        ({**good, "meshes": [{**_meshes()[0], "x": "left"}]}, "finite number"),
        ({**good, "meshes": [{**_meshes()[0], "design": "m/none.yaml"}]}, "not found"),
        ({**good, "meshes": [{**_meshes()[0], "angle": 3}]}, "unknown key"),
        ({**good, "meshes": [_meshes()[0], {**_meshes()[1], "name": "a"}]}, "duplicate"),
    ]
    for data, message in cases:
        with pytest.raises(MuralError, match=message):
            Mural.load(_write(tmp_path, data))


def test_unknown_mesh_and_too_large_meshes(sunset):
    with pytest.raises(MuralError, match="r0c0"):
        sunset.mesh("r9c9")
    with pytest.raises(MuralError, match="larger than"):
        sunset.check_fits(200.0, 230.0)
    with pytest.raises(MuralError, match="no configuration file"):
        Mural.load("no_such_mural")


def test_mesh_designs_load_as_plain_designs(sunset):
    m = sunset.meshes[0]
    assert Design.load(m.source).slots == m.design.slots
    assert m.design.mesh_size == (220.0, 220.0)


@pytest.mark.slow
def test_generator_writes_the_bundled_files_unchanged(tmp_path):
    make_designs.main(["--out", str(tmp_path / "d"), "--murals-out", str(tmp_path / "m")])
    for path in sorted((CONFIG_DIR / "designs").glob("*.yaml")):
        assert (tmp_path / "d" / path.name).read_bytes() == path.read_bytes(), path.name
    bundled = CONFIG_DIR / MURAL_SUBDIR
    written = sorted(p.relative_to(tmp_path / "m") for p in (tmp_path / "m").rglob("*.yaml"))
    assert written == sorted(p.relative_to(bundled) for p in bundled.rglob("*.yaml"))
    for rel in written:
        assert (tmp_path / "m" / rel).read_bytes() == (bundled / rel).read_bytes(), rel


@pytest.mark.slow
def test_a_mural_mesh_builds_in_the_cell(sunset):
    env = gym.make(
        "envs:MosaicAssembly-v0",
        design=sunset.meshes[0].source,
        feed="batch",
        action_mode="pick_place_discrete",
        obs_mode="state",
        execution="kinematic",
    )
    try:
        _, info = env.reset(seed=0)
        assert info["evaluation"]["slots"] == len(sunset.meshes[0].design.slots)
    finally:
        env.close()
