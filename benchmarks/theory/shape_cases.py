"""The shapes benchmark's inputs (`benchmarks.theory.shapes`).

Random tile classes, their figures placed at random, and cases mixing them.
"""

from __future__ import annotations

import math  # noqa: E402
from dataclasses import dataclass  # noqa: E402

import numpy as np  # noqa: E402

from apps.cli import UsageError
from qshape import Description, Figure  # noqa: E402
from qshape.theory.boundary import Boundary  # noqa: E402
from qshape.theory.description import describe_many  # noqa: E402

PALETTE = (
    (0.85, 0.15, 0.15),
    (0.15, 0.55, 0.85),
    (0.95, 0.85, 0.20),
    (0.20, 0.70, 0.30),
    (0.95, 0.95, 0.92),
    (0.10, 0.10, 0.12),
    (0.60, 0.30, 0.70),
    (0.95, 0.55, 0.15),
)


@dataclass(frozen=True)
class ShapeClass:
    """A tile class: local relevant points (y-up, mm), curve mask, holes, colour, symmetry."""

    points: np.ndarray
    mask: np.ndarray
    holes: tuple[tuple[np.ndarray, np.ndarray], ...]
    color: tuple[float, float, float]
    symmetry: int  # rotational symmetry order; 0 = continuous


def _regular(n: int, r: float) -> np.ndarray:
    t = math.pi / 2 - 2 * math.pi * np.arange(n) / n
    return r * np.stack([np.cos(t), np.sin(t)], axis=1)


def _random_convex(rng: np.random.Generator, n: int, r: float) -> np.ndarray:
    while True:
        t = np.sort(rng.uniform(0.0, 2 * math.pi, n))
        gaps = np.diff(np.r_[t, t[0] + 2 * math.pi])
        if gaps.min() > math.radians(15) and gaps.max() < math.radians(150):
            return r * np.stack([np.cos(t), np.sin(t)], axis=1)


def _shapes(rng: np.random.Generator) -> list[tuple[np.ndarray, np.ndarray, tuple, int]]:
    no = np.zeros
    circle = (
        np.array([[-10.0, 0], [0, 10], [10, 0], [0, -10]]),
        np.array([False, True, False, True]),
    )
    ring_hole = (
        np.array([[-4.0, 0], [0, 4], [4, 0], [0, -4]]),
        np.array([False, True, False, True]),
    )
    sq_hole = (np.array([[4.0, -9], [9, -9], [9, -4], [4, -4]]), no(4, bool))
    shapes = [
        (np.array([[-10.0, -10], [10, -10], [10, 10], [-10, 10]]), no(4, bool), (), 4),
        (np.array([[-15.0, -15], [15, -15], [15, 15], [-15, 15]]), no(4, bool), (), 4),
        (np.array([[-10.0, -5], [10, -5], [10, 5], [-10, 5]]), no(4, bool), (), 2),
        (np.array([[-15.0, -7.5], [15, -7.5], [15, 7.5], [-15, 7.5]]), no(4, bool), (), 2),
        (np.array([[-20.0, -10], [20, -10], [20, 10], [-20, 10]]), no(4, bool), (), 2),
        (np.array([[0.0, 0], [20, 0], [0, 20]]), no(3, bool), (), 1),
        (np.array([[0.0, 0], [30, 0], [0, 15]]), no(3, bool), (), 1),
        (np.array([[-10.0, 0], [10, 0], [0, 30]]), no(3, bool), (), 1),
        (_regular(3, 14.0), no(3, bool), (), 3),
        (_regular(5, 12.0), no(5, bool), (), 5),
        (_regular(6, 12.0), no(6, bool), (), 6),
        (_regular(8, 12.0), no(8, bool), (), 8),
        (np.array([[0.0, 0], [20, 0], [20, 8], [8, 8], [8, 20], [0, 20]]), no(6, bool), (), 1),
        (np.array([[0.0, 0], [20, 0], [28, 14], [8, 14]]), no(4, bool), (), 2),
        (np.array([[-10.0, 0], [0, 10], [10, 0]]), np.array([False, True, False]), (), 1),
        (circle[0], circle[1], (), 0),
        (np.array([[-12.0, 0], [0, 12], [12, 0], [0, -12]]), circle[1], (ring_hole,), 0),
        (np.array([[-12.0, -12], [12, -12], [12, 12], [-12, 12]]), no(4, bool), (sq_hole,), 1),
    ]
    for n in (5, 6, 7, 8, 9, 10, 12):
        shapes.append((_random_convex(rng, n, 14.0), no(n, bool), (), 1))
    return shapes


