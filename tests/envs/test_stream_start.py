"""Where a stream's starting tiles lie: ``stream_start`` "random" (v0, v1) or "spaced" (v2).

A running stream leaves its tiles one supply period's belt travel apart; ``MosaicStream-v2``
starts so, and the belt scheduler's rule then saves both starting tiles in every episode, where
``-v1``'s random start loses one in about one episode in five whatever the order of picks.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import envs  # noqa: F401 - registers the ladder
from agents.experts.deadline import belt_timing
from agents.scripted.belt_config import load_belt_schedule_config
from agents.scripted.belt_schedule import deadline_order
from envs.cell.cell import Cell
from envs.cell.config import CellConfig, InputBeltConfig, TileConfig
from envs.cell.tiles.shapes import basic_shapes
from envs.errors import CellError
from envs.tasks import get_task

SEEDS = range(3000, 3040)


def _starts(task_id: str) -> list[tuple[np.ndarray, np.ndarray]]:
    """Per seed: the starting tiles' x along the belt [m] and their radii [m], in feed order."""
    env = gym.make(task_id)
    cell = env.unwrapped.cell
    out = []
    try:
        for seed in SEEDS:
            env.reset(seed=seed)
            first = env.unwrapped.cell.feed.order[: int(cell.on_stage.sum())]
            assert cell.on_stage[first].all()
            out.append((cell.data.xpos[cell.ids.tile_body][first, 0], cell.radii[first]))
    finally:
        env.close()
    return out


def test_v2_keeps_v1_and_starts_the_stream_spaced() -> None:
    v1, v2 = get_task("MosaicStream-v1"), get_task("MosaicStream-v2")
    assert dict(v2.env) == {**v1.env, "stream_start": "spaced"}
    assert gym.spec("MosaicStream-v2").kwargs["stream_start"] == "spaced"
    assert "stream_start" not in gym.spec("MosaicStream-v1").kwargs


def test_spaced_tiles_lie_a_period_of_belt_travel_apart_inside_the_tile_area() -> None:
    task = get_task("MosaicStream-v2")
    env = gym.make(task.id)
    try:
        env.reset(seed=0)
        cell = env.unwrapped.cell
        cfg = cell.cfg
        step = cfg.tiles.stream_period * cfg.input_belt.speed
        half = cfg.input_belt.tile_area[0] / 2
        centre = cell.geometry.input_centre[0]
    finally:
        env.close()
    # a centre lies within the strip's clearance of where it was put, and the reset's first
    # physics steps carry it on a few mm (each picks the belt's speed up in its own time)
    slack = cfg.tiles.min_gap + 0.004
    shortened = 0
    for x, r in _starts(task.id):
        old, new = 0, 1  # feed order: the oldest tile first
        assert len(x) == 2
        spawn = centre - half + r[new] + cfg.tiles.min_gap  # the newest: in the spawn strip
        assert abs(x[new] - spawn) < slack
        # the oldest a period's travel further on, or less where that would reach past the
        # tile area (it lies inside, seen whole)
        edge = centre + half - r[old] - cfg.tiles.min_gap
        assert x[old] < edge + slack
        free = (x[old] - r[old]) - (x[new] - r[new])
        assert free < step + 2 * slack
        if free < step - 2 * slack:
            shortened += 1
            assert x[old] == pytest.approx(edge, abs=slack)
    assert shortened > 0  # the tile area (0.30 m) is shorter than a period's travel plus a tile


def _saved_by_the_schedule(task_id: str) -> list[bool]:
    cfg = load_belt_schedule_config()
    env = gym.make(task_id)
    try:
        timing = belt_timing(env, cfg)
    finally:
        env.close()
    speed, last_x = timing.belt_speed, timing.last_x
    return [
        deadline_order(x, speed, last_x, cfg.first_reach_s, cfg.cycle_s).saves_all
        for x, _ in _starts(task_id)
    ]


def test_every_v2_start_can_be_saved_where_v1_starts_cannot() -> None:
    assert all(_saved_by_the_schedule("MosaicStream-v2"))
    v1 = _saved_by_the_schedule("MosaicStream-v1")
    assert 0 < v1.count(False) < len(v1) / 2


def test_spaced_start_needs_a_moving_belt_and_room() -> None:
    tiles = {"feed": "stream", "stream_start": "spaced", "stream_period": 2.5}

    def cell_config(speed: float, initial: int) -> CellConfig:
        belt = InputBeltConfig(speed=speed)
        return CellConfig(input_belt=belt, tiles=TileConfig(stream_initial=initial, **tiles))

    with pytest.raises(CellError, match=r"stream_start 'spaced'.*> 0 and < the tile area"):
        cell_config(0.0, 2)
    with pytest.raises(CellError, match=r"lays 3 tiles 0\.250 m apart"):
        cell_config(0.1, 3)
    with pytest.raises(CellError, match=r"stream_start.*allowed"):
        TileConfig(stream_start="bunched")  # type: ignore[arg-type]
    cell = Cell(cell_config(0.0, 1), basic_shapes(), seed=2)  # a single tile needs no travel
    try:
        assert cell.on_stage.sum() == 1
    finally:
        cell.close()
