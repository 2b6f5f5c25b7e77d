"""Bad input fails clearly and before anything is simulated."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from configs import CONFIG_DIR
from envs.cell.cell import Cell
from envs.cell.config import (
    CameraConfig,
    CellConfig,
    InputBeltConfig,
    LayoutConfig,
    OutputBeltConfig,
    PhysicsConfig,
    SuctionConfig,
    TileConfig,
    load_cell_config,
)
from envs.cell.tiles.shapes import basic_shapes
from envs.cell.tiles.tile import SlotSpec, TileShape
from envs.errors import CellError, EnvError


def test_bundled_yaml_equals_defaults() -> None:
    assert load_cell_config() == CellConfig()
    assert load_cell_config(None) == CellConfig()


def test_overrides_and_compact_layout() -> None:
    cfg = load_cell_config(
        layout={"belt_separation": 0.5, "work_x": 0.5}, input_belt={"length": 0.6}
    )
    assert (
        cfg.layout.belt_separation == 0.5 and cfg.input_belt.width == CellConfig().input_belt.width
    )
    with pytest.raises(CellError, match="input_belt .* robot base axis"):
        load_cell_config(layout={"belt_separation": 0.5, "work_x": 0.5})


def test_unknown_key_names_allowed_keys() -> None:
    with pytest.raises(CellError, match=r"unknown key\(s\) \['sped'\].*allowed: .*speed"):
        load_cell_config(input_belt={"sped": 0.1})
    with pytest.raises(CellError, match="unknown key"):
        load_cell_config(cameras={})
    with pytest.raises(EnvError):
        load_cell_config(tiles={"thickness": "thin"})


@pytest.mark.parametrize(
    ("cls", "kwargs", "match"),
    [
        (InputBeltConfig, {"speed": -0.1}, r"InputBeltConfig.speed must be in \[0, 1\]"),
        (InputBeltConfig, {"length": 0.0}, "length must be > 0"),
        (InputBeltConfig, {"width": -1.0}, "width must be > 0"),
        (InputBeltConfig, {"tile_area": (0.3, 0.5)}, "exceeds the belt width"),
        (InputBeltConfig, {"tile_area": (0.3,)}, "needs 2 values"),
        (OutputBeltConfig, {"max_mesh_size": (0.7, 0.2)}, "does not fit the belt"),
        (TileConfig, {"thickness": 0.0}, r"thickness must be in \(0, 0.02\]"),
        (TileConfig, {"density": -2400.0}, "density must be > 0"),
        (TileConfig, {"distractor_rate": 1.5}, r"distractor_rate must be in \[0, 1\]"),
        (TileConfig, {"distractor_kinds": ("cracked",)}, "allowed"),
        (TileConfig, {"feed": "trickle"}, "allowed: 'all', 'stream', 'batch'"),
        (TileConfig, {"batch_size": 0}, "batch_size must be an int >= 1"),
        (TileConfig, {"batch_size": 4.5}, "batch_size must be an int"),
        (TileConfig, {"batch_index_time": -1.0}, "batch_index_time must be > 0"),
        (TileConfig, {"variants": 0}, "variants must be an int >= 1"),
        (TileConfig, {"variants": 2.0}, "variants must be an int"),
        (SuctionConfig, {"vacuum_pressure": 0.0}, "vacuum_pressure must be > 0"),
        (SuctionConfig, {"pad_diameter": float("nan")}, "pad_diameter must be a finite number > 0"),
        (CameraConfig, {"width": 0}, "CameraConfig.width must be > 0"),
        (CameraConfig, {"fovy_deg": 180.0}, r"fovy_deg must be in \(0, 170\)"),
        (PhysicsConfig, {"timestep": 0.0}, r"timestep must be in \(0, 0.005\]"),
        (PhysicsConfig, {"timestep": 0.01}, r"timestep must be in \(0, 0.005\], got 0.01"),
        (LayoutConfig, {"belt_separation": -1.0}, "belt_separation must be > 0"),
    ],
)
def test_invalid_values_raise(cls, kwargs, match) -> None:
    with pytest.raises(CellError, match=match):
        cls(**kwargs)


def test_overlapping_belts_raise() -> None:
    with pytest.raises(CellError, match="overlap"):
        CellConfig(layout=LayoutConfig(belt_separation=0.2))


def test_too_many_tiles_raise_before_simulating() -> None:
    with pytest.raises(CellError, match="tiles need about .* cm\\^2"):
        Cell(None, basic_shapes() * 40)


def test_too_large_tile_raises() -> None:
    big = TileShape(np.array([[0, 0], [0.5, 0], [0.5, 0.5], [0, 0.5]]), name="slab")
    with pytest.raises(CellError, match="does not fit the tile area"):
        Cell(None, [big])


def test_slot_outside_the_mesh_raises() -> None:
    sq = basic_shapes()[0]
    with pytest.raises(CellError, match="extends beyond the mesh"):
        Cell(None, [sq], slots=[SlotSpec(sq, (0.12, 0.0, 0.0))], mesh_size=(0.23, 0.23))


@pytest.mark.parametrize(
    ("outline", "match"),
    [
        ([[0, 0], [1, 1], [1, 0], [0, 1]], "invalid polygon"),  # bow tie
        ([[0, 0], [1, 0]], r"n >= 3"),
        ([[0, 0], [1, 0], [np.nan, 1]], "NaN"),
    ],
)
def test_bad_shapes_raise(outline, match) -> None:
    with pytest.raises(CellError, match=match):
        TileShape(np.array(outline, float) * 0.02, name="bad")


def test_bad_color_and_slot_pose() -> None:
    sq = np.array([[0, 0], [0.02, 0], [0.02, 0.02], [0, 0.02]])
    with pytest.raises(CellError, match="color"):
        TileShape(sq, color=(1.2, 0, 0))
    with pytest.raises(CellError, match="pose"):
        SlotSpec(TileShape(sq), (0.0, float("inf"), 0.0))


def test_bad_commands_raise() -> None:
    cell = Cell(None, basic_shapes()[:1])
    try:
        with pytest.raises(CellError, match="6 finite"):
            cell.set_servo(np.full(6, np.nan))
        with pytest.raises(CellError, match="6 finite"):
            cell.set_servo(np.zeros(5))
        with pytest.raises(CellError, match="outside the joint ranges"):
            cell.set_qpos(np.array([0, 3.0, 0, 0, 0, 0]))
        with pytest.raises(CellError, match="n >= 1"):
            cell.step(0)
    finally:
        cell.close()
    with pytest.raises(CellError, match="closed"):
        cell.step(1)


def test_configs_are_frozen() -> None:
    cfg = CellConfig()
    with pytest.raises(dataclasses.FrozenInstanceError):
        cfg.layout.belt_top_z = 1.0  # type: ignore[misc]


@pytest.mark.parametrize(("joint", "angle"), [(0, 10.0), (2, 1.2), (4, -2.1)])
def test_a_robot_home_outside_a_joint_range_is_refused_naming_the_joint(
    tmp_path, joint: int, angle: float
) -> None:
    """A cell.yaml whose home leaves a joint's range (the MJCF's) is refused when the cell is built.

    Loading the file does not build the model (``import envs`` loads the bundled cell config
    and stays free of MuJoCo); building the cell reads the ranges from the model and refuses
    the home before anything is simulated. Ranges: joint1 +-180 deg, joint3 [-230, 50] deg,
    joint5 +-115 deg.
    """
    home = list(load_cell_config().robot.home)
    home[joint] = angle
    text = (CONFIG_DIR / "cell.yaml").read_text()
    bad = tmp_path / "cell.yaml"
    bad.write_text(text.replace("home: [0.0, 0.0, 0.0, 0.0, 1.5707963, 0.0]", f"home: {home}"))
    cfg = load_cell_config(bad)
    assert cfg.robot.home[joint] == angle
    pattern = rf"robot.home\[{joint}\] = {angle!r} rad is outside joint {joint + 1}'s range"
    with pytest.raises(CellError, match=pattern):
        Cell(cfg, basic_shapes()[:1], seed=0)
