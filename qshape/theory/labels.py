"""The label rules of the theory, vectorised over all relevant points of a boundary.

Each node is packed into one small integer ("node code") so that descriptions are cheap to
build, compare and hash:

    bit 0        kind: 0 vertex <A, C, L>, 1 curve <Curve, C, TC>
    bits 1-2     primary A label (vertex) ; 0 for curves
    bits 3-5     admissible A labels, one bit per label (curves: bit of label 0)
    bit 6        primary C label
    bits 7-8     admissible C labels
    bits 9-10    primary L label (vertex) or TC label (curve)
    bits 11-13   admissible L / TC labels

A label is admissible when the measurement lies in its band or within the ambiguity margin of
its band edge; two nodes are compatible when they have the same kind and every component has a
common admissible label.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

from qshape.geometry import BoolArray, FloatArray
from qshape.theory.tolerances import Tolerances

CodeArray = NDArray[np.int64]

ANGLE_LABELS = ("right", "acute", "obtuse")
CONVEXITY_LABELS = ("convex", "concave")
LENGTH_LABELS = ("smaller", "equal", "bigger")
CURVATURE_LABELS = ("plane", "semicircle", "acute")
CURVE = "Curve"

RIGHT, ACUTE, OBTUSE = 0, 1, 2
CONVEX, CONCAVE = 0, 1
SMALLER, EQUAL, BIGGER = 0, 1, 2
PLANE, SEMICIRCLE, ACUTE_CURVE = 0, 1, 2

KIND_BIT = 1
A_SHIFT, A_MASK_SHIFT = 1, 3
C_SHIFT, C_MASK_SHIFT = 6, 7
T_SHIFT, T_MASK_SHIFT = 9, 11
A_MASK = 0b111 << A_MASK_SHIFT
C_MASK = 0b11 << C_MASK_SHIFT
T_MASK = 0b111 << T_MASK_SHIFT


@dataclass(frozen=True)
class _Bands:
    """Precomputed band edges, ambiguity intervals and label bits (rows: A, L, TC)."""

    lo: FloatArray  # (3, 1) band low edges
    hi: FloatArray  # (3, 1) band high edges
    lo_amb: tuple[FloatArray, FloatArray]  # (3, 1) ambiguous interval around low edges
    hi_amb: tuple[FloatArray, FloatArray]  # (3, 1) ambiguous interval around high edges
    below: NDArray[np.int64]  # (3, 1) label indices
    inside: NDArray[np.int64]
    above: NDArray[np.int64]


_RELATIVE = np.array([[False], [True], [True]])
"""Rows (A, L, TC) whose margin is relative (the two ratios) rather than absolute (the angle)."""


def _margins(tol: Tolerances) -> FloatArray:
    """The configured margins, shape (3, 1): [deg] for the angle, relative for the ratios."""
    return np.array([[tol.angle_margin_deg], [tol.length_margin], [tol.semicircle_margin]])


def _ambiguity(edge: FloatArray, m: FloatArray) -> tuple[FloatArray, FloatArray]:
    """The interval ``m`` spans around band edges ``edge`` (rows A, L, TC; see `_RELATIVE`)."""
    f = 1.0 + m
    return np.where(_RELATIVE, edge / f, edge - m), np.where(_RELATIVE, edge * f, edge + m)


@lru_cache(maxsize=16)
def _bands(tol: Tolerances) -> _Bands:
    """Bands of the angle (absolute margin), length and curvature (relative margin) labels."""
    band = np.array([tol.right_angle_deg, tol.equal_length_ratio, tol.semicircle_ratio])
    lo, hi = band[:, 0:1], band[:, 1:2]
    m = _margins(tol)
    labels = np.array(
        [[ACUTE, RIGHT, OBTUSE], [SMALLER, EQUAL, BIGGER], [ACUTE_CURVE, SEMICIRCLE, PLANE]],
        dtype=np.int64,
    )
    return _Bands(
        lo=lo,
        hi=hi,
        lo_amb=_ambiguity(lo, m),
        hi_amb=_ambiguity(hi, m),
        below=labels[:, 0:1],
        inside=labels[:, 1:2],
        above=labels[:, 2:3],
    )


def _band3(value: FloatArray, b: _Bands) -> tuple[CodeArray, CodeArray]:
    """Primary labels and admissible bit masks for the three-way bands.

    Args:
        value: Measurements, shape (3, n): angle [deg], length ratio, half-chord / sagitta.
        b: The bands (edges inclusive: a value on an edge is inside the band).
    """
    primary = np.where(value < b.lo, b.below, np.where(value > b.hi, b.above, b.inside))
    near_lo = (value >= b.lo_amb[0]) & (value <= b.lo_amb[1])
    near_hi = (value >= b.hi_amb[0]) & (value <= b.hi_amb[1])
    mask = (
        (1 << primary)
        | (near_lo * ((1 << b.below) | (1 << b.inside)))
        | (near_hi * ((1 << b.inside) | (1 << b.above)))
    )
    return primary, mask


def widened_masks(value: FloatArray, extra: FloatArray, tol: Tolerances) -> CodeArray:
    """Admissible label masks with each measurement's own uncertainty added to the margins.

    The configured margins stay; ``extra`` widens them per measurement (a value whose
    uncertainty reaches across a band edge also admits the neighbouring label).

    Args:
        value: Measurements, shape (3, n): angle [deg], length ratio, half-chord / sagitta.
        extra: Added margins, shape (3, n): [deg] for the angle, relative (as
            ``length_margin``) for the two ratios; >= 0.
        tol: Bands and configured margins.

    Returns:
        Shape (3, n) admissible bit masks (rows: A, L, TC), as in the node codes.
    """
    b = _bands(tol)
    m = _margins(tol) + extra
    wide = replace(b, lo_amb=_ambiguity(b.lo, m), hi_amb=_ambiguity(b.hi, m))
    return np.asarray(_band3(value, wide)[1], dtype=np.int64)


@lru_cache(maxsize=256)
def ring_index(n: int) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Index arrays of the previous and next point around a closed boundary of n points."""
    i = np.arange(n)
    prev, nxt = (i - 1) % n, (i + 1) % n
    prev.setflags(write=False)
    nxt.setflags(write=False)
    return prev, nxt


