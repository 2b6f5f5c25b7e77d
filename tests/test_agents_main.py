"""The main job: report keys and figures (vision only by default; the full run is slow)."""

from __future__ import annotations

import json

import pytest

from agents.main import main

KEYS = {"tiles_total", "correct", "misplaced", "dropped", "success", "tiles_per_min", "wall_s"}


def test_vision_only_run_writes_the_report(tmp_path):
    report = main(["--no-execute", "--quiet", "--out", str(tmp_path)])
    assert KEYS <= set(report)
    assert report["recognised_correct_class"] == report["tiles_total"] == 16
    assert report["pick_error_max_mm"] < 2.0 and report["yaw_error_max_deg"] < 2.0
    assert report["calibration_input_camera"]["reprojection_px"] < 0.5
    saved = json.loads((tmp_path / "report.json").read_text())
    assert saved["tiles_total"] == 16
    for name in ("report.txt", "input_camera_annotated.png", "output_camera_annotated.png"):
        assert (tmp_path / name).is_file()


@pytest.mark.slow
def test_full_run_places_every_tile(tmp_path):
    report = main(["--quiet", "--out", str(tmp_path)])
    assert report["success"] and report["correct"] == 16
    assert report["misplaced"] == 0 and report["dropped"] == 0
    assert (tmp_path / "cell.mp4").is_file()


def test_a_design_that_fails_validation_is_a_clear_error(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text(
        "name: bad\nmesh: {width: 50, height: 50}\njoint: 2\nslots:\n"
        "- name: a\n  shape: {kind: square, size: 40}\n  color: '#ff0000'\n"
        "  pose: {x: 10, y: 10, angle: 0}\n"
    )
    with pytest.raises(SystemExit, match="error: .*"):
        main(["--no-execute", "--quiet", "--design", str(bad), "--out", str(tmp_path)])
