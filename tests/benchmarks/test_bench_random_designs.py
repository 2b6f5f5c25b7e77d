"""The random-design benchmark: bundled config, a small real sample, totals and pictures."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from benchmarks.random_designs import FAILURE_KINDS, RandomDesignsBenchConfig, main, slot_outcomes
from configs import ConfigError, load_config
from envs.task import Placement
from qshape.design.generator import DesignGenerator
from qshape.design.generator_config import GeneratorConfig


def test_bundled_config_has_the_issue_targets() -> None:
    cfg = load_config(RandomDesignsBenchConfig, "bench_random_designs")
    by = {lv.name: lv for lv in cfg.levels}
    kin = by["ideal camera, kinematic"]
    assert kin.designs[1] - kin.designs[0] >= 200
    assert kin.env["execution"] == "kinematic"
    assert by["ideal camera, dynamic"].env["execution"] == "dynamic"
    assert "cell" in by["realistic camera, kinematic"].env
    for lv in cfg.levels:
        assert (lv.min_correct, lv.min_complete, lv.max_misplaced) == (0.995, 0.98, 0)
    with pytest.raises(ConfigError, match="designs"):
        RandomDesignsBenchConfig(levels=(type(kin)("x", designs=(3, 3)),))


def test_a_small_sample_plays_and_adds_up(tmp_path: Path) -> None:
    cfg = tmp_path / "bench.yaml"
    cfg.write_text(
        "generator: design_generator\n"
        "generator_overrides: {tiles: [4, 5], classes: [2, 3]}\n"
        "image_size: [492, 656]\n"
        "steps_per_slot: 2\n"
        "levels:\n"
        "  - {name: kinematic, designs: [0, 2], env: {execution: kinematic, feed: batch}}\n"
    )
    out = tmp_path / "out" / "bench.json"
    result = main(["--config", str(cfg), "--out", str(out)])
    (level,) = result["levels"]
    assert level["designs"] == 2 and 8 <= level["tiles"] <= 10
    assert json.loads(out.read_text())["levels"][0]["tiles"] == level["tiles"]
    open_slots = level["tiles"] - level["correct"]
    assert sum(level["failures"].values()) == open_slots
    assert set(level["failures"]) <= set(FAILURE_KINDS)
    assert sum(level["failed_families"].values()) == open_slots
    assert level["complete"] == sum(d["correct"] == d["slots"] for d in level["per_design"])
    # One picture per failure kind seen.
    assert len(result["pictures"]) == len(level["failures"])
    for path in result["pictures"].values():
        assert Path(path).stat().st_size > 1000
    assert result["wall_s"] > 0


def test_slot_outcomes_name_each_slot_its_family_and_its_tile() -> None:
    """Per slot: filled by the correct tile nearest it, or open with a wrong tile; their errors."""
    gen = DesignGenerator(GeneratorConfig.load(tiles=(4, 4), classes=(2, 2)))
    design = gen.draw(np.random.default_rng(3))
    nan = float("nan")
    # Tiles 0 and 1 fill slots 2 and 0; tile 2 lies wrong on slot 1; tile 3 is off the mesh.
    placement = Placement(
        on_mesh=np.array([True, True, True, False]),
        flat=np.array([True, True, True, False]),
        slot=np.array([2, 0, 1, -1]),
        position_error=np.array([0.0002, 0.0001, 0.004, nan]),
        yaw_error=np.radians([0.5, 1.5, 20.0, nan]),
        correct=np.array([True, True, False, False]),
        slot_filled=np.array([True, False, True, False]),
    )
    rows = slot_outcomes(design, placement)
    assert [r["name"] for r in rows] == [s.name for s in design.slots]
    assert [r["family"] for r in rows] == [s.name.split("_")[1] for s in design.slots]
    assert [r["filled"] for r in rows] == [True, False, True, False]
    assert [r["misplaced_here"] for r in rows] == [False, True, False, False]
    assert rows[0]["position_error_mm"] == pytest.approx(0.1)
    assert rows[0]["yaw_error_deg"] == pytest.approx(1.5)
    assert rows[2]["position_error_mm"] == pytest.approx(0.2)
    assert rows[1]["yaw_error_deg"] == pytest.approx(20.0)  # the misplaced tile on it
    assert rows[3]["yaw_error_deg"] is None and rows[3]["position_error_mm"] is None
