"""Configuration of the simulated cell (robot, belts, mesh, tiles, suction, cameras).

Every number is a field of a frozen dataclass with its unit in the docstring; bundled defaults
live in ``configs/cell.yaml``. Load with ``load_cell_config()``; validation happens in
``__post_init__`` and raises `CellError` naming the field and what is allowed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any, Literal, get_args

from configs import ConfigError, load_config
from configs.checks import check_fields, checked
from envs.cell.view_config import CameraConfig, RenderConfig, SceneryConfig
from envs.errors import CellError
from spatial.tolerance import MADE_TILE_DEVIATION_M

FeedMode = Literal["all", "stream", "batch"]
"""How tiles arrive on the input belt (`TileConfig.feed`, `envs.cell.feed`)."""
FEED_MODES: tuple[str, ...] = get_args(FeedMode)
"""Allowed ``feed`` values."""
StreamStart = Literal["random", "spaced"]
"""Where a stream's tiles given at reset lie (`TileConfig.stream_start`, `envs.cell.feed`)."""
STREAM_STARTS: tuple[str, ...] = get_args(StreamStart)
"""Allowed ``stream_start`` values."""

REPO_ROOT = Path(__file__).resolve().parents[2]
"""Repository root (assets are resolved relative to it)."""


@dataclass(frozen=True)
class PhysicsConfig:
    """Simulation options.

    Attributes:
        timestep: Physics step [s].
        sleep: Let resting bodies (tiles) sleep (MuJoCo's ``sleep`` enable flag).
        sleep_tolerance: Velocity below which a body may fall asleep [m/s or rad/s, scaled].
        iterations: Constraint solver iterations (upper bound).
        ls_iterations: Line-search iterations.
        impratio: Frictional-to-normal impedance ratio (higher reduces slip on the belt).
    """

    timestep: float = checked(0.002, gt=0, le=0.005)
    sleep: bool = True
    sleep_tolerance: float = checked(1e-3, gt=0)
    iterations: int = checked(50, gt=0)
    ls_iterations: int = checked(20, gt=0)
    impratio: float = checked(1.0, gt=0)

    def __post_init__(self) -> None:
        check_fields(self, CellError, qualify=True)


@dataclass(frozen=True)
class RobotConfig:
    """The arm (joint ranges and axis speed limits are the model's: `planners.robot`).

    Attributes:
        model: Path of the robot MJCF, relative to the repository root or absolute.
        home: Joint angles of the start configuration, shape (6,) [rad].
        base_keepout: Radius about the base axis that no belt may enter [m] (the rotating
            base, 0.11 m, plus margin).
    """

    model: str = "assets/irb140/irb140.xml"
    home: tuple[float, ...] = checked((0.0, 0.0, 0.0, 0.0, 1.5707963, 0.0), length=6)
    base_keepout: float = checked(0.15, gt=0)

    def __post_init__(self) -> None:
        check_fields(self, CellError, qualify=True)
        if not self.model_path.is_file():
            raise CellError(f"RobotConfig.model: no file {self.model_path}")

    @property
    def model_path(self) -> Path:
        """Absolute path of the robot MJCF."""
        p = Path(self.model)
        return p if p.is_absolute() else REPO_ROOT / p


@dataclass(frozen=True)
class LayoutConfig:
    """Where the belts' working areas sit relative to the robot base (at the origin).

    The input working area is centred at (work_x, +belt_separation/2), the output mesh at
    (work_x, -belt_separation/2); both belts run along +x. With the tool pointing down at
    belt_top_z = 0.2 m, the IRB 140 reaches tile-top points between about 0.33 m (joint 3's
    +50 degree limit folds the arm no further) and 0.80 m from the base axis.

    Attributes:
        belt_separation: Distance between the two belts' centre lines [m] (paper: 1.0; compact
            0.5 with work_x 0.5 and input_belt.length 0.6, clear of the base).
        work_x: Forward position of both working areas' centres [m].
        belt_top_z: Height of both belts' top surfaces [m].
    """

    belt_separation: float = checked(1.0, gt=0)
    work_x: float = checked(0.0, finite=True)
    belt_top_z: float = checked(0.2, gt=0)

    def __post_init__(self) -> None:
        check_fields(self, CellError, qualify=True)


