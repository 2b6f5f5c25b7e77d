"""RecordCycleVideo: a decision-level episode's video shows the motion inside each cycle."""

from __future__ import annotations

import gymnasium as gym

import envs  # noqa: F401
from agents.wrappers import RecordCycleVideo


def test_frames_from_inside_the_cycle_reach_the_video(tmp_path) -> None:
    env = gym.make(
        "MosaicAssembly-v0",
        max_slots=1,
        action_mode="pick_place_discrete",
        execution="dynamic",
        obs_mode="state",
        render_mode="rgb_array",
    )
    env = RecordCycleVideo(env, str(tmp_path / "video"), episode_trigger=lambda i: True)
    try:
        env.reset(seed=0)
        _, _, term, _, info = env.step(env.unwrapped.expert_action(0, 0))
        frames = len(env.recorded_frames)
        fps = env.metadata["render_fps"]
        assert info["is_success"] and term
        # One frame per 1/fps of the cycle's simulated time (plus reset's and the step's own).
        assert frames >= 0.9 * info["sim_time"] * fps > 20
    finally:
        env.close()
    assert list((tmp_path / "video").glob("*.mp4"))
