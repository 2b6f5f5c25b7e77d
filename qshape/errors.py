"""Exceptions of the `qshape` package: one base class, one subclass per kind of problem."""

from __future__ import annotations


class QShapeError(ValueError):
    """Base class of every error raised by `qshape`."""


class InvalidFigureError(QShapeError):
    """A boundary or figure is malformed (too few points, NaN, zero area, self-crossing, ...)."""


class InvalidHoleError(InvalidFigureError):
    """A hole lies outside its parent, crosses the parent boundary, or overlaps another hole."""


class ToleranceError(QShapeError):
    """A tolerance or outline parameter is out of range (unordered band, negative margin, ...)."""


class ParseError(QShapeError):
    """The text given to `qshape.parse` is not a valid description; the message says where."""


class MatchError(QShapeError):
    """Arguments to `match` or `assign` are of the wrong kind (e.g. an unknown method name)."""


class DesignError(QShapeError):
    """A design file or design value is malformed; the message names the slot and the problem."""


class GeneratorError(DesignError):
    """A design generator parameter is out of range; the message names it and what is allowed."""


class ExcludedClassError(GeneratorError):
    """No design free of excluded tile classes was drawn in the tries allowed (names the clash)."""


class SmallFeatureWarning(UserWarning):
    """A design slot holds a feature below what the camera resolves (named in it).

    A small arc, or a turn the picture may not fix.
    """


class DesignFileWarning(UserWarning):
    """A design file (SVG, DXF) held something loading skipped or filled in (named in it).

    Text and dimension entities, a missing joint width, a file without units.
    """


class LimitError(QShapeError):
    """An input exceeds a documented cap (``limits`` of configs/qshape.yaml), named in it."""


class FigureLimitError(LimitError, InvalidFigureError):
    """A figure or outline exceeds a cap (points, holes, coordinate range)."""


class TextLimitError(LimitError, ParseError):
    """A description text exceeds a cap (characters, node count)."""


class DesignLimitError(LimitError, DesignError):
    """A design exceeds a size cap (mesh side, tile outline length)."""


__all__ = [
    "DesignError",
    "DesignFileWarning",
    "DesignLimitError",
    "FigureLimitError",
    "ExcludedClassError",
    "GeneratorError",
    "InvalidFigureError",
    "LimitError",
    "InvalidHoleError",
    "MatchError",
    "ParseError",
    "QShapeError",
    "SmallFeatureWarning",
    "TextLimitError",
    "ToleranceError",
]
