"""Tile shapes, physical tiles with manufacturing noise, convex decomposition and layout.

Units: metres and radians throughout. Outlines are counter-clockwise polygons; curved outlines
arrive densely sampled. Nothing here imports MuJoCo: `envs.scene` turns `PhysicalTile` values
into bodies.
"""

from __future__ import annotations

import colorsys
import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from functools import lru_cache
from typing import Any

import numpy as np
import shapely
import shapely.ops
from shapely.geometry import Polygon, box

from envs.cell_config import TileConfig
from envs.errors import CellError

_EPS = 1e-12


def _as_polygon_array(points: object, what: str) -> np.ndarray:
    arr = np.asarray(points, dtype=float)
    if arr.ndim != 2 or arr.shape[1] != 2 or arr.shape[0] < 3:
        raise CellError(f"{what}: expected an (n, 2) array with n >= 3, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise CellError(f"{what}: contains NaN or inf")
    if np.allclose(arr[0], arr[-1]):
        arr = arr[:-1]
    return arr


def signed_area(poly: np.ndarray) -> float:
    """Signed area of a polygon, shape (n, 2) [m^2]; positive when counter-clockwise."""
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


JITTER_TRIES = 8
"""Draws of manufacturing noise tried before a tile keeps its nominal outline (noise on a very
short edge can fold the outline into a self-intersecting polygon MuJoCo cannot mesh)."""


@dataclass(frozen=True, eq=False)
class TileShape:
    """A tile's nominal geometry and colour.

    Attributes:
        outline: Outer boundary, shape (n, 2) [m], any orientation (stored counter-clockwise).
        holes: Inner boundaries, each shape (m, 2) [m] (stored clockwise).
        color: RGB in [0, 1].
        name: Class name (e.g. "square"), used to match tiles to slots.
        symmetry: Order of rotational symmetry (1: none, 4: square, 0: continuous, e.g. a
            circle or ring).
    """

    outline: np.ndarray
    holes: tuple[np.ndarray, ...] = ()
    color: tuple[float, float, float] = (0.8, 0.8, 0.8)
    name: str = "tile"
    symmetry: int = 1

    def __post_init__(self) -> None:
        outline = _as_polygon_array(self.outline, f"TileShape {self.name!r} outline")
        if signed_area(outline) < 0:
            outline = outline[::-1].copy()
        holes = []
        for k, h in enumerate(self.holes):
            hole = _as_polygon_array(h, f"TileShape {self.name!r} hole {k}")
            if signed_area(hole) > 0:
                hole = hole[::-1].copy()
            holes.append(hole)
        poly = Polygon(outline, holes)
        if not poly.is_valid or poly.area <= 0:
            raise CellError(
                f"TileShape {self.name!r}: outline/holes form an invalid polygon "
                f"({shapely.is_valid_reason(poly)}); allowed: simple polygons, holes inside"
            )
        color = tuple(float(c) for c in self.color)
        if len(color) != 3 or not all(0.0 <= c <= 1.0 for c in color):
            raise CellError(
                f"TileShape {self.name!r}: color must be 3 values in [0, 1], got {color}"
            )
        if not isinstance(self.symmetry, int | np.integer) or self.symmetry < 0:
            raise CellError(f"TileShape {self.name!r}: symmetry must be an int >= 0")
        outline.setflags(write=False)
        for h in holes:
            h.setflags(write=False)
        object.__setattr__(self, "outline", outline)
        object.__setattr__(self, "holes", tuple(holes))
        object.__setattr__(self, "color", color)

    @property
    def polygon(self) -> Polygon:
        """The shape as a shapely polygon [m]."""
        return Polygon(self.outline, self.holes)

    @property
    def area(self) -> float:
        """Area [m^2]."""
        return float(self.polygon.area)


@dataclass(frozen=True, eq=False)
class SlotSpec:
    """A slot of the mesh: which tile class goes where.

    Attributes:
        shape: The tile shape expected in the slot (outline relative to its area centroid is
            used; the shape's own origin is ignored).
        pose: (x, y, yaw) of the tile's area centroid and rotation on the mesh, relative to
            the mesh centre [m, m, rad].
        name: Optional slot name (e.g. the design's).
    """

    shape: TileShape
    pose: tuple[float, float, float]
    name: str = ""

    def __post_init__(self) -> None:
        pose = tuple(float(v) for v in self.pose)
        if len(pose) != 3 or not all(math.isfinite(v) for v in pose):
            raise CellError(f"SlotSpec pose must be 3 finite values (x, y, yaw), got {self.pose}")
        object.__setattr__(self, "pose", pose)


@dataclass(frozen=True, eq=False)
class PhysicalTile:
    """One tile as built: noisy geometry centred on its area centroid.

    Attributes:
        shape: The nominal shape it was made from.
        outline: Noisy outer boundary in the tile frame, shape (n, 2) [m].
        holes: Noisy holes in the tile frame [m].
        pieces: Convex pieces covering the tile, each shape (k, 2) [m], for collision.
        color: Noisy RGB in [0, 1] (the glaze).
        base_color: RGB in [0, 1] before the colour noise (the shape's colour, or a colour
            distractor's wrong one); `jitter_colors` re-draws ``color`` from it.
        radius: Bounding-circle radius about the tile origin [m].
        area: Area [m^2].
        grasp: Where to put the pad, in the tile frame, shape (2,) [m]: the point of the tile
            farthest from its boundary (the origin can be in a hole, e.g. a ring's).
        distractor: "" for a real tile, else the distractor kind ("color", "broken", "shape").
    """

    shape: TileShape
    outline: np.ndarray
    holes: tuple[np.ndarray, ...]
    pieces: tuple[np.ndarray, ...]
    color: tuple[float, float, float]
    base_color: tuple[float, float, float]
    radius: float
    area: float
    grasp: np.ndarray
    distractor: str = ""


def _is_convex(poly: np.ndarray, tol: float = 1e-12) -> bool:
    d1 = np.roll(poly, -1, axis=0) - poly
    d2 = np.roll(d1, -1, axis=0)
    cross = d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]
    return bool(np.all(cross >= -tol))


