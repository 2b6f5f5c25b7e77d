"""agents.camera.continuous: the camera policy in pick_place places tiles within the tolerance."""

from __future__ import annotations

import dataclasses
import math
import sys
from collections.abc import Iterator
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

from agents.camera.continuous import ContinuousCameraPolicy, rotation_for, scaled_camera
from agents.errors import AgentError
from envs.tasks import get_task

TASK = "MosaicDecision6-v0"
CHECKPOINT = Path("checkpoints/MosaicDecision6-v0/BC_camera_crops_rgb/seed_0/camera.pt")
SEED = 1000


@pytest.fixture(scope="module")
def env() -> Iterator[gym.Env]:
    """The rung in the continuous pick_place mode, 96 x 128 images (the scorer's size)."""
    kwargs = get_task(TASK).env_kwargs("eval")
    e = gym.make(
        "envs:MosaicAssembly-v0",
        **{**kwargs, "action_mode": "pick_place", "obs_mode": "rgb", "image_size": [96, 128]},
    )
    yield e
    e.close()


def test_places_tiles_within_the_tolerance_from_the_pictures(env) -> None:
    policy = ContinuousCameraPolicy.load(CHECKPOINT)
    spec = env.get_wrapper_attr("task_spec")
    obs, _ = env.reset(seed=SEED)
    for _ in range(2):
        action, _ = policy.predict(obs, spec)
        assert action.shape == env.action_space.shape and np.all(np.abs(action) <= 1)
        obs, _, _, _, info = env.step(action)
    ev = info["evaluation"]  # the env's own measure: every tile on the mesh, nearest slot
    assert ev["correct"] == 2, ev
    assert ev["position_error_mm_max"] <= 1.5 and ev["yaw_error_deg_max"] <= 2.0, ev


def test_refuses_an_env_without_the_pick_place_codec(env) -> None:
    policy = ContinuousCameraPolicy.load(CHECKPOINT)
    obs, _ = env.reset(seed=SEED)
    spec = dataclasses.replace(env.get_wrapper_attr("task_spec"), codec=None)
    with pytest.raises(AgentError, match="pick_place"):
        policy.decide(obs, spec)


def test_rotation_takes_the_symmetric_turn_nearest_the_scorers_quarter_turn() -> None:
    ten = math.radians(10.0)
    assert rotation_for(ten, 4, 1) == pytest.approx(math.radians(80.0))  # square: any turn
    assert rotation_for(ten, 2, 0) == pytest.approx(-ten)
    assert rotation_for(ten, 2, 2) == pytest.approx(math.radians(170.0))
    assert rotation_for(ten, 1, 2) == pytest.approx(-ten)  # no symmetry: the fit decides
    assert rotation_for(ten, 0, 3) == 0.0  # round: never turned


def test_scaled_camera_keeps_pixel_centres(env) -> None:
    cam = env.get_wrapper_attr("task_spec").camera("input_camera")
    big = scaled_camera(cam, 2 * cam.height, 2 * cam.width)
    point = np.array([0.03, 0.52, 0.205])
    assert np.allclose(big.project(point), (cam.project(point) + 0.5) * 2 - 0.5)


def test_apps_evaluate_plays_it_from_the_scorer_file(tmp_path) -> None:
    """``--env action_mode=pick_place`` makes apps.evaluate play the scorer with the tile fit."""
    from apps.evaluate import main  # noqa: PLC0415

    args = ["--task", TASK, "--seeds", "1000", "--env", "action_mode=pick_place"]
    report = main([*args, "--policies", str(CHECKPOINT), "--out", str(tmp_path), "--quiet"])
    (row,) = report["rows"]
    assert row["policy"].endswith("camera@pick_place")
    assert row["env"]["action_mode"] == "pick_place" and row["env"]["image_size"] == [96, 128]
    assert row["filled"] == 1.0 and row["success_rate"] == 1.0  # seed 1000: all 6 slots


def _cli_error(monkeypatch, capsys, args: list[str]) -> str:
    """``python -m apps.evaluate args`` in this process: its one ``error:`` line (exit 1)."""
    from apps.cli import DEBUG_ENV, EXIT_ERROR, run_cli  # noqa: PLC0415
    from apps.evaluate import main  # noqa: PLC0415

    monkeypatch.setattr(sys, "argv", ["apps.evaluate", "--task", TASK, "--seeds", "1000", *args])
    monkeypatch.delenv(DEBUG_ENV, raising=False)
    with pytest.raises(SystemExit) as exc:
        run_cli(main)
    lines = capsys.readouterr().err.strip().splitlines()
    assert exc.value.code == EXIT_ERROR and len(lines) == 1 and lines[0].startswith("error:")
    return lines[0]


def test_apps_evaluate_names_a_wrong_action_mode_and_a_bad_path(
    monkeypatch, capsys, tmp_path
) -> None:
    out = ["--out", str(tmp_path)]
    line = _cli_error(
        monkeypatch, capsys, ["--env", "action_mode=cartesian", "--policies", str(CHECKPOINT), *out]
    )
    assert (
        "camera policy" in line and "'pick_place_discrete' or 'pick_place', not 'cartesian'" in line
    )
    line = _cli_error(monkeypatch, capsys, ["--policies", str(tmp_path / "camera.pt"), *out])
    assert "no such file; a .pt policy is a camera policy (apps.bc.camera)" in line
    (tmp_path / "junk.pt").write_bytes(b"not a torch file")
    line = _cli_error(monkeypatch, capsys, ["--policies", str(tmp_path / "junk.pt"), *out])
    assert "junk.pt is not a saved policy (unreadable" in line