def measure(
    points: FloatArray, prev: FloatArray, nxt: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Raw measurements at relevant points of clockwise (y-up) boundaries.

    Args:
        points: Shape (n, 2), right-handed y-up frame, clockwise as seen.
        prev: The previous point of each point, shape (n, 2).
        nxt: The next point of each point, shape (n, 2).

    Returns:
        (angle_deg, bend_deg, length_ratio, chord_ratio), each shape (n,): the unsigned angle
        between the two edges at the point (the circle test), the signed bend (positive: convex,
        the point lies left of the line from its previous to its next neighbour), the ratio
        |V(i-1) V(i)| / |V(i) V(i+1)|, and half-chord / distance to the chord midpoint (da / db).
    """
    e1 = points - prev
    e2 = nxt - points
    cr = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    dt = e1[:, 0] * e2[:, 0] + e1[:, 1] * e2[:, 1]
    turn = np.degrees(np.arctan2(cr, dt))  # CCW turn of the walk direction
    l1 = np.hypot(e1[:, 0], e1[:, 1])
    l2 = np.hypot(e2[:, 0], e2[:, 1])
    chord = nxt - prev
    da = 0.5 * np.hypot(chord[:, 0], chord[:, 1])
    off = points - 0.5 * (prev + nxt)
    db = np.hypot(off[:, 0], off[:, 1])
    chord_ratio = np.divide(da, db, out=np.full_like(da, np.inf), where=db > 0.0)
    return 180.0 - np.abs(turn), -turn, l1 / l2, chord_ratio


def node_codes(points: FloatArray, curve_mask: BoolArray, tol: Tolerances) -> CodeArray:
    """Node codes (see module doc) of every relevant point of one boundary.

    Args:
        points: Shape (n, 2), right-handed y-up frame, clockwise as seen, distinct points.
        curve_mask: Shape (n,) bool, curve (maximum-curvature) points.
        tol: Bands and margins.

    Returns:
        Shape (n,) int64 node codes.
    """
    prev, nxt = ring_index(len(points))
    return codes_from(points, points[prev], points[nxt], curve_mask, tol)


def codes_from(
    points: FloatArray,
    prev: FloatArray,
    nxt: FloatArray,
    curve_mask: BoolArray,
    tol: Tolerances,
) -> CodeArray:
    """Node codes of points given with their neighbours (any number of boundaries at once).

    Args:
        points: Shape (n, 2), y-up frame, each boundary clockwise as seen.
        prev: Previous neighbour of each point, shape (n, 2).
        nxt: Next neighbour of each point, shape (n, 2).
        curve_mask: Shape (n,) bool.
        tol: Bands and margins.

    Returns:
        Shape (n,) int64 node codes.
    """
    angle, bend, ratio, chord_ratio = measure(points, prev, nxt)
    primary, mask = _band3(np.stack([angle, ratio, chord_ratio]), _bands(tol))
    c_p = (bend < 0.0).astype(np.int64)
    c_m = (1 << c_p) | np.where(np.abs(bend) <= tol.convexity_margin_deg, 0b11, 0)
    curve = curve_mask.astype(np.int64)
    a_p = np.where(curve_mask, 0, primary[0])
    a_m = np.where(curve_mask, 1, mask[0])
    t_p = np.where(curve_mask, primary[2], primary[1])
    t_m = np.where(curve_mask, mask[2], mask[1])
    return np.asarray(
        curve
        | (a_p << A_SHIFT)
        | (a_m << A_MASK_SHIFT)
        | (c_p << C_SHIFT)
        | (c_m << C_MASK_SHIFT)
        | (t_p << T_SHIFT)
        | (t_m << T_MASK_SHIFT),
        dtype=np.int64,
    )


def compatible(a: CodeArray, b: CodeArray) -> NDArray[np.bool_]:
    """Element-wise (broadcasting) compatibility of node codes: same kind, labels overlapping."""
    both = a & b
    return np.asarray(
        (((a ^ b) & KIND_BIT) == 0)
        & ((both & A_MASK) != 0)
        & ((both & C_MASK) != 0)
        & ((both & T_MASK) != 0)
    )


def primary_code(codes: CodeArray) -> CodeArray:
    """Codes reduced to their primary labels (admissible masks = the primary bit only)."""
    a = (codes >> A_SHIFT) & 0b11
    c = (codes >> C_SHIFT) & 0b1
    t = (codes >> T_SHIFT) & 0b11
    return np.asarray(
        (codes & KIND_BIT)
        | (a << A_SHIFT)
        | ((1 << a) << A_MASK_SHIFT)
        | (c << C_SHIFT)
        | ((1 << c) << C_MASK_SHIFT)
        | (t << T_SHIFT)
        | ((1 << t) << T_MASK_SHIFT),
        dtype=np.int64,
    )


def decode(code: int) -> tuple[bool, tuple[int, int], tuple[int, int], tuple[int, int]]:
    """Unpack one code: (is_curve, (A, A mask), (C, C mask), (L or TC, mask))."""
    return (
        bool(code & KIND_BIT),
        ((code >> A_SHIFT) & 0b11, (code >> A_MASK_SHIFT) & 0b111),
        ((code >> C_SHIFT) & 0b1, (code >> C_MASK_SHIFT) & 0b11),
        ((code >> T_SHIFT) & 0b11, (code >> T_MASK_SHIFT) & 0b111),
    )


def encode(is_curve: bool, a: tuple[int, int], c: tuple[int, int], t: tuple[int, int]) -> int:
    """Pack one code from (primary, mask) pairs; inverse of `decode`."""
    return (
        int(is_curve)
        | (a[0] << A_SHIFT)
        | (a[1] << A_MASK_SHIFT)
        | (c[0] << C_SHIFT)
        | (c[1] << C_MASK_SHIFT)
        | (t[0] << T_SHIFT)
        | (t[1] << T_MASK_SHIFT)
    )


__all__ = [
    "ANGLE_LABELS",
    "CONVEXITY_LABELS",
    "CURVATURE_LABELS",
    "CURVE",
    "LENGTH_LABELS",
    "compatible",
    "decode",
    "encode",
    "codes_from",
    "measure",
    "ring_index",
    "widened_masks",
    "node_codes",
    "primary_code",
]
