"""The orientation a drawn tile really has: its drawn outline's best alignment with its design.

A synthetic tile is drawn at an angle, but it is not its design: its vertices are jittered and
its edges worn (rough, chipped) before it is drawn. With rough edges (a few tenths of a
millimetre, correlated over a millimetre) a whole short edge comes out turned, and the tile's
outline as drawn is best aligned with its design a degree or two away from the drawing angle.
That turn is in the picture: no measurement from the picture can give the drawing angle back
more closely. Where the tile fits its slot best is the best alignment of its real outline with
the design, so the recognition benchmarks report the rotation error against both: the drawing
angle, and this best alignment.

The alignment is a rigid fit (rotation and translation, no scale): the drawn outline's samples
are moved into the design's frame and their distances to the design outline (sampled every
``step_mm``) are minimised in a robust least-squares sense (soft L1 with scale ``f_scale_mm``,
so a chipped corner counts less than the edges; roughness lies in the quadratic part).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import least_squares
from scipy.spatial import cKDTree

from qshape.geometry import polygon_centroid
from qshape.synthetic.synth import TileTruth


def drawn_angle(
    tile: TileTruth, px_per_mm: float, step_mm: float = 0.02, f_scale_mm: float = 0.5
) -> float:
    """Orientation [rad] (CCW, y up, like ``TileTruth.angle``) of the tile as drawn.

    The design outline (the slot's, without noise) turned by this angle and moved best aligns
    with ``tile.outline_px``. The fit starts at the drawing angle and its centre, so for a
    symmetric shape it returns the alignment nearest the drawing angle. ``outline_px`` is in
    the drawing's frame (before any lens), like the picture a calibrated cell undistorts.

    Args:
        tile: A drawn tile with its outline (``outline_px`` set).
        px_per_mm: Scale of the picture, [px/mm].
        step_mm: Sampling step of the design outline, [mm].
        f_scale_mm: Distance where the soft L1 loss turns from quadratic to linear, [mm].

    Raises:
        ValueError: The tile carries no drawn outline.
    """
    if tile.outline_px is None or len(tile.outline_px) < 3:
        raise ValueError("drawn_angle needs a tile with its drawn outline (outline_px)")
    design = tile.slot.local_path.outer.dense(step_mm) * px_per_mm  # local, y up
    tree = cKDTree(design)
    drawn = np.asarray(tile.outline_px, dtype=np.float64) * np.array([1.0, -1.0])  # y up
    centre = polygon_centroid(drawn)  # the local origin is the tile's area centroid

    def residuals(x: np.ndarray) -> np.ndarray:
        c, s = math.cos(x[0]), math.sin(x[0])
        d = drawn - (centre + x[1:])
        local = np.column_stack((c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]))
        dist, _ = tree.query(local)
        return np.asarray(dist, dtype=np.float64)

    fit = least_squares(
        residuals,
        np.array([tile.angle, 0.0, 0.0]),
        x_scale=np.array([0.01, 1.0, 1.0]),
        diff_step=1e-4,
        loss="soft_l1",
        f_scale=f_scale_mm * px_per_mm,
    )
    return float(fit.x[0])
