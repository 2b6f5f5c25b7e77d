"""Configuration of the `MosaicAssembly-v0` environment (frozen, strict, with units).

Defaults live in ``configs/env.yaml``; the cell's configuration is nested in it (``cell:``, the
bundled ``configs/cell.yaml`` with the env's changes). Every field can be overridden by keyword,
and the cell's most used keys by flat keywords (`CELL_KEYS`)::

    cfg = load_env_config(action_mode="joint", image_size=64, belt_speed=0.1)
    cfg.cell.input_belt.speed  # 0.1

Unknown keys and unknown mode names raise `EnvConfigError` listing what is allowed.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any, Literal, get_args

from configs import ConfigError, from_dict, load_yaml, resolve_path
from configs.checks import check_fields, checked
from envs.cell.config import FEED_MODES, CellConfig
from envs.env_cell_keys import (
    CELL_KEYS,
    ENV_CELL_CHANGES,
    EnvConfigError,
    env_cell,
    merge_cell,
    split_cell,
)
from spatial.tolerance import PLACEMENT_POSITION_TOLERANCE_M, PLACEMENT_YAW_TOLERANCE_DEG

ActionMode = Literal["joint", "cartesian", "pick_place", "pick_place_discrete"]
ObsMode = Literal["rgb", "state", "rgb+state", "objects"]
ObjectsSource = Literal["privileged", "perception"]
RewardMode = Literal["sparse", "dense", "staged"]
Execution = Literal["dynamic", "kinematic"]
RenderMode = Literal["rgb_array", "human"]
TileOrder = Literal["belt", "shuffled", "design"]
SlotOrder = Literal["mesh", "shuffled", "design"]
RotationFrame = Literal["tile", "slot", "shape"]
InvalidActions = Literal["fail", "refuse"]
DesignSource = Literal["fixed", "procedural"]
DEFAULT_ROTATION_BINS = 4
"""Rotation choices of ``pick_place_discrete`` by default: quarter turns (this 4's one home)."""
ACTION_MODES: tuple[str, ...] = get_args(ActionMode)
"""Allowed ``action_mode`` values."""
OBS_MODES: tuple[str, ...] = get_args(ObsMode)
"""Allowed ``obs_mode`` values."""
OBJECTS_SOURCES: tuple[str, ...] = get_args(ObjectsSource)
"""Allowed ``objects_source`` values."""
OBJECTS_POINTS_RANGE = (8, 256)
"""Allowed ``objects_points`` (inclusive)."""
REWARD_MODES: tuple[str, ...] = get_args(RewardMode)
"""Allowed ``reward_mode`` values."""
EXECUTIONS: tuple[str, ...] = get_args(Execution)
"""Allowed ``execution`` values (``pick_place`` modes)."""
FEEDS = FEED_MODES
"""Allowed ``feed`` values (`envs.cell.config.FEED_MODES`)."""
RENDER_MODES: tuple[str, ...] = get_args(RenderMode)
"""Allowed ``render_mode`` values (or None)."""
TILE_ORDERS: tuple[str, ...] = get_args(TileOrder)
"""Allowed ``tile_order`` values (see `envs.indexing`)."""
SLOT_ORDERS: tuple[str, ...] = get_args(SlotOrder)
"""Allowed ``slot_order`` values (see `envs.indexing`)."""
ROTATION_FRAMES: tuple[str, ...] = get_args(RotationFrame)
"""Allowed ``rotation_frame`` values (see `envs.indexing`)."""
INVALID_ACTIONS: tuple[str, ...] = get_args(InvalidActions)
"""Allowed ``invalid_actions`` values (see `envs.masks`)."""
DESIGN_SOURCES: tuple[str, ...] = get_args(DesignSource)
"""Allowed ``design_source`` values (see `envs.design_source`)."""


@dataclass(frozen=True)
class EnvConfig:
    """Settings of `MosaicAssembly-v0`.

    Attributes:
        design: Bundled design name (``configs/designs``) or path to a design YAML.
        max_slots: Use only the first ``max_slots`` slots (and their tiles); 0 uses all.
        design_source: One of `DESIGN_SOURCES`: ``fixed`` builds ``design`` once;
            ``procedural`` draws a new design of exactly ``max_slots`` slots (>= 1 required)
            at every reset from the env's ``np_random`` (`envs.design_source`).
        design_generator: ``procedural``: the design generator's parameters, a bundled name
            (``configs/``) or path of a `qshape.design.generator_config.GeneratorConfig` file.
        exclude_designs: ``procedural``: designs (bundled names or paths) whose tile classes a
            drawn design never holds (`qshape.design.exclusion`).
        design_tries: ``procedural``: draws per reset before a design free of excluded
            classes is given up (`envs.design_source.DesignSourceError`).
        design_pool: ``procedural``: prepare the next designs and their cells ahead in a
            worker process (`envs.pool`): a bundled name (``design_pool``) or path of
            a `envs.pool.DesignPoolConfig` file; None (default): off. Same episodes
            for the same seed either way; a ``fixed`` source ignores it.
        cell: The cell (`envs.cell.config.CellConfig`), nested: in YAML a bundled name or
            path, or a mapping ``{config: <name or path>, <section>: {<key>: value}}`` that
            changes sections of that cell file key by key. The input belt's speed, the tile
            feed and the tiles' noise and variants live here (``cell.input_belt.speed``,
            ``cell.tiles.feed``, ...); the flat keywords of `CELL_KEYS` (``belt_speed=0.1``,
            ``feed="stream"``, ...) still set them.
        planner: Planner configuration: bundled name or path (``configs/planner.yaml``).
        action_mode: One of `ACTION_MODES`.
        obs_mode: One of `OBS_MODES` (``state`` = robot + privileged state, no images;
            ``objects`` = robot + entity rows without class ids, `envs.observations.objects`).
        objects_points: ``objects``: outline points per row, in `OBJECTS_POINTS_RANGE`.
        objects_rows: ``objects``: rows of ``tiles`` and of ``slots`` (padded with zero rows,
            ``valid`` 0); None: the episode's tile and slot counts.
        objects_noise_mm: ``objects``: std of Gaussian noise on each tile outline point [mm]
            (0: off).
        objects_source: ``objects``: where the rows come from, one of `OBJECTS_SOURCES`
            (``privileged``: the simulator's poses and the built outlines; ``perception``: the
            tile rows from the input camera's picture, `envs.observations.objects_perception`).
        objects_image_size: ``objects`` with ``perception``: (height, width) [px] the input
            camera is rendered at for the extraction (independent of ``image_size``).
        objects_gate_mm: ``objects`` with ``perception``: a perceived figure fills tile ``i``'s
            row only when its centroid lies within this distance [mm] of tile ``i``'s.
        image_size: Observation image (height, width) [px]; an int gives a square image. The
            default 72 x 96 keeps the cameras' 4:3 aspect: a square image narrows the
            horizontal field (fixed vertical field of view) and crops the ends of the tile
            area.
        depth: Add depth images [m] to the observation.
        reward_mode: One of `REWARD_MODES`.
        execution: One of `EXECUTIONS` (pick_place modes only).
        pick_yaw_entry: ``pick_place`` actions carry the tile's yaw at the pick: Box(6), the
            ``-v0`` layout (the entry changes nothing: no grasp offset for it to turn); False:
            Box(5) = pick x, y, place x, y, rotation (the ``-v1`` ids).
        chain_cycles: Dynamic pick_place: a step's cycle ends at rest at the place contact
            (vacuum off, pad 0.5 mm above the released tile) and the next step's cycle leaves
            it vertically, blended into its move to the pick, as a real cell chains its
            cycles; False ends every cycle at rest at the approach point above the place.
        color_randomization: Std of a per-reset multiplicative tile colour change (0: off).
        light_randomization: Std of a per-reset multiplicative light change (0: off).
        camera_position_jitter: Per-reset camera shift, uniform in +- this per axis [m]
            (0: off); both cameras. ``task_spec.cameras`` keep the built poses.
        camera_angle_jitter_deg: Per-reset camera turn, uniform in +- this about each axis
            of the camera's frame [deg] (0: off).
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
            ``tile``: the slot-aligned pose nearest to how the tile lies; ``shape``: the same,
            the tile's offset from its slot counted modulo the figure's symmetry (so the
            right index depends only on what a camera can see).
        invalid_actions: What a ``pick_place_discrete`` action its mask forbids does (one of
            `INVALID_ACTIONS`, `envs.masks`): ``fail`` charges ``failed_action_time`` and the
            failed-action penalty; ``refuse`` raises `ActionError` (no time passes).
        kinematic_settle: Physics settling time after a kinematic place [s].
        failed_action_time: Simulated time charged for an action that cannot execute [s].
        reject_past_belt_end: How far past the input belt's end `MosaicAssemblyEnv.reject`
            releases a tile over the reject bin [m].
        reject_release_height: Height above the belt top of that release [m].
        reset_settle: Physics time simulated after reset [s] (0: none; tiles are laid at rest).
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
    max_slots: int = checked(0, ge=0)
    design_source: DesignSource = checked("fixed", choices=DESIGN_SOURCES)
    design_generator: str = "design_generator_train"
    exclude_designs: tuple[str, ...] = ()
    design_tries: int = checked(50, ge=1, integer=True)
    design_pool: str | None = None
    cell: CellConfig = field(default_factory=lambda: env_cell("cell", ENV_CELL_CHANGES))
    planner: str = "planner"
    action_mode: ActionMode = checked("pick_place", choices=ACTION_MODES)
    obs_mode: ObsMode = checked("rgb", choices=OBS_MODES)
    objects_points: int = 32
    objects_rows: int | None = None
    objects_noise_mm: float = checked(0.0, ge=0)
    objects_source: ObjectsSource = checked("privileged", choices=OBJECTS_SOURCES)
    objects_image_size: tuple[int, int] = (492, 656)
    objects_gate_mm: float = 5.0
    image_size: tuple[int, int] = (72, 96)
    depth: bool = False
    reward_mode: RewardMode = checked("sparse", choices=REWARD_MODES)
    execution: Execution = checked("dynamic", choices=EXECUTIONS)
    pick_yaw_entry: bool = True
    chain_cycles: bool = True
    color_randomization: float = checked(0.0, ge=0)
    light_randomization: float = checked(0.0, ge=0)
    camera_position_jitter: float = checked(0.0, ge=0)
    camera_angle_jitter_deg: float = checked(0.0, ge=0)
    action_noise: float = checked(0.0, ge=0)
    obs_noise: float = checked(0.0, ge=0)
    control_dt: float = checked(0.04, gt=0)
    tool_speed: float = checked(0.5, gt=0)
    tool_yaw_rate: float = checked(3.0, gt=0)
    tool_z_range: tuple[float, float] = (0.004, 0.3)
    pick_margin: float = checked(0.0, ge=0)
    place_margin: float = checked(0.0, ge=0)
    rotation_bins: int = checked(DEFAULT_ROTATION_BINS, ge=1, integer=True)
    tile_order: TileOrder = checked("belt", choices=TILE_ORDERS)
    slot_order: SlotOrder = checked("mesh", choices=SLOT_ORDERS)
    rotation_frame: RotationFrame = checked("tile", choices=ROTATION_FRAMES)
    invalid_actions: InvalidActions = checked("fail", choices=INVALID_ACTIONS)
    kinematic_settle: float = checked(0.01, gt=0)
    failed_action_time: float = checked(0.04, gt=0)
    reject_past_belt_end: float = checked(0.08, gt=0)
    reject_release_height: float = checked(0.03, gt=0)
    reset_settle: float = checked(0.0, ge=0)
    layout_tries: int = checked(20, ge=1, integer=True)
    position_tolerance: float = checked(PLACEMENT_POSITION_TOLERANCE_M, gt=0)
    yaw_tolerance_deg: float = checked(PLACEMENT_YAW_TOLERANCE_DEG, gt=0)
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
    render_mode: RenderMode | None = checked(None, choices=(None, *RENDER_MODES))

    def __post_init__(self) -> None:
        raw: Any = self.image_size
        if isinstance(raw, int):
            raw = (raw, raw)
        size = tuple(int(v) for v in raw)
        object.__setattr__(self, "image_size", size)
        if len(size) != 2 or min(size) < 1:
            raise EnvConfigError(f"image_size must be (height, width) >= 1 px, got {size}")
        check_fields(self, EnvConfigError)
        self._check_objects()
        lo_hi = tuple(self.tool_z_range)
        if len(lo_hi) != 2 or not 0 <= lo_hi[0] < lo_hi[1]:  # noqa: PLR2004 - (low, high)
            raise EnvConfigError(
                f"tool_z_range must be (low, high) [m] with 0 <= low < high, got {lo_hi!r}"
            )
        if self.design_source == "fixed" and self.exclude_designs:
            raise EnvConfigError(
                "exclude_designs needs design_source 'procedural' (a fixed design is not drawn)"
            )
        if self.design_source == "procedural" and self.max_slots < 1:
            raise EnvConfigError(
                "design_source 'procedural' needs max_slots >= 1 (the spaces are built for "
                f"that many tiles and slots), got max_slots={self.max_slots!r}"
            )

    def _check_objects(self) -> None:
        lo, hi = OBJECTS_POINTS_RANGE
        p = self.objects_points
        if not isinstance(p, int) or isinstance(p, bool) or not lo <= p <= hi:
            raise EnvConfigError(f"objects_points must be an int in [{lo}, {hi}], got {p!r}")
        r = self.objects_rows
        if r is not None and (not isinstance(r, int) or isinstance(r, bool) or r < 1):
            raise EnvConfigError(f"objects_rows must be None or an int >= 1, got {r!r}")
        raw: Any = self.objects_image_size
        size = tuple(raw) if isinstance(raw, (tuple, list)) else (raw,)
        if len(size) != 2 or not all(  # noqa: PLR2004 - (height, width)
            isinstance(v, int) and not isinstance(v, bool) and v >= 1 for v in size
        ):
            raise EnvConfigError(
                f"objects_image_size must be (height, width), ints >= 1 px, got {raw!r}"
            )
        object.__setattr__(self, "objects_image_size", size)
        g = self.objects_gate_mm
        if isinstance(g, bool) or not isinstance(g, (int, float)) or not g > 0:
            raise EnvConfigError(f"objects_gate_mm must be a number > 0 [mm], got {g!r}")

    @property
    def belt_speed(self) -> float:
        """Input belt speed [m/s] (``cell.input_belt.speed``)."""
        return self.cell.input_belt.speed

    @property
    def feed(self) -> str:
        """Tile feed (``cell.tiles.feed``)."""
        return self.cell.tiles.feed


def allowed_keys() -> list[str]:
    """Every allowed keyword override: the `EnvConfig` fields and the flat `CELL_KEYS`."""
    return sorted([f.name for f in fields(EnvConfig)] + list(CELL_KEYS))


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
        unknown = sorted(set(overrides) - set(base) - set(CELL_KEYS))
        if unknown:
            raise EnvConfigError(
                f"unknown key(s) {unknown} for EnvConfig; allowed: {allowed_keys()}"
            )
        base.update(overrides)
        config, overrides = None, base
    if "image_size" in overrides and isinstance(overrides["image_size"], int):
        overrides["image_size"] = (overrides["image_size"],) * 2
    data: dict[str, Any] = {}
    if config is not None:
        data = load_yaml(config)
    file_cell = data.pop("cell", None) if config is not None else None
    if config is None and not isinstance(overrides.get("cell"), CellConfig):
        file_cell = {"config": "cell", **ENV_CELL_CHANGES}  # the env's own defaults
    raw_cell = merge_cell(file_cell, overrides.pop("cell", None))
    flat = {**{k: data.pop(k) for k in list(data) if k in CELL_KEYS}, **overrides}
    overrides = {k: v for k, v in flat.items() if k not in CELL_KEYS}
    overrides["cell"] = split_cell(raw_cell, flat)
    source = "<defaults>" if config is None else str(resolve_path(config))
    try:
        return from_dict(EnvConfig, {**data, **overrides}, source=source)
    except EnvConfigError:
        raise
    except ConfigError as exc:
        hint = f"; flat cell keywords: {sorted(CELL_KEYS)}" if "unknown key" in str(exc) else ""
        raise EnvConfigError(f"{exc}{hint}") from exc


__all__ = [
    "ActionMode",
    "DesignSource",
    "Execution",
    "ObjectsSource",
    "ObsMode",
    "RenderMode",
    "RewardMode",
    "ACTION_MODES",
    "DEFAULT_ROTATION_BINS",
    "DESIGN_SOURCES",
    "EXECUTIONS",
    "FEEDS",
    "OBJECTS_POINTS_RANGE",
    "OBJECTS_SOURCES",
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