def _hertel_mehlhorn(points: np.ndarray, tris: list[list[int]]) -> list[list[int]]:
    """Merge counter-clockwise triangles (vertex indices) into convex polygons."""
    pieces: dict[int, list[int]] = dict(enumerate(tris))
    changed = True
    while changed:
        changed = False
        edge_owner = {}
        for pid, poly in pieces.items():
            for k in range(len(poly)):
                edge_owner[(poly[k], poly[(k + 1) % len(poly)])] = pid
        for pid in sorted(pieces):
            poly = pieces[pid]
            for k in range(len(poly)):
                a, b = poly[k], poly[(k + 1) % len(poly)]
                qid = edge_owner.get((b, a))
                if qid is None or qid == pid:
                    continue
                q = pieces[qid]
                ib = poly.index(b)
                p_rot = poly[ib:] + poly[:ib]  # starts at b, ends at a
                ia = q.index(a)
                q_rot = q[ia:] + q[:ia]  # starts at a, ends at b
                merged = p_rot + q_rot[1:-1]
                if _is_convex(points[merged]):
                    pieces[pid] = merged
                    del pieces[qid]
                    changed = True
                    break
            if changed:
                break
    return list(pieces.values())


def convex_decomposition(
    outline: np.ndarray, holes: Sequence[np.ndarray] = ()
) -> tuple[np.ndarray, tuple[list[int], ...]]:
    """Split a polygon (with holes) into convex pieces.

    Constrained Delaunay triangulation (shapely) followed by Hertel-Mehlhorn merging, so the
    pieces share the polygon's own vertices.

    Args:
        outline: Outer boundary, shape (n, 2), counter-clockwise.
        holes: Holes, each shape (m, 2).

    Returns:
        ``(points, pieces)``: all vertices, shape (n + sum m, 2), outline first then holes in
        order; and each convex piece as a counter-clockwise list of indices into ``points``.
    """
    points = np.vstack([outline, *holes]) if holes else np.asarray(outline)
    if not holes and _is_convex(points):
        return points, (list(range(len(points))),)
    index = {(round(float(x), 12), round(float(y), 12)): i for i, (x, y) in enumerate(points)}
    tris_geom = shapely.constrained_delaunay_triangles(Polygon(outline, list(holes)))
    tris: list[list[int]] = []
    for tri in tris_geom.geoms:
        coords = np.asarray(tri.exterior.coords)[:3]
        try:
            ids = [index[(round(float(x), 12), round(float(y), 12))] for x, y in coords]
        except KeyError as exc:  # pragma: no cover - shapely adds no Steiner points
            raise CellError("convex decomposition produced a vertex not in the polygon") from exc
        if signed_area(points[ids]) < 0:
            ids = ids[::-1]
        if abs(signed_area(points[ids])) > _EPS * 1e-3:
            tris.append(ids)
    return points, tuple(_hertel_mehlhorn(points, tris))


