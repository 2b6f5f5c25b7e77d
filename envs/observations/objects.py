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

Start point of ``points``: of `OVERSAMPLE` x P samples at equal arc length along the outline
(fixed on the body), the one of smallest polar angle in the world frame, angles counted
counter-clockwise from the world +x axis in [0, 2 pi) about the centroid; the P points are
then every `OVERSAMPLE`-th sample from it. So turning a tile turns its points, the start moves
along the outline in steps of 1 / `OVERSAMPLE` of the point spacing (about 0.25 mm on a
paper_mixed tile at P = 32), every point lies on the built outline, and a tile lying as its
slot wants it gives the slot's points (within that step and the tile's manufacturing noise)
whatever its body frame or symmetry.

Cost: per episode the outlines are resampled once in the body frame and their polar
angles sorted; per observation one search per entity finds the start, one gather takes the
points and one complex multiplication turns them. ``objects_noise_mm`` adds Gaussian noise
[mm] to each tile's P points at every observation (from the env's ``np_random``); slot
outlines come from the design and carry none.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
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
OVERSAMPLE = 16
"""Body-frame samples per observed point (the start point's resolution along the outline)."""
CM2_PER_M2 = 1e4
"""Square centimetres per square metre."""
BOUND = 1e3
"""Bound of the Box (positions [m] and points [mm] lie well inside)."""
TWO_PI = 2 * np.pi


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
    """What does not change in an episode, per entity (tile or slot); m entities, P points.

    Attributes:
        fine: Outer outline in the body frame about the area centroid as complex x + iy
            [mm], counter-clockwise at equal arc length from vertex 0, twice round (so P
            points from any start are contiguous), shape (m, 2 * OVERSAMPLE * P) complex.
        ranked: Each entity's sample polar angles in the body frame, sorted, plus its
            smallest + 2 pi at the end, plus 4 pi times the entity's index; flattened, shape
            (m * (OVERSAMPLE * P + 1),) [rad], increasing: one search finds every start.
        order: The sample index of each ``ranked`` entry, same shape.
        rgb: Colours, shape (m, 3) in [0, 1].
        area: Areas with holes subtracted, shape (m,) [cm^2].
        hole_area: Summed hole areas, shape (m,) [cm^2].
    """

    fine: np.ndarray
    ranked: np.ndarray
    order: np.ndarray
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
    pts = np.asarray(outline, float)
    if not LinearRing(pts).is_ccw:
        pts = pts[::-1]
    closed = np.vstack([pts, pts[:1]])
    along = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(closed, axis=0).T))])
    distances = np.linspace(0.0, along[-1], count, endpoint=False)
    return np.column_stack(
        [np.interp(distances, along, closed[:, 0]), np.interp(distances, along, closed[:, 1])]
    )


