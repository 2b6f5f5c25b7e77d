"""Configuration of the `MosaicAssembly-v0` environment (frozen, strict, with units).

Defaults live in ``configs/env.yaml``. Every field can be overridden by keyword, flat::

    cfg = load_env_config(action_mode="joint", image_size=64, belt_speed=0.1)

Unknown keys and unknown mode names raise `EnvConfigError` listing what is allowed.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

from configs import ConfigError, load_config

ACTION_MODES = ("joint", "cartesian", "pick_place", "pick_place_discrete")
"""Allowed ``action_mode`` values."""
OBS_MODES = ("rgb", "state", "rgb+state")
"""Allowed ``obs_mode`` values."""
REWARD_MODES = ("sparse", "dense", "staged")
"""Allowed ``reward_mode`` values."""
EXECUTIONS = ("dynamic", "kinematic")
"""Allowed ``execution`` values (``pick_place`` modes)."""
FEEDS = ("all", "stream", "batch")
"""Allowed ``feed`` values."""
RENDER_MODES = ("rgb_array", "human")
"""Allowed ``render_mode`` values (or None)."""
TILE_ORDERS = ("belt", "shuffled", "design")
"""Allowed ``tile_order`` values (see `envs.indexing`)."""
SLOT_ORDERS = ("mesh", "shuffled", "design")
"""Allowed ``slot_order`` values (see `envs.indexing`)."""
ROTATION_FRAMES = ("tile", "slot")
"""Allowed ``rotation_frame`` values (see `envs.indexing`)."""


class EnvConfigError(ConfigError):
    """Bad environment configuration: unknown key or mode, or an invalid value."""


@dataclass(frozen=True)
class EnvConfig:
    """Settings of `MosaicAssembly-v0`.

    Attributes:
        design: Bundled design name (``configs/designs``) or path to a design YAML.
        max_slots: Use only the first ``max_slots`` slots (and their tiles); 0 uses all.
        cell: Cell configuration: bundled name or path (``configs/cell.yaml``).
        planner: Planner configuration: bundled name or path (``configs/planner.yaml``).
        action_mode: One of `ACTION_MODES`.
        obs_mode: One of `OBS_MODES` (``state`` = robot + privileged state, no images).
        image_size: Observation image (height, width) [px]; an int gives a square image. The
            default 72 x 96 keeps the cameras' 4:3 aspect: a square image narrows the
            horizontal field (fixed vertical field of view) and crops the ends of the tile
            area.
        depth: Add depth images [m] to the observation.
        belt_speed: Input belt speed [m/s].
        reward_mode: One of `REWARD_MODES`.
        execution: One of `EXECUTIONS` (pick_place modes only).
        chain_cycles: Dynamic pick_place: a step's cycle ends at rest at the place contact
            (vacuum off, pad 0.5 mm above the released tile) and the next step's cycle leaves
            it vertically, blended into its move to the pick, as a real cell chains its
            cycles; False ends every cycle at rest at the approach point above the place.
        feed: ``all`` tiles at reset, a ``stream`` along the input belt, or ``batch``es of
            ``batch_size`` over the whole tile area, the next one indexed in once the input
            side holds no real tile (leftover distractors leave with their batch).
        stream_period: Time between streamed tiles [s].
        stream_initial: Tiles laid out at reset when streaming.
        batch_size: Tiles per batch [count].
        batch_index_time: From the last real tile of a batch picked to the next batch at rest
            [s].
        distractor_rate: Distractor tiles per real tile.
        vertex_jitter: Std of tile outline (manufacturing) noise [m].
        tile_color_jitter: Std of tile glaze colour noise per RGB channel [0..1 units].
        tile_variants: Noisy variants built per tile [count]: each reset gives every tile one
            of its variants at random (outline noise) and a fresh colour noise, so episodes
            differ in manufacturing noise without rebuilding the model (each tile's body
            holds V shapes; the ones not shown are massless, without contacts and invisible).
            1: the noise is drawn once when the env is built and kept by every episode.
            Build time and model size grow about linearly with it, a physics step by ~5 %
            per variant (8: ~+35 %); reset and render time do not.
        color_randomization: Std of a per-reset multiplicative tile colour change (0: off).
        light_randomization: Std of a per-reset multiplicative light change (0: off).
        action_noise: Std of Gaussian noise added to continuous actions, in normalised units.
        obs_noise: Std of Gaussian noise on joint position observations [rad].
        control_dt: Control period of the joint and cartesian modes [s].
        tool_speed: Largest tool translation speed of the cartesian mode [m/s].
        tool_yaw_rate: Largest tool yaw rate of the cartesian mode [rad/s].
        tool_z_range: Tool height range above the belt top of the cartesian mode [m].
        pick_margin: Margin added around the input tile area for pick poses [m].
        place_margin: Margin added around the mesh for place poses [m].
        rotation_bins: Rotation choices of ``pick_place_discrete`` (multiples of 2 pi / bins).
        tile_order: What a tile index names (discrete actions, ``tiles`` rows): one of
            `TILE_ORDERS`; ``belt``: rank on the input belt from its downstream end.
        slot_order: What a slot index names: one of `SLOT_ORDERS`; ``mesh``: raster order on
            the mesh.
        rotation_frame: What a rotation index counts from: one of `ROTATION_FRAMES`;
            ``tile``: the slot-aligned pose nearest to how the tile lies.
        kinematic_settle: Physics settling time after a kinematic place [s].
        failed_action_time: Simulated time charged for an action that cannot execute [s].
        reset_settle: Physics time simulated after reset so tiles rest [s].
        layout_tries: Layout draws tried at reset until the tiles fit the belt.
        position_tolerance: Placement position tolerance [m].
        yaw_tolerance_deg: Placement yaw tolerance [deg], modulo the tile's symmetry.
        mesh_height_tolerance: A tile on the mesh lies flat on the sheet (can fill a slot)
            within this height of resting on it [m]; higher (e.g. stacked on another tile)
            it is misplaced.
        max_tilt_deg: ... and when tilted less than this from flat [deg].
        reward_correct: Sparse reward per correctly filled slot.
        reward_success: Bonus when the mosaic is complete.
        penalty_misplaced: Penalty per newly misplaced tile (positive number).
        penalty_dropped: Penalty per dropped tile.
        penalty_lost: Penalty per tile lost off the belt.
        penalty_distractor: Penalty per distractor placed on the mesh.
        penalty_failed_action: Penalty for an action that cannot execute (unreachable, empty).
        dense_reach: Dense: weight of minus the tool's distance to the nearest wanted tile [1/m].
        dense_grasp: Dense: reward for grasping a wanted tile.
        dense_carry: Dense: weight of minus the held tile's distance to its nearest free slot [1/m].
        render_mode: None, ``rgb_array`` or ``human``.
    """

    design: str = "paper_mixed"
    max_slots: int = 0
    cell: str = "cell"
    planner: str = "planner"
    action_mode: str = "pick_place"
    obs_mode: str = "rgb"
    image_size: tuple[int, int] = (72, 96)
    depth: bool = False
    belt_speed: float = 0.0
    reward_mode: str = "sparse"
    execution: str = "dynamic"
    chain_cycles: bool = True
    feed: str = "all"
    stream_period: float = 2.5
    stream_initial: int = 1
    batch_size: int = 16
    batch_index_time: float = 0.5
    distractor_rate: float = 0.0
    vertex_jitter: float = 0.0002
    tile_color_jitter: float = 0.02
    tile_variants: int = 8
    color_randomization: float = 0.0
    light_randomization: float = 0.0
    action_noise: float = 0.0
    obs_noise: float = 0.0
    control_dt: float = 0.04
    tool_speed: float = 0.5
    tool_yaw_rate: float = 3.0
    tool_z_range: tuple[float, float] = (0.004, 0.3)
    pick_margin: float = 0.0
    place_margin: float = 0.0
    rotation_bins: int = 4
    tile_order: str = "belt"
    slot_order: str = "mesh"
    rotation_frame: str = "tile"
    kinematic_settle: float = 0.01
    failed_action_time: float = 0.04
    reset_settle: float = 0.16
    layout_tries: int = 20
    position_tolerance: float = 0.0015
    yaw_tolerance_deg: float = 2.0
    mesh_height_tolerance: float = 0.003
    max_tilt_deg: float = 8.0
    reward_correct: float = 1.0
    reward_success: float = 5.0
    penalty_misplaced: float = 0.5
    penalty_dropped: float = 0.5
    penalty_lost: float = 0.5
    penalty_distractor: float = 0.5
    penalty_failed_action: float = 0.1
    dense_reach: float = 0.5
    dense_grasp: float = 0.2
    dense_carry: float = 0.5
    render_mode: str | None = None

    def __post_init__(self) -> None:
        raw: Any = self.image_size
        if isinstance(raw, int):
            raw = (raw, raw)
        size = tuple(int(v) for v in raw)
        object.__setattr__(self, "image_size", size)
        if len(size) != 2 or min(size) < 1:
            raise EnvConfigError(f"image_size must be (height, width) >= 1 px, got {size}")
        for name, allowed in (
            ("action_mode", ACTION_MODES),
            ("obs_mode", OBS_MODES),
            ("reward_mode", REWARD_MODES),
            ("execution", EXECUTIONS),
            ("feed", FEEDS),
            ("tile_order", TILE_ORDERS),
            ("slot_order", SLOT_ORDERS),
            ("rotation_frame", ROTATION_FRAMES),
        ):
            value = getattr(self, name)
            if value not in allowed:
                raise EnvConfigError(f"unknown {name} {value!r}; allowed: {list(allowed)}")
        if self.render_mode is not None and self.render_mode not in RENDER_MODES:
            raise EnvConfigError(
                f"unknown render_mode {self.render_mode!r}; allowed: None, {list(RENDER_MODES)}"
            )
        positive = (
            "control_dt",
            "tool_speed",
            "tool_yaw_rate",
            "position_tolerance",
            "yaw_tolerance_deg",
            "kinematic_settle",
            "failed_action_time",
            "batch_index_time",
        )
        for name in positive:
            if not getattr(self, name) > 0:
                raise EnvConfigError(f"{name} must be > 0, got {getattr(self, name)!r}")
        nonneg = (
            "max_slots",
            "belt_speed",
            "distractor_rate",
            "vertex_jitter",
            "tile_color_jitter",
            "color_randomization",
            "light_randomization",
            "action_noise",
            "obs_noise",
            "reset_settle",
            "pick_margin",
            "place_margin",
        )
        for name in nonneg:
            if not getattr(self, name) >= 0:
                raise EnvConfigError(f"{name} must be >= 0, got {getattr(self, name)!r}")
        for name in ("rotation_bins", "layout_tries", "tile_variants", "batch_size"):
            value = getattr(self, name)
            if not isinstance(value, int) or isinstance(value, bool) or value < 1:
                raise EnvConfigError(f"{name} must be an int >= 1, got {value!r}")


def allowed_keys() -> list[str]:
    """Names of every `EnvConfig` field (the allowed keyword overrides)."""
    return [f.name for f in fields(EnvConfig)]


def load_env_config(config: EnvConfig | str | Path | None = "env", **overrides: Any) -> EnvConfig:
    """Build an `EnvConfig` from a dataclass, a bundled name or path, plus flat overrides.

    Args:
        config: An `EnvConfig`, a bundled YAML name (``"env"``), a path, or None (defaults).
        **overrides: Field values replacing the config's (``image_size=64``).

    Raises:
        EnvConfigError: Unknown key (lists the allowed ones), unknown mode or a bad value.
    """
    if isinstance(config, EnvConfig):
        base = {f.name: getattr(config, f.name) for f in fields(EnvConfig)}
        unknown = sorted(set(overrides) - set(base))
        if unknown:
            raise EnvConfigError(f"unknown key(s) {unknown} for EnvConfig; allowed: {sorted(base)}")
        base.update(overrides)
        config, overrides = None, base
    if "image_size" in overrides and isinstance(overrides["image_size"], int):
        overrides["image_size"] = (overrides["image_size"],) * 2
    try:
        return load_config(EnvConfig, config, **overrides)
    except EnvConfigError:
        raise
    except ConfigError as exc:
        raise EnvConfigError(str(exc)) from exc


__all__ = [
    "ACTION_MODES",
    "EXECUTIONS",
    "FEEDS",
    "OBS_MODES",
    "RENDER_MODES",
    "REWARD_MODES",
    "ROTATION_FRAMES",
    "SLOT_ORDERS",
    "TILE_ORDERS",
    "EnvConfig",
    "EnvConfigError",
    "allowed_keys",
    "load_env_config",
]
