"""A scripted low-level controller of the one-tile task in the ``cartesian`` action mode.

`LowLevelExpert` seals, lifts, carries, aligns and releases a tile by tool moves (dx, dy, dz,
dyaw) and the vacuum, reading only the ``state`` observation (``robot``, the privileged
``tiles`` and ``slots`` rows, `envs.observations.spaces`) and the env's public
`envs.task_spec.TaskSpec` (surface heights, tile thickness, the tool step of one action). It keeps
no memory: every action is a function of the current observation, so its demonstrations are Markov
for behaviour cloning and it can serve as the base of residual RL.

Phases, chosen from the observation alone:

- *approach*: the pad over the tile's centre at ``hover`` above its top, the vacuum off;
  within ``descend_radius`` of it, down to ``seal_press`` below the top with the vacuum on
  (the pad seals as soon as it is close and flat, `envs.cell.suction`).
- *lift and carry* (held): the tile up to ``carry_height`` above the place surface, then to
  its slot. Every sideways move (the approach too) goes round the robot's base: while the goal
  is more than ``direct_deg`` round the base from the moving point, the point heads for one
  ``lead_deg`` further round on the circle of ``route_radius``, through the front of the robot
  (close to the base or behind it, low down, the tool cannot point down).
- *align and set down* (held, within ``align_radius`` of the slot): the tile's centre and yaw
  (modulo its symmetry) servoed onto the slot's, and, once within ``lower_xy_tolerance`` and
  ``lower_yaw_tolerance_deg``, down to ``place_gap`` above the mesh; released when within
  ``release_*`` of the slot.
- *retreat* (not held, the tile on the mesh): straight up, the vacuum off.

The tile is servoed by its observed pose (it moves rigidly with the pad), the tool by its
observed pose; an action is the error divided by ``task_spec.tool_step`` times ``gain``,
clipped to [-1, 1] (the servo tracks a target within one control period).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np

from agents.errors import AgentError
from configs import load_config
from envs.observations.fields import SLOT_DIM, SLOT_FIELDS, TILE_DIM, TILE_FIELDS, column
from envs.task_spec import TaskSpec
from spatial.angles import wrap_angle

EXPERT_CONFIG = "lowlevel_expert"
"""Bundled config name (``configs/lowlevel_expert.yaml``)."""
TOOL_POS = slice(12, 15)
"""Tool position (x, y, z) [m] in the ``robot`` vector."""
TOOL_YAW = slice(15, 17)
"""Tool yaw as (cos, sin) in the ``robot`` vector."""
HELD = 18
"""Index of the pressure switch (tile held) in the ``robot`` vector."""
CARTESIAN_DIM = 5
"""Length of a ``cartesian`` action: tool (dx, dy, dz, dyaw) and the vacuum."""


@dataclass(frozen=True)
class LowLevelExpertConfig:
    """Set points and tolerances of `LowLevelExpert`.

    Attributes:
        hover: Pad height above the tile's top while approaching it [m].
        descend_radius: Pad-to-tile-centre xy distance under which the pad goes down [m].
        seal_press: Pad target below the tile's top at the seal [m].
        carry_height: Tile bottom above the place surface while carrying [m].
        carry_z_margin: The carry moves sideways once the tile is this close to its height [m].
        base_xy: World (x, y) of the robot's base axis [m].
        route_radius: Radius of the circle round the base sideways moves follow [m].
        lead_deg: How far round the circle a routed move aims ahead [deg].
        direct_deg: Goals at most this far round the base are approached straight [deg].
        align_radius: Tile-to-slot xy distance under which the tile turns and descends [m].
        align_height: Tile bottom above the place surface while aligning [m].
        lower_xy_tolerance: xy error under which the tile is set down [m].
        lower_yaw_tolerance_deg: Yaw error under which the tile is set down [deg].
        set_down_step: Largest descent per control period while setting the tile down [m].
        place_gap: Tile bottom above the place surface at the release [m].
        release_xy_tolerance: xy error under which the vacuum releases [m].
        release_yaw_tolerance_deg: Yaw error under which the vacuum releases [deg].
        release_z_tolerance: Height error (to ``place_gap``) under which it releases [m].
        retreat_height: Pad height above the place surface after the release [m].
        gain: Fraction of the error corrected per control period (1: dead-beat).
        approach_blend: 0: the pad drops from ``hover`` to the seal once within
            ``descend_radius`` (a step in the action); > 0: its height target falls linearly
            from ``hover`` at ``descend_radius + approach_blend`` to the seal at
            ``descend_radius``, the vacuum on within that band [m]. A continuous action is
            what a behaviour clone can fit; the step is what the clone smears out.
        lower_blend: 0: the tile is set down once within the lower tolerances (a step);
            > 0: its height target falls linearly from ``align_height`` at (1 +
            ``lower_blend``) times the tolerances to ``place_gap`` within them.
    """

    hover: float = 0.02
    descend_radius: float = 0.003
    seal_press: float = 0.0005
    carry_height: float = 0.04
    carry_z_margin: float = 0.01
    base_xy: tuple[float, float] = (0.0, 0.0)
    route_radius: float = 0.5
    lead_deg: float = 30.0
    direct_deg: float = 20.0
    align_radius: float = 0.01
    align_height: float = 0.01
    lower_xy_tolerance: float = 0.001
    lower_yaw_tolerance_deg: float = 0.5
    set_down_step: float = 0.002
    place_gap: float = 0.0005
    release_xy_tolerance: float = 0.0005
    release_yaw_tolerance_deg: float = 0.5
    release_z_tolerance: float = 0.001
    retreat_height: float = 0.05
    gain: float = 1.0
    approach_blend: float = 0.0
    lower_blend: float = 0.0


def load_expert_config(
    name_or_path: str | None = EXPERT_CONFIG, **overrides: Any
) -> LowLevelExpertConfig:
    """Load a `LowLevelExpertConfig` strictly (unknown keys are a `configs.ConfigError`)."""
    return load_config(LowLevelExpertConfig, name_or_path, **overrides)


class LowLevelExpert:
    """Scripted ``cartesian`` controller: one tile from the belt into its slot.

    Args:
        env: A ``cartesian`` env with ``state`` (or ``rgb+state``) observations (any wrapper).
        config: Set points (default: ``configs/lowlevel_expert.yaml``).
        tool_step: The tool move of a full action (dx, dy, dz, dyaw) [m, m, m, rad] for a
            controller that maps these cartesian actions onto another action mode
            (`agents.experts.joint`); then any action mode is accepted and
            ``action_space`` is the cartesian Box(5). None: the env's ``task_spec.tool_step``.

    Raises:
        AgentError: The env is not in the ``cartesian`` action mode (and no ``tool_step`` is
            given) or has no state rows.
    """

    def __init__(
        self,
        env: gym.Env,
        config: LowLevelExpertConfig | None = None,
        tool_step: tuple[float, float, float, float] | None = None,
    ) -> None:
        spec: TaskSpec = env.get_wrapper_attr("task_spec")
        if tool_step is None and (spec.action_mode != "cartesian" or spec.tool_step is None):
            raise AgentError(
                f"LowLevelExpert acts in the 'cartesian' action mode, the env's is "
                f"{spec.action_mode!r}"
            )
        space = env.observation_space
        if not isinstance(space, gym.spaces.Dict) or "tiles" not in space.spaces:
            raise AgentError(
                "LowLevelExpert reads the 'state' observation rows (robot, tiles, slots); "
                f"the env's observation space is {space}"
            )
        self.cfg = config or load_expert_config()
        self.spec = spec
        self.step = np.asarray(spec.tool_step if tool_step is None else tool_step, float)
        self.symmetry = np.array([s.symmetry for s in spec.slots], int)
        self.observation_space = space
        self.action_space = (
            env.action_space
            if tool_step is None
            else gym.spaces.Box(-1.0, 1.0, (CARTESIAN_DIM,), np.float32)
        )

    def predict(
        self, obs: dict[str, Any], state: Any = None, episode_start: Any = None, **_: Any
    ) -> tuple[np.ndarray, None]:
        """The action for ``obs`` (SB3 style: ``(action, None)``; no memory is kept)."""
        del state, episode_start
        return self.act(obs), None

    def __call__(self, obs: dict[str, Any]) -> np.ndarray:
        """The action for ``obs``."""
        return self.act(obs)

    def act(self, obs: dict[str, Any]) -> np.ndarray:
        """The action for one observation, float32 (5,) in [-1, 1]."""
        robot = np.asarray(obs["robot"], float)
        tiles = np.asarray(obs["tiles"], float).reshape(-1, TILE_DIM)
        slots = np.asarray(obs["slots"], float).reshape(-1, SLOT_DIM)
        tool = robot[TOOL_POS]
        tool_yaw = math.atan2(robot[TOOL_YAW][1], robot[TOOL_YAW][0])
        target = _target(tiles, slots)
        if target is None:  # nothing left to place: rise and wait
            return self._move(tool, tool, self.spec.place.surface_z + self.cfg.retreat_height)
        tile, slot = target
        if robot[HELD] > 0.5:
            return self._carry(tiles[tile], slots[slot], self.symmetry[slot], tool, tool_yaw)
        if self._on_mesh(tiles[tile]):
            return self._move(tool, tool, self.spec.place.surface_z + self.cfg.retreat_height)
        return self._approach(tiles[tile], tool)

    def _approach(self, tile: np.ndarray, tool: np.ndarray) -> np.ndarray:
        cfg, top = self.cfg, float(tile[2]) + self.spec.tile_thickness / 2
        dist = float(np.linalg.norm(tile[:2] - tool[:2]))
        if cfg.approach_blend > 0:  # height falls with the distance: no step in the action
            up = float(np.clip((dist - cfg.descend_radius) / cfg.approach_blend, 0.0, 1.0))
            z = top - cfg.seal_press + up * (cfg.hover + cfg.seal_press)
            return self._move(tool, self._route(tool[:2], tile[:2]), z, vacuum=up < 1.0)
        near = dist < cfg.descend_radius
        z = top - cfg.seal_press if near else top + cfg.hover
        return self._move(tool, self._route(tool[:2], tile[:2]), z, vacuum=near)

    def _route(self, at: np.ndarray, goal: np.ndarray) -> np.ndarray:
        """Where a sideways move from ``at`` to ``goal`` (x, y) [m] heads now (round the base)."""
        cfg, base = self.cfg, np.asarray(self.cfg.base_xy, float)
        a, g = at - base, goal - base
        # Angles in (-pi, pi]: unwrapped, the turn never crosses the back of the robot (pi).
        turn = math.atan2(g[1], g[0]) - math.atan2(a[1], a[0])
        if abs(turn) <= math.radians(cfg.direct_deg):
            return goal
        heading = math.atan2(a[1], a[0]) + math.copysign(math.radians(cfg.lead_deg), turn)
        return base + cfg.route_radius * np.array([math.cos(heading), math.sin(heading)])

    def _carry(
        self, tile: np.ndarray, slot: np.ndarray, symmetry: int, tool: np.ndarray, tool_yaw: float
    ) -> np.ndarray:
        cfg, place = self.cfg, self.spec.place
        half = self.spec.tile_thickness / 2
        tile_z = float(tile[2])
        err = slot[:2] - tile[:2]
        dist = float(np.linalg.norm(err))
        yaw_err = _yaw_error(math.atan2(tile[4], tile[3]), math.atan2(slot[3], slot[2]), symmetry)
        if dist > cfg.align_radius:
            carry_z = place.surface_z + half + cfg.carry_height
            goal = tile[:2]
            if tile_z > carry_z - cfg.carry_z_margin:
                goal = self._route(tile[:2], slot[:2])
            return self._move(tile[:3], goal, carry_z, vacuum=True, tool_yaw=yaw_err)
        off = max(
            dist / cfg.lower_xy_tolerance, abs(yaw_err) / math.radians(cfg.lower_yaw_tolerance_deg)
        )
        if cfg.lower_blend > 0:  # height rises with the error: no step in the action
            up = float(np.clip((off - 1.0) / cfg.lower_blend, 0.0, 1.0))
        else:
            up = 0.0 if off < 1.0 else 1.0
        z = place.surface_z + half + cfg.place_gap + up * (cfg.align_height - cfg.place_gap)
        if up < 1.0:  # set down slowly: a fast touch-down knocks the tile out of line
            z = max(z, tile_z - cfg.set_down_step)
        release = (
            dist < cfg.release_xy_tolerance
            and abs(yaw_err) < math.radians(cfg.release_yaw_tolerance_deg)
            and abs(tile_z - (place.surface_z + half + cfg.place_gap)) < cfg.release_z_tolerance
        )
        return self._move(tile[:3], slot[:2], z, vacuum=not release, tool_yaw=yaw_err)

    def _move(
        self,
        at: np.ndarray,
        goal_xy: np.ndarray,
        goal_z: float,
        *,
        vacuum: bool = False,
        tool_yaw: float = 0.0,
    ) -> np.ndarray:
        """Action moving the point ``at`` (tool or held tile) to the goal, turning by a yaw."""
        err = np.array([*(np.asarray(goal_xy, float)[:2] - at[:2]), goal_z - at[2], tool_yaw])
        a = np.clip(self.cfg.gain * err / self.step, -1.0, 1.0)
        return np.array([*a, 1.0 if vacuum else -1.0], np.float32)

    def _on_mesh(self, tile: np.ndarray) -> bool:
        place = self.spec.place
        return bool(np.all(tile[:2] >= place.lo) and np.all(tile[:2] <= place.hi))


def _target(tiles: np.ndarray, slots: np.ndarray) -> tuple[int, int] | None:
    """(tile, slot): the first open slot and the present tile of its class nearest to it."""
    t_class, present = column(TILE_FIELDS, "class"), column(TILE_FIELDS, "present")
    s_class, filled = column(SLOT_FIELDS, "class"), column(SLOT_FIELDS, "filled")
    for k in np.flatnonzero(slots[:, filled] < 0.5):
        same = np.flatnonzero(
            (tiles[:, present] > 0.5) & (np.abs(tiles[:, t_class] - slots[k, s_class]) < 0.5)
        )
        if len(same):
            d = np.linalg.norm(tiles[same, :2] - slots[k, :2], axis=1)
            return int(same[np.argmin(d)]), int(k)
    return None


def _yaw_error(tile_yaw: float, slot_yaw: float, symmetry: int) -> float:
    """Turn [rad] bringing ``tile_yaw`` onto ``slot_yaw`` modulo the symmetry (0: any yaw)."""
    if symmetry <= 0:
        return 0.0
    return float(wrap_angle((slot_yaw - tile_yaw) * symmetry)) / symmetry


__all__ = ["LowLevelExpert", "LowLevelExpertConfig", "load_expert_config"]
