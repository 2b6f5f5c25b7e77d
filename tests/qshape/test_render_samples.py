"""``render.samples``: multisampling of the cell's images (anti-aliased edges or not)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np

import envs


def test_samples_set_the_models_multisampling_and_smooth_edges() -> None:
    """Without multisampling an edge pixel takes one surface's colour: far fewer colours."""
    colours = {}
    for samples in (4, 0):
        env = gym.make(
            envs.ENV_ID,
            action_mode="pick_place_discrete",
            execution="kinematic",
            obs_mode="rgb",
            cell={"render": {"samples": samples}},
        )
        try:
            obs, _ = env.reset(seed=0)
            assert env.unwrapped.cell.model.vis.quality.offsamples == samples
            img = obs["input_camera"]
            colours[samples] = len(np.unique(img.reshape(-1, 3), axis=0))
        finally:
            env.close()
    assert colours[0] < colours[4] / 2
