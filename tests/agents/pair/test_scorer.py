"""The pair scorer: cloned from a few expert episodes it beats random; its .pt plays by name."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
import torch

pytest.importorskip("minari")

import envs  # noqa: E402, F401
from agents.errors import AgentError  # noqa: E402
from agents.learning.decision_bc import BCConfig, train_bc  # noqa: E402
from agents.pair.state_rows import state_rows  # noqa: E402
from agents.policies import PolicyError, make_policies  # noqa: E402
from apps.evaluate import Protocol, evaluate_policy_set  # noqa: E402
from apps.record_demos import load, record  # noqa: E402
from tests.presets import FAST_DISCRETE

TASK = "MosaicDecision6-v0"
BASE = {**FAST_DISCRETE, "max_slots": 6}
HELD_OUT = Protocol((1000, 1001, 1002, 1003), (), 12)
"""Seeds none of the demonstrations used, the task's 12-step limit."""


@pytest.fixture(scope="module")
def clone(tmp_path_factory: pytest.TempPathFactory) -> str:
    """A pair scorer cloned from 10 expert episodes of MosaicDecision6-v0 (seeds 0-9)."""
    root = tmp_path_factory.mktemp("pair")
    torch.manual_seed(0)
    record(
        10,
        root=root,
        dataset_id="mosaic/pair-v0",
        env_kwargs={"obs_mode": "state"},
        expert=True,
        task=TASK,
    )
    cfg = BCConfig(
        arch="pair",
        hidden=32,
        layers=2,
        epochs=60,
        batch_size=8,
        learning_rate=3e-3,
        weight_decay=0.0,
    )
    summary = train_bc(load("mosaic/pair-v0", root), root / "run", 0, cfg)
    assert summary["samples"] == 60 and summary["arch"] == "pair"
    return str(summary["model_path"])


def test_pair_clone_beats_random_on_held_out_seeds(clone: str) -> None:
    rows, _ = evaluate_policy_set(make_policies([clone, "random"], BASE), HELD_OUT)
    pair, rand = rows
    assert pair.filled >= 0.75 > rand.filled + 0.25
    assert pair.misplaced < rand.misplaced


def test_pair_clone_file_plays_through_policy_resolution(clone: str) -> None:
    (pol,) = make_policies([clone], BASE)
    env = gym.make(f"envs:{TASK}", **pol.env_kwargs)
    obs, _ = env.reset(seed=1000)
    action = pol.factory(env)(obs, True)
    assert env.action_space.contains(action)
    mask = env.unwrapped.action_masks()  # type: ignore[attr-defined]
    n, k = (int(v) for v in env.action_space.nvec[:2])
    assert mask[action[0]] and mask[n + action[1]]  # it picks a tile and slot the env allows
    env.close()
    with pytest.raises(PolicyError, match="space"):
        evaluate_policy_set(make_policies([clone], {**BASE, "max_slots": 3}), Protocol((0,), (), 4))


def test_state_rows_mask_filled_slots_and_placed_tiles() -> None:
    env = gym.make(f"envs:{TASK}")
    env.reset(seed=3)
    for i in range(2):
        obs, *_ = env.step(env.unwrapped.expert_action(i, i))  # type: ignore[attr-defined]
    rows = state_rows(torch.as_tensor(obs["tiles"]), torch.as_tensor(obs["slots"]))
    mask = env.unwrapped.action_masks()  # type: ignore[attr-defined]
    env.close()
    assert rows.tile_mask[0].numpy().tolist() == mask[:6].tolist()
    assert rows.slot_mask[0].numpy().tolist() == mask[6:12].tolist()
    assert rows.pairs.shape == (1, 6, 6, 5)
    assert int(rows.pairs[0, ..., 0].sum()) == 6  # one class match per tile (6 classes)


