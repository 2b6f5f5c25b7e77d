"""Scoring contract of `MosaicAssembly-v0` (`envs.task`): which tile fills which slot, and the
counts of the evaluation, for tiles laid directly at chosen poses.

Written from the documented contract (`envs.task` module docstring, `Placement`, `Evaluation`,
``configs/env.yaml``): a tile fills the nearest slot when it lies flat on the sheet, its class is
the slot's, its centre is within ``position_tolerance`` (1.5 mm) and its yaw within
``yaw_tolerance_deg`` (2 deg) modulo the tile's symmetry; one tile per slot (the closest); every
other real tile over the mesh is misplaced. Each test names the bug it guards against; each was
run against that bug made by hand and failed.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterator
from types import SimpleNamespace
from typing import Any

import gymnasium as gym
import mujoco
import numpy as np
import pytest

import envs
from envs.actions import transfer_poses
from envs.cell.cell import Cell
from envs.cell.tiles.tile import SlotSpec, TileShape
from envs.env_config import load_env_config
from envs.errors import EnvError
from envs.task import SEED_BOUND, Evaluation, MosaicTask, tiles_per_minute
from spatial.angles import yaw_error
from spatial.rotations import quat_from_yaw, yaw_from_quat

MM = 1e-3
"""Metres per millimetre (offsets below are written in mm)."""


@pytest.fixture(scope="module")
def env() -> Iterator[gym.Env]:
    """The full paper_mixed design: 16 slots, two tiles of one class, symmetries 0, 1, 2, 4, 6."""
    e = gym.make(
        envs.ENV_ID,
        action_mode="pick_place_discrete",
        execution="kinematic",
        obs_mode="state",
        tile_variants=1,  # one noisy outline per tile: a faster build, the same contract
        disable_env_checker=True,
    )
    yield e
    e.close()


@pytest.fixture
def u(env: gym.Env) -> Any:
    env.reset(seed=0)
    return env.unwrapped


def lay(u: Any, tile: int, xy: Any, yaw: float, *, dz: float = 0.0, tilt_deg: float = 0.0) -> None:
    """Put ``tile`` at world ``xy`` [m] and ``yaw`` [rad], ``dz`` [m] above resting on the sheet,
    tilted ``tilt_deg`` about the world x axis."""
    cell = u.cell
    q = cell.ids.tile_qpos_index[tile]
    z = cell.geometry.mesh_top + cell.cfg.tiles.thickness / 2 + dz
    quat = quat_from_yaw(yaw)
    if tilt_deg:
        t = math.radians(tilt_deg)
        tilt = np.array([math.cos(t / 2), math.sin(t / 2), 0.0, 0.0])
        out = np.zeros(4)
        mujoco.mju_mulQuat(out, tilt, quat)
        quat = out
    cell.data.qpos[q[:3]] = [xy[0], xy[1], z]
    cell.data.qpos[q[3:]] = quat
    cell.on_stage[tile] = True
    mujoco.mj_forward(cell.model, cell.data)


def slot_of(u: Any, tile: int, nth: int = 0) -> int:
    """The ``nth`` slot of ``tile``'s class."""
    task = u.task
    return int(np.flatnonzero(task.slot_class == task.tile_class[tile])[nth])


def on_slot(
    u: Any,
    tile: int,
    slot: int,
    *,
    dx_mm: float = 0.0,
    dy_mm: float = 0.0,
    dyaw_deg: float = 0.0,
    **kw: Any,
) -> None:
    x, y, yaw = u.task.slot_xyyaw[slot]
    lay(u, tile, (x + dx_mm * MM, y + dy_mm * MM), yaw + math.radians(dyaw_deg), **kw)


def tile_with_symmetry(u: Any, order: int) -> int:
    return int(np.flatnonzero(u.task.symmetry == order)[0])


def test_a_tile_laid_on_its_slot_fills_it_and_nothing_else(u: Any) -> None:
    """Guards against a slot filled by the wrong tile, or a fill not counted as `correct`."""
    tile = 3
    slot = slot_of(u, tile)
    on_slot(u, tile, slot)
    p = u.task.placement()
    assert p.on_mesh[tile] and p.flat[tile] and p.slot[tile] == slot
    assert np.flatnonzero(p.correct).tolist() == [tile]
    assert np.flatnonzero(p.slot_filled).tolist() == [slot]
    e = u.evaluate()
    assert (e.correct, e.misplaced, e.success) == (1, 0, False)
    assert e.slot_filled[slot] and sum(e.slot_filled) == 1
    assert e.position_error_mm == pytest.approx(0.0, abs=1e-6)
    assert e.yaw_error_deg == pytest.approx(0.0, abs=1e-6)


