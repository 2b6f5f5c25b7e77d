"""SVG and DXF designs: reading drawings, writing them, round trips and the errors."""

from __future__ import annotations

import math
import warnings
from pathlib import Path

import ezdxf
import numpy as np
import pytest
import shapely

from qshape.design import Design, bundled_designs
from qshape.design.generator import DesignGenerator
from qshape.errors import DesignError, DesignFileWarning

STEP = 0.2  # mm, outline sampling of the comparisons


def _change_mm(a: Design, b: Design) -> float:
    """Largest distance between two designs' slot outlines (both ways) and centroids."""
    assert [s.name for s in a.slots] == [s.name for s in b.slots]
    worst = 0.0
    for s, t in zip(a.slots, b.slots, strict=True):
        assert s.color == pytest.approx(t.color, abs=0.5 / 255)
        for la, lb in zip(
            (s.path.outer, *s.path.holes), (t.path.outer, *t.path.holes), strict=True
        ):
            pa, pb = la.dense(STEP), lb.dense(STEP)
            d1 = shapely.distance(shapely.LinearRing(pa), shapely.points(pb)).max()
            d2 = shapely.distance(shapely.LinearRing(pb), shapely.points(pa)).max()
            worst = max(worst, float(d1), float(d2))
        worst = max(worst, math.hypot(s.x - t.x, s.y - t.y))
    return worst


def _quiet_load(path: Path) -> Design:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return Design.load(path)


@pytest.mark.parametrize("fmt", ["svg", "dxf"])
@pytest.mark.parametrize(
    "name",
    [
        pytest.param(n, marks=pytest.mark.slow) if n == "trencadis" else n  # 42 shapes: 4 s
        for n in bundled_designs()
    ],
)
def test_bundled_designs_round_trip(tmp_path: Path, name: str, fmt: str) -> None:
    design = Design.load(name)
    path = tmp_path / f"{name}.{fmt}"
    design.to_svg(path) if fmt == "svg" else design.to_dxf(path)
    back = _quiet_load(path)
    assert back.mesh_size == pytest.approx(design.mesh_size, abs=1e-6)
    assert back.joint == design.joint and back.name == design.name
    assert _change_mm(design, back) <= 0.01
    # Tiles of one class stay one class, whatever their turn on the drawing.
    assert len({s.class_key for s in back.slots}) == len({s.class_key for s in design.slots})


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_generated_designs_round_trip(tmp_path: Path, seed: int) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        design = DesignGenerator().draw(np.random.default_rng(seed), name=f"random_{seed}")
    for fmt in ("svg", "dxf"):
        path = tmp_path / f"d.{fmt}"
        design.to_svg(path) if fmt == "svg" else design.to_dxf(path)
        assert _change_mm(design, _quiet_load(path)) <= 0.01


SVG_HEAD = (
    '<svg xmlns="http://www.w3.org/2000/svg" width="300mm" height="200mm" '
    'viewBox="0 0 300 200" data-joint="2.5">'
)


def _svg(tmp_path: Path, body: str, head: str = SVG_HEAD) -> Path:
    path = tmp_path / "drawing.svg"
    path.write_text(f"{head}\n{body}\n</svg>\n")
    return path