def entity_geometry(
    outlines: Sequence[np.ndarray],
    holes: Sequence[Sequence[np.ndarray]],
    colors: Sequence[Sequence[float]] | np.ndarray,
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
    m, count = len(outlines), OVERSAMPLE * points
    fine = np.zeros((m, count), complex)
    area, hole_area = np.zeros(m), np.zeros(m)
    for i, (outer, inner) in enumerate(zip(outlines, holes, strict=True)):
        poly = Polygon(outer, list(inner))
        c = np.array([poly.centroid.x, poly.centroid.y])
        xy = resample_outline(np.asarray(outer) - c, count) * MM_PER_M
        fine[i] = xy[:, 0] + 1j * xy[:, 1]
        area[i] = poly.area * CM2_PER_M2
        hole_area[i] = sum(Polygon(h).area for h in inner) * CM2_PER_M2
    angle = np.angle(fine) % TWO_PI
    order = np.argsort(angle, axis=1, kind="stable")
    order = np.concatenate([order, order[:, :1]], axis=1)
    ranked = np.take_along_axis(angle, order, 1)
    ranked[:, -1] += TWO_PI
    ranked += 2 * TWO_PI * np.arange(m)[:, None]
    rgb = np.asarray(colors, float).reshape(m, 3)
    twice = np.concatenate([fine, fine], axis=1)
    return EntityGeometry(twice, ranked.ravel(), order.ravel(), rgb, area, hole_area)


def oriented_points(
    geometry: EntityGeometry, turn: np.ndarray, yaw: np.ndarray, points: int
) -> np.ndarray:
    """Body-frame outlines turned by ``yaw``, P points from the world-frame start point.

    Args:
        geometry: The entities' precomputed outlines (``fine``, ``ranked``, ``order``).
        turn: ``exp(i yaw)`` of each entity, shape (m,) complex.
        yaw: Yaw of each entity, shape (m,) [rad].
        points: P.

    Returns:
        Shape (m, P) complex x + iy [mm] (see the module docstring's start rule).
    """
    m, count = len(yaw), geometry.fine.shape[1] // 2
    rows = np.arange(m)
    # the first body angle at or after the world +x ray's (-yaw), wrapping round
    pos = np.searchsorted(geometry.ranked, np.mod(-yaw, TWO_PI) + 2 * TWO_PI * rows)
    start = geometry.order[pos] + rows * (2 * count)
    idx = start[:, None] + OVERSAMPLE * np.arange(points)
    return geometry.fine.ravel()[idx] * turn[:, None]


def as_xy(z: np.ndarray) -> np.ndarray:
    """Complex points (m, P) -> float (m, 2 * P): (x0, y0, x1, y1, ...) per row."""
    return np.ascontiguousarray(z).view(np.float64).reshape(len(z), -1)


class ObjectRows:
    """Builds the ``objects`` rows of one cell (cell order; the env permutes them).

    Per episode it builds row templates (colour, areas, valid; the slots' poses and points
    too, as slots do not move); per observation it fills in the tiles' poses, points and flags
    and the slots' flags.

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
        self._tile_template = np.zeros((self.tile_rows, self.dim), np.float32)
        self._slots_seen: tuple[Any, ...] | None = None
        self._slot_template = np.zeros((self.slot_rows, self.dim), np.float32)
        f = self.fields
        self._flag, self._xy, self._yaw, self._points = (
            f["flag"].start,
            f["xy"],
            f["yaw"],
            f["points"],
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
            self._start_tiles()
        if cell.slots is not self._slots_seen:
            self._start_slots()
        n, k = len(cell.tiles), len(cell.slots)
        poses = cell.tile_poses()
        turn = np.exp(1j * poses.yaw)
        pts = as_xy(oriented_points(self._tile_geometry, turn, poses.yaw, self.points))
        if self.noise_mm > 0:
            pts = pts + rng.normal(0.0, self.noise_mm, pts.shape)
        tiles = self._tile_template.copy()
        tiles[:n, self._xy] = poses.pos[:, :2]
        tiles[:n, self._yaw] = as_xy(turn[:, None])
        tiles[:n, self._flag] = cell.input_half()
        tiles[:n, self._points] = pts
        slots = self._slot_template.copy()
        slots[:k, self._flag] = evaluation.slot_filled
        return tiles, slots

    def _start_tiles(self) -> None:
        tiles = self.cell.tiles
        self._tiles_seen = tiles
        self._tile_geometry = entity_geometry(
            [t.outline for t in tiles],
            [t.holes for t in tiles],
            [t.color for t in tiles],
            self.points,
        )
        self._tile_template = self._template(self.tile_rows, self._tile_geometry)

    def _start_slots(self) -> None:
        slots = self.cell.slots
        self._slots_seen = slots
        geometry = entity_geometry(
            [s.shape.outline for s in slots],
            [s.shape.holes for s in slots],
            [s.shape.color for s in slots],
            self.points,
        )
        rows = self._template(self.slot_rows, geometry)
        xyyaw, k = self.task.slot_xyyaw, len(slots)
        rows[:k, self._xy] = xyyaw[:, :2]
        turn = np.exp(1j * xyyaw[:, 2])
        rows[:k, self._yaw] = as_xy(turn[:, None])
        rows[:k, self._points] = as_xy(oriented_points(geometry, turn, xyyaw[:, 2], self.points))
        self._slot_template = rows

    def _template(self, rows: int, geometry: EntityGeometry) -> np.ndarray:
        """Rows with what does not move: colour, areas, valid (the rest zero)."""
        f, m = self.fields, len(geometry.fine)
        out = np.zeros((rows, self.dim), np.float32)
        out[:m, f["rgb"]] = geometry.rgb
        out[:m, f["area"].start] = geometry.area
        out[:m, f["hole_area"].start] = geometry.hole_area
        out[:m, f["valid"].start] = 1.0
        return out


__all__ = [
    "DEFAULT_POINTS",
    "OBJECT_DIM",
    "OBJECT_FIELDS",
    "OVERSAMPLE",
    "SCALAR_FIELDS",
    "EntityGeometry",
    "as_xy",
    "ObjectRows",
    "entity_geometry",
    "object_dim",
    "object_fields",
    "oriented_points",
    "resample_outline",
]