@pytest.mark.parametrize(
    ("dx", "dy", "ok"),
    [
        (1.49, 0.0, True),
        (1.51, 0.0, False),
        (-1.49, 0.0, True),
        (-1.51, 0.0, False),
        (0.0, 1.49, True),
        (0.0, -1.51, False),
        (1.05, 1.05, True),  # 1.485 mm away on the diagonal
        (1.07, 1.07, False),  # 1.513 mm: the distance, not each axis, is compared
    ],
)
def test_position_tolerance_at_its_edges(u: Any, dx: float, dy: float, ok: bool) -> None:
    """Guards against a tolerance compared per axis, in the wrong unit or with the wrong sign
    (1.5 mm: 1.49 mm fills the slot, 1.51 mm is misplaced)."""
    tile = 4  # no symmetry
    slot = slot_of(u, tile)
    on_slot(u, tile, slot, dx_mm=dx, dy_mm=dy)
    e = u.evaluate()
    assert e.slot_filled[slot] is ok
    assert (e.correct, e.misplaced) == ((1, 0) if ok else (0, 1))
    assert e.position_error_mm == pytest.approx(math.hypot(dx, dy), abs=1e-6)
    assert e.position_error_mm_max == pytest.approx(math.hypot(dx, dy), abs=1e-6)


@pytest.mark.parametrize(("dyaw", "ok"), [(1.9, True), (2.1, False), (-1.9, True), (-2.1, False)])
def test_yaw_tolerance_at_its_edges(u: Any, dyaw: float, ok: bool) -> None:
    """Guards against a yaw tolerance in the wrong unit or a yaw error with a sign
    (2 deg: 1.9 deg fills the slot, 2.1 deg is misplaced, both ways round)."""
    tile = 4  # no symmetry
    slot = slot_of(u, tile)
    on_slot(u, tile, slot, dyaw_deg=dyaw)
    e = u.evaluate()
    assert e.slot_filled[slot] is ok
    assert e.yaw_error_deg == pytest.approx(abs(dyaw), abs=1e-6)
    assert e.yaw_error_deg_max == pytest.approx(abs(dyaw), abs=1e-6)


@pytest.mark.parametrize(
    ("order", "turn", "ok"),
    [
        (4, 90 + 1.9, True),
        (4, 90 + 2.1, False),
        (4, 180 - 1.9, True),
        (4, 45, False),
        (2, 180 + 1.9, True),
        (2, 180 - 2.1, False),
        (2, 90, False),
        (6, 60 - 1.9, True),
        (6, 120 + 2.1, False),
        (1, 180, False),
        (1, 360 - 1.9, True),
        (0, 137, True),  # a disc fits at any yaw
    ],
)
def test_yaw_is_compared_modulo_the_tiles_symmetry(
    u: Any, order: int, turn: float, ok: bool
) -> None:
    """Guards against the symmetry period ignored or taken as 2 pi / (order + 1) or 2 pi * order:
    a symmetric tile turned by its period fills the slot, within the same 2 deg edges."""
    tile = tile_with_symmetry(u, order)
    slot = slot_of(u, tile)
    on_slot(u, tile, slot, dyaw_deg=turn)
    assert u.evaluate().slot_filled[slot] is ok


@pytest.mark.parametrize("nth", [0, 1])
def test_two_tiles_in_one_slot_fill_it_once_the_closer_one_counts(
    env: gym.Env, u: Any, nth: int
) -> None:
    """Guards against ranking the candidates by error before slot (a one-line change of the
    sort keys): with a tile of another slot ranked between them, both tiles of one slot
    counted as correct and none as misplaced; and against each candidate's slot compared with
    the first candidate's instead of the one before it (the shared slot, 0 or 12, ranked
    before or after the other tile's slot 4)."""
    same = np.flatnonzero(u.task.tile_class == u.task.tile_class[0])
    assert len(same) == 2  # two tiles of one class, two slots of it
    a, b = (int(i) for i in same)
    slot = slot_of(u, a, nth)
    other = 4
    for first, second in ((a, b), (b, a)):  # index order must not matter
        env.reset(seed=0)
        on_slot(u, first, slot, dx_mm=0.1)
        on_slot(u, second, slot, dx_mm=-0.9)
        on_slot(u, other, slot_of(u, other), dy_mm=0.5)
        p = u.task.placement()
        assert p.slot[first] == p.slot[second] == slot
        assert p.correct[first] and not p.correct[second] and p.correct[other]
        e = u.evaluate()
        assert (e.correct, e.misplaced) == (2, 1)
        assert sum(e.slot_filled) == 2
        states = u.task.tile_states()
        assert int(np.count_nonzero(states == 2)) == 2  # CORRECT: one per slot


