"""SVG designs: reading a drawing (Inkscape, Illustrator, CAD exports) and writing one.

Reading (`read_svg`, through ``svgelements``): units are millimetres; every closed, filled
``path``, ``polygon``, ``rect``, ``circle`` or ``ellipse`` is a tile of its fill colour, with
every transform applied; its sub-paths inside it are its holes by its ``fill-rule``
(``evenodd``: every nested sub-path cuts; ``nonzero``: one wound the other way cuts). The mesh
is the element with ``id="mesh"`` (its fill, if any, the joint colour), else the ``viewBox``;
the joint width is the root's ``data-joint`` attribute (else ``default_joint_mm``, with a
`qshape.errors.DesignFileWarning`). Circular arcs stay arcs; Beziers and elliptical arcs become
arcs within ``curve_tolerance_mm`` (`qshape.design.arc_fit`). Text and unfilled shapes are
skipped with one warning.

Writing (`svg_text`): the mesh as ``rect id="mesh"``, one ``path`` per slot (``id`` its name,
arcs as SVG arcs, holes as sub-paths, ``fill-rule="evenodd"``), the joint as ``data-joint``.
"""

from __future__ import annotations

import math
import re
import warnings
from pathlib import Path
from typing import Any
from xml.sax.saxutils import escape, quoteattr

import numpy as np

from qshape.design.arc_fit import fit_arcs, three_point_bulge
from qshape.design.drawn import DrawnClasses, DrawnTile, loop_from_nodes, nest_loops
from qshape.design.fields import DesignFields
from qshape.design.file_params import DesignFileParams, drawing_joint
from qshape.design.paths import Loop, TilePath
from qshape.design.rules import DesignRules
from qshape.design.values import color_hex
from qshape.errors import DesignError, DesignFileWarning
from qshape.geometry import FloatArray

PPI = 96.0
"""CSS pixels per inch, the resolution ``svgelements`` resolves absolute units at."""
_LENGTH = re.compile(r"^\s*[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?\s*(mm|cm|in|pt|pc|px|q|Q)?\s*$")


def _scale(root: Any, source: str) -> float:
    """Millimetres per parsed unit: a root size with units was resolved to CSS pixels."""
    units = set()
    for key in ("width", "height"):
        raw = root.values.get(key)
        if raw is None:
            continue
        m = _LENGTH.match(str(raw))
        if m is None:
            raise DesignError(
                f"{source}: <svg {key}={str(raw)!r}>: unknown units; allowed: a number with "
                "mm, cm, in, pt, pc, px or Q, or none (user units are millimetres)"
            )
        units.add(m.group(3) or "")
    if not units - {""}:
        return 1.0
    import svgelements as se  # noqa: PLC0415

    return 100.0 / (float(se.Length("100mm").in_inches()) * PPI)  # its own mm-to-inch factor


class _Subpaths:
    """Collects the closed sub-paths of one element as (vertices, bulges) in mesh mm."""

    def __init__(self, where: str, to_mm: Any, params: DesignFileParams) -> None:
        self.where, self.to_mm, self.params = where, to_mm, params
        self.done: list[tuple[FloatArray, FloatArray]] = []
        self.verts: list[FloatArray] = []
        self.bulges: list[float] = []
        self.start: FloatArray | None = None
        self.end: FloatArray | None = None

    def finish(self, closed: bool) -> None:
        if self.start is None:
            return
        gap = float(np.hypot(*(self.end - self.start))) if self.end is not None else 0.0
        if not closed and gap > self.params.close_tolerance_mm:
            raise DesignError(
                f"{self.where}: an open path (ends {gap:.3f} mm from its start); allowed: "
                f"closed paths (Z, or an end within {self.params.close_tolerance_mm} mm)"
            )
        if self.verts:
            self.done.append((np.array(self.verts), np.array(self.bulges)))
        self.verts, self.bulges, self.start, self.end = [], [], None, None

    def add(self, seg: Any) -> None:
        import svgelements as se  # noqa: PLC0415 - only SVG loading needs it

        if isinstance(seg, se.Move):
            self.finish(False)
            self.start = self.end = self.to_mm(np.array([[seg.end.x, seg.end.y]]))[0]
            return
        if self.start is None:
            return
        a = self.to_mm(np.array([[seg.start.x, seg.start.y]]))[0]
        b = self.to_mm(np.array([[seg.end.x, seg.end.y]]))[0]
        if isinstance(seg, se.Close | se.Line):
            if np.hypot(*(b - a)) > 0.0:
                self.verts.append(a)
                self.bulges.append(0.0)
            self.end = b
            if isinstance(seg, se.Close):
                self.finish(True)
            return
        if isinstance(seg, se.Arc) and abs(seg.rx - seg.ry) <= 1e-9 * max(seg.rx, seg.ry):
            m = self.to_mm(np.array([[seg.point(0.5).x, seg.point(0.5).y]]))[0]
            self.verts.append(a)
            self.bulges.append(three_point_bulge(a, m, b))
            self.end = b
            return
        pts = self._samples(seg)
        v, bl = fit_arcs(pts, self.params.curve_tolerance_mm)
        self.verts.extend(v)
        self.bulges.extend(bl.tolist())
        self.end = b

    def _samples(self, seg: Any) -> FloatArray:
        """The curve sampled ``curve_step_mm`` apart (at least 16 samples), in mesh mm."""
        coarse = self.to_mm(
            np.array([[p.x, p.y] for p in (seg.point(t) for t in np.linspace(0, 1, 17))])
        )
        length = float(np.sum(np.hypot(*np.diff(coarse, axis=0).T)))
        n = max(16, math.ceil(length / self.params.curve_step_mm))
        raw = seg.npoint(np.linspace(0.0, 1.0, n + 1))
        out: FloatArray = self.to_mm(np.asarray(raw, dtype=np.float64))
        return out


