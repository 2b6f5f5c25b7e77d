"""The same seed gives the same episode as recorded (`tests.envs.rollouts`): the reset's and
every step's observations (camera images included), rewards and filled slots, bit for bit, for
procedural and fixed designs. Pins that the reset, step and render speed-ups change nothing."""

from __future__ import annotations

import pytest

from tests.envs.rollouts import CASES, load, rollout


@pytest.mark.parametrize("name", sorted(CASES))
def test_seeded_rollouts_match_the_recorded_fingerprints(name: str) -> None:
    want = load()[name]
    got = rollout(name)
    for a, b in zip(got, want, strict=True):
        assert a == b, f"{name}: seed {b['seed']} step {b['step']} differs"
