"""The shipped RLPD policy of `MosaicOneTileJoint-v1` plays by file name and places its tile."""

from __future__ import annotations

from pathlib import Path

from agents.policies import make_policies
from apps.evaluate import Protocol, evaluate_policy_set, task_protocol

ROOT = Path(__file__).resolve().parents[3]
TASK = "MosaicOneTileJoint-v1"
MODEL = ROOT / "checkpoints" / TASK / "RLPD_state" / "seed_0" / "model.zip"


def test_the_shipped_joint_policy_places_the_tile_from_joint_moves_alone() -> None:
    """Two held-out seeds, the rung's protocol: the tile placed within tolerance by six joint
    target moves and the vacuum per step, with no demonstration dataset on the machine's path
    (the checkpoint was saved portable)."""
    base, proto = task_protocol(TASK)
    short = Protocol((1001, 1002), proto.designs, proto.max_steps, proto.horizon_s)
    rows, episodes = evaluate_policy_set(make_policies([str(MODEL)], base), short)
    assert rows[0].success_rate == 1.0 and rows[0].misplaced == 0.0, rows[0]
    assert all(e.steps < proto.max_steps for e in episodes[rows[0].policy])
