"""apps.evaluate with any policy: module:callable, checkpoints with wrong spaces, resuming."""

from __future__ import annotations

import json
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import envs  # noqa: F401
from agents.policies import PolicyError, make_policies, make_policy
from apps.evaluate import EPISODES_FILE, Protocol, evaluate_policy_set, main
from tests.presets import FAST_DISCRETE

BASE = {**FAST_DISCRETE, "max_slots": 2}
SEEDS = Protocol((1000, 1001), (), 4)


class ClassMatcher:
    """A user's policy object: matches tile and slot classes from the privileged state.

    Built with the env (a class named as ``module:Class``), it reads only the observation.
    """

    def __init__(self, env: gym.Env) -> None:
        self.action_space = env.action_space
        self.n, self.k = (int(v) for v in env.action_space.nvec[:2])
        self.used: set[int] = set()

    def predict(self, obs: dict) -> tuple[np.ndarray, None]:
        tiles = obs["tiles"].reshape(self.n, -1)
        slots = obs["slots"].reshape(self.k, -1)
        for i in range(self.n):
            if not tiles[i, 6]:
                continue
            for j in range(self.k):
                if slots[j, 5] or tiles[i, 5] != slots[j, 4]:
                    continue
                # Rotation index from the observed yaws (relative to the tile as it lies).
                d = np.arctan2(tiles[i, 4], tiles[i, 3]) - np.arctan2(slots[j, 3], slots[j, 2])
                base = round(float(np.remainder(d + np.pi, 2 * np.pi) - np.pi) / (np.pi / 2)) % 4
                return np.array([i, j, (-base) % 4]), None
        return np.zeros(3, np.int64), None


def random_function(obs: dict) -> np.ndarray:
    """A plain function policy ``f(obs) -> action``."""
    del obs
    return np.array([0, 0, 0])


def test_module_callable_policies(tmp_path) -> None:
    pols = make_policies([f"{__name__}:ClassMatcher", f"{__name__}:random_function"], BASE)
    rows, eps = evaluate_policy_set(pols, SEEDS, log=tmp_path / EPISODES_FILE)
    matcher, fn = rows
    assert matcher.success_rate == 1.0 and matcher.filled == 1.0  # it read the observation
    assert fn.success_rate == 0.0
    lines = (tmp_path / EPISODES_FILE).read_text().splitlines()
    assert len(lines) == 4 and json.loads(lines[0])["policy"] == pols[0].label


def test_bad_names_fail_clearly() -> None:
    with pytest.raises(PolicyError, match="cannot import"):
        make_policy("no_such_module_xyz:thing", BASE)
    with pytest.raises(PolicyError, match="unknown policy"):
        make_policy("gibberish", BASE)


def test_checkpoint_with_other_spaces_fails_before_any_episode(tmp_path) -> None:
    from stable_baselines3 import PPO  # noqa: PLC0415

    env = gym.make("MosaicAssembly-v0", **BASE)
    PPO("MultiInputPolicy", env, n_steps=8, batch_size=8, device="cpu").save(tmp_path / "m.zip")
    env.close()
    log = tmp_path / "out" / EPISODES_FILE
    pols = make_policies(["random", str(tmp_path / "m.zip")], {**BASE, "max_slots": 3})
    with pytest.raises(PolicyError, match="space"):
        evaluate_policy_set(pols, SEEDS, log=log)
    assert not log.exists()  # not even the random policy's episodes were played


def test_results_are_appended_and_never_recomputed(tmp_path, monkeypatch) -> None:
    out = tmp_path / "eval"
    args = ["--policies", "random", "--seeds", "1000-1001", "--out", str(out), "--quiet"]
    env_args = ["--env", *(f"{k}={v}" for k, v in BASE.items())]
    main([*args, *env_args])
    first = (out / EPISODES_FILE).read_text().splitlines()
    assert len(first) == 2
    # A rerun over more seeds plays only the new one; the old lines stay as they were.
    report = main(
        ["--policies", "random", "--seeds", "1000-1002", "--out", str(out), "--quiet", *env_args]
    )
    lines = (out / EPISODES_FILE).read_text().splitlines()
    assert lines[:2] == first and len(lines) == 3
    assert [e["seed"] for e in report["episodes"]["random"]] == [1000, 1001, 1002]


def test_task_protocol_and_train_preset_names() -> None:
    from apps.evaluate import load_env_overrides, task_protocol  # noqa: PLC0415

    base, proto = task_protocol("MosaicHeldOutDesigns-v0")
    assert proto.designs == ("hexagon", "trencadis") and proto.max_steps == 12
    assert proto.seeds[0] == 1000 and proto.horizon_s > 0
    assert load_env_overrides("tiny")["max_slots"] == 2  # a configs/train preset by name


def test_image_checkpoint_spaces_are_compared_as_sb3_stores_them(tmp_path) -> None:
    from stable_baselines3 import PPO  # noqa: PLC0415

    kw = {**BASE, "obs_mode": "rgb", "image_size": [36, 48]}
    env = gym.make("MosaicAssembly-v0", **kw)
    PPO("MultiInputPolicy", env, n_steps=8, batch_size=8, device="cpu").save(tmp_path / "m.zip")
    env.close()
    (tmp_path / "train_config.yaml").write_text(
        "algo: PPO\nenv: {obs_mode: rgb, image_size: [36, 48]}\n"
    )
    rows, _ = evaluate_policy_set(make_policies([str(tmp_path / "m.zip")], BASE), SEEDS)
    assert rows[0].episodes == 2  # images transposed by SB3 still match


CHECKPOINTS = Path(__file__).resolve().parents[2] / "checkpoints"


@pytest.mark.parametrize(
    "path",
    sorted(str(p) for p in CHECKPOINTS.glob("*/*/seed_*/model.zip")),
    ids=lambda p: "/".join(Path(p).parts[-4:-2]),
)
def test_committed_checkpoints_bind_to_their_task(path: str) -> None:
    """Every SB3 checkpoint in the repository loads and acts on its task's held-out env."""
    from apps.evaluate import bind, task_protocol  # noqa: PLC0415

    task = Path(path).parts[-4]
    base, proto = task_protocol(task)
    pol = make_policy(path, base)
    [(env, predict)] = bind(pol, proto.designs[:1])
    try:
        obs, _ = env.reset(seed=proto.seeds[0])
        action = predict(obs, True)
        assert env.action_space.contains(action.astype(env.action_space.dtype))
    finally:
        env.close()


def test_random_samples_only_allowed_actions_where_the_env_refuses_the_others() -> None:
    """On ``invalid_actions="refuse"`` (the ``-v1`` ids) every random action is accepted."""
    refuse = {**BASE, "max_slots": 6, "invalid_actions": "refuse"}
    rows, _ = evaluate_policy_set(
        make_policies(["random"], refuse), Protocol((1000, 1001, 1002), (), 6)
    )
    assert rows[0].episodes == 3
    env = gym.make("MosaicDecision6-v1")
    try:
        predict = make_policy("random", dict(refuse)).factory(env)
        env.reset(seed=5)
        env.action_space.seed(5)
        for _ in range(6):
            action = predict({}, False)
            mask = env.get_wrapper_attr("action_masks")()
            assert mask[action[0]] and mask[6 + action[1]]
            _, _, terminated, _, _ = env.step(action)
            if terminated:
                break
    finally:
        env.close()