@dataclass(frozen=True)
class InputBeltConfig:
    """Input conveyor, bin and tile area.

    Attributes:
        length: Belt length along x [m].
        width: Belt width [m].
        thickness: Belt slab thickness [m].
        speed: Belt surface speed along +x [m/s]; 0 is a static belt (the paper's set-up).
        end_offset: Downstream end of the belt, measured from the working-area centre [m].
        tile_area: Length (x) and width (y) of the area where tiles are laid out [m]; keep it
            inside the input camera's view (default 0.32 x 0.24 m).
        bin_length: Length of the bin catching tiles past the belt end [m].
        bin_depth: How far the bin floor is below the belt top [m].
        lost_margin: A tile whose centre is this far below the belt top, or past the belt end,
            is counted lost [m].
    """

    length: float = checked(1.0, gt=0)
    width: float = checked(0.3, gt=0)
    thickness: float = checked(0.04, gt=0)
    speed: float = checked(0.0, ge=0, le=1)
    end_offset: float = 0.3
    tile_area: tuple[float, ...] = checked((0.30, 0.22), length=2, gt=0)
    bin_length: float = checked(0.3, gt=0)
    bin_depth: float = checked(0.15, gt=0)
    lost_margin: float = checked(0.02, gt=0)

    def __post_init__(self) -> None:
        check_fields(self, CellError, qualify=True)
        if self.tile_area[1] > self.width:
            raise CellError(
                f"InputBeltConfig.tile_area width {self.tile_area[1]} m exceeds the belt width "
                f"{self.width} m"
            )
        if self.tile_area[0] / 2 > self.end_offset or self.end_offset >= self.length:
            raise CellError(
                "InputBeltConfig.end_offset must be >= tile_area[0]/2 (the tile area ends before "
                f"the belt end) and < length; got end_offset={self.end_offset}, "
                f"tile_area={self.tile_area}, length={self.length}"
            )


@dataclass(frozen=True)
class OutputBeltConfig:
    """Output belt carrying the mesh (the grid the tiles are placed into).

    Attributes:
        length: Belt length along x [m].
        width: Belt width [m].
        thickness: Belt slab thickness [m].
        max_mesh_size: The largest mesh sheet the cell takes, x and y [m]: what the output
            belt holds and the arm reaches. The sheet itself is the design's mesh
            (`envs.cell.geometry.cell_geometry`); a cell built without a design lays this one.
        mesh_thickness: Thickness of the mesh sheet [m].
        slot_mark_height: Height of the visual slot marks above the sheet [m] (no contacts).
        frame_margin: Belt seen beyond each mesh edge in the output camera's picture [m]: the
            output camera is raised above its ``height_above_belt`` when a larger mesh would
            not fit its view with this margin.
    """

    length: float = checked(0.6, gt=0)
    width: float = checked(0.32, gt=0)
    thickness: float = checked(0.04, gt=0)
    max_mesh_size: tuple[float, ...] = checked((0.32, 0.32), length=2, gt=0)
    mesh_thickness: float = checked(0.002, gt=0)
    slot_mark_height: float = checked(0.0003, gt=0)
    frame_margin: float = checked(0.005, ge=0)

    def __post_init__(self) -> None:
        check_fields(self, CellError, qualify=True)
        if self.max_mesh_size[0] > self.length or self.max_mesh_size[1] > self.width:
            raise CellError(
                f"OutputBeltConfig.max_mesh_size {self.max_mesh_size} m does not fit the belt "
                f"({self.length} x {self.width} m)"
            )