def test_a_tile_of_another_class_on_a_slot_is_misplaced(u: Any) -> None:
    """Guards against a class test dropped or inverted."""
    tile = 4
    wrong = int(np.flatnonzero(u.task.slot_class != u.task.tile_class[tile])[0])
    on_slot(u, tile, wrong)
    e = u.evaluate()
    assert (e.correct, e.misplaced) == (0, 1)
    assert not any(e.slot_filled)


@pytest.mark.parametrize(
    ("dz_mm", "tilt", "flat"),
    [(2.9, 0.0, True), (3.1, 0.0, False), (0.0, 7.5, True), (0.0, 8.5, False), (-2.9, 0.0, True)],
)
def test_height_and_tilt_decide_flat(u: Any, dz_mm: float, tilt: float, flat: bool) -> None:
    """Guards against the height tolerance (3 mm) or the tilt limit (8 deg) moved, dropped or
    compared the wrong way: a tile stacked or tilted over its slot is misplaced."""
    tile = 4
    slot = slot_of(u, tile)
    on_slot(u, tile, slot, dz=dz_mm * MM, tilt_deg=tilt)
    p = u.task.placement()
    assert p.on_mesh[tile] and p.flat[tile] is np.bool_(flat)
    e = u.evaluate()
    assert (e.correct, e.misplaced) == ((1, 0) if flat else (0, 1))


def test_a_tile_stacked_on_another_is_misplaced(u: Any) -> None:
    """Guards against stacked tiles (a tile's thickness above the sheet) counted as filling."""
    a, b = 4, 3
    on_slot(u, a, slot_of(u, a))
    on_slot(u, b, slot_of(u, a), dz=u.cell.cfg.tiles.thickness)
    e = u.evaluate()
    assert (e.correct, e.misplaced) == (1, 1)


def test_mesh_edges_decide_on_mesh_and_beside_it_is_stranded(env: gym.Env, u: Any) -> None:
    """Guards against the mesh bounds moved or swapped: just inside every edge a tile is on the
    mesh (misplaced); just outside, on the output belt, it is stranded."""
    cell = u.cell
    c = cell.geometry.output_centre[:2]
    half = np.asarray(cell.geometry.mesh_size) / 2
    tile = 4
    for sign in (-1, 1):
        for axis in (0, 1):
            for inside, state in ((0.999, "misplaced"), (1.001, "stranded")):
                xy = c.copy()
                xy[axis] += sign * half[axis] * inside
                env.reset(seed=0)
                lay(u, tile, xy, 0.3)
                e = u.evaluate().as_dict()
                assert e[state] == 1, (sign, axis, inside, e)
                assert u.task.placement().on_mesh[tile] is np.bool_(state == "misplaced")


def test_fresh_episode_counts_every_tile_on_the_input_belt(u: Any) -> None:
    """Guards against the evaluation's counts not summing to the tiles fed."""
    e = u.evaluate()
    n = len(u.cell.tiles)
    assert (e.fed, e.on_input, e.waiting, e.held) == (n, n, 0, 0)
    assert (e.correct, e.misplaced, e.stranded, e.dropped, e.lost) == (0, 0, 0, 0, 0)
    assert (e.slots, e.placeable, e.success, e.failure) == (16, 16, False, False)
    assert e.position_error_mm is None and e.yaw_error_deg_max is None


def test_every_slot_filled_is_a_success_and_errors_are_means_and_maxima(u: Any) -> None:
    """Guards against success declared early or the error summaries mixing units."""
    task = u.task
    used: set[int] = set()
    offsets = []
    for tile in range(len(u.cell.tiles)):
        slot = next(
            int(j)
            for j in np.flatnonzero(task.slot_class == task.tile_class[tile])
            if int(j) not in used
        )
        used.add(slot)
        d = 0.1 * (tile % 5)
        offsets.append(d)
        on_slot(u, tile, slot, dx_mm=d, dyaw_deg=0.2)
        e = u.evaluate()
        assert e.success is (tile == len(u.cell.tiles) - 1)
        assert e.correct == tile + 1 and e.placeable == 16 - tile - 1
    assert e.failure is False
    assert e.position_error_mm == pytest.approx(np.mean(offsets), abs=1e-6)
    assert e.position_error_mm_max == pytest.approx(max(offsets), abs=1e-6)
    turned = np.count_nonzero(u.task.symmetry != 0)  # a disc has no yaw error
    assert e.yaw_error_deg == pytest.approx(0.2 * turned / 16, abs=1e-6)
    assert e.yaw_error_deg_max == pytest.approx(0.2, abs=1e-6)
    assert e.tiles_per_min(60.0) == pytest.approx(16.0)


