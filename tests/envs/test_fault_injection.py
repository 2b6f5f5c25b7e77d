"""Faults injected into the cell: every real tile fed stays accounted for; the episode ends.

Weak vacuum (tiles dropped in transit), a tile stranded beside the mesh, a tile moved after
placing, a tile released over the reject bin, a tile carried into the bin by the belt,
distractors, and black or noisy pictures given to the scripted agent. The reward terms of a drop
and of a lost tile are pinned to their sign and size.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import mujoco
import numpy as np
import pytest

import envs  # noqa: F401 - registers the env
from envs.cell.accounting import TILE_STATES

ENV_ID = "envs:MosaicAssembly-v0"


def _make(**kw: Any) -> Any:
    base: dict[str, Any] = {
        "action_mode": "pick_place",
        "obs_mode": "state",
        "execution": "kinematic",
        "max_slots": 3,
    }
    return gym.make(ENV_ID, **{**base, **kw})


def _accounted(ev: dict[str, Any]) -> None:
    assert sum(ev[s] for s in TILE_STATES) == ev["fed"], ev


def _move_tile(env: Any, tile: int, xyz: np.ndarray) -> None:
    """Teleport a tile (at rest, flat) to a world point [m]."""
    cell = env.unwrapped.cell
    q = cell.ids.tile_qpos_index[tile]
    cell.data.qpos[q[:3]] = xyz
    cell.data.qpos[q[3:]] = [1.0, 0.0, 0.0, 0.0]
    cell.data.qvel[cell.ids.tile_dof_index[tile]] = 0.0
    mujoco.mj_forward(cell.model, cell.data)


def _slot_of(env: Any, tile: int) -> int:
    task = env.unwrapped.task
    return int(np.flatnonzero(task.slot_class == task.tile_class[tile])[0])


def test_a_tile_stranded_beside_the_mesh_is_counted_and_ends_the_episode():
    env = _make(max_slots=1)
    _, info = env.reset(seed=0)
    cell = env.unwrapped.cell
    assert info["evaluation"]["placeable"] == 1
    geo = cell.geometry
    half = geo.mesh_size / 2
    beside = geo.output_centre[:2] + [half[0] + 0.03, 0.0]  # on the output belt, off the mesh
    real = int(np.flatnonzero(~cell.is_distractor)[0])
    rest_z = geo.mesh_top + cell.cfg.tiles.thickness / 2  # a tile's centre lying on the mesh
    _move_tile(env, real, [*beside, rest_z])
    ev = env.unwrapped.task.evaluate()
    assert ev.stranded == 1
    assert ev.on_input == 0
    assert ev.placeable == 0
    assert ev.failure
    # The env ends the episode at the next step instead of running to the step limit.
    _, _, terminated, truncated, info = env.step(np.array([-1, -1, 0, 1, 1, 0], np.float32))
    assert terminated and not truncated
    _accounted(info["evaluation"])


def test_a_tile_moved_after_placing_is_misplaced_not_correct():
    env = _make()
    _, info = env.reset(seed=1)
    u = env.unwrapped
    tile = int(np.flatnonzero(~u.cell.is_distractor)[0])
    _, _, _, _, info = env.step(u.expert_action(tile, _slot_of(env, tile)))
    ev = info["evaluation"]
    assert ev["correct"] == 1
    _accounted(ev)
    pos = u.cell.tile_poses().pos[tile]
    _move_tile(env, tile, pos + [0.006, 0.0, 0.0])  # knocked 6 mm: beyond the 1.5 mm tolerance
    ev2 = u.task.evaluate()
    assert (ev2.correct, ev2.misplaced) == (0, 1)
    assert ev2.fed == ev["fed"]
    assert sum(getattr(ev2, s) for s in TILE_STATES) == ev2.fed


def test_a_tile_released_over_the_reject_bin_is_rejected_not_lost():
    env = _make(action_mode="cartesian", execution="dynamic")
    env.reset(seed=0)
    u = env.unwrapped
    cell = u.cell
    tile = int(np.flatnonzero(~cell.is_distractor)[0])
    # The pad holds the tile over the bin (put there directly), then lets go.
    bin_point = np.array([cell.geometry.input_belt_end + 0.1, cell.geometry.input_y, 0.0])
    _move_tile(env, tile, bin_point + [0, 0, cell.geometry.belt_top + 0.05])
    cell.suction.held = tile
    cell.suction.vacuum_on = True
    event = cell.vacuum(False)
    assert event is not None and event.kind == "release"
    cell.step(200)
    ev = u.task.evaluate()
    assert ev.rejected == 1
    assert ev.lost_tiles == 0 and ev.lost == 0
    assert sum(getattr(ev, s) for s in TILE_STATES) == ev.fed


def test_a_lost_tile_costs_the_lost_penalty_once():
    # Mutation pin: the sign and size of the `lost` reward term.
    env = _make(max_slots=2)
    _, info = env.reset(seed=2)
    u = env.unwrapped
    cell = u.cell
    tile = int(np.flatnonzero(~cell.is_distractor)[0])
    end = np.array([cell.geometry.input_belt_end + 0.1, cell.geometry.input_y, 0.0])
    _move_tile(env, tile, end + [0, 0, cell.geometry.belt_top])
    idle = np.array([-1, -1, 0, 1, 1, 0], np.float32)  # picks in a corner: nothing there
    _, _, _, _, info = env.step(idle)
    ev = info["evaluation"]
    assert ev["lost"] == 1 and ev["lost_tiles"] == 1
    assert info["reward_lost"] == pytest.approx(-u.config.penalty_lost)
    _accounted(ev)
    _, _, _, _, info = env.step(idle)
    assert info["reward_lost"] == 0.0


def test_weak_vacuum_drops_tiles_in_transit_and_the_drop_penalty_is_negative():
    # Mutation pin: the sign and size of the `dropped` reward term.
    weak = {"suction": {"vacuum_pressure": 300.0}}  # holds ~0.12 N: less than a tile's weight
    env = _make(execution="dynamic", cell=weak)
    _, info = env.reset(seed=0)
    u = env.unwrapped
    n_steps = 0
    dropped_seen = False
    terminated = truncated = False
    for tile in np.flatnonzero(~u.cell.is_distractor):
        _, _, terminated, truncated, info = env.step(u.expert_action(tile, _slot_of(env, tile)))
        n_steps += 1
        ev = info["evaluation"]
        _accounted(ev)
        if ev["dropped"] and not dropped_seen:
            dropped_seen = True
            assert info["reward_dropped"] == pytest.approx(
                -u.config.penalty_dropped * ev["dropped"]
            )
        if terminated or truncated:
            break
    assert dropped_seen
    assert ev["correct"] < ev["slots"]


def test_distractors_are_not_counted_among_the_real_tiles():
    env = _make(action_mode="pick_place_discrete", distractor_rate=1.0, max_slots=2)
    _, info = env.reset(seed=0)
    ev = info["evaluation"]
    n = len(env.unwrapped.cell.tiles)
    real = int(np.sum(~env.unwrapped.cell.is_distractor))
    assert n > real
    assert ev["fed"] + ev["waiting"] == real
    _accounted(ev)
    env.action_space.seed(0)
    for _ in range(40):
        _, _, terminated, truncated, info = env.step(env.action_space.sample())
        _accounted(info["evaluation"])
        if terminated or truncated:
            break
    assert terminated


def _scripted(env: Any) -> Any:
    from agents.scripted.agent import ScriptedAgent  # noqa: PLC0415
    from agents.scripted.config import load_agents_config  # noqa: PLC0415

    return ScriptedAgent.from_env(env, load_agents_config(), calibrate=False)


def test_the_scripted_agent_waits_on_a_black_or_noisy_picture_then_picks():
    env = gym.make(
        ENV_ID, action_mode="pick_place", obs_mode="rgb", max_slots=2, image_size=(240, 320)
    )
    obs, _ = env.reset(seed=0)
    agent = _scripted(env)
    black = {**obs, "input_camera": np.zeros_like(obs["input_camera"])}
    agent.predict(black)
    assert agent.last_command is None
    assert any("not usable" in m for m in agent.last_perception.unrecognised)
    rng = np.random.default_rng(0)
    noise = {**obs, "input_camera": rng.integers(0, 256, obs["input_camera"].shape, np.uint8)}
    agent.predict(noise)
    assert agent.last_command is None
    agent.predict(obs)  # the camera is back: the next picture is planned
    assert agent.last_command is not None


@pytest.mark.parametrize("execution", ["kinematic", "dynamic"])
def test_env_reject_puts_a_tile_into_the_bin_and_the_line_goes_on(execution):
    env = _make(execution=execution, feed="batch", batch_size=2, max_slots=3)
    _, info = env.reset(seed=0)
    u = env.unwrapped
    on_belt = np.flatnonzero(u.cell.input_side() & ~u.cell.is_distractor)
    tile = int(on_belt[0])
    _, reward, terminated, _, info = u.reject(u.ground_truth().xy[tile])
    ev = info["evaluation"]
    assert not info["action_failed"], info["action_error"]
    assert ev["rejected"] == 1
    assert ev["lost"] == 0
    assert reward == pytest.approx(0.0)  # rejecting is neither a loss nor a drop
    assert u.cell.rejected[tile]
    _accounted(ev)
    assert not terminated  # the other tiles can still fill their slots
