"""qshape.image_health: a typed verdict on a camera picture."""

from __future__ import annotations

import numpy as np
import pytest

import qshape
from qshape.vision.health import HealthParams, image_health


def test_verdicts() -> None:
    assert image_health(np.zeros((50, 60, 3), np.uint8)).verdict == "dark"
    assert image_health(np.full((50, 60, 3), 255, np.uint8)).verdict == "overexposed"
    belt = image_health(np.full((50, 60, 3), (61, 66, 71), np.uint8))
    assert belt.verdict == "uniform" and not belt.ok
    assert belt.color == pytest.approx((61 / 255, 66 / 255, 71 / 255))
    rng = np.random.default_rng(0)
    seen = np.clip(rng.normal(70, 3, (50, 60, 3)), 0, 255).astype(np.uint8)
    seen[10:30, 10:30] = (200, 60, 50)
    h = qshape.image_health(seen)
    assert h.ok and h.channel_span > 100 and 0.0 <= h.saturated_fraction < 0.01
    assert qshape.extract(np.full((50, 60, 3), (61, 66, 71), np.uint8)) == []


def test_bad_input_and_params() -> None:
    with pytest.raises(qshape.ImageError):
        image_health(np.zeros((50, 60), np.uint8))
    with pytest.raises(qshape.ImageError):
        HealthParams(saturated_fraction=0.0)
    assert HealthParams.load() == HealthParams.load(uniform_range=2)