def read_svg(
    path: str | Path, rules: DesignRules | None = None, params: DesignFileParams | None = None
) -> dict[str, Any]:
    """The design file mapping of an SVG drawing (see the module docstring).

    Raises:
        DesignError: Unreadable file, unknown units, no mesh, an open path, a self-crossing
            outline, overlapping sub-paths, a bad ``data-joint``; the message names the element.
    """
    import svgelements as se  # noqa: PLC0415 - only SVG loading needs it

    rules, params = rules or DesignRules(), params or DesignFileParams.load()
    source = str(path)
    try:
        svg = se.SVG.parse(str(path), reify=True)
    except Exception as exc:  # svgelements raises XML and OS errors of several kinds
        raise DesignError(f"{source}: not a readable SVG file ({exc})") from exc
    mm = _scale(svg, source)
    mesh_el = next((e for e in svg.elements() if getattr(e, "id", None) == "mesh"), None)
    if isinstance(mesh_el, se.Shape):
        x0, y0, x1, y1 = mesh_el.bbox(transformed=True)
    elif svg.viewbox is not None and svg.width and svg.height:
        x0, y0, x1, y1 = 0.0, 0.0, float(svg.width), float(svg.height)
    else:
        raise DesignError(
            f'{source}: no mesh; allowed: an element with id="mesh" (a rect) or a viewBox'
        )
    x0, y0, x1, y1 = (float(v) * mm for v in (x0, y0, x1, y1))

    def to_mm(p: FloatArray) -> FloatArray:
        p = np.asarray(p, dtype=np.float64).reshape(-1, 2) * mm
        return np.column_stack([p[:, 0] - x0, y1 - p[:, 1]])

    joint = drawing_joint(
        svg.values.get("data-joint"),
        f"{source}: no data-joint on <svg>",
        f"{source}: <svg data-joint={svg.values.get('data-joint')!r}>",
        params,
    )
    grout = None
    if (
        isinstance(mesh_el, se.Shape)
        and mesh_el.fill is not None
        and mesh_el.fill.value is not None
    ):
        grout = color_hex(_rgb(mesh_el.fill))
    skipped: dict[str, int] = {}
    tiles: list[DrawnTile] = []
    for k, el in enumerate(svg.elements()):
        if isinstance(el, se.Text):
            skipped["text"] = skipped.get("text", 0) + 1
            continue
        if not isinstance(el, se.Shape) or el is mesh_el:
            continue
        if el.fill is None or el.fill.value is None:
            skipped["unfilled shape"] = skipped.get("unfilled shape", 0) + 1
            continue
        name = el.id or f"{type(el).__name__.lower()}_{k}"
        where = f"{source}: <{type(el).__name__.lower()} id={name!r}>"
        tiles.extend(_element_tiles(el, name, where, to_mm, rules=rules, params=params))
    if skipped:
        what = ", ".join(f"{n} {kind}" for kind, n in sorted(skipped.items()))
        warnings.warn(f"{source}: skipped {what} (not tiles)", DesignFileWarning, stacklevel=3)
    if not tiles:
        raise DesignError(f"{source}: no tiles (closed, filled shapes) in the drawing")
    classes = DrawnClasses(rules, params.same_shape_tolerance_mm, params.decimals)
    out: dict[str, Any] = {
        "name": str(svg.values.get("data-name") or Path(path).stem),
        "mesh": {"width": x1 - x0, "height": y1 - y0},
        "joint": joint,
        "slots": [classes.slot(t) for t in tiles],
    }
    if grout is not None:
        out["grout_color"] = grout
    return out


