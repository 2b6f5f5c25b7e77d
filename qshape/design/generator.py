"""Procedural mosaic designs drawn from a `numpy.random.Generator`: `DesignGenerator`.

A drawn design has a number of shape-and-colour classes, each with one or more copies, laid on
a grid of cells over the mesh (one tile per cell, random cells, random turns). A class's shape
is one of the `SHAPE_FAMILIES`:

- ``regular``: a regular polygon (3 to 8 sides), the ``regular_polygon`` kind;
- ``convex``: a random convex polygon (vertices on a circle at random angles);
- ``concave``: a random star-shaped polygon with at least one reflex corner;
- ``named``: a parallelogram, trapezoid, kite, arrow, five-pointed star, quarter disc or L;
- ``arcs``: a convex polygon whose edges are arcs bowing out (positive bulge) or in
  (negative), or straight;
- ``rounded``: a convex polygon with corners rounded by arcs tangent to both edges;
- ``bite``: a convex polygon with a concave arc bitten out of, or a bulge added to, part of
  an edge;
- ``thin``: thin, concave tiles with sharp tips: an arrowhead (a dart: a tip of 18-32 deg, two
  barbs and a notch), a four-pointed star with thin points, or a chevron.

Any class may get holes (circle, square, rectangle, triangle, regular polygon), centred on the
outline's area centroid or off it, of a symmetry other than the outline's. Every feature stays
above the smallest-feature parameters: straight edges, arc chords, hole sizes and the material
between a hole and the outline are at least ``min_feature_mm``, arc sagittas at least
``min_sagitta_mm``; and the turn is one the camera fixes (the turn cues of
`qshape.design.turn_cues` at or above the design rules' ``min_turn_shift_mm``,
``min_asymmetry_mm``, ``min_hole_turn_mm`` and ``min_turn_capability``: no nearly round or
nearly symmetric tile, no hole whose turns differ by less than the camera sees, no tile whose
own manufacturing deviation leaves its turn loose). The result is validated by the design
loader's own checks (`Design.from_dict`); a draw failing them is drawn again (``max_tries``).

The bundled families are special cases in their shapes: ``square_grid`` and ``hexagon`` are
the ``regular`` family with 4 or 6 sides at one size and no turn (``families: {regular: 1}``,
``size_mm`` a single value, ``turns_deg: 0``); ``paper_mixed``'s holed square is a ``regular``
square with an off-centre square hole. Their layouts are not: the generator lays tiles in a
grid of cells as wide as a tile's circumscribed circle, so a bundled square grid's 5 x 5
squares of 40 mm take 3 x 3 cells here.

Parameters: `qshape.design.generator_config.GeneratorConfig` (bundled values in
``configs/design_generator.yaml``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
import shapely

from qshape import geometry as geo
from qshape.design.features import edge_features
from qshape.design.generator_config import (
    HOLE_KINDS,
    NAMED,
    SHAPE_FAMILIES,
    GeneratorConfig,
)
from qshape.design.model import Design
from qshape.design.paths import TilePath
from qshape.design.rules import DesignRules
from qshape.design.shape_maps import (
    Shape,
    circumradius,
    hole_shape,
    inradius,
    polygon_shape,
    rounded_polygon_shape,
    scaled_shape,
)
from qshape.design.shapes import tile_path
from qshape.design.slot import Slot
from qshape.design.turn_cues import rule_cues, weak_cues
from qshape.errors import DesignError, GeneratorError, InvalidFigureError

_HOLE_ORDER = {"circle": 0, "square": 4, "rectangle": 2, "triangle": 3, "pentagon": 5, "hexagon": 6}
KEEP_ABOVE_MM = 0.01
"""[mm] drawn features stay this far above their limits (design files round to 0.1 um, and
the loader's small-feature check is strict)."""


class DesignGenerator:
    """Draws random designs (see the module docstring).

    Args:
        config: Parameters (None: the bundled ``configs/design_generator.yaml``).
        rules: Design validation rules of the drawn designs.
    """

    def __init__(
        self, config: GeneratorConfig | None = None, rules: DesignRules | None = None
    ) -> None:
        self.config = config if config is not None else GeneratorConfig.load()
        self.rules = rules if rules is not None else DesignRules()

    # ------------------------------------------------------------------------------ designs
    def draw(self, rng: np.random.Generator, name: str = "random") -> Design:
        """One random design, validated by the design loader.

        Raises:
            GeneratorError: No valid design in ``max_tries`` draws (parameters too tight).
        """
        if not isinstance(rng, np.random.Generator):
            raise GeneratorError(f"rng must be a numpy.random.Generator, got {type(rng).__name__}")
        last = ""
        for _ in range(self.config.max_tries):
            data = self.draw_mapping(rng, name)
            try:
                return Design.from_dict(data, rules=self.rules, source=f"generated design {name!r}")
            except DesignError as exc:  # pragma: no cover - kept for safety; draws are checked
                last = str(exc)
        raise GeneratorError(f"no valid design in {self.config.max_tries} draws; last: {last}")

    def draw_mapping(self, rng: np.random.Generator, name: str = "random") -> dict[str, Any]:
        """The design file mapping of one random design (not yet loaded)."""
        cfg = self.config
        n_tiles = int(rng.integers(cfg.tiles[0], cfg.tiles[1] + 1))
        n_classes = int(rng.integers(cfg.classes[0], min(cfg.classes[1], n_tiles) + 1))
        classes: list[tuple[Shape, str, str]] = []
        for _ in range(n_classes):
            if classes and rng.random() < cfg.recolor_probability:
                shape, family, _ = classes[int(rng.integers(len(classes)))]
                used = {c for s, _, c in classes if s is shape}
                free = [c for c in cfg.palette if c not in used]
                if free:
                    classes.append((shape, family, free[int(rng.integers(len(free)))]))
                    continue
            family, shape = self._draw_class(rng)
            classes.append((shape, family, cfg.palette[int(rng.integers(len(cfg.palette)))]))
        # Every class at least once, the rest as copies of random classes.
        members = list(range(n_classes)) + rng.integers(0, n_classes, n_tiles - n_classes).tolist()
        cols, rows = cfg.cells()
        pitch = cfg.size_mm[1] + cfg.joint_mm
        chosen = rng.choice(cols * rows, size=n_tiles, replace=False)
        used_w = cols * pitch - cfg.joint_mm
        used_h = rows * pitch - cfg.joint_mm
        x0 = (cfg.mesh_mm[0] - used_w) / 2.0 + (pitch - cfg.joint_mm) / 2.0
        y0 = (cfg.mesh_mm[1] - used_h) / 2.0 + (pitch - cfg.joint_mm) / 2.0
        slots = []
        counts: dict[int, int] = {}
        for cell, k in zip(chosen.tolist(), members, strict=True):
            shape, family, color = classes[k]
            counts[k] = counts.get(k, 0) + 1
            c, r = divmod(int(cell), rows)
            slots.append(
                {
                    "name": f"c{k}_{family}_{counts[k]}",
                    "shape": shape,
                    "color": color,
                    "pose": {
                        "x": round(x0 + c * pitch, 4),
                        "y": round(y0 + r * pitch, 4),
                        "angle": round(float(rng.uniform(0.0, cfg.turns_deg)), 3),
                    },
                }
            )
        return {
            "name": name,
            "description": (
                f"Random design: {n_tiles} tiles of {n_classes} classes (qshape.design.generator)."
            ),
            "mesh": {"width": cfg.mesh_mm[0], "height": cfg.mesh_mm[1]},
            "joint": cfg.joint_mm,
            "grout_color": cfg.grout_color,
            "slots": slots,
        }

    def _draw_class(self, rng: np.random.Generator) -> tuple[str, Shape]:
        """A family and a shape of it.

        A family that cannot be drawn at the drawn size is drawn again with another size (and
        family), up to ``max_tries`` times.
        """
        last: GeneratorError | None = None
        for _ in range(self.config.max_tries):
            family = self._family(rng)
            size = float(rng.uniform(*self.config.size_mm))
            try:
                return family, self.draw_shape(rng, family, size, tries=20)
            except GeneratorError as exc:
                last = exc
        assert last is not None
        raise last

    def _family(self, rng: np.random.Generator) -> str:
        names = [f for f in SHAPE_FAMILIES if self.config.families.get(f, 0.0) > 0.0]
        w = np.array([self.config.families[f] for f in names], dtype=float)
        return names[int(rng.choice(len(names), p=w / w.sum()))]

    # ------------------------------------------------------------------------------ shapes
    def draw_shape(
        self, rng: np.random.Generator, family: str, size_mm: float, tries: int = 0
    ) -> Shape:
        """One shape mapping of ``family`` of size at most ``size_mm``, features above the limits.

        The size is twice the largest distance from the area centroid, holes included;
        ``tries`` is the number of draws before giving up (0: ``max_tries``).

        Raises:
            GeneratorError: Unknown family, or no valid shape in ``max_tries`` draws.
        """
        if family not in SHAPE_FAMILIES:
            raise GeneratorError(
                f"unknown shape family {family!r}; allowed: {list(SHAPE_FAMILIES)}"
            )
        cfg = self.config
        draw: Callable[[np.random.Generator, float], Shape | None] = getattr(
            self, f"_draw_{family}"
        )
        tries = tries or cfg.max_tries
        for _ in range(tries):
            shape = draw(rng, size_mm / 2.0)
            if shape is None:
                continue
            fitted = self._fit(shape, size_mm / 2.0)
            if fitted is None:
                continue
            if rng.random() < cfg.hole_probability:
                holed = self._add_holes(rng, fitted)
                # An off-centre hole moves the area centroid: fit again.
                fitted = None if holed is None else self._fit(holed, size_mm / 2.0)
                if fitted is None:
                    continue
            if self._valid(fitted, size_mm / 2.0):
                return fitted
        raise GeneratorError(
            f"no {family} shape of size {size_mm:g} mm with every feature >= min_feature_mm "
            f"({cfg.min_feature_mm:g}) and min_sagitta_mm ({cfg.min_sagitta_mm:g}) in "
            f"{tries} draws: lower them or raise size_mm"
        )

    def _fit(self, shape: Shape, radius: float) -> Shape | None:
        """The shape scaled so its largest distance from its area centroid is ``radius``."""
        try:
            path = tile_path(shape, "generated shape")
        except DesignError:
            return None
        area, c = path.area_centroid(self.rules.outline_step_mm)
        if not area > 0.0:
            return None
        far = float(np.max(np.hypot(*(path.outer.dense(self.rules.outline_step_mm) - c).T)))
        return scaled_shape(shape, radius / far)

    def _valid(self, shape: Shape, radius: float) -> bool:
        """Every feature above the limits, the outline simple, holes inside with material.

        The turn too must be one the camera fixes: every cue of `qshape.design.turn_cues`
        at or above the design rules' limits (the loader warns below them).
        """
        cfg = self.config
        slot = Slot("probe", shape, (0.5, 0.5, 0.5), 0.0, 0.0, 0.0, self.rules)
        try:
            path = slot.local_path
            slot.figure()
        except (DesignError, InvalidFigureError):
            return False
        step = self.rules.outline_step_mm
        outer = path.outer.dense(step)
        if geo.self_intersects(outer) or float(np.max(np.hypot(*outer.T))) > radius + 1e-6:
            return False
        for f in edge_features(slot):
            if f.chord_mm < cfg.min_feature_mm + KEEP_ABOVE_MM:
                return False
            if f.curved and abs(f.sagitta_mm) < cfg.min_sagitta_mm + KEEP_ABOVE_MM:
                return False
            whole_turn = abs(f.sagitta_mm) >= f.chord_mm / 2.0 - 1e-9
            if f.curved and not whole_turn and f.chord_mm < cfg.min_arc_chord_mm + KEEP_ABOVE_MM:
                return False
        if not self._holes_ok(path):
            return False
        return not weak_cues(rule_cues(slot, self.rules), self.rules)

    def _holes_ok(self, path: TilePath) -> bool:
        step = self.rules.outline_step_mm
        if not path.holes:
            return True
        solid = shapely.Polygon(path.outer.dense(step))
        inner = solid.buffer(-self.config.min_feature_mm)
        polys = [shapely.Polygon(h.dense(step)) for h in path.holes]
        for k, p in enumerate(polys):
            if not (p.is_valid and inner.contains(p)):
                return False
            for q in polys[k + 1 :]:
                if p.distance(q) < self.config.min_feature_mm:
                    return False
        return True

    # The families: each draws an outline of about unit radius about the origin.
    def _draw_regular(self, rng: np.random.Generator, r: float) -> Shape:
        return {"kind": "regular_polygon", "sides": int(rng.integers(3, 9)), "radius": r}

    def _convex_vertices(self, rng: np.random.Generator, r: float, lo: int, hi: int) -> np.ndarray:
        n = int(rng.integers(lo, hi + 1))
        # Angles at least a third of the mean spacing apart keep every edge long.
        gaps = rng.uniform(1.0, 3.0, n)
        t = np.cumsum(gaps / gaps.sum() * 2.0 * math.pi) + rng.uniform(0.0, 2.0 * math.pi)
        return np.stack([r * np.cos(t), r * np.sin(t)], axis=1)

    def _draw_convex(self, rng: np.random.Generator, r: float) -> Shape:
        return polygon_shape(self._convex_vertices(rng, r, 3, 8))

    def _draw_concave(self, rng: np.random.Generator, r: float) -> Shape:
        n = int(rng.integers(4, 10))
        gaps = rng.uniform(1.0, 2.0, n)
        t = np.cumsum(gaps / gaps.sum() * 2.0 * math.pi)
        radii = rng.uniform(0.7, 1.0, n) * r
        inward = rng.choice(n, size=max(1, int(rng.integers(1, n // 2 + 1))), replace=False)
        radii[inward] *= rng.uniform(0.35, 0.6, len(inward))
        return polygon_shape(np.stack([radii * np.cos(t), radii * np.sin(t)], axis=1))

    def _draw_named(self, rng: np.random.Generator, r: float) -> Shape:
        """A named shape at unit size (`_fit` scales it)."""
        del r
        kind = NAMED[int(rng.integers(len(NAMED)))]
        a, b = rng.uniform(0.45, 1.0, 2)
        if kind == "parallelogram":
            s = rng.uniform(0.2, 0.6)
            return polygon_shape([[0, 0], [1, 0], [1 + s, b], [s, b]])
        if kind == "trapezoid":
            s = rng.uniform(0.15, 0.35)
            return polygon_shape([[0, 0], [1, 0], [1 - s, b], [s, b]])
        if kind == "kite":
            return polygon_shape([[0, -1], [a, 0], [0, b * 0.6], [-a, 0]])
        if kind == "arrow":
            w, head = rng.uniform(0.25, 0.4), rng.uniform(0.3, 0.5)
            return polygon_shape(
                [
                    [0, -w / 2],
                    [1 - head, -w / 2],
                    [1 - head, -0.5],
                    [1, 0],
                    [1 - head, 0.5],
                    [1 - head, w / 2],
                    [0, w / 2],
                ]
            )
        if kind == "star":
            t = math.pi / 2 + math.pi * np.arange(10) / 5
            rad = np.where(np.arange(10) % 2 == 0, 1.0, rng.uniform(0.45, 0.6))
            return polygon_shape(np.stack([rad * np.cos(t), rad * np.sin(t)], axis=1))
        if kind == "quarter_disc":
            bulge = math.tan(math.pi / 8)  # a quarter turn
            return {"kind": "polygon", "vertices": [[0, 0], [1, 0, bulge], [0, 1]]}
        w = rng.uniform(0.35, 0.55)
        return polygon_shape([[0, 0], [1, 0], [1, w], [w, w], [w, 1], [0, 1]])

    def _draw_thin(self, rng: np.random.Generator, r: float) -> Shape:
        """A thin, concave tile with sharp tips at unit size (`_fit` scales it)."""
        del r
        kind = int(rng.integers(3))
        if kind == 0:  # arrowhead: tip at (1, 0), barbs at (0, +-w/2), notch at (n, 0)
            w = 2.0 * math.tan(math.radians(rng.uniform(9.0, 16.0)))
            n = rng.uniform(0.15, 0.4)
            return polygon_shape([[0.0, -w / 2], [1.0, 0.0], [0.0, w / 2], [n, 0.0]])
        if kind == 1:  # four-pointed star, the points thin, one pair longer
            t = math.pi / 4 * np.arange(8)
            long = rng.uniform(1.0, 1.6)
            rad = np.array([long, 0.0, 1.0, 0.0, long, 0.0, 1.0, 0.0])
            rad[1::2] = rng.uniform(0.22, 0.32)
            return polygon_shape(np.stack([rad * np.cos(t), rad * np.sin(t)], axis=1))
        w, d = rng.uniform(0.25, 0.4), rng.uniform(0.35, 0.6)  # chevron: a V of two thin arms
        return polygon_shape(
            [[0.0, 0.0], [1.0, d], [1.0, d + w], [0.0, w], [-1.0, d + w], [-1.0, d]]
        )

    def _arc_bulge(self, rng: np.random.Generator, chord: float, sign: float) -> float:
        """A bulge of sagitta uniform in [min_sagitta_mm, max_sagitta_ratio x chord].

        0 (straight) when the chord is too short for the smallest sagitta.
        """
        cfg = self.config
        top = cfg.max_sagitta_ratio * chord
        if top < cfg.min_sagitta_mm or chord < cfg.min_arc_chord_mm:
            return 0.0
        return sign * 2.0 * float(rng.uniform(cfg.min_sagitta_mm, top)) / chord

    def _draw_arcs(self, rng: np.random.Generator, r: float) -> Shape:
        v = self._convex_vertices(rng, r, 3, 6)
        n = len(v)
        lengths = np.hypot(*(np.roll(v, -1, axis=0) - v).T)
        b = np.zeros(n)
        curved = rng.choice(n, size=int(rng.integers(1, n + 1)), replace=False)
        for i in curved.tolist():
            b[i] = self._arc_bulge(rng, float(lengths[i]), 1.0 if rng.random() < 0.5 else -1.0)
        return polygon_shape(v, b)

    def _draw_rounded(self, rng: np.random.Generator, r: float) -> Shape | None:
        cfg = self.config
        if rng.random() < 0.5:
            a = rng.uniform(0.5, 1.0)
            v = np.array([[-1.0, -a], [1.0, -a], [1.0, a], [-1.0, a]]) * r / math.hypot(1.0, a)
        else:
            v = self._convex_vertices(rng, r, 3, 4)
        v = v if geo.signed_area(v) > 0 else v[::-1]
        d = np.roll(v, -1, axis=0) - v
        heading = np.arctan2(d[:, 1], d[:, 0])
        turn = np.abs(geo.wrap_angles(heading - np.roll(heading, 1)))  # at each vertex
        cot = 1.0 / np.tan((math.pi - turn) / 2.0)  # tangent length per unit radius
        lengths = np.hypot(d[:, 0], d[:, 1])
        # Some corners (at least one) rounded, all by one radius: every arc at least
        # min_sagitta_mm deep with a chord of at least min_arc_chord_mm, every straight edge
        # left at least the smallest feature long.
        rounded = rng.random(len(v)) < 0.5
        rounded[int(rng.integers(len(v)))] = True
        t = turn[rounded]
        rho_lo = max(
            cfg.min_sagitta_mm / float(np.min(1.0 - np.cos(t / 2.0))),
            cfg.min_arc_chord_mm / float(np.min(2.0 * np.sin(t / 2.0))),
        )
        cot = np.where(rounded, cot, 0.0)
        rho_hi = float(np.min((lengths - cfg.min_feature_mm) / (cot + np.roll(cot, -1) + 1e-12)))
        if rho_hi < rho_lo:
            return None
        return rounded_polygon_shape(v, float(rng.uniform(rho_lo, rho_hi)), rounded)

    def _draw_bite(self, rng: np.random.Generator, r: float) -> Shape | None:
        cfg = self.config
        if rng.random() < 0.5:
            v = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]]) * r / math.sqrt(2)
        else:
            v = self._convex_vertices(rng, r, 3, 6)
        n = len(v)
        lengths = np.hypot(*(np.roll(v, -1, axis=0) - v).T)
        k = int(rng.choice(n, p=lengths / lengths.sum()))
        p, q, length = v[k], v[(k + 1) % n], float(lengths[k])
        w_lo = max(cfg.min_arc_chord_mm, cfg.min_sagitta_mm / cfg.max_sagitta_ratio)
        w_hi = length - 2.0 * cfg.min_feature_mm
        if w_hi < w_lo:
            return None  # too short an edge for a bite
        w = float(rng.uniform(w_lo, w_hi))
        s0 = float(rng.uniform(cfg.min_feature_mm, length - cfg.min_feature_mm - w)) / length
        a, b = p + (q - p) * s0, p + (q - p) * (s0 + w / length)
        sign = -1.0 if rng.random() < 0.7 else 1.0
        verts = [*v[: k + 1].tolist(), a.tolist(), b.tolist(), *v[k + 1 :].tolist()]
        bulges = [0.0] * len(verts)
        bulges[k + 1] = self._arc_bulge(rng, w, sign)
        return polygon_shape(np.array(verts), np.array(bulges))

    # ------------------------------------------------------------------------------- holes
    def _order(self, shape: Shape) -> int:
        """Rotational symmetry order of the outline (0: continuous)."""
        return Slot("probe", shape, (0.5, 0.5, 0.5), 0.0, 0.0, 0.0, self.rules).symmetry

    def _add_holes(self, rng: np.random.Generator, shape: Shape) -> Shape | None:
        cfg = self.config
        path = tile_path(shape, "generated shape")
        step = self.rules.outline_step_mm
        solid = shapely.Polygon(path.outer.dense(step))
        room = solid.buffer(-cfg.min_feature_mm)
        if room.is_empty:
            return None
        _, c = TilePath(path.outer).area_centroid(step)
        order = self._order(shape)
        count = 2 if rng.random() < cfg.two_hole_probability else 1
        holes = []
        for k in range(count):
            kinds = [h for h in HOLE_KINDS if _HOLE_ORDER[h] != order]
            kind = kinds[int(rng.integers(len(kinds)))]
            # Inscribed size between the smallest feature and what the room allows.
            fit = inradius(room, c) if k == 0 else 0.0
            # Off-centre holes move the area centroid and the tile is fitted again (shrunk a
            # little): holes start a fifth above the smallest feature.
            lo = 1.2 * cfg.min_feature_mm
            hi = max(lo, min(0.6 * inradius(solid, c), 2.0 * fit))
            size = float(rng.uniform(lo, hi))
            centred = k == 0 and rng.random() < cfg.centred_hole_probability
            hole = hole_shape(kind, size, rng)
            if centred:
                at = c
            else:
                # Anywhere the whole hole (its circumscribed circle) keeps the smallest
                # feature of material, at least the smallest feature off the centroid.
                reach = room.buffer(-circumradius(hole))
                if reach.is_empty:
                    return None
                minx, miny, maxx, maxy = reach.bounds
                for _ in range(_PLACE_TRIES):
                    at = np.array([rng.uniform(minx, maxx), rng.uniform(miny, maxy)])
                    far = float(np.hypot(*(at - c))) >= cfg.min_feature_mm
                    if far and reach.contains(shapely.Point(float(at[0]), float(at[1]))):
                        break
                else:
                    return None
            hole.update({"x": float(at[0]), "y": float(at[1]), "angle": float(rng.uniform(0, 360))})
            holes.append(hole)
        return {**shape, "holes": holes}


_PLACE_TRIES = 50
"""Random positions tried for an off-centre hole."""


def random_design(
    rng: np.random.Generator, config: GeneratorConfig | None = None, name: str = "random"
) -> Design:
    """One random design from ``rng`` (see `DesignGenerator.draw`)."""
    return DesignGenerator(config).draw(rng, name)


__all__ = ["DesignGenerator", "random_design"]
