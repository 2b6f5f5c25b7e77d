"""The ``objects`` observation: one entity row per tile and per slot, without identity labels.

``obs_mode="objects"`` gives ``tiles`` float32 (rows_t, D) and ``slots`` float32 (rows_s, D),
D = `object_dim` (``objects_points``) = 75 for the default 32 points. Row ``i`` of ``tiles``
is the tile the ``pick_place_discrete`` action's tile index ``i`` names, row ``j`` of
``slots`` its slot ``j`` (`envs.indexing`, as the ``state`` rows); rows past the episode's
tiles or slots (``objects_rows`` larger than the counts) are padding: all zeros. No class id
appears: a policy matches tiles to slots from outline and colour. The row layout (fixed
fields first, so their offsets do not depend on the point count):

=========== ======================= ==========================================================
field       slice (P = 32)          meaning
=========== ======================= ==========================================================
rgb         0:3                     glaze colour in [0, 1]. Tiles: the tile's colour as built
                                    for this episode (`PhysicalTile.color`, with the cell's
                                    glaze noise, without ``color_randomization``'s render
                                    change); slots: the nominal colour of the class the slot
                                    wants (`TileShape.color`).
area        3:4                     area [cm^2], holes subtracted.
hole_area   4:5                     summed area of the holes [cm^2] (0: none).
xy          5:7                     world position of the area centroid [m].
yaw         7:9                     (cos, sin) of the yaw: the tile's as it lies now; the
                                    slot's (how it wants its tile set down).
flag        9:10                    tiles: 1 when on the input belt and pickable now (the
                                    predicate the discrete action accepts a tile by,
                                    `Cell.input_half`); slots: 1 when filled correctly.
valid       10:11                   1 for a real row, 0 for a padded row.
points      11:11+2P                outer outline as P points (x, y) [mm] flattened
                                    row-major (x0, y0, x1, y1, ...), about the area centroid,
                                    oriented as the entity lies in the world frame (a tile as
                                    on the belt now, a slot as it wants its tile),
                                    counter-clockwise at equal arc length.
=========== ======================= ==========================================================

Start point of ``points``: where the outline crosses the world +x ray from the centroid (polar
angle 0, angles counted in [0, 2 pi)), i.e. the point of smallest polar angle in the world
frame; when the outline does not cross that ray (the centroid outside a concave tile), the
sampled point of smallest polar angle. Turning a tile turns its points (and moves the start
along the outline continuously, except where the ray is tangent to it), so a tile lying as its
slot wants it gives nearly the slot's points whatever its body frame.

Cost: per episode the outlines are resampled once in the body frame (`OVERSAMPLE` x P points
at equal arc length, shapely); per step they are only rotated, the start found and every
`OVERSAMPLE`-th point taken (linear interpolation between neighbours for the start's
fraction, so a point next to a corner may cut it by up to the sagitta of one fine spacing:
under 0.1 mm for the bundled tiles at P = 32). ``objects_noise_mm`` adds Gaussian noise [mm] to each tile's P points at every
observation (from the env's ``np_random``); slot outlines come from the design and carry none.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import shapely
from gymnasium import spaces
from shapely.geometry import LinearRing, Polygon

from envs.cell.cell import Cell
from envs.env_config import EnvConfig, EnvConfigError
from envs.task import Evaluation, MosaicTask
from spatial.units import MM_PER_M

SCALAR_FIELDS: tuple[tuple[str, int], ...] = (
    ("rgb", 3),
    ("area", 1),
    ("hole_area", 1),
    ("xy", 2),
    ("yaw", 2),
    ("flag", 1),
    ("valid", 1),
)
"""The fields before ``points``, in row order, with their widths."""
SCALAR_DIM = sum(w for _, w in SCALAR_FIELDS)
"""Columns before ``points`` (11)."""
DEFAULT_POINTS = 32
"""Default ``objects_points``."""
OVERSAMPLE = 8
"""Body-frame samples per observed point (the start point's resolution along the outline)."""
CM2_PER_M2 = 1e4
"""Square centimetres per square metre."""
BOUND = 1e3
"""Bound of the Box (positions [m] and points [mm] lie well inside)."""


def object_fields(points: int = DEFAULT_POINTS) -> dict[str, slice]:
    """Field name -> column slice of an entity row with ``points`` outline points."""
    fields: dict[str, slice] = {}
    start = 0
    for name, width in SCALAR_FIELDS:
        fields[name] = slice(start, start + width)
        start += width
    fields["points"] = slice(start, start + 2 * points)
    return fields


def object_dim(points: int = DEFAULT_POINTS) -> int:
    """Length of an entity row with ``points`` outline points."""
    return SCALAR_DIM + 2 * points


OBJECT_FIELDS: dict[str, slice] = object_fields()
"""Field name -> column slice at the default 32 points (see the module docstring)."""
OBJECT_DIM = object_dim()
"""Row length at the default 32 points (75)."""


@dataclass(frozen=True)
class EntityGeometry:
    """What does not change in an episode, per entity (tile or slot).

    Attributes:
        fine: Outer outline in the body frame about the area centroid, counter-clockwise at
            equal arc length from vertex 0, shape (m, OVERSAMPLE * P, 2) [mm].
        rgb: Colours, shape (m, 3) in [0, 1].
        area: Areas with holes subtracted, shape (m,) [cm^2].
        hole_area: Summed hole areas, shape (m,) [cm^2].
    """

    fine: np.ndarray
    rgb: np.ndarray
    area: np.ndarray
    hole_area: np.ndarray


def resample_outline(outline: np.ndarray, count: int) -> np.ndarray:
    """A closed outline at ``count`` points of equal arc length, counter-clockwise.

    Args:
        outline: Polygon vertices, shape (v, 2), either orientation, not closed.
        count: Number of points.

    Returns:
        Shape (count, 2), starting at the counter-clockwise outline's first vertex.
    """
    ring = LinearRing(outline)
    if not ring.is_ccw:
        ring = LinearRing(np.asarray(outline)[::-1])
    distances = np.linspace(0.0, ring.length, count, endpoint=False)
    return shapely.get_coordinates(shapely.line_interpolate_point(ring, distances))


def entity_geometry(
    outlines: Sequence[np.ndarray],
    holes: Sequence[Sequence[np.ndarray]],
    colors: Sequence[Sequence[float]],
    points: int,
) -> EntityGeometry:
    """Precompute the body-frame rows of entities (at reset).

    Args:
        outlines: Outer outline of each entity [m], any origin (re-centred on the area
            centroid of the outline with its holes).
        holes: Each entity's holes [m], same frame as its outline.
        colors: Each entity's RGB in [0, 1].
        points: Observed points per outline (P).
    """
    m = len(outlines)
    fine = np.zeros((m, OVERSAMPLE * points, 2))
    area, hole_area = np.zeros(m), np.zeros(m)
    for i, (outer, inner) in enumerate(zip(outlines, holes, strict=True)):
        poly = Polygon(outer, list(inner))
        c = np.array([poly.centroid.x, poly.centroid.y])
        fine[i] = (resample_outline(np.asarray(outer) - c, OVERSAMPLE * points)) * MM_PER_M
        area[i] = poly.area * CM2_PER_M2
        hole_area[i] = sum(Polygon(h).area for h in inner) * CM2_PER_M2
    rgb = np.asarray(colors, float).reshape(m, 3)
    return EntityGeometry(fine, rgb, area, hole_area)


def oriented_points(fine: np.ndarray, yaw: np.ndarray, points: int) -> np.ndarray:
    """Body-frame outlines turned by ``yaw``, P points from the world-frame start point.

    Args:
        fine: Body-frame outlines, shape (m, OVERSAMPLE * P, 2).
        yaw: Yaw of each entity, shape (m,) [rad].
        points: P.

    Returns:
        Shape (m, P, 2), in the same unit as ``fine`` (see the module docstring's start rule).
    """
    m, count = fine.shape[0], fine.shape[1]
    if m == 0:
        return np.zeros((0, points, 2))
    c, s = np.cos(yaw)[:, None], np.sin(yaw)[:, None]
    x = c * fine[..., 0] - s * fine[..., 1]
    y = s * fine[..., 0] + c * fine[..., 1]
    k0 = np.argmin(np.arctan2(y, x) % (2 * np.pi), axis=1)
    rows = np.arange(m)
    y_prev, y_k0 = y[rows, k0 - 1], y[rows, k0]
    crossing = (y_prev < 0) & (y_k0 >= 0)
    frac = np.where(crossing, y_prev / np.where(crossing, y_prev - y_k0, 1.0), 1.0)
    start = k0 - 1 + frac  # fractional sample index of the start point
    lo = np.floor(start).astype(int)
    w = (start - lo)[:, None]
    idx = (lo[:, None] + OVERSAMPLE * np.arange(points)[None, :]) % count
    nxt = (idx + 1) % count
    px = (1 - w) * np.take_along_axis(x, idx, 1) + w * np.take_along_axis(x, nxt, 1)
    py = (1 - w) * np.take_along_axis(y, idx, 1) + w * np.take_along_axis(y, nxt, 1)
    return np.stack([px, py], axis=-1)


class ObjectRows:
    """Builds the ``objects`` rows of one cell (cell order; the env permutes them).

    Args:
        cell: The cell.
        task: The task (slot poses).
        config: Environment configuration (``objects_points``, ``objects_rows``,
            ``objects_noise_mm``, ``objects_source``).

    Raises:
        EnvConfigError: ``objects_rows`` smaller than the episode's tiles or slots.
    """

    def __init__(self, cell: Cell, task: MosaicTask, config: EnvConfig) -> None:
        self.cell = cell
        self.task = task
        self.points = config.objects_points
        self.noise_mm = config.objects_noise_mm
        self.fields = object_fields(self.points)
        self.dim = object_dim(self.points)
        n, k = len(cell.tiles), len(cell.slots)
        rows = config.objects_rows
        if rows is not None and rows < max(n, k):
            raise EnvConfigError(
                f"objects_rows {rows} is smaller than the episode's {n} tiles / {k} slots; "
                f"allowed: None (the counts) or an int >= {max(n, k)}"
            )
        self.tile_rows = n if rows is None else rows
        self.slot_rows = k if rows is None else rows
        self._tiles_seen: tuple[Any, ...] | None = None
        self._tile_geometry = entity_geometry([], [], np.zeros((0, 3)), self.points)
        self._slot_geometry = entity_geometry(
            [s.shape.outline for s in cell.slots],
            [s.shape.holes for s in cell.slots],
            [s.shape.color for s in cell.slots],
            self.points,
        )

    def spaces(self) -> dict[str, spaces.Box]:
        """The ``tiles`` and ``slots`` Boxes."""
        return {
            "tiles": spaces.Box(-BOUND, BOUND, (self.tile_rows, self.dim), np.float32),
            "slots": spaces.Box(-BOUND, BOUND, (self.slot_rows, self.dim), np.float32),
        }

    def observe(
        self, rng: np.random.Generator, evaluation: Evaluation
    ) -> tuple[np.ndarray, np.ndarray]:
        """``tiles`` (rows_t, D) and ``slots`` (rows_s, D) in the cell's order (fresh arrays).

        Args:
            rng: Generator for the outline noise (drawn only when ``objects_noise_mm`` > 0).
            evaluation: The task's current `Evaluation` (slot fill).
        """
        cell = self.cell
        if cell.tiles is not self._tiles_seen:  # a reset drew new variants or colours
            self._tiles_seen = cell.tiles
            self._tile_geometry = entity_geometry(
                [t.outline for t in cell.tiles],
                [t.holes for t in cell.tiles],
                [t.color for t in cell.tiles],
                self.points,
            )
        poses = cell.tile_poses()
        tile_pts = oriented_points(self._tile_geometry.fine, poses.yaw, self.points)
        if self.noise_mm > 0:
            tile_pts = tile_pts + rng.normal(0.0, self.noise_mm, tile_pts.shape)
        tiles = self._rows(
            self.tile_rows,
            self._tile_geometry,
            tile_pts,
            poses.pos[:, :2],
            poses.yaw,
            cell.input_half(),
        )
        s = self.task.slot_xyyaw
        slot_pts = oriented_points(self._slot_geometry.fine, s[:, 2], self.points)
        slots = self._rows(
            self.slot_rows,
            self._slot_geometry,
            slot_pts,
            s[:, :2],
            s[:, 2],
            np.asarray(evaluation.slot_filled, bool),
        )
        return tiles, slots

    def _rows(
        self,
        rows: int,
        geometry: EntityGeometry,
        pts: np.ndarray,
        xy: np.ndarray,
        yaw: np.ndarray,
        flag: np.ndarray,
    ) -> np.ndarray:
        f, m = self.fields, len(pts)
        out = np.zeros((rows, self.dim), np.float32)
        out[:m, f["rgb"]] = geometry.rgb
        out[:m, f["area"].start] = geometry.area
        out[:m, f["hole_area"].start] = geometry.hole_area
        out[:m, f["xy"]] = np.clip(xy, -BOUND, BOUND)
        out[:m, f["yaw"].start] = np.cos(yaw)
        out[:m, f["yaw"].start + 1] = np.sin(yaw)
        out[:m, f["flag"].start] = flag
        out[:m, f["valid"].start] = 1.0
        out[:m, f["points"]] = pts.reshape(m, -1)
        return out


__all__ = [
    "DEFAULT_POINTS",
    "OBJECT_DIM",
    "OBJECT_FIELDS",
    "OVERSAMPLE",
    "SCALAR_FIELDS",
    "EntityGeometry",
    "ObjectRows",
    "entity_geometry",
    "object_dim",
    "object_fields",
    "oriented_points",
    "resample_outline",
]