def test_pair_policy_learns_under_maskable_ppo(tmp_path) -> None:
    from sb3_contrib import MaskablePPO  # noqa: PLC0415

    from agents.learning.wrappers import FlatDiscreteActions  # noqa: PLC0415
    from agents.pair.maskable_policy import PairScorerPolicy  # noqa: PLC0415

    env = FlatDiscreteActions(gym.make(f"envs:{TASK}"))
    model = MaskablePPO(PairScorerPolicy, env, n_steps=32, batch_size=32, n_epochs=1, seed=0)
    model.learn(64)
    model.save(tmp_path / "model.zip")
    loaded = MaskablePPO.load(tmp_path / "model.zip", device="cpu")
    obs, _ = env.reset(seed=1000)
    mask = env.action_masks()
    action, _ = loaded.predict(obs, action_masks=mask, deterministic=True)
    assert mask[int(action)]
    with pytest.raises(AgentError, match="Discrete"):
        MaskablePPO(PairScorerPolicy, gym.make(f"envs:{TASK}"), n_steps=32)
    env.close()
    assert np.isfinite(loaded.policy.value_net.weight.detach().numpy()).all()


def _tile_row(x: float, y: float, yaw_deg: float, cls: int, present: float = 1.0) -> list[float]:
    a = np.radians(yaw_deg)
    return [x, y, 0.2, float(np.cos(a)), float(np.sin(a)), float(cls), present]


def _slot_row(x: float, y: float, yaw_deg: float, cls: int, filled: float = 0.0) -> list[float]:
    a = np.radians(yaw_deg)
    return [x, y, float(np.cos(a)), float(np.sin(a)), float(cls), filled]


@pytest.mark.parametrize(("tile_yaw", "slot_yaw"), [(30.0, 100.0), (-150.0, 20.0), (0.0, 90.0)])
def test_state_pair_features_are_the_yaw_difference_at_known_yaws(tile_yaw, slot_yaw) -> None:
    """Guards against the slot yaw's angle computed with its arguments swapped (atan2(cos, sin))
    or the difference taken the other way: the pair features are (class equal, cos d, sin d,
    cos 2d, sin 2d) with d = tile yaw - slot yaw."""
    tiles = torch.tensor([_tile_row(0.1, 0.3, tile_yaw, 2), _tile_row(0.2, 0.3, 0.0, 5)])
    slots = torch.tensor([_slot_row(0.0, -0.5, slot_yaw, 2), _slot_row(0.05, -0.5, 0.0, 4, 1.0)])
    rows = state_rows(tiles.reshape(-1), slots.reshape(-1))
    d = np.radians(tile_yaw - slot_yaw)
    expected = [1.0, np.cos(d), np.sin(d), np.cos(2 * d), np.sin(2 * d)]
    np.testing.assert_allclose(rows.pairs[0, 0, 0].numpy(), expected, atol=1e-6)
    assert rows.pairs[0, 0, 1, 0] == 0.0 and rows.pairs[0, 1, 0, 0] == 0.0  # classes differ
    d10 = np.radians(0.0 - slot_yaw)
    np.testing.assert_allclose(
        rows.pairs[0, 1, 0, 1:3].numpy(), [np.cos(d10), np.sin(d10)], atol=1e-6
    )
    # rows: tile x, y, present; slot x, y, filled; masks from the flags
    np.testing.assert_allclose(rows.tiles[0].numpy(), [[0.1, 0.3, 1.0], [0.2, 0.3, 1.0]], atol=1e-6)
    np.testing.assert_allclose(
        rows.slots[0].numpy(), [[0.0, -0.5, 0.0], [0.05, -0.5, 1.0]], atol=1e-6
    )
    assert rows.tile_mask[0].tolist() == [True, True]
    assert rows.slot_mask[0].tolist() == [True, False]


def test_state_tile_mask_closes_absent_tiles_and_tiles_on_a_slot() -> None:
    """Guards against the on-slot distance (5 mm) or the present flag ignored by the mask."""
    tiles = torch.tensor(
        [
            _tile_row(0.0, -0.5 + 0.0049, 0.0, 1),  # 4.9 mm from slot 0: on it
            _tile_row(0.0, -0.5 + 0.0051, 0.0, 1),  # 5.1 mm: not
            _tile_row(0.1, 0.3, 0.0, 1, present=0.0),
        ]
    )
    slots = torch.tensor([_slot_row(0.0, -0.5, 0.0, 1)])
    rows = state_rows(tiles[None].reshape(1, -1), slots[None].reshape(1, -1))
    assert rows.tile_mask[0].tolist() == [False, True, False]
