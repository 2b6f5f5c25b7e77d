"""Vectorised envs (Gymnasium sync/async, SB3 SubprocVecEnv), RecordVideo, plain make."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import envs

SMALL = {"max_slots": 3, "image_size": 48, "action_mode": "joint"}


def _python(code: str) -> str:
    """Stdout (stripped) of ``code`` run in a fresh interpreter at the repository root."""
    out = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        check=True,
        cwd=Path(__file__).resolve().parents[2],
    )
    return out.stdout.strip()


def test_make_without_prior_import() -> None:
    code = (
        "import gymnasium as gym; e = gym.make('envs:MosaicAssembly-v0', max_slots=2, "
        "obs_mode='state'); e.reset(seed=0); e.close(); "
        "import sys; print('mujoco' in sys.modules)"
    )
    assert _python(code) == "True"


def test_import_is_light() -> None:
    code = "import envs, sys; print('mujoco' in sys.modules, 'torch' in sys.modules)"
    assert _python(code) == "False False"


def test_make_vec_sync() -> None:
    vec = gym.make_vec(envs.ENV_ID, num_envs=2, vectorization_mode="sync", **SMALL)
    try:
        obs, _ = vec.reset(seed=0)
        assert obs["input_camera"].shape == (2, 48, 48, 3)
        assert not np.array_equal(obs["input_camera"][0], obs["input_camera"][1])
        obs, r, term, trunc, info = vec.step(vec.action_space.sample())
        assert r.shape == (2,) and "sim_time" in info
    finally:
        vec.close()


@pytest.mark.slow
def test_make_vec_async() -> None:
    # "spawn": a forked worker hangs in EGL when the parent process has rendered before.
    vec = gym.make_vec(
        envs.ENV_ID,
        num_envs=2,
        vectorization_mode="async",
        vector_kwargs={"context": "spawn"},
        **SMALL,
    )
    try:
        obs, _ = vec.reset(seed=0)
        for _ in range(3):
            obs, r, *_ = vec.step(vec.action_space.sample())
        assert obs["robot"].shape == (2, 19) and r.shape == (2,)
    finally:
        vec.close()


@pytest.mark.slow
def test_sb3_subproc_vec_env() -> None:
    from stable_baselines3.common.env_util import make_vec_env  # noqa: PLC0415
    from stable_baselines3.common.vec_env import SubprocVecEnv  # noqa: PLC0415

    vec = make_vec_env(
        "envs:MosaicAssembly-v0",  # spawned workers import envs through the id
        n_envs=2,
        seed=0,
        vec_env_cls=SubprocVecEnv,
        env_kwargs=SMALL,
        vec_env_kwargs={"start_method": "spawn"},
    )
    try:
        obs = vec.reset()
        for _ in range(3):
            obs, r, done, info = vec.step(np.stack([vec.action_space.sample()] * 2))
        assert obs["output_camera"].shape == (2, 48, 48, 3) and r.shape == (2,)
    finally:
        vec.close()


def test_record_video(tmp_path: Path) -> None:
    env = gym.make(
        envs.ENV_ID,
        render_mode="rgb_array",
        max_episode_steps=12,
        obs_mode="state",
        max_slots=2,
        action_mode="joint",
    )
    env = gym.wrappers.RecordVideo(
        env, str(tmp_path / "videos"), episode_trigger=lambda e: True, disable_logger=True
    )
    try:
        env.reset(seed=0)
        done = False
        while not done:
            _, _, term, trunc, _ = env.step(env.action_space.sample())
            done = term or trunc
    finally:
        env.close()
    videos = list((tmp_path / "videos").glob("*.mp4"))
    assert videos and videos[0].stat().st_size > 1000


def test_forked_child_of_a_rendering_process_fails_clearly_instead_of_hanging() -> None:
    code = (
        "import multiprocessing as mp, gymnasium as gym, envs\n"
        "e = gym.make(envs.ENV_ID, max_slots=2, image_size=32); e.reset(seed=0)\n"
        "def child(q):\n"
        "    try:\n"
        "        e.reset(seed=1); q.put('rendered')\n"
        "    except Exception as exc:\n"
        "        q.put(type(exc).__name__ + ': ' + str(exc)[:60])\n"
        "q = mp.get_context('fork').Queue()\n"
        "p = mp.get_context('fork').Process(target=child, args=(q,)); p.start()\n"
        "print(q.get(timeout=60)); p.join(); e.close()\n"
    )
    assert _python(code).startswith("CellError: this process was forked")