def test_nothing_placeable_is_a_failure(u: Any) -> None:
    """Guards against `failure` missing when the only tile of a class is misplaced."""
    tile = 4
    wrong = int(np.flatnonzero(u.task.slot_class != u.task.tile_class[tile])[0])
    on_slot(u, tile, wrong)
    e = u.evaluate()
    assert e.placeable == 15 and not e.failure  # other tiles still fill the other slots
    for t in range(len(u.cell.tiles)):
        lay(u, t, u.cell.geometry.output_centre[:2] + [0.0, 0.13], 0.0)  # beside the mesh
    e = u.evaluate()
    assert e.stranded == 16 and e.placeable == 0 and e.failure and not e.success


def test_evaluation_round_trips_through_info(u: Any) -> None:
    """Guards against `as_dict` / `from_info` losing or renaming a field."""
    on_slot(u, 4, slot_of(u, 4), dx_mm=0.7)
    e = u.evaluate()
    assert Evaluation.from_info({"evaluation": e.as_dict()}) == e
    assert isinstance(e.as_dict()["slot_filled"], list)


@pytest.mark.parametrize("drop", ["slot_filled", "correct", None])
def test_an_info_without_a_complete_evaluation_is_refused_by_name(u: Any, drop: str | None) -> None:
    """Guards against `from_info` accepting an evaluation with a field missing (a record read
    from another step's info, or the mapping test turned into `and`: it then fails later with a
    bare KeyError), and its one-line message losing what it names."""
    d = u.evaluate().as_dict()
    info: dict[str, Any] = {"sim_time": 1.0}
    if drop is not None:
        info["evaluation"] = {k: v for k, v in d.items() if k != drop}
    message = "info has no complete 'evaluation' (a MosaicAssembly step's info)"
    with pytest.raises(EnvError) as caught:
        Evaluation.from_info(info)
    assert str(caught.value) == message


def test_ground_truth_holds_the_poses_and_finds_the_nearest_fed_tile(u: Any) -> None:
    """Guards against the privileged poses or classes read wrong, or `nearest` returning a
    tile not fed (parked tiles are never the nearest) or a distance in another unit."""
    gt = u.ground_truth()
    cell = u.cell
    poses = cell.tile_poses()
    np.testing.assert_allclose(gt.xy, poses.pos[:, :2])
    np.testing.assert_allclose(gt.yaw, poses.yaw)
    assert gt.class_name == tuple(t.shape.name for t in cell.tiles)
    assert gt.slot_class == tuple(s.shape.name for s in cell.slots)
    np.testing.assert_array_equal(gt.symmetry, u.task.symmetry)
    assert not gt.distractor.any() and gt.on_stage.all()
    target = gt.xy[5] + [0.003, -0.004]
    assert gt.nearest(target) == (5, pytest.approx(0.005))
    on = gt.on_stage.copy()
    on[5] = False
    parked = dataclasses.replace(gt, on_stage=on)
    i, d = parked.nearest(target)
    assert i != 5 and d > 0.005


def test_a_tile_exactly_on_a_mesh_edge_is_on_the_mesh(env: gym.Env, u: Any) -> None:
    """Guards against the mesh's edges excluded (a tile counts as placed over the mesh, its
    edges included): a tile whose centre lies exactly on any of the sheet's four edges is on the
    mesh (misplaced, not stranded)."""
    cell = u.cell
    lo, hi = cell.geometry.mesh_lo, cell.geometry.mesh_hi
    centre = (lo + hi) / 2
    tile = 4
    for axis in (0, 1):
        for edge in (lo[axis], hi[axis]):
            xy = centre.copy()
            xy[axis] = edge
            env.reset(seed=0)
            lay(u, tile, xy, 0.3)
            assert cell.data.qpos[cell.ids.tile_qpos_index[tile][axis]] == edge  # exactly
            assert u.task.placement().on_mesh[tile], (axis, edge)
            assert u.evaluate().misplaced == 1


