"""Random non-overlapping layouts of tiles on the input belt's tile area.

Poses are (x, y, yaw) relative to the tile area's centre [m, m, rad]; tiles are kept apart by a
minimum gap between their outlines (or bounding circles).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import shapely
import shapely.ops
from shapely.geometry import Polygon

from envs.errors import CellError, LayoutError

OUTLINE_FILL = 0.5
"""Largest fraction of a tile area random placement of outlines is asked to fill."""


CIRCLE_FILL = 0.8
"""The same for bounding circles (no outlines given)."""


def layout_capacity(outlines: Sequence[np.ndarray], area_size: Sequence[float], gap: float) -> int:
    """How many of ``outlines``, taken in order, `sample_layout` can be asked to lay out.

    Args:
        outlines: Tile outlines in their own frames, each shape (k, 2) [m].
        area_size: (x, y) size of the rectangle [m].
        gap: Minimum clearance between tiles [m].

    Returns:
        The longest prefix whose area (each outline grown by ``gap / 2``) is within
        `OUTLINE_FILL` of the rectangle's.
    """
    need = np.cumsum([Polygon(o).buffer(gap / 2).area for o in outlines])
    return int(np.searchsorted(need, OUTLINE_FILL * area_size[0] * area_size[1], side="right"))


def sample_layout(
    radii: np.ndarray,
    area_size: tuple[float, ...],
    gap: float,
    attempts: int,
    rng: np.random.Generator,
    *,
    outlines: Sequence[np.ndarray] | None = None,
    occupied: np.ndarray | None = None,
    occupied_radii: np.ndarray | None = None,
    restarts: int = 1,
) -> np.ndarray:
    """Random non-overlapping poses for tiles in a rectangle.

    Tiles are placed largest first at uniform random positions and yaws. Two tiles whose
    bounding circles (plus ``gap``) do not overlap are accepted at once; with ``outlines``
    given, closer pairs are accepted when the actual outlines keep ``gap`` apart.

    Args:
        radii: Bounding radii about each tile's origin, shape (n,) [m].
        area_size: (length, width) of the rectangle centred at the origin [m].
        gap: Clearance between tiles [m].
        attempts: Tries per tile before giving up.
        rng: Random generator.
        outlines: Optional outline per tile in its own frame, each shape (k, 2) [m] (exact
            test, denser packing).
        occupied: Centres of circles already there, shape (k, 2) [m], optional.
        occupied_radii: Their radii, shape (k,) [m].
        restarts: Whole layouts tried before giving up (random sequential placement can jam
            near 50 % fill even when a layout exists; a fresh draw usually succeeds).

    Returns:
        Poses (x, y, yaw), shape (n, 3), in the rectangle's frame [m, m, rad].

    Raises:
        CellError: A tile does not fit (too large, or the area is too full).
    """
    radii = np.asarray(radii, dtype=float)
    half = np.asarray(area_size, dtype=float) / 2
    if outlines is not None:
        extent = np.array([_min_half_extent(o) for o in outlines])
    else:
        extent = radii
    if np.any(extent + gap / 2 > half.min()):
        k = int(np.argmax(extent))
        raise CellError(
            f"tile {k} (size {2 * extent[k] * 1000:.1f} mm) does not fit the tile area "
            f"{area_size[0] * 1000:.0f} x {area_size[1] * 1000:.0f} mm"
        )
    if outlines is not None:
        need = float(sum(Polygon(o).buffer(gap / 2).area for o in outlines))
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

    shapes = None if outlines is None else [_Footprint.of(o) for o in outlines]

    def once() -> np.ndarray:
        return _layout_once(
            radii,
            half,
            gap,
            attempts,
            rng,
            shapes=shapes,
            occupied=occupied,
            occupied_radii=occupied_radii,
        )

    for _ in range(max(restarts, 1) - 1):
        try:
            return once()
        except CellError:
            continue
    return once()


def _layout_once(
    radii: np.ndarray,
    half: np.ndarray,
    gap: float,
    attempts: int,
    rng: np.random.Generator,
    *,
    shapes: Sequence[_Footprint] | None,
    occupied: np.ndarray | None,
    occupied_radii: np.ndarray | None,
) -> np.ndarray:
    """One try of `sample_layout` (outlines as ``shapes``); raises CellError when it jams.

    Each tile draws all its candidate poses at once and takes the first acceptable one in
    draw order. The cheap tests (bounding circles clear) run on every candidate at once; the
    outline tests (inside the area, clearance) only on the candidates before the first one
    that passes them all (`_Placed.first_clear`).
    """
    area_size = 2 * half
    centres = np.zeros((0, 2)) if occupied is None else np.asarray(occupied, float)
    rads = np.zeros(0) if occupied_radii is None else np.asarray(occupied_radii, float)
    n_fixed = len(centres)
    placed = _Placed(gap, half)
    out = np.zeros((len(radii), 3))
    for i in np.argsort(-radii):
        lim = half - radii[i]
        lim = np.where(lim > 0, lim, 0.0)
        cand = rng.uniform(-lim, lim, size=(attempts, 2))
        yaws = rng.uniform(-np.pi, np.pi, attempts)
        d = np.linalg.norm(cand[:, None, :] - centres[None, :, :], axis=2)
        clear = d >= rads[None, :] + radii[i] + gap
        if shapes is None:
            ok = clear.all(axis=1)
            first = int(np.argmax(ok)) if ok.any() else attempts
        else:
            ok = clear[:, :n_fixed].all(axis=1)
            if placed.inner:  # inscribed circles closer than the gap: sure overlaps
                reach = shapes[i].inner + np.array(placed.inner) + gap - SURE
                ok &= ~np.any(d[:, n_fixed:] < reach[None, :], axis=1)
            first = placed.first_clear(
                np.flatnonzero(ok), shapes[i], cand, yaws, clear[:, n_fixed:]
            )
        if first >= attempts:
            raise LayoutError(
                f"could not place {len(radii)} tiles without overlap in the tile area "
                f"{area_size[0] * 1000:.0f} x {area_size[1] * 1000:.0f} mm after {attempts} "
                "tries per tile; use fewer tiles, a larger area or feed='stream'"
            )
        out[i] = (cand[first, 0], cand[first, 1], yaws[first])
        centres = np.concatenate([centres, cand[first : first + 1]])
        rads = np.append(rads, radii[i])
    return out


EXACT_CHUNKS = (8, 32, 128)
"""Candidates per clearance batch, growing (then all the rest): few when an early one passes,
few calls when many fail."""
SURE = 1e-9
"""Margin [m] by which a bound must clear the gap to decide a pair without the exact distance
(far above rounding, so every decision equals the exact test's)."""


@dataclass(frozen=True)
class _Footprint:
    """A tile outline and the bounds the clearance tests use.

    Attributes:
        outline: Outline in the tile's own frame, shape (k, 2) [m].
        reach: Largest vertex distance from the frame's origin [m].
        inner: Radius of the largest circle about the origin inside the outline (0 when the
            origin is outside) [m].
    """

    outline: np.ndarray
    reach: float
    inner: float

    @staticmethod
    def of(outline: np.ndarray) -> _Footprint:
        """Footprint of an outline, shape (k, 2) [m]."""
        o = np.asarray(outline, float)
        poly, origin = Polygon(o), shapely.Point(0.0, 0.0)
        inner = float(poly.exterior.distance(origin)) if poly.contains(origin) else 0.0
        return _Footprint(o, float(np.max(np.linalg.norm(o, axis=1))), inner)


class _Placed:
    """Outlines placed so far in one layout, and the tests of a new one against them.

    Args:
        gap: Clearance between outlines [m].
        half: Half size of the area, shape (2,) [m].
    """

    def __init__(self, gap: float, half: np.ndarray) -> None:
        self.gap = gap
        self.half = half
        self.polys: list[Polygon] = []
        self.centre: list[np.ndarray] = []
        self.inner: list[float] = []
        self.box: list[np.ndarray] = []

    def first_clear(
        self,
        todo: np.ndarray,
        shape: _Footprint,
        xy: np.ndarray,
        yaw: np.ndarray,
        clear: np.ndarray,
    ) -> int:
        """First candidate of ``todo`` inside the area and ``gap`` from every placed outline.

        Taken in draw order, in chunks of growing size (`EXACT_CHUNKS`). Inside: sure when the
        outline's bounding circle is, else by its vertices. Against a placed outline whose
        bounding circle is near, a pair is decided by bounds where they are sure (inscribed
        circles closer than the gap: too close; bounding boxes farther apart: clear), else by
        the exact outline distance (GEOS). The chosen outline is placed.

        Args:
            todo: Candidate indices in draw order, shape (m,).
            shape: The tile's footprint.
            xy: Candidate origins, shape (attempts, 2) [m].
            yaw: Candidate yaws, shape (attempts,) [rad].
            clear: Bounding circles clear of each placed outline, shape (attempts, placed).

        Returns:
            The candidate index, or ``attempts`` when none passes.
        """
        gap, half, n = self.gap, self.half, len(xy)
        inner = shape.inner
        centre, inners, box = np.array(self.centre), np.array(self.inner), np.array(self.box)
        others = np.empty(len(self.polys), dtype=object)
        others[:] = self.polys
        start = 0
        for size in (*EXACT_CHUNKS, len(todo)):
            chunk = todo[start : start + size]
            start += len(chunk)
            if len(chunk) == 0:
                break
            verts = _posed_all(shape.outline, xy[chunk], yaw[chunk])
            lo_all, hi_all = _boxes(verts)
            bad = np.any(np.abs(xy[chunk]) > half - shape.reach - SURE, axis=1)
            bad[bad] = np.any((lo_all[bad] < -half) | (hi_all[bad] > half), axis=1)
            rows, cols = np.nonzero(~clear[chunk])
            if len(rows):
                dist = np.linalg.norm(xy[chunk[rows]] - centre[cols], axis=1)
                near = dist < inner + inners[cols] + gap - SURE
                lo, hi = lo_all[rows], hi_all[rows]
                apart = np.maximum(np.maximum(lo - box[cols, 2:], box[cols, :2] - hi), 0.0)
                far = np.hypot(apart[:, 0], apart[:, 1]) >= gap + SURE
                bad[rows[near]] = True
                exact = np.flatnonzero(~near & ~far & ~bad[rows])
                if len(exact):
                    polys = shapely.polygons(verts[rows[exact]])
                    close = shapely.distance(polys, others[cols[exact]]) < gap
                    bad[rows[exact[close]]] = True
            if not bad.all():
                k = int(np.argmin(bad))
                self.polys.append(Polygon(verts[k]))
                self.centre.append(xy[chunk[k]])
                self.inner.append(inner)
                self.box.append(np.concatenate([lo_all[k], hi_all[k]]))
                return int(chunk[k])
        return n


def _boxes(verts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Bounding boxes of outlines (m, k, 2): lower and upper corners, each (m, 2) [m]."""
    x, y = verts[:, :, 0], verts[:, :, 1]
    lo = np.stack([x.min(axis=1), y.min(axis=1)], axis=1)
    hi = np.stack([x.max(axis=1), y.max(axis=1)], axis=1)
    return lo, hi


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
    "OUTLINE_FILL",
    "layout_capacity",
    "sample_layout",
]
