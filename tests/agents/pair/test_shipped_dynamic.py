"""The shipped clones of the dynamic rungs play their rung by file name and do what it asks."""

from __future__ import annotations

import json
from pathlib import Path

import gymnasium as gym
import pytest

from agents.experts.deadline import DeadlineExpert
from agents.learning.decision_bc import BCPolicy
from agents.policies import make_policies
from apps.evaluate import Protocol, evaluate_policy_set, task_protocol

ROOT = Path(__file__).resolve().parents[3]
DISTRACTORS = "MosaicDistractors-v1"
DISTRACTOR_CLONE = ROOT / "checkpoints" / DISTRACTORS / "PairBC_objects" / "seed_0" / "bc.pt"


def test_the_distractor_clone_plays_on_objects_rows_by_its_file() -> None:
    """The file names its rows: ``apps.evaluate`` needs no ``@obs_mode=objects``."""
    assert BCPolicy(DISTRACTOR_CLONE).env_overrides == {"obs_mode": "objects"}


def test_the_distractor_clone_fills_every_slot_and_never_places_a_distractor(
    tmp_path: Path,
) -> None:
    """Held-out seeds with distractors on the belt: one step per slot, none spent on a tile the
    design lacks (a clone on ``state`` rows, where a distractor carries its shape's class, placed
    them: 0.72 filled)."""
    base, proto = task_protocol(DISTRACTORS)
    seeds = (1000, 1001, 1002, 1003)
    short = Protocol(seeds, proto.designs, proto.max_steps, proto.horizon_s)
    rows, episodes = evaluate_policy_set(make_policies([str(DISTRACTOR_CLONE)], base), short)
    assert rows[0].filled == 1.0 and rows[0].success_rate == 1.0, rows[0]
    eps = episodes[rows[0].policy]
    assert [e.steps for e in eps] == [e.slots for e in eps]
    assert json.loads(eps[0].env)["distractor_rate"] == pytest.approx(0.5)


def _stream_clone(task: str) -> Path:
    return ROOT / "checkpoints" / task / "PairBC_stream" / "seed_0" / "bc.pt"


@pytest.mark.parametrize(
    ("task", "seed"),
    [("MosaicStream-v1", 1003), ("MosaicStream-v1", 1010), ("MosaicStream-v2", 1004)],
)
def test_the_stream_clone_picks_first_the_tile_its_teacher_picks_at_the_right_turn(
    task: str, seed: int
) -> None:
    """On the stream's first picture the clone names the tile nearest the belt's end, an open
    slot of its class and the rotation index that places it (the teacher's choice)."""
    env = gym.make(task)
    try:
        obs, _ = env.reset(seed=seed)
        u = env.unwrapped
        tile, slot = DeadlineExpert(env).choose()  # type: ignore[misc]
        action, _ = BCPolicy(_stream_clone(task)).predict(obs)
        picked = int(u.index.tiles[action[0]])  # type: ignore[attr-defined]
        chosen = int(u.index.slots[action[1]])  # type: ignore[attr-defined]
        assert picked == tile
        assert u.task.slot_class[chosen] == u.task.tile_class[tile]  # type: ignore[attr-defined]
        assert action[2] == u.expert_action(picked, chosen)[2]  # type: ignore[attr-defined]
    finally:
        env.close()


@pytest.mark.slow
def test_the_v2_stream_clone_places_every_tile_of_a_held_out_episode() -> None:
    """A whole episode of the stream (dynamic execution): 16 tiles streamed, 16 placed in their
    slots, none lost off the belt's end."""
    task = "MosaicStream-v2"
    base, proto = task_protocol(task)
    one = Protocol((1007,), proto.designs, proto.max_steps, proto.horizon_s)
    rows, episodes = evaluate_policy_set(make_policies([str(_stream_clone(task))], base), one)
    (episode,) = episodes[rows[0].policy]
    assert episode.success and episode.correct == 16, episode
    assert episode.lost == episode.misplaced == 0
