"""Contract tests of the task description (`envs.task_spec`): `work_areas`, `world_slots`,
`build_task_spec`, `discrete_codec` and `TaskSpec.camera`, on the cell of
``MosaicDecision6-v1`` (6 slots of paper_mixed, built once per module).

Each test calls the function itself with the configuration it checks (a changed copy of the
env's), so the function runs inside the test; each names the bug it guards against.
"""

from __future__ import annotations

import dataclasses
import math
import re

import numpy as np
import pytest

from envs.env_config import EnvConfig
from envs.observations.objects import object_fields
from envs.task_spec import (
    DiscreteCodec,
    PickPlaceCodec,
    StateFields,
    build_task_spec,
    discrete_codec,
    work_areas,
    world_slots,
)
from qshape.design.model import Design

MARGIN = 0.25
"""A pick or place margin that is exact in binary [m]."""


def _config(env, **changes: object) -> EnvConfig:
    return dataclasses.replace(env.unwrapped.config, **changes)


def _moving(cfg: EnvConfig, speed: float) -> EnvConfig:
    belt = dataclasses.replace(cfg.cell.input_belt, speed=speed)
    return dataclasses.replace(cfg, cell=dataclasses.replace(cfg.cell, input_belt=belt))


@pytest.fixture(scope="module")
def design() -> Design:
    """The full paper_mixed design (16 slots; the cell holds its first 6)."""
    return Design.load("paper_mixed")


def test_work_areas_are_the_tile_area_and_the_mesh_with_their_heights(decision6_env) -> None:
    """Without a configuration: pick = the input tile area, place = the mesh, each centred on
    its belt, at the belt top and the mesh top, tile tops one thickness higher.

    Guards against a half size taken as the full size, centres or heights swapped.
    """
    cell = decision6_env.unwrapped.cell
    g, c = cell.geometry, cell.cfg
    pick, place = work_areas(cell)
    half_in = np.asarray(c.input_belt.tile_area) / 2
    np.testing.assert_array_equal(pick.lo, g.input_centre[:2] - half_in)
    np.testing.assert_array_equal(pick.hi, g.input_centre[:2] + half_in)
    np.testing.assert_array_equal(place.lo, g.output_centre[:2] - np.asarray(g.mesh_size) / 2)
    np.testing.assert_array_equal(place.hi, g.output_centre[:2] + np.asarray(g.mesh_size) / 2)
    np.testing.assert_allclose(pick.centre, g.input_centre[:2], atol=1e-15)
    assert (pick.surface_z, place.surface_z) == (g.belt_top, g.mesh_top)
    assert pick.tile_top_z == g.belt_top + c.tiles.thickness
    assert place.tile_top_z == g.mesh_top + c.tiles.thickness
    assert pick.tile_top_z != place.tile_top_z  # the two surfaces differ in this cell


def test_work_area_margins_grow_each_area_on_every_side(decision6_env) -> None:
    """pick_margin grows the pick area only, place_margin the place area only, by the margin
    on each side.

    Guards against a margin applied to the wrong area, to one side, or doubled.
    """
    env = decision6_env
    cell = env.unwrapped.cell
    pick0, place0 = work_areas(cell, _config(env))
    pick, place = work_areas(cell, _config(env, pick_margin=MARGIN))
    np.testing.assert_allclose(pick.lo, pick0.lo - MARGIN, atol=1e-15)
    np.testing.assert_allclose(pick.hi, pick0.hi + MARGIN, atol=1e-15)
    np.testing.assert_array_equal(place.lo, place0.lo)
    np.testing.assert_array_equal(place.hi, place0.hi)
    pick, place = work_areas(cell, _config(env, place_margin=MARGIN))
    np.testing.assert_array_equal(pick.lo, pick0.lo)
    np.testing.assert_array_equal(pick.hi, pick0.hi)
    np.testing.assert_allclose(place.lo, place0.lo - MARGIN, atol=1e-15)
    np.testing.assert_allclose(place.hi, place0.hi + MARGIN, atol=1e-15)
    assert (pick.surface_z, pick.tile_top_z) == (pick0.surface_z, pick0.tile_top_z)
    assert (place.surface_z, place.tile_top_z) == (place0.surface_z, place0.tile_top_z)


