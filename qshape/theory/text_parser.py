"""`parse`: reading the text form of a description back, in time linear in the text.

The text form is written by ``str(description)`` (`qshape.theory.description.format_description`);
``parse(str(d)) == d`` exactly. Every line is split by hand (no backtracking regular
expressions), numbers are plain ASCII decimals, and the text length and node counts are capped
(``Limits.max_text_chars``, ``Limits.max_points``), so any input is read or refused quickly.
"""

from __future__ import annotations

import math
import re

import numpy as np

from qshape.errors import ParseError, TextLimitError
from qshape.limits import default_limits
from qshape.theory import labels as lb
from qshape.theory.description import (
    CENTRE,
    CONES,
    HEADER,
    ONLY_CURVES,
    WITH_CURVES,
    WITH_HOLES,
    WITHOUT_CURVES,
    WITHOUT_HOLES,
    BoundaryDescription,
    CIi,
    Description,
    HoleDescription,
    type_curve_of,
)
from qshape.theory.figure import Color

_NUMBER = re.compile(r"[-+]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][-+]?[0-9]+)?|[-+]?(?:inf|nan)")
"""An ASCII decimal; unambiguous (digits before the point never compete with those after)."""

_COUNT_DIGITS = 9
"""Longest node count read, in digits (the cap ``Limits.max_points`` is far below 10^9)."""

_HOLE_RE = re.compile(
    r"^hole:\s*(\w+)\s*\[([^\]]*)\]\s*(without curves|with curves|only curves)"
    r",\s*nodes:\s*([0-9]+)\s*$",
    re.ASCII,
)


def _component(text: str, names: tuple[str, ...], where: str) -> tuple[int, int]:
    parts = [p.strip() for p in text.split("/")]
    idx = []
    for p in parts:
        if p not in names:
            raise ParseError(f"{where}: unknown label {p!r}; allowed: {', '.join(names)}")
        idx.append(names.index(p))
    if len(set(idx)) != len(idx):
        raise ParseError(f"{where}: repeated label in {text!r}")
    mask = 0
    for k in idx:
        mask |= 1 << k
    return idx[0], mask


def _parse_node(line: str, where: str) -> tuple[int, tuple[float, float]]:
    expected = (
        f"{where}: expected a node '  <A, C, L> @ (x, y)' or '  <Curve, C, TC> @ (x, y)', "
        f"got {_clip(line)!r}"
    )
    if not line[:1].isspace():
        raise ParseError(expected)
    body = line.strip()
    close = body.find(">")
    if not body.startswith("<") or close < 0:
        raise ParseError(expected)
    labels = body[1:close].split(",")
    rest = body[close + 1 :].strip()
    if len(labels) != 3 or not rest.startswith("@"):
        raise ParseError(expected)
    point = rest[1:].strip()
    if not (point.startswith("(") and point.endswith(")")):
        raise ParseError(expected)
    coords = point[1:-1].split(",")
    if len(coords) != 2:
        raise ParseError(expected)
    first, conv, third = (t.strip() for t in labels)
    c = _component(conv, lb.CONVEXITY_LABELS, where)
    if first == lb.CURVE:
        code = lb.encode(True, (0, 1), c, _component(third, lb.CURVATURE_LABELS, where))
    else:
        a = _component(first, lb.ANGLE_LABELS, where)
        code = lb.encode(False, a, c, _component(third, lb.LENGTH_LABELS, where))
    x = _float(coords[0].strip(), "node point x", where)
    y = _float(coords[1].strip(), "node point y", where)
    return code, (x, y)


def _parse_boundary(lines: list[str], at: int, count: int, what: str) -> BoundaryDescription:
    if count < 3:
        raise ParseError(f"line {at}: {what} needs at least 3 nodes, got {count}")
    if at + count > len(lines):
        raise ParseError(
            f"line {at}: {what} announces {count} nodes but the text ends after {len(lines) - at}"
        )
    codes, pts = [], []
    for k in range(count):
        code, p = _parse_node(lines[at + k], f"line {at + k + 1}")
        codes.append(code)
        pts.append(p)
    c = np.array(codes, dtype=np.int64)
    p_arr = np.array(pts, dtype=np.float64)
    curve = (c & lb.KIND_BIT) == 1
    if np.any(curve & np.roll(curve, 1)):
        raise ParseError(
            f"line {at}: {what} has two adjacent Curve nodes; a curve node needs "
            "its start and end vertices as neighbours"
        )
    c.setflags(write=False)
    p_arr.setflags(write=False)
    return BoundaryDescription(c, p_arr)


def _value(line: str, key: str, where: str) -> str:
    prefix = f"{key}:"
    if not line.startswith(prefix):
        raise ParseError(f"{where}: expected '{key}: ...', got {_clip(line)!r}")
    return line[len(prefix) :].strip()


def _clip(text: str, keep: int = 60) -> str:
    """The text, cut to ``keep`` characters for an error message."""
    return text if len(text) <= keep else text[:keep] + f"... ({len(text)} characters)"