def make_classes(rng: np.random.Generator, count: int) -> list[ShapeClass]:
    """``count`` classes: every shape in two colours, then more colours as needed."""
    shapes = _shapes(rng)
    out: list[ShapeClass] = []
    k = 0
    while len(out) < count:
        pts, mask, holes, sym = shapes[k % len(shapes)]
        color = PALETTE[(k * 3 + k // len(shapes)) % len(PALETTE)]
        out.append(ShapeClass(pts, mask, holes, color, sym))
        k += 1
    return out


def _place(pts: np.ndarray, angle: float, shift: np.ndarray) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return pts @ np.array([[c, s], [-s, c]]) + shift


def make_figure(
    cls: ShapeClass, rng: np.random.Generator, angle: float, jitter: float, color_jitter: float
) -> Figure:
    """One posed copy of a class with vertex jitter [mm] and colour jitter."""
    shift = rng.uniform(-200.0, 200.0, 2)

    def noisy(p: np.ndarray) -> np.ndarray:
        return _place(p, angle, shift) + rng.uniform(-jitter, jitter, p.shape)

    color = np.clip(np.array(cls.color) + rng.uniform(-color_jitter, color_jitter, 3), 0, 1)
    holes = tuple(Boundary.make(noisy(hp), hm) for hp, hm in cls.holes)
    return Figure(noisy(cls.points), cls.mask, holes, tuple(color.tolist()))


TESSERA = np.array([[-10.0, -10], [10, -10], [10, 10], [-10, 10]])
"""A 20 mm square tessera, local points (y-up, mm)."""


def mix_classes(
    mix: str, rng: np.random.Generator, balanced: int
) -> tuple[list[ShapeClass], np.ndarray]:
    """Classes of a class mix and the probability of each.

    ``balanced``: ``balanced`` classes of `make_classes`, equally likely. ``one_class``: one
    20 mm square tessera in one colour. ``five_colours``: that tessera in five colours, equally
    likely. ``zipf20``: 20 classes of `make_classes`, the k-th (from 1) with probability
    proportional to 1/k.
    """
    none = np.zeros(4, bool)
    if mix == "balanced":
        classes = make_classes(rng, balanced)
        return classes, np.full(len(classes), 1.0 / len(classes))
    if mix == "one_class":
        return [ShapeClass(TESSERA, none, (), PALETTE[0], 4)], np.ones(1)
    if mix == "five_colours":
        return [ShapeClass(TESSERA, none, (), PALETTE[k], 4) for k in range(5)], np.full(5, 0.2)
    if mix == "zipf20":
        weights = 1.0 / np.arange(1, 21)
        return make_classes(rng, 20), weights / weights.sum()
    raise UsageError(f"unknown mix {mix!r}; allowed: {', '.join(MIXES)}")


MIXES = ("balanced", "one_class", "five_colours", "zipf20")
"""Class mixes of the assignment cases, in table order."""


@dataclass(frozen=True)
class Case:
    """One assignment input: posed slots and noisy tiles copied from them (tile order shuffled).

    Attributes:
        classes: Tile classes.
        slot_class, slot_angle, tile_class, tile_angle: Per slot / tile, class and pose [rad].
        tile_order: Tile i is a copy of slot ``tile_order[i]``.
        tile_figs, slot_desc: Tile figures and slot descriptions.
    """

    classes: list[ShapeClass]
    slot_class: np.ndarray
    slot_angle: np.ndarray
    tile_class: np.ndarray
    tile_angle: np.ndarray
    tile_order: np.ndarray
    tile_figs: list[Figure]
    slot_desc: list[Description]


def make_case(
    *, classes: list[ShapeClass], weights: np.ndarray, n: int, rng: np.random.Generator, args, tol
) -> Case:
    """Draw ``n`` slots from ``classes`` with probabilities ``weights`` and ``n`` tiles."""
    slot_class = rng.choice(len(classes), n, p=weights)
    slot_angle = rng.uniform(-math.pi, math.pi, n)
    tile_order = rng.permutation(n)
    tile_class = slot_class[tile_order]
    tile_angle = rng.uniform(-math.pi, math.pi, n)
    slot_figs = [
        make_figure(classes[c], rng, a, 0.0, 0.0)
        for c, a in zip(slot_class, slot_angle, strict=True)
    ]
    tile_figs = [
        make_figure(classes[c], rng, a, args.jitter, 0.03)
        for c, a in zip(tile_class, tile_angle, strict=True)
    ]
    return Case(
        classes,
        slot_class,
        slot_angle,
        tile_class,
        tile_angle,
        tile_order,
        tile_figs,
        describe_many(slot_figs, tol),
    )


__all__ = [
    "Case",
    "MIXES",
    "PALETTE",
    "ShapeClass",
    "TESSERA",
    "make_case",
    "make_classes",
    "make_figure",
    "mix_classes",
]
