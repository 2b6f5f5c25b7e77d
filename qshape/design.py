"""Mosaic designs: the mesh, the joint and the slots (shape, colour, pose) a cell assembles.

A design lives in a YAML file (format in ``configs/designs/README.md``), is validated strictly on
load (unknown keys, bad sizes, unknown shape kinds, degenerate or self-crossing outlines,
overlapping slots, slots outside the mesh) and gives each slot as a `qshape.Figure` in mesh
millimetres (x right, y up, origin at the mesh's lower-left corner).

Every slot shape compiles to a `TilePath`: closed boundaries made of vertices joined by straight
edges or circular arcs (DXF-style *bulges*), which gives the dense outline, the relevant points
(vertices plus the middle, maximum-curvature point of each arc), the rotational symmetry and
the jittered copies the synthetic-image generator needs.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from functools import cached_property
from pathlib import Path
from typing import Any, TypeVar

import numpy as np
import yaml
from numpy.typing import ArrayLike
from scipy.spatial import cKDTree

from configs import CONFIG_DIR, ConfigError, from_dict, load_yaml, resolve_path
from qshape import geometry as geo
from qshape.errors import InvalidFigureError, QShapeError
from qshape.figure import Boundary, Figure
from qshape.geometry import BoolArray, FloatArray

DESIGN_SUBDIR = "designs"
"""Sub-folder of ``configs/`` holding the bundled designs."""


class DesignError(QShapeError):
    """A design file or design value is malformed; the message names the slot and the problem."""


# --------------------------------------------------------------------------------- parameters
@dataclass(frozen=True)
class DesignRules:
    """How outlines are sampled and designs validated.

    Attributes:
        outline_step_mm: Largest distance between consecutive samples of a dense outline, in
            [mm] (straight edges and arcs alike).
        max_arc_deg: Arcs turning more than this are split into equal arcs, each with its own
            maximum-curvature point, in [deg]. 240 keeps (noisy) semicircles whole and splits
            circles given as one arc (the rule of ``OutlineParams.max_curve_turn_deg``).
        check_step_mm: Outline sampling used for the self-crossing, gap and mesh checks, in
            [mm] (vertices are always samples, so straight edges are exact).
        min_gap_fraction: Two slots closer than this fraction of the joint width overlap
            (dimensionless; 0.5 accepts joints narrowed by rounding in a design image).
        mesh_margin_mm: Slots must stay at least this far inside the mesh outline, in [mm]
            (negative values let tiles overhang).
        symmetry_tolerance: A rotation is a symmetry when every rotated outline sample lies
            within this fraction of sqrt(area) of the outline (dimensionless).
        max_symmetry_order: Largest finite rotational symmetry order looked for.
        symmetry_samples: Outline samples used for the symmetry test.
    """

    outline_step_mm: float = 0.25
    max_arc_deg: float = 240.0
    check_step_mm: float = 1.0
    min_gap_fraction: float = 0.5
    mesh_margin_mm: float = 0.0
    symmetry_tolerance: float = 0.01
    max_symmetry_order: int = 12
    symmetry_samples: int = 512

    def __post_init__(self) -> None:
        """Raise `DesignError` on out-of-range values."""
        if not (self.outline_step_mm > 0.0 and self.check_step_mm > 0.0):
            raise DesignError("outline_step_mm and check_step_mm must be > 0")
        if not 90.0 <= self.max_arc_deg < 360.0:
            raise DesignError(f"max_arc_deg must be in [90, 360), got {self.max_arc_deg}")
        if not 0.0 <= self.min_gap_fraction <= 1.0:
            raise DesignError(f"min_gap_fraction must be in [0, 1], got {self.min_gap_fraction}")
        if not self.symmetry_tolerance > 0.0:
            raise DesignError("symmetry_tolerance must be > 0")
        if self.max_symmetry_order < 1 or self.symmetry_samples < 16:
            raise DesignError("max_symmetry_order must be >= 1 and symmetry_samples >= 16")

    @classmethod
    def load(cls, name_or_path: str | Path | None = None, **overrides: Any) -> DesignRules:
        """Load the ``design`` section of ``configs/vision.yaml`` (or another file).

        Raises:
            configs.ConfigError: Unknown key or wrong type.
        """
        return load_section(cls, "design", name_or_path, overrides)


_Section = TypeVar("_Section")


def load_section(
    cls: type[_Section],
    section: str,
    name_or_path: str | Path | None,
    overrides: Mapping[str, Any],
) -> _Section:
    """Load one section of a vision YAML file (None: ``configs/vision.yaml``) strictly into cls.

    Raises:
        configs.ConfigError: Unknown key, wrong type, or the section is not a mapping.
    """
    name = "vision" if name_or_path is None else name_or_path
    data = load_yaml(name)
    source = str(resolve_path(name))
    body = data.get(section, {})
    if not isinstance(body, dict):
        raise ConfigError(f"{source}: {section!r} must be a mapping")
    return from_dict(cls, {**body, **overrides}, source=f"{source}:{section}")


# ------------------------------------------------------------------------------ path geometry
def _rot(angle: float) -> FloatArray:
    """Row-vector rotation matrix: points times it turn CCW by ``angle`` rad (y-up)."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, s], [-s, c]])


