"""The belt scheduler's rule on privileged state: a teacher for learned stream policies.

`DeadlineExpert` plays ``pick_place_discrete`` on a moving belt with the rule of the scripted
cell's scheduler (`agents.scripted.belt_schedule.deadline_order`: earliest deadline first,
tiles no pick can reach in time rejected), read from the env's ground truth instead of pictures:
every wanted tile's position along the belt, the belt's speed and end. The pick goes to an open
slot of the tile's class (the lowest slot index), at the rotation that places it
(`envs.mosaic_env.MosaicAssemblyEnv.expert_action`). When no order saves a tile, the most
downstream wanted tile is tried (a try costs no other tile: none would be saved). While no tile
lies on the input belt, it waits: the first tile index the env allows, the first open slot.

For recording demonstrations (`benchmarks.learned.stream`) and as a privileged reference; a
policy under evaluation never reads the ground truth.
"""

from __future__ import annotations

from typing import Any, cast

import gymnasium as gym
import numpy as np

from agents.errors import AgentError
from agents.pair.stream_rows import BeltTiming
from agents.scripted.belt_config import BeltScheduleConfig, load_belt_schedule_config
from agents.scripted.belt_schedule import deadline_order
from envs.mosaic_env import MosaicAssemblyEnv


def belt_timing(env: gym.Env[Any, Any], cfg: BeltScheduleConfig | None = None) -> BeltTiming:
    """The stream adapter's belt of ``env``, from its public `TaskSpec`.

    The belt's end is the pick area's downstream edge; a pick contact must come ``end_margin``
    (`configs/belt_schedule.yaml`) before it.

    Raises:
        AgentError: The env's belt does not move.
    """
    spec = cast(MosaicAssemblyEnv, env.unwrapped).task_spec
    cfg = cfg or load_belt_schedule_config()
    if not spec.belt_speed > 0:
        raise AgentError(
            f"a stream policy needs a belt moving along +x; this env's belt_speed is "
            f"{spec.belt_speed} m/s"
        )
    return BeltTiming(
        belt_speed=float(spec.belt_speed),
        last_x=float(spec.pick.hi[0]) - cfg.end_margin,
        pick_y=(float(spec.pick.lo[1]), float(spec.pick.hi[1])),
    )


class DeadlineExpert:
    """Earliest-deadline-first picks on a moving belt from the env's ground truth.

    Args:
        env: A ``pick_place_discrete`` env on a moving belt (wrappers allowed).
        cfg: The scheduler's settings (reach and cycle times, end margin); the bundled ones
            by default.

    Raises:
        AgentError: The env's action mode is not ``pick_place_discrete`` or its belt is still.
    """

    def __init__(self, env: gym.Env[Any, Any], cfg: BeltScheduleConfig | None = None) -> None:
        self.env = cast(MosaicAssemblyEnv, env.unwrapped)
        if (mode := self.env.config.action_mode) != "pick_place_discrete":
            raise AgentError(f"the deadline expert plays pick_place_discrete, not {mode!r}")
        self.cfg = cfg or load_belt_schedule_config()
        self.timing = belt_timing(env, self.cfg)
        self._first = True

    def reset(self) -> None:
        """A new episode: the next pick starts from home (the shorter first reach)."""
        self._first = True

    def choose(self) -> tuple[int, int] | None:
        """(tile, slot) cell indices of the next pick, or None while nothing can be picked."""
        task = self.env.task
        evaluation = task.evaluate()
        wanted = np.flatnonzero(task.wanted_tiles(evaluation) & self.env.cell.input_half())
        if not len(wanted):
            return None
        x = np.asarray(task.ground_truth().xy, float)[wanted, 0]
        reach = self.cfg.first_reach_s if self._first else self.cfg.reach_s
        order = deadline_order(
            x, self.timing.belt_speed, self.timing.last_x, reach, self.cfg.cycle_s
        ).order
        tile = int(wanted[order[0]] if order else wanted[int(np.argmax(x))])
        filled = np.asarray(evaluation.slot_filled, bool)
        slot = int(np.flatnonzero(~filled & (task.slot_class == task.tile_class[tile]))[0])
        return tile, slot

    def action(self) -> np.ndarray:
        """The next ``pick_place_discrete`` action (agent indices): `encode` of `choose`."""
        return self.encode(self.choose())

    def encode(self, choice: tuple[int, int] | None) -> np.ndarray:
        """The action of a `choose` result (a wait when None); the next pick is not the first.

        For a caller that reads the choice itself (`benchmarks.learned.stream` counts waits):
        the choice is computed once.
        """
        self._first = False
        if choice is not None:
            return self.env.expert_action(*choice)
        mask = self.env.action_masks()
        n, k, _ = (int(v) for v in self.env.action_space.nvec)  # type: ignore[attr-defined]
        return np.array(
            [int(np.flatnonzero(mask[:n])[0]), int(np.flatnonzero(mask[n : n + k])[0]), 0],
            np.int64,
        )


__all__ = ["DeadlineExpert", "belt_timing"]
