"""Perception of the scripted cell: image -> tiles in the world; design -> slots in the world.

Tiles: `qshape.extract_detailed` finds the tiles' relevant points in pixels (y down); every
relevant point is cast as a ray through the calibrated camera and intersected with the plane of
the tiles' top faces, giving the figure on the belt in world millimetres (x, y of the world,
y up). Designs are in millimetres too, so the qualitative sizes compare, and a matched rotation is
directly a world yaw (counter-clockwise seen from above). A figure's world centre is its area
centroid on the plane (equal to the ray-plane intersection of the pixel centroid for a camera
looking straight down; both are reported).

Slots: the env's world slots (``TaskSpec.slots``: each design slot's figure in millimetres and
its world pose, converted once by the env) described with qshape.

Only the camera model (what a calibrated cell knows) and the image are used: no simulator state.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import shapely
from shapely.geometry import Point, Polygon

import qshape
from agents.errors import PerceptionError
from agents.scripted.config import PerceptionConfig
from agents.scripted.grasp import best_hold
from agents.scripted.seen_slots import SeenSlot, seen_outlines
from agents.scripted.white_balance import color_gain, recolour
from envs.cell.cameras import CameraModel
from envs.errors import CellError
from envs.task_spec import WorldSlot
from qshape import Description, Figure
from qshape.geometry import signed_area
from qshape.theory.boundary import Boundary

_BLACK = (0.0, 0.0, 0.0)
"""Colour of a figure extracted without one."""

WhiteBalance = Callable[[np.ndarray], np.ndarray]
"""Measured colours of one picture's tiles, shape (n, 3) in [0, 1] -> per-channel gain (3,)."""


def _unproject(camera: CameraModel, uv: np.ndarray, z: float) -> np.ndarray:
    """World points (n, 3) [m] on the plane at height ``z`` seen at pixels ``uv`` (n, 2) [px].

    `envs.cell.cameras.CameraModel.unproject_to_plane` (the one pinhole model), its refusal
    as this package's error.

    Raises:
        PerceptionError: A ray parallel to the plane or the plane behind the camera.
    """
    try:
        return camera.unproject_to_plane(uv, z)
    except CellError as exc:
        raise PerceptionError(str(exc)) from exc


@dataclass(frozen=True, eq=False)
class PerceivedTile:
    """One whole tile seen by a camera.

    Attributes:
        index: Position in the extraction order (stable for one image).
        figure_px: The extracted figure, pixel coordinates, ``y_down=True``.
        figure: The same figure on the plane of the tile tops, world x, y in [mm] (y up).
        description: qshape description of ``figure``.
        centre: World area centroid of the figure, shape (2,) [m].
        centre_ray: Ray-plane intersection of the pixel area centroid, shape (2,) [m].
        grasp: Where the pad should seal, shape (2,) [m]: the centre when it lies at least
            ``pad_clearance`` inside the material, else the pole of inaccessibility.
        color: Measured RGB in [0, 1].
        area: Area on the plane [m^2].
        outline_px: The traced outer outline the figure was simplified from, shape (k, 2)
            [px], y down (None: not kept).
        outline_mm: That traced outline on the plane of the tile tops, world x, y [mm] (y up),
            shape (k, 2) (None: not kept): every boundary pixel, where ``figure`` has its
            relevant points and the arcs through three of them.
    """

    index: int
    figure_px: Figure
    figure: Figure
    description: Description
    centre: np.ndarray
    centre_ray: np.ndarray
    grasp: np.ndarray
    color: tuple[float, float, float]
    area: float
    outline_px: np.ndarray | None = None
    outline_mm: np.ndarray | None = None


@dataclass(frozen=True, eq=False)
class PartialRegion:
    """A region touching the image border (part of a tile): never described, never placed.

    Attributes:
        centre: World position of the visible part's centroid, shape (2,) [m].
        area: Visible area on the plane [m^2].
        color: Median RGB in [0, 1].
    """

    centre: np.ndarray
    area: float
    color: tuple[float, float, float]


@dataclass(frozen=True, eq=False)
class Perception:
    """Everything perceived in one image.

    Attributes:
        tiles: Whole tiles, described.
        partial: Regions touching the image border.
        unrecognised: Messages for regions whose outline could not be made into a figure.
        plane_z: Height of the plane the figures were mapped to [m].
    """

    tiles: tuple[PerceivedTile, ...]
    partial: tuple[PartialRegion, ...]
    unrecognised: tuple[str, ...]
    plane_z: float


def _to_world_boundary(
    camera: CameraModel, b: Boundary, z: float, scale: float
) -> tuple[np.ndarray, np.ndarray]:
    pts = _unproject(camera, np.asarray(b.points), z)[:, :2] * scale
    return pts, np.asarray(b.curve_mask)


