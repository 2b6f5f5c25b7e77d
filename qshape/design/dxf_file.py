"""DXF designs: reading a CAD drawing and writing one (through ``ezdxf``).

Reading (`read_dxf`): units from ``$INSUNITS`` (converted to millimetres; 0, unitless, is
taken as millimetres with a `qshape.errors.DesignFileWarning`; a code ``ezdxf`` does not know
is an error). In the modelspace, closed ``LWPOLYLINE``s (bulges: circular arcs), ``CIRCLE``s
and closed ``SPLINE``s and ``ELLIPSE``s are outlines; an outline inside another tile's is its
hole (`qshape.design.drawn.nest_loops`); each tile has its entity's true colour, else its ACI
colour (by layer when ``BYLAYER``). Splines and ellipses become circular arcs within
``curve_tolerance_mm`` (`qshape.design.arc_fit`). The mesh is the closed rectangle on layer
``MESH``; the joint width the ``joint`` custom property of the header (else
``default_joint_mm``, with a warning). Text and dimension entities are skipped with one
warning; an open outline (``LINE``, ``ARC``, an open polyline or spline) is an error naming the
entity's handle and layer. Slot names are read from the entity's ``MOSAIC`` XDATA when
present (as written here), else ``<TYPE>_<handle>``.

Writing (`write_dxf`): ``$INSUNITS`` 4 (mm), the mesh on layer ``MESH``, each slot's outline and
holes as closed ``LWPOLYLINE``s with bulges on layer ``TILES`` (holes on ``HOLES``), true
colours, the slot name as XDATA, the design's name, joint and joint colour as custom header
properties.
"""

from __future__ import annotations

import math
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from qshape.design.arc_fit import fit_arcs
from qshape.design.drawn import DrawnClasses, DrawnTile, loop_from_nodes, nest_loops
from qshape.design.fields import DesignFields
from qshape.design.file_params import DesignFileParams, drawing_joint
from qshape.design.paths import Loop, TilePath
from qshape.design.rules import DesignRules
from qshape.design.values import color_hex, parse_color
from qshape.errors import DesignError, DesignFileWarning
from qshape.geometry import FloatArray

MESH_LAYER = "MESH"
"""Layer of the mesh rectangle."""
APP_ID = "MOSAIC"
"""XDATA application name holding a slot's name."""
SKIPPED_TYPES = frozenset(
    {"TEXT", "MTEXT", "DIMENSION", "ARC_DIMENSION", "LEADER", "MLEADER", "ATTRIB", "ATTDEF"}
)
"""Annotation entities loading skips (with one warning)."""
INSUNITS_MM = 4
"""``$INSUNITS`` code of millimetres."""


def _units(doc: Any, source: str) -> float:
    from ezdxf import units  # noqa: PLC0415 - only DXF loading needs it

    code = int(doc.header.get("$INSUNITS", 0))
    if code == 0:
        warnings.warn(
            f"{source}: $INSUNITS 0 (unitless): read as millimetres",
            DesignFileWarning,
            stacklevel=4,
        )
        return 1.0
    try:
        return float(units.conversion_factor(code, INSUNITS_MM))  # type: ignore[arg-type]
    except (KeyError, IndexError, ValueError) as exc:
        raise DesignError(
            f"{source}: unknown units ($INSUNITS {code}); allowed: the DXF unit codes "
            "(4 millimetres, 5 centimetres, 1 inches, 6 metres, ...) or 0 (millimetres)"
        ) from exc


def _where(e: Any, source: str) -> str:
    return f"{source}: {e.dxftype()} #{e.dxf.handle} on layer {e.dxf.layer!r}"


def _rgb(doc: Any, e: Any) -> tuple[float, float, float]:
    from ezdxf import colors  # noqa: PLC0415

    if e.dxf.hasattr("true_color"):
        r, g, b = e.rgb
        return (r / 255.0, g / 255.0, b / 255.0)
    aci = int(e.dxf.color)
    if aci == colors.BYLAYER and e.dxf.layer in doc.layers:
        layer = doc.layers.get(e.dxf.layer)
        if layer.dxf.hasattr("true_color"):
            r, g, b = layer.rgb
            return (r / 255.0, g / 255.0, b / 255.0)
        aci = abs(int(layer.color))
    if aci in (colors.BYLAYER, colors.BYBLOCK):
        aci = 7
    r, g, b = colors.aci2rgb(aci)
    return (r / 255.0, g / 255.0, b / 255.0)


