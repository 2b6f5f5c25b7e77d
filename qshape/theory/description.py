"""Qualitative descriptions: `describe`, the `Description` value, its text form and `parse`.

A description is the paper's tuple ``[type_hole, type_curve, colour, [nodes...],
(CIi, position, [hole nodes...])*]``. It also keeps, for matching, each node's admissible
neighbouring labels (near band edges) and the relevant points relative to the outer centroid in
the y-up frame (so the rotation that places a tile can be computed). The text form holds all of
it, floats written exactly, so ``parse(str(d)) == d`` and matching parsed descriptions works.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from qshape.errors import InvalidFigureError
from qshape.geometry import BoolArray, FloatArray
from qshape.theory import labels as lb
from qshape.theory.boundary import densify
from qshape.theory.figure import Color, Figure
from qshape.theory.labels import CodeArray
from qshape.theory.tolerances import Tolerances, default_tolerances, resolve_tolerances  # noqa: F401

WITHOUT_HOLES, WITH_HOLES = "without holes", "with holes"
WITHOUT_CURVES, WITH_CURVES, ONLY_CURVES = "without curves", "with curves", "only curves"
CONES = ("N", "NE", "E", "SE", "S", "SW", "W", "NW")
CENTRE = "C"
CIi = "CIi"
HEADER = "qshape-description v1"
_CONE_DEG = 45.0
_HOLE_ARC_SAMPLES = 8
"""Samples per arc when measuring the angles a hole spans (numerical resolution only)."""


@dataclass(frozen=True)
class Node:
    """One node of a description, readable form.

    Attributes:
        kind: "vertex" or "curve".
        labels: (A, C, L) for a vertex, ("Curve", C, TC) for a curve: the measured labels.
        admissible: For each of the three components, every admissible label (the measured one
            first; a neighbouring label too when the measurement is within the margin of an edge).
    """

    kind: str
    labels: tuple[str, str, str]
    admissible: tuple[tuple[str, ...], tuple[str, ...], tuple[str, ...]]

    @property
    def ambiguous(self) -> bool:
        """True when some component admits a neighbouring label."""
        return any(len(a) > 1 for a in self.admissible)


def _names(primary: int, mask: int, names: tuple[str, ...]) -> tuple[str, ...]:
    rest = tuple(names[k] for k in range(len(names)) if mask >> k & 1 and k != primary)
    return (names[primary], *rest)


def node_of(code: int) -> Node:
    """Readable `Node` of a node code."""
    is_curve, (a, am), (c, cm), (t, tm) = lb.decode(int(code))
    conv = _names(c, cm, lb.CONVEXITY_LABELS)
    if is_curve:
        tc = _names(t, tm, lb.CURVATURE_LABELS)
        return Node("curve", (lb.CURVE, conv[0], tc[0]), ((lb.CURVE,), conv, tc))
    ang = _names(a, am, lb.ANGLE_LABELS)
    ln = _names(t, tm, lb.LENGTH_LABELS)
    return Node("vertex", (ang[0], conv[0], ln[0]), (ang, conv, ln))


def type_curve_of(codes: CodeArray) -> str:
    """type_curve of a boundary from its node codes."""
    curve = (codes & lb.KIND_BIT) == 1
    if not curve.any():
        return WITHOUT_CURVES
    if len(codes) % 2 or curve.sum() * 2 != len(codes):
        return WITH_CURVES
    if np.all(curve | (np.roll(curve, 1) & np.roll(curve, -1))):
        return ONLY_CURVES
    return WITH_CURVES


@dataclass(frozen=True, eq=False)
class BoundaryDescription:
    """Nodes and relevant points of one boundary.

    Attributes:
        codes: Node codes, shape (n,) int64 (see `qshape.theory.labels`). Read-only.
        points: Relevant points relative to the parent's outer centroid, right-handed y-up
            frame, clockwise as seen, in the figure's unit, shape (n, 2). Read-only.
    """

    codes: CodeArray
    points: FloatArray

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, BoundaryDescription):
            return NotImplemented
        return np.array_equal(self.codes, other.codes) and np.array_equal(self.points, other.points)

    __hash__ = None  # type: ignore[assignment]

    @property
    def nodes(self) -> tuple[Node, ...]:
        """Readable nodes."""
        return tuple(node_of(int(c)) for c in self.codes)

    @property
    def curve_mask(self) -> BoolArray:
        """Shape (n,) bool, True at curve nodes."""
        return np.asarray((self.codes & lb.KIND_BIT) == 1)

    @property
    def type_curve(self) -> str:
        """One of "without curves", "with curves" or "only curves"."""
        return type_curve_of(self.codes)


@dataclass(frozen=True, eq=False)
class HoleDescription:
    """One hole: the CIi relation, its position in the 8-cone frame, and its boundary.

    Attributes:
        position: Cones of the cardinal frame (at the parent's outer centroid, north towards the
            parent's first vertex) the hole covers, in compass order, or ("C",) when the hole
            surrounds the centroid.
        boundary: The hole's nodes and points, starting at its vertex nearest the parent's first
            vertex.
        relation: Always "CIi" (the parent is completely-inside-inverse of the hole).
    """

    position: tuple[str, ...]
    boundary: BoundaryDescription
    relation: str = CIi

    @cached_property
    def angles(self) -> tuple[float, float] | None:
        """Polar angle interval [deg] the hole spans (None: it surrounds the centroid).

        Angles are counter-clockwise from +x about the parent's centroid in the y-up frame.
        Computed once, for matching.
        """
        return hole_angles(self.boundary.points, self.boundary.curve_mask)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, HoleDescription):
            return NotImplemented
        return (
            self.position == other.position
            and self.relation == other.relation
            and self.boundary == other.boundary
        )

    __hash__ = None  # type: ignore[assignment]


@dataclass(frozen=True, eq=False)
class Description:
    """Qualitative description of a figure (the paper's tuple plus matching data).

    Attributes:
        type_hole: "without holes" or "with holes".
        type_curve: "without curves", "with curves" or "only curves" (outer boundary).
        color: RGB in [0, 1] or None.
        area: Figure area (holes subtracted) in the figure's unit squared.
        perimeter: Outer perimeter in the figure's unit.
        outer: Outer boundary nodes and points, starting at its uppermost (then leftmost)
            vertex in the y-up frame, as in the paper.
        holes: One `HoleDescription` per hole.
    """

    type_hole: str
    type_curve: str
    color: Color | None
    area: float
    perimeter: float
    outer: BoundaryDescription
    holes: tuple[HoleDescription, ...] = ()

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Description):
            return NotImplemented
        return (
            self.type_hole == other.type_hole
            and self.type_curve == other.type_curve
            and self.color == other.color
            and self.area == other.area
            and self.perimeter == other.perimeter
            and self.outer == other.outer
            and self.holes == other.holes
        )

    __hash__ = None  # type: ignore[assignment]

    @property
    def nodes(self) -> tuple[Node, ...]:
        """Readable nodes of the outer boundary."""
        return self.outer.nodes

    def __str__(self) -> str:
        return format_description(self)

    def __repr__(self) -> str:
        return f"Description({_node_string(self.outer.codes)!r}, holes={len(self.holes)})"


def _node_string(codes: CodeArray) -> str:
    return " ".join(_node_text(int(c)) for c in codes)


def _node_text(code: int) -> str:
    node = node_of(code)
    return "<" + ", ".join("/".join(a) for a in node.admissible) + ">"


def _start_index(points: FloatArray, tie: float) -> int:
    """Uppermost vertex (y-up), leftmost among those equally high within ``tie``."""
    y = points[:, 1]
    top = y >= y.max() - tie
    return int(np.argmin(np.where(top, points[:, 0], np.inf)))


def hole_angles(points: FloatArray, curve_mask: BoolArray) -> tuple[float, float] | None:
    """Polar-angle interval [deg] (CCW from +x) a hole spans about the origin.

    Args:
        points: Hole relevant points relative to the parent's centroid, y-up, shape (m, 2).
        curve_mask: Shape (m,) bool; arcs are sampled.

    Returns:
        (low, high) with high - low < 360, or None when the hole winds around the origin.
    """
    dense = densify(points, curve_mask, _HOLE_ARC_SAMPLES)
    ang = np.degrees(np.arctan2(dense[:, 1], dense[:, 0]))
    step = (np.diff(ang, append=ang[0]) + 180.0) % 360.0 - 180.0
    if abs(float(step.sum())) > 180.0:  # winding number 1: the hole surrounds the centroid
        return None
    walk = ang[0] + np.concatenate([[0.0], np.cumsum(step[:-1])])
    return float(walk.min()), float(walk.max())


def hole_angles_many(points: FloatArray, curve_mask: BoolArray) -> FloatArray:
    """`hole_angles` of a stack of holes sharing one curve mask, all at once.

    Args:
        points: Holes' relevant points, shape (G, m, 2) (see `hole_angles`).
        curve_mask: Shape (m,) bool.

    Returns:
        (G, 2) intervals [deg]; NaN rows for holes around the origin.
    """
    dense = densify(points, curve_mask, _HOLE_ARC_SAMPLES)
    ang = np.degrees(np.arctan2(dense[..., 1], dense[..., 0]))  # (G, k)
    step = (np.diff(ang, axis=1, append=ang[:, :1]) + 180.0) % 360.0 - 180.0
    around = np.abs(step.sum(axis=1)) > 180.0
    walk = ang[:, :1] + np.concatenate(
        [np.zeros((len(ang), 1)), np.cumsum(step[:, :-1], axis=1)], axis=1
    )
    out = np.stack([walk.min(axis=1), walk.max(axis=1)], axis=1)
    out[around] = np.nan
    return out


def hole_interval(
    points: FloatArray, curve_mask: BoolArray, north: FloatArray
) -> tuple[float, float] | None:
    """Bearing interval (deg, clockwise from north) a hole covers, or None if around origin.

    Args:
        points: Hole relevant points relative to the parent's centroid, y-up, shape (m, 2).
        curve_mask: Shape (m,) bool.
        north: Direction of north (the parent's first vertex), shape (2,).
    """
    iv = hole_angles(points, curve_mask)
    if iv is None:
        return None
    nu = math.degrees(math.atan2(float(north[1]), float(north[0])))
    return nu - iv[1], nu - iv[0]


def cones_of(interval: tuple[float, float] | None, shrink: float = 0.0) -> frozenset[int]:
    """Cone indices (0 = N, clockwise) covered by a bearing interval shrunk by ``shrink`` deg.

    An interval narrower than twice ``shrink`` covers no cone (no constraint); None (a hole
    around the centroid) gives the set {-1} meaning centre.
    """
    if interval is None:
        return frozenset({-1})
    lo, hi = interval[0] + shrink, interval[1] - shrink
    if lo > hi:
        return frozenset()
    first = math.floor((lo + _CONE_DEG / 2) / _CONE_DEG)
    last = math.floor((hi + _CONE_DEG / 2) / _CONE_DEG)
    return frozenset(k % len(CONES) for k in range(first, last + 1))


def position_names(cones: frozenset[int]) -> tuple[str, ...]:
    """Cone names in compass order (("C",) for centre)."""
    if -1 in cones:
        return (CENTRE,)
    return tuple(CONES[k] for k in sorted(cones))


def describe(figure: Figure, tolerances: Tolerances | None = None) -> Description:
    """Qualitative description of a figure.

    Args:
        figure: The figure (any unit; y_down figures are described in the y-up frame).
        tolerances: Bands and margins; None uses the bundled defaults.

    Returns:
        The `Description`; the outer boundary starts at its uppermost-left vertex (y-up).

    Raises:
        InvalidFigureError: ``figure`` is not a `Figure`.
        ToleranceError: ``tolerances`` is not a `Tolerances` (or None).
    """
    tol = resolve_tolerances(tolerances)
    if not isinstance(figure, Figure):
        raise InvalidFigureError(f"describe expects a qshape.Figure, got {type(figure).__name__}")
    flip = np.array([1.0, -1.0]) if figure.y_down else np.array([1.0, 1.0])
    centre = figure.outer_centroid * flip
    rel = figure.points * flip - centre
    mask = figure.curve_mask
    size = float(np.ptp(rel, axis=0).max())
    start = _start_index(rel, tol.tie_tolerance * size)
    if start:
        rel = np.roll(rel, -start, axis=0)
        mask = np.roll(mask, -start)
    codes = lb.node_codes(rel, mask, tol)
    rel.setflags(write=False)
    codes.setflags(write=False)
    outer = BoundaryDescription(codes, rel)
    holes = tuple(
        _describe_hole(h.points * flip - centre, h.curve_mask, rel[0], tol) for h in figure.holes
    )
    return Description(
        WITH_HOLES if holes else WITHOUT_HOLES,
        type_curve_of(codes),
        figure.color,
        figure.area,
        figure.perimeter,
        outer,
        holes,
    )


def describe_many(
    figures: Sequence[Figure], tolerances: Tolerances | None = None
) -> list[Description]:
    """Describe many figures at once; equal to ``[describe(f) for f in figures]``, faster.

    The labels of all outer boundaries are computed in one vectorised pass over every relevant
    point; holes are described figure by figure.

    Args:
        figures: The figures.
        tolerances: Bands and margins; None uses the bundled defaults.

    Raises:
        InvalidFigureError: ``figures`` is not a sequence of `Figure`.
        ToleranceError: ``tolerances`` is not a `Tolerances` (or None).
    """
    tol = resolve_tolerances(tolerances)
    if not isinstance(figures, Sequence) or isinstance(figures, str | bytes):
        raise InvalidFigureError(
            f"describe_many expects a sequence of qshape.Figure, got {type(figures).__name__}"
        )
    for k, f in enumerate(figures):
        if not isinstance(f, Figure):
            raise InvalidFigureError(
                f"describe_many: item {k} must be a qshape.Figure, got {type(f).__name__}"
            )
    if not figures:
        return []
    counts = np.array([len(f.points) for f in figures])
    offsets = np.concatenate([[0], np.cumsum(counts)[:-1]])
    seg = np.repeat(np.arange(len(figures)), counts)
    local = np.arange(len(seg)) - offsets[seg]
    flip = np.array([-1.0 if f.y_down else 1.0 for f in figures])
    pts = np.concatenate([f.points for f in figures])
    cen = np.stack([f.outer_centroid for f in figures])
    cen[:, 1] *= flip
    pts[:, 1] *= flip[seg]
    rel = pts - cen[seg]
    mask = np.concatenate([f.curve_mask for f in figures])
    size = np.maximum(
        np.maximum.reduceat(rel[:, 0], offsets) - np.minimum.reduceat(rel[:, 0], offsets),
        np.maximum.reduceat(rel[:, 1], offsets) - np.minimum.reduceat(rel[:, 1], offsets),
    )
    top = rel[:, 1] >= (np.maximum.reduceat(rel[:, 1], offsets) - tol.tie_tolerance * size)[seg]
    key = np.where(top, rel[:, 0], np.inf)
    is_min = key == np.minimum.reduceat(key, offsets)[seg]
    first = np.flatnonzero(is_min)
    start = np.full(len(figures), -1)
    start[seg[first[::-1]]] = local[first[::-1]]  # earliest index wins
    order = offsets[seg] + (local + start[seg]) % counts[seg]
    rel = rel[order]
    mask = mask[order]
    prev = offsets[seg] + (local - 1) % counts[seg]
    nxt = offsets[seg] + (local + 1) % counts[seg]
    codes = lb.codes_from(rel, rel[prev], rel[nxt], mask, tol)
    rel.setflags(write=False)
    codes.setflags(write=False)
    out = []
    for k, f in enumerate(figures):
        a, b = int(offsets[k]), int(offsets[k] + counts[k])
        c = codes[a:b]
        r = rel[a:b]
        holes: tuple[HoleDescription, ...] = ()
        if f.holes:
            fl = np.array([1.0, flip[k]])
            holes = tuple(
                _describe_hole(h.points * fl - cen[k], h.curve_mask, r[0], tol) for h in f.holes
            )
        out.append(
            Description(
                WITH_HOLES if holes else WITHOUT_HOLES,
                type_curve_of(c),
                f.color,
                f.area,
                f.perimeter,
                BoundaryDescription(c, r),
                holes,
            )
        )
    return out


def _describe_hole(
    points: FloatArray, mask: BoolArray, first: FloatArray, tol: Tolerances
) -> HoleDescription:
    d = np.hypot(*(points - first).T)
    start = int(np.argmin(d))
    pts = np.roll(points, -start, axis=0)
    msk = np.roll(mask, -start)
    codes = lb.node_codes(pts, msk, tol)
    pts.setflags(write=False)
    codes.setflags(write=False)
    position = position_names(cones_of(hole_interval(pts, msk, first)))
    return HoleDescription(position, BoundaryDescription(codes, pts))


# ------------------------------------------------------------------------------- text form
def _f(v: float) -> str:
    return repr(float(v))


def _boundary_lines(b: BoundaryDescription, indent: str) -> list[str]:
    return [
        f"{indent}{_node_text(int(c))} @ ({_f(p[0])}, {_f(p[1])})"
        for c, p in zip(b.codes, b.points, strict=True)
    ]


def format_description(d: Description) -> str:
    """Stable, readable text form (exact floats); `parse` reads it back."""
    color = "none" if d.color is None else " ".join(_f(v) for v in d.color)
    lines = [
        HEADER,
        f"type: {d.type_hole}, {d.type_curve}",
        f"color: {color}",
        f"area: {_f(d.area)}",
        f"perimeter: {_f(d.perimeter)}",
        f"nodes: {len(d.outer.codes)}",
        *_boundary_lines(d.outer, "  "),
    ]
    for h in d.holes:
        lines.append(
            f"hole: {h.relation} [{', '.join(h.position)}] {h.boundary.type_curve}, "
            f"nodes: {len(h.boundary.codes)}"
        )
        lines.extend(_boundary_lines(h.boundary, "  "))
    return "\n".join(lines) + "\n"


__all__ = [
    "BoundaryDescription",
    "Description",
    "HoleDescription",
    "Node",
    "cones_of",
    "describe",
    "describe_many",
    "format_description",
    "hole_angles",
    "hole_angles_many",
    "hole_interval",
]