def test_a_moving_belt_stretches_the_pick_area_to_the_belts_end(decision6_env) -> None:
    """belt_speed > 0: the pick area's upper x reaches the input belt's end (tiles travel
    downstream); a static belt, or no configuration, does not.

    Guards against the stretch lost, applied to y or to the low side, or applied at speed 0.
    """
    env = decision6_env
    cell = env.unwrapped.cell
    end = cell.geometry.input_belt_end
    still, _ = work_areas(cell, _config(env))
    assert still.hi[0] < end  # the tile area stops short of the belt's end
    moving, _ = work_areas(cell, _moving(_config(env), 0.05))
    assert moving.hi[0] == end
    np.testing.assert_array_equal(moving.lo, still.lo)
    assert moving.hi[1] == still.hi[1]
    wide, _ = work_areas(cell, _moving(_config(env, pick_margin=MARGIN), 0.05))
    assert wide.hi[0] == still.hi[0] + MARGIN  # a margin past the belt's end is kept
    assert wide.hi[0] > end


def test_world_slots_are_the_cells_slots_with_the_designs_names_and_figures(
    decision6_env, design: Design
) -> None:
    """Slot k: index k, the design's name, colour and figure, the cell's class, symmetry and
    world pose.

    Guards against an index, pose or field taken from another slot, or a wrong type.
    """
    cell = decision6_env.unwrapped.cell
    slots = world_slots(cell, design)
    poses = cell.slot_poses_world()
    assert len(slots) == len(cell.slots) == 6  # noqa: PLR2004 - the design has 16
    for k, s in enumerate(slots):
        assert s.index == k
        assert s.name == design.slots[k].name
        assert s.class_name == cell.slots[k].shape.name
        np.testing.assert_array_equal(s.xy, poses[k, :2])
        assert s.xy.shape == (2,)
        assert s.yaw == float(poses[k, 2]) and type(s.yaw) is float
        assert s.symmetry == cell.slots[k].shape.symmetry and type(s.symmetry) is int
        assert s.color == tuple(float(v) for v in design.slots[k].color)
        assert all(type(v) is float for v in s.color)
        assert s.figure == design.slots[k].figure()
    assert [s.symmetry for s in slots] == [4, 4, 2, 0, 1, 1]
    assert len({s.name for s in slots}) == 6  # noqa: PLR2004
    slots[0].xy[0] = 99.0  # a copy: the cell's poses are untouched
    assert cell.slot_poses_world()[0, 0] != 99.0  # noqa: PLR2004


def test_discrete_codec_of_a_cell_counts_its_tiles_slots_and_bins(decision6_env) -> None:
    """(tiles, slots, rotation_bins, rotation_frame) of the cell and the configuration.

    Guards against a size from the wrong count or the configuration's values swapped.
    """
    env = decision6_env
    cell = env.unwrapped.cell
    codec = discrete_codec(cell, _config(env, rotation_bins=5, rotation_frame="shape"))
    assert codec == DiscreteCodec(6, 6, 5, "shape")
    assert codec.nvec == (6, 6, 5)


def test_build_task_spec_of_the_discrete_mode(decision6_env, design: Design) -> None:
    """Every field of the spec: design, slots, areas, heights, mesh centre, belt, feed, mode,
    image size, both cameras at that size, the codecs of the mode only, the field maps.

    Guards against a field taken from the wrong source or a codec given to the wrong mode.
    """
    env = decision6_env
    cell = env.unwrapped.cell
    cfg = _config(env, image_size=(40, 56), objects_points=16, rotation_bins=6)
    spec = build_task_spec(cell, cfg, design)
    assert spec.design == "paper_mixed"
    assert [s.name for s in spec.slots] == [s.name for s in world_slots(cell, design)]
    pick, place = work_areas(cell, cfg)
    for got, want in ((spec.pick, pick), (spec.place, place)):
        np.testing.assert_array_equal(got.lo, want.lo)
        np.testing.assert_array_equal(got.hi, want.hi)
        assert (got.surface_z, got.tile_top_z) == (want.surface_z, want.tile_top_z)
    assert spec.tile_thickness == cell.cfg.tiles.thickness and type(spec.tile_thickness) is float
    np.testing.assert_array_equal(spec.mesh_centre, cell.geometry.output_centre[:2])
    assert spec.mesh_centre.shape == (2,)
    assert spec.belt_speed == 0.0 and type(spec.belt_speed) is float
    assert spec.feed == cell.cfg.tiles.feed
    assert spec.action_mode == "pick_place_discrete"
    assert spec.image_size == (40, 56)
    assert sorted(spec.cameras) == ["input_camera", "output_camera"]
    for name, cam in spec.cameras.items():
        want = cell.camera_model(name, 40, 56)
        assert (cam.name, cam.height, cam.width) == (name, 40, 56)
        np.testing.assert_array_equal(cam.K, want.K)
        np.testing.assert_array_equal(cam.world_to_camera, want.world_to_camera)
    assert spec.codec is None and spec.tool_step is None and spec.joint_step is None
    assert spec.discrete == DiscreteCodec(6, 6, 6, cfg.rotation_frame)
    assert spec.state_fields == StateFields()
    assert spec.object_fields == object_fields(16)
    assert spec.object_fields != object_fields(32)
    spec.mesh_centre[0] = 99.0  # a copy: the cell's geometry is untouched
    assert cell.geometry.output_centre[0] != 99.0  # noqa: PLR2004


