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

import numpy as np
from numpy.typing import NDArray

from qshape.geometry import BoolArray, FloatArray, cross2
from qshape.tolerances import Tolerances

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


def _band3(
    value: FloatArray,
    band: tuple[float, float],
    ambiguous: tuple[tuple[float, float], tuple[float, float]],
    labels: tuple[int, int, int],
) -> tuple[CodeArray, CodeArray]:
    """Primary label and admissible bit mask for a three-way band.

    Args:
        value: Measurements, shape (n,).
        band: (low, high) band edges (inclusive: a value on an edge is inside).
        ambiguous: (from, to) intervals around the low and the high edge that are ambiguous.
        labels: Label indices (below, inside, above).
    """
    lo, hi = band
    lo_amb, hi_amb = ambiguous
    below, inside, above = labels
    primary = np.where(value < lo, below, np.where(value > hi, above, inside))
    mask = np.left_shift(1, primary)
    near_lo = (value >= lo_amb[0]) & (value <= lo_amb[1])
    near_hi = (value >= hi_amb[0]) & (value <= hi_amb[1])
    mask = mask | np.where(near_lo, (1 << below) | (1 << inside), 0)
    mask = mask | np.where(near_hi, (1 << inside) | (1 << above), 0)
    return primary.astype(np.int64), mask.astype(np.int64)


def measure(points: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Raw measurements at every relevant point of a clockwise (y-up) boundary.

    Args:
        points: Shape (n, 2), right-handed y-up frame, clockwise as seen.

    Returns:
        (angle_deg, bend_deg, length_ratio, chord_ratio), each shape (n,): the unsigned angle
        between the two edges at the point (the circle test), the signed bend (positive: convex,
        the point lies left of the line from its previous to its next neighbour), the ratio
        |V(i-1) V(i)| / |V(i) V(i+1)|, and half-chord / distance to the chord midpoint (da / db).
    """
    prev = np.roll(points, 1, axis=0)
    nxt = np.roll(points, -1, axis=0)
    e1 = points - prev
    e2 = nxt - points
    cr = cross2(e1, e2)
    dt = np.einsum("ij,ij->i", e1, e2)
    turn = np.degrees(np.arctan2(cr, dt))  # CCW turn of the walk direction
    bend = -turn
    angle = 180.0 - np.abs(turn)
    l1 = np.hypot(e1[:, 0], e1[:, 1])
    l2 = np.hypot(e2[:, 0], e2[:, 1])
    ratio = l1 / l2
    mid = 0.5 * (prev + nxt)
    da = 0.5 * np.hypot(*(nxt - prev).T)
    db = np.hypot(*(points - mid).T)
    chord_ratio = da / np.where(db > 0.0, db, np.inf)
    chord_ratio = np.where(db > 0.0, chord_ratio, np.inf)
    return angle, bend, ratio, chord_ratio


def node_codes(points: FloatArray, curve_mask: BoolArray, tol: Tolerances) -> CodeArray:
    """Node codes (see module doc) of every relevant point of a boundary.

    Args:
        points: Shape (n, 2), right-handed y-up frame, clockwise as seen, distinct points.
        curve_mask: Shape (n,) bool, curve (maximum-curvature) points.
        tol: Bands and margins.

    Returns:
        Shape (n,) int64 node codes.
    """
    angle, bend, ratio, chord_ratio = measure(points)
    alo, ahi = tol.right_angle_deg[0], tol.right_angle_deg[1]
    am = tol.angle_margin_deg
    a_p, a_m = _band3(
        angle, (alo, ahi), ((alo - am, alo + am), (ahi - am, ahi + am)), (ACUTE, RIGHT, OBTUSE)
    )
    c_p = np.where(bend >= 0.0, CONVEX, CONCAVE)
    c_m = np.left_shift(1, c_p) | np.where(np.abs(bend) <= tol.convexity_margin_deg, 0b11, 0)
    llo, lhi = tol.equal_length_ratio[0], tol.equal_length_ratio[1]
    f = 1.0 + tol.length_margin
    l_p, l_m = _band3(
        ratio, (llo, lhi), ((llo / f, llo * f), (lhi / f, lhi * f)), (SMALLER, EQUAL, BIGGER)
    )
    slo, shi = tol.semicircle_ratio[0], tol.semicircle_ratio[1]
    g = 1.0 + tol.semicircle_margin
    t_p, t_m = _band3(
        chord_ratio,
        (slo, shi),
        ((slo / g, slo * g), (shi / g, shi * g)),
        (ACUTE_CURVE, SEMICIRCLE, PLANE),
    )
    curve = curve_mask.astype(np.int64)
    a_p = np.where(curve_mask, 0, a_p)
    a_m = np.where(curve_mask, 1, a_m)
    t_p = np.where(curve_mask, t_p, l_p)
    t_m = np.where(curve_mask, t_m, l_m)
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


def encode(
    is_curve: bool, a: tuple[int, int], c: tuple[int, int], t: tuple[int, int]
) -> int:
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
    "measure",
    "node_codes",
    "primary_code",
]