@dataclass(frozen=True)
class TileConfig:
    """Physical tiles, noise, placement and feeding.

    Attributes:
        thickness: Tile thickness [m].
        density: Ceramic density [kg/m^3].
        friction: Sliding friction coefficient of tiles (belts and sheet use it too) [-].
        body_color: RGB in [0, 1] of the unglazed ceramic (sides and bottom).
        glaze_thickness: Thickness of the coloured glaze layer drawn on the top face [m]
            (visual only).
        vertex_jitter: Std of the manufacturing noise added to outline vertices [m] (by
            default the made tile's deviation of `spatial.tolerance`).
        color_jitter: Std of the noise added to each RGB channel [0..1 units].
        variants: Noisy copies built per tile [count]. With 1 the noise (outline and colour)
            is drawn once when the cell is built and kept by every reset. With V > 1 each
            tile's body holds V shapes (jointless child bodies), each with its own outline
            noise; every reset shows one per tile at random (the others massless, without
            contacts and invisible) and re-draws its glaze colour noise, so episodes see fresh
            manufacturing noise without a rebuild.
        min_gap: Minimum clearance between bounding circles of placed tiles [m].
        placement_attempts: Random tries per tile before a layout attempt is abandoned.
        placement_restarts: Whole layouts drawn before the layout is declared impossible.
        distractor_rate: Expected distractors per real tile (0: none) [-].
        distractor_kinds: Kinds drawn uniformly: "color" (wrong colour), "broken" (a corner
            cut off), "shape" (scaled to a wrong size).
        feed: "all" lays every tile out at reset; "stream" spawns tiles one at a time at the
            upstream end of the tile area (use with a moving belt); "batch" lays out
            ``batch_size`` tiles over the whole tile area and indexes the next batch in once
            the input side holds no real tile (the last one picked), as an indexing conveyor
            does: leftovers (distractors) leave with the old batch into the reject bin.
        stream_period: Time between spawned tiles in "stream" mode [s].
        stream_initial: Tiles laid out at reset in "stream" mode (the rest are spawned).
        stream_start: Where those tiles lie at reset: "random" anywhere over the tile area
            (two may start so far downstream that no order of picks saves both); "spaced" as
            a running stream would have fed them, the newest at the upstream edge and each
            older one a supply period's belt travel (``stream_period`` x the belt's speed)
            further downstream (shortened alike where the oldest would reach past the tile
            area: it lies inside, seen whole), each at a random place across the belt and a
            random yaw.
        batch_size: Tiles per batch in "batch" mode [count].
        batch_index_time: Time from the input side holding no real tile to the next batch
            lying at rest in the tile area, in "batch" mode [s] (the arm lifts the last
            picked tile clear first).
    """

    thickness: float = checked(0.005, gt=0, le=0.02)
    density: float = checked(2400.0, gt=0)
    friction: float = checked(0.8, gt=0)
    body_color: tuple[float, ...] = checked((0.80, 0.74, 0.64), length=3, ge=0, le=1)
    glaze_thickness: float = checked(0.0008, gt=0)
    vertex_jitter: float = checked(MADE_TILE_DEVIATION_M, ge=0)
    color_jitter: float = checked(0.02, ge=0)
    variants: int = checked(1, ge=1, integer=True)
    min_gap: float = checked(0.006, ge=0)
    placement_attempts: int = checked(400, gt=0)
    placement_restarts: int = checked(40, gt=0)
    distractor_rate: float = checked(0.0, ge=0, le=1)
    distractor_kinds: tuple[str, ...] = ("color", "broken", "shape")
    feed: FeedMode = checked("all", choices=FEED_MODES)
    stream_period: float = checked(2.0, gt=0)
    stream_initial: int = checked(0, ge=0)
    stream_start: StreamStart = checked("random", choices=STREAM_STARTS)
    batch_size: int = checked(16, ge=1, integer=True)
    batch_index_time: float = checked(0.5, gt=0)

    def __post_init__(self) -> None:
        check_fields(self, CellError, qualify=True)
        if self.glaze_thickness >= self.thickness:
            raise CellError(
                f"TileConfig.glaze_thickness {self.glaze_thickness} m must be < thickness "
                f"{self.thickness} m"
            )
        allowed = {"color", "broken", "shape"}
        bad = set(self.distractor_kinds) - allowed
        if bad or not self.distractor_kinds:
            raise CellError(
                f"TileConfig.distractor_kinds {self.distractor_kinds}; allowed: non-empty subset "
                f"of {sorted(allowed)}"
            )


@dataclass(frozen=True)
class SuctionConfig:
    """Vacuum pad: seal check and holding-force limit.

    Attributes:
        pad_diameter: Suction cup diameter [m] (paper: 23 mm).
        vacuum_pressure: Pressure difference the pneumatic circuit holds [Pa].
        friction: Cup-to-tile friction coefficient limiting shear [-].
        seal_max_gap: Largest pad-face to tile-top distance that still seals [m].
        seal_max_tilt_deg: Largest angle between pad axis and tile normal that seals [deg].
        force_filter: Weight of the newest sample in the exponential filter of the measured
            holding force, 0 < w <= 1 [-] (1: no filtering).
    """

    pad_diameter: float = checked(0.023, gt=0)
    vacuum_pressure: float = checked(60000.0, gt=0)
    friction: float = checked(0.5, gt=0)
    seal_max_gap: float = checked(0.002, gt=0)
    seal_max_tilt_deg: float = checked(5.0, gt=0)
    force_filter: float = checked(0.5, gt=0, le=1)

    def __post_init__(self) -> None:
        check_fields(self, CellError, qualify=True)

    @property
    def holding_force(self) -> float:
        """Largest pull along the pad axis the vacuum holds [N] (pressure x pad area)."""
        return self.vacuum_pressure * math.pi * (self.pad_diameter / 2) ** 2


