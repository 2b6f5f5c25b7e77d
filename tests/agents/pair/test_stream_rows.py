"""Stream rows: each tile's time left before the belt's end, the input belt's tiles, the file."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
import torch

import envs  # noqa: F401
from agents.errors import AgentError
from agents.experts.deadline import DeadlineExpert, belt_timing
from agents.learning.decision_bc import BCConfig
from agents.pair.adapters import FEATURE_DIMS, row_adapter
from agents.pair.state_bc import PairBCPolicy, fit_scorer
from agents.pair.stream_rows import TIME_SCALE_S, BeltTiming, stream_rows
from envs.observations.fields import SLOT_DIM, TILE_DIM

TIMING = BeltTiming(belt_speed=0.1, last_x=0.28, pick_y=(0.39, 0.61))


def _tiles(rows: list[tuple[float, float, float]]) -> torch.Tensor:
    """Flat ``tiles`` of tiles at (x, y, present), class 0, yaw 0."""
    out = np.zeros((len(rows), TILE_DIM), np.float32)
    for i, (x, y, present) in enumerate(rows):
        out[i, :3] = (x, y, 0.2)
        out[i, 3], out[i, 6] = 1.0, present
    return torch.as_tensor(out.reshape(-1))


def _slots(k: int = 2) -> torch.Tensor:
    out = np.zeros((k, SLOT_DIM), np.float32)
    out[:, 0], out[:, 1], out[:, 2] = 0.0, -0.5 + 0.05 * np.arange(k), 1.0
    return torch.as_tensor(out.reshape(-1))


def test_time_left_is_the_distance_to_the_last_saving_x_over_the_belt_speed() -> None:
    """A tile at x = 0.08 m has (0.28 - 0.08) / 0.1 = 2 s left (bug: x used as it is)."""
    rows = stream_rows(_tiles([(0.08, 0.5, 1), (0.23, 0.45, 1)]), _slots(), timing=TIMING)
    left = rows.tiles[0, :, 3] * TIME_SCALE_S
    assert left.tolist() == pytest.approx([2.0, 0.5], abs=1e-5)
    assert rows.tiles.shape[-1] == FEATURE_DIMS["stream"][0]


def test_only_tiles_on_the_input_belt_may_be_picked_and_while_none_is_any_index_waits() -> None:
    """Present tiles across the pick area only; an empty belt allows every index (env's rule)."""
    rows = stream_rows(
        _tiles([(0.1, 0.5, 1), (0.0, -0.5, 1), (-5.8, -1.0, 0)]), _slots(), timing=TIMING
    )
    assert rows.tile_mask[0].tolist() == [True, False, False]
    empty = stream_rows(_tiles([(0.0, -0.5, 1), (-5.8, -1.0, 0)]), _slots(), timing=TIMING)
    assert empty.tile_mask[0].tolist() == [True, True]


@pytest.mark.parametrize(
    ("kwargs", "words"),
    [
        ({"belt_speed": 0.0, "last_x": 0.28, "pick_y": (0.39, 0.61)}, "belt_speed"),
        ({"belt_speed": 0.1, "last_x": 0.28, "pick_y": (0.61, 0.39)}, "pick_y"),
    ],
)
def test_a_belt_timing_that_cannot_be_is_a_typed_error(kwargs: dict, words: str) -> None:
    with pytest.raises(AgentError, match=words):
        BeltTiming(**kwargs)


def test_a_stream_adapter_needs_its_timing_and_unknown_adapters_are_named() -> None:
    with pytest.raises(AgentError, match="belt timing"):
        row_adapter("stream")
    with pytest.raises(AgentError, match="allowed"):
        row_adapter("pixels")


def test_a_stream_clone_file_keeps_its_belt_and_plays_the_trained_choice(tmp_path) -> None:
    """Fit on one step repeated, write, load: the policy reads the same rows (timing saved)."""
    tiles = _tiles([(0.05, 0.5, 1), (0.2, 0.45, 1)])[None].repeat(8, 1)
    slots = _slots()[None].repeat(8, 1)
    nvec = np.array([2, 2, 4])
    y = torch.full((8,), int(np.ravel_multi_index((1, 0, 0), nvec)))
    rows = row_adapter("stream", TIMING.as_dict())(tiles, slots)
    cfg = BCConfig(
        arch="pair", hidden=16, layers=1, epochs=40, batch_size=8, learning_rate=1e-2,
        weight_decay=0.0,
    )  # fmt: skip
    _, _, path = fit_scorer(
        rows, y, nvec, cfg, adapter="stream", seed=0, out=tmp_path, adapter_args=TIMING.as_dict()
    )
    blob = torch.load(str(path), weights_only=True)
    assert BeltTiming.from_dict(blob["adapter_args"]) == TIMING
    action, _ = PairBCPolicy(blob).predict({"tiles": tiles[0].numpy(), "slots": slots[0].numpy()})
    assert action.tolist() == [1, 0, 0]


def test_the_deadline_expert_picks_the_wanted_tile_nearest_the_belt_s_end() -> None:
    """On the stream's first picture the tile farther downstream goes first (bug: upstream)."""
    env = gym.make("MosaicStream-v1")
    try:
        env.reset(seed=1003)
        expert = DeadlineExpert(env)
        u = env.unwrapped
        tile, slot = expert.choose()  # type: ignore[misc]
        on_belt = np.flatnonzero(u.cell.input_half())  # type: ignore[attr-defined]
        xs = np.asarray(u.task.ground_truth().xy)[on_belt, 0]  # type: ignore[attr-defined]
        assert len(on_belt) == 2 and tile == on_belt[int(np.argmax(xs))]
        assert u.task.slot_class[slot] == u.task.tile_class[tile]  # type: ignore[attr-defined]
        timing = belt_timing(env)
        assert timing.belt_speed == pytest.approx(0.1)
        assert timing.last_x == pytest.approx(0.3 - expert.cfg.end_margin)
    finally:
        env.close()


def test_the_deadline_expert_refuses_a_still_belt() -> None:
    env = gym.make("MosaicDecision6-v1")
    try:
        env.reset(seed=0)
        with pytest.raises(AgentError, match="belt_speed"):
            DeadlineExpert(env)
    finally:
        env.close()


@pytest.mark.parametrize(("yaw_deg", "index"), [(43.9, 0), (46.1, 3), (-46.1, 1), (180.0, 2)])
def test_each_pair_carries_the_tile_frame_s_rotation_index(yaw_deg: float, index: int) -> None:
    """-round(d / 90 deg) mod 4 for a tile d off its slot: the flip at 45 deg is given, not
    learned (a clone turned a tile lying 43.9 deg off by the wrong quarter)."""
    tiles = _tiles([(0.1, 0.5, 1)]).reshape(1, TILE_DIM)
    tiles[0, 3], tiles[0, 4] = np.cos(np.radians(yaw_deg)), np.sin(np.radians(yaw_deg))
    rows = stream_rows(tiles.reshape(-1), _slots(1), timing=TIMING)
    assert rows.pairs[0, 0, 0, -4:].tolist() == [float(i == index) for i in range(4)]
