"""The kinematic pick_place step returns what it returned before its overhead was cut (issue 38).

Right, wrong and invalid actions, several observation and reward modes (`tests.envs.step_rollouts`):
every observation array, reward, ``terminated``, ``truncated`` and ``info`` (or the refusal's
message) of each step, bit for bit, equal to ``tests/data/step_fingerprints.json``.
"""

from __future__ import annotations

import pytest

from tests.envs.step_rollouts import CASES, load, rollout


@pytest.mark.parametrize("name", sorted(CASES))
def test_kinematic_steps_match_the_recorded_fingerprints(name: str) -> None:
    want = load()[name]
    got = rollout(name)
    assert len(got) == len(want), f"{name}: {len(got)} records, recorded {len(want)}"
    for a, b in zip(got, want, strict=True):
        assert a == b, f"{name}: seed {b['seed']} step {b['step']} differs"


def test_the_cases_cover_refused_failed_and_successful_actions() -> None:
    records = [r for name in CASES for r in load()[name]]
    assert any("error" in r for r in records)  # an action outside the space, refused
    assert len({r["reward"] for r in records if "reward" in r}) > 3  # different outcomes
