"""The task ladder: registered ids, frozen presets, splits and the staged reward."""

from __future__ import annotations

from collections.abc import Iterator

import gymnasium as gym
import numpy as np
import pytest

import envs
from envs.actions import transfer_poses
from envs.rewards import STAGES
from envs.task import REWARD_TERMS
from envs.tasks import TaskError, bundled_tasks, get_task


def test_every_rung_is_registered_with_its_limit() -> None:
    tasks = bundled_tasks()
    assert list(tasks) == list(envs.TASK_IDS)
    assert {
        "MosaicOneTile-v0",
        "MosaicDecision6-v0",
        "MosaicDecision16-v0",
        "MosaicStream-v0",
        "MosaicDistractors-v0",
        "MosaicHeldOutDesigns-v0",
    } <= set(tasks)
    for task in tasks.values():
        spec = gym.spec(task.id)
        assert spec.max_episode_steps == task.max_episode_steps
        assert len(task.seeds) >= 20 and min(task.seeds) >= 1000


def test_held_out_designs_are_disjoint() -> None:
    t = get_task("MosaicHeldOutDesigns-v0")
    assert not set(t.designs("train")) & set(t.designs("eval"))
    assert t.env_kwargs("train", 1)["design"] == t.designs("train")[1]
    with pytest.raises(TaskError, match="split"):
        t.designs("test")
    with pytest.raises(TaskError, match="bundled"):
        get_task("MosaicNope-v0")


@pytest.mark.parametrize(
    ("task_id", "n_tiles"),
    [("MosaicDecision6-v0", 6), ("MosaicDistractors-v0", 9), ("MosaicDecision16-v0", 16)],
)
def test_decision_rungs_build_with_their_spaces(task_id: str, n_tiles: int) -> None:
    env = gym.make(task_id)
    try:
        env.reset(seed=0)
        assert env.action_space.nvec[0] == n_tiles
        obs, *_ = env.step(env.action_space.sample())
        assert obs["tiles"].shape == (n_tiles * 7,)
    finally:
        env.close()


def test_stream_rung_feeds_in_a_drawn_order() -> None:
    env = gym.make("MosaicStream-v0")
    try:
        firsts = set()
        for seed in range(4):
            env.reset(seed=seed)
            cell = env.unwrapped.cell
            firsts.add(tuple(np.flatnonzero(cell.on_stage)))
        assert len(firsts) > 1  # the first tiles on the belt differ between episodes
    finally:
        env.close()


def test_staged_reward_telescopes_to_the_stage_weights() -> None:
    env = gym.make(
        "MosaicOneTile-v0", action_mode="pick_place", execution="kinematic"
    )  # the same task, one privileged cycle
    try:
        u = env.unwrapped
        env.reset(seed=3)
        start = u.task.staged.potentials(u.task.evaluate())  # the potentials at the reset
        _, r, term, _, info = env.step(u.expert_action(0, 0))
        cfg = u.task.staged.cfg
        assert term and info["is_success"]
        for s in STAGES:
            w = getattr(cfg, s)
            assert info[f"reward_stage_{s}"] == pytest.approx(w * (1 - start[s]))
        assert r == pytest.approx(sum(info[f"reward_{t}"] for t in REWARD_TERMS))
    finally:
        env.close()


@pytest.fixture
def one_tile() -> Iterator[gym.Env]:
    """``MosaicOneTile-v0`` as registered; closed after the test."""
    env = gym.make("MosaicOneTile-v0")
    yield env
    env.close()


def test_staged_potentials_rise_through_reach_and_seal(one_tile: gym.Env) -> None:
    env = one_tile
    u = env.unwrapped
    env.reset(seed=1)
    st = u.task.staged
    far = st.potentials(u.evaluate())["reach"]
    # Put the pad on the tile (kinematic, through the privileged pose) and seal.
    cmd = transfer_poses(u.cell, 0, 0)
    q = u.ik.solve(np.array([*cmd.pick_xy, u.pick_area.tile_top_z]), cmd.pick_yaw).q
    u.cell.set_qpos(q)
    near = st.potentials(u.evaluate())
    assert near["reach"] > 0.95 > far and near["seal"] == 0.0
    u.cell.vacuum(True)
    held = st.potentials(u.evaluate())
    assert u.cell.held_tile == 0 and held["seal"] == 1.0 and held["reach"] == 1.0


def test_one_tile_cartesian_starts_inside_its_box(one_tile: gym.Env) -> None:
    """A zero action keeps the tool still: the home pose lies in the tool target's box.

    The box used to be only the tile area and the mesh, so the first step clipped the target
    0.3 m away and the carry had to cross over the robot's base.
    """
    env = one_tile
    env.reset(seed=1000)
    u = env.unwrapped
    start, _ = u.cell.tcp_pose()
    lo, hi = u.actions.box
    assert np.all(start >= lo - 1e-9) and np.all(start <= hi + 1e-9)
    assert hi[0] >= start[0] > max(u.pick_area.hi[0], u.place_area.hi[0])
    still = np.array([0, 0, 0, 0, -1], np.float32)
    for _ in range(3):
        _, _, _, _, info = env.step(still)
    end, _ = u.cell.tcp_pose()
    assert np.linalg.norm(end - start) < 0.002


def test_the_first_step_pays_only_the_change_since_reset(one_tile: gym.Env) -> None:
    """Reset stores the reset state's potentials: standing still earns (almost) nothing."""
    env = one_tile
    u = env.unwrapped
    for seed in (1, 3):
        env.reset(seed=seed)
        start = u.task.staged.potentials(u.evaluate())
        assert start["reach"] > 1e-3  # the pad starts near enough to have a potential
        still = np.array([0, 0, 0, 0, -1], np.float32)  # no move, no vacuum
        _, _, _, _, info = env.step(still)
        for s in STAGES:
            assert abs(info[f"reward_stage_{s}"]) < 1e-6, (seed, s, info[f"reward_stage_{s}"])