@lru_cache(maxsize=256)
def _decompose_cached(key: bytes, n_out: int, hole_sizes: tuple[int, ...]) -> tuple:
    flat = np.frombuffer(key, dtype=float).reshape(-1, 2)
    outline = flat[:n_out]
    holes, start = [], n_out
    for m in hole_sizes:
        holes.append(flat[start : start + m])
        start += m
    return convex_decomposition(outline, holes)


def _decompose(outline: np.ndarray, holes: Sequence[np.ndarray]) -> tuple:
    flat = np.vstack([outline, *holes]).astype(float)
    return _decompose_cached(flat.tobytes(), len(outline), tuple(len(h) for h in holes))


def _centre(outline: np.ndarray, holes: Sequence[np.ndarray]) -> tuple[np.ndarray, list]:
    c = Polygon(outline, list(holes)).centroid
    off = np.array([c.x, c.y])
    return outline - off, [h - off for h in holes]


def _jitter_color(
    color: tuple[float, float, float], std: float, rng: np.random.Generator
) -> tuple[float, float, float]:
    c = np.clip(np.asarray(color) + rng.normal(0.0, std, 3), 0.0, 1.0)
    return (float(c[0]), float(c[1]), float(c[2]))


def _wrong_color(color: tuple[float, float, float], rng: np.random.Generator) -> tuple:
    h, s, v = colorsys.rgb_to_hsv(*color)
    h = (h + rng.uniform(0.3, 0.7)) % 1.0
    s = max(s, 0.5)
    v = min(max(v, 0.4), 0.9)
    return colorsys.hsv_to_rgb(h, s, v)


def make_tile(
    shape: TileShape,
    cfg: TileConfig,
    rng: np.random.Generator,
    distractor: str = "",
) -> PhysicalTile:
    """Build one physical tile from a shape with manufacturing noise.

    The nominal shape is decomposed into convex pieces (cached per shape); the vertex jitter
    then moves shared vertices consistently, so pieces stay within the jitter of convex.

    Args:
        shape: Nominal shape.
        cfg: Tile configuration (jitter levels).
        rng: Random generator of the episode.
        distractor: "" for a real tile, or "color", "broken", "shape".

    Raises:
        CellError: Unknown distractor kind.
    """
    outline, holes = _centre(shape.outline, shape.holes)
    color = shape.color
    if distractor == "color":
        color = _wrong_color(color, rng)
    elif distractor == "shape":
        scale = rng.choice([0.7, 1.35])
        outline, holes = outline * scale, [h * scale for h in holes]
    elif distractor == "broken":
        poly = Polygon(outline, holes)
        ang = rng.uniform(0, 2 * np.pi)
        d = np.array([np.cos(ang), np.sin(ang)])
        proj = outline @ d
        cut = proj.max() - 0.3 * (proj.max() - proj.min())
        big = 10.0 * float(np.max(np.abs(outline))) + 1.0
        half = shapely.affinity.rotate(
            box(cut, -big, cut + big, big), float(np.degrees(ang)), origin=(0, 0)
        )
        part = poly.difference(half)
        if part.geom_type == "MultiPolygon":
            part = max(part.geoms, key=lambda g: g.area)
        part = shapely.simplify(part, 1e-6)
        outline = np.asarray(part.exterior.coords)[:-1]
        holes = [np.asarray(r.coords)[:-1] for r in part.interiors]
        if signed_area(outline) < 0:
            outline = outline[::-1]
        holes = [h[::-1] if signed_area(h) > 0 else h for h in holes]
        outline, holes = _centre(outline, holes)
    elif distractor != "":
        raise CellError(f"unknown distractor kind {distractor!r}; allowed: color, broken, shape")
    points, piece_ids = _decompose(outline, holes)
    n_out = len(outline)
    for _ in range(JITTER_TRIES):
        noisy = points + rng.normal(0.0, cfg.vertex_jitter, points.shape)
        n_outline = noisy[:n_out]
        n_holes, start = [], n_out
        for h in holes:
            n_holes.append(noisy[start : start + len(h)])
            start += len(h)
        if Polygon(n_outline, n_holes).is_valid:
            break
    else:  # jitter keeps folding a short edge (e.g. at a break line): keep the nominal outline
        noisy = points.astype(float)
        n_outline, n_holes = outline, list(holes)
    off = np.array(Polygon(n_outline, n_holes).centroid.coords[0])
    noisy = noisy - off
    n_outline = noisy[:n_out]
    n_holes, start = [], n_out
    for h in holes:
        n_holes.append(noisy[start : start + len(h)])
        start += len(h)
    pieces = tuple(noisy[ids] for ids in piece_ids)
    return PhysicalTile(
        shape=shape,
        outline=n_outline,
        holes=tuple(n_holes),
        pieces=pieces,
        color=_jitter_color(color, cfg.color_jitter, rng),
        base_color=(float(color[0]), float(color[1]), float(color[2])),
        radius=float(np.max(np.linalg.norm(n_outline, axis=1))),
        area=float(Polygon(n_outline, n_holes).area),
        grasp=grasp_point(n_outline, n_holes),
        distractor=distractor,
    )