def outline_to_world(
    camera: CameraModel, outline_px: np.ndarray, z: float, cfg: PerceptionConfig | None = None
) -> np.ndarray:
    """A traced pixel outline (k, 2) cast onto the plane at height ``z``: world x, y [mm], y up.

    Raises:
        PerceptionError: Plane not in front of the camera.
    """
    cfg = cfg or PerceptionConfig()
    return _unproject(camera, np.asarray(outline_px, dtype=float), z)[:, :2] * cfg.mm_per_m


def figure_to_world(
    camera: CameraModel, fig: Figure, z: float, cfg: PerceptionConfig | None = None
) -> Figure:
    """Map a pixel figure (``y_down``) onto the world plane at height ``z``, in [mm], y up.

    Relevant points and curve marks are mapped one by one (a camera looking down maps circles
    to circles; a small tilt keeps arcs within the curve tolerances). The figure is taken as
    qshape extracted it: no shape correction happens here.

    Raises:
        PerceptionError: Plane not in front of the camera.
        qshape.InvalidFigureError: The mapped outline is degenerate.
    """
    cfg = cfg or PerceptionConfig()
    outer, mask = _to_world_boundary(camera, fig.outer, z, cfg.mm_per_m)
    holes = []
    for h in fig.holes:
        hp, hm = _to_world_boundary(camera, h, z, cfg.mm_per_m)
        holes.append(Boundary.make(hp, hm, y_down=False, what="hole"))
    return Figure.from_polygon(outer, holes, fig.color, curve_mask=mask, y_down=False)


def grasp_point(fig_mm: Figure, centre: np.ndarray, cfg: PerceptionConfig) -> np.ndarray:
    """Pad position [m], shape (2,): the centre if the pad fits there, else its best hold.

    Args:
        fig_mm: World figure in [mm].
        centre: Its centroid [m], shape (2,).
        cfg: Clearance and search tolerance.
    """
    s = 1.0 / cfg.mm_per_m
    poly = Polygon(
        np.asarray(fig_mm.outer.dense()) * s,
        [np.asarray(h.dense()) * s for h in fig_mm.holes],
    )
    if not poly.is_valid:
        poly = poly.buffer(0)
    c = Point(float(centre[0]), float(centre[1]))
    if poly.contains(c) and poly.boundary.distance(c) >= cfg.pad_clearance:
        return np.asarray(centre, dtype=float).copy()
    best = shapely.ops.polylabel(poly, tolerance=cfg.polylabel_tolerance)
    if poly.boundary.distance(best) >= cfg.thin_fraction * cfg.pad_clearance:
        return np.array([best.x, best.y])  # (nearly) the whole pad on material
    return best_hold(poly, centre, cfg.pad_clearance, cfg.grasp_step, cfg.polylabel_tolerance)


def perceive_tiles(
    image: np.ndarray,
    camera: CameraModel,
    tile_top_z: float,
    *,
    cfg: PerceptionConfig | None = None,
    extract_params: qshape.ExtractParams | None = None,
    tolerances: qshape.Tolerances | None = None,
    white_balance: WhiteBalance | None = None,
    height: np.ndarray | None = None,
) -> Perception:
    """Tiles in an input-camera image, located in the world and described (once).

    Args:
        image: RGB uint8, shape (h, w, 3).
        camera: Calibrated camera model of that image.
        tile_top_z: Height of the tiles' top faces [m] (``TaskSpec.pick.tile_top_z``): the
            plane every relevant point is cast onto.
        cfg: Perception settings (bundled defaults when None).
        extract_params: qshape extraction parameters (bundled ``configs/vision.yaml`` when
            None).
        tolerances: qshape tolerances for the descriptions (bundled when None).
        white_balance: Called once with the measured colours of the picture's tiles, shape
            (n, 3), when there are any; the tiles' colours are multiplied by the gain (3,) it
            returns (clipped to [0, 1], `recolour`) before they are described. None: the
            colours as measured.
        height: The tiles' height above the belt [mm], shape (h, w), aligned with ``image``
            (`agents.scripted.height.HeightMap`), or None: a tile of the belt's colour is then found
            by its height (`qshape.extract_detailed`).

    Returns:
        The perceived tiles, partial regions and unrecognised regions. An image qshape cannot
        use (one uniform colour: a covered or dark camera) gives no tiles and its reason in
        ``unrecognised``.

    Raises:
        qshape.ImageError: Not an RGB uint8 image of a usable size.
        PerceptionError: Plane not in front of the camera.
    """
    cfg = cfg or PerceptionConfig()
    z = float(tile_top_z)
    res = _extract(image, extract_params, height)
    if isinstance(res, str):
        return Perception((), (), (res,), z)
    world: list[Figure] = []
    unrecognised = list(res.rejected)
    kept_px: list[tuple[Figure, np.ndarray]] = []
    for k, fig in enumerate(res.figures):
        try:
            world.append(figure_to_world(camera, fig, z, cfg))
            kept_px.append((fig, res.outlines[k]))
        except qshape.QShapeError as exc:
            unrecognised.append(f"figure {k}: not mapped to the belt plane: {exc}")
    colors = [fw.color if fw.color is not None else _BLACK for fw in world]
    figs = world
    if white_balance is not None and world:
        gain = white_balance(np.array(colors))
        figs = [recolour(fw, c, gain) for fw, c in zip(world, colors, strict=True)]
        colors = [f.color or c for f, c in zip(figs, colors, strict=True)]
    descs = qshape.describe_many(figs, tolerances) if figs else []
    tiles = [
        _perceived(k, fpx, fw, f, d, color, camera, z, cfg, outline)
        for k, ((fpx, outline), fw, f, d, color) in enumerate(
            zip(kept_px, world, figs, descs, colors, strict=True)
        )
    ]
    partial = tuple(
        PartialRegion(
            _unproject(camera, np.asarray(p.centroid)[None], z)[0, :2],
            _pixel_area_to_plane(camera, np.asarray(p.outline), z),
            p.color,
        )
        for p in res.partial
    )
    return Perception(tuple(tiles), partial, tuple(unrecognised), z)


