"""`Figure`: one closed shape given by its relevant points, curve segments, holes and colour.

Coordinates are in any length unit (mm for designs, pixels for images). A figure with
``y_down=True`` has image coordinates (y pointing down); every label, orientation and rotation
is computed in the right-handed y-up frame ``(x, -y)``, so a figure taken from an image and the
same figure given in y-up millimetres describe identically.

Boundaries are normalised to one orientation: walked clockwise as seen by a viewer (clockwise in
the y-up frame), the paper's convention, under which a convex vertex lies left of the oriented
line from its previous to its next neighbour.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence, Sized
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from qshape import geometry as geo
from qshape.errors import FigureLimitError, InvalidFigureError, InvalidHoleError
from qshape.geometry import BoolArray, FloatArray
from qshape.limits import default_limits
from qshape.outline.params import OutlineParams
from qshape.outline.simplify import simplify_outlines
from qshape.theory.boundary import Boundary, boundaries_many, check_holes, measures_many, read_only

Color = tuple[float, float, float]


def _pose(local: FloatArray, center: Sequence[float], angle: float, y_down: bool) -> FloatArray:
    """Rotate y-up local points by ``angle`` (rad, CCW in y-up), flip if y_down, translate."""
    pts = geo.rotate(local, angle)
    if y_down:
        pts = pts * np.array([1.0, -1.0])
    return pts + np.asarray(center, dtype=np.float64)


def _as_color(color: Iterable[float] | None) -> Color | None:
    if color is None:
        return None
    try:
        rgb = tuple(float(v) for v in color)
    except (TypeError, ValueError) as exc:
        raise InvalidFigureError(f"color must be three numbers in [0, 1]: {exc}") from exc
    if len(rgb) != 3 or not all(math.isfinite(v) and 0.0 <= v <= 1.0 for v in rgb):
        raise InvalidFigureError(f"color must be three RGB numbers in [0, 1], got {color!r}")
    return (rgb[0], rgb[1], rgb[2])


HoleLike = Boundary | ArrayLike


@dataclass(frozen=True, eq=False)
class Figure:
    """One closed shape: relevant points of the outer boundary, curves, holes and colour.

    Build it with the constructors (`from_polygon`, `from_outline`, primitives), which accept
    either orientation and any start point.

    Attributes:
        points: Outer relevant points, shape (n, 2), figure coordinates, clockwise as seen.
        curve_mask: Shape (n,) bool, maximum-curvature points of curve segments.
        holes: The holes, each a `Boundary` in the same coordinates and orientation.
        color: RGB in [0, 1], or None when unknown.
        y_down: True when coordinates are image pixels with y pointing down.
        centroid: Area centroid, holes subtracted, figure coordinates, shape (2,). Derived.
        area: Area with arcs included and holes subtracted, in the unit squared. Derived.
        perimeter: Outer perimeter with arcs as circular arcs, in the unit. Derived.
        outer_centroid: Area centroid of the outer boundary alone (the origin of the cardinal
            frame), figure coordinates, shape (2,). Derived.
    """

    points: FloatArray
    curve_mask: BoolArray
    holes: tuple[Boundary, ...] = ()
    color: Color | None = None
    y_down: bool = False
    centroid: FloatArray = field(init=False)
    area: float = field(init=False)
    perimeter: float = field(init=False)
    outer_centroid: FloatArray = field(init=False)

    def __post_init__(self) -> None:
        """Validate, normalise orientation, check the holes and derive area and centroid.

        Raises:
            InvalidFigureError: Bad outer boundary or colour.
            InvalidHoleError: A hole outside the parent, crossing it, or overlapping a hole.
        """
        if not isinstance(self.y_down, bool | np.bool_):
            raise InvalidFigureError(f"y_down must be True or False, got {self.y_down!r}")
        limits = default_limits()
        if isinstance(self.holes, str | bytes) or not isinstance(self.holes, Iterable):
            raise InvalidFigureError(
                f"holes must be a sequence of hole boundaries (each (m, 2) points or a Boundary), "
                f"got {type(self.holes).__name__}"
            )
        object.__setattr__(self, "holes", tuple(self.holes))
        limits.check_count(len(self.holes), "max_holes", "figure: holes", FigureLimitError)
        outer = Boundary.make(self.points, self.curve_mask, y_down=self.y_down, what="figure")
        holes = tuple(
            Boundary.make(
                h.points if isinstance(h, Boundary) else h,
                h.curve_mask if isinstance(h, Boundary) else None,
                y_down=self.y_down,
                what=f"hole {k}",
            )
            for k, h in enumerate(self.holes)
        )
        total = len(outer.points) + sum(len(h.points) for h in holes)
        limits.check_count(total, "max_points", "figure: relevant points", FigureLimitError)
        self._derive(outer, holes, _as_color(self.color))

    def _derive(
        self,
        outer: Boundary,
        holes: tuple[Boundary, ...],
        color: Color | None,
        measured: tuple[float, FloatArray, float] | None = None,
    ) -> None:
        """Set the boundaries and colour, check the holes, derive area and centroid.

        ``measured`` is ``outer.measures()`` when already known (`figures_from_outlines`).
        """
        object.__setattr__(self, "points", outer.points)
        object.__setattr__(self, "curve_mask", outer.curve_mask)
        object.__setattr__(self, "holes", holes)
        object.__setattr__(self, "color", color)
        area, centroid, perim = outer.measures() if measured is None else measured
        object.__setattr__(self, "outer_centroid", read_only(centroid))
        object.__setattr__(self, "perimeter", perim)
        if holes:
            check_holes(outer, holes)
            moments = centroid * area
            for h in holes:
                ha, hc, _ = h.measures()
                area -= ha
                moments = moments - hc * ha
            centroid = moments / area
        object.__setattr__(self, "area", float(area))
        object.__setattr__(self, "centroid", read_only(np.asarray(centroid, dtype=np.float64)))

    @classmethod
    def _from_boundaries(
        cls,
        outer: Boundary,
        holes: tuple[Boundary, ...],
        color: Iterable[float] | None,
        measured: tuple[float, FloatArray, float] | None = None,
    ) -> Figure:
        """Figure from boundaries already validated (`Boundary.make`): no second validation."""
        fig = object.__new__(cls)
        object.__setattr__(fig, "y_down", outer.y_down)
        fig._derive(outer, holes, _as_color(color), measured)
        return fig

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Figure):
            return NotImplemented
        return self.outer == other.outer and self.holes == other.holes and self.color == other.color

    __hash__ = None  # type: ignore[assignment]

    @property
    def outer(self) -> Boundary:
        """The outer boundary as a `Boundary`."""
        return Boundary(self.points, self.curve_mask, self.y_down)

    # ---------------------------------------------------------------- constructors
    @classmethod
    def from_polygon(
        cls,
        points: ArrayLike,
        holes: Sequence[HoleLike] = (),
        color: Iterable[float] | None = None,
        *,
        curve_mask: ArrayLike | None = None,
        y_down: bool = False,
    ) -> Figure:
        """Figure from its relevant points (either orientation, any start point).

        Args:
            points: Relevant points, shape (n, 2), n >= 3. A closing copy of the first point is
                dropped.
            holes: Each hole as an (m, 2) array of relevant points or a `Boundary`.
            color: RGB in [0, 1], or None.
            curve_mask: Optional (n,) bool of maximum-curvature points (see `Figure`).
            y_down: Coordinates are image pixels with y pointing down.

        Raises:
            InvalidFigureError: See `Boundary.make`; InvalidHoleError for bad holes.
        """
        return cls(
            points,  # type: ignore[arg-type]
            curve_mask,  # type: ignore[arg-type]
            holes,  # type: ignore[arg-type]
            color,  # type: ignore[arg-type]
            y_down,
        )

    @classmethod
    def from_outline(
        cls,
        dense_points: ArrayLike,
        holes: Sequence[ArrayLike] = (),
        color: Iterable[float] | None = None,
        *,
        params: OutlineParams | None = None,
        y_down: bool = False,
    ) -> Figure:
        """Figure from dense closed outline(s) (a traced contour), simplified to relevant points.

        Args:
            dense_points: Closed outline, shape (k, 2), k >= 3, either orientation.
            holes: Dense outlines of the holes.
            color: RGB in [0, 1], or None.
            params: Simplification parameters; None loads ``configs/qshape.yaml``.
            y_down: Coordinates are image pixels with y pointing down.

        Raises:
            InvalidFigureError: Too few points, NaN/inf, zero area, or a simplified boundary
                that is not a simple polygon.
        """
        (out,) = figures_from_outlines([dense_points], [holes], [color], params, y_down=y_down)
        if isinstance(out, InvalidFigureError):
            raise out
        return out

    @classmethod
    def rectangle(
        cls,
        width: float,
        height: float,
        color: Iterable[float] | None = None,
        *,
        center: Sequence[float] = (0.0, 0.0),
        angle: float = 0.0,
        y_down: bool = False,
    ) -> Figure:
        """Axis-aligned rectangle centred on ``center``, rotated by ``angle`` rad (CCW, y-up)."""
        w, h = _positive(width, "width") / 2.0, _positive(height, "height") / 2.0
        local = np.array([[-w, h], [w, h], [w, -h], [-w, -h]])
        return cls(_pose(local, center, angle, y_down), None, (), color, y_down)  # type: ignore[arg-type]

    @classmethod
    def regular_polygon(
        cls,
        n: int,
        radius: float,
        color: Iterable[float] | None = None,
        *,
        center: Sequence[float] = (0.0, 0.0),
        angle: float = 0.0,
        y_down: bool = False,
    ) -> Figure:
        """Regular n-gon of circumradius ``radius`` with a vertex straight up at angle 0."""
        if int(n) != n or n < 3:
            raise InvalidFigureError(f"regular_polygon needs an integer n >= 3, got {n!r}")
        r = _positive(radius, "radius")
        t = math.pi / 2 - 2 * math.pi * np.arange(int(n)) / int(n)
        local = r * np.stack([np.cos(t), np.sin(t)], axis=1)
        return cls(_pose(local, center, angle, y_down), None, (), color, y_down)  # type: ignore[arg-type]

    @classmethod
    def circle(
        cls,
        radius: float,
        color: Iterable[float] | None = None,
        *,
        center: Sequence[float] = (0.0, 0.0),
        angle: float = 0.0,
        y_down: bool = False,
    ) -> Figure:
        """Circle as two semicircular arcs (4 relevant points: 2 ends, 2 curve points)."""
        local, mask = _circle_local(_positive(radius, "radius"))
        return cls(_pose(local, center, angle, y_down), mask, (), _as_color(color), y_down)

    @classmethod
    def semicircle(
        cls,
        radius: float,
        color: Iterable[float] | None = None,
        *,
        center: Sequence[float] = (0.0, 0.0),
        angle: float = 0.0,
        y_down: bool = False,
    ) -> Figure:
        """Half disc; ``center`` is the midpoint of its diameter, the arc bulges up at angle 0."""
        r = _positive(radius, "radius")
        local = np.array([[-r, 0.0], [0.0, r], [r, 0.0]])
        mask = np.array([False, True, False])
        return cls(_pose(local, center, angle, y_down), mask, (), _as_color(color), y_down)

    @classmethod
    def ring(
        cls,
        r_out: float,
        r_in: float,
        color: Iterable[float] | None = None,
        *,
        center: Sequence[float] = (0.0, 0.0),
        angle: float = 0.0,
        y_down: bool = False,
    ) -> Figure:
        """Disc of radius ``r_out`` with a concentric circular hole of radius ``r_in``."""
        ro, ri = _positive(r_out, "r_out"), _positive(r_in, "r_in")
        if ri >= ro:
            raise InvalidHoleError(f"ring needs r_in < r_out, got r_in={ri}, r_out={ro}")
        out, mask = _circle_local(ro)
        hole, hmask = _circle_local(ri)
        hb = Boundary.make(_pose(hole, center, angle, y_down), hmask, y_down=y_down, what="hole 0")
        return cls(_pose(out, center, angle, y_down), mask, (hb,), _as_color(color), y_down)


def figures_from_outlines(
    outlines: Sequence[ArrayLike],
    holes: Sequence[Sequence[ArrayLike]],
    colors: Sequence[Iterable[float] | None],
    params: OutlineParams | None = None,
    *,
    y_down: bool = False,
) -> list[Figure | InvalidFigureError]:
    """`Figure.from_outline` for many figures: every outline is simplified in one batch.

    Args:
        outlines: Dense outer outlines, each (k_i, 2).
        holes: For each figure, the dense outlines of its holes.
        colors: For each figure, RGB in [0, 1] or None.
        params: Simplification parameters; None loads ``configs/qshape.yaml``.
        y_down: Coordinates are image pixels with y pointing down.

    Returns:
        Per outline, the figure or the `InvalidFigureError` (or `InvalidHoleError`) it raised.
    """
    limits = default_limits()
    dense: list[ArrayLike] = list(outlines)
    whats = ["outline"] * len(dense)
    parents: list[int | None] = [None] * len(dense)
    for i, h in enumerate(holes):
        limits.check_count(len(h), "max_holes", "outline: holes", FigureLimitError)
        dense.extend(h)
        whats.extend(f"hole {k} outline" for k in range(len(h)))
        parents.extend([i] * len(h))
    for d, what in zip(dense, whats, strict=True):
        count = len(d) if isinstance(d, Sized) else 0
        limits.check_count(count, "max_dense_points", f"{what}: points", FigureLimitError)
    simple = simplify_outlines(dense, params, whats=whats, parents=parents)
    good = [k for k, x in enumerate(simple) if not isinstance(x, InvalidFigureError)]
    names = ["figure"] * len(outlines) + [
        w.removesuffix(" outline") for w in whats[len(outlines) :]
    ]
    made = boundaries_many(
        [simple[k] for k in good],  # type: ignore[misc]
        y_down=y_down,
        whats=[names[k] for k in good],
    )
    bounds: list[Boundary | InvalidFigureError] = list(simple)  # type: ignore[arg-type]
    for k, b in zip(good, made, strict=True):
        bounds[k] = b
    outers = [b for b in bounds[: len(outlines)] if isinstance(b, Boundary)]
    measured = iter(measures_many(outers))
    out: list[Figure | InvalidFigureError] = []
    at = len(outlines)
    for i, h in enumerate(holes):
        mine = bounds[at : at + len(h)]
        at += len(h)
        outer = bounds[i]
        m = next(measured) if isinstance(outer, Boundary) else None
        try:
            for b in (outer, *mine):
                if isinstance(b, InvalidFigureError):
                    raise b
            out.append(Figure._from_boundaries(outer, tuple(mine), colors[i], m))  # type: ignore[arg-type]
        except InvalidFigureError as exc:
            out.append(exc)
    return out


def _circle_local(r: float) -> tuple[FloatArray, BoolArray]:
    pts = np.array([[-r, 0.0], [0.0, r], [r, 0.0], [0.0, -r]])
    return pts, np.array([False, True, False, True])


def _positive(value: float, name: str) -> float:
    v = float(value)
    if not (math.isfinite(v) and v > 0.0):
        raise InvalidFigureError(f"{name} must be a finite number > 0, got {value!r}")
    return v


__all__ = ["Color", "Figure", "figures_from_outlines"]
