"""`MosaicAssembly-v0`: the Gymnasium environment of the mosaic cell.

Composition only: the `Cell` simulates, `MosaicTask` evaluates and rewards, `Observer` senses,
an `ActionAdapter` (one per action mode) acts. See `MosaicAssemblyEnv` for the spaces.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import gymnasium as gym
import numpy as np

from envs.actions import transfer_poses
from envs.cell.cameras import CameraModel
from envs.cell.cell import CAMERAS, Cell
from envs.cell.scene import build_arm_model
from envs.design_source import FIRST_DRAW_SEED, design_source, source_config
from envs.env_config import EnvConfig, load_env_config
from envs.env_parts import build_parts
from envs.errors import EnvError
from envs.frames import FrameSchedule
from envs.masks import action_mask, check_allowed
from envs.pool import design_pool, draw_design
from envs.task import REWARD_TERMS, Evaluation, GroundTruth
from envs.task_spec import (
    ActionError,
    PickPlaceCommand,
    TaskSpec,
)
from planners.config import load_planner_config
from planners.ik import IKSolver

if TYPE_CHECKING:
    from qshape.design import Design

DEFAULT_CONTROL_DT = 0.04
"""Default control period [s] (``configs/env.yaml``); the class's ``render_fps`` is 1 / it."""
CAMERA_PANEL_DIVISOR = 2
"""Each camera panel of the ``rgb_array`` frame is the overview's height / this."""
_INFO_KEYS = {k: f"reward_{k}" for k in REWARD_TERMS}
"""The ``info`` key of each reward term (formatted once)."""


class MosaicEnvError(EnvError, RuntimeError):
    """The environment is used in a wrong state (step before reset, after close, no display)."""


