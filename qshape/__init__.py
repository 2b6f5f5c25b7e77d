"""Qualitative 2D shape description and matching (Museros et al.), as a pure library.

Describe closed figures (polygons, curve segments, holes, colour) qualitatively, print and parse
the descriptions, match them (with the rotation that places a tile), and assign tiles to slots::

    import qshape
    slot = qshape.describe(qshape.Figure.rectangle(20, 10, (0.8, 0.1, 0.1)))
    tile = qshape.describe(qshape.Figure.from_outline(contour, color=rgb, y_down=True))
    m = qshape.match(slot, tile)            # Match(rotation=..., rotations=..., score=...)
    text = str(slot); assert qshape.parse(text) == slot
    placed = qshape.assign(tiles, slots)     # [Assignment(tile, slot, rotation, score)]

Tolerances (bands, margins, thresholds) live in `Tolerances`, defaults in configs/qshape.yaml.
"""

from qshape.errors import (
    DesignError,
    FigureLimitError,
    InvalidFigureError,
    InvalidHoleError,
    LimitError,
    MatchError,
    ParseError,
    QShapeError,
    TextLimitError,
    ToleranceError,
)
from qshape.limits import Limits
from qshape.outline.params import OutlineParams
from qshape.theory.assign import Assignment, assign
from qshape.theory.boundary import Boundary
from qshape.theory.description import (
    BoundaryDescription,
    Description,
    HoleDescription,
    Node,
    describe,
    describe_many,
)
from qshape.theory.figure import Figure
from qshape.theory.matching import Match, canonical_key, canonical_keys, match, match_best
from qshape.theory.text_parser import parse
from qshape.theory.tolerances import Tolerances

__all__ = [
    "Assignment",
    "Boundary",
    "BoundaryDescription",
    "Description",
    "DesignError",
    "FigureLimitError",
    "Figure",
    "HoleDescription",
    "InvalidFigureError",
    "InvalidHoleError",
    "LimitError",
    "Limits",
    "Match",
    "MatchError",
    "Node",
    "OutlineParams",
    "ParseError",
    "QShapeError",
    "TextLimitError",
    "ToleranceError",
    "Tolerances",
    "assign",
    "canonical_key",
    "canonical_keys",
    "describe",
    "describe_many",
    "match",
    "match_best",
    "parse",
]

# Vision: mosaic designs, rendering, extraction from images (issue 3).
from qshape.design import Design, Slot  # noqa: E402
from qshape.synthetic.render import render_design, save_png  # noqa: E402
from qshape.vision.extract import ExtractResult, extract, extract_detailed
from qshape.vision.health import ImageHealth, image_health  # noqa: E402
from qshape.vision.params import ExtractParams, ImageError

__all__ += [
    "Design",
    "ExtractParams",
    "ExtractResult",
    "ImageError",
    "ImageHealth",
    "Slot",
    "extract",
    "extract_detailed",
    "image_health",
    "render_design",
    "save_png",
]