def test_svg_shapes_colours_transforms_holes_and_mesh(tmp_path: Path) -> None:
    body = """
    <rect id="mesh" x="0" y="0" width="300" height="200" fill="#d9d4c7"/>
    <g transform="translate(20 10)">
      <rect id="red" x="0" y="0" width="40" height="20" fill="#ff0000"/>
      <circle id="black" cx="80" cy="30" r="15" fill="black"/>
      <rect id="turned" x="0" y="0" width="40" height="20" fill="#ff0000"
            transform="translate(150 30) rotate(90)"/>
      <path id="eo" fill="rgb(0,128,0)" fill-rule="evenodd"
            d="M 0 100 H 50 V 150 H 0 Z M 10 110 H 30 V 130 H 10 Z"/>
      <path id="nz_same" fill="#0000ff"
            d="M 100 100 H 150 V 150 H 100 Z M 110 110 H 130 V 130 H 110 Z"/>
      <path id="nz_other" fill="#0000ff"
            d="M 200 100 H 250 V 150 H 200 Z M 210 110 V 130 H 230 V 110 Z"/>
    </g>
    <text x="5" y="5">a note</text>
    """
    with pytest.warns(DesignFileWarning, match="skipped 1 text"):
        d = Design.load(_svg(tmp_path, body))
    assert d.mesh_size == pytest.approx((300.0, 200.0)) and d.joint == 2.5
    assert d.grout_color == pytest.approx((0xD9 / 255, 0xD4 / 255, 0xC7 / 255))
    red = d.slot("red")
    # SVG y runs down from the top: the rect's centre (40, 20) is 180 mm above the bottom.
    assert (red.x, red.y) == pytest.approx((40.0, 180.0), abs=1e-6)
    assert red.color == (1.0, 0.0, 0.0) and red.area == pytest.approx(800.0, rel=1e-6)
    black = d.slot("black")
    assert black.color == (0.0, 0.0, 0.0)
    assert black.area == pytest.approx(math.pi * 15**2, rel=2e-3)
    # Drawn as four quarter arcs, read as a design's circle is: two half circles.
    assert black.local_path.outer.bulges.tolist() == pytest.approx([1.0, 1.0])
    turned = d.slot("turned")
    assert turned.class_key == red.class_key and abs(turned.angle) % 180 == pytest.approx(90.0)
    assert len(d.slot("eo").local_path.holes) == 1
    assert len(d.slot("nz_same").local_path.holes) == 0  # the same winding fills
    assert len(d.slot("nz_other").local_path.holes) == 1  # the other winding cuts


def test_svg_ellipse_and_beziers_become_arcs_within_the_tolerance(tmp_path: Path) -> None:
    body = """
    <ellipse id="oval" cx="100" cy="100" rx="40" ry="22" fill="#336699"/>
    <path id="drop" fill="#993366" d="M 200 60 C 240 90 240 140 200 150 C 160 140 160 90 200 60 Z"/>
    """
    with pytest.warns(DesignFileWarning):  # no data-joint: the default joint
        d = Design.load(_svg(tmp_path, body, SVG_HEAD.replace(' data-joint="2.5"', "")))
    assert d.joint == 2.0
    oval = d.slot("oval")
    assert np.any(oval.local_path.outer.bulges != 0.0) and len(oval.local_path.outer.bulges) >= 4
    t = np.linspace(0.0, 2 * np.pi, 20000)
    truth = np.column_stack([100 + 40 * np.cos(t), 100 + 22 * np.sin(t)])  # y flip: symmetric
    dense = oval.path.outer.dense(0.05)
    dist = shapely.distance(shapely.LinearRing(truth), shapely.points(dense))
    assert float(dist.max()) <= 0.05 + 1e-3
    assert np.count_nonzero(oval.figure().curve_mask) >= 4  # curve points kept


@pytest.mark.parametrize(
    ("body", "head", "match"),
    [
        (
            '<path id="hook" fill="#ff0000" d="M 10 10 L 50 10 L 50 50"/>',
            SVG_HEAD,
            "hook.*open path",
        ),
        (
            '<path id="bow" fill="#ff0000" d="M 10 10 L 50 50 L 50 10 L 10 50 Z"/>',
            SVG_HEAD,
            "bow.*crosses itself",
        ),
        (
            '<rect id="a" x="10" y="10" width="40" height="40" fill="#f00"/>'
            '<rect id="b" x="30" y="30" width="40" height="40" fill="#0f0"/>',
            SVG_HEAD,
            "'a' and 'b' overlap",
        ),
        (
            '<rect id="a" x="10" y="10" width="40" height="40" fill="#f00"/>',
            '<svg xmlns="http://www.w3.org/2000/svg" data-joint="2">',
            "no mesh",
        ),
        (
            '<rect id="a" x="10" y="10" width="40" height="40" fill="#f00"/>',
            SVG_HEAD.replace('width="300mm"', 'width="80%"'),
            "unknown units",
        ),
    ],
)
def test_svg_errors_name_the_element(tmp_path: Path, body: str, head: str, match: str) -> None:
    with pytest.raises(DesignError, match=match):
        _quiet_load(_svg(tmp_path, body, head))


def _dxf(units: int = 4, mesh: bool = True) -> ezdxf.document.Drawing:
    doc = ezdxf.new("R2010")
    doc.header["$INSUNITS"] = units
    doc.header.custom_vars.append("joint", "3")
    if mesh:
        doc.modelspace().add_lwpolyline(
            [(0, 0), (300, 0), (300, 300), (0, 300)], close=True, dxfattribs={"layer": "MESH"}
        )
    return doc


