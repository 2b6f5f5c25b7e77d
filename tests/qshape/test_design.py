"""Mosaic designs: bundled files, the format's validation, geometry, rendering and round trips."""

from __future__ import annotations

import copy
import math
from pathlib import Path

import numpy as np
import pytest

from qshape import Tolerances, describe, match
from qshape.design import Design, DesignError, Slot, bundled_designs
from qshape.errors import DesignLimitError, LimitError, QShapeError
from qshape.limits import Limits
from qshape.synthetic.render import render_design, save_png

BUNDLED = ["hexagon", "paper_mixed", "square_grid", "trencadis"]


@pytest.fixture(scope="module")
def designs() -> dict[str, Design]:
    return {name: Design.load(name) for name in BUNDLED}


def _base() -> dict:
    return {
        "name": "t",
        "mesh": {"width": 100, "height": 100},
        "joint": 2.0,
        "slots": [
            {
                "name": "a",
                "shape": {"kind": "square", "size": 20},
                "color": "#c0392b",
                "pose": {"x": 25, "y": 25},
            },
            {
                "name": "b",
                "shape": {"kind": "circle", "radius": 10},
                "color": [0.2, 0.4, 0.8],
                "pose": {"x": 70, "y": 70, "angle": 10},
            },
        ],
    }


def test_bundled_list_and_sizes(designs: dict[str, Design]) -> None:
    assert set(BUNDLED) <= set(bundled_designs())
    for d in designs.values():
        assert max(d.mesh_size) <= 250.0
        d.validate()
    assert 12 <= len(designs["paper_mixed"].slots) <= 20
    assert 35 <= len(designs["trencadis"].slots) <= 45
    assert len(designs["square_grid"].slots) == 25


def test_paper_mixed_covers_the_paper_set(designs: dict[str, Design]) -> None:
    d = designs["paper_mixed"]
    kinds = {s.shape["kind"] for s in d.slots}
    assert {
        "square",
        "rectangle",
        "triangle_right",
        "triangle_isosceles",
        "polygon",
        "circle",
        "semicircle",
    } <= kinds
    assert any(s.shape.get("holes") for s in d.slots) or "ring" in kinds
    # Repeated shapes in different colours.
    by_shape: dict[str, set[str]] = {}
    for s in d.slots:
        by_shape.setdefault(s.shape_key, set()).add(s.class_key)
    assert any(len(v) > 1 for v in by_shape.values())
    assert len({s.class_key[-7:] for s in d.slots}) >= 4
    for s in d.slots:
        extent = np.ptp(s.outline_mm(), axis=0).max()
        assert 20.0 <= extent <= 65.0, s.name
    # One concave tile (the L).
    ell = next(s for s in d.slots if s.shape["kind"] == "polygon")
    labels = [n.labels[1] for n in describe(ell.figure()).outer.nodes]
    assert labels.count("concave") == 1


def test_trencadis_has_convex_and_concave_pieces(designs: dict[str, Design]) -> None:
    concave = 0
    for s in designs["trencadis"].slots:
        nodes = describe(s.figure()).outer.nodes
        concave += any(n.labels[1] == "concave" for n in nodes)
    n = len(designs["trencadis"].slots)
    assert 0.2 * n <= concave <= 0.8 * n


