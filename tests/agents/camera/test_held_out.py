"""agents.camera.crop_bc on MosaicHeldOutDesigns-v0's training designs, per episode."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("minari")

from agents.camera.crop_bc import demo_arrays, episode_specs  # noqa: E402
from agents.camera.crop_scorer import load_camera_bc_config  # noqa: E402
from agents.camera.crops import slot_templates  # noqa: E402
from agents.policies import make_policies  # noqa: E402
from apps.bc.camera import train  # noqa: E402
from apps.evaluate import Protocol, evaluate_policy_set  # noqa: E402
from apps.record_demos import load, record  # noqa: E402
from envs.tasks import get_task  # noqa: E402

TASK = "MosaicHeldOutDesigns-v0"
SIZE = [96, 128]
PROCEDURAL = get_task(TASK).design_kwargs("train", 2)
DATASET = "mosaic/camera-held-out-test-v0"
FIXED = "mosaic/camera-held-out-test-paper-mixed-v0"


@pytest.fixture(scope="module")
def recorded(tmp_path_factory) -> dict:
    """Expert episodes on two training designs: procedural (a new design per seed, 0-5) and
    paper_mixed (seeds 0-5)."""
    root = tmp_path_factory.mktemp("demos")
    for dataset_id, design in ((DATASET, PROCEDURAL), (FIXED, {})):
        record(
            6,
            seed=0,
            root=root,
            dataset_id=dataset_id,
            env_kwargs={"obs_mode": "rgb", "image_size": SIZE, **design},
            expert=True,
            lossless=True,
            task=TASK,
        )
    return {"root": root, "dataset": load(DATASET, root)}


def test_each_episode_gets_its_own_design(recorded) -> None:
    dataset = recorded["dataset"]
    specs = episode_specs(dataset, 3)
    assert len({tuple(s.name for s in spec.slots) for spec in specs}) == 3
    # the rebuilt episode is the recorded one: same first image, and its templates reach the crops
    data = demo_arrays(dataset, specs, load_camera_bc_config(), 3)
    first = next(iter(dataset.iterate_episodes([0])))
    env = dataset.recover_environment()
    try:
        obs, _ = env.reset(seed=0)
    finally:
        env.close()
    assert np.array_equal(obs["input_camera"], first.observations["input_camera"][0])
    crop = load_camera_bc_config().crop()
    assert np.array_equal(data.templates[0], slot_templates(specs[0], crop))
    assert any(np.array_equal(t, slot_templates(specs[1], crop)) for t in data.templates)
    assert not np.array_equal(data.templates[0], data.templates[-1])


@pytest.mark.slow
def test_held_out_training_path_learns_training_designs(recorded) -> None:
    summary = train(
        [DATASET, FIXED],
        recorded["root"] / "run",
        root=recorded["root"],
        task_id=TASK,
        env_kwargs={"image_size": SIZE, **PROCEDURAL},
        cfg=load_camera_bc_config("camera_bc_held_out", steps=150, eval_every=0),
    )
    assert summary["demos"] == 12 and summary["samples"] + summary["skipped_steps"] == 72
    base = get_task(TASK).env_kwargs("train", 0)  # paper_mixed
    pols = make_policies([summary["model_path"], "random"], base)
    rows, _ = evaluate_policy_set(pols, Protocol((2000, 2001), (), 12))  # unseen seeds
    camera, random = rows[0].filled, rows[1].filled
    assert camera > random + 0.2, (camera, random)