@pytest.mark.parametrize("sign", [1, -1])
def test_height_tolerance_includes_its_edges(u: Any, sign: int) -> None:
    """Guards against the height tolerance's edges excluded (a tile lies flat *within*
    ``mesh_height_tolerance`` of resting on the sheet, and a tile that far below rest is still
    over it): with a tolerance of 2^-9 m (exact in binary), a tile exactly that far above or
    below rest on its slot fills it."""
    tol = 2.0**-9
    task = MosaicTask(u.cell, dataclasses.replace(u.config, mesh_height_tolerance=tol))
    tile = 4
    slot = slot_of(u, tile)
    on_slot(u, tile, slot, dz=sign * tol)
    cell = u.cell
    rest = cell.geometry.mesh_top + cell.cfg.tiles.thickness / 2
    assert cell.data.qpos[cell.ids.tile_qpos_index[tile][2]] - rest == sign * tol  # exactly
    p = task.placement()
    assert p.on_mesh[tile] and p.flat[tile] and p.slot_filled[slot]


def _tilted(u: Any, tile: int, slot: int, quat: np.ndarray) -> None:
    """Lay ``tile`` on ``slot`` at rest with the orientation ``quat`` (w, x, y, z)."""
    on_slot(u, tile, slot)
    cell = u.cell
    cell.data.qpos[cell.ids.tile_qpos_index[tile][3:]] = quat
    mujoco.mj_forward(cell.model, cell.data)


def test_a_tile_tilted_exactly_the_limit_is_not_flat(u: Any) -> None:
    """Guards against the tilt limit included (a tile is flat when tilted *less* than
    ``max_tilt_deg``): a tile tilted exactly 8 deg over its slot does not fill it."""
    tile = 4
    slot = slot_of(u, tile)
    limit = math.cos(math.radians(u.config.max_tilt_deg))
    qx = math.sqrt((1 - limit) / 2)
    assert 1 - 2 * (qx * qx + 0.0) == limit  # exactly the limit
    _tilted(u, tile, slot, np.array([math.sqrt(1 - qx * qx), qx, 0.0, 0.0]))
    p = u.task.placement()
    assert p.on_mesh[tile] and not p.flat[tile] and not p.slot_filled[slot]


@pytest.mark.parametrize(("deg", "flat"), [(7.5, True), (8.5, False)])
def test_a_tilt_about_the_y_axis_counts_like_one_about_x(u: Any, deg: float, flat: bool) -> None:
    """Guards against the tile's tilt read from its x rotation only (a sign slip in the z
    component of its z axis): tilted about the world y axis, 7.5 deg is flat, 8.5 deg is not."""
    tile = 4
    slot = slot_of(u, tile)
    t = math.radians(deg)
    _tilted(u, tile, slot, np.array([math.cos(t / 2), 0.0, math.sin(t / 2), 0.0]))
    p = u.task.placement()
    assert p.on_mesh[tile] and p.flat[tile] is np.bool_(flat)


def test_a_held_tile_over_its_slot_is_not_placed(u: Any) -> None:
    """Guards against the held tile counted over the mesh, or not counted as available for
    its class's open slots (tile 0 included: a test of the held index against 0 or 1 that
    skips it): tile 0 held by the pad right on its slot neither fills it nor counts as placed;
    it is held, and all 16 slots stay placeable."""
    tile = 0
    slot = slot_of(u, tile)
    cell = u.cell
    cmd = transfer_poses(cell, tile, slot)
    cell.set_qpos(u.ik.solve(np.array([*cmd.pick_xy, u.pick_area.tile_top_z]), cmd.pick_yaw).q)
    cell.vacuum(True)
    assert cell.held_tile == tile
    on_slot(u, tile, slot)
    assert cell.held_tile == tile
    p = u.task.placement()
    assert not p.on_mesh[tile] and not p.correct[tile] and not p.slot_filled[slot]
    e = u.evaluate()
    assert (e.held, e.correct, e.misplaced) == (1, 0, 0)
    assert e.placeable == 16  # the held tile is still available for its class's slots