def _perceived(  # noqa: PLR0913, PLR0917
    k: int,
    fpx: Figure,
    fw: Figure,
    figure: Figure,
    d: qshape.Description,
    color: tuple[float, float, float],
    camera: CameraModel,
    z: float,
    cfg: PerceptionConfig,
    outline: np.ndarray | None,
) -> PerceivedTile:
    """One perceived tile: ``fw`` places it, ``figure`` (``fw`` recoloured) describes it."""
    s = 1.0 / cfg.mm_per_m
    centre = np.asarray(fw.centroid) * s
    ray = _unproject(camera, np.asarray(fpx.centroid)[None], z)[0, :2]
    grasp = grasp_point(fw, centre, cfg)
    traced = None if outline is None else outline_to_world(camera, outline, z, cfg)
    return PerceivedTile(
        k, fpx, figure, d, centre, ray, grasp, color, fw.area * s * s, outline, traced
    )


def refigured(
    tile: PerceivedTile,
    camera: CameraModel,
    z: float,
    outline_params: qshape.OutlineParams,
    *,
    cfg: PerceptionConfig | None = None,
    tolerances: qshape.Tolerances | None = None,
) -> PerceivedTile | None:
    """The tile with its traced outline simplified again with other outline parameters.

    The holes, index and colour (as balanced for the first figure) stay those of the first
    figure. None when the tile kept no traced outline or the new simplification gives no
    valid figure.

    Args:
        tile: A perceived tile (``outline_px`` kept).
        camera: The camera model of its image.
        z: Plane height of its relevant points [m].
        outline_params: The simplification parameters of the retry.
        cfg: Perception settings (bundled defaults when None).
        tolerances: qshape tolerances for the description (bundled when None).
    """
    if tile.outline_px is None:
        return None
    cfg = cfg or PerceptionConfig()
    try:
        color = tile.figure_px.color
        outer = Figure.from_outline(tile.outline_px, (), color, params=outline_params, y_down=True)
        fpx = Figure.from_polygon(
            outer.outer.points,
            list(tile.figure_px.holes),
            color,
            curve_mask=outer.outer.curve_mask,
            y_down=True,
        )
        fw = figure_to_world(camera, fpx, z, cfg)
        figure = dataclasses.replace(fw, color=tile.color)
        d = qshape.describe(figure, tolerances)
    except qshape.QShapeError:
        return None
    return _perceived(tile.index, fpx, fw, figure, d, tile.color, camera, z, cfg, tile.outline_px)


def _extract(
    image: np.ndarray,
    extract_params: qshape.ExtractParams | None,
    height: np.ndarray | None = None,
) -> qshape.ExtractResult | str:
    """The figures qshape extracts from a picture, or why the picture is not usable.

    Raises:
        qshape.ImageError: Not an RGB uint8 image of a usable size.
    """
    try:
        health = qshape.image_health(image)
        if health.verdict in ("dark", "overexposed"):
            # A uniform picture is an empty belt; a black or blown-out one is a camera fault.
            return f"image not usable: {health.message}"
        return qshape.extract_detailed(image, extract_params, height)
    except qshape.ImageError as exc:
        arr = np.asarray(image)
        well_formed = arr.dtype == np.uint8 and arr.ndim == 3 and arr.shape[2] == 3  # noqa: PLR2004
        if not well_formed:
            raise
        return f"image not usable: {exc}"


