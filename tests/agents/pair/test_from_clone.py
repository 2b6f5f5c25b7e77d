"""The MaskablePPO pair-scorer policy started from the stream clone acts as the clone."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
import torch

import envs  # noqa: F401 - registers the ladder
from agents.errors import AgentError
from agents.learning.decision_bc import BCPolicy
from agents.learning.wrappers import FlatDiscreteActions
from agents.pair.from_clone import clone_policy_kwargs, load_clone, read_clone
from apps.train import build_model, load_train_config, make_vec

ROOT = Path(__file__).resolve().parents[3]
CLONE = ROOT / "checkpoints" / "MosaicStream-v1" / "PairBC_stream" / "seed_0" / "bc.pt"
MLP_CLONE = ROOT / "checkpoints" / "MosaicDecision6-v0" / "BC_state_200_expert_demos"
PRESET = "maskable_ppo_stream_finetune"
STEPS = 12
"""Env steps of the clone's own episode compared (its first picks and waits)."""


@pytest.fixture(scope="module")
def model() -> Any:
    """The preset's MaskablePPO model on one stream env, started from the shipped clone."""
    cfg = load_train_config(PRESET, n_envs=1)
    venv = make_vec(cfg, None)
    yield build_model(cfg, venv)
    venv.close()


def test_the_policy_started_from_the_clone_picks_what_the_clone_picks(model: Any) -> None:
    """On the observations of a real episode (seed 1003, the clone playing), the policy's
    greedy action under the env's joint mask is the clone's, and its logits are the clone's."""
    clone = BCPolicy(CLONE)
    env = FlatDiscreteActions(gym.make(load_train_config(PRESET).task))
    scorer = read_clone(CLONE)
    try:
        obs, _ = env.reset(seed=1003)
        for _ in range(STEPS):
            mine, _ = clone.predict(obs)
            ours, _ = model.predict(obs, deterministic=True, action_masks=env.action_masks())
            assert int(ours) == env.flat(mine)
            batch = {k: torch.as_tensor(v)[None] for k, v in obs.items()}
            with torch.no_grad():
                logits = model.policy.get_distribution(batch).distribution.logits
                feats = model.policy.pi_features_extractor
                theirs = feats.scorer.logits(feats.adapter(batch["tiles"], batch["slots"]))
            allowed = env.action_masks()
            got = torch.log_softmax(logits[0, allowed], 0)
            want = torch.log_softmax(theirs[0, allowed], 0)
            assert torch.allclose(got, want, atol=1e-5)
            obs, _, term, trunc, _ = env.step(int(ours))
            assert not (term or trunc)
    finally:
        env.close()
    assert scorer.adapter == "stream" and scorer.adapter_args is not None


def test_the_critic_starts_from_the_clone_features_and_its_own_value_head(model: Any) -> None:
    """An unshared critic's scorer holds the clone's weights too (a separate copy)."""
    pi = model.policy.pi_features_extractor.scorer
    vf = model.policy.vf_features_extractor.scorer
    assert pi is not vf
    for (name, a), b in zip(pi.state_dict().items(), vf.state_dict().values(), strict=True):
        assert torch.equal(a, b), name
        assert torch.equal(a, read_clone(CLONE).state_dict[name])


def test_a_file_that_is_no_pair_clone_is_refused_saying_what_was_expected(tmp_path: Path) -> None:
    text = tmp_path / "notes.pt"
    text.write_text("not a torch file", encoding="utf-8")
    for path in (text, MLP_CLONE / "seed_0" / "bc.pt", tmp_path / "missing.pt"):
        with pytest.raises(AgentError, match="pair-scorer clone"):
            read_clone(path)


def test_settings_that_differ_from_the_clone_are_refused() -> None:
    clone = read_clone(CLONE)
    with pytest.raises(AgentError, match="hidden"):
        clone_policy_kwargs(clone, {"features_extractor_kwargs": {"hidden": 32}})
    with pytest.raises(AgentError, match="allowed"):
        clone_policy_kwargs(clone, {"features_extractor_kwargs": {"width": 32}})
    kwargs = clone_policy_kwargs(clone, {"share_features_extractor": False})
    assert kwargs["share_features_extractor"] is False
    assert kwargs["features_extractor_kwargs"]["adapter_args"] == dict(clone.adapter_args or {})


def test_a_policy_of_another_shape_is_refused(model: Any) -> None:
    """A scorer 32 wide, the state rows, or a clone of another action count: each refused."""
    from sb3_contrib import MaskablePPO  # noqa: PLC0415

    from agents.pair.maskable_policy import PairScorerPolicy  # noqa: PLC0415

    clone = read_clone(CLONE)
    env = model.get_env()
    narrow = clone_policy_kwargs(clone, {})
    narrow["features_extractor_kwargs"] = {**narrow["features_extractor_kwargs"], "hidden": 32}
    other = MaskablePPO(PairScorerPolicy, env, policy_kwargs=narrow, n_steps=16)
    with pytest.raises(AgentError, match="scorer"):
        load_clone(other.policy, clone)
    state = MaskablePPO(PairScorerPolicy, env, n_steps=16)  # state rows, no timing
    with pytest.raises(AgentError, match="rows"):
        load_clone(state.policy, clone)
    fewer = dataclasses.replace(clone, nvec=(6, 6, 4))
    with pytest.raises(AgentError, match=r"Discrete\(144\)"):
        load_clone(model.policy, fewer)


def test_the_clone_weights_make_the_flat_actions_of_the_clone_file(model: Any) -> None:
    """Action count of the policy: tiles x slots x rotation bins of the file (16 x 16 x 4)."""
    assert model.action_space.n == int(np.prod(read_clone(CLONE).nvec)) == 1024