def _curve_nodes(e: Any, mm: float, params: DesignFileParams) -> tuple[FloatArray, FloatArray]:
    """A closed spline or ellipse as arcs within ``curve_tolerance_mm`` (in drawing mm)."""
    flat = params.curve_tolerance_mm / 5.0
    coarse = np.array([[p.x, p.y] for p in e.flattening(flat / mm)], dtype=np.float64) * mm
    seg = np.hypot(*np.diff(coarse, axis=0).T)
    along = np.concatenate([[0.0], np.cumsum(seg)])
    n = max(32, math.ceil(along[-1] / params.curve_step_mm))
    t = np.linspace(0.0, along[-1], n + 1)
    pts = np.column_stack([np.interp(t, along, coarse[:, 0]), np.interp(t, along, coarse[:, 1])])
    return fit_arcs(pts, params.curve_tolerance_mm - flat)


def _outline(
    e: Any, mm: float, params: DesignFileParams, where: str
) -> tuple[FloatArray, FloatArray] | None:
    """(vertices [mm], bulges) of a closed outline entity; None for entities that are none."""
    kind = e.dxftype()
    if kind == "LWPOLYLINE":
        pts = np.array(list(e.get_points("xyb")), dtype=np.float64).reshape(-1, 3)
        v, b = pts[:, :2] * mm, pts[:, 2]
        gap = float(np.hypot(*(v[-1] - v[0]))) if len(v) > 1 else 0.0
        if not e.closed:
            if gap > params.close_tolerance_mm:
                raise DesignError(f"{where}: an open polyline; allowed: closed outlines")
            v, b = v[:-1], b[:-1]
        return v, b
    if kind == "CIRCLE":
        c = np.array([e.dxf.center.x, e.dxf.center.y]) * mm
        r = float(e.dxf.radius) * mm
        return np.array([c - [r, 0.0], c + [r, 0.0]]), np.array([1.0, 1.0])
    if kind in ("SPLINE", "ELLIPSE"):
        closed = e.closed if kind == "SPLINE" else _full_ellipse(e)
        if not closed:
            start = e.construction_tool().point(0) if kind == "SPLINE" else None
            flat: list[Any] = [] if start is None else list(e.flattening(1.0))
            if (
                start is None
                or not flat
                or np.hypot(*(np.subtract(flat[-1][:2], flat[0][:2]))) * mm
                > params.close_tolerance_mm
            ):
                raise DesignError(f"{where}: an open curve; allowed: closed outlines")
        return _curve_nodes(e, mm, params)
    if kind in ("LINE", "ARC", "POLYLINE"):
        raise DesignError(f"{where}: an open path; allowed: closed LWPOLYLINE, CIRCLE, SPLINE")
    return None


def _full_ellipse(e: Any) -> bool:
    span = (float(e.dxf.end_param) - float(e.dxf.start_param)) % (2.0 * math.pi)
    return span < 1e-9 or abs(span - 2.0 * math.pi) < 1e-9


