"""agents.camera.crop_scorer: clone the expert from camera images, play it, refuse bad data."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

pytest.importorskip("minari")

from agents.camera.crop_bc import equivalent_turns  # noqa: E402
from agents.camera.crop_scorer import load_camera_bc_config  # noqa: E402
from agents.camera.crops import CropConfig, belt_tiles  # noqa: E402
from agents.errors import AgentError  # noqa: E402
from agents.policies import make_policies  # noqa: E402
from apps.bc.camera import train  # noqa: E402
from apps.evaluate import Protocol, evaluate_policy_set  # noqa: E402
from apps.record_demos import record  # noqa: E402
from envs.tasks import get_task  # noqa: E402

TASK = "MosaicDecision6-v0"
SIZE = [96, 128]
RGB = {"obs_mode": "rgb", "image_size": SIZE}
DATASET = "mosaic/camera-test-v0"


@pytest.fixture(scope="module")
def trained(tmp_path_factory) -> dict:
    """A camera policy trained for a few seconds on 6 expert episodes (seeds 0-5)."""
    root = tmp_path_factory.mktemp("demos")
    record(
        6,
        seed=0,
        root=root,
        dataset_id=DATASET,
        env_kwargs=RGB,
        expert=True,
        lossless=True,
        task=TASK,
    )
    return train(
        DATASET,
        root / "run",
        root=root,
        task_id=TASK,
        env_kwargs={"image_size": SIZE},
        seed=0,
        cfg=load_camera_bc_config(steps=150, eval_every=0),
    ) | {"root": root}


def test_camera_policy_learns_and_plays_by_its_file_name(trained) -> None:
    base = get_task(TASK).env_kwargs("eval")
    pols = make_policies([trained["model_path"], "random"], base)
    assert pols[0].env_kwargs["obs_mode"] == "rgb" and pols[0].env_kwargs["image_size"] == SIZE
    rows, _ = evaluate_policy_set(pols, Protocol((2000, 2001), (), 12))  # unseen seeds
    camera, random = rows[0].filled, rows[1].filled
    assert camera >= 0.5 and camera > random + 0.3, (camera, random)


def test_dataset_with_other_spaces_fails_at_load_naming_both(trained) -> None:
    with pytest.raises(AgentError, match=r"\(96, 128, 3\).*\(72, 96, 3\)"):
        train(
            DATASET,
            trained["root"] / "bad",
            root=trained["root"],
            task_id=TASK,
            env_kwargs={"image_size": [72, 96]},
        )


def test_symmetric_slots_accept_every_equivalent_turn() -> None:
    assert equivalent_turns(1, 1).tolist() == [False, True, False, False]
    assert equivalent_turns(1, 2).tolist() == [False, True, False, True]
    assert equivalent_turns(3, 4).all() and equivalent_turns(2, 0).all()
    assert equivalent_turns(0, 6).tolist() == [True, False, True, False]


def test_belt_blobs_are_ordered_downstream_first() -> None:
    env = gym.make(f"envs:{TASK}", **RGB)
    try:
        obs, _ = env.reset(seed=7)
        spec = env.get_wrapper_attr("task_spec")
        found = belt_tiles(
            obs["input_camera"], spec.camera("input_camera"), spec.pick.tile_top_z, CropConfig()
        )
    finally:
        env.close()
    assert len(found.xy) == 6
    assert np.all(np.diff(found.xy[:, 0]) <= 0)
    assert set(np.unique(found.labels)) == set(range(7))