def _rgb(color: Any) -> tuple[float, float, float]:
    return (color.red / 255.0, color.green / 255.0, color.blue / 255.0)


def _element_tiles(
    el: Any, name: str, where: str, to_mm: Any, *, rules: DesignRules, params: DesignFileParams
) -> list[DrawnTile]:
    """The tiles of one filled element: its sub-paths nested into outlines and holes."""
    import svgelements as se  # noqa: PLC0415

    sub = _Subpaths(where, to_mm, params)
    for seg in se.Path(el).segments():
        sub.add(seg)
    sub.finish(False)
    loops: list[Loop] = []
    winding: list[float] = []
    for k, (v, b) in enumerate(sub.done):
        loops.append(loop_from_nodes(v, b, f"{where} sub-path {k}", params.curve_tolerance_mm))
        winding.append(float(np.sign(_signed_area(v))))
    even_odd = str(el.values.get("fill-rule", "nonzero")).strip() == "evenodd"
    names = [f"{name} sub-path {k}" for k in range(len(loops))]
    nested = nest_loops(loops, names, rules.check_step_mm)
    color = _rgb(el.fill)
    tiles = []
    for n, (i, holes) in enumerate(nested):
        cut = [h for h in holes if even_odd or winding[h] != winding[i]]
        label = name if len(nested) == 1 else f"{name}_{n}"
        tiles.append(DrawnTile(label, TilePath(loops[i], tuple(loops[h] for h in cut)), color))
    return tiles


def _signed_area(v: FloatArray) -> float:
    x, y = v[:, 0], v[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def _loop_d(loop: Loop, height: float, decimals: int) -> str:
    """SVG path data of a closed loop (y flipped for the SVG frame), arcs as arcs."""

    def f(v: float) -> str:
        text = f"{v:.{decimals}f}".rstrip("0").rstrip(".")
        return "0" if text in ("-0", "") else text

    v = loop.vertices
    parts = [f"M {f(v[0, 0])} {f(height - v[0, 1])}"]
    n = len(v)
    for i in range(n):
        q = v[(i + 1) % n]
        b = float(loop.bulges[i])
        end = f"{f(q[0])} {f(height - q[1])}"
        if b == 0.0:
            parts.append(f"L {end}" if i < n - 1 else "Z")
            continue
        chord = float(np.hypot(*(q - v[i])))
        radius = chord * (1.0 + b * b) / (4.0 * abs(b))
        large = int(abs(b) > 1.0)
        sweep = int(b < 0.0)  # counter-clockwise with y up is clockwise with SVG's y down
        parts.append(f"A {f(radius)} {f(radius)} 0 {large} {sweep} {end}")
        if i == n - 1:
            parts.append("Z")
    return " ".join(parts)


def svg_text(design: DesignFields, params: DesignFileParams | None = None) -> str:
    """The design as an SVG document (millimetres; see the module docstring)."""
    params = params or DesignFileParams.load()
    w, h = design.mesh_size
    d = params.decimals
    lines = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{w:g}mm" height="{h:g}mm" '
        f'viewBox="0 0 {w:g} {h:g}" data-joint="{design.joint:g}" '
        f"data-name={quoteattr(design.name)}>",
        f"  <title>{escape(design.name)}</title>",
    ]
    if design.description:
        lines.append(f"  <desc>{escape(design.description)}</desc>")
    lines.append(
        f'  <rect id="mesh" x="0" y="0" width="{w:g}" height="{h:g}" '
        f'fill="{color_hex(design.grout_color)}"/>'
    )
    for s in design.slots:
        loops = (s.path.outer, *s.path.holes)
        data = " ".join(_loop_d(lp, h, d) for lp in loops)
        lines.append(
            f'  <path id={quoteattr(s.name)} fill="{color_hex(s.color)}" '
            f'fill-rule="evenodd" d="{data}"/>'
        )
    lines.append("</svg>")
    return "\n".join(lines) + "\n"


__all__ = ["PPI", "read_svg", "svg_text"]