def make_tiles(
    shapes: Sequence[TileShape], cfg: TileConfig, rng: np.random.Generator
) -> tuple[PhysicalTile, ...]:
    """Physical tiles for a list of shapes plus distractors at ``cfg.distractor_rate``.

    Distractors are appended after the real tiles; each real tile adds one with probability
    ``distractor_rate`` (kind drawn uniformly from ``cfg.distractor_kinds``).

    Raises:
        CellError: No shapes.
    """
    if len(shapes) == 0:
        raise CellError("no tile shapes given; allowed: one or more TileShape values")
    tiles = [make_tile(s, cfg, rng) for s in shapes]
    for s in shapes:
        if rng.random() < cfg.distractor_rate:
            kind = str(rng.choice(list(cfg.distractor_kinds)))
            tiles.append(make_tile(s, cfg, rng, kind))
    return tuple(tiles)


def make_tile_pool(
    shapes: Sequence[TileShape], cfg: TileConfig, rng: np.random.Generator
) -> tuple[tuple[PhysicalTile, ...], ...]:
    """``cfg.variants`` independently noisy copies of the tiles `make_tiles` draws.

    Variant 0 is exactly `make_tiles`'s draw (same generator calls); variants 1.. re-draw the
    outline and colour noise (and a distractor's random cut, scale or wrong colour) of each
    tile, keeping its shape and distractor kind.

    Returns:
        Tiles indexed ``[variant][tile]``: ``cfg.variants`` tuples of the same length.

    Raises:
        CellError: No shapes.
    """
    first = make_tiles(shapes, cfg, rng)
    others = tuple(
        tuple(make_tile(t.shape, cfg, rng, t.distractor) for t in first)
        for _ in range(cfg.variants - 1)
    )
    return (first, *others)