@pytest.mark.parametrize("pick_yaw", [True, False])
def test_build_task_spec_gives_the_pick_place_codec_its_layout(
    decision6_env, design: Design, pick_yaw: bool
) -> None:
    """pick_place: a codec over the work areas, with or without the pick-yaw entry as
    configured; no other mode's codec.

    Guards against the layout flag ignored or the areas swapped.
    """
    env = decision6_env
    cfg = _config(env, action_mode="pick_place", pick_yaw_entry=pick_yaw, pick_margin=MARGIN)
    spec = build_task_spec(env.unwrapped.cell, cfg, design)
    assert isinstance(spec.codec, PickPlaceCodec)
    assert spec.codec.pick_yaw is pick_yaw
    assert spec.codec.size == (6 if pick_yaw else 5)
    pick, place = work_areas(env.unwrapped.cell, cfg)
    np.testing.assert_array_equal(spec.codec.pick.lo, pick.lo)
    np.testing.assert_array_equal(spec.codec.place.hi, place.hi)
    assert spec.action_mode == "pick_place"
    assert spec.discrete is None and spec.tool_step is None and spec.joint_step is None


@pytest.mark.parametrize(
    ("control_dt", "substeps"),
    [(0.04, 20), (0.0413, 21), (0.0005, 1)],  # timestep 2 ms: rounded, at least one step
)
def test_build_task_spec_tool_and_joint_steps_use_the_whole_control_period(
    decision6_env, design: Design, control_dt: float, substeps: int
) -> None:
    """cartesian: tool_step = (speed, speed, speed, yaw rate) x period; joint: each axis'
    speed limit x period; the period is a whole number (>= 1) of physics steps.

    Guards against the configured control_dt used as is, the rounding or the floor of one
    step lost, or a step given to the wrong mode.
    """
    env = decision6_env
    cell = env.unwrapped.cell
    dt = float(cell.model.opt.timestep)
    assert dt == 0.002  # noqa: PLR2004 - the substeps above assume it
    period = substeps * dt
    cfg = _config(env, action_mode="cartesian", control_dt=control_dt, tool_speed=0.25)
    spec = build_task_spec(cell, cfg, design)
    s = 0.25 * period
    assert spec.tool_step == pytest.approx((s, s, s, cfg.tool_yaw_rate * period), rel=1e-12)
    assert spec.joint_step is None and spec.codec is None and spec.discrete is None
    assert spec.action_mode == "cartesian"
    spec = build_task_spec(cell, dataclasses.replace(cfg, action_mode="joint"), design)
    want = tuple(float(v) * period for v in cell.max_joint_speed)
    assert spec.joint_step == pytest.approx(want, rel=1e-12)
    assert len(spec.joint_step) == 6 and all(type(v) is float for v in spec.joint_step)  # noqa: PLR2004
    assert spec.tool_step is None and spec.codec is None and spec.discrete is None


def test_build_task_spec_names_a_drawn_design_by_its_own_name(decision6_env, design) -> None:
    """A procedural design source: the spec names the drawn design; a fixed one: the
    configured name or path.

    Guards against the two sources swapped.
    """
    env = decision6_env
    drawn = dataclasses.replace(design, name="drawn_0007")
    cell = env.unwrapped.cell
    assert build_task_spec(cell, _config(env), drawn).design == "paper_mixed"
    procedural = _config(env, design_source="procedural")
    assert build_task_spec(cell, procedural, drawn).design == "drawn_0007"


def test_camera_returns_the_named_model_and_lists_the_allowed_names(decision6_env) -> None:
    """camera(name) is the spec's model of that name; an unknown name is a KeyError listing
    the allowed ones.

    Guards against the allowed names missing from the message.
    """
    spec = decision6_env.unwrapped.task_spec
    assert spec.camera("input_camera") is spec.cameras["input_camera"]
    assert spec.camera("output_camera").name == "output_camera"
    msg = "unknown camera 'top_camera'; allowed: ['input_camera', 'output_camera']"
    with pytest.raises(KeyError, match=re.escape(msg)):
        spec.camera("top_camera")  # type: ignore[arg-type]
    assert math.isfinite(float(spec.camera("input_camera").K[0, 0]))
