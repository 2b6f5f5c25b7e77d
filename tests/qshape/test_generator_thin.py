"""The generator's ``thin`` family: concave tiles with sharp tips, valid and drawn."""

from __future__ import annotations

import math
import warnings

import numpy as np

from qshape.design.generator import DesignGenerator
from qshape.design.generator_config import BASE_FAMILIES, GeneratorConfig


def _corners_deg(points: np.ndarray) -> np.ndarray:
    prev, nxt = np.roll(points, 1, axis=0) - points, np.roll(points, -1, axis=0) - points
    cos = np.sum(prev * nxt, axis=1) / (np.linalg.norm(prev, axis=1) * np.linalg.norm(nxt, axis=1))
    return np.degrees(np.arccos(np.clip(cos, -1, 1)))


def test_thin_designs_hold_sharp_concave_tiles() -> None:
    cfg = GeneratorConfig.load(families={"thin": 1.0})
    sharp = concave = 0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for seed in range(4):
            design = DesignGenerator(cfg).draw(np.random.default_rng(seed))
            for s in design.slots:
                v = s.local_path.outer.vertices
                sharp += int(_corners_deg(v).min() < 35.0)
                turn = np.cross(np.roll(v, -1, axis=0) - v, v - np.roll(v, 1, axis=0))
                concave += int(np.any(turn < 0))
    assert sharp > 0 and concave > 0


def test_the_default_families_are_unchanged() -> None:
    assert set(GeneratorConfig().families) == set(BASE_FAMILIES)
    assert (
        "thin" not in GeneratorConfig.load().families or not GeneratorConfig.load().families["thin"]
    )
    assert math.isfinite(len(BASE_FAMILIES))
