"""The shipped equivariant checkpoints: they play the held-out rung by name, discrete and in
continuous pick_place from the pictures."""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym

from agents.camera.continuous import ContinuousCameraPolicy
from agents.policies import make_policies
from apps.evaluate import Protocol, evaluate_policy_set, task_protocol

ROOT = Path(__file__).resolve().parents[3]
TASK = "MosaicHeldOutDesigns-v1"
TEN = ROOT / "checkpoints" / TASK / "EquiMatch-10demos_rgb" / "seed_0" / "model.pt"
HUNDRED = ROOT / "checkpoints" / TASK / "EquiMatch_rgb" / "seed_0" / "model.pt"


def test_the_shipped_policies_fill_unseen_designs_by_file_name() -> None:
    """Two held-out seeds (a hexagon and a trencadis episode), turns counted modulo symmetry."""
    base, proto = task_protocol(TASK)
    short = Protocol((1000, 1001), proto.designs, proto.max_steps, proto.horizon_s)
    pols = make_policies([str(TEN), str(HUNDRED)], {**base, "rotation_frame": "shape"})
    rows, episodes = evaluate_policy_set(pols, short)
    for row in rows:
        assert row.filled == 1.0, row
    assert [e.design for e in episodes[rows[0].policy]] == ["hexagon", "trencadis"]


def test_continuous_pick_place_never_offers_a_slot_twice_and_lands_within_tolerance() -> None:
    """``pick_place`` has no action mask: without the policy's own memory of the slots it
    placed into, the scorer chose a filled hexagon slot of the same colour again (3 of 6)."""
    base, _ = task_protocol(TASK)
    env = gym.make(
        TASK,
        **{
            **base,
            "design": "hexagon",
            "action_mode": "pick_place",
            "obs_mode": "rgb",
            "image_size": [246, 328],
        },
    )
    policy = ContinuousCameraPolicy.load(HUNDRED)
    try:
        obs, _ = env.reset(seed=1000)
        policy.reset()
        spec = env.get_wrapper_attr("task_spec")
        slots = []
        for _ in range(6):
            decision = policy.decide(obs, spec)
            assert decision is not None
            slots.append(decision.slot)
            obs, _, terminated, _, info = env.step(decision.action)
            if terminated:
                break
        assert len(set(slots)) == len(slots) == 6
        ev = info["evaluation"]
        assert ev["correct"] == 6, ev
        assert 0 <= ev["position_error_mm_max"] < 1.5
    finally:
        env.close()
