"""Random non-overlapping layouts of tiles on the input belt's tile area.

Poses are (x, y, yaw) relative to the tile area's centre [m, m, rad]; tiles are kept apart by a
minimum gap between their outlines (or bounding circles).

Outlines are laid out largest first by random contact placement: the placed outlines, grown by
half the gap, are rasterised into an occupancy grid (`GRID_STEP`); for a random yaw, the grid
dilated by the tile's own grown outline leaves the cells where the tile's origin can go, and
the tile takes a random cell on the edge of that free set (it then lies one gap from a placed
tile or the area's edge), jittered within the cell and tested exactly. Uniform random poses
(random sequential placement) jammed at the last tiles of a 16-tile design (about 45 % of the
area) three times in four: they spread the first tiles out and leave only gaps too narrow for
the last; placing each tile against the others keeps the free space in one piece.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np
import shapely
from shapely.geometry import Polygon

from envs.errors import CellError, LayoutError
from spatial.units import MM_PER_M

OUTLINE_FILL = 0.5
"""Largest fraction of a tile area random placement of outlines is asked to fill."""


CIRCLE_FILL = 0.8
"""The same for bounding circles (no outlines given)."""

FREE_DRAWS = 8
"""Poses drawn from the edge of the free space per yaw (one dilation of the grid per yaw)."""
GRID_STEP = 0.002
"""Cell size of the occupancy grid [m] (finer: fewer jams, slower dilations)."""
GRID_SHIFT = 8
"""Fractional bits of the vertex coordinates the grid's polygons are drawn with."""


@dataclass(frozen=True, eq=False)
class Footprint:
    """What a layout needs of one tile outline, computed once per outline and gap.

    Attributes:
        outline: Outline in the tile's own frame, shape (k, 2) [m].
        gap: The clearance the footprint was made for [m].
        reach: Largest vertex distance from the frame's origin [m].
        inner: Radius of the largest circle about the origin inside the outline (0 when the
            origin is outside) [m].
        half_extent: Half the outline's smallest width over rotations (it must fit some way)
            [m].
        grown: The outline grown by ``gap / 2`` (rounded corners), shape (m, 2) [m].
        area: Area of ``grown`` [m^2].
    """

    outline: np.ndarray
    gap: float
    reach: float
    inner: float
    half_extent: float
    grown: np.ndarray
    area: float

    @staticmethod
    def of(outline: np.ndarray, gap: float) -> Footprint:
        """Footprint of an outline, shape (k, 2) [m], for clearance ``gap`` [m]."""
        o = np.asarray(outline, float)
        poly, origin = Polygon(o), shapely.Point(0.0, 0.0)
        inner = float(poly.exterior.distance(origin)) if poly.contains(origin) else 0.0
        grown = poly.buffer(gap / 2, quad_segs=GROWN_QUAD_SEGS)
        return Footprint(
            outline=o,
            gap=float(gap),
            reach=float(np.max(np.linalg.norm(o, axis=1))),
            inner=inner,
            half_extent=_min_half_extent(o),
            grown=np.asarray(grown.exterior.coords)[:-1],
            area=float(grown.area),
        )


GROWN_QUAD_SEGS = 2
"""Segments per quarter circle of a grown outline's rounded corners (grid rasterising only)."""


def footprints(outlines: Sequence[np.ndarray], gap: float) -> tuple[Footprint, ...]:
    """`Footprint` of each outline (shape (k, 2) [m]) for clearance ``gap`` [m]."""
    return tuple(Footprint.of(o, gap) for o in outlines)


def layout_capacity(
    outlines: Sequence[np.ndarray | Footprint], area_size: Sequence[float], gap: float
) -> int:
    """How many of ``outlines``, taken in order, `sample_layout` can be asked to lay out.

    Args:
        outlines: Tile outlines in their own frames, each shape (k, 2) [m], or their
            footprints (made for ``gap``).
        area_size: (x, y) size of the rectangle [m].
        gap: Minimum clearance between tiles [m].

    Returns:
        The longest prefix whose area (each outline grown by ``gap / 2``) is within
        `OUTLINE_FILL` of the rectangle's.
    """
    need = np.cumsum([f.area for f in _as_footprints(outlines, gap)])
    return int(np.searchsorted(need, OUTLINE_FILL * area_size[0] * area_size[1], side="right"))