@dataclass(frozen=True, eq=False)
class Loop:
    """One closed boundary of straight edges and circular arcs, counter-clockwise (y-up).

    Attributes:
        vertices: Shape (n, 2), in [mm] (or any unit), counter-clockwise.
        bulges: Shape (n,): edge i runs from vertex i to vertex i+1; bulge = tan(turn / 4) of its
            arc (0 straight, 1 semicircle), positive bowing out of the tile, negative into it.
    """

    vertices: FloatArray
    bulges: FloatArray

    @classmethod
    def make(cls, vertices: ArrayLike, bulges: ArrayLike | None = None) -> Loop:
        """Normalise to counter-clockwise (reversing edges keeps each bulge's meaning).

        Raises:
            DesignError: Fewer than 3 vertices (2 when an edge is an arc), non-finite values.
        """
        v = np.asarray(vertices, dtype=np.float64).reshape(-1, 2)
        b = np.zeros(len(v)) if bulges is None else np.asarray(bulges, dtype=np.float64)
        if b.shape != (len(v),):
            raise DesignError(f"need one bulge per vertex, got {b.shape} for {len(v)} vertices")
        if not (np.all(np.isfinite(v)) and np.all(np.isfinite(b))):
            raise DesignError("vertices and bulges must be finite numbers")
        if len(v) < (2 if np.any(b != 0.0) else 3):
            raise DesignError(f"a closed outline needs at least 3 vertices, got {len(v)}")
        edges = np.roll(v, -1, axis=0) - v
        if np.any(np.hypot(edges[:, 0], edges[:, 1]) <= 0.0):
            raise DesignError("repeated consecutive vertex (zero-length edge)")
        loop = cls(v, b)
        poly_area = geo.signed_area(v) if len(v) >= 3 else 0.0
        if (poly_area if poly_area != 0.0 else loop.signed_area()) < 0.0:
            # Edge i (v_i -> v_i+1) becomes edge (v_i+1 -> v_i); bulge sign is orientation-free.
            loop = cls(v[::-1].copy(), np.roll(b[::-1], -1).copy())
        return loop

    def transformed(
        self, angle: float = 0.0, shift: ArrayLike = (0.0, 0.0), scale: float = 1.0
    ) -> Loop:
        """Rotated by ``angle`` rad CCW about the origin, scaled, then shifted."""
        v = (self.vertices @ _rot(angle)) * scale + np.asarray(shift, dtype=np.float64)
        return Loop(v, self.bulges.copy())

    def _arcs(self) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """Per edge: (start (n,2), end (n,2), outward unit normal (n,2), chord length (n,))."""
        p0 = self.vertices
        p1 = np.roll(p0, -1, axis=0)
        d = p1 - p0
        c = np.hypot(d[:, 0], d[:, 1])
        normal = np.stack([d[:, 1], -d[:, 0]], axis=1) / c[:, None]
        return p0, p1, normal, c

    def edge_points(self, t: FloatArray, edge: np.ndarray) -> FloatArray:
        """Points at fraction t in [0, 1] along edges ``edge`` (arcs followed), shape (m, 2)."""
        p0, p1, normal, c = self._arcs()
        b = self.bulges[edge]
        a, q0, q1, nrm, ch = t, p0[edge], p1[edge], normal[edge], c[edge]
        straight = q0 + (q1 - q0) * a[:, None]
        theta = 4.0 * np.arctan(b)  # signed included angle
        safe = np.where(b == 0.0, 1.0, b)
        radius = ch / (2.0 * np.sin(np.abs(theta) / 2.0 + (b == 0.0)))
        sag = np.abs(safe) * ch / 2.0
        mid = 0.5 * (q0 + q1)
        sign = np.sign(safe)
        centre = mid + nrm * (sign * (sag - radius))[:, None]
        v0 = q0 - centre
        phi = theta * a  # outward (positive) arcs of a CCW loop turn CCW about their centre
        cs, sn = np.cos(phi), np.sin(phi)
        arc = centre + np.stack(
            [v0[:, 0] * cs - v0[:, 1] * sn, v0[:, 0] * sn + v0[:, 1] * cs], axis=1
        )
        out: FloatArray = np.where((b == 0.0)[:, None], straight, arc)
        return out

    def edge_lengths(self) -> FloatArray:
        """Length of each edge (arc length for arcs), shape (n,)."""
        _, _, _, c = self._arcs()
        theta = np.abs(4.0 * np.arctan(self.bulges))
        with np.errstate(invalid="ignore", divide="ignore"):
            arc = np.where(theta > 0.0, c * (theta / 2.0) / np.sin(theta / 2.0 + (theta == 0)), c)
        return np.where(theta > 0.0, arc, c)

    def dense(self, step: float) -> FloatArray:
        """Closed outline sampled at most ``step`` apart, starting at vertex 0, shape (m, 2)."""
        counts = np.maximum(1, np.ceil(self.edge_lengths() / step).astype(int))
        edge = np.repeat(np.arange(len(self.vertices)), counts)
        starts = np.cumsum(counts) - counts
        t = (np.arange(counts.sum()) - np.repeat(starts, counts)) / np.repeat(counts, counts)
        return self.edge_points(t.astype(np.float64), edge)

    def relevant(self, max_arc_deg: float) -> tuple[FloatArray, BoolArray]:
        """Relevant points (vertices, arc middles, splits of long arcs) and their curve mask.

        Returns:
            (points (k, 2) counter-clockwise, curve_mask (k,) True at arc middles).
        """
        turn = np.degrees(np.abs(4.0 * np.arctan(self.bulges)))
        pieces = np.where(turn > 0.0, np.ceil(turn / max_arc_deg - 1e-9).astype(int), 0)
        pieces = np.maximum(pieces, (turn > 0.0).astype(int))
        # Per edge: vertex (t=0), then for each of `pieces` arcs its middle and (but the last) end.
        per_edge = np.maximum(1, 2 * pieces)
        edge = np.repeat(np.arange(len(self.vertices)), per_edge)
        starts = np.cumsum(per_edge) - per_edge
        k = np.arange(per_edge.sum()) - np.repeat(starts, per_edge)
        denom = np.repeat(np.maximum(2 * pieces, 1), per_edge)
        t = k / denom
        mask = (k % 2 == 1) & (np.repeat(pieces, per_edge) > 0)
        return self.edge_points(t.astype(np.float64), edge), mask

    def signed_area(self) -> float:
        """Area with arcs, positive when counter-clockwise."""
        return float(geo.signed_area(self.dense(self._auto_step())))

    def _auto_step(self) -> float:
        size = float(np.ptp(self.vertices, axis=0).max()) if len(self.vertices) > 1 else 1.0
        return max(size, 1e-9) / 200.0


