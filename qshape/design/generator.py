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
  an edge.

Any class may get holes (circle, square, rectangle, triangle, regular polygon), centred on the
outline's area centroid or off it, of a symmetry other than the outline's. Every feature stays
above the smallest-feature parameters: straight edges, arc chords, hole sizes and the material
between a hole and the outline are at least ``min_feature_mm``, arc sagittas at least
``min_sagitta_mm``. The result is validated by the design loader's own checks
(`Design.from_dict`); a draw failing them is drawn again (``max_tries``).

The bundled families are special cases in their shapes: ``square_grid`` and ``hexagon`` are
the ``regular`` family with 4 or 6 sides at one size and no turn (``families: {regular: 1}``,
``size_mm`` a single value, ``turns_deg: 0``); ``paper_mixed``'s holed square is a ``regular``
square with an off-centre square hole. Their layouts are not: the generator lays tiles in a
grid of cells as wide as a tile's circumscribed circle, so a bundled square grid's 5 x 5
squares of 40 mm take 3 x 3 cells here.

Bundled parameters: ``configs/design_generator.yaml``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import shapely

from configs import ConfigError, check_field_types, load_config
from qshape import geometry as geo
from qshape.design.features import edge_features
from qshape.design.model import Design
from qshape.design.paths import TilePath
from qshape.design.rules import DesignRules
from qshape.design.shapes import tile_path
from qshape.design.slot import Slot
from qshape.design.values import parse_color
from qshape.errors import DesignError, GeneratorError, InvalidFigureError

SHAPE_FAMILIES = ("regular", "convex", "concave", "named", "arcs", "rounded", "bite")
"""Shape families a class is drawn from (see the module docstring)."""
HOLE_KINDS = ("circle", "square", "rectangle", "triangle", "pentagon", "hexagon")
"""Hole shapes."""
_HOLE_ORDER = {"circle": 0, "square": 4, "rectangle": 2, "triangle": 3, "pentagon": 5, "hexagon": 6}
NAMED = ("parallelogram", "trapezoid", "kite", "arrow", "star", "quarter_disc", "ell")
"""Shapes of the ``named`` family."""
DEFAULT_PALETTE = (
    "#c0392b",
    "#2e6fd1",
    "#e8c33a",
    "#2aa39a",
    "#e07b2a",
    "#3f9e4d",
    "#8e4fb5",
    "#f2f2ee",
    "#d96aa7",
)
"""Colours of the bundled designs and a few more, '#rrggbb'. No near-black: the input belt is
near-black (RGB 0.12), and a tile of its colour is not seen on it."""
KEEP_ABOVE_MM = 0.01
"""[mm] drawn features stay this far above their limits (design files round to 0.1 um, and
the loader's small-feature check is strict)."""
CONFIG_NAME = "design_generator"
"""Bundled parameter file, ``configs/design_generator.yaml``."""