@pytest.mark.parametrize(
    ("shape", "area", "symmetry", "points", "curves"),
    [
        ({"kind": "square", "size": 20}, 400.0, 4, 4, 0),
        ({"kind": "rectangle", "width": 30, "height": 10}, 300.0, 2, 4, 0),
        ({"kind": "regular_polygon", "sides": 6, "radius": 10}, 1.5 * math.sqrt(3) * 100, 6, 6, 0),
        ({"kind": "triangle_right", "width": 30, "height": 20}, 300.0, 1, 3, 0),
        ({"kind": "triangle_isosceles", "base": 20, "height": 30}, 300.0, 1, 3, 0),
        ({"kind": "circle", "radius": 10}, math.pi * 100, 0, 4, 2),
        ({"kind": "semicircle", "radius": 10}, math.pi * 50, 1, 3, 1),
        ({"kind": "ring", "radius": 10, "inner_radius": 4}, math.pi * 84, 0, 4, 2),
        ({"kind": "polygon", "vertices": [[0, 0], [20, 0, 1.0], [0, 0.0001]]}, None, 1, None, None),
        (
            {"kind": "polygon", "vertices": [[0, 0], [20, 0], [20, 10, 1.0], [0, 10]]},
            200 + math.pi * 50,
            1,
            5,
            1,
        ),
        (
            {
                "kind": "square",
                "size": 20,
                "holes": [{"kind": "square", "size": 6, "x": 4, "y": 4}],
            },
            364.0,
            1,
            4,
            0,
        ),
    ],
)
def test_shape_geometry(
    shape: dict, area: float | None, symmetry: int, points: int | None, curves: int | None
) -> None:
    slot = Slot("s", shape, (0.5, 0.5, 0.5), 50.0, 50.0, 33.0)
    if area is None:
        return  # only checks that a polygon with an arc compiles
    assert slot.area == pytest.approx(area, rel=2e-3)
    assert slot.symmetry == symmetry
    fig = slot.figure()
    assert fig.area == pytest.approx(area, rel=2e-3)
    np.testing.assert_allclose(fig.centroid, [50.0, 50.0], atol=0.05)
    assert len(fig.points) == points
    assert int(fig.curve_mask.sum()) == curves
    outline = slot.outline_mm()
    assert np.max(np.hypot(*np.diff(outline, axis=0).T)) <= slot.rules.outline_step_mm + 1e-9
    # Counter-clockwise, y up.
    x, y = outline.T
    assert np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y) > 0


def test_pose_rotates_about_centroid() -> None:
    a = Slot("a", {"kind": "rectangle", "width": 30, "height": 10}, (1, 0, 0), 40, 40, 0.0)
    b = Slot("b", {"kind": "rectangle", "width": 30, "height": 10}, (1, 0, 0), 40, 40, 90.0)
    ea, eb = np.ptp(a.outline_mm(), axis=0), np.ptp(b.outline_mm(), axis=0)
    np.testing.assert_allclose(ea, eb[::-1], atol=1e-6)
    m = match(a.figure(), b.figure(), Tolerances(), use_color=True)
    assert m is not None
    assert min(abs(math.remainder(r - math.pi / 2, math.pi)) for r in m.rotations) < 1e-6


def test_dict_round_trip(tmp_path: Path, designs: dict[str, Design]) -> None:
    for d in designs.values():
        path = tmp_path / f"{d.name}.yaml"
        d.save(path, "header line")
        again = Design.load(path)
        assert [s.to_dict() for s in again.slots] == [s.to_dict() for s in d.slots]
        assert again.mesh_size == d.mesh_size and again.joint == d.joint


