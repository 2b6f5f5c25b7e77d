"""A tile the pad drops over the input belt is counted on the input, then picked and placed.

The scripted agent drives `pick_place` steps (dynamic execution: the cycle is tracked by the
servos and the vacuum's holding force is checked at every control period). The only privileged
set-up is a vacuum fault during the agent's first cycle: the pad's holding force is cut below a
tile's weight, so the pad drops the tile it just sealed on while lifting it off the input belt;
the force is restored after that step. The dropped tile must be counted on the input (placeable,
not dropped) and the agent must pick it again and place it in its slot.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np

import envs  # noqa: F401 - registers the env
from agents.scripted import ScriptedAgent
from envs.cell.accounting import TILE_STATES

FAULT_FORCE = 0.01
"""Holding force during the fault [N]: far less than a tile's weight (~0.19 N)."""


def _accounted(ev: dict) -> None:
    assert sum(ev[s] for s in TILE_STATES) == ev["fed"], ev


def test_a_tile_dropped_over_the_input_belt_is_picked_again_and_placed():
    env = gym.make(
        "envs:MosaicAssembly-v0",
        action_mode="pick_place",
        obs_mode="rgb",
        execution="dynamic",
        max_slots=2,
        image_size=(492, 656),
    )
    try:
        obs, info = env.reset(seed=0)
        cell = env.unwrapped.cell
        slots = info["evaluation"]["slots"]
        agent = ScriptedAgent.from_env(env)

        # The fault: the agent's first cycle seals on a tile, then the pad drops it.
        strong = cell.suction.holding_force
        cell.suction.holding_force = FAULT_FORCE
        action, _ = agent.predict(obs, episode_start=np.array([True]))
        obs, _, terminated, _, info = env.step(action)
        cell.suction.holding_force = strong
        assert [e.kind for e in cell.events] == ["grasp", "drop"]
        tile = cell.events[0].tile
        assert info["action_failed"]
        assert cell.input_side()[tile] and not cell.tile_held  # it lies on the input belt
        pick = env.unwrapped.pick_area
        rest_z = (pick.surface_z + pick.tile_top_z) / 2
        assert abs(cell.tile_poses().pos[tile][2] - rest_z) < 1e-3  # flat, at rest on it
        ev = info["evaluation"]
        assert (ev["on_input"], ev["dropped_tiles"], ev["dropped"]) == (slots, 0, 1)
        assert ev["placeable"] == slots and not terminated
        _accounted(ev)

        for _ in range(2 * slots):
            action, _ = agent.predict(obs)
            obs, _, terminated, truncated, info = env.step(action)
            _accounted(info["evaluation"])
            if terminated or truncated:
                break
        final = info["evaluation"]
        assert final["success"] and final["correct"] == final["slots"] == slots
        assert final["misplaced"] == 0 and final["dropped_tiles"] == 0
        # The dropped tile was sealed on again and released in its slot.
        assert [e.kind for e in cell.events if e.tile == tile] == [
            "grasp",
            "drop",
            "grasp",
            "release",
        ]
        assert not cell.was_dropped[tile]
    finally:
        env.close()
