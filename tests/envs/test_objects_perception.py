"""Perception rows (`envs.observations.objects_perception`): tile rows from the picture."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from typing import Any, cast

import gymnasium as gym
import mujoco
import numpy as np
import pytest

import envs
from envs.env_config import EnvConfigError, load_env_config
from envs.errors import CellError
from envs.mosaic_env import MosaicAssemblyEnv
from envs.observations.objects import OBJECT_FIELDS as F
from envs.observations.objects_perception import PerceivedFigure, PerceivedTiles, register

TASK = "MosaicDecision6-v0"
SEED = 1000
CENTROID_MM = 2.0
YAW_DEG = 3.0
AREA_PCT = 5.0
RGB_TOL = 0.02
"""Tolerances of a perceived row against the privileged one."""


def _make(**kw: Any) -> gym.Env:
    return gym.make(TASK, obs_mode="objects", disable_env_checker=True, **kw)


@pytest.fixture(scope="module")
def perceived() -> Iterator[gym.Env]:
    e = _make(objects_source="perception")
    yield e
    e.close()


def _rows(env: gym.Env) -> tuple[np.ndarray, np.ndarray]:
    """Privileged and perceived tile rows of the current state, cell order."""
    u = cast(MosaicAssemblyEnv, env.unwrapped)
    objects, per = u.observer.objects, u.observer.perceived
    assert objects is not None and per is not None
    priv, _ = objects.observe(np.random.default_rng(0), u.task.evaluate())
    return priv, per.observe(priv)


def _yaw_error_deg(a: np.ndarray, b: np.ndarray, symmetry: int) -> float:
    if symmetry == 0:
        return 0.0
    period = 2 * np.pi / symmetry
    d = (np.arctan2(a[1], a[0]) - np.arctan2(b[1], b[0])) % period
    return float(np.degrees(min(d, period - d)))


def test_perceived_rows_agree_with_privileged(perceived: gym.Env) -> None:
    """Guards against a perceived row's centroid, yaw, area, colour (a figure's measured colour
    replaced by black) or points drifting from the tile's privileged row."""
    obs, _ = perceived.reset(seed=SEED)
    u = cast(MosaicAssemblyEnv, perceived.unwrapped)
    priv, per = _rows(perceived)
    n = len(u.cell.tiles)
    assert np.all(per[:n, F["valid"]] == 1.0)
    assert np.all(per[:n, F["flag"]] == priv[:n, F["flag"]])
    for i, tile in enumerate(u.cell.tiles):
        centroid = np.linalg.norm(per[i, F["xy"]] - priv[i, F["xy"]]) * 1e3
        assert centroid < CENTROID_MM
        yaw = _yaw_error_deg(per[i, F["yaw"]], priv[i, F["yaw"]], tile.shape.symmetry)
        assert yaw < YAW_DEG
        area = abs(per[i, F["area"]][0] / priv[i, F["area"]][0] - 1) * 100
        assert area < AREA_PCT
        assert np.abs(per[i, F["rgb"]] - priv[i, F["rgb"]]).max() < RGB_TOL  # measured colour
        # points about the centroid, world-oriented, the same start rule: close point by point
        diff = per[i, F["points"]] - priv[i, F["points"]]
        assert np.median(np.hypot(diff[0::2], diff[1::2])) < CENTROID_MM
    # the env's observation holds the same rows, permuted into the action indices
    tiles, _ = u.index.permute_state(per, priv)
    np.testing.assert_array_equal(obs["tiles"], tiles)


def test_spaces_identical_to_privileged(perceived: gym.Env) -> None:
    privileged = _make()
    try:
        assert perceived.observation_space == privileged.observation_space
        assert perceived.action_space == privileged.action_space
        obs, _ = perceived.reset(seed=SEED)
        assert perceived.observation_space.contains(obs)
    finally:
        privileged.close()


def test_tile_off_the_picture_or_cut_by_its_border_is_masked(perceived: gym.Env) -> None:
    perceived.reset(seed=SEED)
    u = cast(MosaicAssemblyEnv, perceived.unwrapped)
    cell = u.cell
    h, w = load_env_config().objects_image_size
    z = cell.geometry.input_centre[2]
    border = cell.camera_model("input_camera", h, w).unproject_to_plane(
        np.array([[0.0, h / 2]]), z
    )[0]
    c = cell.geometry.input_centre
    off = np.array([[0.0, 0.5, 0.0]])  # 0.5 m beside the tile area: out of view
    cut = np.array([[border[0] - c[0], border[1] - c[1], 0.0]])  # centre on the left border
    cell.place_tiles(np.array([0]), off)
    cell.place_tiles(np.array([1]), cut)
    mujoco.mj_forward(cell.model, cell.data)
    _, per = _rows(perceived)
    assert not per[0].any() and not per[1].any()  # masked: valid 0, all zeros
    assert np.all(per[2 : len(cell.tiles), F["valid"]] == 1.0)