@pytest.mark.parametrize(
    ("mutate", "message"),
    [
        (lambda d: d.update(colour="red"), "unknown key"),
        (lambda d: d["slots"][0].update(size=3), "slot 'a'"),
        (lambda d: d["slots"][0]["shape"].update(kind="star"), "allowed"),
        (lambda d: d["slots"][0]["shape"].update(size=-2), "must be > 0"),
        (lambda d: d["slots"][0]["shape"].update(size=0), "must be > 0"),
        (lambda d: d["slots"][0]["shape"].update(side=2), "unknown key"),
        (lambda d: d["mesh"].update(width=0), "mesh.width"),
        (lambda d: d.update(joint=-1), "joint"),
        (lambda d: d.update(slots=[]), "non-empty"),
        (lambda d: d.pop("mesh"), "missing key"),
        (lambda d: d["slots"][0].update(color="#12345"), "colour"),
        (lambda d: d["slots"][0].update(color=[1.5, 0, 0]), "colour"),
        (
            lambda d: d["slots"][0].update(
                shape={"kind": "polygon", "vertices": [[0, 0], [10, 0], [20, 0]]}
            ),
            "slot 'a'",
        ),
        (
            lambda d: d["slots"][0].update(
                shape={"kind": "polygon", "vertices": [[0, 0], [20, 12], [20, 0], [0, 8]]}
            ),
            "crosses itself",
        ),
        (
            lambda d: d["slots"][0].update(shape={"kind": "polygon", "vertices": [[0, 0], [1, 1]]}),
            "at least 3",
        ),
        (lambda d: d["slots"][1]["pose"].update(x=30, y=30), "overlap"),
        (lambda d: d["slots"][1]["pose"].update(x=25, y=45.8), "apart"),
        (lambda d: d["slots"][0]["pose"].update(x=5), "outside"),
        (lambda d: d["slots"][1].update(name="a"), "duplicate"),
        (
            lambda d: d["slots"][0]["shape"].update(holes=[{"kind": "square", "size": 8, "x": 9}]),
            "slot 'a'",
        ),
        (lambda d: d["slots"][0]["shape"].update(holes=[{"kind": "star"}]), r"holes\[0\]"),
        (lambda d: d["slots"][1]["shape"].update(kind="ring", inner_radius=12), "inner_radius"),
        (
            lambda d: d["slots"][0]["shape"].update(kind="regular_polygon", sides=2.5, radius=5),
            "sides",
        ),
        (lambda d: d["slots"][0].update(pose={"x": 25}), "pose needs"),
    ],
)
def test_malformed_designs(mutate, message: str) -> None:  # noqa: ANN001
    data = copy.deepcopy(_base())
    if callable(mutate):
        mutate(data)
        if "sides" in message:
            data["slots"][0]["shape"].pop("size", None)
    with pytest.raises(DesignError, match=message):
        Design.from_dict(data)


def test_valid_base_design() -> None:
    d = Design.from_dict(_base())
    assert [s.name for s in d.slots] == ["a", "b"]
    with pytest.raises(DesignError, match="no slot"):
        d.slot("zz")


def test_bad_files(tmp_path: Path) -> None:
    with pytest.raises(DesignError, match="no configuration file"):
        Design.load(tmp_path / "missing.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: [unclosed\n")
    with pytest.raises(DesignError):
        Design.load(bad)
    bad.write_text("- just\n- a list\n")
    with pytest.raises(DesignError):
        Design.load(bad)
    assert issubclass(DesignError, QShapeError)


def test_render_and_overlay(designs: dict[str, Design]) -> None:
    d = designs["paper_mixed"]
    img = render_design(d, 2.0)
    assert img.shape == (460, 460, 3) and img.dtype == np.uint8
    # Tile colour at a slot centroid (away from holes), grout in a corner.
    s = d.slot("square_red_1")
    px = img[round((d.mesh_size[1] - s.y) * 2), round(s.x * 2)]
    np.testing.assert_allclose(px / 255.0, s.color, atol=0.01)
    np.testing.assert_allclose(img[1, 1] / 255.0, d.grout_color, atol=0.01)
    over = render_design(d, 2.0, overlay=True)
    assert np.any(over != img)
    with pytest.raises(QShapeError):
        render_design(d, 0.0)


@pytest.mark.parametrize("name", BUNDLED)
def test_design_reloads_from_its_rendering(
    name: str, designs: dict[str, Design], tmp_path: Path
) -> None:
    d = designs[name]
    s = 4.0
    path = save_png(render_design(d, s), tmp_path / f"{name}.png")
    again = Design.from_image(path, mm_per_px=1.0 / s, joint_mm=d.joint, name=name)
    assert len(again.slots) == len(d.slots)
    np.testing.assert_allclose(again.mesh_size, d.mesh_size, atol=0.5)
    tol = Tolerances(joint_width=d.joint)
    centres = np.array([[t.x, t.y] for t in again.slots])
    for slot in d.slots:
        k = int(np.argmin(np.hypot(*(centres - [slot.x, slot.y]).T)))
        assert np.hypot(*(centres[k] - [slot.x, slot.y])) < 1.0, slot.name
        m = match(slot.figure(), again.slots[k].figure(), tol, use_color=True)
        assert m is not None, slot.name


