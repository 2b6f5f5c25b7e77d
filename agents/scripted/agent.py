"""The scripted cell as a policy of `MosaicAssembly-v0` (``pick_place`` action mode).

The paper's loop through the env's public API only. The agent is built from the env's task
description (`envs.task_spec.TaskSpec`, read once by `ScriptedAgent.from_env`): the design's
slots in the world are described once; each picture (the ``input_camera`` observation) is
perceived on the tiles' top plane (`agents.scripted.perception`) and assigned to the open slots
(`agents.scripted.placement`); the resulting commands are encoded one per step by the spec's
``pick_place`` codec, and a new picture is taken once they are used up. Tiles matching no open
slot are never placed; a tile still on the belt after its command (a failed pick) reopens its
slot. The input camera is calibrated from checkerboard pictures the env takes
(``calibration_views``, `agents.scripted.calibration`) at the observation's image size, or the
spec's camera model is used (``calibrate=False``). Each picture's tiles are described once (after
the white balance) and matched against the design's slots once per colour mode
(`agents.scripted.placement.FeasiblePairs`).

`ScriptedAgent.predict` has stable-baselines3's signature, so ``evaluate_policy`` can run it
like a learned policy (one env; a vectorised observation with a leading batch of 1 is
accepted)::

    env = gym.make("envs:MosaicAssembly-v0", action_mode="pick_place", image_size=(492, 656))
    agent = ScriptedAgent.from_env(env)
    obs, _ = env.reset(seed=0)
    action, _ = agent.predict(obs)
"""

from __future__ import annotations

import dataclasses
from collections import deque
from typing import Any

import gymnasium as gym
import numpy as np

from agents.errors import AgentError
from agents.scripted.belt_schedule import BeltScheduler
from agents.scripted.calibration import CalibrationResult, calibrate_env_camera
from agents.scripted.config import AgentsConfig, load_agents_config
from agents.scripted.height import HeightMap
from agents.scripted.outline_fit import TileOutline, fit_unmatched
from agents.scripted.perception import (
    Perception,
    perceive_tiles,
    refigured,
    slot_targets,
)
from agents.scripted.placement import (
    FeasiblePairs,
    PickPlace,
    PlacementPlan,
    Unplaced,
    fitted_command,
    plan_placements,
)
from agents.scripted.seen_slots import camera_scale
from agents.scripted.white_balance import color_gain
from envs.cell.cameras import CameraModel
from envs.task_spec import PickPlaceCodec, PickPlaceCommand, TaskSpec
from qshape import ExtractParams, OutlineParams
from qshape.design.rules import DesignRules
from qshape.design.turn_cues import hole_turn_gap
from qshape.theory.tolerances import default_tolerances
from spatial.units import MM_PER_M

IMAGE_DIMS = 3
"""An unbatched RGB observation has (height, width, 3)."""
IDLE_GRID = (25, 13)
"""Candidate points (along x, y) of the rest action's pick and place searches."""
IDLE_HORIZON_S = 3.0
"""Belt travel time [s] the rest action's pick keeps clear of (about one cycle)."""


UNMATCHED = ("shape_absent", "color_absent")
"""Why a tile left by the descriptions may be fitted by its outline (`agents.scripted.outline_fit`):
it matches no open slot's shape, or only slots of other colours."""


