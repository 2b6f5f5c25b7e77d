"""The shipped MaskablePPO fine-tuning of the stream clone plays its rung by file name."""

from __future__ import annotations

from pathlib import Path

import pytest

from agents.policies import make_policies, run_config
from apps.evaluate import Protocol, evaluate_policy_set, task_protocol

ROOT = Path(__file__).resolve().parents[3]
TASK = "MosaicStream-v2"
MODEL = ROOT / "checkpoints" / TASK / "PPO_stream" / "seed_0" / "model.zip"


def test_the_shipped_file_names_its_algorithm_task_and_flat_masked_actions() -> None:
    """``apps.evaluate`` rebuilds the policy from the run config beside the model."""
    run = run_config(MODEL)
    assert run["algo"] == "MaskablePPO" and run["flatten_actions"] is True
    assert run["task"] == TASK


@pytest.mark.slow
def test_the_shipped_policy_fills_every_slot_of_held_out_seeds() -> None:
    """Loaded by its path, greedy with the env's masks: every tile of two held-out episodes
    placed in its slot, none lost or misplaced."""
    base, proto = task_protocol(TASK)
    short = Protocol((1004, 1010), proto.designs, proto.max_steps, proto.horizon_s)
    rows, _ = evaluate_policy_set(make_policies([str(MODEL)], base), short)
    row = rows[0]
    assert row.episodes == 2
    assert row.filled == 1.0 and row.misplaced == 0 and row.lost == 0, row
