"""The scripted cell's belt scheduler: deadlines, the tiles it follows out of view, its settings.

Pure checks of the order (earliest deadline first, tiles past saving rejected, a set no order
saves) and of placing a tile cut by the view's edge; the settings' validation; and, on the
stream rung itself (dynamic execution), the first picture's two tiles: the one nearer the
belt's end is picked first, and the other, carried out of the camera's view meanwhile, is
picked where the scheduler follows it and placed in its slot.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from shapely.affinity import translate
from shapely.geometry import Polygon, box

import envs  # noqa: F401 - registers the env
from agents.errors import AgentError
from agents.policies import make_policies
from agents.scripted.agent import ScriptedAgent
from agents.scripted.belt_config import (
    BeltScheduleConfig,
    BeltScheduleError,
    load_belt_schedule_config,
)
from agents.scripted.belt_schedule import deadline_order
from agents.scripted.belt_tracks import slid_into_view
from apps.evaluate import task_protocol
from configs import ConfigError

SPEED = 0.1  # m/s
LAST_X = 0.28  # m
REACH = 1.2  # s
CYCLE = 2.3  # s


def test_the_tile_with_the_nearest_deadline_is_picked_first():
    s = deadline_order([-0.31, 0.12, -0.08], SPEED, LAST_X, REACH, CYCLE)
    assert s.order == (1, 2, 0)
    assert s.saves_all
    np.testing.assert_allclose(s.deadlines, [5.9, 1.6, 3.6])


def test_a_tile_past_saving_is_rejected_not_picked():
    s = deadline_order([0.2, -0.1], SPEED, LAST_X, REACH, CYCLE)  # 0.8 s left < 1.2 s reach
    assert s.order == (1,)
    assert s.rejected == (0,)
    assert not s.saves_all


def test_when_no_order_saves_every_tile_the_urgent_one_keeps_its_place():
    # Both leave within 1.7 s; the second pick's contact comes 2.3 s after the first.
    s = deadline_order([0.12, 0.11], SPEED, LAST_X, REACH, CYCLE)
    assert s.order == (0,)
    assert s.deferred == (1,)
    assert s.rejected == ()


@pytest.mark.parametrize("x", [0.150, 0.158, 0.166])
def test_a_tile_cut_by_the_view_s_edge_is_placed_by_its_visible_area(x):
    view = (np.array([-0.16, 0.38]), np.array([0.16, 0.62]))
    ring = Polygon(
        [(0.015 * np.cos(a), 0.015 * np.sin(a)) for a in np.linspace(0, 2 * np.pi, 64)[:-1]],
        [[(0.007 * np.cos(a), 0.007 * np.sin(a)) for a in np.linspace(0, 2 * np.pi, 64)[:-1]]],
    )
    y = 0.45
    seen = ring.buffer(0)
    area = translate(seen, xoff=x, yoff=y).intersection(box(-0.16, 0.38, 0.16, 0.62)).area
    assert slid_into_view(ring, y, area, view) == pytest.approx(x, abs=1e-6)


def test_the_bundled_settings_load():
    cfg = load_belt_schedule_config()
    assert cfg.reach_s < cfg.cycle_s and cfg.first_reach_s < cfg.first_cycle_s


@pytest.mark.parametrize(
    ("changes", "names"),
    [
        ({"cycle_smoothing": 0.0}, "cycle_smoothing"),
        ({"reach_s": -1.0}, "reach_s"),
        ({"end_margin": float("nan")}, "end_margin"),
        ({"reach_s": 3.0, "cycle_s": 2.3}, "reach_s"),
        ({"match_tolerance_x": 0.1, "match_gate_x": 0.05}, "match_tolerance_x"),
    ],
)
def test_settings_out_of_range_are_typed_errors_naming_the_field(changes, names):
    with pytest.raises(BeltScheduleError, match=names) as err:
        BeltScheduleConfig(**changes)
    assert isinstance(err.value, AgentError) and isinstance(err.value, ConfigError)


def test_an_unknown_setting_is_refused():
    with pytest.raises(ConfigError, match="cycle_seconds"):
        load_belt_schedule_config(cycle_seconds=2.0)


@pytest.mark.slow
def test_on_the_stream_the_tile_nearer_the_end_goes_first_and_the_other_is_followed():
    base, _ = task_protocol("MosaicStream-v1")
    kwargs = make_policies(["scripted"], base)[0].env_kwargs
    env = gym.make("envs:MosaicAssembly-v0", **kwargs)
    try:
        agent = ScriptedAgent.from_env(env)
        obs, info = env.reset(seed=2)  # two tiles: x = -0.017 m and 0.119 m
        cell = env.unwrapped.cell  # ground truth only
        on = np.flatnonzero(cell.input_side())
        xs = cell.data.xpos[cell.ids.tile_body][on, 0]
        assert len(on) == 2 and xs.max() - xs.min() > 0.1
        action, _ = agent.predict(obs)
        first = agent.last_command
        assert first is not None
        # The pad point of the first pick lies on the tile nearer the belt's end.
        assert abs(first.pick[0] - xs.max()) < 0.005
        obs, _, _, _, info = env.step(action)
        assert info["evaluation"]["correct"] == 1
        # The other tile left the whole view meanwhile (cut by its edge): followed, picked.
        action, _ = agent.predict(obs)
        assert agent.last_perception is not None and not agent.last_perception.tiles
        assert agent.last_command is not None and agent.belt is not None
        obs, _, _, _, info = env.step(action)
        ev = info["evaluation"]
        assert ev["correct"] == 2 and ev["lost"] == 0 and ev["misplaced"] == 0
        tally = agent.belt.tally()
        assert tally.ghost_picks == 1 and tally.rejected == 0 and tally.measured >= 1
    finally:
        env.close()