@dataclass(frozen=True, eq=False)
class TilePath:
    """A tile outline (`Loop`) with its holes, in one frame (tile-local or placed)."""

    outer: Loop
    holes: tuple[Loop, ...] = ()

    def transformed(
        self, angle: float = 0.0, shift: ArrayLike = (0.0, 0.0), scale: float = 1.0
    ) -> TilePath:
        """Rotated by ``angle`` rad CCW (y-up) about the origin, scaled, then shifted."""
        return TilePath(
            self.outer.transformed(angle, shift, scale),
            tuple(h.transformed(angle, shift, scale) for h in self.holes),
        )

    def area_centroid(self, step: float) -> tuple[float, FloatArray]:
        """(area with holes subtracted, area centroid (2,)) from outlines sampled at ``step``."""
        total = 0.0
        moment = np.zeros(2)
        for sign, loop in [(1.0, self.outer)] + [(-1.0, h) for h in self.holes]:
            d = loop.dense(step)
            a = abs(geo.signed_area(d))
            total += sign * a
            moment += sign * a * geo.polygon_centroid(d)
        if not total > 0.0:
            return total, np.zeros(2)
        return total, moment / total

    def jittered(self, rng: np.random.Generator, amount: float, bulge_rel: float) -> TilePath:
        """Manufacturing-noise copy: vertices moved, bulges scaled.

        Each vertex moves uniformly within a disc of radius ``amount``; each bulge is scaled by
        a factor uniform in [1 - bulge_rel, 1 + bulge_rel].
        """

        def jit(loop: Loop) -> Loop:
            n = len(loop.vertices)
            r = amount * np.sqrt(rng.random(n))
            a = rng.random(n) * 2.0 * math.pi
            v = loop.vertices + np.stack([r * np.cos(a), r * np.sin(a)], axis=1)
            b = loop.bulges * (1.0 + bulge_rel * (2.0 * rng.random(n) - 1.0))
            return Loop(v, b)

        return TilePath(jit(self.outer), tuple(jit(h) for h in self.holes))

    def figure(
        self, color: Sequence[float] | None, max_arc_deg: float, *, y_down: bool = False
    ) -> Any:
        """The `qshape.Figure` of this path's relevant points (arc middles as curve points).

        Raises:
            qshape.errors.InvalidFigureError: Degenerate or self-crossing relevant points.
        """
        pts, mask = self.outer.relevant(max_arc_deg)
        holes = []
        for k, h in enumerate(self.holes):
            hp, hm = h.relevant(max_arc_deg)
            holes.append(Boundary.make(hp, hm, y_down=y_down, what=f"hole {k}"))
        return Figure.from_polygon(pts, holes, color, curve_mask=mask, y_down=y_down)


# ------------------------------------------------------------------------------ shape specs
_SHAPE_KEYS: dict[str, tuple[str, ...]] = {
    "polygon": ("vertices",),
    "rectangle": ("width", "height"),
    "square": ("size",),
    "regular_polygon": ("sides", "radius"),
    "triangle_right": ("width", "height"),
    "triangle_isosceles": ("base", "height"),
    "circle": ("radius",),
    "semicircle": ("radius",),
    "ring": ("radius", "inner_radius"),
}
"""Shape kinds and their required parameters (every kind also takes optional ``holes``)."""

_HOLE_POSE_KEYS = ("x", "y", "angle")


def _number(value: Any, where: str, positive: bool = True) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise DesignError(f"{where}: expected a finite number, got {value!r}")
    if positive and value <= 0:
        raise DesignError(f"{where}: must be > 0, got {value!r}")
    return float(value)


