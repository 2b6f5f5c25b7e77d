"""Frame listeners: callbacks on a simulated-time schedule inside pick_place cycles."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import envs  # noqa: F401 - registers MosaicAssembly-v0
from envs.mosaic_env import MosaicEnvError


def test_frame_listener_renders_inside_a_dynamic_cycle() -> None:
    env = gym.make("envs:MosaicAssembly-v0", max_slots=2, render_mode="rgb_array")
    u = env.unwrapped
    times: list[float] = []
    frames: list[np.ndarray] = []

    def grab() -> None:
        times.append(u.cell.time)
        frames.append(u.cell.render("overview", 48, 64))

    u.add_frame_listener(grab, 10.0)
    try:
        env.reset(seed=0)
        _, _, _, _, info = env.step(u.expert_action(0, 0))
        # one cycle of ~1.9 s simulated: a frame every 0.1 s of it, not one per step
        assert len(times) == pytest.approx(info["sim_time"] / 0.1, abs=2)
        assert np.allclose(np.diff(times), 0.1, atol=0.0025)
        assert not np.array_equal(frames[0], frames[len(frames) // 2])  # the arm moved
        n = len(times)
        env.reset(seed=1)  # the schedule restarts at reset
        env.step(u.expert_action(1, 1))
        assert len(times) > n + 5
    finally:
        env.close()


@pytest.mark.parametrize("fps", [0.0, -1.0, float("nan")])
def test_frame_listener_rejects_bad_rates(fps: float) -> None:
    env = gym.make("envs:MosaicAssembly-v0", max_slots=1, execution="kinematic")
    try:
        with pytest.raises(MosaicEnvError, match="fps"):
            env.unwrapped.add_frame_listener(lambda: None, fps)
    finally:
        env.close()
