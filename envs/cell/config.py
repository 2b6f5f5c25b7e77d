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
from typing import Any, Literal

from configs import ConfigError, check_positive, load_config
from envs.errors import CellError

REPO_ROOT = Path(__file__).resolve().parents[2]
"""Repository root (assets are resolved relative to it)."""

_positive = partial(check_positive, error=CellError)
_non_negative = partial(check_positive, error=CellError, strict=False)


def _length(obj: object, name: str, n: int) -> None:
    value = getattr(obj, name)
    if len(value) != n:
        raise CellError(f"{type(obj).__name__}.{name} needs {n} values, got {value!r}")


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
        mesh_size: Size of the mesh sheet, x and y [m].
        mesh_thickness: Thickness of the mesh sheet [m].
        slot_mark_height: Height of the visual slot marks above the sheet [m] (no contacts).
    """

    length: float = 0.6
    width: float = 0.32
    thickness: float = 0.04
    mesh_size: tuple[float, ...] = (0.23, 0.23)
    mesh_thickness: float = 0.002
    slot_mark_height: float = 0.0003

    def __post_init__(self) -> None:
        _length(self, "mesh_size", 2)
        _positive(self, "length", "width", "thickness", "mesh_size", "mesh_thickness")
        _positive(self, "slot_mark_height")
        if self.mesh_size[0] > self.length or self.mesh_size[1] > self.width:
            raise CellError(
                f"OutputBeltConfig.mesh_size {self.mesh_size} m does not fit the belt "
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
    feed: Literal["all", "stream", "batch"] = "all"
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
        if self.feed not in ("all", "stream", "batch"):
            raise CellError(f"TileConfig.feed {self.feed!r}; allowed: 'all', 'stream', 'batch'")
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
class CameraConfig:
    """One downward-looking camera above a belt's working area.

    Attributes:
        width: Image width [px] (paper: 656).
        height: Image height [px] (paper: 492).
        height_above_belt: Camera height above the belt top [m].
        fovy_deg: Vertical field of view [deg].
        offset: Camera position offset (x, y) from the working-area centre [m].
        distortion: Lens distortion in OpenCV's model, (k1, k2, p1, p2, k3) on normalised
            image coordinates (dimensionless); all zero: an ideal pinhole. The rendered image
            is warped by it (`envs.cell.cameras.LensWarp`).
        exposure_time: Shutter time [s]: tiles on a moving belt blur over belt speed x this
            (`envs.cell.cameras.BeltBlur`); 0: a still picture.
    """

    width: int = 656
    height: int = 492
    height_above_belt: float = 0.5
    fovy_deg: float = 27.0
    offset: tuple[float, ...] = (0.0, 0.0)
    distortion: tuple[float, ...] = (0.0, 0.0, 0.0, 0.0, 0.0)
    exposure_time: float = 0.0

    def __post_init__(self) -> None:
        _length(self, "offset", 2)
        _length(self, "distortion", 5)
        _non_negative(self, "exposure_time")
        if not all(math.isfinite(c) for c in self.distortion):
            raise CellError(f"CameraConfig.distortion {self.distortion}; allowed: finite numbers")
        _positive(self, "width", "height", "height_above_belt", "fovy_deg")
        if self.fovy_deg >= 170:
            raise CellError(f"CameraConfig.fovy_deg {self.fovy_deg}; allowed: (0, 170)")

    @property
    def pixels_per_metre(self) -> float:
        """Image scale on the belt plane [px/m]."""
        view = 2 * self.height_above_belt * math.tan(math.radians(self.fovy_deg) / 2)
        return self.height / view


@dataclass(frozen=True)
class RenderConfig:
    """Rendering options.

    Attributes:
        shadows: Render shadows (slow in software rendering; off for observations).
        reflections: Render reflections.
        overview_size: Overview image (height, width) [px].
        cull: Leave geoms a model camera cannot see out of its scene (same image, faster in
            software rendering; `envs.cell.view_culling`).
        samples: Multisamples per pixel of every rendered image not supersampled
            (anti-aliasing; MuJoCo's ``offsamples``). 0 renders small images about 40 % faster
            in software rendering, with stair-stepped edges.
        supersample: With ``samples`` > 0, small RGB images are anti-aliased by
            supersampling instead: rendered at this factor times the size without
            multisampling, then each factor x factor block averaged (``cv2.INTER_AREA``); 1
            turns it off. In software rendering a 72 x 96 image costs about half of a
            4-sample multisampled one, with edges as smooth (tested against it).
        supersample_max_pixels: Largest image (height x width [px]) supersampled; larger ones
            (where multisampling is the cheaper of the two) and depth images use ``samples``.
        lens_max_iterations: Iterations of the solver inverting a lens distortion (once per
            camera and image size).
        lens_tolerance: Its convergence tolerance, in normalised image units (1 px ~ 1 / the
            focal length in px).
    """

    shadows: bool = False
    reflections: bool = False
    overview_size: tuple[int, ...] = (480, 640)
    cull: bool = True
    samples: int = 4
    supersample: int = 2
    supersample_max_pixels: int = 40000
    lens_max_iterations: int = 40
    lens_tolerance: float = 1e-9

    def __post_init__(self) -> None:
        _length(self, "overview_size", 2)
        _positive(self, "overview_size", "lens_max_iterations", "lens_tolerance", "supersample")
        if self.samples < 0:
            raise CellError(f"RenderConfig.samples must be >= 0, got {self.samples}")
        _non_negative(self, "supersample_max_pixels")


@dataclass(frozen=True)
class SceneryConfig:
    """What the cell looks like around the working parts: floor, light, frames, bin, colours.

    Attributes:
        floor_half_size: Half side of the square floor plane [m].
        floor_checker: The floor texture's two checker colours, RGB in [0, 1] each (2, 3).
        floor_texture_px: Checker texture side [px].
        floor_texture_repeat: Texture repeats across the floor.
        light_pos: Position of the directional top light [m] (3,).
        light_diffuse: Diffuse weight of the top light (relative; see ``exposure``).
        light_specular: Specular intensity of the top light (0: diffuse lighting, as a vision
            cell's dome gives; > 0 puts a glaze highlight on every tile).
        headlight_ambient: Ambient weight of the viewer's headlight (relative).
        headlight_diffuse: Diffuse weight of the headlight (relative).
        exposure: Grey level, in (0, 1], at which a white matte face looking up renders: the
            ambient and diffuse intensities above are scaled so that they sum to it, so a
            glaze renders at its own colour times ``exposure`` (1: the glaze colour itself)
            instead of over-brightened or saturated.
        belt_rgba: Belt colour, RGBA in [0, 1].
        frame_rgba: Colour of rails and stands.
        sheet_rgba: Colour of the mesh sheet.
        bin_floor_rgba: Colour of the bin's floor.
        bin_wall_rgba: Colour of the bin's walls.
        slot_white: White mixed into each slot mark's tile colour, in [0, 1].
        rail_gap: Gap between the input belt's edge and each side rail's centre [m].
        rail_half_width: Half width of a side rail [m].
        rail_height: Half height of a side rail [m].
        stand_inset: How much narrower than its belt a stand is, (along, across) per side [m].
        bin_gap: Gap between the input belt's end and the bin [m].
        bin_side_margin: How much wider than the belt the bin is, per side [m].
        bin_wall: Half thickness of the bin's floor and walls [m].
        bin_stand_inset: How much smaller than the bin its stand is, per side [m].
        overview_pos: Position of the overview camera [m] (3,).
        overview_xyaxes: The overview camera's image x and y axes in the world (MuJoCo
            ``xyaxes``) (6,).
    """

    floor_half_size: float = 4.0
    floor_checker: tuple[tuple[float, ...], ...] = ((0.33, 0.35, 0.38), (0.28, 0.3, 0.33))
    floor_texture_px: int = 256
    floor_texture_repeat: int = 8
    light_pos: tuple[float, ...] = (0.3, 0.0, 2.5)
    light_diffuse: float = 0.45
    light_specular: float = 0.0
    headlight_ambient: float = 0.3
    headlight_diffuse: float = 0.35
    exposure: float = 1.0
    belt_rgba: tuple[float, ...] = (0.12, 0.12, 0.13, 1.0)
    frame_rgba: tuple[float, ...] = (0.55, 0.57, 0.6, 1.0)
    sheet_rgba: tuple[float, ...] = (0.22, 0.22, 0.24, 1.0)
    bin_floor_rgba: tuple[float, ...] = (0.35, 0.25, 0.15, 1.0)
    bin_wall_rgba: tuple[float, ...] = (0.45, 0.33, 0.2, 1.0)
    slot_white: float = 0.45
    rail_gap: float = 0.01
    rail_half_width: float = 0.01
    rail_height: float = 0.01
    stand_inset: tuple[float, ...] = (0.05, 0.03)
    bin_gap: float = 0.005
    bin_side_margin: float = 0.05
    bin_wall: float = 0.005
    bin_stand_inset: float = 0.02
    overview_pos: tuple[float, ...] = (1.45, 0.0, 1.35)
    overview_xyaxes: tuple[float, ...] = (0.0, 1.0, 0.0, -0.62, 0.0, 0.78)

    def __post_init__(self) -> None:
        for name, n in (
            ("light_pos", 3),
            ("belt_rgba", 4),
            ("frame_rgba", 4),
            ("sheet_rgba", 4),
            ("bin_floor_rgba", 4),
            ("bin_wall_rgba", 4),
            ("stand_inset", 2),
            ("overview_pos", 3),
            ("overview_xyaxes", 6),
        ):
            _length(self, name, n)
        if len(self.floor_checker) != 2 or any(len(c) != 3 for c in self.floor_checker):  # noqa: PLR2004
            raise CellError(
                f"SceneryConfig.floor_checker needs two RGB colours, got {self.floor_checker}"
            )
        _positive(
            self,
            "floor_half_size",
            "floor_texture_px",
            "floor_texture_repeat",
            "rail_half_width",
            "rail_height",
            "bin_wall",
        )
        _non_negative(self, "light_diffuse", "light_specular", "slot_white", "rail_gap", "bin_gap")
        _non_negative(self, "headlight_ambient", "headlight_diffuse")
        if not 0.0 < self.exposure <= 1.0 or self.light_weight_sum <= 0.0:
            raise CellError(
                f"SceneryConfig.exposure {self.exposure}; allowed: (0, 1], with a positive sum "
                "of light_diffuse, headlight_ambient and headlight_diffuse"
            )

    @property
    def light_weight_sum(self) -> float:
        """Sum of the ambient and diffuse light weights (what ``exposure`` rescales to)."""
        return self.light_diffuse + self.headlight_ambient + self.headlight_diffuse

    @property
    def light_scale(self) -> float:
        """Factor applied to every configured ambient and diffuse intensity."""
        return self.exposure / self.light_weight_sum
        _non_negative(self, "stand_inset", "bin_side_margin", "bin_stand_inset")


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
    "REPO_ROOT",
    "CameraConfig",
    "CellConfig",
    "InputBeltConfig",
    "LayoutConfig",
    "OutputBeltConfig",
    "PhysicsConfig",
    "RenderConfig",
    "RobotConfig",
    "SuctionConfig",
    "TileConfig",
    "load_cell_config",
    "section_names",
]