@dataclass(frozen=True)
class GeneratorConfig:
    """Parameters of `DesignGenerator` (lengths in [mm], ranges inclusive ``(low, high)``).

    Attributes:
        mesh_mm: Mesh (width, height), in [mm].
        joint_mm: Joint between tiles, in [mm].
        margin_mm: Border of the mesh left empty, in [mm].
        tiles: Range of the number of slots of a design.
        classes: Range of the number of shape-and-colour classes (at most the slots drawn;
            slots beyond it are further copies of the classes).
        size_mm: Range of a tile's size: twice its largest distance from its area centroid,
            in [mm]. The mesh is cut into cells of ``size_mm[1] + joint_mm``.
        min_feature_mm: Smallest straight edge, arc chord, hole size (inscribed diameter) and
            material between a hole and the outline or another hole, in [mm].
        min_sagitta_mm: Smallest depth of an arc off its chord, in [mm].
        min_arc_chord_mm: Smallest chord of an arc, in [mm] (arcs turning less than 180 deg).
        max_sagitta_ratio: Largest arc sagitta / chord of the ``arcs`` and ``bite`` families
            (dimensionless; 0.5 is a half circle).
        families: Weight of each of `SHAPE_FAMILIES` (missing: 0; at least one > 0).
        hole_probability: Chance that a class has holes.
        two_hole_probability: Chance that a holed class has a second hole.
        centred_hole_probability: Chance that a class's first hole is centred.
        recolor_probability: Chance that a new class repeats an earlier class's shape in
            another colour.
        turns_deg: Slot turns are drawn uniform in [0, turns_deg) (0: every slot at 0 deg).
        palette: Colours, '#rrggbb' (at least one).
        grout_color: Joint colour, '#rrggbb'.
        max_tries: Draws of one shape (or one design) before giving up with `GeneratorError`.
    """

    mesh_mm: tuple[float, float] = (230.0, 230.0)
    joint_mm: float = 2.0
    margin_mm: float = 3.0
    tiles: tuple[int, int] = (6, 16)
    classes: tuple[int, int] = (3, 9)
    size_mm: tuple[float, float] = (30.0, 50.0)
    min_feature_mm: float = 6.0
    min_sagitta_mm: float = 5.0
    min_arc_chord_mm: float = 20.0
    max_sagitta_ratio: float = 0.3
    families: dict[str, float] = field(default_factory=lambda: dict.fromkeys(SHAPE_FAMILIES, 1.0))
    hole_probability: float = 0.3
    two_hole_probability: float = 0.2
    centred_hole_probability: float = 0.5
    recolor_probability: float = 0.2
    turns_deg: float = 360.0
    palette: tuple[str, ...] = DEFAULT_PALETTE
    grout_color: str = "#d9d4c7"
    max_tries: int = 200

    def __post_init__(self) -> None:
        """Raise `GeneratorError` naming the parameter and what is allowed."""
        try:
            check_field_types(self)
        except ConfigError as exc:
            raise GeneratorError(str(exc)) from exc
        pre = "GeneratorConfig."
        for name in (
            "joint_mm",
            "min_feature_mm",
            "min_sagitta_mm",
            "min_arc_chord_mm",
            "max_sagitta_ratio",
        ):
            if not getattr(self, name) > 0.0:
                raise GeneratorError(f"{pre}{name} must be > 0, got {getattr(self, name)!r}")
        if min(self.mesh_mm) <= 0.0:
            raise GeneratorError(f"{pre}mesh_mm must be two sizes > 0, got {self.mesh_mm}")
        if self.margin_mm < 0.0:
            raise GeneratorError(f"{pre}margin_mm must be >= 0, got {self.margin_mm}")
        for name in ("tiles", "classes"):
            lo, hi = getattr(self, name)
            if not 1 <= lo <= hi:
                raise GeneratorError(f"{pre}{name} must be (low, high) with 1 <= low <= high")
        if self.classes[0] > self.tiles[1]:
            raise GeneratorError(
                f"{pre}classes: the least number of classes ({self.classes[0]}) exceeds the "
                f"most slots ({self.tiles[1]}); allowed: classes[0] <= tiles[1]"
            )
        lo_s, hi_s = self.size_mm
        least = 4.0 * self.min_feature_mm
        if not least <= lo_s <= hi_s:
            raise GeneratorError(
                f"{pre}size_mm must be (low, high) with 4 x min_feature_mm ({least:g}) <= low "
                f"<= high, got {self.size_mm}"
            )
        if not self.max_sagitta_ratio <= 0.5:
            raise GeneratorError(
                f"{pre}max_sagitta_ratio must be in (0, 0.5], got {self.max_sagitta_ratio}"
            )
        if self.min_sagitta_mm > self.max_sagitta_ratio * lo_s:
            raise GeneratorError(
                f"{pre}min_sagitta_mm {self.min_sagitta_mm} is deeper than max_sagitta_ratio x "
                f"size_mm[0] ({self.max_sagitta_ratio * lo_s:g} mm) allows"
            )
        unknown = sorted(set(self.families) - set(SHAPE_FAMILIES))
        if unknown:
            raise GeneratorError(
                f"{pre}families: unknown {unknown}; allowed: {list(SHAPE_FAMILIES)}"
            )
        weights = list(self.families.values())
        if any(not (math.isfinite(w) and w >= 0.0) for w in weights) or not sum(weights) > 0:
            raise GeneratorError(
                f"{pre}families: weights must be >= 0 with one > 0, got {dict(self.families)}"
            )
        for name in (
            "hole_probability",
            "two_hole_probability",
            "centred_hole_probability",
            "recolor_probability",
        ):
            if not 0.0 <= getattr(self, name) <= 1.0:
                raise GeneratorError(f"{pre}{name} must be in [0, 1], got {getattr(self, name)}")
        if not 0.0 <= self.turns_deg <= 360.0:
            raise GeneratorError(f"{pre}turns_deg must be in [0, 360], got {self.turns_deg}")
        if not self.palette:
            raise GeneratorError(f"{pre}palette must hold at least one '#rrggbb' colour")
        try:
            for c in (*self.palette, self.grout_color):
                parse_color(c, f"{pre}palette")
        except DesignError as exc:
            raise GeneratorError(str(exc)) from exc
        if self.max_tries < 1:
            raise GeneratorError(f"{pre}max_tries must be >= 1, got {self.max_tries}")
        cells = self.cells()
        if self.tiles[1] > cells[0] * cells[1]:
            raise GeneratorError(
                f"{pre}tiles: a {self.mesh_mm[0]:g} x {self.mesh_mm[1]:g} mm mesh (margin "
                f"{self.margin_mm:g} mm) holds at most {cells[0] * cells[1]} tiles of size_mm up "
                f"to {hi_s:g} at a {self.joint_mm:g} mm joint; asked for up to {self.tiles[1]}: "
                "lower tiles or size_mm, or enlarge mesh_mm"
            )

    @classmethod
    def load(
        cls, name_or_path: str | Path | None = CONFIG_NAME, **overrides: Any
    ) -> GeneratorConfig:
        """Load the bundled ``configs/design_generator.yaml`` (or another file) strictly.

        Raises:
            configs.ConfigError: Unknown key or wrong type.
            GeneratorError: A value out of range.
        """
        return load_config(cls, name_or_path, **overrides)

    def cells(self) -> tuple[int, int]:
        """(columns, rows) of the mesh's cells, one tile each."""
        pitch = self.size_mm[1] + self.joint_mm
        usable = [m - 2.0 * self.margin_mm + self.joint_mm for m in self.mesh_mm]
        return (max(0, int(usable[0] // pitch)), max(0, int(usable[1] // pitch)))


Shape = dict[str, Any]


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
        return _scaled(shape, radius / far)

    def _valid(self, shape: Shape, radius: float) -> bool:
        """Every feature above the limits, the outline simple, holes inside with material."""
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
        return self._holes_ok(path)

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
        return _polygon(self._convex_vertices(rng, r, 3, 8))

    def _draw_concave(self, rng: np.random.Generator, r: float) -> Shape:
        n = int(rng.integers(4, 10))
        gaps = rng.uniform(1.0, 2.0, n)
        t = np.cumsum(gaps / gaps.sum() * 2.0 * math.pi)
        radii = rng.uniform(0.7, 1.0, n) * r
        inward = rng.choice(n, size=max(1, int(rng.integers(1, n // 2 + 1))), replace=False)
        radii[inward] *= rng.uniform(0.35, 0.6, len(inward))
        return _polygon(np.stack([radii * np.cos(t), radii * np.sin(t)], axis=1))

    def _draw_named(self, rng: np.random.Generator, r: float) -> Shape:
        """A named shape at unit size (`_fit` scales it)."""
        del r
        kind = NAMED[int(rng.integers(len(NAMED)))]
        a, b = rng.uniform(0.45, 1.0, 2)
        if kind == "parallelogram":
            s = rng.uniform(0.2, 0.6)
            return _polygon([[0, 0], [1, 0], [1 + s, b], [s, b]])
        if kind == "trapezoid":
            s = rng.uniform(0.15, 0.35)
            return _polygon([[0, 0], [1, 0], [1 - s, b], [s, b]])
        if kind == "kite":
            return _polygon([[0, -1], [a, 0], [0, b * 0.6], [-a, 0]])
        if kind == "arrow":
            w, head = rng.uniform(0.25, 0.4), rng.uniform(0.3, 0.5)
            return _polygon(
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
            return _polygon(np.stack([rad * np.cos(t), rad * np.sin(t)], axis=1))
        if kind == "quarter_disc":
            bulge = math.tan(math.pi / 8)  # a quarter turn
            return {"kind": "polygon", "vertices": [[0, 0], [1, 0, bulge], [0, 1]]}
        w = rng.uniform(0.35, 0.55)
        return _polygon([[0, 0], [1, 0], [1, w], [w, w], [w, 1], [0, 1]])

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
        return _polygon(v, b)

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
        return _rounded(v, float(rng.uniform(rho_lo, rho_hi)), rounded)

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
        return _polygon(np.array(verts), np.array(bulges))

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
            fit = _inradius(room, c) if k == 0 else 0.0
            # Off-centre holes move the area centroid and the tile is fitted again (shrunk a
            # little): holes start a fifth above the smallest feature.
            lo = 1.2 * cfg.min_feature_mm
            hi = max(lo, min(0.6 * _inradius(solid, c), 2.0 * fit))
            size = float(rng.uniform(lo, hi))
            centred = k == 0 and rng.random() < cfg.centred_hole_probability
            hole = _hole(kind, size, rng)
            if centred:
                at = c
            else:
                # Anywhere the whole hole (its circumscribed circle) keeps the smallest
                # feature of material, at least the smallest feature off the centroid.
                reach = room.buffer(-_circumradius(hole))
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


def _circumradius(hole: Shape) -> float:
    """Largest distance of a hole mapping's outline from its own centre, [mm]."""
    path = tile_path(hole, "generated hole")
    return float(np.max(np.hypot(*path.outer.dense(0.5).T)))


def _inradius(poly: shapely.Polygon, c: np.ndarray) -> float:
    return float(poly.boundary.distance(shapely.Point(float(c[0]), float(c[1]))))


def _hole(kind: str, size: float, rng: np.random.Generator) -> Shape:
    """A hole of inscribed diameter ``size`` (the rectangle's short side)."""
    if kind == "circle":
        return {"kind": "circle", "radius": size / 2.0}
    if kind == "square":
        return {"kind": "square", "size": size}
    if kind == "rectangle":
        return {"kind": "rectangle", "width": size * float(rng.uniform(1.3, 2.0)), "height": size}
    if kind == "triangle":
        # Equilateral: inradius = circumradius / 2.
        return {"kind": "regular_polygon", "sides": 3, "radius": size}
    sides = 5 if kind == "pentagon" else 6
    return {
        "kind": "regular_polygon",
        "sides": sides,
        "radius": size / 2.0 / math.cos(math.pi / sides),
    }


def _polygon(vertices: Any, bulges: Any = None) -> Shape:
    v = np.asarray(vertices, dtype=float)
    b = np.zeros(len(v)) if bulges is None else np.asarray(bulges, dtype=float)
    rows = [
        [float(x), float(y), float(bb)] if bb != 0.0 else [float(x), float(y)]
        for (x, y), bb in zip(v, b, strict=True)
    ]
    return {"kind": "polygon", "vertices": rows}


def _rounded(v: np.ndarray, rho: float, which: np.ndarray) -> Shape:
    """A convex counter-clockwise polygon with some corners rounded.

    The corners ``which`` (bool per vertex) get a radius-``rho`` arc tangent to both edges.
    """
    n = len(v)
    verts: list[list[float]] = []
    for i in range(n):
        p, a, b = v[i], v[i - 1], v[(i + 1) % n]
        if not which[i]:
            verts.append(p.tolist())
            continue
        u0 = (a - p) / np.hypot(*(a - p))
        u1 = (b - p) / np.hypot(*(b - p))
        interior = math.acos(float(np.clip(np.dot(u0, u1), -1.0, 1.0)))
        d = rho / math.tan(interior / 2.0)
        turn = math.pi - interior
        verts.append([*(p + u0 * d).tolist(), math.tan(turn / 4.0)])
        verts.append((p + u1 * d).tolist())
    return {"kind": "polygon", "vertices": verts}


def _scaled(shape: Shape, s: float) -> Shape:
    """The shape mapping with every length scaled by ``s`` (bulges and angles kept)."""
    out: Shape = {}
    for k, val in shape.items():
        if k in ("radius", "size", "width", "height", "base", "inner_radius", "x", "y"):
            out[k] = float(val) * s
        elif k == "vertices":
            out[k] = [[r[0] * s, r[1] * s, *r[2:]] for r in val]
        elif k == "holes":
            out[k] = [_scaled(h, s) for h in val]
        else:
            out[k] = val
    return out


def random_design(
    rng: np.random.Generator, config: GeneratorConfig | None = None, name: str = "random"
) -> Design:
    """One random design from ``rng`` (see `DesignGenerator.draw`)."""
    return DesignGenerator(config).draw(rng, name)


__all__ = [
    "DEFAULT_PALETTE",
    "HOLE_KINDS",
    "NAMED",
    "SHAPE_FAMILIES",
    "DesignGenerator",
    "GeneratorConfig",
    "random_design",
]
