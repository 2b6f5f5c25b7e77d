"""Qualitative 2D shape description and matching (Museros et al.), as a pure library.

Describe closed figures (polygons, curve segments, holes, colour) qualitatively, print and parse
the descriptions, match them (with the rotation that places a tile), and assign tiles to slots.
"""

from qshape.assign import Assignment, assign
from qshape.description import (
    BoundaryDescription,
    Description,
    HoleDescription,
    Node,
    describe,
    parse,
)
from qshape.errors import (
    InvalidFigureError,
    InvalidHoleError,
    MatchError,
    ParseError,
    QShapeError,
    ToleranceError,
)
from qshape.figure import Boundary, Figure
from qshape.matching import Match, canonical_key, canonical_keys, match
from qshape.simplify import OutlineParams
from qshape.tolerances import Tolerances

__all__ = [
    "Assignment",
    "Match",
    "assign",
    "canonical_key",
    "canonical_keys",
    "match",
    "Boundary",
    "BoundaryDescription",
    "Description",
    "Figure",
    "HoleDescription",
    "InvalidFigureError",
    "InvalidHoleError",
    "MatchError",
    "Node",
    "OutlineParams",
    "ParseError",
    "QShapeError",
    "ToleranceError",
    "Tolerances",
    "describe",
    "parse",
]