def jitter_colors(
    tiles: Sequence[PhysicalTile], std: float, rng: np.random.Generator
) -> tuple[PhysicalTile, ...]:
    """The tiles with freshly drawn glaze colour noise (std per RGB channel) on `base_color`."""
    base = np.array([t.base_color for t in tiles], dtype=float).reshape(-1, 3)
    colors = np.clip(base + rng.normal(0.0, std, base.shape), 0.0, 1.0)
    return tuple(
        replace(t, color=(float(c[0]), float(c[1]), float(c[2])))
        for t, c in zip(tiles, colors, strict=True)
    )


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

    def once() -> np.ndarray:
        return _layout_once(
            radii,
            half,
            gap,
            attempts,
            rng,
            outlines=outlines,
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
    outlines: Sequence[np.ndarray] | None,
    occupied: np.ndarray | None,
    occupied_radii: np.ndarray | None,
) -> np.ndarray:
    """One try of `sample_layout` (same arguments); raises CellError when it jams."""
    area_size = 2 * half
    centres = np.zeros((0, 2)) if occupied is None else np.asarray(occupied, float)
    rads = np.zeros(0) if occupied_radii is None else np.asarray(occupied_radii, float)
    n_fixed = len(centres)
    placed: list[Polygon] = []
    out = np.zeros((len(radii), 3))
    for i in np.argsort(-radii):
        lim = half - radii[i]
        lim = np.where(lim > 0, lim, 0.0)
        cand = rng.uniform(-lim, lim, size=(attempts, 2))
        yaws = rng.uniform(-np.pi, np.pi, attempts)
        if len(centres):
            d = np.linalg.norm(cand[:, None, :] - centres[None, :, :], axis=2)
            clear = d >= rads[None, :] + radii[i] + gap
        else:
            clear = np.ones((attempts, 0), bool)
        chosen = -1
        for c in range(attempts):
            poly = None
            if outlines is not None:
                poly = _posed(outlines[i], cand[c], yaws[c])
                if not _inside(poly, half):
                    continue
            if clear[c].all():
                chosen = c
            elif outlines is not None and not clear[c, :n_fixed].all():
                continue
            elif outlines is not None:
                near = [placed[k - n_fixed] for k in np.flatnonzero(~clear[c])]
                if np.all(shapely.distance(poly, near) >= gap):
                    chosen = c
            if chosen >= 0:
                if poly is not None:
                    placed.append(poly)
                break
        if chosen < 0:
            raise CellError(
                f"could not place {len(radii)} tiles without overlap in the tile area "
                f"{area_size[0] * 1000:.0f} x {area_size[1] * 1000:.0f} mm after {attempts} "
                "tries per tile; use fewer tiles, a larger area or feed='stream'"
            )
        out[i] = (cand[chosen, 0], cand[chosen, 1], yaws[chosen])
        centres = np.vstack([centres, cand[chosen]])
        rads = np.append(rads, radii[i])
    return out


def _posed(outline: np.ndarray, xy: np.ndarray, yaw: float) -> Polygon:
    c, s = np.cos(yaw), np.sin(yaw)
    return Polygon(outline @ np.array([[c, s], [-s, c]]) + xy)


def _inside(poly: Polygon, half: np.ndarray) -> bool:
    x0, y0, x1, y1 = poly.bounds
    return bool(x0 >= -half[0] and x1 <= half[0] and y0 >= -half[1] and y1 <= half[1])


def _min_half_extent(outline: np.ndarray) -> float:
    """Half the smallest width of an outline over rotations (it must fit some way) [m]."""
    hull = np.asarray(Polygon(outline).convex_hull.exterior.coords)[:-1]
    edges = np.roll(hull, -1, axis=0) - hull
    normals = np.stack([-edges[:, 1], edges[:, 0]], axis=1)
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    proj = hull @ normals.T
    return float(np.min(proj.max(axis=0) - proj.min(axis=0)) / 2)


def grasp_point(outline: np.ndarray, holes: Sequence[np.ndarray] = ()) -> np.ndarray:
    """Point of a polygon farthest from its boundary (pole of inaccessibility), shape (2,) [m].

    The origin is returned when it is already within 1 mm of the best clearance, so symmetric
    tiles are picked at their centroid.
    """
    poly = Polygon(outline, list(holes))
    best = shapely.ops.polylabel(poly, tolerance=1e-4)
    origin = shapely.Point(0.0, 0.0)
    d_best = poly.exterior.distance(best) if not holes else poly.boundary.distance(best)
    if poly.contains(origin) and poly.boundary.distance(origin) >= d_best - 1e-3:
        return np.zeros(2)
    return np.array([best.x, best.y])


def _loop_points(loop: Any, arc_step_mm: float) -> np.ndarray:
    """Vertices of a `qshape.design.Loop`: straight edges kept, arcs sampled [mm]."""
    n = len(loop.vertices)
    lengths = loop.edge_lengths()
    counts = np.where(loop.bulges == 0.0, 1, np.maximum(2, np.ceil(lengths / arc_step_mm)))
    counts = counts.astype(int)
    edge = np.repeat(np.arange(n), counts)
    starts = np.cumsum(counts) - counts
    t = (np.arange(counts.sum()) - np.repeat(starts, counts)) / np.repeat(counts, counts)
    return np.asarray(loop.edge_points(t.astype(float), edge))


