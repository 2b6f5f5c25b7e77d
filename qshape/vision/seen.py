"""A design figure described as the camera's outline simplification sees it.

A design puts a relevant point wherever its path changes: at both ends of an arc, at every
corner. The camera's outline simplification (`qshape.Figure.from_outline` with the extraction's
`qshape.OutlineParams`) finds a corner only where the outline turns by more than its corner
angle within its corner window. Where a design's corner turns less, the picture has no
corner: an arc meeting a straight edge tangentially (a rounded corner), an arc edge whose end
nearly continues its neighbour's direction, two short edges turning opposite ways a few
millimetres apart. The measured figure then has fewer relevant points than the design's, and
no labelling of it can match the design's description.

`seen_figure` describes the design's outline the way the picture does: the outer boundary is
sampled densely (its arcs as arcs), scaled to the camera's pixels and simplified with the
extraction's own parameters. The holes, the colour and the frame are the design's, so a
rotation matched against the seen figure turns the tile onto the design's slot. It is the
description of a noise-free picture: where a picture's noise places a corner differently, the
two may still differ.
"""

from __future__ import annotations

import math

import numpy as np

from qshape.errors import InvalidFigureError
from qshape.outline.params import OutlineParams
from qshape.theory.figure import Figure


def seen_figure(figure: Figure, params: OutlineParams, px_per_mm: float) -> Figure:
    """``figure`` with its outer boundary's relevant points as a noise-free picture gives them.

    Args:
        figure: A design figure (in the design's unit, mm).
        params: The outline simplification the pictures get (``configs/vision.yaml``,
            ``extract.outline``).
        px_per_mm: The camera's scale on the tile tops [px/mm]: the boundary is simplified at
            this size, as a picture's traced outline is.

    Returns:
        A figure in ``figure``'s frame and unit: the simplified outer boundary, ``figure``'s
        holes and colour.

    Raises:
        InvalidFigureError: ``px_per_mm`` not positive and finite, or the simplified boundary
            not a valid figure.
    """
    if not (math.isfinite(px_per_mm) and px_per_mm > 0.0):
        raise InvalidFigureError(f"px_per_mm must be a finite number > 0, got {px_per_mm!r}")
    dense = figure.outer.dense()  # arcs sampled, the figure's coordinates
    outer = Figure.from_outline(
        dense * px_per_mm, (), figure.color, params=params, y_down=figure.y_down
    )
    return Figure.from_polygon(
        outer.points / px_per_mm,
        list(figure.holes),
        figure.color,
        curve_mask=outer.curve_mask,
        y_down=figure.y_down,
    )


def near_turns(figure: Figure, residual: float) -> int:
    """How many turns bring ``figure``'s outer relevant points nearly onto themselves.

    A turn is a cyclic shift of the points that keeps every point's kind (vertex, curve
    point), aligned by the best rotation about the points' mean; it counts when the RMS
    distance left is at most ``residual`` x sqrt(area). The identity counts, so a figure with
    no near symmetry gives 1. A seen figure has fewer points than its design: it may be nearly
    symmetric where the design is not, and a tile matched to it may then be turned wrongly.

    Args:
        figure: A figure (any unit).
        residual: Largest RMS distance left, as a fraction of sqrt(area). Dimensionless.
    """
    pts = figure.points - figure.points.mean(axis=0)
    z = pts[:, 0] + 1j * pts[:, 1]
    mask = figure.curve_mask
    n = len(z)
    own = float(np.sum(np.abs(z) ** 2))
    count = 1
    for k in range(1, n):
        if not np.array_equal(np.roll(mask, k), mask):
            continue
        q = np.roll(z, k)
        rss = 2.0 * own - 2.0 * abs(complex(np.sum(np.conj(q) * z)))
        if math.sqrt(max(rss, 0.0) / (n * figure.area)) <= residual:
            count += 1
    return count


__all__ = ["near_turns", "seen_figure"]