# Pinned by mutation testing: changes these tests must notice.
def test_slot_touching_the_mesh_edge_is_inside() -> None:
    data = _base()
    data["slots"][0]["pose"] = {"x": 10, "y": 10}  # the 20 mm square ends exactly at 0
    data["slots"][1]["pose"] = {"x": 90, "y": 90}  # the r 10 circle ends exactly at 100
    d = Design.from_dict(data)
    lo = d.slots[0].outline_mm().min(axis=0)
    hi = d.slots[1].outline_mm().max(axis=0)
    np.testing.assert_allclose(lo, [0.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(hi, [100.0, 100.0], atol=1e-9)
    data["slots"][0]["pose"] = {"x": 9.9, "y": 10}
    with pytest.raises(DesignError, match="outside"):
        Design.from_dict(data)


@pytest.mark.parametrize("bulge", [0.3, 1.0, -0.5])
def test_arc_samples_lie_on_their_circle(bulge: float) -> None:
    data = _base()
    data["slots"][0]["shape"] = {
        "kind": "polygon",
        "vertices": [[-10, -10], [10, -10, bulge], [10, 10], [-10, 10]],
    }
    slot = Design.from_dict(data).slots[0]
    loop = slot.local_path.outer
    edge = int(np.flatnonzero(loop.bulges)[0])
    p = loop.edge_points(np.linspace(0.0, 1.0, 9), np.full(9, edge))
    nxt = loop.vertices[(edge + 1) % len(loop.vertices)]
    np.testing.assert_allclose(p[[0, 8]], [loop.vertices[edge], nxt], atol=1e-9)
    # The circle through the arc's ends and middle: every sample at the same distance.
    a, m, b = p[0], p[4], p[8]
    d = 2 * (a[0] * (m[1] - b[1]) + m[0] * (b[1] - a[1]) + b[0] * (a[1] - m[1]))
    ux = (a @ a * (m[1] - b[1]) + m @ m * (b[1] - a[1]) + b @ b * (a[1] - m[1])) / d
    uy = (a @ a * (b[0] - m[0]) + m @ m * (a[0] - b[0]) + b @ b * (m[0] - a[0])) / d
    r = np.hypot(p[:, 0] - ux, p[:, 1] - uy)
    np.testing.assert_allclose(r, r[0], rtol=1e-9)
    chord = np.hypot(*(b - a))
    sagitta = abs(bulge) * chord / 2.0  # bulge = 2 sagitta / chord
    mid = 0.5 * (a + b)
    assert np.hypot(*(m - mid)) == pytest.approx(sagitta, rel=1e-9)


@pytest.mark.parametrize(
    ("mutate", "where"),
    [
        (lambda d: d["slots"][0]["shape"].update(size=1e12), r"slot 'a'.*outline length: 4e\+12"),
        (lambda d: d["slots"][1]["shape"].update(radius=1e9), r"slot 'b'.*outline length"),
        (lambda d: d["mesh"].update(width=1e12), r"mesh width: 1e\+12"),
    ],
)
def test_a_design_above_the_size_cap_is_refused_before_any_allocation(mutate, where) -> None:  # noqa: ANN001
    import tracemalloc  # noqa: PLC0415

    data = copy.deepcopy(_base())
    mutate(data)
    tracemalloc.start()
    try:
        with pytest.raises(DesignLimitError, match=where) as exc:
            Design.from_dict(data)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 10_000_000  # [B]: refused before sampling 4e12 mm of outline (116 TiB)
    assert "max_design_mm=10000" in str(exc.value)
    assert isinstance(exc.value, LimitError) and isinstance(exc.value, DesignError)


def test_a_design_at_the_size_cap_loads() -> None:
    cap = Limits.load().max_design_mm
    data = copy.deepcopy(_base())
    data["mesh"] = {"width": cap, "height": 100}
    assert Design.from_dict(data).mesh_size == (cap, 100)
    with pytest.raises(DesignLimitError):
        data["mesh"]["width"] = cap * 1.001
        Design.from_dict(data)