def _circle_loop(r: float) -> Loop:
    return Loop.make([[-r, 0.0], [r, 0.0]], [1.0, 1.0])


def _shape_loop(spec: Mapping[str, Any], where: str) -> Loop:
    """Compile one shape mapping (without holes) to its local `Loop`.

    Raises:
        DesignError: Unknown kind (the message lists the kinds), missing/unknown keys, bad values.
    """
    if not isinstance(spec, Mapping):
        raise DesignError(f"{where}: a shape must be a mapping with a 'kind', got {spec!r}")
    kind = spec.get("kind")
    if kind not in _SHAPE_KEYS:
        raise DesignError(f"{where}: unknown shape kind {kind!r}; allowed: {sorted(_SHAPE_KEYS)}")
    need = _SHAPE_KEYS[kind]
    allowed = {"kind", "holes", *need}
    unknown = sorted(set(spec) - allowed)
    if unknown:
        raise DesignError(
            f"{where}: unknown key(s) {unknown} for {kind}; allowed: {sorted(allowed)}"
        )
    missing = [k for k in need if k not in spec]
    if missing:
        raise DesignError(f"{where}: {kind} needs {missing}")
    try:
        if kind == "polygon":
            rows = spec["vertices"]
            if not isinstance(rows, list) or not all(
                isinstance(r, list) and len(r) in (2, 3) for r in rows
            ):
                raise DesignError(f"{where}: vertices must be a list of [x, y] or [x, y, bulge]")
            v = [[_number(r[0], where, False), _number(r[1], where, False)] for r in rows]
            b = [_number(r[2], where, False) if len(r) == 3 else 0.0 for r in rows]
            return Loop.make(v, b)
        if kind in ("rectangle", "square"):
            w = _number(spec["width" if kind == "rectangle" else "size"], f"{where}.width/size")
            h = _number(spec["height"], f"{where}.height") if kind == "rectangle" else w
            return Loop.make([[-w / 2, -h / 2], [w / 2, -h / 2], [w / 2, h / 2], [-w / 2, h / 2]])
        if kind == "regular_polygon":
            n = spec["sides"]
            if isinstance(n, bool) or not isinstance(n, int) or n < 3:
                raise DesignError(f"{where}.sides: an integer >= 3, got {n!r}")
            r = _number(spec["radius"], f"{where}.radius")
            t = math.pi / 2 + 2 * math.pi * np.arange(n) / n
            return Loop.make(r * np.stack([np.cos(t), np.sin(t)], axis=1))
        if kind == "triangle_right":
            w, h = (
                _number(spec["width"], f"{where}.width"),
                _number(spec["height"], f"{where}.height"),
            )
            return Loop.make([[-w / 2, -h / 2], [w / 2, -h / 2], [-w / 2, h / 2]])
        if kind == "triangle_isosceles":
            w, h = (
                _number(spec["base"], f"{where}.base"),
                _number(spec["height"], f"{where}.height"),
            )
            return Loop.make([[-w / 2, -h / 2], [w / 2, -h / 2], [0.0, h / 2]])
        if kind == "circle":
            return _circle_loop(_number(spec["radius"], f"{where}.radius"))
        if kind == "semicircle":
            r = _number(spec["radius"], f"{where}.radius")
            return Loop.make([[r, 0.0], [-r, 0.0]], [1.0, 0.0])
        # ring: outer circle here; the concentric hole is added by _tile_path.
        return _circle_loop(_number(spec["radius"], f"{where}.radius"))
    except DesignError as exc:
        if str(exc).startswith(where):
            raise
        raise DesignError(f"{where}: {exc}") from exc


def _tile_path(spec: Mapping[str, Any], where: str) -> TilePath:
    """Compile a shape mapping with its holes (tile-local frame, before recentring)."""
    outer = _shape_loop(spec, where)
    holes: list[Loop] = []
    if spec.get("kind") == "ring":
        ro = _number(spec["radius"], f"{where}.radius")
        ri = _number(spec["inner_radius"], f"{where}.inner_radius")
        if ri >= ro:
            raise DesignError(f"{where}: inner_radius {ri} must be < radius {ro}")
        holes.append(_circle_loop(ri))
    raw_holes = spec.get("holes", [])
    if not isinstance(raw_holes, list):
        raise DesignError(f"{where}.holes: must be a list of shapes")
    for k, h in enumerate(raw_holes):
        hw = f"{where}.holes[{k}]"
        if not isinstance(h, Mapping):
            raise DesignError(f"{hw}: must be a mapping")
        pose = {key: h[key] for key in _HOLE_POSE_KEYS if key in h}
        body = {key: v for key, v in h.items() if key not in _HOLE_POSE_KEYS}
        if "holes" in body:
            raise DesignError(f"{hw}: a hole cannot have holes")
        loop = _shape_loop(body, hw)
        ang = math.radians(_number(pose.get("angle", 0.0), f"{hw}.angle", False))
        shift = (
            _number(pose.get("x", 0.0), f"{hw}.x", False),
            _number(pose.get("y", 0.0), f"{hw}.y", False),
        )
        holes.append(loop.transformed(ang, shift))
    return TilePath(outer, tuple(holes))