def test_unfed_tiles_are_masked() -> None:
    env = _make(objects_source="perception", feed="stream")
    try:
        env.reset(seed=SEED)
        u = cast(MosaicAssemblyEnv, env.unwrapped)
        _, per = _rows(env)
        fed = u.cell.on_stage
        assert 0 < fed.sum() < len(fed)
        assert np.all(per[fed, F["valid"]] == 1.0)
        assert not per[~fed].any()
    finally:
        env.close()


def test_register_finds_the_turn_of_a_sampled_outline() -> None:
    k = np.arange(64)
    square = np.exp(1j * (np.pi / 4 + np.pi / 2 * (k // 16))) * 10  # corners only, coarse
    ref = np.stack([np.roll(square, 3), np.exp(2j * np.pi * k / 64) * 7])
    turned = np.roll(square, 5) * np.exp(0.3j)
    r, angle, rms = register(turned, ref)
    assert r == 0
    assert rms < 1e-9
    assert abs((angle - 0.3 + np.pi / 4) % (np.pi / 2) - np.pi / 4) < 1e-9


@pytest.mark.parametrize(
    ("key", "value", "needle"),
    [
        ("objects_source", "camera", "objects_source"),
        ("objects_image_size", [492], "objects_image_size"),
        ("objects_image_size", [0, 656], "objects_image_size"),
        ("objects_image_size", [True, 656], "objects_image_size"),
        ("objects_gate_mm", 0.0, "objects_gate_mm"),
        ("objects_gate_mm", -1.0, "objects_gate_mm"),
    ],
)
def test_bad_perception_config_is_refused(key: str, value: object, needle: str) -> None:
    with pytest.raises(EnvConfigError, match=needle):
        load_env_config(**{key: value})


def test_image_size_outside_the_extraction_limits_is_refused() -> None:
    with pytest.raises(EnvConfigError, match="objects_image_size 8 x 656"):
        _make(objects_source="perception", objects_image_size=[8, 656])


def _figure_at(centre: np.ndarray) -> PerceivedFigure:
    square = np.array([[-0.01, -0.01], [0.01, -0.01], [0.01, 0.01], [-0.01, 0.01]]) + centre
    return PerceivedFigure(square, (), (0.5, 0.5, 0.5), np.asarray(centre, float))


def test_a_figure_fills_a_row_only_within_the_gate(perceived: gym.Env) -> None:
    """Guards against the perception gate removed or in the wrong unit (``objects_gate_mm``
    5 mm): a figure 4.9 mm from a fed tile fills its row, one 5.1 mm away fills none, and the
    pairing is one to one (a second figure near a paired tile is dropped)."""
    perceived.reset(seed=SEED)
    u = cast(MosaicAssemblyEnv, perceived.unwrapped)
    per = u.observer.perceived
    assert per is not None and per.gate == pytest.approx(0.005)
    xy = u.cell.tile_poses().pos[:, :2]
    figs = [
        _figure_at(xy[0] + [0.0049, 0.0]),
        _figure_at(xy[1] + [0.0, -0.0051]),
        _figure_at(xy[2] + [0.0, 0.0]),
        _figure_at(xy[2] + [0.0010, 0.0]),
    ]
    pairs = per.associate(figs)
    assert sorted(pairs) == [(0, 0), (2, 2)]
    # the gate is a config value: 6 mm takes the second figure in
    wide = _make(objects_source="perception", objects_gate_mm=6.0)
    try:
        wide.reset(seed=SEED)
        w = cast(MosaicAssemblyEnv, wide.unwrapped).observer.perceived
        assert w is not None
        assert sorted(w.associate(figs)) == [(0, 0), (1, 1), (2, 2)]
    finally:
        wide.close()


def test_holed_tiles_of_the_full_design_keep_their_hole_area_and_yaw() -> None:
    """Guards against the holes dropped from the perceived figures or from the registration's
    references (an off-centre hole moves the area centroid), or kept with a z column (a
    `PerceivedFigure`'s holes are world (x, y)): on the full paper_mixed design the holed
    square and the ring are perceived with their hole area and their yaw."""
    env = gym.make(
        envs.ENV_ID,
        obs_mode="objects",
        objects_source="perception",
        action_mode="pick_place_discrete",
        execution="kinematic",
        tile_variants=1,
        disable_env_checker=True,
    )
    try:
        env.reset(seed=SEED)
        u = cast(MosaicAssemblyEnv, env.unwrapped)
        priv, per = _rows(env)
        holed = [i for i, t in enumerate(u.cell.tiles) if len(t.holes)]
        assert len(holed) == 2
        per_tiles = u.observer.perceived
        assert per_tiles is not None
        holes = [b for fig in per_tiles.last_figures for b in fig.holes]
        assert len(holes) == 2 and all(b.ndim == 2 and b.shape[1] == 2 for b in holes)  # (x, y)
        for i in holed:
            assert per[i, F["valid"]][0] == 1.0
            hole = per[i, F["hole_area"]][0]
            assert hole == pytest.approx(priv[i, F["hole_area"]][0], rel=0.15) and hole > 0.5
            area = per[i, F["area"]][0] / priv[i, F["area"]][0]
            assert abs(area - 1) * 100 < AREA_PCT
            centroid = np.linalg.norm(per[i, F["xy"]] - priv[i, F["xy"]]) * 1e3
            assert centroid < CENTROID_MM
            sym = u.cell.tiles[i].shape.symmetry
            assert _yaw_error_deg(per[i, F["yaw"]], priv[i, F["yaw"]], sym) < YAW_DEG
    finally:
        env.close()


def test_rows_at_another_picture_size_use_that_size_s_camera_model() -> None:
    """Guards against the picture rendered at the camera's native size instead of
    ``objects_image_size``, and the figures cast through the camera model of another picture
    size: at half the native size the picture is that size and the perceived centroids still lie
    on the tiles'."""
    env = _make(objects_source="perception", objects_image_size=[246, 328])
    try:
        env.reset(seed=SEED)
        priv, per = _rows(env)
        per_tiles = cast(MosaicAssemblyEnv, env.unwrapped).observer.perceived
        assert per_tiles is not None and per_tiles.last_picture is not None
        assert per_tiles.last_picture.shape[:2] == (246, 328)  # rendered at that size
        seen = per[:, F["valid"]].ravel() == 1.0
        assert seen.sum() >= 4
        d = np.linalg.norm(per[seen][:, F["xy"]] - priv[seen][:, F["xy"]], axis=1) * 1e3
        assert d.max() < 2 * CENTROID_MM
    finally:
        env.close()


def test_picture_size_bounds_are_inclusive(perceived: gym.Env) -> None:
    """Guards against the accepted picture sizes' ends excluded (qshape's 16..8192 px per side),
    and the figures cast onto another plane than the tiles' top faces on the input belt."""
    u = cast(MosaicAssemblyEnv, perceived.unwrapped)
    objects = u.observer.objects
    assert objects is not None and u.observer.perceived is not None
    top = u.cell.geometry.belt_top + u.cell.cfg.tiles.thickness
    assert u.observer.perceived.plane_z == pytest.approx(top)
    base = load_env_config()
    for size in ((16, 8192), (8192, 16)):
        cfg = dataclasses.replace(base, objects_image_size=size)
        per = PerceivedTiles(u.cell, cfg, objects.fields, objects.dim)
        assert per.size == size
    for size in ((15, 656), (492, 8193)):
        with pytest.raises(EnvConfigError, match="objects_image_size"):
            PerceivedTiles(
                u.cell,
                dataclasses.replace(base, objects_image_size=size),
                objects.fields,
                objects.dim,
            )


def test_register_residual_is_the_rms_distance_left() -> None:
    """Guards against the residual's power terms miscomputed (the RMS left after the best turn):
    a 10 mm circle registered on a 7 mm one leaves 3 mm at every sample."""
    k = np.arange(64)
    big = 10 * np.exp(2j * np.pi * k / 64)
    small = 7 * np.exp(2j * np.pi * k / 64)
    r, _, rms = register(big, np.stack([small, 3 * small]))
    assert r == 0
    assert rms == pytest.approx(3.0, abs=1e-9)


def _with_gate(env: gym.Env, gate_mm: float) -> PerceivedTiles:
    """The env's perception rows with another ``objects_gate_mm`` (the same cell)."""
    u = cast(MosaicAssemblyEnv, env.unwrapped)
    objects = u.observer.objects
    assert objects is not None
    cfg = dataclasses.replace(load_env_config(), objects_gate_mm=gate_mm)
    return PerceivedTiles(u.cell, cfg, objects.fields, objects.dim)


def test_a_figure_exactly_at_the_gate_fills_the_row(perceived: gym.Env) -> None:
    """Guards against the gate's edge excluded (a pair counts *within* ``objects_gate_mm``, its
    edge included): a figure exactly one gate (7.8125 mm, 2^-7 m: exact in binary) from a tile's
    centroid fills its row."""
    perceived.reset(seed=SEED)
    per = _with_gate(perceived, 7.8125)
    assert per.gate == 2.0**-7
    xy = cast(MosaicAssemblyEnv, perceived.unwrapped).cell.tile_poses().pos[:, :2]
    fig = _figure_at(xy[3] + [2.0**-7, 0.0])
    assert np.linalg.norm(fig.centre - xy[3]) == per.gate  # exactly on the edge
    assert per.associate([fig]) == [(3, 0)]


def test_pairing_keeps_every_pair_it_can_within_the_gate(perceived: gym.Env) -> None:
    """Guards against the cost past the gate dropped or made too small (it must outweigh every
    set of in-gate distances, ``gate x tiles x figures``): with a 60 mm gate, figure 0 lies 49 mm
    from tile 3 and just past the gate of tile 0, figure 1 lies 9 mm from tile 3 and 51 mm from
    tile 5. Pairing 3-0 and 5-1 keeps both figures; the smaller total distance (3-1, and 0-0
    past the gate) keeps one. Far figures (1 m off, more figures than tiles) change nothing."""
    perceived.reset(seed=SEED)
    per = _with_gate(perceived, 60.0)
    xy = cast(MosaicAssemblyEnv, perceived.unwrapped).cell.tile_poses().pos[:, :2]
    figs = [_figure_at(xy[3] + [-0.036, -0.033]), _figure_at(xy[3] + [-0.007, 0.006])]
    d = np.linalg.norm(xy[:, None] - np.array([f.centre for f in figs])[None], axis=2)
    assert d[3, 0] < per.gate < d[0, 0] < d[3, 0] + d[5, 1] - d[3, 1]  # the trap is set
    assert d[5, 1] < per.gate and np.sum(d < per.gate) == 3
    assert sorted(per.associate(figs)) == [(3, 0), (5, 1)]
    far = [_figure_at(xy.mean(axis=0) + [1.0 + 0.01 * k, 0.0]) for k in range(30)]
    assert sorted(per.associate([*figs, *far])) == [(3, 0), (5, 1)]


def test_a_picture_without_figures_masks_every_row(perceived: gym.Env) -> None:
    """Guards against the no-figure case handled only when no tile is fed either (it then fails
    on an empty assignment): with every fed tile moved out of the camera's view, every row is
    masked."""
    perceived.reset(seed=SEED)
    u = cast(MosaicAssemblyEnv, perceived.unwrapped)
    cell = u.cell
    n = len(cell.tiles)
    away = np.array([[0.0, 0.5 + 0.05 * k, 0.0] for k in range(n)])  # beside the tile area
    cell.place_tiles(np.arange(n), away)
    mujoco.mj_forward(cell.model, cell.data)
    assert cell.on_stage.all()
    _, per = _rows(perceived)
    per_tiles = u.observer.perceived
    assert per_tiles is not None and per_tiles.last_figures == ()
    assert not per.any()


class _RefusingCamera:
    """The input camera's model, except that the first outline cast is refused or twisted."""

    def __init__(self, model: Any, mode: str) -> None:
        self.model, self.mode, self.calls = model, mode, 0

    def unproject_to_plane(self, pts: np.ndarray, z: float) -> np.ndarray:
        out = self.model.unproject_to_plane(pts, z)
        self.calls += 1
        if self.calls > 1:
            return out
        if self.mode == "refuse":
            raise CellError("outline off the plane")
        twisted = out.copy()  # two vertices swapped: the outline crosses itself
        k = len(out) // 3
        twisted[[k, k + len(out) // 3]] = twisted[[k + len(out) // 3, k]]
        return twisted


@pytest.mark.parametrize("mode", ["refuse", "twist"])
def test_a_figure_the_plane_refuses_is_dropped_and_the_others_kept(
    perceived: gym.Env, monkeypatch: pytest.MonkeyPatch, mode: str
) -> None:
    """Guards against the figure loop stopping at the first figure it drops (every later figure
    lost) and against a figure whose outline on the plane is not a valid polygon kept (a
    self-crossing outline with a positive area): the first figure's outline refused by the
    camera model, or twisted to cross itself, drops that figure alone."""
    perceived.reset(seed=SEED)
    u = cast(MosaicAssemblyEnv, perceived.unwrapped)
    per = u.observer.perceived
    assert per is not None
    image = u.cell.render("input_camera", *per.size)
    base = per.figures(image)
    assert len(base) >= 4
    real = u.cell.camera_model
    monkeypatch.setattr(u.cell, "camera_model", lambda *a: _RefusingCamera(real(*a), mode))
    kept = per.figures(image)
    assert [f.centre.tolist() for f in kept] == [f.centre.tolist() for f in base[1:]]
