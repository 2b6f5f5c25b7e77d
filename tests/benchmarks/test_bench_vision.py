"""The recognition benchmarks: the old benchmark's command line (scale override, refusal of bad
input) and the realistic benchmark's machinery on a tiny run (levels, lens, table, plot)."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from apps.cli import UsageError
from benchmarks.recognition import synthetic as vision
from benchmarks.recognition.realistic import Level, RealisticBench, markdown, plot, run_level
from configs import load_config
from qshape.synthetic.effects import CameraEffects
from qshape.synthetic.synth import SynthParams
from qshape.vision.params import ExtractParams


def test_pictures_at_another_scale(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "vision.json"
    vision.main(["--images", "1", "--designs", "hexagon", "--px-per-mm", "1.8", "--out", str(out)])
    result = json.loads(out.read_text())
    assert result["params"]["px_per_mm"] == 1.8
    rows = result["levels"]
    assert set(rows) == {"hexagon@0", "hexagon@1", "hexagon@2", "hexagon@3"}
    for row in rows.values():
        assert row["tiles"] > 0
        assert row["false_matches_shape"] == 0 and row["false_matches_shape_color"] == 0
    assert rows["hexagon@0"]["shape_accuracy"] == 1.0
    assert result["timing"]["figures"] == 30
    assert "timing on 656 x 492 px" in capsys.readouterr().out


@pytest.mark.parametrize("bad", ["0", "-2", "nan"])
def test_a_bad_scale_is_refused(bad: str, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(UsageError, match="--px-per-mm must be a positive number"):
        vision.main(["--timing-only", "--px-per-mm", bad])


def _bench() -> RealisticBench:
    return replace(load_config(RealisticBench, "bench_vision_realistic"), designs=("square_grid",))


def test_config_sweeps_every_effect_and_sizes_the_target_level() -> None:
    bench = load_config(RealisticBench, "bench_vision_realistic")
    effects = {lv.effect for lv in bench.levels}
    for name in (
        "edge roughness",
        "chipped corners",
        "motion blur",
        "jpeg",
        "lens distortion",
        "soft shadow",
        "glaze highlights",
        "illumination gradient",
        "touching tiles",
        "partial tiles",
        "realistic",
    ):
        assert name in effects
    # >= 1000 whole tiles at the target level (about 11 whole tiles per picture).
    assert bench.target_images * len(bench.designs) * 11 >= 1000


def test_lensed_pictures_are_undistorted_before_extraction(
    synth_params: SynthParams, extract_params: ExtractParams
) -> None:
    bench = _bench()
    lens = Level("lens distortion", "k1 -0.3", effects=CameraEffects(lens_k1=-0.3))
    sp, ep = synth_params, extract_params
    undist = run_level(lens, 1, bench, sp, ep, np.random.default_rng(3))
    raw = run_level(lens, 1, replace(bench, undistort=False), sp, ep, np.random.default_rng(3))
    assert undist["tiles"] == raw["tiles"] > 0
    assert undist["class_accuracy"] == 1.0 and undist["false_matches"] == 0
    assert undist["rotation_err_deg_max"] < raw["rotation_err_deg_max"]


@pytest.mark.slow
def test_table_and_plot_are_written(
    tmp_path: Path, synth_params: SynthParams, extract_params: ExtractParams
) -> None:
    bench = _bench()
    sp, ep = synth_params, extract_params
    rows = [
        run_level(lv, 1, bench, sp, ep, np.random.default_rng(1))
        for lv in (
            Level("none", "default noise"),
            Level("jpeg", "q75", effects=CameraEffects(jpeg_quality=75)),
        )
    ]
    text = markdown(rows, "2026-01-01")
    assert "| jpeg | q75 |" in text and "2026-01-01" in text
    path = tmp_path / "plot.png"
    plot(rows, path)
    assert path.stat().st_size > 1000
