"""Tile outlines of straight edges and circular arcs (DXF-style bulges): `Loop`, `TilePath`.

A `TilePath` gives the dense outline, the relevant points (vertices plus the middle,
maximum-curvature point of each arc), area and centroid, jittered copies, and the
`qshape.Figure` of its relevant points.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from qshape import geometry as geo
from qshape.errors import DesignError
from qshape.geometry import BoolArray, FloatArray
from qshape.theory.boundary import Boundary
from qshape.theory.figure import Figure


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
        v = geo.rotate(self.vertices, angle) * scale + np.asarray(shift, dtype=np.float64)
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
        return np.asarray(np.where((b == 0.0)[:, None], straight, arc), dtype=np.float64)

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

    def made_vertices(self, arc_step: float) -> FloatArray:
        """The vertices of the tile as made, shape (m, 2).

        Straight edges keep their ends; arcs are cut into at least two pieces, each at most
        ``arc_step`` long. The cell builds its tiles' meshes from these, each vertex moved by
        its own manufacturing deviation.
        """
        counts = np.where(
            self.bulges == 0.0, 1, np.maximum(2, np.ceil(self.edge_lengths() / arc_step))
        ).astype(int)
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
    ) -> Figure:
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


__all__ = ["Loop", "TilePath"]
