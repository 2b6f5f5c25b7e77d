"""agents.learning.decision_bc: clone the privileged expert from Minari demos, play it by file."""

from __future__ import annotations

import pytest

pytest.importorskip("minari")

from agents.learning.decision_bc import BCConfig, train_bc  # noqa: E402
from agents.policies import PolicyError, make_policies  # noqa: E402
from apps.evaluate import Protocol, evaluate_policy_set  # noqa: E402
from apps.record_demos import load, record  # noqa: E402
from tests.presets import FAST_DISCRETE

BASE = {**FAST_DISCRETE, "max_slots": 2}


def test_clone_fits_its_demos_and_plays(tmp_path) -> None:
    record(8, seed=0, root=tmp_path, dataset_id="mosaic/bc-v0", env_kwargs=BASE, expert=True)
    summary = train_bc(load("mosaic/bc-v0", tmp_path), tmp_path / "run", 0, BCConfig(epochs=150))
    assert summary["samples"] == 16 and summary["train_accuracy"] == 1.0
    pols = make_policies([summary["model_path"]], BASE)
    rows, _ = evaluate_policy_set(pols, Protocol((0, 1), (), 4))  # two demonstrated seeds
    assert rows[0].filled == 1.0  # it reproduces what it saw
    with pytest.raises(PolicyError, match="space"):
        evaluate_policy_set(
            make_policies([summary["model_path"]], {**BASE, "max_slots": 3}), Protocol((0,), (), 4)
        )