def _parse_color(value: Any, where: str) -> tuple[float, float, float]:
    """RGB floats in [0, 1] from ``[r, g, b]`` (floats in [0, 1]) or ``"#rrggbb"``."""
    if isinstance(value, str):
        s = value.lstrip("#")
        if len(s) != 6 or any(c not in "0123456789abcdefABCDEF" for c in s):
            raise DesignError(f"{where}: colour string must be '#rrggbb', got {value!r}")
        return (int(s[0:2], 16) / 255.0, int(s[2:4], 16) / 255.0, int(s[4:6], 16) / 255.0)
    if isinstance(value, list | tuple) and len(value) == 3:
        rgb = tuple(_number(v, where, False) for v in value)
        if all(0.0 <= v <= 1.0 for v in rgb):
            return (rgb[0], rgb[1], rgb[2])
    raise DesignError(f"{where}: colour must be '#rrggbb' or [r, g, b] in [0, 1], got {value!r}")


def color_hex(rgb: Sequence[float]) -> str:
    """``"#rrggbb"`` of an RGB triple in [0, 1]."""
    r, g, b = (int(round(min(max(float(v), 0.0), 1.0) * 255)) for v in rgb)
    return f"#{r:02x}{g:02x}{b:02x}"


# ----------------------------------------------------------------------------------- slots
@dataclass(frozen=True)
class Slot:
    """One tile position of a design.

    Attributes:
        name: Unique name within the design.
        shape: The shape mapping as written in the design file (``kind``, its parameters and
            optional ``holes``); see ``configs/designs/README.md``.
        color: RGB in [0, 1].
        x: Mesh x of the tile's area centroid, in [mm].
        y: Mesh y of the tile's area centroid, in [mm] (y up).
        angle: Rotation of the shape about its centroid, in [deg], counter-clockwise.
        rules: Sampling and validation rules.
    """

    name: str
    shape: Mapping[str, Any]
    color: tuple[float, float, float]
    x: float
    y: float
    angle: float = 0.0
    rules: DesignRules = field(default_factory=DesignRules, compare=False, repr=False)

    @cached_property
    def local_path(self) -> TilePath:
        """Tile outline and holes in the tile frame: area centroid at the origin, angle 0, [mm].

        Raises:
            DesignError: Malformed shape.
        """
        path = _tile_path(self.shape, f"slot {self.name!r}.shape")
        area, c = path.area_centroid(self.rules.outline_step_mm)
        if not area > 0.0:
            raise DesignError(f"slot {self.name!r}: zero or negative area (holes too large?)")
        return path.transformed(0.0, -c)

    @cached_property
    def path(self) -> TilePath:
        """Tile outline and holes placed on the mesh, [mm], y up."""
        return self.local_path.transformed(math.radians(self.angle), (self.x, self.y))

    def outline_mm(self) -> FloatArray:
        """Dense closed outline on the mesh, counter-clockwise, [mm], shape (m, 2)."""
        return self.path.outer.dense(self.rules.outline_step_mm)

    def holes_mm(self) -> list[FloatArray]:
        """Dense closed outline of each hole on the mesh, counter-clockwise, [mm]."""
        return [h.dense(self.rules.outline_step_mm) for h in self.path.holes]

    def figure(self) -> Any:
        """The slot as a `qshape.Figure` in mesh millimetres (y up), with its colour."""
        return self.path.figure(self.color, self.rules.max_arc_deg)

    @property
    def centroid(self) -> FloatArray:
        """Area centroid on the mesh, [mm], shape (2,)."""
        return np.array([self.x, self.y])

    @cached_property
    def area(self) -> float:
        """Tile area with holes subtracted, in [mm^2]."""
        return self.local_path.area_centroid(self.rules.outline_step_mm)[0]

    @cached_property
    def shape_key(self) -> str:
        """Identifier of the shape class: equal for slots whose shapes are equal (any pose)."""
        text = yaml.safe_dump(_plain(self.shape), sort_keys=True)
        return hashlib.sha1(text.encode()).hexdigest()[:12]

    @property
    def class_key(self) -> str:
        """Identifier of the shape-and-colour class."""
        return f"{self.shape_key}{color_hex(self.color)}"

    @cached_property
    def symmetry(self) -> int:
        """Rotational symmetry order of the shape (1: none, 4: square, 0: continuous)."""
        rules = self.rules
        loops = (self.local_path.outer, *self.local_path.holes)
        samples = np.concatenate([lp.dense(rules.outline_step_mm / 4.0) for lp in loops])
        tree = cKDTree(samples)
        step = max(1, len(samples) // rules.symmetry_samples)
        probe = samples[::step]
        tol = rules.symmetry_tolerance * math.sqrt(self.area)

        def invariant(angle: float) -> bool:
            dist, _ = tree.query(probe @ _rot(angle))
            return bool(np.max(dist) <= tol)

        if invariant(1.0) and invariant(math.sqrt(2.0)):
            return 0
        for order in range(rules.max_symmetry_order, 1, -1):
            if invariant(2.0 * math.pi / order):
                return order
        return 1

    def to_dict(self) -> dict[str, Any]:
        """The slot as written in a design file."""
        return {
            "name": self.name,
            "shape": _plain(self.shape),
            "color": color_hex(self.color),
            "pose": {"x": _r(self.x), "y": _r(self.y), "angle": _r(self.angle)},
        }


def _r(v: float) -> float:
    return float(round(float(v), 4))


def _plain(value: Any) -> Any:
    """Plain Python (dicts, lists, floats) for YAML output and hashing."""
    if isinstance(value, Mapping):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple | np.ndarray):
        return [_plain(v) for v in value]
    if isinstance(value, np.integer | int) and not isinstance(value, bool):
        return int(value)
    if isinstance(value, np.floating | float):
        return _r(float(value))
    return value


