"""The ``-v1`` ids beside the unchanged ``-v0`` ones: what v1 changes and what it keeps."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import envs
from envs.task_spec import ActionError, PickPlaceCommand
from envs.tasks import TaskError, bundled_tasks, get_task, load_task


def test_every_rung_has_a_v1_with_the_v1_changes_and_v0_keeps_its_preset():
    v0 = bundled_tasks()
    every = bundled_tasks(all_versions=True)
    assert all(t.endswith("-v0") for t in v0)
    later_ids = {*(t.replace("-v0", "-v1") for t in v0), "MosaicStream-v2"}
    assert set(every) == {*v0, *later_ids}
    for task_id, task in v0.items():
        later = every[task_id.replace("-v0", "-v1")]
        assert later.version == "v1" and later.eval_seeds == task.eval_seeds
        assert {**task.env, **envs.V1_CHANGES} == dict(later.env)
        assert "invalid_actions" not in gym.spec(task_id).kwargs
        assert gym.spec(later.id).kwargs["invalid_actions"] == "refuse"
        assert get_task(later.id) == later
    assert gym.spec("MosaicAssembly-v0").kwargs == {}
    assert gym.spec("MosaicAssembly-v1").kwargs == envs.V1_CHANGES


def test_a_version_must_be_named_v_and_a_number(tmp_path):
    path = tmp_path / "bad.yaml"
    text = (
        "id: MosaicX-v0\ndescription: x\nmax_episode_steps: 5\nhorizon_s: 1.0\n"
        "eval_seeds: [1, 2]\nenv: {max_slots: 1}\n"
    )
    path.write_text(text + "versions:\n  latest: {invalid_actions: refuse}\n")
    with pytest.raises(TaskError, match="names v1, v2"):
        load_task(path)
    path.write_text(text + "versions:\n  v1: {invalid_actions: maybe}\n")
    with pytest.raises(Exception, match="invalid_actions"):
        load_task(path)
    with pytest.raises(TaskError, match="no version 'v7'"):
        get_task("MosaicDecision6-v0").at_version("v7")


def test_v1_pick_place_is_box5_and_its_codec_round_trips():
    v0 = gym.make("MosaicAssembly-v0", max_slots=1, execution="kinematic", obs_mode="state")
    v1 = gym.make("MosaicAssembly-v1", max_slots=1, execution="kinematic", obs_mode="state")
    try:
        assert v0.action_space.shape == (6,) and v1.action_space.shape == (5,)
        c0 = v0.get_wrapper_attr("task_spec").codec
        c1 = v1.get_wrapper_attr("task_spec").codec
        assert (c0.size, c1.size) == (6, 5)
        cmd = PickPlaceCommand((c1.pick.lo[0] + 0.01, c1.pick.hi[1] - 0.01), 0.7, (0.0, 0.0), -0.4)
        cmd = PickPlaceCommand(cmd.pick_xy, 0.7, tuple(c1.place.lo + 0.02), -0.4)
        a0, a1 = c0.encode(cmd), c1.encode(cmd)
        np.testing.assert_allclose(np.delete(a0, 2), a1)
        back = c1.decode(a1)
        np.testing.assert_allclose(back.pick_xy, cmd.pick_xy, atol=1e-6)
        np.testing.assert_allclose(back.place_xy, cmd.place_xy, atol=1e-6)
        assert back.pick_yaw == 0.0 and back.rotation == pytest.approx(-0.4, abs=1e-6)
        v1.reset(seed=0)
        with pytest.raises(ActionError, match=r"expects \(5,\)"):
            v1.step(np.zeros(6, np.float32))
    finally:
        v0.close()
        v1.close()


def test_v1_decision_rungs_refuse_what_their_mask_forbids():
    env = gym.make("MosaicDecision6-v1")
    try:
        _, info = env.reset(seed=1000)
        env.step(env.unwrapped.expert_action(0, 0))
        placed_slot = int(env.unwrapped.index.encode(0, 0)[1])
        with pytest.raises(ActionError, match=f"slot index {placed_slot} is filled"):
            env.step(np.array([0, placed_slot, 0]))
    finally:
        env.close()