class ScriptedAgent:
    """Vision + qualitative matching + planner cycles, as a policy.

    Args:
        spec: The env's task description (``pick_place`` action mode).
        config: Agent settings (bundled ``configs/agents.yaml`` when None).
        calibration: The input camera's calibration at the observation size (its camera model
            is used), or None: the spec's camera model.
        replan_every_step: Take a new picture before every command (tiles move on a moving
            belt, new ones arrive with a stream feed) instead of once per batch of commands
            (the paper's static loop). None: every step when the belt moves or tiles stream.

    Raises:
        AgentError: Wrong action mode.
    """

    def __init__(
        self,
        spec: TaskSpec,
        config: AgentsConfig | None = None,
        calibration: CalibrationResult | None = None,
        replan_every_step: bool | None = None,
    ) -> None:
        self.cfg = config or load_agents_config()
        if spec.codec is None:
            raise AgentError(
                f"the scripted agent needs action_mode 'pick_place', got {spec.action_mode!r}"
            )
        self.spec = spec
        self.codec: PickPlaceCodec = spec.codec
        self.belt_speed = spec.belt_speed
        self.replan_every_step = (
            bool(spec.belt_speed > 0 or spec.feed != "all")
            if replan_every_step is None
            else replan_every_step
        )
        self.calibration = calibration
        self.camera: CameraModel = (
            calibration.camera if calibration is not None else spec.camera("input_camera")
        )
        self.tile_top = spec.pick.tile_top_z
        self.heights = HeightMap(self.camera, spec.pick.surface_z)
        """Heights above the belt from the depth picture (`agents.scripted.height`), if any."""
        self.height: np.ndarray | None = None
        """The latest picture's tile heights [mm] (``input_depth`` observations), or None."""
        outline = ExtractParams.load().outline
        seen = (
            (
                outline,
                camera_scale(self.camera, self.tile_top),
                self.cfg.perception.seen_turn_residual,
            )
            if self.cfg.perception.seen_slots
            else None
        )
        self.slots = slot_targets(spec.slots, seen=seen)
        retry = self.cfg.perception.retry_outline
        self.retry_params: OutlineParams | None = (
            OutlineParams(**{**dataclasses.asdict(outline), **retry}) if retry else None
        )
        self.palette = np.array([s.color for s in self.slots])
        # A slot whose outline's turns only its holes tell apart, by less than the design
        # rules' limit (the loader warns about it), is never matched: its tile would be set
        # down one outline turn off as often as not.
        gap = DesignRules.load().min_hole_turn_mm
        self.turn_unresolved: frozenset[int] = frozenset(
            s.index for s in self.slots if hole_turn_gap(s.figure, s.symmetry, None) < gap
        )
        self.belt: BeltScheduler | None = (
            BeltScheduler.for_spec(spec, self.camera) if spec.belt_speed > 0 else None
        )
        """On a moving belt: the pick order by deadline (`agents.scripted.belt_schedule`)."""
        self.queue: deque[PickPlace] = deque()
        self.filled: set[int] = set()
        self.order: list[int] = []
        self.unplaced: tuple[Unplaced, ...] = ()
        self.last_plan: PlacementPlan | None = None
        self.last_perception: Perception | None = None
        self.last_command: PickPlace | None = None
        self.pictures = 0
        self.colors: deque[tuple[float, float, float]] = deque(
            maxlen=self.cfg.perception.color_history
        )

    @classmethod
    def from_env(
        cls,
        env: gym.Env[Any, Any],
        config: AgentsConfig | None = None,
        calibrate: bool = True,
        replan_every_step: bool | None = None,
        *,
        calibration: CalibrationResult | None = None,
    ) -> ScriptedAgent:
        """The agent of a `MosaicAssembly-v0` env (wrapped or not), from its task description.

        The one place an agent reads an env beyond its spaces: ``task_spec`` and, with
        ``calibrate``, the checkerboard pictures of the input camera (``calibration_views``,
        at the observation size), through Gymnasium's ``get_wrapper_attr``.

        ``calibration``: an earlier calibration of the same camera, used instead of a new one.

        Raises:
            AgentError: Not a ``pick_place`` env with an ``input_camera`` observation.
            CalibrationError: The calibration failed.
        """
        obs_space = env.observation_space
        if not isinstance(obs_space, gym.spaces.Dict) or "input_camera" not in obs_space.spaces:
            raise AgentError("the scripted agent needs the input_camera observation (obs_mode rgb)")
        spec: TaskSpec = env.get_wrapper_attr("task_spec")
        cfg = config or load_agents_config()
        cal = calibration
        if cal is None and calibrate:
            cal = calibrate_env_camera(env, "input_camera", cfg.calibration, spec.image_size)
        return cls(spec, cfg, cal, replan_every_step)

    def reset(self) -> None:
        """Forget the episode (open slots, queued commands, measured colours)."""
        self.colors.clear()
        self.queue.clear()
        self.filled.clear()
        self.order.clear()
        self.unplaced = ()
        self.last_plan = None
        self.last_perception = None
        self.last_command = None
        self.pictures = 0
        if self.belt is not None:
            self.belt.reset()

    def plan(self, image: np.ndarray) -> PlacementPlan:
        """Perceive one input-camera image and assign its tiles to the open slots.

        A real tile whose every matching slot was already commanded means a command failed
        (the tile is still on the belt; the env gives one tile per slot): the most recently
        commanded of those slots is reopened and the picture planned again.
        """
        pcfg = self.cfg.perception
        per = perceive_tiles(
            image,
            self.camera,
            self.tile_top,
            cfg=pcfg,
            white_balance=self._white_balance if pcfg.color_balance else None,
            height=self.height,
        )
        if self.belt is not None:
            self.belt.observe(per.tiles, per.partial)
        pairs = FeasiblePairs(per.tiles, self.slots)
        plan = self._assign(per, pairs)
        if self.retry_params is not None and any(u.reason == "shape_absent" for u in plan.unplaced):
            per, pairs, plan = self._retry_unmatched(per, pairs, plan)
        taken = [u.tile for u in plan.unplaced if u.reason == "slots_taken"]
        if taken and self._reopen(taken, pairs):
            plan = self._assign(per, pairs)
        if self.cfg.placement.fit_max_residual > 0 and any(
            u.reason in UNMATCHED for u in plan.unplaced
        ):
            plan = self._fit_unmatched(per, plan)
        self.pictures += 1
        self.last_perception = per
        self.last_plan = plan
        self.unplaced = plan.unplaced
        return plan

    def _retry_unmatched(
        self, per: Perception, pairs: FeasiblePairs, plan: PlacementPlan
    ) -> tuple[Perception, FeasiblePairs, PlacementPlan]:
        """Simplify the outlines of tiles matching no open slot's shape again (finer).

        A tile's retried figure replaces its first one only when it then matches an open
        slot; the pairs and the plan are made again when any did.
        """
        assert self.retry_params is not None
        absent = {u.tile for u in plan.unplaced if u.reason == "shape_absent"}
        left_out = self.filled | self.turn_unresolved | self._reserved()
        open_slots = [s for s in self.slots if s.index not in left_out]
        use_color = self.cfg.placement.use_color
        tiles = list(per.tiles)
        changed = False
        for pos, t in enumerate(tiles):
            if t.index not in absent:
                continue
            again = refigured(
                t, self.camera, per.plane_z, self.retry_params, cfg=self.cfg.perception
            )
            if again is not None and FeasiblePairs([again], open_slots).slots_of(0, use_color):
                tiles[pos] = again
                changed = True
        if not changed:
            return per, pairs, plan
        per = dataclasses.replace(per, tiles=tuple(tiles))
        pairs = FeasiblePairs(per.tiles, self.slots)
        return per, pairs, self._assign(per, pairs)

    def _fit_unmatched(self, per: Perception, plan: PlacementPlan) -> PlacementPlan:
        """Tiles no description matched, fitted by outline (`agents.scripted.outline_fit`).

        A quantitative last resort: the tiles still matching no open slot's shape (or only
        slots of other colours, `UNMATCHED`) are turned
        onto the slots the plan leaves open by their traced outlines, and those fitting one
        slot class unambiguously are placed by that fit.
        """
        absent = {u.tile for u in plan.unplaced if u.reason in UNMATCHED}
        traced = [(t, TileOutline.of(t)) for t in per.tiles if t.index in absent]
        tiles = [t for t, o in traced if o is not None]
        outlines = [o for _, o in traced if o is not None]
        open_ = set(plan.open_slots)
        slots = [s for s in self.slots if s.index in open_]
        pcfg = self.cfg.placement
        found = fit_unmatched(
            outlines, slots, pcfg, default_tolerances().color_distance, pcfg.fit_spacing_mm
        )
        if not found:
            return plan
        more = tuple(
            fitted_command(
                tiles[i], slots[j], f.rotation, f.centre / MM_PER_M, score=f.residual, cfg=pcfg
            )
            for i, j, f in found
        )
        placed = {c.tile for c in more}
        filled = {c.slot for c in more}
        return dataclasses.replace(
            plan,
            commands=plan.commands + more,
            unplaced=tuple(u for u in plan.unplaced if u.tile not in placed),
            open_slots=tuple(k for k in plan.open_slots if k not in filled),
        )

    def _white_balance(self, measured: np.ndarray) -> np.ndarray:
        """The gain of a picture's measured colours (n, 3), fitted on the recent history."""
        pcfg = self.cfg.perception
        self.colors.extend((r, g, b) for r, g, b in measured.tolist())
        many = len(self.colors) >= pcfg.color_min_samples
        return color_gain(np.array(self.colors), self.palette, pcfg, per_channel=many)

    def _reserved(self) -> frozenset[int]:
        """Slots of tiles followed out of the camera's view (moving belt), kept for them."""
        return self.belt.reserved() if self.belt is not None else frozenset()

    def _assign(self, per: Perception, pairs: FeasiblePairs) -> PlacementPlan:
        left_out = self.filled | self.turn_unresolved | self._reserved()
        open_slots = [s for s in self.slots if s.index not in left_out]
        done = [s for s in self.slots if s.index in self.filled]
        return plan_placements(per.tiles, open_slots, self.cfg.placement, filled=done, pairs=pairs)

    def _reopen(self, tiles: list[int], pairs: FeasiblePairs) -> bool:
        """Reopen, per tile (by position), the most recently commanded filled slot it matches."""
        if not self.filled:
            return False
        reopened = False
        for k in tiles:
            cands = pairs.slots_of(k, self.cfg.placement.use_color) & self.filled
            recent = [i for i in reversed(self.order) if i in cands]
            if recent:
                self.filled.discard(recent[0])
                reopened = True
        return reopened

    def next_command(self, image: np.ndarray) -> PickPlace | None:
        """The next command; a new picture is perceived when the queue is empty (or always)."""
        if self.replan_every_step:
            self.queue.clear()
        if not self.queue:
            cmds = list(self.plan(image).commands)
            if self.belt is not None:  # one pick, by deadline (followed tiles included)
                chosen = self.belt.choose(cmds)
                cmds = [chosen] if chosen is not None else []
            self.queue.extend(cmds)
        if not self.queue:
            self.last_command = None
            return None
        cmd = self.queue.popleft()
        self.filled.add(cmd.slot)
        self.order.append(cmd.slot)
        self.last_command = cmd
        return cmd

    def action(self, cmd: PickPlace | None) -> np.ndarray:
        """The normalised ``pick_place`` action of a command (a rest action when None).

        The rest action (nothing placeable is seen, e.g. a stream feed has not delivered the
        next tile yet) picks where nothing is: the point of the pick area farthest from every
        region of the last picture, swept downstream over `IDLE_HORIZON_S` of belt travel and
        away from the upstream edge where streamed tiles appear; and it "places" at the mesh
        point farthest from every slot. Nothing seals, so nothing moves: a harmless wait.
        """
        if cmd is None:
            pick, place = self._idle_points()
            idle = PickPlaceCommand((pick[0], pick[1]), 0.0, (place[0], place[1]), 0.0)
            return self.codec.encode(idle)
        return self.codec.encode(cmd.command)

    def _idle_points(self) -> tuple[np.ndarray, np.ndarray]:
        pick_area, place_area = self.codec.pick, self.codec.place
        nx, ny = IDLE_GRID

        def grid(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
            gx, gy = np.meshgrid(np.linspace(lo[0], hi[0], nx), np.linspace(lo[1], hi[1], ny))
            return np.column_stack([gx.ravel(), gy.ravel()])

        cand = grid(pick_area.lo, pick_area.hi)
        clear = cand[:, 0] - float(pick_area.lo[0])  # streamed tiles enter at the upstream edge
        per = self.last_perception
        regions = [(t.centre, t.area) for t in per.tiles] if per else []
        regions += [(r.centre, r.area) for r in per.partial] if per else []
        travel = np.array([self.belt_speed * IDLE_HORIZON_S, 0.0])
        for centre, area in regions:
            a = np.asarray(centre, float)
            d = cand - a
            s = np.clip(d @ travel / max(float(travel @ travel), 1e-12), 0.0, 1.0)
            gap = np.linalg.norm(d - s[:, None] * travel, axis=1) - np.sqrt(area / np.pi)
            clear = np.minimum(clear, gap)
        pick = cand[int(np.argmax(clear))]
        spots = grid(place_area.lo, place_area.hi)
        slots = np.array([s.pose[:2] for s in self.slots]).reshape(-1, 2)
        far = np.min(np.linalg.norm(spots[:, None] - slots[None], axis=2), axis=1)
        return pick, spots[int(np.argmax(far))]

    def predict(
        self,
        observation: dict[str, np.ndarray],
        state: Any = None,
        episode_start: np.ndarray | None = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, Any]:
        """stable-baselines3 policy interface.

        Args:
            observation: The env's observation dict (or a batch of one).
            state: Unused (no recurrent state); returned as given.
            episode_start: Per-env flags; a True resets the agent's memory.
            deterministic: Unused (the agent is deterministic).

        Returns:
            (action, state): the (6,) float32 action, or (1, 6) for a batched observation.
        """
        del deterministic
        image = np.asarray(observation["input_camera"])
        depth = observation.get("input_depth") if hasattr(observation, "get") else None
        batched = image.ndim == IMAGE_DIMS + 1
        if batched:
            if image.shape[0] != 1:
                raise AgentError(
                    f"the scripted agent drives one env, got a batch of {image.shape[0]}"
                )
            image = image[0]
            depth = None if depth is None else np.asarray(depth)[0]
        self.height = None if depth is None else self.heights.height_mm(depth)
        if episode_start is not None and bool(np.asarray(episode_start).ravel()[0]):
            self.reset()
        act = self.action(self.next_command(image))
        return (act[None] if batched else act), state


__all__ = ["UNMATCHED", "ScriptedAgent"]