def test_tiles_off_the_mesh_have_no_slot_and_no_errors(u: Any) -> None:
    """Guards against the placement's fill values for tiles off the mesh changed (slot -1, an
    int; position and yaw errors NaN): at a fresh episode every tile is on the input belt."""
    p = u.task.placement()
    assert not p.on_mesh.any()
    assert p.flat.dtype == bool and not p.flat.any()
    assert p.correct.dtype == bool and not p.correct.any()
    assert p.slot_filled.dtype == bool and not p.slot_filled.any()
    assert p.slot.dtype.kind == "i" and p.slot.tolist() == [-1] * len(p.slot)
    assert p.position_error.dtype == np.float64 and np.isnan(p.position_error).all()
    assert p.yaw_error.dtype == np.float64 and np.isnan(p.yaw_error).all()


def test_position_tolerance_includes_its_edge(u: Any) -> None:
    """Guards against the position tolerance's edge excluded (a tile fills its slot *within*
    ``position_tolerance``): with a tolerance of 2^-9 m (exact in binary), a tile exactly that
    far from its slot fills it."""
    tol = 2.0**-9
    task = MosaicTask(u.cell, dataclasses.replace(u.config, position_tolerance=tol))
    tile = 4
    slot = slot_of(u, tile)
    x, y, yaw = task.slot_xyyaw[slot]
    lay(u, tile, (x + tol, y), yaw)
    p = task.placement()
    assert p.position_error[tile] == tol  # exactly on the edge
    assert p.correct[tile] and p.slot_filled[slot]


def test_yaw_tolerance_includes_its_edge(u: Any) -> None:
    """Guards against the yaw tolerance's edge excluded (a tile fills its slot *within*
    ``yaw_tolerance_deg``): a tile turned about 2 deg, with the tolerance set to exactly its
    yaw error (the nearest float to it in degrees), fills its slot."""
    tile = 4  # no symmetry
    slot = slot_of(u, tile)
    on_slot(u, tile, slot, dyaw_deg=2.0)
    cell = u.cell
    quat = cell.data.qpos[cell.ids.tile_qpos_index[tile][3:]]
    err = float(yaw_error(yaw_from_quat(quat), u.task.slot_xyyaw[slot, 2], 1))
    deg = 2.0
    for _ in range(100):  # the degrees whose radians are exactly that error
        if math.radians(deg) == err:
            break
        deg = float(np.nextafter(deg, 3.0 if math.radians(deg) < err else 1.0))
    assert math.radians(deg) == err
    task = MosaicTask(cell, dataclasses.replace(u.config, yaw_tolerance_deg=deg))
    p = task.placement()
    assert p.yaw_error[tile] == err  # exactly on the edge
    assert p.correct[tile] and p.slot_filled[slot]


def test_a_one_slot_design_filled_is_a_success() -> None:
    """Guards against success requiring more than one slot (the one-tile task has one): its
    tile laid on its slot is a success."""
    env = gym.make("MosaicOneTile-v0", disable_env_checker=True)
    try:
        env.reset(seed=1)
        one = env.unwrapped
        assert len(one.task.slot_class) == 1
        assert not one.evaluate().success
        on_slot(one, 0, 0)
        e = one.evaluate()
        assert e.slots == 1 and e.correct == 1 and e.success and not e.failure
    finally:
        env.close()


def test_tiles_not_yet_fed_are_counted_as_waiting() -> None:
    """Guards against the ``waiting`` count lost (tiles of a ``stream`` feed not yet on the
    belt): at a stream episode's start the tiles not fed are waiting, the others fed."""
    env = gym.make("MosaicDecision6-v0", feed="stream", disable_env_checker=True)
    try:
        env.reset(seed=1000)
        cell = env.unwrapped.cell
        fed = int(np.count_nonzero(cell.on_stage))
        assert 0 < fed < len(cell.tiles)
        e = env.unwrapped.evaluate()
        assert (e.fed, e.waiting) == (fed, len(cell.tiles) - fed)
    finally:
        env.close()


def test_throughput_is_correct_tiles_per_minute_over_the_episode_s_span(u: Any) -> None:
    """Guards against the throughput's span or its edge cases changed: a success is measured over
    its own time, a failure over the longer of its time and the horizon (no horizon: its own
    time, however short), no time gives 0 (not a division by zero), and 60 s make a minute."""
    on_slot(u, 4, slot_of(u, 4))
    on_slot(u, 3, slot_of(u, 3))
    e = u.evaluate()
    assert e.correct == 2 and not e.success
    assert e.throughput_span(0.5) == 0.5 and e.tiles_per_min(0.5) == pytest.approx(240.0)
    assert e.throughput_span(20.0, 30.0) == 30.0 and e.tiles_per_min(20.0, 30.0) == 4.0
    assert e.throughput_span(40.0, 30.0) == 40.0
    assert e.tiles_per_min(0.0) == 0.0
    won = dataclasses.replace(e, success=True)
    assert won.throughput_span(20.0, 30.0) == 20.0 and won.tiles_per_min(20.0, 30.0) == 6.0
    assert tiles_per_minute(3, 0.5) == 360.0 and tiles_per_minute(3, 0.0) == 0.0


