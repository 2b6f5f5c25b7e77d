"""agents.learning.classifier_fit: the clones' one training loop fits, counts steps, repeats."""

from __future__ import annotations

import torch

from agents.learning.classifier_fit import fit_classifier
from agents.learning.decision_bc import BCConfig


def _fit(seed: int):
    torch.manual_seed(0)
    x = torch.randn(90, 2)
    y = (x[:, 0] > x[:, 1]).long() + 2 * (x[:, 0] > 0).long()  # four separable classes
    net = torch.nn.Linear(2, 4)
    settings = BCConfig(epochs=60, batch_size=32, learning_rate=0.05, weight_decay=0.0)
    fit = fit_classifier(
        lambda idx: net(x if idx is None else x[idx]),
        net.parameters(),
        y,
        settings,
        seed,
        accuracy=True,
    )
    return fit, net


def test_fit_learns_a_separable_problem_and_reports_its_curve() -> None:
    fit, _ = _fit(0)
    assert fit.gradient_steps == 60 * 3  # 90 samples in batches of 32: 3 per epoch
    assert len(fit.curve) == 60 and fit.curve[-1]["gradient_steps"] == 180
    assert fit.curve[0]["train_accuracy"] < 0.9 <= fit.curve[-1]["train_accuracy"]
    assert fit.curve[-1]["loss"] < fit.curve[0]["loss"]
    assert 0.0 < fit.last_batch_loss


def test_fit_is_repeatable_by_its_seed() -> None:
    (a, net_a), (b, net_b), (c, _) = _fit(1), _fit(1), _fit(2)
    assert a == b and torch.equal(net_a.weight, net_b.weight)
    assert a.curve != c.curve  # another batch order