# ---------------------------------------------------------------------------------- design
_DESIGN_KEYS = {"name", "description", "mesh", "joint", "grout_color", "slots"}
_SLOT_KEYS = {"name", "shape", "color", "pose"}
_POSE_KEYS = {"x", "y", "angle"}


@dataclass(frozen=True)
class Design:
    """A mosaic design: a rectangular mesh, a joint width and the slots to fill.

    Attributes:
        name: Design name.
        mesh_size: (width, height) of the mesh, in [mm]; the origin is its lower-left corner,
            y up.
        joint: Joint (grout) width between neighbouring tiles, in [mm].
        slots: The slots, names unique.
        grout_color: RGB in [0, 1] of the joints and empty mesh (used for rendering).
        description: Free text.
        rules: Sampling and validation rules.
    """

    name: str
    mesh_size: tuple[float, float]
    joint: float
    slots: tuple[Slot, ...]
    grout_color: tuple[float, float, float] = (0.85, 0.83, 0.78)
    description: str = ""
    rules: DesignRules = field(default_factory=DesignRules, compare=False, repr=False)

    # ------------------------------------------------------------------ loading and saving
    @classmethod
    def load(cls, name_or_path: str | Path, rules: DesignRules | None = None) -> Design:
        """Load and validate a design: a bundled name (``"paper_mixed"``) or a YAML path.

        Raises:
            DesignError: Missing or unreadable file, unknown keys, bad values, degenerate or
                overlapping slots, slots outside the mesh; the message names the slot.
        """
        try:
            data = load_yaml(name_or_path, DESIGN_SUBDIR)
        except ConfigError as exc:
            raise DesignError(str(exc)) from exc
        return cls.from_dict(data, rules=rules, source=str(name_or_path))

    @classmethod
    def from_dict(
        cls, data: Mapping[str, Any], rules: DesignRules | None = None, source: str = "<dict>"
    ) -> Design:
        """Build and validate a design from its file mapping (see `load`).

        Raises:
            DesignError: As `load`.
        """
        rules = rules or DesignRules()
        if not isinstance(data, Mapping):
            raise DesignError(f"{source}: a design must be a mapping")
        unknown = sorted(set(data) - _DESIGN_KEYS)
        if unknown:
            raise DesignError(
                f"{source}: unknown key(s) {unknown}; allowed: {sorted(_DESIGN_KEYS)}"
            )
        for key in ("name", "mesh", "joint", "slots"):
            if key not in data:
                raise DesignError(f"{source}: missing key {key!r}")
        mesh = data["mesh"]
        if not isinstance(mesh, Mapping) or set(mesh) != {"width", "height"}:
            raise DesignError(f"{source}: mesh must be a mapping with exactly width and height")
        size = (
            _number(mesh["width"], f"{source}: mesh.width"),
            _number(mesh["height"], f"{source}: mesh.height"),
        )
        joint = _number(data["joint"], f"{source}: joint")
        raw = data["slots"]
        if not isinstance(raw, list) or not raw:
            raise DesignError(f"{source}: slots must be a non-empty list")
        slots = []
        for i, s in enumerate(raw):
            where = f"{source}: slot {i}"
            if not isinstance(s, Mapping):
                raise DesignError(f"{where}: must be a mapping")
            name = str(s.get("name", f"slot_{i}"))
            where = f"{source}: slot {name!r}"
            bad = sorted(set(s) - _SLOT_KEYS)
            if bad:
                raise DesignError(f"{where}: unknown key(s) {bad}; allowed: {sorted(_SLOT_KEYS)}")
            for key in ("shape", "color", "pose"):
                if key not in s:
                    raise DesignError(f"{where}: missing key {key!r}")
            pose = s["pose"]
            if not isinstance(pose, Mapping) or sorted(set(pose) - _POSE_KEYS):
                raise DesignError(f"{where}: pose must be a mapping of {sorted(_POSE_KEYS)}")
            if "x" not in pose or "y" not in pose:
                raise DesignError(f"{where}: pose needs x and y")
            slots.append(
                Slot(
                    name=name,
                    shape=_plain(s["shape"]) if isinstance(s["shape"], Mapping) else s["shape"],
                    color=_parse_color(s["color"], f"{where}.color"),
                    x=_number(pose["x"], f"{where}.pose.x", False),
                    y=_number(pose["y"], f"{where}.pose.y", False),
                    angle=_number(pose.get("angle", 0.0), f"{where}.pose.angle", False),
                    rules=rules,
                )
            )
        design = cls(
            name=str(data["name"]),
            mesh_size=size,
            joint=joint,
            slots=tuple(slots),
            grout_color=_parse_color(data.get("grout_color", "#d9d4c7"), f"{source}: grout_color"),
            description=str(data.get("description", "")),
            rules=rules,
        )
        design.validate(source)
        return design

    def to_dict(self) -> dict[str, Any]:
        """The design as a file mapping (inverse of `from_dict`)."""
        out: dict[str, Any] = {"name": self.name}
        if self.description:
            out["description"] = self.description
        out["mesh"] = {"width": _r(self.mesh_size[0]), "height": _r(self.mesh_size[1])}
        out["joint"] = _r(self.joint)
        out["grout_color"] = color_hex(self.grout_color)
        out["slots"] = [s.to_dict() for s in self.slots]
        return out

    def save(self, path: str | Path, header: str = "") -> None:
        """Write the design as YAML (``header`` lines become leading comments)."""
        text = "".join(f"# {line}\n".replace("# \n", "#\n") for line in header.splitlines())
        text += yaml.safe_dump(self.to_dict(), sort_keys=False, default_flow_style=None, width=100)
        Path(path).write_text(text, encoding="utf-8")

    # ------------------------------------------------------------------------ validation
    def validate(self, source: str = "") -> None:
        """Check every slot and the layout.

        Raises:
            DesignError: Duplicate names, degenerate or self-crossing outlines, bad holes,
                slots outside the mesh (by more than ``rules.mesh_margin_mm``), or two slots
                closer than ``rules.min_gap_fraction`` x joint.
        """
        pre = f"{source}: " if source else f"design {self.name!r}: "
        names = [s.name for s in self.slots]
        dupes = sorted({n for n in names if names.count(n) > 1})
        if dupes:
            raise DesignError(f"{pre}duplicate slot name(s) {dupes}")
        w, h = self.mesh_size
        margin = self.rules.mesh_margin_mm
        outlines = []
        for s in self.slots:
            try:
                dense = s.path.outer.dense(self.rules.check_step_mm)
                if geo.self_intersects(dense):
                    raise DesignError("its outline crosses itself")
                s.figure()
            except (DesignError, InvalidFigureError) as exc:
                text = str(exc)
                named = text if text.startswith(f"slot {s.name!r}") else f"slot {s.name!r}: {text}"
                raise DesignError(f"{pre}{named}") from exc
            lo, hi = dense.min(axis=0), dense.max(axis=0)
            if lo[0] < margin or lo[1] < margin or hi[0] > w - margin or hi[1] > h - margin:
                raise DesignError(
                    f"{pre}slot {s.name!r} lies outside the {w} x {h} mm mesh (extent x "
                    f"{lo[0]:.1f}..{hi[0]:.1f}, y {lo[1]:.1f}..{hi[1]:.1f} mm; margin {margin} mm)"
                )
            outlines.append(dense)
        min_gap = self.rules.min_gap_fraction * self.joint
        centres = np.array([d.mean(axis=0) for d in outlines])
        radii = np.array(
            [np.max(np.hypot(*(d - c).T)) for d, c in zip(outlines, centres, strict=False)]
        )
        dc = np.hypot(*(centres[:, None, :] - centres[None, :, :]).transpose(2, 0, 1))
        ii, jj = np.nonzero(np.triu(dc < radii[:, None] + radii[None, :] + min_gap, k=1))
        for i, j in zip(ii.tolist(), jj.tolist(), strict=False):
            gap = _outline_gap(outlines[i], outlines[j])
            if gap < min_gap:
                what = "overlap" if gap < 0 else f"are {gap:.2f} mm apart"
                raise DesignError(
                    f"{pre}slots {self.slots[i].name!r} and {self.slots[j].name!r} {what}; the "
                    f"joint is {self.joint} mm (at least {min_gap:.2f} mm required)"
                )

    # ------------------------------------------------------------------------- queries
    def figures(self) -> list[Any]:
        """Every slot as a `qshape.Figure` in mesh millimetres, in slot order."""
        return [s.figure() for s in self.slots]

    def slot(self, name: str) -> Slot:
        """The slot called ``name``.

        Raises:
            DesignError: No such slot (the message lists the names).
        """
        for s in self.slots:
            if s.name == name:
                return s
        raise DesignError(
            f"design {self.name!r} has no slot {name!r}; slots: {[s.name for s in self.slots]}"
        )

    def with_slots(self, slots: Sequence[Slot]) -> Design:
        """Copy with other slots (validated)."""
        d = replace(self, slots=tuple(slots))
        d.validate()
        return d

    @classmethod
    def from_image(
        cls,
        image: str | Path | np.ndarray,
        mm_per_px: float,
        joint_mm: float,
        *,
        name: str = "from_image",
        params: Any = None,
        rules: DesignRules | None = None,
    ) -> Design:
        """Design from a design image (tiles on a joint colour), e.g. drawn in any editor.

        Tiles are found by `qshape.extract`; tiles touching the image border are left out.
        Each tile becomes a ``polygon`` slot (arcs as bulges) with the extracted colour. The
        mesh is the whole image.

        Args:
            image: RGB uint8 array (H, W, 3) or a path to an image file (PNG, JPEG, ...).
            mm_per_px: Scale, in [mm/px].
            joint_mm: Joint width of the design, in [mm].
            name: Design name.
            params: `qshape.extract.ExtractParams` (None: ``configs/vision.yaml``).
            rules: Validation rules.

        Raises:
            DesignError: Unreadable file, bad scale, no tiles, or an invalid resulting design.
            qshape.extract.ImageError: Malformed image.
        """
        from qshape.extract import extract_detailed, read_image  # noqa: PLC0415 (cycle)

        scale = _number(mm_per_px, "mm_per_px")
        arr = read_image(image) if isinstance(image, str | Path) else image
        result = extract_detailed(arr, params)
        if not result.figures:
            raise DesignError("design image: no whole tiles found")
        height_px = arr.shape[0]
        slots = []
        for k, fig in enumerate(result.figures):
            slots.append(_slot_from_figure(fig, k, scale, height_px, rules or DesignRules()))
        data = {
            "name": name,
            "mesh": {"width": arr.shape[1] * scale, "height": height_px * scale},
            "joint": _number(joint_mm, "joint_mm"),
            "grout_color": color_hex(result.background),
            "slots": [s.to_dict() for s in slots],
        }
        return cls.from_dict(data, rules=rules, source=f"design image {name!r}")