def _as_footprints(items: Sequence[np.ndarray | Footprint], gap: float) -> tuple[Footprint, ...]:
    """Footprints of outlines or footprints (checked to be made for ``gap``)."""
    out = tuple(f if isinstance(f, Footprint) else Footprint.of(f, gap) for f in items)
    wrong = [k for k, f in enumerate(out) if f.gap != gap]
    if wrong:
        raise CellError(
            f"footprint {wrong[0]} was made for a gap of {out[wrong[0]].gap} m, the layout's "
            f"gap is {gap} m; make footprints with the layout's gap"
        )
    return out


def sample_layout(
    radii: np.ndarray,
    area_size: tuple[float, ...],
    gap: float,
    attempts: int,
    rng: np.random.Generator,
    *,
    outlines: Sequence[np.ndarray | Footprint] | None = None,
    occupied: np.ndarray | None = None,
    occupied_radii: np.ndarray | None = None,
    restarts: int = 1,
) -> np.ndarray:
    """Random non-overlapping poses for tiles in a rectangle.

    Tiles are placed largest first. Without ``outlines`` each takes the first of
    ``attempts`` uniform random poses whose bounding circle (plus ``gap``) is clear of the
    others'. With ``outlines`` the actual outlines must keep ``gap`` apart and stay inside;
    each is put against the tiles placed before it or the area's edge at a random place
    (module docstring), ``attempts`` poses tried per tile.

    Args:
        radii: Bounding radii about each tile's origin, shape (n,) [m].
        area_size: (length, width) of the rectangle centred at the origin [m].
        gap: Clearance between tiles [m].
        attempts: Poses tried per tile before giving up.
        rng: Random generator.
        outlines: Optional outline per tile in its own frame, each shape (k, 2) [m], or its
            `Footprint` for ``gap`` (made once and reused: faster).
        occupied: Centres of circles already there, shape (k, 2) [m], optional (bounding
            circles only; not with ``outlines``).
        occupied_radii: Their radii, shape (k,) [m].
        restarts: Whole layouts tried before giving up (random sequential placement can
            still jam where a tile finds no free place; a fresh draw usually succeeds).

    Returns:
        Poses (x, y, yaw), shape (n, 3), in the rectangle's frame [m, m, rad].

    Raises:
        CellError: A tile does not fit (too large, or the area is too full); `LayoutError`
            when every layout jams.
    """
    radii = np.asarray(radii, dtype=float)
    half = np.asarray(area_size, dtype=float) / 2
    shapes = None if outlines is None else _as_footprints(outlines, gap)
    if shapes is not None and occupied is not None and len(occupied):
        raise CellError("occupied circles are supported with bounding circles only, not outlines")
    if shapes is not None:
        extent = np.array([f.half_extent for f in shapes])
    else:
        extent = radii
    _check_fits(radii, area_size, gap, shapes, extent)

    def once() -> np.ndarray:
        if shapes is None:
            return _circles_once(
                radii, half, gap, attempts, rng, occupied=occupied, occupied_radii=occupied_radii
            )
        return _outlines_once(radii, half, gap, attempts, rng, shapes=shapes)

    for _ in range(max(restarts, 1) - 1):
        try:
            return once()
        except CellError:
            continue
    return once()


