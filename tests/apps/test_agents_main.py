"""The main job: report keys and figures, the video, bad input (the full run is slow)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from apps.main import main
from qshape import QShapeError

ROOT = Path(__file__).resolve().parents[2]

KEYS = {"tiles_total", "correct", "misplaced", "dropped", "success", "tiles_per_min", "wall_s"}


def test_vision_only_run_writes_the_report(tmp_path):
    report = main(["--no-execute", "--quiet", "--out", str(tmp_path)])
    assert KEYS <= set(report)
    assert report["recognised_correct_class"] == report["tiles_total"] == 16
    assert report["pick_error_max_mm"] < 2.0 and report["yaw_error_max_deg"] < 2.0
    assert report["calibration_input_camera"]["reprojection_px"] < 0.5
    assert report["steps"] == 0 and report["correct"] == 0
    saved = json.loads((tmp_path / "report.json").read_text())
    assert saved["tiles_total"] == 16
    for name in ("report.txt", "input_camera_annotated.png", "output_camera_annotated.png"):
        assert (tmp_path / name).is_file()


def test_short_run_places_through_the_env_and_films_both_cameras(tmp_path):
    report = main(["--quiet", "--max-slots", "3", "--true-camera", "--out", str(tmp_path)])
    assert report["success"] and report["correct"] == report["tiles_total"] == 3
    assert report["steps"] == 3 and report["failed_actions"] == 0
    assert report["misplaced"] == report["dropped"] == 0
    assert report["tiles_per_min"] > 0 and report["sim_s"] > 3
    video = tmp_path / "cell.mp4"
    cap = cv2.VideoCapture(str(video))
    frames = []
    ok, frame = cap.read()
    while ok:
        frames.append(frame)
        ok, frame = cap.read()
    cap.release()
    # a frame every 0.1 s of simulated time: the motion inside each cycle, not one per step
    assert len(frames) >= report["sim_s"] * 10 - 2
    h, w = frames[0].shape[:2]
    assert w > h  # overview on the left, the two camera views stacked on the right
    right = frames[len(frames) // 2][:, w - w // 3 :]
    # annotations: red relevant points (BGR) on the input view, green/white slot marks below
    red = (right[..., 2] > 200) & (right[..., 1] < 60) & (right[..., 0] < 60)
    assert red[: h // 2].sum() > 20
    assert not np.array_equal(frames[0], frames[-1])


def test_distractors_are_reported_and_never_placed(tmp_path):
    args = ["--no-execute", "--max-slots", "10", "--distractor-rate", "0.3"]
    report = main([*args, "--quiet", "--out", str(tmp_path)])
    reasons = {u["reason"] for u in report["unplaced"]}
    assert reasons and reasons <= {"shape_absent", "color_absent"}
    assert report["recognised_correct_class"] == 10  # every command targets a real tile
    assert "not placed: tile" in (tmp_path / "report.txt").read_text()


@pytest.mark.slow
def test_full_run_places_every_tile(tmp_path):
    report = main(["--quiet", "--out", str(tmp_path)])
    assert report["success"] and report["correct"] == 16
    assert report["misplaced"] == 0 and report["dropped"] == 0
    assert report["tiles_per_min"] >= 24.0
    assert (tmp_path / "cell.mp4").is_file()


def test_a_design_that_fails_validation_is_a_clear_error(tmp_path, yaml_file):
    bad = yaml_file(
        "name: bad\nmesh: {width: 50, height: 50}\njoint: 2\nslots:\n"
        "- name: a\n  shape: {kind: square, size: 40}\n  color: '#ff0000'\n"
        "  pose: {x: 10, y: 10, angle: 0}\n"
    )
    with pytest.raises(QShapeError):
        main(["--no-execute", "--quiet", "--design", str(bad), "--out", str(tmp_path)])


def test_command_line_reports_a_bad_setting_in_one_line(tmp_path):
    proc = subprocess.run(
        [sys.executable, "-m", "apps.main", "--quiet", "--belt-speed", "-1"]
        + ["--out", str(tmp_path)],
        capture_output=True,
        text=True,
        check=False,
    )
    assert proc.returncode != 0
    assert proc.stderr.strip().splitlines()[-1].startswith("error: run: belt_speed")


@pytest.mark.slow
def test_the_main_job_waits_through_an_empty_stream_belt_to_the_end(tmp_path):
    # Between streamed tiles the belt is empty (a uniform picture): the job waits and goes on.
    args = ["--feed", "stream", "--belt-speed", "0.1", "--max-slots", "4", "--true-camera"]
    report = main([*args, "--quiet", "--out", str(tmp_path)])
    assert report["correct"] == 4
    assert report["success"]
    assert report["feed"] == "stream"


DOCUMENTED = [
    [],
    ["--belt-speed", "0.1", "--feed", "stream"],
    ["--distractor-rate", "0.3"],
]
"""The README's main-job commands (``python -m apps.main ...``)."""


@pytest.mark.slow
@pytest.mark.parametrize("args", DOCUMENTED, ids=lambda a: " ".join(a) or "default")
def test_documented_commands_run_headless_as_written(tmp_path, args):
    # No MUJOCO_GL and no display, as on a fresh headless machine.
    env = {k: v for k, v in os.environ.items() if k not in ("MUJOCO_GL", "PYOPENGL_PLATFORM")}
    env.pop("DISPLAY", None)
    env["PYTHONPATH"] = str(ROOT)
    cmd = [sys.executable, "-m", "apps.main", *args, "--quiet", "--out", str(tmp_path)]
    done = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr[-2000:]
    report = json.loads((tmp_path / "report.json").read_text())
    assert report["correct"] >= report["tiles_total"] - 1
    assert report["distractors_placed"] == 0


@pytest.mark.slow
def test_the_main_job_takes_a_drawing_and_another_cell(tmp_path):
    """A DXF design on its own 300 mm mesh builds; a cell taking less names its largest mesh."""
    from agents.scripted.config import RunConfig  # noqa: PLC0415
    from apps.main import make_env  # noqa: PLC0415
    from envs.errors import MeshSizeError  # noqa: PLC0415

    env = make_env(RunConfig(design="configs/designs/catalogue.dxf"))
    try:
        assert env.unwrapped.cell.geometry.mesh_size == pytest.approx([0.3, 0.3])
        assert "input_depth" in env.observation_space.spaces  # the height picture
    finally:
        env.close()
    small = {"cell": {"output_belt": {"max_mesh_size": [0.25, 0.25]}}}
    with pytest.raises(MeshSizeError, match="largest mesh it takes is 250 x 250 mm"):
        make_env(RunConfig(design="catalogue"), env_over=small)