def _bulges_from_relevant(pts: FloatArray, mask: BoolArray) -> tuple[FloatArray, FloatArray]:
    """Vertices and bulges (CCW, y-up) from relevant points whose curve points are arc middles."""
    keep = ~mask
    v = pts[keep]
    b = np.zeros(len(v))
    idx = np.flatnonzero(keep)
    n = len(pts)
    for e, i in enumerate(idx):
        j = (i + 1) % n
        if mask[j]:
            k = (j + 1) % n
            chord = pts[k] - pts[i]
            c = float(np.hypot(*chord))
            mid = 0.5 * (pts[i] + pts[k])
            out = np.array([chord[1], -chord[0]]) / c  # outward for a CCW loop
            sag = float((pts[j] - mid) @ out)
            b[e] = 2.0 * sag / c
    return v, b


def _slot_from_figure(fig: Any, k: int, scale: float, height_px: int, rules: DesignRules) -> Slot:
    """A polygon slot (mesh mm, y up) from an extracted pixel figure (y down)."""

    def to_mm(p: FloatArray) -> FloatArray:
        return np.stack([p[:, 0] * scale, (height_px - p[:, 1]) * scale], axis=1)

    def loop_of(points: FloatArray, mask: BoolArray) -> Loop:
        mm = to_mm(np.asarray(points))
        m = np.asarray(mask, dtype=bool)
        if geo.signed_area(mm) < 0:
            mm, m = mm[::-1].copy(), m[::-1].copy()
        v, b = _bulges_from_relevant(mm, m)
        return Loop.make(v, b)

    outer = loop_of(fig.points, fig.curve_mask)
    holes = [loop_of(h.points, h.curve_mask) for h in fig.holes]
    path = TilePath(outer, tuple(holes))
    _, c = path.area_centroid(rules.outline_step_mm)

    def rows(loop: Loop) -> list[list[float]]:
        v = loop.vertices - c
        return [
            [_r(x), _r(y)] + ([_r(b)] if b != 0.0 else [])
            for (x, y), b in zip(v, loop.bulges, strict=False)
        ]

    shape: dict[str, Any] = {"kind": "polygon", "vertices": rows(outer)}
    if holes:
        shape["holes"] = [{"kind": "polygon", "vertices": rows(h)} for h in holes]
    r, g, b = fig.color if fig.color is not None else (0.5, 0.5, 0.5)
    return Slot(f"tile_{k:03d}", shape, (r, g, b), float(c[0]), float(c[1]), 0.0, rules)