def _check_fits(
    radii: np.ndarray,
    area_size: tuple[float, ...],
    gap: float,
    shapes: Sequence[Footprint] | None,
    extent: np.ndarray,
) -> None:
    """Raise `CellError` when a tile is too large or the tiles too many for the area.

    Deterministic (no draw can pass): a tile's half extent plus half the gap beyond the
    area's half width, or more tile area than random placement fills (`OUTLINE_FILL`,
    `CIRCLE_FILL`).
    """
    half = np.asarray(area_size, dtype=float) / 2
    if np.any(extent + gap / 2 > half.min()):
        k = int(np.argmax(extent))
        raise CellError(
            f"tile {k} (size {2 * extent[k] * MM_PER_M:.1f} mm) does not fit the tile area "
            f"{area_size[0] * MM_PER_M:.0f} x {area_size[1] * MM_PER_M:.0f} mm"
        )
    if shapes is not None:
        need = float(sum(f.area for f in shapes))
        fill = OUTLINE_FILL
    else:
        need = float(np.sum(np.pi * (radii + gap / 2) ** 2))
        fill = CIRCLE_FILL
    have = float(area_size[0] * area_size[1])
    if need > fill * have:
        raise CellError(
            f"{len(radii)} tiles need about {need * 1e4:.0f} cm^2 of belt but the tile area is "
            f"{have * 1e4:.0f} cm^2 (random placement fills at most ~{fill:.0%}); use fewer "
            "tiles, a larger input_belt.tile_area, or feed='stream' or 'batch'"
        )


def _jammed(n: int, half: np.ndarray, attempts: int) -> LayoutError:
    return LayoutError(
        f"could not place {n} tiles without overlap in the tile area "
        f"{2 * half[0] * MM_PER_M:.0f} x {2 * half[1] * MM_PER_M:.0f} mm after {attempts} "
        "tries per tile; use fewer tiles, a larger area or feed='stream'"
    )


def _circles_once(
    radii: np.ndarray,
    half: np.ndarray,
    gap: float,
    attempts: int,
    rng: np.random.Generator,
    *,
    occupied: np.ndarray | None,
    occupied_radii: np.ndarray | None,
) -> np.ndarray:
    """One try of `sample_layout` with bounding circles; raises LayoutError when it jams."""
    centres = np.zeros((0, 2)) if occupied is None else np.asarray(occupied, float)
    rads = np.zeros(0) if occupied_radii is None else np.asarray(occupied_radii, float)
    out = np.zeros((len(radii), 3))
    for i in np.argsort(-radii):
        lim = half - radii[i]
        lim = np.where(lim > 0, lim, 0.0)
        cand = rng.uniform(-lim, lim, size=(attempts, 2))
        yaws = rng.uniform(-np.pi, np.pi, attempts)
        d = np.linalg.norm(cand[:, None, :] - centres[None, :, :], axis=2)
        ok = (d >= rads[None, :] + radii[i] + gap).all(axis=1)
        if not ok.any():
            raise _jammed(len(radii), half, attempts)
        first = int(np.argmax(ok))
        out[i] = (cand[first, 0], cand[first, 1], yaws[first])
        centres = np.concatenate([centres, cand[first : first + 1]])
        rads = np.append(rads, radii[i])
    return out