def test_dxf_outlines_colours_holes_units_and_annotations(tmp_path: Path) -> None:
    doc = _dxf()
    msp = doc.modelspace()
    # A square with a rounded (bulged) right edge, drawn clockwise, true colour.
    sq = msp.add_lwpolyline(
        [(10, 10, 0), (10, 50, 0), (50, 50, -0.3), (50, 10, 0)], format="xyb", close=True
    )
    sq.rgb = (20, 20, 20)
    msp.add_circle((150, 150), 30, dxfattribs={"color": 1})  # ACI 1: red
    msp.add_circle((150, 150), 10)  # inside the ring's circle: its hole
    spline = msp.add_spline([(220, 40), (260, 60), (270, 100), (240, 120), (210, 90), (220, 40)])
    spline.closed = True
    spline.rgb = (0, 0, 255)
    msp.add_text("a note", dxfattribs={"insert": (5, 290)})
    msp.add_linear_dim(base=(0, 280), p1=(0, 0), p2=(300, 0)).render()
    path = tmp_path / "drawing.dxf"
    doc.saveas(path)
    with pytest.warns(DesignFileWarning, match="skipped 2 text and dimension"):
        d = Design.load(path)
    assert d.joint == 3.0 and d.mesh_size == pytest.approx((300.0, 300.0))
    square, disc, blob = d.slots
    assert square.color == pytest.approx((20 / 255,) * 3)
    assert np.count_nonzero(square.local_path.outer.bulges) == 1
    # A clockwise -0.3 bulge bows out of the tile: the area grows by the circular segment.
    theta = 4 * math.atan(0.3)
    r = 40 / (2 * math.sin(theta / 2))
    segment = r * r / 2 * (theta - math.sin(theta))
    assert square.area == pytest.approx(1600 + segment, rel=1e-3)
    assert disc.color == (1.0, 0.0, 0.0) and len(disc.local_path.holes) == 1
    assert disc.area == pytest.approx(math.pi * (30**2 - 10**2), rel=2e-3)
    assert blob.color == (0.0, 0.0, 1.0) and np.any(blob.local_path.outer.bulges != 0)


def test_dxf_insunits_are_honoured(tmp_path: Path) -> None:
    """The same numbers in centimetres: a tile and a mesh ten times as large."""
    doc = _dxf(units=5)
    doc.modelspace().add_lwpolyline(
        [(0, 0), (30, 0), (30, 30), (0, 30)], close=True, dxfattribs={"layer": "MESH"}
    )
    doc.modelspace().add_lwpolyline([(1, 1), (5, 1), (5, 3), (1, 3)], close=True)
    path = tmp_path / "cm.dxf"
    doc.saveas(path)
    d = _quiet_load(path)
    assert d.slots[0].area == pytest.approx(800.0) and (
        d.slots[0].x,
        d.slots[0].y,
    ) == pytest.approx((30.0, 20.0))


@pytest.mark.parametrize(
    ("edit", "match"),
    [
        (lambda msp: msp.add_line((10, 10), (40, 40)), r"LINE #\w+ on layer '0'.*open path"),
        (lambda msp: msp.add_lwpolyline([(10, 10), (40, 10), (40, 40)]), "open polyline"),
        (
            lambda msp: (msp.add_circle((50, 50), 20), msp.add_circle((70, 50), 20)),
            "overlap",
        ),
    ],
)
def test_dxf_errors_name_the_entity(tmp_path: Path, edit, match: str) -> None:
    doc = _dxf()
    edit(doc.modelspace())
    path = tmp_path / "bad.dxf"
    doc.saveas(path)
    with pytest.raises(DesignError, match=match):
        _quiet_load(path)


def test_dxf_without_mesh_or_with_unknown_units_is_refused(tmp_path: Path) -> None:
    doc = _dxf(mesh=False)
    doc.modelspace().add_circle((50, 50), 20)
    path = tmp_path / "bad.dxf"
    doc.saveas(path)
    with pytest.raises(DesignError, match="no mesh.*layer 'MESH'"):
        _quiet_load(path)
    doc = _dxf(units=99)
    doc.modelspace().add_circle((50, 50), 20)
    doc.saveas(path)
    with pytest.raises(DesignError, match=r"unknown units \(\$INSUNITS 99\)"):
        _quiet_load(path)