def tile_shapes_from_design(
    design: Any, arc_step_mm: float = 2.0
) -> tuple[tuple[TileShape, ...], tuple[SlotSpec, ...]]:
    """Tile shapes and slots of a `qshape.design.Design` (mm, mesh origin at a corner).

    One tile per slot. Shapes are named by the slot's shape-and-colour class
    (``Slot.class_key``), so tiles and slots of a class share a name. Slot poses are moved to
    the mesh centre and converted to metres and radians.

    Args:
        design: A loaded design (``Design.load("paper_mixed")``).
        arc_step_mm: Largest distance between samples along arcs [mm] (straight edges keep
            only their vertices).

    Returns:
        ``(shapes, slots)``, in the design's slot order.
    """
    if not arc_step_mm > 0:
        raise CellError(f"arc_step_mm must be positive, got {arc_step_mm}")
    mm = 1e-3
    width, height = design.mesh_size
    shapes, slots = [], []
    for slot in design.slots:
        path = slot.local_path
        shape = TileShape(
            _loop_points(path.outer, arc_step_mm) * mm,
            holes=tuple(_loop_points(h, arc_step_mm) * mm for h in path.holes),
            color=tuple(slot.color),
            name=slot.class_key,
            symmetry=int(slot.symmetry),
        )
        pose = ((slot.x - width / 2) * mm, (slot.y - height / 2) * mm, math.radians(slot.angle))
        shapes.append(shape)
        slots.append(SlotSpec(shape, pose, slot.name))
    return tuple(shapes), tuple(slots)


def _circle(r: float, n: int, start: float = 0.0, stop: float = 2 * np.pi) -> np.ndarray:
    t = np.linspace(start, stop, n, endpoint=False)
    return np.stack([r * np.cos(t), r * np.sin(t)], axis=1)


@dataclass(frozen=True)
class BasicShapes:
    """Sizes of the built-in test shapes [m]."""

    size: float = 0.02
    samples: int = 32
    colors: dict[str, tuple[float, float, float]] = field(
        default_factory=lambda: {
            "square": (0.85, 0.15, 0.12),
            "rectangle": (0.15, 0.45, 0.85),
            "triangle": (0.95, 0.8, 0.1),
            "l_shape": (0.2, 0.7, 0.3),
            "circle": (0.95, 0.5, 0.1),
            "semicircle": (0.6, 0.25, 0.7),
            "ring": (0.1, 0.75, 0.8),
        }
    )


def basic_shapes(spec: BasicShapes | None = None) -> tuple[TileShape, ...]:
    """Square, rectangle, right triangle, L (concave), circle, semicircle, ring (with a hole).

    Args:
        spec: Sizes and colours; default 20 mm tiles.
    """
    spec = spec or BasicShapes()
    s, n, c = spec.size, spec.samples, spec.colors
    sq = np.array([[0, 0], [s, 0], [s, s], [0, s]])
    return (
        TileShape(sq, color=c["square"], name="square", symmetry=4),
        TileShape(sq * [2, 1], color=c["rectangle"], name="rectangle", symmetry=2),
        TileShape(np.array([[0, 0], [s, 0], [0, s]]), color=c["triangle"], name="triangle"),
        TileShape(
            np.array(
                [[0, 0], [2 * s, 0], [2 * s, s / 2], [s / 2, s / 2], [s / 2, 2 * s], [0, 2 * s]]
            )
            * 0.75,
            color=c["l_shape"],
            name="l_shape",
        ),
        TileShape(_circle(s / 2, n), color=c["circle"], name="circle", symmetry=0),
        TileShape(
            np.vstack([_circle(s / 2, n // 2 + 1, 0.0, np.pi * (1 + 2 / n))[: n // 2 + 1]]),
            color=c["semicircle"],
            name="semicircle",
        ),
        TileShape(
            _circle(s * 0.6, n),
            holes=(_circle(s * 0.25, n // 2)[::-1],),
            color=c["ring"],
            name="ring",
            symmetry=0,
        ),
    )


__all__ = [
    "CIRCLE_FILL",
    "OUTLINE_FILL",
    "BasicShapes",
    "PhysicalTile",
    "SlotSpec",
    "TileShape",
    "basic_shapes",
    "convex_decomposition",
    "grasp_point",
    "jitter_colors",
    "layout_capacity",
    "make_tile",
    "make_tile_pool",
    "make_tiles",
    "sample_layout",
    "signed_area",
    "tile_shapes_from_design",
]
