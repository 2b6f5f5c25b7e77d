"""Extraction from images: known renderings, partial tiles, bad input, synthetic views."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import cv2
import numpy as np
import pytest

from qshape import Boundary, Figure, Tolerances, describe, match
from qshape.design import Design
from qshape.errors import QShapeError
from qshape.synthetic.render import render_design, save_png
from qshape.synthetic.synth import SynthParams, generate
from qshape.vision.extract import extract, extract_detailed, read_image
from qshape.vision.params import ExtractParams, ImageError

S = 3.0  # px/mm of the test renderings

KNOWN = {
    "name": "known",
    "mesh": {"width": 200, "height": 140},
    "joint": 2.0,
    "grout_color": "#d9d4c7",
    "slots": [
        {
            "name": "square",
            "shape": {"kind": "square", "size": 36},
            "color": "#c0392b",
            "pose": {"x": 30, "y": 110, "angle": 20},
        },
        {
            "name": "ell",
            "shape": {
                "kind": "polygon",
                "vertices": [[0, 0], [40, 0], [40, 18], [18, 18], [18, 40], [0, 40]],
            },
            "color": "#3f9e4d",
            "pose": {"x": 90, "y": 105},
        },
        {
            "name": "triangle",
            "shape": {"kind": "triangle_right", "width": 44, "height": 30},
            "color": "#2e6fd1",
            "pose": {"x": 160, "y": 110, "angle": -35},
        },
        {
            "name": "semicircle",
            "shape": {"kind": "semicircle", "radius": 22},
            "color": "#e8c33a",
            "pose": {"x": 35, "y": 40, "angle": 60},
        },
        {
            "name": "circle",
            "shape": {"kind": "circle", "radius": 20},
            "color": "#8e4fb5",
            "pose": {"x": 100, "y": 38},
        },
        {
            "name": "holed",
            "shape": {
                "kind": "square",
                "size": 44,
                "holes": [{"kind": "square", "size": 14, "x": 10, "y": 10}],
            },
            "color": "#e07b2a",
            "pose": {"x": 160, "y": 40, "angle": 10},
        },
    ],
}

EXPECTED = {  # points, curve points, holes
    "square": (4, 0, 0),
    "ell": (6, 0, 0),
    "triangle": (3, 0, 0),
    "semicircle": (3, 1, 0),
    "circle": (4, 2, 0),
    "holed": (4, 0, 1),
}


def _px_figure(fig: Figure, s: float) -> Figure:
    holes = [Boundary.make(h.points * s, h.curve_mask) for h in fig.holes]
    return Figure.from_polygon(fig.points * s, holes, fig.color, curve_mask=fig.curve_mask)


@pytest.fixture(scope="module")
def known() -> tuple[Design, np.ndarray, list[Figure]]:
    design = Design.from_dict(KNOWN)
    image = render_design(design, S)
    return design, image, extract(image)


def _nearest(figs: list[Figure], design: Design, name: str) -> Figure:
    slot = design.slot(name)
    target = np.array([slot.x * S, (design.mesh_size[1] - slot.y) * S])
    return min(figs, key=lambda f: float(np.hypot(*(f.centroid - target))))


def test_known_figures_found(known: tuple[Design, np.ndarray, list[Figure]]) -> None:
    design, _, figs = known
    assert len(figs) == len(design.slots)
    for f in figs:
        assert f.y_down


@pytest.mark.parametrize("name", list(EXPECTED))
def test_known_figure_details(name: str, known: tuple[Design, np.ndarray, list[Figure]]) -> None:
    design, _, figs = known
    slot = design.slot(name)
    fig = _nearest(figs, design, name)
    n_points, n_curves, n_holes = EXPECTED[name]
    assert len(fig.points) == n_points
    assert int(fig.curve_mask.sum()) == n_curves
    assert len(fig.holes) == n_holes
    assert fig.color is not None
    np.testing.assert_allclose(fig.color, slot.color, atol=0.03)
    ref = _px_figure(slot.figure(), S)
    assert fig.area == pytest.approx(ref.area, rel=0.03)
    tol = Tolerances(joint_width=design.joint * S)
    assert describe(fig, tol).type_curve == describe(ref, tol).type_curve
    m = match(ref, fig, tol, use_color=True)
    assert m is not None
    if slot.symmetry != 0:
        period = 2 * math.pi / slot.symmetry
        assert min(abs(math.remainder(r, period)) for r in m.rotations) < math.radians(1.5)


def test_known_labels(known: tuple[Design, np.ndarray, list[Figure]]) -> None:
    design, _, figs = known
    tol = Tolerances(joint_width=design.joint * S)
    ell = describe(_nearest(figs, design, "ell"), tol)
    assert [n.labels[1] for n in ell.outer.nodes].count("concave") == 1
    assert all(n.labels[0] == "right" for n in ell.outer.nodes)
    semi = describe(_nearest(figs, design, "semicircle"), tol)
    curve = [n for n in semi.outer.nodes if n.kind == "curve"]
    assert len(curve) == 1 and "semicircle" in curve[0].admissible[2]
    holed = describe(_nearest(figs, design, "holed"), tol)
    assert holed.type_hole == "with holes" and len(holed.holes) == 1


def test_relevant_points_on_corners(known: tuple[Design, np.ndarray, list[Figure]]) -> None:
    design, _, figs = known
    for name in ("square", "ell", "triangle"):
        slot = design.slot(name)
        truth = slot.figure().points * np.array([S, -S]) + [0, design.mesh_size[1] * S]
        fig = _nearest(figs, design, name)
        d = np.hypot(*(truth[:, None, :] - fig.points[None, :, :]).transpose(2, 0, 1))
        # Corners (acute tips and the concave one included) refined by fitted edge lines.
        assert d.min(axis=1).max() < 1.5, name
        assert np.median(d.min(axis=1)) < 1.5, name


def test_border_tiles_are_partial(known: tuple[Design, np.ndarray, list[Figure]]) -> None:
    design, image, _ = known
    cut_px = 60
    crop = image[:, cut_px:]
    cut = sum(s.outline_mm()[:, 0].min() * S < cut_px + 1 for s in design.slots)
    gone = sum(s.outline_mm()[:, 0].max() * S < cut_px for s in design.slots)
    assert cut - gone >= 1
    res = extract_detailed(crop)
    assert len(res.figures) == len(design.slots) - cut
    assert len(res.partial) == cut - gone
    for p in res.partial:
        assert p.area > 0 and p.outline.shape[1] == 2


def test_colour_robust_to_shading(known: tuple[Design, np.ndarray, list[Figure]]) -> None:
    design, image, _ = known
    h, w = image.shape[:2]
    ramp = np.linspace(0.85, 1.15, w)[None, :, None]
    shaded = np.clip(image * ramp, 0, 255).astype(np.uint8)
    figs = extract(shaded)
    assert len(figs) == len(design.slots)
    for slot in design.slots:
        fig = _nearest(figs, design, slot.name)
        assert fig.color is not None
        assert math.dist(fig.color, slot.color) < 0.06, slot.name


@pytest.mark.parametrize("reduction", [1, 2])
def test_touching_tiles_split_by_canny(reduction: int, extract_params: ExtractParams) -> None:
    data = {
        "name": "touch",
        "mesh": {"width": 100, "height": 60},
        "joint": 0.5,
        "slots": [
            {
                "name": "a",
                "shape": {"kind": "square", "size": 30},
                "color": "#c0392b",
                "pose": {"x": 34.75, "y": 30},
            },
            {
                "name": "b",
                "shape": {"kind": "square", "size": 30},
                "color": "#2e6fd1",
                "pose": {"x": 65.25, "y": 30},
            },
        ],
    }
    design = Design.from_dict(data)
    image = render_design(design, S)
    # Close the 0.5 mm joint: the two tiles touch.
    lo, hi = round(49.5 * S), round(50.5 * S) + 1
    image[:, lo:hi] = image[:, lo - 1 : lo]
    on = replace(extract_params, canny_reduction=reduction)
    assert len(extract(image, on)) == 2
    off = replace(on, split_touching=False)
    assert len(extract(image, off)) == 1


@pytest.mark.parametrize(
    "bad",
    [
        np.zeros((0, 0, 3), np.uint8),
        np.zeros((100, 100, 3), np.float32),
        np.zeros((100, 100), np.uint8),
        np.zeros((100, 100, 4), np.uint8),
        np.zeros((8, 8, 3), np.uint8),
        np.zeros((9000, 20, 3), np.uint8),
        [[1, 2, 3]],
    ],
)
def test_bad_input(bad: object) -> None:
    with pytest.raises(ImageError):
        extract(bad)  # type: ignore[arg-type]
    assert issubclass(ImageError, QShapeError)


@pytest.mark.parametrize("level", [0, 137, 255])
def test_uniform_picture_is_an_empty_belt(level: int) -> None:
    image = np.full((120, 160, 3), level, np.uint8)
    res = extract_detailed(image)
    assert res.figures == [] and res.partial == [] and res.rejected == []
    assert res.background == pytest.approx((level / 255.0,) * 3)
    assert extract(image) == []


def test_uniform_noise_gives_no_figures() -> None:
    rng = np.random.default_rng(3)
    noise = rng.integers(0, 256, (1000, 1000, 3), dtype=np.uint8)
    res = extract_detailed(noise)
    assert res.figures == [] and res.partial == []
    assert any("no dominant background" in r for r in res.rejected)


def test_narrow_hole_filter_uses_twice_area_over_perimeter(extract_params: ExtractParams) -> None:
    """A hole is kept when 2 x area / perimeter (its width) reaches ``min_hole_width_px``.

    The slit's width is measured as extraction traces it; thresholds at 0.7 and 1.3 x that
    width put it between one and two minimum widths (kept) and below one (dropped).
    """
    image = np.full((240, 240, 3), 60, np.uint8)
    image[40:200, 40:200] = (200, 60, 50)
    image[80:160, 117:123] = 60  # a 6 x 80 px slit
    kept = extract(image)
    assert len(kept) == 1 and len(kept[0].holes) == 1
    res = extract_detailed(image)
    fg = np.zeros((240, 240), np.uint8)
    cv2.fillPoly(fg, [np.round(res.outlines[0]).astype(np.int32)], 255)
    fg[80:160, 117:123] = 0
    contours, hier = cv2.findContours(fg, cv2.RETR_CCOMP, cv2.CHAIN_APPROX_NONE)
    hole = next(c for c, h in zip(contours, hier[0], strict=True) if h[3] != -1)
    width = 2.0 * cv2.contourArea(hole) / cv2.arcLength(hole, True)
    base = extract_params
    between = replace(base, min_hole_width_px=0.7 * width, min_hole_area_px=10.0)
    above = replace(base, min_hole_width_px=1.3 * width, min_hole_area_px=10.0)
    assert len(extract(image, between)[0].holes) == 1
    assert len(extract(image, above)[0].holes) == 0
    square = image.copy()
    square[80:160, 117:123] = (200, 60, 50)
    square[100:140, 100:140] = 60  # a wide hole is kept whatever the slit threshold
    assert len(extract(square, above)[0].holes) == 1


def test_no_tiles_is_empty() -> None:
    rng = np.random.default_rng(0)
    belt = np.clip(rng.normal(70, 3, (492, 656, 3)), 0, 255).astype(np.uint8)
    res = extract_detailed(belt)
    assert res.figures == [] and res.partial == []


def test_read_image(tmp_path: Path, known: tuple[Design, np.ndarray, list[Figure]]) -> None:
    _, image, _ = known
    path = save_png(image, tmp_path / "k.png")
    np.testing.assert_array_equal(read_image(path), image)
    with pytest.raises(ImageError, match="cannot read"):
        read_image(tmp_path / "none.png")
    (tmp_path / "junk.png").write_bytes(b"not a png")
    with pytest.raises(ImageError):
        read_image(tmp_path / "junk.png")


def test_params_load_and_validate(extract_params: ExtractParams) -> None:
    p = extract_params
    assert p.outline.max_curve_turn_deg >= 200.0
    with pytest.raises(ImageError):
        ExtractParams(threshold_min=50.0, threshold_max=10.0)
    with pytest.raises(ImageError, match="canny_reduction"):
        ExtractParams(canny_reduction=0)


def test_synthetic_view_matches_slots(synth_params: SynthParams, design: Design) -> None:
    sp = synth_params
    img = generate(design, 10, 11, sp)
    res = extract_detailed(img.image)
    assert len(res.figures) == len(img.tiles)
    tol = Tolerances(joint_width=design.joint * sp.px_per_mm)
    ok = 0
    for t in img.tiles:
        fig = min(res.figures, key=lambda f: float(np.hypot(*(f.centroid - t.center_px))))
        assert np.hypot(*(fig.centroid - t.center_px)) < 2.0
        ref = _px_figure(t.slot.figure(), sp.px_per_mm)
        m = match(ref, fig, tol, use_color=True)
        if m is None:
            continue
        ok += 1
        if t.slot.symmetry:
            period = 2 * math.pi / t.slot.symmetry
            err = min(abs(math.remainder(r - t.rotation, period)) for r in m.rotations)
            assert math.degrees(err) < 2.0
    assert ok >= len(img.tiles) - 1


# --- Cell-scale pixel outlines (the cell's input camera sees the belt at 2 px/mm) ----------
CELL_PX_PER_MM = 2.0


def _posed_slots(shape: dict, angles: list[float], color: str, pitch: float) -> Design:
    """One slot of ``shape`` per angle [deg], on a grid ``pitch`` mm apart, dark grout."""
    per_row = 12
    slots = [
        {
            "name": f"s{k}",
            "shape": shape,
            "color": color,
            "pose": {
                "x": pitch * (0.5 + k % per_row),
                "y": pitch * (0.5 + k // per_row),
                "angle": a,
            },
        }
        for k, a in enumerate(angles)
    ]
    rows = -(-len(angles) // per_row)
    mesh = {"width": pitch * min(per_row, len(angles)), "height": pitch * rows}
    return Design.from_dict(
        {"name": "posed", "mesh": mesh, "joint": 2.0, "grout_color": "#3d4247", "slots": slots}
    )


@pytest.mark.parametrize("px_per_mm", [1.7, 1.8, CELL_PX_PER_MM])
def test_coarse_arcs_are_not_split(px_per_mm: float) -> None:
    # The pixel staircase of a traced 20-24 mm arc at ~2 px/mm turns the outline by more
    # than corner_angle_deg over the corner window: only the change in excess of the arc's
    # own turning may make a corner (vision.yaml extract.outline.arc_turning_deg).
    angles = [float(a) for a in range(0, 180, 15)]
    for radius in (20.0, 22.0, 24.0):
        design = _posed_slots({"kind": "semicircle", "radius": radius}, angles, "#e8c33a", 60.0)
        figs = extract(render_design(design, px_per_mm))
        assert len(figs) == len(angles)
        for fig in figs:
            assert len(fig.points) == 3 and int(fig.curve_mask.sum()) == 1, radius


def test_traced_circles_are_two_semicircles(synth_params: SynthParams, design: Design) -> None:
    # Where a traced closed curve is split depends on its noise; two unequal halves would
    # label one arc acute and the other plane (vision.yaml extract.outline.circle_residual).
    slots = [s for s in design.slots if s.name in ("ring_orange", "circle_teal")]
    sp = replace(synth_params, px_per_mm=CELL_PX_PER_MM)
    tol = Tolerances(joint_width=design.joint * CELL_PX_PER_MM)
    boundaries = 0
    for seed in range(4):
        img = generate(slots, 8, seed, sp)
        figs = extract(img.image)
        assert len(figs) == len(img.tiles)
        for fig in figs:
            d = describe(fig, tol)
            for b in (d.outer, *(h.boundary for h in d.holes)):
                curves = [n for n in b.nodes if n.kind == "curve"]
                assert len(b.nodes) == 4 and len(curves) == 2
                assert all("semicircle" in n.admissible[2] for n in curves)
                boundaries += 1
    assert boundaries >= 30


@pytest.mark.parametrize("px_per_mm", [1.6, CELL_PX_PER_MM])
def test_square_hole_corners_are_single_vertices(px_per_mm: float) -> None:
    # A small square hole's corner, cut off or rounded by the pixel grid, must stay one
    # vertex (vision.yaml extract.outline.chamfer_fraction).
    holed = {
        "kind": "square",
        "size": 50.0,
        "holes": [{"kind": "square", "size": 18.0, "x": 11.0, "y": 11.0}],
    }
    angles = [float(a) for a in np.arange(0.0, 90.0, 3.0)]
    design = _posed_slots(holed, angles, "#c0392b", 75.0)
    figs = extract(render_design(design, px_per_mm))
    assert len(figs) == len(angles)
    for fig in figs:
        assert len(fig.points) == 4 and len(fig.holes) == 1
        assert len(fig.holes[0].points) == 4 and not fig.holes[0].curve_mask.any()
