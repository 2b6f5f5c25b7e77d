"""Tiles: shapes, slots, and physical tiles made with manufacturing noise.

Units: metres and radians throughout. Outlines are counter-clockwise polygons; curved outlines
arrive densely sampled. Nothing here imports MuJoCo: `envs.cell.scene` turns `PhysicalTile` values
into bodies (convex pieces from `envs.cell.tiles.decompose`); layouts on the belt are
`envs.cell.layout`'s,
shapes from designs and the built-in test shapes `envs.cell.tiles.shapes`'.
"""

from __future__ import annotations

import colorsys
import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
import shapely
import shapely.ops
from shapely.geometry import Polygon, box

from envs.cell.config import TileConfig
from envs.cell.tiles.decompose import decompose
from envs.errors import CellError
from qshape.geometry import signed_area


def _as_polygon_array(points: object, what: str) -> np.ndarray:
    arr = np.asarray(points, dtype=float)
    if arr.ndim != 2 or arr.shape[1] != 2 or arr.shape[0] < 3:
        raise CellError(f"{what}: expected an (n, 2) array with n >= 3, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise CellError(f"{what}: contains NaN or inf")
    if np.allclose(arr[0], arr[-1]):
        arr = arr[:-1]
    return arr


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


def _broken(
    outline: np.ndarray, holes: list[np.ndarray], rng: np.random.Generator
) -> tuple[np.ndarray, list[np.ndarray]]:
    """A tile with a random side broken off (the outline and holes of the larger part, centred).

    A straight cut at a random angle removes 30 % of the tile's extent along it.
    """
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
    return _centre(outline, holes)


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
        outline, holes = _broken(outline, holes, rng)
    elif distractor != "":
        raise CellError(f"unknown distractor kind {distractor!r}; allowed: color, broken, shape")
    points, piece_ids = decompose(outline, holes)
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


@dataclass(frozen=True, eq=False)
class TilePoses:
    """Tile poses at one instant (copies).

    Attributes:
        pos: Positions of the tiles' area centroids at mid-thickness, shape (n, 3) [m].
        quat: Orientations (w, x, y, z), shape (n, 4).
        yaw: Rotation about world z, shape (n,) [rad] (meaningful for tiles lying flat).
    """

    pos: np.ndarray
    quat: np.ndarray
    yaw: np.ndarray


__all__ = [
    "TilePoses",
    "PhysicalTile",
    "SlotSpec",
    "TileShape",
    "grasp_point",
    "jitter_colors",
    "make_tile",
    "make_tile_pool",
    "make_tiles",
]