def _float(text: str, what: str, where: str) -> float:
    if _NUMBER.fullmatch(text) is None:
        raise ParseError(f"{where}: {what} must be a decimal number, got {_clip(text)!r}")
    v = float(text)
    if not math.isfinite(v):
        raise ParseError(f"{where}: {what} must be finite, got {_clip(text)!r}")
    return v


def parse(text: str) -> Description:
    """Read the text form of a description back (exact inverse of ``str(description)``).

    Raises:
        ParseError: Naming the line and what was expected.
        TextLimitError: Text longer than ``Limits.max_text_chars``, or a node count above
            ``Limits.max_points`` (a `ParseError` too).
    """
    if not isinstance(text, str):
        raise ParseError(f"parse expects a string, got {type(text).__name__}")
    default_limits().check_count(len(text), "max_text_chars", "parse: text", TextLimitError)
    lines = [ln for ln in text.splitlines() if ln.strip()]
    if len(lines) < 6 or lines[0].strip() != HEADER:
        raise ParseError(
            f"line 1: expected the header {HEADER!r} followed by type, color, area, "
            "perimeter and nodes lines"
        )
    types = [t.strip() for t in _value(lines[1], "type", "line 2").split(",")]
    if (
        len(types) != 2
        or types[0] not in (WITHOUT_HOLES, WITH_HOLES)
        or types[1] not in (WITHOUT_CURVES, WITH_CURVES, ONLY_CURVES)
    ):
        raise ParseError(
            f"line 2: type must be '<without holes|with holes>, <without curves|with curves|"
            f"only curves>', got {_clip(lines[1])!r}"
        )
    color = _color(_value(lines[2], "color", "line 3"))
    area = _float(_value(lines[3], "area", "line 4"), "area", "line 4")
    perimeter = _float(_value(lines[4], "perimeter", "line 5"), "perimeter", "line 5")
    if area <= 0.0 or perimeter <= 0.0:
        raise ParseError("lines 4-5: area and perimeter must be > 0")
    count = _int(_value(lines[5], "nodes", "line 6"), "line 6")
    outer = _parse_boundary(lines, 6, count, "the outer boundary")
    if type_curve_of(outer.codes) != types[1]:
        raise ParseError(
            f"line 2: type says {types[1]!r} but the nodes are {type_curve_of(outer.codes)!r}"
        )
    at = 6 + count
    holes: list[HoleDescription] = []
    while at < len(lines):
        hole, at = _hole(lines, at, len(holes))
        holes.append(hole)
    if (types[0] == WITH_HOLES) != bool(holes):
        raise ParseError(f"line 2: type says {types[0]!r} but {len(holes)} holes follow")
    return Description(types[0], types[1], color, area, perimeter, outer, tuple(holes))


def _color(ctext: str) -> Color | None:
    """The colour line's value: 'none' or three numbers in [0, 1]."""
    if ctext == "none":
        return None
    parts = ctext.split()
    if len(parts) != 3:
        raise ParseError(f"line 3: color must be 'none' or three numbers, got {_clip(ctext)!r}")
    rgb = [_float(p, "color", "line 3") for p in parts]
    if not all(0.0 <= v <= 1.0 for v in rgb):
        raise ParseError(f"line 3: color components must be in [0, 1], got {_clip(ctext)!r}")
    return (rgb[0], rgb[1], rgb[2])


def _hole(lines: list[str], at: int, index: int) -> tuple[HoleDescription, int]:
    """Hole ``index`` whose header is line ``at`` (0-based), and the line after its nodes."""
    m = _HOLE_RE.match(lines[at])
    if not m:
        raise ParseError(
            f"line {at + 1}: expected 'hole: CIi [cones] <type_curve>, nodes: n'"
            f", got {_clip(lines[at])!r}"
        )
    rel, pos, hcurve, hcount = m.groups()
    if rel != CIi:
        raise ParseError(f"line {at + 1}: hole relation must be {CIi!r}, got {rel!r}")
    position = tuple(p.strip() for p in pos.split(",") if p.strip())
    allowed = (*CONES, CENTRE)
    if (
        not position
        or any(p not in allowed for p in position)
        or (CENTRE in position and len(position) > 1)
    ):
        raise ParseError(
            f"line {at + 1}: position must be 'C' or cones from {', '.join(CONES)}, got [{pos}]"
        )
    hcount_int = _int(hcount, f"line {at + 1}")
    boundary = _parse_boundary(lines, at + 1, hcount_int, f"hole {index}")
    if boundary.type_curve != hcurve:
        raise ParseError(
            f"line {at + 1}: hole type says {hcurve!r} but its nodes are {boundary.type_curve!r}"
        )
    return HoleDescription(position, boundary, rel), at + 1 + hcount_int


def _int(text: str, where: str) -> int:
    if not (text.isascii() and text.isdigit()) or len(text) > _COUNT_DIGITS:
        raise ParseError(
            f"{where}: expected a node count (up to {_COUNT_DIGITS} digits), got {_clip(text)!r}"
        )
    count = int(text)
    default_limits().check_count(count, "max_points", f"{where}: node count", TextLimitError)
    return count


__all__ = ["parse"]