def _outline_gap(a: FloatArray, b: FloatArray) -> float:
    """Smallest distance between two closed outlines; negative when they overlap."""
    if geo.points_in_polygon(a, b).any() or geo.points_in_polygon(b, a).any():
        return -1.0
    return min(_point_segment_distance(a, b), _point_segment_distance(b, a))


def _point_segment_distance(points: FloatArray, loop: FloatArray) -> float:
    """Smallest distance from points (m, 2) to the edges of a closed polyline (n, 2)."""
    p0 = loop
    d = np.roll(loop, -1, axis=0) - p0
    dd = np.einsum("ij,ij->i", d, d)
    rel = points[:, None, :] - p0[None, :, :]
    t = np.clip(np.einsum("mnj,nj->mn", rel, d) / np.where(dd > 0, dd, 1.0), 0.0, 1.0)
    diff = rel - t[..., None] * d[None, :, :]
    return float(np.sqrt(np.min(np.einsum("mnj,mnj->mn", diff, diff))))


def bundled_designs() -> list[str]:
    """Names of the designs in ``configs/designs/``."""
    return sorted(p.stem for p in (CONFIG_DIR / DESIGN_SUBDIR).glob("*.yaml"))


__all__ = [
    "Design",
    "DesignError",
    "DesignRules",
    "Loop",
    "Slot",
    "TilePath",
    "bundled_designs",
    "color_hex",
    "load_section",
]