def _outlines_once(
    radii: np.ndarray,
    half: np.ndarray,
    gap: float,
    attempts: int,
    rng: np.random.Generator,
    *,
    shapes: Sequence[Footprint],
) -> np.ndarray:
    """One try of `sample_layout` with outlines; raises LayoutError when a tile jams.

    Each tile draws a yaw, then up to `FREE_DRAWS` origins on the edge of its free space at
    that yaw (`_Grid.contact_cells`), and takes the first that passes the exact test (in draw
    order); another yaw while none does, ``attempts`` poses in all.
    """
    placed = _Placed(gap, half, len(radii))
    grid = _Grid(half, GRID_STEP)
    out = np.zeros((len(radii), 3))
    origin = np.zeros((1, 2))
    for i in np.argsort(-radii):
        shape = shapes[i]
        for _ in range(max(attempts // FREE_DRAWS, 1)):
            yaw = rng.uniform(-np.pi, np.pi, 1)
            cells = grid.contact_cells(_posed_all(shape.grown, origin, yaw)[0])
            if len(cells) == 0:
                continue
            xy = grid.centres(cells[rng.integers(len(cells), size=FREE_DRAWS)])
            xy += rng.uniform(-GRID_STEP / 2, GRID_STEP / 2, size=xy.shape)
            first = placed.first_clear(shape, radii[i], xy, np.repeat(yaw, FREE_DRAWS))
            if first < FREE_DRAWS:
                break
        else:
            raise _jammed(len(radii), half, attempts)
        out[i] = (xy[first, 0], xy[first, 1], yaw[0])
        grid.mark(_posed_all(shape.grown, xy[first : first + 1], yaw)[0])
    return out


_CROSS = cv2.getStructuringElement(cv2.MORPH_CROSS, (3, 3))
"""Neighbourhood that tells a free cell on the edge of the free space (a 4-neighbour not free)."""


class _Grid:
    """Occupancy grid of a rectangle: the cells covered by the placed grown outlines.

    Args:
        half: Half size of the rectangle, shape (2,) [m].
        step: Cell size [m].
    """

    def __init__(self, half: np.ndarray, step: float) -> None:
        self.half = half
        self.step = step
        nx, ny = (math.ceil(2 * h / step) for h in half)
        self.occupied = np.zeros((ny, nx), np.uint8)
        """Covered cells, shape (rows along y, columns along x), 1: covered."""

    def _points(self, outline: np.ndarray, offset: np.ndarray) -> np.ndarray:
        """Fixed-point cell coordinates of an outline (cell centres at integers)."""
        return np.round((outline / self.step + offset) * (1 << GRID_SHIFT)).astype(np.int32)

    def mark(self, outline: np.ndarray) -> None:
        """Cover the cells whose centres an outline (m, 2) [m] in the area's frame holds."""
        pts = self._points(outline, self.half / self.step - 0.5)
        cv2.fillPoly(self.occupied, [pts], 1, cv2.LINE_8, GRID_SHIFT)

    def contact_cells(self, outline: np.ndarray) -> np.ndarray:
        """Free cells for an outline's origin that border cells where it would not be free.

        The outline's cells are its boundary and its origin (a placed outline is far wider
        than a cell, so it cannot slip inside the boundary unseen; the exact test catches
        what the grid misses).

        Args:
            outline: The outline about its origin, at its yaw, shape (m, 2) [m].

        Returns:
            Flat indices of those cells (row-major), shape (f,).
        """
        q = outline / self.step
        lo = np.floor(q.min(axis=0)).astype(int)
        size = np.ceil(q.max(axis=0)).astype(int) - lo + 1
        kernel = np.zeros((size[1], size[0]), np.uint8)
        cv2.polylines(kernel, [self._points(outline, -lo)], True, 1, 1, cv2.LINE_8, GRID_SHIFT)
        kernel[-lo[1], -lo[0]] = 1
        anchor = (int(-lo[0]), int(-lo[1]))
        hit = cv2.dilate(
            self.occupied, kernel, anchor=anchor, borderType=cv2.BORDER_CONSTANT, borderValue=1
        )
        free = 1 - hit
        inner = cv2.erode(free, _CROSS, borderType=cv2.BORDER_CONSTANT, borderValue=0)
        return np.flatnonzero((free - inner).ravel())

    def centres(self, cells: np.ndarray) -> np.ndarray:
        """Centres of flat cell indices, shape (m, 2) [m] in the area's frame."""
        rows, cols = np.divmod(cells, self.occupied.shape[1])
        return np.stack([cols, rows], axis=1) * self.step + self.step / 2 - self.half


SURE = 1e-9
"""Margin [m] by which a bound must clear the gap to decide a pair without the exact distance
(far above rounding, so every decision equals the exact test's)."""


class _Placed:
    """Outlines placed so far in one layout, and the tests of a new one against them.

    Args:
        gap: Clearance between outlines [m].
        half: Half size of the area, shape (2,) [m].
        capacity: Most outlines the layout places.
    """

    def __init__(self, gap: float, half: np.ndarray, capacity: int) -> None:
        self.gap = gap
        self.half = half
        self.count = 0
        self.polys = np.empty(capacity, dtype=object)
        self.centre = np.zeros((capacity, 2))
        self.radius = np.zeros(capacity)
        self.inner = np.zeros(capacity)
        self.box = np.zeros((capacity, 4))

    def first_clear(self, shape: Footprint, radius: float, xy: np.ndarray, yaw: np.ndarray) -> int:
        """First candidate inside the area and ``gap`` from every placed outline; placed.

        Candidates are tested one by one in draw order. Inside: by the outline's vertices.
        Against a placed outline whose bounding circle (plus ``gap``) is near, a pair is
        decided by bounds where they are sure (inscribed circles closer than the gap: too
        close; bounding boxes farther apart: clear), else by the exact outline distance
        (GEOS).

        Args:
            shape: The tile's footprint.
            radius: Its bounding radius about its origin [m].
            xy: Candidate origins, shape (m, 2) [m].
            yaw: Candidate yaws, shape (m,) [rad].

        Returns:
            The candidate index, or ``m`` when none passes.
        """
        gap, half, k = self.gap, self.half, self.count
        centre, inners, box = self.centre[:k], self.inner[:k], self.box[:k]
        reach = self.radius[:k] + radius + gap
        close = shape.inner + inners + gap - SURE
        for j in range(len(xy)):
            c, s = math.cos(yaw[j]), math.sin(yaw[j])
            verts = shape.outline @ np.array([[c, s], [-s, c]]) + xy[j]
            lo, hi = verts.min(axis=0), verts.max(axis=0)
            if np.any(lo < -half) or np.any(hi > half):
                continue
            dist = np.hypot(centre[:, 0] - xy[j, 0], centre[:, 1] - xy[j, 1])
            near = np.flatnonzero(dist < reach)
            if len(near):
                if np.any(dist[near] < close[near]):
                    continue
                apart = np.maximum(np.maximum(lo - box[near, 2:], box[near, :2] - hi), 0.0)
                exact = near[np.hypot(apart[:, 0], apart[:, 1]) < gap + SURE]
                poly = shapely.polygons(verts)
                if len(exact) and np.any(shapely.distance(poly, self.polys[exact]) < gap):
                    continue
            else:
                poly = shapely.polygons(verts)
            self.polys[k] = poly
            self.centre[k] = xy[j]
            self.radius[k] = radius
            self.inner[k] = shape.inner
            self.box[k] = (*lo, *hi)
            self.count += 1
            return j
        return len(xy)


def _posed_all(outline: np.ndarray, xy: np.ndarray, yaw: np.ndarray) -> np.ndarray:
    """An outline at every pose: shape (n, k, 2) [m] for ``xy`` (n, 2) and ``yaw`` (n,)."""
    rot = np.empty((len(yaw), 2, 2))
    rot[:, 0, 0] = rot[:, 1, 1] = np.cos(yaw)
    rot[:, 0, 1] = np.sin(yaw)
    rot[:, 1, 0] = -rot[:, 0, 1]
    return outline[None] @ rot + xy[:, None, :]


def _min_half_extent(outline: np.ndarray) -> float:
    """Half the smallest width of an outline over rotations (it must fit some way) [m]."""
    hull = np.asarray(Polygon(outline).convex_hull.exterior.coords)[:-1]
    edges = np.roll(hull, -1, axis=0) - hull
    normals = np.stack([-edges[:, 1], edges[:, 0]], axis=1)
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    proj = hull @ normals.T
    return float(np.min(proj.max(axis=0) - proj.min(axis=0)) / 2)


__all__ = [
    "CIRCLE_FILL",
    "FREE_DRAWS",
    "GRID_STEP",
    "OUTLINE_FILL",
    "Footprint",
    "footprints",
    "layout_capacity",
    "sample_layout",
]