def read_dxf(
    path: str | Path, rules: DesignRules | None = None, params: DesignFileParams | None = None
) -> dict[str, Any]:
    """The design file mapping of a DXF drawing (see the module docstring).

    Raises:
        DesignError: Unreadable file, unknown units, no mesh, an open outline, a
            self-crossing or overlapping outline, a bad joint; the message names the entity.
    """
    import ezdxf  # noqa: PLC0415 - only DXF loading needs it

    rules, params = rules or DesignRules(), params or DesignFileParams.load()
    source = str(path)
    try:
        doc = ezdxf.readfile(str(path))
    except (OSError, ezdxf.DXFError) as exc:
        raise DesignError(f"{source}: not a readable DXF file ({exc})") from exc
    mm = _units(doc, source)
    custom = dict(doc.header.custom_vars)
    mesh = None
    loops: list[Loop] = []
    names: list[str] = []
    colors: list[tuple[float, float, float]] = []
    skipped = 0
    for e in doc.modelspace():
        kind = e.dxftype()
        if kind in SKIPPED_TYPES:
            skipped += 1
            continue
        where = _where(e, source)
        if e.dxf.layer.upper() == MESH_LAYER:
            if kind == "LWPOLYLINE" and (got := _outline(e, mm, params, where)) is not None:
                mesh = _rectangle(*got, where)
            continue
        got = _outline(e, mm, params, where)
        if got is None:
            continue
        loops.append(loop_from_nodes(*got, where, params.curve_tolerance_mm))
        names.append(_slot_name(e))
        colors.append(_rgb(doc, e))
    if skipped:
        warnings.warn(
            f"{source}: skipped {skipped} text and dimension entities",
            DesignFileWarning,
            stacklevel=3,
        )
    if mesh is None:
        raise DesignError(
            f"{source}: no mesh; allowed: a closed rectangle (LWPOLYLINE) on layer {MESH_LAYER!r}"
        )
    if not loops:
        raise DesignError(f"{source}: no tiles (closed outlines) in the modelspace")
    lo, hi = mesh
    loops = [lp.transformed(0.0, -lo) for lp in loops]
    tiles = [
        DrawnTile(names[i], TilePath(loops[i], tuple(loops[h] for h in holes)), colors[i])
        for i, holes in nest_loops(loops, names, rules.check_step_mm)
    ]
    classes = DrawnClasses(rules, params.same_shape_tolerance_mm, params.decimals)
    out: dict[str, Any] = {
        "name": str(custom.get("name") or Path(path).stem),
        "mesh": {"width": float(hi[0] - lo[0]), "height": float(hi[1] - lo[1])},
        "joint": drawing_joint(
            custom.get("joint"),
            f"{source}: no 'joint' custom property",
            f"{source}: custom property joint={custom.get('joint')!r}",
            params,
        ),
        "slots": [classes.slot(t) for t in tiles],
    }
    if custom.get("grout_color"):
        out["grout_color"] = color_hex(parse_color(custom["grout_color"], f"{source}: grout"))
    return out


def _slot_name(e: Any) -> str:
    if e.has_xdata(APP_ID):
        for code, value in e.get_xdata(APP_ID):
            if code == 1000:
                return str(value)
    return f"{e.dxftype()}_{e.dxf.handle}"


def _rectangle(v: FloatArray, b: FloatArray, where: str) -> tuple[FloatArray, FloatArray]:
    lo, hi = v.min(axis=0), v.max(axis=0)
    on_edge = np.minimum(np.abs(v - lo), np.abs(v - hi)).max(axis=1)
    if len(v) != 4 or np.any(b != 0.0) or float(on_edge.max()) > 1e-6 or np.any(hi - lo <= 0):
        raise DesignError(f"{where}: the mesh must be a closed axis-aligned rectangle")
    return lo, hi


def write_dxf(
    design: DesignFields, path: str | Path, params: DesignFileParams | None = None
) -> None:
    """Write the design as a DXF drawing (see the module docstring)."""
    import ezdxf  # noqa: PLC0415
    from ezdxf import colors  # noqa: PLC0415

    params = params or DesignFileParams.load()
    d = params.decimals
    doc = ezdxf.new("R2010", setup=False)
    doc.header["$INSUNITS"] = INSUNITS_MM
    doc.header["$MEASUREMENT"] = 1
    doc.header.custom_vars.append("name", design.name)
    doc.header.custom_vars.append("joint", f"{design.joint:g}")
    doc.header.custom_vars.append("grout_color", color_hex(design.grout_color))
    doc.appids.add(APP_ID)
    for layer in (MESH_LAYER, "TILES", "HOLES"):
        doc.layers.add(layer)
    msp = doc.modelspace()
    w, h = design.mesh_size
    msp.add_lwpolyline(
        [(0.0, 0.0), (w, 0.0), (w, h), (0.0, h)], close=True, dxfattribs={"layer": MESH_LAYER}
    )
    for s in design.slots:
        r, g, b = (int(round(c * 255)) for c in s.color)
        rgb = (r, g, b)
        for k, loop in enumerate((s.path.outer, *s.path.holes)):
            rows = [
                (round(float(x), d), round(float(y), d), float(b))
                for (x, y), b in zip(loop.vertices, loop.bulges, strict=True)
            ]
            e = msp.add_lwpolyline(
                rows, format="xyb", close=True, dxfattribs={"layer": "TILES" if k == 0 else "HOLES"}
            )
            e.rgb = rgb
            if k == 0:
                e.set_xdata(APP_ID, [(1000, s.name)])
            else:
                e.dxf.color = colors.BYLAYER
    doc.saveas(str(path))


__all__ = ["APP_ID", "MESH_LAYER", "read_dxf", "write_dxf"]
