"""Configuration of the simulated cell (robot, belts, mesh, tiles, suction, cameras).

Every number is a field of a frozen dataclass with its unit in the docstring; bundled defaults
live in ``configs/cell.yaml``. Load with ``load_cell_config()``; validation happens in
``__post_init__`` and raises `CellError` naming the field and what is allowed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from functools import partial
from pathlib import Path
from typing import Any, Literal, get_args

from configs import ConfigError, check_length, check_positive, load_config
from envs.cell.view_config import CameraConfig, RenderConfig, SceneryConfig
from envs.errors import CellError

FeedMode = Literal["all", "stream", "batch"]
"""How tiles arrive on the input belt (`TileConfig.feed`, `envs.cell.feed`)."""
FEED_MODES: tuple[str, ...] = get_args(FeedMode)
"""Allowed ``feed`` values."""

REPO_ROOT = Path(__file__).resolve().parents[2]
"""Repository root (assets are resolved relative to it)."""

_positive = partial(check_positive, error=CellError)
_non_negative = partial(check_positive, error=CellError, strict=False)


_length = partial(check_length, error=CellError)


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

    timestep: float = 0.002
    sleep: bool = True
    sleep_tolerance: float = 1e-3
    iterations: int = 50
    ls_iterations: int = 20
    impratio: float = 1.0

    def __post_init__(self) -> None:
        _positive(self, "timestep", "sleep_tolerance", "iterations", "ls_iterations", "impratio")
        if self.timestep > 0.005:
            raise CellError(
                f"PhysicsConfig.timestep {self.timestep} s is too large for 5 mm tiles; "
                "allowed: (0, 0.005]"
            )


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
    home: tuple[float, ...] = (0.0, 0.0, 0.0, 0.0, 1.5707963, 0.0)
    base_keepout: float = 0.15

    def __post_init__(self) -> None:
        _length(self, "home", 6)
        _positive(self, "base_keepout")
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

    belt_separation: float = 1.0
    work_x: float = 0.0
    belt_top_z: float = 0.2

    def __post_init__(self) -> None:
        _positive(self, "belt_separation", "belt_top_z")
        if not math.isfinite(self.work_x):
            raise CellError(f"LayoutConfig.work_x must be finite, got {self.work_x!r}")


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

    length: float = 1.0
    width: float = 0.3
    thickness: float = 0.04
    speed: float = 0.0
    end_offset: float = 0.3
    tile_area: tuple[float, ...] = (0.30, 0.22)
    bin_length: float = 0.3
    bin_depth: float = 0.15
    lost_margin: float = 0.02

    def __post_init__(self) -> None:
        _length(self, "tile_area", 2)
        _positive(self, "length", "width", "thickness", "tile_area", "bin_length", "bin_depth")
        _positive(self, "lost_margin")
        _non_negative(self, "speed")
        if self.speed > 1.0:
            raise CellError(f"InputBeltConfig.speed {self.speed} m/s; allowed: 0 to 1.0 m/s")
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

    length: float = 0.6
    width: float = 0.32
    thickness: float = 0.04
    max_mesh_size: tuple[float, ...] = (0.32, 0.32)
    mesh_thickness: float = 0.002
    slot_mark_height: float = 0.0003
    frame_margin: float = 0.005

    def __post_init__(self) -> None:
        _length(self, "max_mesh_size", 2)
        _positive(self, "length", "width", "thickness", "max_mesh_size", "mesh_thickness")
        _positive(self, "slot_mark_height")
        _non_negative(self, "frame_margin")
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
        vertex_jitter: Std of the manufacturing noise added to outline vertices [m].
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
        batch_size: Tiles per batch in "batch" mode [count].
        batch_index_time: Time from the input side holding no real tile to the next batch
            lying at rest in the tile area, in "batch" mode [s] (the arm lifts the last
            picked tile clear first).
    """

    thickness: float = 0.005
    density: float = 2400.0
    friction: float = 0.8
    body_color: tuple[float, ...] = (0.80, 0.74, 0.64)
    glaze_thickness: float = 0.0008
    vertex_jitter: float = 0.0002
    color_jitter: float = 0.02
    variants: int = 1
    min_gap: float = 0.006
    placement_attempts: int = 400
    placement_restarts: int = 40
    distractor_rate: float = 0.0
    distractor_kinds: tuple[str, ...] = ("color", "broken", "shape")
    feed: FeedMode = "all"
    stream_period: float = 2.0
    stream_initial: int = 0
    batch_size: int = 16
    batch_index_time: float = 0.5

    def __post_init__(self) -> None:
        _positive(
            self,
            "thickness",
            "density",
            "friction",
            "placement_attempts",
            "placement_restarts",
            "variants",
        )
        _positive(self, "glaze_thickness")
        for name in ("variants", "batch_size"):
            value = getattr(self, name)
            if not isinstance(value, int) or isinstance(value, bool):
                raise CellError(f"TileConfig.{name} must be an int >= 1, got {value!r}")
        _length(self, "body_color", 3)
        if not all(0.0 <= c <= 1.0 for c in self.body_color):
            raise CellError(f"TileConfig.body_color must be RGB in [0, 1], got {self.body_color}")
        if self.glaze_thickness >= self.thickness:
            raise CellError(
                f"TileConfig.glaze_thickness {self.glaze_thickness} m must be < thickness "
                f"{self.thickness} m"
            )
        _positive(self, "stream_period", "batch_size", "batch_index_time")
        _non_negative(self, "vertex_jitter", "color_jitter", "min_gap", "distractor_rate")
        _non_negative(self, "stream_initial")
        if self.distractor_rate > 1.0:
            raise CellError(f"TileConfig.distractor_rate {self.distractor_rate}; allowed: 0..1")
        allowed = {"color", "broken", "shape"}
        bad = set(self.distractor_kinds) - allowed
        if bad or not self.distractor_kinds:
            raise CellError(
                f"TileConfig.distractor_kinds {self.distractor_kinds}; allowed: non-empty subset "
                f"of {sorted(allowed)}"
            )
        if self.feed not in FEED_MODES:
            feeds = ", ".join(repr(m) for m in FEED_MODES)
            raise CellError(f"TileConfig.feed {self.feed!r}; allowed: {feeds}")
        if self.thickness > 0.02:
            raise CellError(f"TileConfig.thickness {self.thickness} m; allowed: (0, 0.02]")


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

    pad_diameter: float = 0.023
    vacuum_pressure: float = 60000.0
    friction: float = 0.5
    seal_max_gap: float = 0.002
    seal_max_tilt_deg: float = 5.0
    force_filter: float = 0.5

    def __post_init__(self) -> None:
        _positive(self, "pad_diameter", "vacuum_pressure", "friction", "seal_max_gap")
        _positive(self, "seal_max_tilt_deg", "force_filter")
        if self.force_filter > 1:
            raise CellError(f"SuctionConfig.force_filter {self.force_filter}; allowed: (0, 1]")

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
    "TileConfig",
    "load_cell_config",
    "section_names",
]