@dataclass(frozen=True)
class CellConfig:
    """Everything about the cell; see each part's docstring."""

    physics: PhysicsConfig = field(default_factory=PhysicsConfig)
    robot: RobotConfig = field(default_factory=RobotConfig)
    layout: LayoutConfig = field(default_factory=LayoutConfig)
    input_belt: InputBeltConfig = field(default_factory=InputBeltConfig)
    output_belt: OutputBeltConfig = field(default_factory=OutputBeltConfig)
    tiles: TileConfig = field(default_factory=TileConfig)
    suction: SuctionConfig = field(default_factory=SuctionConfig)
    input_camera: CameraConfig = field(default_factory=CameraConfig)
    output_camera: CameraConfig = field(default_factory=CameraConfig)
    render: RenderConfig = field(default_factory=RenderConfig)
    scenery: SceneryConfig = field(default_factory=SceneryConfig)

    def __post_init__(self) -> None:
        lay = self.layout
        if lay.belt_separation < self.input_belt.width / 2 + self.output_belt.width / 2:
            raise CellError(
                f"LayoutConfig.belt_separation {lay.belt_separation} m: the belts "
                f"(widths {self.input_belt.width}, {self.output_belt.width} m) would overlap"
            )
        end = lay.work_x + self.input_belt.end_offset
        belts = {
            "input_belt": (end - self.input_belt.length, end, self.input_belt.width),
            "output_belt": (
                lay.work_x - self.output_belt.length / 2,
                lay.work_x + self.output_belt.length / 2,
                self.output_belt.width,
            ),
        }
        tiles, belt = self.tiles, self.input_belt
        if tiles.feed == "stream" and tiles.stream_start == "spaced" and tiles.stream_initial > 1:
            travel = (tiles.stream_initial - 1) * tiles.stream_period * belt.speed
            if not 0 < travel < belt.tile_area[0]:
                raise CellError(
                    f"TileConfig.stream_start 'spaced' lays {tiles.stream_initial} tiles "
                    f"{tiles.stream_period * belt.speed:.3f} m apart (stream_period x "
                    f"input_belt.speed): {travel:.3f} m must be > 0 and < the tile area's "
                    f"length {belt.tile_area[0]} m; use fewer tiles, a moving belt, or "
                    "stream_start 'random'"
                )
        for name, (x0, x1, width) in belts.items():
            dx = max(x0, 0.0, -x1)
            dy = max(lay.belt_separation / 2 - width / 2, 0.0)
            if math.hypot(dx, dy) < self.robot.base_keepout:
                raise CellError(
                    f"{name} (x {x0:.2f}..{x1:.2f} m, {width} m wide, centre line "
                    f"{lay.belt_separation / 2:.2f} m from the base) comes within "
                    f"{self.robot.base_keepout} m of the robot base axis; shorten it, move "
                    "work_x forward or widen belt_separation"
                )


def load_cell_config(name_or_path: str | Path | None = "cell", **overrides: Any) -> CellConfig:
    """Load a `CellConfig` from YAML (bundled name or path) with top-level overrides.

    Args:
        name_or_path: Bundled name in ``configs/`` (default ``"cell"``), a path, or None for
            the dataclass defaults.
        **overrides: Top-level sections replacing the file's, e.g.
            ``input_belt={"speed": 0.1}`` (a mapping replaces the whole section, unspecified
            keys take their defaults) or a section dataclass.

    Raises:
        CellError: Unknown key, wrong type or invalid value (the message names it).
    """
    try:
        return load_config(CellConfig, name_or_path, **overrides)
    except ConfigError as exc:
        raise CellError(str(exc)) from exc


def section_names() -> list[str]:
    """Names of the top-level sections of `CellConfig`."""
    return [f.name for f in fields(CellConfig)]


__all__ = [
    "FEED_MODES",
    "STREAM_STARTS",
    "REPO_ROOT",
    "CameraConfig",
    "CellConfig",
    "InputBeltConfig",
    "LayoutConfig",
    "OutputBeltConfig",
    "PhysicsConfig",
    "RenderConfig",
    "RobotConfig",
    "SceneryConfig",
    "SuctionConfig",
    "FeedMode",
    "StreamStart",
    "TileConfig",
    "load_cell_config",
    "section_names",
]