def test_episode_setup_randomises_lights_and_cameras_and_settles_as_configured() -> None:
    """Guards against the episode set-up's per-task state lost (the lights' base brightness,
    the camera jitter, the settling step count): a task built with light randomisation, camera
    jitter and 0.05 s of settling changes the lights within [0, 1], moves a camera and runs the
    physics 0.05 s at an episode start; and against an episode not drawn from the generator
    given (the same seed, the same layout and lights)."""
    env = gym.make("MosaicDecision6-v0", disable_env_checker=True)
    try:
        env.reset(seed=0)
        one = env.unwrapped
        cell = one.cell
        cfg = dataclasses.replace(
            one.config,
            light_randomization=0.2,
            camera_position_jitter=0.01,
            reset_settle=0.05,
        )
        task = MosaicTask(cell, cfg)
        base = cell.model.light_diffuse.copy()
        cams = cell.data.cam_xpos.copy()
        task.initialize_episode(np.random.default_rng(3))
        light = cell.model.light_diffuse.copy()
        assert not np.allclose(light, base) and light.min() >= 0.0 and light.max() <= 1.0
        mujoco.mj_forward(cell.model, cell.data)
        assert not np.allclose(cell.data.cam_xpos, cams)
        assert cell.data.time == pytest.approx(0.05, abs=cell.model.opt.timestep)
        poses = cell.tile_poses().pos.copy()
        task.initialize_episode(np.random.default_rng(3))  # the same seed: the same episode
        np.testing.assert_array_equal(cell.tile_poses().pos, poses)
        np.testing.assert_array_equal(cell.model.light_diffuse, light)
    finally:
        env.close()


def test_colour_randomisation_multiplies_each_tile_colour_by_one_plus_a_normal_draw() -> None:
    """Guards against the colour change off its documented form (each visible tile geom's RGB
    times ``1 + normal(0, color_randomization)``, clipped to [0, 1], drawn after the layout's
    seed from the episode's generator): the colours of an episode with 0.1 are those of the
    same episode without, times the factors drawn from the same seed; and nothing is drawn for
    the colours when they are off (the lights' draws come first then)."""
    env = gym.make("MosaicDecision6-v0", disable_env_checker=True)
    try:
        env.reset(seed=0)
        one = env.unwrapped
        cell = one.cell
        MosaicTask(cell, one.config).initialize_episode(np.random.default_rng(3))
        visual = cell.ids.tile_visual.ravel()
        nominal = cell.model.geom_rgba[visual, :3].copy()
        cfg = dataclasses.replace(one.config, color_randomization=0.1)
        MosaicTask(cell, cfg).initialize_episode(np.random.default_rng(3))
        np.testing.assert_array_equal(cell.ids.tile_visual.ravel(), visual)  # the same episode
        rng = np.random.default_rng(3)
        rng.integers(SEED_BOUND)  # the layout's seed comes first
        f = 1 + rng.normal(0.0, 0.1, (len(visual), 3))
        expected = np.clip(nominal * f, 0.0, 1.0)
        np.testing.assert_allclose(cell.model.geom_rgba[visual, :3], expected, atol=1e-6)
        assert not np.allclose(expected, nominal)
        # colours off, lights on: the lights' factors are the first draws after the layout's
        base = cell.model.light_diffuse.copy()
        lights = MosaicTask(cell, dataclasses.replace(one.config, light_randomization=0.2))
        lights.initialize_episode(np.random.default_rng(3))
        rng = np.random.default_rng(3)
        rng.integers(SEED_BOUND)
        g = 1 + rng.normal(0.0, 0.2, (cell.model.nlight, 1))
        np.testing.assert_allclose(cell.model.light_diffuse, np.clip(base * g, 0.0, 1.0), atol=1e-6)
    finally:
        env.close()


