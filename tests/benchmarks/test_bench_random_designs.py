"""The random-design benchmark: bundled config, a small real sample, totals and pictures."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from benchmarks.random_designs import FAILURE_KINDS, RandomDesignsBenchConfig, main
from configs import ConfigError, load_config


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