class MosaicAssemblyEnv(gym.Env[dict[str, Any], np.ndarray]):
    """Assemble a ceramic mosaic with an ABB IRB 140 and a vacuum pad.

    ## Description
    Tiles of a design lie on an input belt seen by ``input_camera``; the mesh with the design's
    slots lies on an output belt seen by ``output_camera``. The agent moves tiles into the
    slots of their class (shape and colour), turned to the slot's yaw modulo the tile's
    rotational symmetry, within tight tolerances (default 1.5 mm and 2 deg; a mosaic joint is
    2-3 mm). Physics: MuJoCo (timestep 2 ms), servo actuators, a weld-based suction seal.

    ## Action Space
    Chosen by ``action_mode`` (continuous ones are Box in [-1, 1] float32):

    - ``joint``: Box(7): joint target deltas scaled by each axis' speed limit times
      ``control_dt``, then vacuum (> 0: on). One step = ``control_dt`` of simulated time.
    - ``cartesian``: Box(5): tool dx, dy, dz (x ``tool_speed * control_dt``) and dyaw
      (x ``tool_yaw_rate * control_dt``), tool kept pointing down (planners' IK), then vacuum.
    - ``pick_place``: Box(6): pick x, y, the tile's yaw, place x, y, the rotation. x, y map
      linearly onto the input tile area (pick) and the mesh (place), see
      ``task_spec.codec``; angles onto [-pi, pi]. The pad goes to the pick point and then to
      the place point; the tile turns by the rotation (the tile's yaw changes nothing; ``-v1``
      is Box(5) without it). One step = one full time-optimal cycle planned by the planners;
      with ``chain_cycles`` (default) a dynamic cycle ends at rest at the place contact and
      the next one leaves it vertically, blended into its move (as a real cell chains them).
      ``task_spec.codec.encode(PickPlaceCommand(...))`` normalises a world command;
      ``pick_place_action(pick_xy, pick_yaw, place_xy, place_yaw)`` one given as two
      absolute yaws [m, rad].
    - ``pick_place_discrete``: MultiDiscrete([tiles, slots, rotation_bins]): move tile i
      (ground-truth grasp point) into slot j turned by r * 2 pi / rotation_bins. What the
      indices name carries no answer (`envs.indexing`): by default tile i is the i-th tile on
      the input belt from its downstream end (then the others), slot j the j-th slot in raster
      order on the mesh, and r counts from the slot-aligned pose nearest to how the tile lies
      (``tile_order``, ``slot_order``, ``rotation_frame``). ``action_masks()`` (`envs.masks`).

    ``execution`` (pick_place modes): ``dynamic`` tracks the planned trajectory with the
    servo actuators at every physics step (full physics, suction weld). ``kinematic`` puts the
    arm at the pick, place and retreat poses (qpos, no arm dynamics), the held tile moving
    with the pad and set down on the surface (not dropped from the release gap), then settles
    the released tile briefly; tiles at rest sleep. Kinematic mode gives up: arm
    dynamics and tracking errors, inertial drops, collisions along the path, tile motion on a
    moving belt during the cycle, and the real cycle time (it charges the planners' lower
    bound plus dwells). Outcomes of clean picks agree with dynamic mode (tested).

    ## Observation Space
    Dict (see `envs.observations.spaces`): ``input_camera``, ``output_camera`` RGB uint8
    (H, W, 3) at ``image_size`` (``rgb``/``rgb+state``; depth (H, W, 1) float32 [m] with
    ``depth``), ``robot`` float32 (19,) (joint pos/vel, tool pose, vacuum, held), and with
    ``state``/``rgb+state`` the privileged ``tiles`` (n * 7,) and ``slots`` (k * 6,), rows in the
    same index order as the discrete actions. With ``objects`` (no images), ``robot`` and
    ``tiles`` (rows, D), ``slots`` (rows, D) float32: one entity row per tile / slot in the
    same index order, without class ids (outline points [mm], colour, area, hole area, position,
    yaw, pickable / filled flag, valid), columns named by
    `envs.observations.objects.OBJECT_FIELDS`. Camera intrinsics/extrinsics at the observation
    size: ``task_spec.cameras``.

    ## Task description
    ``env.get_wrapper_attr("task_spec")`` is a frozen `envs.task_spec.TaskSpec`: the design's
    slots in the world, the pick and place areas and heights, the tile thickness, the camera
    models and the ``pick_place`` action codec. Agents are built from it and calibrate from
    ``calibration_views(camera)`` (``ScriptedAgent.from_env``). ``ground_truth()`` (privileged
    tile poses and classes) is for scoring and reports, never for decisions.

    ## Rewards
    ``sparse``: +reward_correct per newly filled slot, +reward_success when complete,
    -penalty per newly misplaced tile, dropped tile, lost tile, placed distractor and failed
    action. ``dense`` adds: -dense_reach x distance tool-to-nearest wanted tile (not holding),
    +dense_grasp while holding a wanted tile, -dense_carry x distance of the held tile to its
    nearest free slot. ``staged`` (the one-tile low-level task) adds potential-based terms
    for reach, seal, lift, transport, align and release (`envs.rewards`). Every term is in
    ``info`` as ``reward_<term>``.

    ## Starting State
    Arm at home, vacuum off, tiles laid out at random (non-overlapping, each placed against
    the ones before it or the tile area's edge, `envs.cell.layout`) on the input belt
    (``feed="all"``), the first ``stream_initial`` of them (``feed="stream"``; with
    ``stream_start="spaced"`` one supply period's belt travel apart from the upstream edge
    instead of at random) or the first
    ``batch_size`` (``feed="batch"``), lying at rest on the belt (``reset_settle`` > 0
    simulates that long after the reset; 0 by default: the tiles are put at their contact
    height). Manufacturing noise is re-drawn at every reset: each tile gets one of
    ``tile_variants`` outlines built with ``vertex_jitter`` (pre-built shapes in the tile's
    body, the ones not shown massless, without contacts and invisible, so a reset costs no
    rebuild) and a fresh glaze colour noise (``tile_color_jitter``); with ``tile_variants=1``
    both are drawn once when the env is built. ``env.unwrapped.cell.tiles`` holds the
    episode's tiles (outline, grasp point, colour). Further per-reset colour and light changes
    with ``color_randomization``/``light_randomization``, and camera poses with
    ``camera_position_jitter``/``camera_angle_jitter_deg`` (``task_spec.cameras`` keep the
    built poses). A realistic camera (lens distortion, exposure time blurring the moving
    belt) is set in the cell's camera sections (``cell={"input_camera": {...}}``).

    ## Episode End
    ``terminated`` when every slot is filled correctly or no real tile on the input belt, held
    or still to be fed can fill an open slot (stranded, dropped, lost and rejected tiles are out
    of reach; ``info["evaluation"]`` counts every real tile fed in one state,
    `envs.cell.accounting`);
    truncation by ``TimeLimit`` (``max_episode_steps`` at registration: 1000).

    ## Arguments
    ``gym.make("MosaicAssembly-v0", config=None, render_mode=None, **overrides)``; ``config``
    is an `EnvConfig`, a bundled name or a YAML path (``configs/env.yaml``); overrides are
    the flat `EnvConfig` fields: design, max_slots, action_mode, obs_mode, image_size, depth,
    belt_speed, reward_mode, execution, feed, distractor_rate, tile_variants, noise and
    randomisation levels, tolerances, reward weights. Unknown keys raise `EnvConfigError`
    listing the allowed ones. ``design_source="procedural"`` (with ``design_generator``,
    ``exclude_designs``, ``design_tries``) draws a new design of ``max_slots`` slots at every
    reset from ``np_random``, never one holding a class of ``exclude_designs``, and rebuilds the
    cell for it (`envs.design_source`); the spaces stay the same.

    ## Info
    ``sim_time`` [s since reset], ``tiles_placed`` (slots filled correctly), ``tiles_per_min``
    (per simulated minute), ``evaluation`` (the `evaluate()` dict), ``reward_<term>``,
    ``action_failed`` and ``action_error`` (why), ``is_success``, ``action_mask`` (discrete).

    ## Rendering
    ``rgb_array``: the overview camera (left) beside the input and output cameras (right),
    uint8. ``human``: MuJoCo's passive viewer (needs a display; a clear `MosaicEnvError`
    otherwise). Headless rendering uses ``MUJOCO_GL=egl`` unless set. ``render_fps`` is
    1 / ``control_dt`` in every mode (a pick_place step spans a whole cycle). In a process that
    has rendered already, start async/subprocess workers with ``spawn`` (a forked worker can
    hang in EGL). Every camera image leaves out the geoms the camera cannot see (same pixels,
    `envs.cell.view_culling`). Small images (up to ``cell.render.supersample_max_pixels``, e.g. the
    72 x 96 and 96 x 96 observations) are anti-aliased by rendering them at twice the size and
    averaging 2 x 2 blocks (``cell.render.supersample``), about half the cost of 4-sample
    multisampling in software rendering and as smooth; larger ones are multisampled
    (``cell.render.samples``). ``cell={"render": {"samples": 0}}`` turns anti-aliasing off
    (stair-stepped edges, cheaper still).

    ## Version History
    ``-v1``: ``pick_place`` is Box(5) without the pick-yaw entry that did nothing; discrete ids
    refuse masked actions (`ActionError`). ``-v0`` stays. Details and the rule: ``CHANGELOG.md``.
    """

    metadata = {  # noqa: RUF012 - Gymnasium convention
        "render_modes": ["rgb_array", "human"],
        "render_fps": round(1.0 / DEFAULT_CONTROL_DT),
    }

    def __init__(
        self,
        config: EnvConfig | str | Path | None = None,
        render_mode: str | None = None,
        **overrides: Any,
    ) -> None:
        if render_mode is not None:
            overrides["render_mode"] = render_mode
        self.config = source_config(
            load_env_config("env" if config is None else config, **overrides)
        )
        cfg = self.config
        self.render_mode = cfg.render_mode
        self.metadata = {**self.metadata, "render_fps": round(1.0 / cfg.control_dt)}
        self.designs = design_source(cfg)
        """The procedural design source (``design_source: procedural``), else None."""
        first = None
        if self.designs is not None:
            first = self.designs.draw(np.random.default_rng(FIRST_DRAW_SEED))
        self.pool = design_pool(cfg, self.designs)
        """Designs prepared ahead (``design_pool`` set, procedural source), else None."""
        self._pcfg = load_planner_config(cfg.planner)
        self.ik = IKSolver(
            build_arm_model(cfg.cell, with_cell=False), self._pcfg.ik, self._pcfg.limits
        )
        self._frames = FrameSchedule()
        self._viewer: Any = None
        self._build(first, seed=0)
        self.action_space = self.actions.space
        self.observation_space = self.observer.space
        self._t0 = 0.0
        self._needs_reset = True
        self._closed = False
        self._mask: np.ndarray | None = None

    def _build(self, drawn: Design | None, seed: int, cell: Cell | None = None) -> None:
        """Build the cell of a design (None: ``design``) and its parts (`envs.env_parts`)."""
        p = build_parts(self.config, drawn, seed, self.ik, self._pcfg, cell=cell)
        self.cell, self.task, self.observer, self.index = p.cell, p.task, p.observer, p.index
        self.pick_area, self.place_area, self.codec = p.pick_area, p.place_area, p.codec
        self.executor, self.actions = p.executor, p.actions
        self.task_spec: TaskSpec = p.task_spec
        """What agents may know besides the observations (see `envs.task_spec`); with a
        procedural design source, of the current episode's design."""
        self.calibration_views = self.cell.views.calibration_views
        """Checkerboard pictures to calibrate a camera (`envs.cell.views.CellViews`)."""
        if self.executor is not None and self._frames:
            self.executor.on_physics_step = self._tick

    def _draw_design(self, rng: np.random.Generator) -> None:
        """Procedural source: replace the cell by one of a design drawn from ``rng``."""
        assert self.designs is not None
        drawn = draw_design(self.pool, self.config, self.designs, rng)  # `envs.pool`
        if self._viewer is not None:
            self._viewer.close()
            self._viewer = None
        self.cell.close()
        self._build(drawn.design, drawn.seed, drawn.cell)

    # ------------------------------------------------------------------ Gymnasium API
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, Any], dict[str, Any]]:
        """Start an episode: new tile layout (and colours/lights if enabled), arm at home."""
        self._check_open()
        super().reset(seed=seed)
        if self.designs is not None:
            self._draw_design(self.np_random)
        cell, rng = self.cell, self.np_random
        self.task.initialize_episode(rng)
        self._t0 = cell.time
        self.actions.reset()
        self.index.reset(rng)
        self._frames.restart(cell.time)
        self._needs_reset = False
        evaluation = self.task.last_evaluation  # taken at the episode's set-up; nothing moved
        obs = self._observe(evaluation)
        if self.pool is not None:
            self.pool.plan(rng, seed)
        return obs, self._info(evaluation, dict.fromkeys(REWARD_TERMS, 0.0), False, "")

    def step(self, action: np.ndarray) -> tuple[dict[str, Any], float, bool, bool, dict[str, Any]]:
        """Apply one action (see the class docstring), evaluate, observe.

        Raises:
            MosaicEnvError: Called before `reset` or after `close`.
            ActionError: Wrong shape, NaN/inf or out-of-range action.
        """
        self._check_ready("step")
        a = self.actions.validate(action)
        a = self.actions.noisy(a, self.np_random)
        if self._mask is not None:
            check_allowed(a, self._mask, self.action_space, self.config.invalid_actions)
            a = self.index.decode(a)
        result = self.actions.apply(a)
        if self._frames:
            self._tick()
        evaluation = self.task.evaluate()
        terms = self.task.rewards(evaluation, result.failed)
        reward = float(sum(terms.values()))
        terminated = evaluation.success or evaluation.failure
        obs = self._observe(evaluation)
        info = self._info(evaluation, terms, result.failed, result.reason)
        if self.render_mode == "human":
            self.render()
        return obs, reward, terminated, False, info

    def render(self) -> np.ndarray | None:
        """``rgb_array``: overview (left) + input and output camera (right), uint8 (H, W, 3).

        Raises:
            MosaicEnvError: ``human`` without a display, or the env is closed.
        """
        self._check_open()
        if self.render_mode == "human":
            self._human()
            return None
        if self.render_mode != "rgb_array":
            return None
        h, w = self.cell.cfg.render.overview_size
        overview = self.cell.render("overview", h, w)
        ph = h // CAMERA_PANEL_DIVISOR
        cam = self.cell.cfg.input_camera
        pw = round(ph * cam.width / cam.height)
        panels = [self.cell.render(name, ph, pw) for name in CAMERAS]
        return np.concatenate([overview, np.concatenate(panels, axis=0)], axis=1)

    def _human(self) -> None:
        if self._viewer is None:
            if not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
                raise MosaicEnvError(
                    "render_mode='human' needs a display (DISPLAY is not set); use "
                    "render_mode='rgb_array' on a headless machine"
                )
            import mujoco.viewer  # noqa: PLC0415 - only with a display

            self._viewer = mujoco.viewer.launch_passive(self.cell.model, self.cell.data)
        self._viewer.sync()

    def close(self) -> None:
        """Free renderers and the viewer (safe to call twice)."""
        if self._closed:
            return
        if self._viewer is not None:
            self._viewer.close()
            self._viewer = None
        if self.pool is not None:
            self.pool.close()
        self.cell.close()
        self._closed = True

    # ------------------------------------------------------------------ extras
    def action_masks(self) -> np.ndarray:
        """Allowed discrete indices now (`envs.masks`); `MosaicEnvError` in other action modes."""
        if (mode := self.config.action_mode) != "pick_place_discrete":
            raise MosaicEnvError(f"action_masks() needs pick_place_discrete, not {mode!r}")
        self._check_ready("action_masks")
        return self._mask.copy()  # type: ignore[union-attr] # set at reset

    def evaluate(self) -> Evaluation:
        """The task's evaluation now (see `envs.task.Evaluation`)."""
        return self.task.evaluate()

    def camera_model(
        self, name: str, height: int | None = None, width: int | None = None
    ) -> CameraModel:
        """Intrinsics/extrinsics of ``"input"`` or ``"output"`` (or ``*_camera``) at a size.

        Args:
            name: Camera.
            height: Image height [px]; default the observation's ``image_size``.
            width: Image width [px].

        Raises:
            CellError: Unknown camera (the message lists the allowed names).
        """
        full = name if name.endswith("_camera") else f"{name}_camera"
        h, w = self.config.image_size
        return self.cell.camera_model(full, height or h, width or w)

    def pick_place_action(
        self, pick_xy: np.ndarray, pick_yaw: float, place_xy: np.ndarray, place_yaw: float
    ) -> np.ndarray:
        """Normalised ``pick_place`` action from world poses with absolute yaws [m, rad].

        Raises:
            ActionError: A position outside its area.
        """
        p, q = np.asarray(pick_xy, float), np.asarray(place_xy, float)
        cmd = PickPlaceCommand.between_yaws((p[0], p[1]), pick_yaw, (q[0], q[1]), place_yaw)
        return self.codec.encode(cmd)

    def expert_action(self, tile: int, slot: int) -> np.ndarray:
        """Privileged action moving ``tile`` into ``slot`` exactly (pick_place modes only).

        For baselines, tests and debugging: the ground-truth grasp point and yaws. ``tile`` and
        ``slot`` are the cell's (design) indices; in ``pick_place_discrete`` the action is
        encoded with the current index maps (``env.unwrapped.index``).

        Raises:
            MosaicEnvError: The action mode is not a pick_place mode.
        """
        mode = self.config.action_mode
        if mode == "pick_place_discrete":
            return self.index.encode(tile, slot)
        if mode != "pick_place":
            raise MosaicEnvError(f"expert_action needs a pick_place mode, not {mode!r}")
        return self.codec.encode(transfer_poses(self.cell, tile, slot))

    def ground_truth(self) -> GroundTruth:
        """Privileged tile poses and classes now (scoring and reports only)."""
        return self.task.ground_truth()

    def reject(
        self, pick_xy: tuple[float, float], pick_yaw: float = 0.0
    ) -> tuple[dict[str, Any], float, bool, bool, dict[str, Any]]:
        """Pick the tile at ``pick_xy`` [m] and drop it into the reject bin (pick_place modes).

        A step outside the action space, for a cell that clears tiles it cannot use (a
        defective or unrecognised tile holding the next batch back): one planned cycle from the
        pick point to ``reject_past_belt_end`` past the input belt's end, released
        ``reject_release_height`` above the belt. The tile counts as ``rejected``, not lost.
        Returns what `step` returns.

        Raises:
            MosaicEnvError: Not a pick_place mode, before `reset` or after `close`.
        """
        self._check_ready("reject")
        if self.executor is None:
            raise MosaicEnvError(f"reject needs a pick_place mode, not {self.config.action_mode!r}")
        cfg, geo = self.config, self.cell.geometry
        drop = (geo.input_belt_end + cfg.reject_past_belt_end, geo.input_y)
        cmd = PickPlaceCommand((float(pick_xy[0]), float(pick_xy[1])), float(pick_yaw), drop, 0.0)
        result = self.executor.run(cmd, place_z=geo.belt_top + cfg.reject_release_height)
        if self._frames:
            self._tick()
        evaluation = self.task.evaluate()
        terms = self.task.rewards(evaluation, result.failed)
        terminated = evaluation.success or evaluation.failure
        obs = self._observe(evaluation)
        info = self._info(evaluation, terms, result.failed, result.reason)
        return obs, float(sum(terms.values())), terminated, False, info

    def move_home(self) -> dict[str, Any]:
        """Move the arm home with one planned move; returns a fresh observation, as `step`'s.

        For a picture of the work after an episode (the arm out of the cameras' view):
        ``dynamic`` execution tracks a time-optimal joint move with the servos (simulated
        time advances); otherwise the arm is put at home. Nothing is evaluated or rewarded.

        Raises:
            MosaicEnvError: Called before `reset` or after `close`.
        """
        self._check_ready("move_home")
        home = np.asarray(self.cell.cfg.robot.home, float)
        if self.executor is not None:
            self.executor.move_to(home)
        else:
            self.cell.set_qpos(home)
        self.actions.reset()
        return self._observe(self.task.evaluate())

    def add_frame_listener(self, listener: Callable[[], None], fps: float) -> None:
        """Call ``listener()`` every ``1 / fps`` s of simulated time, also inside a step.

        A ``pick_place`` step spans a whole cycle; a listener that renders (``env.render()``
        or ``env.unwrapped.cell.render(...)``) records a video of the motion within it. In the
        other modes it is called at most once per step (after it). The schedule restarts at
        each reset.

        Raises:
            MosaicEnvError: ``fps`` is not a positive finite number.
        """
        if not (np.isfinite(fps) and fps > 0):
            raise MosaicEnvError(f"fps must be a positive number of frames per second, got {fps}")
        self._frames.add(listener, 1.0 / fps, self.cell.time)
        if self.executor is not None:
            self.executor.on_physics_step = self._tick

    def _tick(self) -> None:
        self._frames.tick(self.cell.time)

    # ------------------------------------------------------------------ helpers
    def _observe(self, evaluation: Evaluation) -> dict[str, Any]:
        """The observation, privileged rows in the agent's index order (`envs.indexing`)."""
        self.index.update()
        if isinstance(space := self.action_space, gym.spaces.MultiDiscrete):
            self._mask = action_mask(self.cell, self.index, evaluation.slot_filled, space.nvec)
        obs = self.observer.observe(self.np_random, evaluation)
        if "tiles" in obs:
            obs["tiles"], obs["slots"] = self.index.permute_state(obs["tiles"], obs["slots"])
        return obs

    def _info(
        self, evaluation: Evaluation, terms: dict[str, float], failed: bool, reason: str
    ) -> dict[str, Any]:
        t = self.cell.time - self._t0
        placed = evaluation.correct
        info: dict[str, Any] = {
            "sim_time": t,
            "tiles_placed": placed,
            "tiles_per_min": evaluation.tiles_per_min(t),
            "evaluation": evaluation.as_dict(),
            "is_success": evaluation.success,
            "action_failed": failed,
            "action_error": reason,
        }
        info.update({_INFO_KEYS.get(k) or f"reward_{k}": float(v) for k, v in terms.items()})
        if self._mask is not None:
            info["action_mask"] = self._mask.copy()
        return info

    def _check_open(self) -> None:
        if self._closed:
            raise MosaicEnvError("the environment is closed; make a new one")

    def _check_ready(self, name: str) -> None:
        self._check_open()
        if self._needs_reset:
            raise MosaicEnvError(f"{name}() called before reset(): call env.reset() first")


__all__ = ["ActionError", "MosaicAssemblyEnv", "MosaicEnvError"]
