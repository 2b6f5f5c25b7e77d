"""Settings of the scripted agent's layers, as frozen dataclasses with units.

Bundled defaults live in ``configs/agents.yaml``; `load_agents_config` loads them strictly
(unknown keys are a `configs.ConfigError`) and applies top-level keyword overrides::

    cfg = load_agents_config(placement={"method": "greedy", "use_color": False})
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

from agents.errors import AgentError
from configs import load_config
from configs.checks import check_fields, checked
from envs.cell.calibration_board import CalibrationTarget
from envs.task_spec import FeedMode
from spatial.units import MM_PER_M

AGENTS_CONFIG = "agents"
"""Bundled config name (``configs/agents.yaml``)."""


@dataclass(frozen=True)
class PerceptionConfig:
    """How camera images become perceived tiles.

    Attributes:
        mm_per_m: Unit of the world figures handed to qshape, [mm/m] (designs are in mm):
            a unit, not a tuning knob; the default is `spatial.units.MM_PER_M` and the key
            is left out of the bundled ``configs/agents.yaml`` (still accepted there).
        pad_clearance: A tile is picked at its centroid when the centroid lies at least this
            far inside the tile material; otherwise at its pole of inaccessibility, [m] (half
            the 23 mm pad of the paper: the pad seals on material all round).
        polylabel_tolerance: Precision of the pole-of-inaccessibility search, [m].
        thin_fraction: A tile whose pole lies less than this x ``pad_clearance`` inside it
            (no room for the pad anywhere: a thin tile) is picked where the most of the pad
            lies on it instead (`agents.scripted.grasp.best_hold`), dimensionless.
        grasp_step: Grid of that search before it is refined (to ``polylabel_tolerance``), [m].
        color_balance: Estimate a per-channel gain mapping measured tile colours onto the
            design's palette (white balance against known colours: camera calibration)
            before matching.
        color_balance_iterations: Nearest-palette / median-gain rounds of that estimate.
        max_color_gain: The gain per channel is clipped to [1 / max, max] (dimensionless).
        color_history: Tile colours (from every picture of the episode, newest kept) the gain
            is fitted on. A white balance is the camera's, not one picture's: fitted on one
            tile it maps that tile onto its nearest palette colour, right or wrong (a red tile
            measured brighter is nearer orange).
        color_min_samples: Fewer colours in the history than this (the first pictures of a
            streamed belt): one brightness gain for all channels, which keeps each colour's
            hue, instead of a gain per channel.
        retry_outline: `qshape.OutlineParams` fields changed for a second simplification of a
            tile whose figure matches no open slot's shape (empty: no retry). The bundled
            outline parameters keep rough edges straight with a noise floor of 6 x the measured
            edge roughness and a corner window of 3.25 % of the perimeter; an edge's own small
            curved feature (a bite or bulge on part of an edge) raises that roughness measure
            and falls below the floor. The retry uses the clean-outline values; the first
            figure is kept when the retry matches nothing either.
        seen_slots: Describe each design slot a second time as the pictures' outline
            simplification sees its outline (at the input camera's scale on the tile tops),
            and let a tile matching neither the slot's own description nor another slot's
            match that seen description (`agents.scripted.perception.SlotTarget.seen`): a design's
            corner that turns too little to show in a picture (a rounded corner's tangent
            ends) is a relevant point the measured figure never has.
        seen_turn_residual: A seen outline turning nearly onto itself (RMS residual at most
            this fraction of sqrt(area), `qshape.vision.seen.near_turns`) more often than the
            slot's symmetry is not used: a tile matched to it might be set down turned.
            Twice qshape's ``uncertainty_residual``: a tile within that residual of one turn
            may be as near the other (dimensionless).

    How outlines become figures (corner threshold, circles, chamfered corners) is qshape's
    business: ``configs/vision.yaml`` section ``extract``.
    """

    mm_per_m: float = checked(MM_PER_M, gt=0)
    pad_clearance: float = checked(0.0115, ge=0)
    polylabel_tolerance: float = checked(1e-4, gt=0)
    thin_fraction: float = checked(0.9, ge=0, le=1)
    grasp_step: float = checked(0.002, gt=0)
    color_balance: bool = True
    color_balance_iterations: int = 3
    max_color_gain: float = 2.0
    color_history: int = checked(64, ge=1)
    color_min_samples: int = checked(6, ge=1)
    retry_outline: dict[str, float] = field(default_factory=dict)
    seen_slots: bool = False
    seen_turn_residual: float = checked(0.1, ge=0)

    def __post_init__(self) -> None:
        """Raise `AgentError` on non-positive values."""
        check_fields(self, AgentError, prefix="perception: ")


@dataclass(frozen=True)
class PlacementConfig:
    """How assignments become pick-and-place commands.

    Attributes:
        method: "optimal" (most matches, least residual) or "greedy" (the paper's loop).
        use_color: Match shape and colour (True) or shape alone.
        continuous_yaw_steps: Equivalent yaws listed for a rotationally continuous tile
            (circle, ring): any yaw fits, this many evenly spaced ones are offered.
        refine_span_deg: qshape's rotation is refined within +- this by fitting the dense
            outlines, [deg] (a precision step: relevant points alone fix a curved tile's turn
            to a degree or two; 0: qshape's rotation as it is).
        refine_tolerance_deg: Precision of that refinement, [deg].
        refine_scan_deg: The span is scanned this far apart before the refinement, [deg].
        refine_spacing_mm: Largest distance between the outline points the refinement
            compares, [mm] (every edge sampled, straight ones too).
        fit_max_residual: A tile that no description matches (the design's, the seen one,
            the retry's) is fitted by its traced outline onto the open slots' outlines
            (`agents.scripted.outline_fit`): the mean distance left must be at most this x sqrt(slot
            area) (dimensionless; 0: no fit, such tiles stay unplaced).
        fit_margin: Every turn that is not a symmetry of the slot, and every slot of another
            class, must fit at least this many times worse than the best (dimensionless).
        fit_turn_window_deg: Turns closer than this to a symmetry of the slot count as it, [deg].
        fit_step_deg: Turns tried by that fit, this far apart, [deg].
        fit_spacing_mm: Largest distance between the outline points compared, [mm].
        centre_fit_below_deg: A tile whose slot has a corner sharper than this is centred by
            the slot's outline fitted to its traced outline (`agents.scripted.centre_fit`), not
            by its relevant points (the picture blunts a sharp tip), [deg] (0: never).
        centre_fit_step_mm: Sampling of the slot's outline in that fit, [mm].
        centre_fit_iterations: Translation updates of that fit.
        centre_fit_trim: Traced points farther off than this x the median distance are left
            out of each update (dimensionless).
    """

    method: Literal["optimal", "greedy"] = checked("optimal", choices=("optimal", "greedy"))
    use_color: bool = True
    continuous_yaw_steps: int = checked(12, ge=1)
    refine_span_deg: float = 5.0
    refine_tolerance_deg: float = 0.01
    refine_scan_deg: float = checked(1.0, gt=0)
    refine_spacing_mm: float = checked(0.5, gt=0)
    fit_max_residual: float = checked(0.0, ge=0)
    fit_margin: float = checked(2.0, ge=1)
    fit_turn_window_deg: float = checked(10.0, ge=0)
    fit_step_deg: float = checked(2.0, gt=0)
    fit_spacing_mm: float = checked(1.0, gt=0)
    centre_fit_below_deg: float = checked(30.0, ge=0)
    centre_fit_step_mm: float = checked(0.25, gt=0)
    centre_fit_iterations: int = checked(12, ge=1, integer=True)
    centre_fit_trim: float = checked(3.0, gt=1)

    def __post_init__(self) -> None:
        """Raise `AgentError` on bad values."""
        check_fields(self, AgentError, prefix="placement: ")


@dataclass(frozen=True)
class CalibrationConfig:
    """The rendered checkerboard calibration.

    Attributes:
        squares: Squares of the board along its x and y, (nx, ny); inner corners are one less.
        square_size: Side of one square, [m].
        border: White margin around the squares, [m].
        plate_thickness: Thickness of the white plate, [m].
        square_height: Height of the black squares above the plate, [m].
        tilts_deg: Board tilts for the intrinsic views, [deg] (about x then y per view pair).
        lift: Heights of the board's centre above the belt for the intrinsic views, [m].
        shifts: In-plane offsets of the board centre for the intrinsic views, [m].
        subpix_window_px: Half size of the cornerSubPix search window, [px].
        subpix_iterations: cornerSubPix iteration limit.
        subpix_epsilon_px: cornerSubPix convergence, [px].
        max_reprojection_px: Calibration is rejected above this RMS reprojection error, [px].
        min_views: Fewest views with the board found.
        fix_aspect_ratio: Estimate one focal length (square pixels).
        zero_tangential: Assume no tangential distortion.
        fix_k3: Do not estimate the third radial coefficient.
        lens_grid: Points per side of the image grid the estimated lens is checked on.
    """

    # The board and its poses (the env renders them; `target`), defaults as the env's.
    squares: tuple[int, int] = checked(CalibrationTarget.squares, ge=3)
    square_size: float = checked(CalibrationTarget.square_size, gt=0)
    border: float = checked(CalibrationTarget.border, ge=0)
    plate_thickness: float = CalibrationTarget.plate_thickness
    square_height: float = CalibrationTarget.square_height
    tilts_deg: tuple[float, ...] = CalibrationTarget.tilts_deg
    lift: tuple[float, ...] = CalibrationTarget.lift
    shifts: tuple[tuple[float, float], ...] = CalibrationTarget.shifts
    subpix_window_px: int = checked(5, ge=1)
    subpix_iterations: int = 50
    subpix_epsilon_px: float = 1e-3
    max_reprojection_px: float = 1.0
    min_views: int = checked(5, ge=3)
    fix_aspect_ratio: bool = True
    zero_tangential: bool = True
    fix_k3: bool = True
    lens_grid: int = 9

    def __post_init__(self) -> None:
        """Raise `AgentError` on bad values."""
        check_fields(self, AgentError, prefix="calibration: ")

    @property
    def target(self) -> CalibrationTarget:
        """The board and its poses, as the env renders them (`envs.cell.calibration_board`)."""
        return CalibrationTarget(
            squares=self.squares,
            square_size=self.square_size,
            border=self.border,
            plate_thickness=self.plate_thickness,
            square_height=self.square_height,
            tilts_deg=self.tilts_deg,
            lift=self.lift,
            shifts=self.shifts,
        )


@dataclass(frozen=True)
class RunConfig:
    """The main job (``python -m apps.main``).

    Attributes:
        design: Bundled design name or path.
        seed: Episode seed (``env.reset(seed=...)``: tile layout and noise).
        belt_speed: Input belt speed [m/s].
        feed: ``all`` tiles at reset or a ``stream`` (``configs/env.yaml`` sets its pace).
        distractor_rate: Distractor tiles (absent from the design) per real tile.
        max_slots: Use only the design's first ``max_slots`` slots and their tiles (0: all).
        max_steps_per_slot: Episode step limit per design slot (failed picks retry).
        max_idle_steps: Consecutive waiting steps (pictures with nothing to place: an empty
            belt between streamed tiles, an unusable picture retried) before the job stops.
        reject_after_idle: With the batch feed, after this many waits in a row a tile the
            design has no slot for (a defective tile or a distractor) still on the belt is
            put into the reject bin, so the next batch can come (0: never).
        execute: Run the pick-and-place cycles (False: one picture, perception and plan only).
        calibrate: Use the calibrated cameras instead of the simulator's true ones.
        video_fps: Frames per second of the cell video (simulated time), [1/s].
        marker_radius_px: Radius of drawn relevant points at full camera resolution, [px].
        out_dir: Output folder (relative to the repository root unless absolute).
    """

    design: str = "paper_mixed"
    seed: int = 0
    belt_speed: float = checked(0.0, ge=0)
    feed: FeedMode = "all"
    distractor_rate: float = checked(0.0, ge=0)
    max_slots: int = checked(0, ge=0)
    max_steps_per_slot: int = checked(2, ge=1)
    max_idle_steps: int = checked(8, ge=0)
    reject_after_idle: int = checked(2, ge=0)
    execute: bool = True
    calibrate: bool = True
    video_fps: float = checked(10.0, gt=0)
    marker_radius_px: int = 3
    out_dir: str = "out"

    def __post_init__(self) -> None:
        """Raise `AgentError` on bad values."""
        check_fields(self, AgentError, prefix="run: ")


@dataclass(frozen=True)
class AgentsConfig:
    """All agent settings (``configs/agents.yaml``)."""

    perception: PerceptionConfig = field(default_factory=PerceptionConfig)
    placement: PlacementConfig = field(default_factory=PlacementConfig)
    calibration: CalibrationConfig = field(default_factory=CalibrationConfig)
    run: RunConfig = field(default_factory=RunConfig)


def load_agents_config(
    name_or_path: str | Path | None = AGENTS_CONFIG, **overrides: Any
) -> AgentsConfig:
    """Load the agent settings.

    Args:
        name_or_path: Bundled name or YAML path; None: dataclass defaults.
        **overrides: Top-level sections (dicts of fields or dataclass values).

    Raises:
        configs.ConfigError: Unknown key or wrong type.
        AgentError: Out-of-range value.
    """
    return load_config(AgentsConfig, name_or_path, **overrides)


__all__ = [
    "AgentsConfig",
    "CalibrationConfig",
    "PerceptionConfig",
    "PlacementConfig",
    "RunConfig",
    "load_agents_config",
]
