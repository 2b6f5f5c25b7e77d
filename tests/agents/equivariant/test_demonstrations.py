"""agents.equivariant: demonstrations by disassembly and from the expert, their files, training
and play on unseen shapes, and the refusals of files and pictures made for something else."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
import torch

from agents.equivariant.collect import collect
from agents.equivariant.config import EquivariantConfig
from agents.equivariant.policy import EquivariantPolicy, save_policy
from agents.equivariant.records import RecordsError, load_records, save_records
from agents.equivariant.train import train
from agents.errors import AgentError
from envs.tasks import get_task
from spatial.angles import symmetry_period

TASK = "MosaicHeldOutDesigns-v1"
SIZE = (96, 128)
CFG = EquivariantConfig(steps=40)


@pytest.fixture(scope="module")
def records() -> dict:
    """One episode of each source on the same seed (the training design paper_mixed)."""
    sources = ("disassembly", "expert")
    return {src: collect(TASK, src, 1, CFG, image_size=SIZE, seed=123) for src in sources}


def test_disassembly_reversed_demonstrates_what_the_expert_does(records) -> None:
    """Every tile once, into its own slot, with the turn the expert makes (modulo the figure's
    symmetry): the disassembly puts each tile back where the reset laid it, so the state with
    every tile on the belt is the expert's first."""
    dis, exp = records["disassembly"], records["expert"]
    assert len(dis.tile) == len(exp.tile) == 6
    assert dis.tile_ok.sum(1).tolist() == [1, 2, 3, 4, 5, 6]  # removal order: one more each
    assert exp.tile_ok.sum(1).tolist() == [6, 5, 4, 3, 2, 1]
    full_d, full_e = int(np.argmax(dis.tile_ok.sum(1))), 0
    np.testing.assert_allclose(
        dis.tiles[full_d].astype(float), exp.tiles[full_e].astype(float), atol=40
    )  # same picture up to where the robot set each tile down (sub-millimetre)

    def turns(rec) -> dict[int, float]:
        out = {}
        for s in range(len(rec.tile)):
            j = int(rec.slot[s])
            period = symmetry_period(int(rec.symmetry[s, j])) or 2 * math.pi
            out[round(float(rec.slot_ok[s].sum()))] = rec.turn[s] % period
        return out

    # the turn of the step with m open slots: the same tile in both? compare as sets per design
    assert sorted(np.round(np.sort([v for v in turns(dis).values()]), 3)) == sorted(
        np.round(np.sort([v for v in turns(exp).values()]), 3)
    )


def test_records_file_round_trip_and_refusals(records, tmp_path) -> None:
    rec = records["disassembly"]
    path = save_records(tmp_path / "d.npz", rec)
    back = load_records(path, task=TASK, cfg=CFG, image_size=SIZE)
    np.testing.assert_array_equal(back.tiles, rec.tiles)
    assert back.header == rec.header
    with pytest.raises(RecordsError, match="of MosaicHeldOutDesigns-v1, not of MosaicDecision6-v1"):
        load_records(path, task="MosaicDecision6-v1")
    with pytest.raises(RecordsError, match="96x128 images; expected 72x96"):
        load_records(path, image_size=(72, 96))
    with pytest.raises(RecordsError, match="crop settings"):
        load_records(path, cfg=EquivariantConfig(grid=20))
    (tmp_path / "x.npz").write_bytes(b"not a file")
    with pytest.raises(RecordsError, match="not a demonstrations file"):
        load_records(tmp_path / "x.npz")


@pytest.fixture(scope="module")
def policy(records, tmp_path_factory) -> tuple[EquivariantPolicy, object]:
    net, curve = train(records["disassembly"], CFG, seed=0)
    path = save_policy(
        tmp_path_factory.mktemp("pol") / "model.pt", net, CFG, {"image_size": list(SIZE)}
    )
    return EquivariantPolicy.load(path), path


def test_one_disassembled_mosaic_teaches_it_to_fill_an_unseen_design(policy) -> None:
    """Trained on one paper_mixed episode taken apart, it fills trencadis shards (never seen)
    on a held-out seed, counting turns modulo the figure's symmetry."""
    pol, _ = policy
    task = get_task(TASK)
    env = gym.make(
        TASK,
        **{
            **task.env_kwargs("eval", 1),
            "obs_mode": "rgb",
            "image_size": list(SIZE),
            "rotation_frame": "shape",
        },
    )
    try:
        obs, _ = env.reset(seed=1001)
        u = env.unwrapped
        for _ in range(task.max_episode_steps):
            action, _ = pol.predict(obs, env.get_wrapper_attr("task_spec"), u.action_masks())
            obs, _, terminated, truncated, info = env.step(action)
            if terminated or truncated:
                break
        ev = info["evaluation"]
        assert ev["correct"] >= ev["slots"] - 1, ev
    finally:
        env.close()


def test_policy_refuses_other_pictures_and_files(policy, tmp_path) -> None:
    pol, _ = policy
    spec = None
    with pytest.raises(AgentError, match="obs_mode 'rgb'"):
        pol.turn_scores({"tiles": np.zeros(3)}, spec)
    small = {
        "input_camera": np.zeros((72, 96, 3), np.uint8),
        "output_camera": np.zeros((72, 96, 3), np.uint8),
    }
    with pytest.raises(AgentError, match=r"trained on 96x128 images, got 72x96"):
        pol.turn_scores(small, spec)
    other = tmp_path / "other.pt"
    torch.save({"kind": "camera_crops", "state_dict": {}}, other)
    with pytest.raises(AgentError, match="not an equivariant policy"):
        EquivariantPolicy.load(other)
    wrong = tmp_path / "wrong.pt"
    torch.save({"kind": "equivariant", "state_dict": {}, "config": {"turns": 30}}, wrong)
    with pytest.raises(AgentError, match="wrong entry"):
        EquivariantPolicy.load(wrong)