def test_a_tile_moved_after_an_evaluation_is_scored_where_it_lies_now(u: Any) -> None:
    """Guards against a stale remembered placement: `MosaicTask` keeps each tile's lie while its
    pose is unchanged, so every move (onto its slot, a little off it, turned, back to the belt,
    or only its height or tilt) must be scored afresh, as a task built now scores it."""
    tile = 3
    slot = slot_of(u, tile)
    home = u.cell.data.qpos[u.cell.ids.tile_qpos_index[tile]].copy()
    rng = np.random.default_rng(5)
    moves = [
        {},
        {"dx_mm": 1.2},
        {"dx_mm": 1.6},
        {"dyaw_deg": 2.5},
        {"dz": 4 * MM},
        {"tilt_deg": 5.0},
        {},
    ]
    seen = set()
    for kw in moves + [{"dx_mm": float(rng.normal(0, 1.5))} for _ in range(6)]:
        u.task.evaluate()  # remembers the tile's lie at its last pose
        on_slot(u, tile, slot, **kw)
        now = u.task.evaluate()
        assert now == MosaicTask(u.cell, u.config).evaluate(), kw
        seen.add(now.correct)
    u.cell.data.qpos[u.cell.ids.tile_qpos_index[tile]] = home
    assert u.task.evaluate() == MosaicTask(u.cell, u.config).evaluate()
    assert u.task.evaluate().correct == 0
    assert seen == {0, 1}


def test_a_tile_exactly_between_two_slots_takes_the_first_of_them(u: Any) -> None:
    """Guards against a tie between two slots settled by the last one seen: a tile whose
    centroid is at exactly the same distance from two slots takes the first of them (design
    order), with that distance as its error."""
    xy = u.task.slot_xyyaw[:, :2]
    pairs = [
        (a, b)
        for a in range(len(xy))
        for b in range(a + 1, len(xy))
        if xy[a, 1] == xy[b, 1] and xy[a, 0] != xy[b, 0]
    ]
    found = None
    for a, b in pairs:  # the first pair with a point at exactly equal distances, no slot nearer
        xa, xb, y = float(xy[a, 0]), float(xy[b, 0]), float(xy[a, 1])
        lo = hi = (xa + xb) / 2
        for _ in range(200):
            for x in (lo, hi):
                others = np.hypot(xy[:, 0] - x, xy[:, 1] - y)
                others[[a, b]] = np.inf
                if found is None and abs(x - xa) == abs(xb - x) < others.min():
                    found = (a, b, x, y, abs(x - xa))
            lo, hi = math.nextafter(lo, -math.inf), math.nextafter(hi, math.inf)
        if found:
            break
    assert found is not None, "the design has two slots in a row"
    a, b, x, y, dist = found
    lay(u, 3, (x, y), 0.0)
    p = u.task.placement()
    assert p.on_mesh[3] and p.slot[3] == min(a, b)
    assert p.position_error[3] == dist


def test_tiles_before_an_unfed_or_held_one_do_not_hide_the_ones_after_it(u: Any) -> None:
    """Guards against the placement stopping at the first tile it leaves out (not fed, or on
    the pad): with tile 0 taken off the stage, the tiles after it laid on their slots are
    still scored."""
    u.cell.on_stage[0] = False
    for tile in (3, 5):
        on_slot(u, tile, slot_of(u, tile))
    p = u.task.placement()
    assert not p.on_mesh[0]
    assert np.flatnonzero(p.correct).tolist() == [3, 5]
    assert u.evaluate().correct == 2


def test_placeable_counts_open_slots_not_spare_tiles() -> None:
    """Guards against `placeable` counting tiles instead of the open slots they can fill: a
    cell fed three tiles of one class for its two slots has two placeable slots; with one slot
    filled, one; with both, none (the spare tile on the belt fills nothing) and success."""
    cfg = load_env_config(vertex_jitter=0.0, tile_color_jitter=0.0, tile_variants=1)
    sq = TileShape(np.array([[0.0, 0.0], [0.03, 0.0], [0.03, 0.03], [0.0, 0.03]]), name="sq")
    slots = (SlotSpec(sq, (-0.05, 0.0, 0.0)), SlotSpec(sq, (0.05, 0.0, 0.0)))
    cell = Cell(cfg.cell, (sq, sq, sq), slots, seed=3)
    try:
        task = MosaicTask(cell, cfg)
        one = SimpleNamespace(cell=cell, task=task)
        assert task.evaluate().placeable == 2
        on_slot(one, 0, 0)
        assert (task.evaluate().placeable, task.evaluate().correct) == (1, 1)
        on_slot(one, 1, 1)
        e = task.evaluate()
        assert (e.placeable, e.correct, e.on_input, e.success, e.failure) == (0, 2, 1, True, False)
    finally:
        cell.close()
