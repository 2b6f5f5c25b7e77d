"""apps.record_demos: 2 short scripted episodes as a Minari dataset, loaded back, replayed."""

from __future__ import annotations

import pytest

pytest.importorskip("minari")
pytest.importorskip("jax")

from apps.record_demos import DemoError, load, record, replay  # noqa: E402

ENV = {"max_slots": 2}


@pytest.mark.slow
def test_record_load_replay(tmp_path):
    rec = record(
        2, seed=7, root=tmp_path, dataset_id="mosaic/test-v0", env_kwargs=ENV, calibrate=False
    )
    assert rec.episodes == 2 and rec.seeds == (7, 8) and rec.success_rate == 1.0
    assert rec.steps >= 4 and rec.path.is_relative_to(tmp_path)
    ds = load("mosaic/test-v0", tmp_path)
    assert ds.total_episodes == 2 and ds.total_steps == rec.steps
    eps = list(ds.iterate_episodes())
    assert eps[0].actions.shape[1] == 6
    assert eps[0].observations["tiles"].shape[0] == len(eps[0]) + 1
    assert "input_camera" in eps[0].observations
    rep = replay(ds)
    assert rep.episodes == 2 and rep.matching_episodes == 2 and rep.replayed_success == 2
    assert rep.max_state_error == 0.0 and rep.max_reward_error == 0.0
    with pytest.raises(DemoError, match="exists"):
        record(1, root=tmp_path, dataset_id="mosaic/test-v0", env_kwargs=ENV, calibrate=False)


def test_discrete_expert_demos_at_training_size_lossless(tmp_path):
    import gymnasium as gym  # noqa: PLC0415
    import numpy as np  # noqa: PLC0415

    rec = record(
        2,
        seed=3,
        root=tmp_path,
        dataset_id="mosaic/expert-v0",
        expert=True,
        lossless=True,
        task="MosaicDecision6-v0",
    )
    assert rec.success_rate == 1.0 and rec.steps == 12
    ds = load("mosaic/expert-v0", tmp_path)
    ep = next(iter(ds.iterate_episodes()))
    assert ep.actions.shape == (6, 3)  # (tile, slot, rotation) per step
    assert ep.observations["input_camera"].shape[1:] == (72, 96, 3)
    # Lossless: the stored first image is exactly what the env renders at that reset.
    env = gym.make("MosaicDecision6-v0", obs_mode="rgb+state")
    obs, _ = env.reset(seed=3)
    env.close()
    assert np.array_equal(ep.observations["input_camera"][0], obs["input_camera"])
    rep = replay(ds)
    assert rep.matching_episodes == 2 and rep.replayed_success == 2


@pytest.mark.parametrize("bad", ["mosaic/no-version", "mosaic/name-vx", "v0"])
def test_a_dataset_id_without_a_version_is_refused_before_recording(tmp_path, bad):
    """Minari reads the version off the id and failed with a bare TypeError after recording."""
    with pytest.raises(DemoError, match=r"not Minari's form: \[namespace/\]name-vN"):
        record(1, root=tmp_path, dataset_id=bad, env_kwargs=ENV, calibrate=False)
    assert not any(tmp_path.rglob("*.hdf5"))