def balance_colors(
    perception: Perception,
    palette: np.ndarray,
    cfg: PerceptionConfig | None = None,
    tolerances: qshape.Tolerances | None = None,
    *,
    history: np.ndarray | None = None,
    per_channel: bool = True,
) -> tuple[Perception, np.ndarray]:
    """The perception with tile colours corrected by `color_gain` (tiles re-described).

    Args:
        perception: Tiles as measured.
        palette: The design's colours, shape (m, 3).
        cfg: Gain settings.
        tolerances: For the new descriptions.
        history: Measured colours, shape (k, 3), to fit the gain on instead of this picture's.
        per_channel: See `color_gain`.

    Returns:
        (corrected perception, gain (3,)).
    """
    cfg = cfg or PerceptionConfig()
    if not perception.tiles:
        return perception, np.ones(3)
    fit_on = np.array([t.color for t in perception.tiles]) if history is None else history
    gain = color_gain(fit_on, palette, cfg, per_channel)
    figs = [recolour(t.figure, t.color, gain) for t in perception.tiles]
    descs = qshape.describe_many(figs, tolerances)
    tiles = [
        dataclasses.replace(t, figure=f, description=d, color=f.color or t.color)
        for t, f, d in zip(perception.tiles, figs, descs, strict=True)
    ]
    return dataclasses.replace(perception, tiles=tuple(tiles)), gain


def _pixel_area_to_plane(camera: CameraModel, outline_px: np.ndarray, z: float) -> float:
    pts = _unproject(camera, outline_px, z)[:, :2]
    return abs(signed_area(pts))


@dataclass(frozen=True, eq=False)
class SlotTarget:
    """One design slot in the world.

    Attributes:
        index: Slot index in the design.
        name: Slot name.
        figure: The slot's figure in mesh millimetres (y up).
        description: Its qshape description.
        pose: World x, y [m] of the slot's area centroid and its yaw [rad] (the design angle).
        symmetry: Rotational symmetry order (1: none, 0: continuous).
        color: Design RGB in [0, 1].
        seen: The slot's outline as the camera's outline simplification sees it, when its
            description matches no turn of ``description``: a design corner turning too
            little for a picture to show (a rounded corner's tangent ends, an arc edge nearly
            continuing its neighbour, a short edge between opposite turns). None when the
            two agree.
        class_name: The design's shape-and-colour class of the slot ("": not known).
    """

    index: int
    name: str
    figure: Figure
    description: Description
    pose: np.ndarray
    symmetry: int
    color: tuple[float, float, float]
    seen: SeenSlot | None = None
    class_name: str = ""

    @property
    def descriptions(self) -> tuple[Description, ...]:
        """The design's description, then the seen one when there is one."""
        if self.seen is None:
            return (self.description,)
        return (self.description, self.seen.description)


def slot_targets(
    slots: Sequence[WorldSlot],
    tolerances: qshape.Tolerances | None = None,
    *,
    seen: tuple[qshape.OutlineParams, float, float] | None = None,
) -> tuple[SlotTarget, ...]:
    """Describe the env's world slots (``TaskSpec.slots``) for matching.

    Args:
        slots: The slots in the world (figures in design millimetres).
        tolerances: qshape tolerances (bundled when None).
        seen: (the pictures' outline parameters, the camera's scale on the tile tops
            [px/mm], the near-turn residual of `_seen_one`): each slot also gets the
            description of its outline as a picture's simplification sees it, where that
            differs from its own (`SlotTarget.seen`). None: no seen descriptions.

    Returns:
        One `SlotTarget` per slot, in the given order.
    """
    descs = qshape.describe_many([s.figure for s in slots], tolerances) if slots else []
    seen_descs = seen_outlines(slots, descs, tolerances, seen)
    return tuple(
        SlotTarget(
            s.index,
            s.name,
            s.figure,
            d,
            np.array([s.xy[0], s.xy[1], s.yaw]),
            s.symmetry,
            s.color,
            sd,
            s.class_name,
        )
        for s, d, sd in zip(slots, descs, seen_descs, strict=True)
    )


__all__ = [
    "PartialRegion",
    "PerceivedTile",
    "Perception",
    "WhiteBalance",
    "SlotTarget",
    "balance_colors",
    "figure_to_world",
    "grasp_point",
    "outline_to_world",
    "refigured",
    "perceive_tiles",
    "slot_targets",
]
