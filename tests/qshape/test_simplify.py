"""Outline simplification (`qshape.outline.simplify`): relevant points and curves of dense
outlines, batched and alone; rough outlines keep their corners (the slope comparison's window)
and a rough hexagon stays a hexagon (bent runs of two edges are not arcs, ``fit_split_turn_deg``).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import replace
from pathlib import Path

import cv2
import numpy as np
import pytest

import qshape
from qshape import (
    Figure,
    InvalidFigureError,
    OutlineParams,
    Tolerances,
    canonical_key,
    describe,
    match,
)
from qshape.design import Design
from qshape.outline.fit import BendTest, bent_runs, outline_moments
from qshape.outline.simplify import simplify_outline
from qshape.synthetic.effects import CameraEffects, roughen
from qshape.synthetic.synth import SynthParams, generate
from qshape.theory.boundary import densify
from qshape.theory.figure import figures_from_outlines
from qshape.vision.extract import extract_detailed
from qshape.vision.params import ExtractParams, default_params

SEED = 5
DATA = Path(__file__).parents[1] / "data"
L_TILE = [[0, 0], [20, 0], [20, 8], [8, 8], [8, 20], [0, 20]]


def dense_outline(fig_points, curve_mask, spacing: float, rng, noise: float) -> np.ndarray:
    """Sample a boundary (arcs included) every ``spacing`` units, with uniform noise."""
    poly = densify(np.asarray(fig_points, float), np.asarray(curve_mask), per_arc=200)
    closed = np.vstack([poly, poly[:1]])
    seg = np.hypot(*np.diff(closed, axis=0).T)
    cum = np.r_[0.0, np.cumsum(seg)]
    s = np.arange(0.0, cum[-1], spacing)
    pts = np.stack([np.interp(s, cum, closed[:, 0]), np.interp(s, cum, closed[:, 1])], 1)
    start = int(rng.integers(0, len(pts)))
    return np.roll(pts, start, axis=0) + rng.uniform(-noise, noise, pts.shape)


PRIMITIVES = {
    "square": Figure.rectangle(20, 20),
    "rectangle": Figure.rectangle(30, 15),
    "right_triangle": Figure.from_polygon([[0, 0], [20, 0], [0, 20]]),
    "equilateral": Figure.regular_polygon(3, 12.0),
    "hexagon": Figure.regular_polygon(6, 12.0),
    "octagon": Figure.regular_polygon(8, 12.0),
    "l_tile": Figure.from_polygon(L_TILE),
    "circle": Figure.circle(10.0),
    "semicircle": Figure.semicircle(12.0),
    "ring": Figure.ring(12.0, 5.0),
}


@pytest.mark.parametrize("name", sorted(PRIMITIVES))
@pytest.mark.parametrize("trial", range(3))
def test_from_outline_gives_the_primitives_description(name, trial):
    rng = np.random.default_rng(SEED * 100 + trial)
    exact = PRIMITIVES[name]
    angle = rng.uniform(-math.pi, math.pi)
    c, s = math.cos(angle), math.sin(angle)
    rot = np.array([[c, s], [-s, c]])
    dense = dense_outline(exact.points @ rot, exact.curve_mask, 0.25, rng, 0.03)
    holes = [dense_outline(h.points @ rot, h.curve_mask, 0.25, rng, 0.03) for h in exact.holes]
    fig = Figure.from_outline(dense, holes, y_down=bool(trial % 2))
    if trial % 2:  # the same outline read as image coordinates: mirror it back to compare
        fig = Figure.from_outline(dense * [1, -1], [h * [1, -1] for h in holes], y_down=True)
    d_exact, d_fig = describe(exact), describe(fig)
    assert len(fig.points) == len(exact.points)
    assert d_fig.type_curve == d_exact.type_curve
    assert canonical_key(d_fig) == canonical_key(d_exact)
    m = qshape.match(d_exact, d_fig)
    assert m is not None
    if not m.continuous:
        assert min(abs(math.remainder(r + angle, 2 * math.pi)) for r in m.rotations) < 0.05
    assert fig.area == pytest.approx(exact.area, rel=0.02)


def test_pixel_scale_outline_with_default_params():
    # A 40 px tile traced at one-pixel spacing, half-pixel noise (camera-like).
    rng = np.random.default_rng(SEED)
    exact = Figure.rectangle(40, 24)
    dense = np.round(dense_outline(exact.points + 100, exact.curve_mask, 1.0, rng, 0.3))
    dense = dense[np.r_[True, np.any(np.diff(dense, axis=0) != 0, axis=1)]]
    fig = Figure.from_outline(dense, y_down=True)
    assert canonical_key(describe(fig)) == canonical_key(describe(exact))


def test_simplify_returns_points_and_mask():
    t = np.linspace(0, 2 * math.pi, 300, endpoint=False)
    pts, mask = simplify_outline(np.stack([np.cos(t), np.sin(t)], 1))
    assert pts.shape == (4, 2)
    assert mask.tolist() in ([False, True, False, True], [True, False, True, False])


@pytest.mark.parametrize(
    ("dense", "message"),
    [
        ([[0, 0], [1, 1]], "at least 3"),
        ([[0, 0], [1, 0], [float("nan"), 1]], "finite"),
        (np.zeros((10, 2)), "at least 3"),
        ([[0, 0], [1, 1], [2, 2], [3, 3]], "zero area"),
        (np.zeros((5, 3)), "shape"),
    ],
)
def test_bad_outlines_raise(dense, message):
    with pytest.raises(InvalidFigureError, match=message):
        Figure.from_outline(dense)


def test_params_are_used():
    t = np.linspace(0, 2 * math.pi, 400, endpoint=False)
    circle = np.stack([10 * np.cos(t), 10 * np.sin(t)], 1)
    three = Figure.from_outline(circle, params=OutlineParams(max_curve_turn_deg=130.0))
    assert int(three.curve_mask.sum()) == 3


def test_refine_corners_is_sub_sample_accurate_on_a_clean_polygon():
    rng = np.random.default_rng(SEED)
    tri = np.array([[0.0, 0.0], [100.0, 10.0], [30.0, 60.0]])
    dense = dense_outline(tri[::-1], np.zeros(3, bool), 0.5, rng, 0.0)
    plain, _ = simplify_outline(dense)
    refined, _ = simplify_outline(dense, OutlineParams(refine_corners=True))

    def worst(points: np.ndarray) -> float:
        return float(np.hypot(*(tri[:, None, :] - points[None]).transpose(2, 0, 1)).min(1).max())

    assert worst(refined) < 1e-6 < worst(plain)


@pytest.mark.parametrize(
    "field", ["arc_turning_deg", "circle_residual", "chamfer_fraction", "missed_corner_ratio"]
)
def test_cell_image_fixes_validate(field):
    with pytest.raises(qshape.ToleranceError, match=field):
        OutlineParams(**{field: -0.1})
    assert getattr(OutlineParams(), field) == 0.0  # off for the bundled (vector) outlines


def _cell_outline_params(missed_corner_ratio: float) -> OutlineParams:
    """The bundled pixel-outline parameters with ``missed_corner_ratio`` set."""
    return dataclasses.replace(default_params().outline, missed_corner_ratio=missed_corner_ratio)


def test_shallow_concave_corner_of_a_rendered_tile_is_a_corner_not_a_curve():
    # A trencadis piece as the cell's input camera rendered it (seed 2): its 34 deg concave
    # corner sits beside a long pixel staircase, so the window measure misses it and the two
    # edges came out as one curve (no design slot has that shape: the cell stalled).
    image = cv2.cvtColor(cv2.imread(str(DATA / "concave_tile_cell.png")), cv2.COLOR_BGR2RGB)
    params = default_params()
    (fig,) = qshape.extract(image, params)
    assert fig.curve_mask.tolist() == [False] * 5
    nodes = describe(fig, qshape.Tolerances.load(check_size=False)).nodes
    assert [n.labels[1] for n in nodes].count("concave") == 1
    assert all(n.kind == "vertex" for n in nodes)
    off = dataclasses.replace(params, outline=_cell_outline_params(0.0))
    (missed,) = qshape.extract(image, off)
    assert missed.curve_mask.any()


@pytest.mark.parametrize("arc_deg", [60.0, 90.0, 180.0])
def test_missed_corner_rule_keeps_arcs_curved(arc_deg):
    # A circular segment (arc + chord, radius 60 px) traced to whole pixels: the arc must stay
    # one curve, not become two straight edges.
    r, a = 60.0, math.radians(arc_deg) / 2
    t = np.linspace(-a, a, 400)
    arc = np.stack([r * np.sin(t), r * np.cos(t)], 1)
    x = np.linspace(r * math.sin(a), -r * math.sin(a), 200)[1:-1]
    chord = np.stack([x, np.full_like(x, r * math.cos(a))], 1)
    dense = np.round(np.vstack([arc, chord]) + 100.0)
    dense = dense[np.r_[True, np.any(np.diff(dense, axis=0) != 0, axis=1)]]
    _, mask = simplify_outline(dense, _cell_outline_params(0.035))
    assert mask.tolist().count(True) == 1


@pytest.mark.parametrize("sides", [3, 4, 6])
def test_rough_edges_keep_their_corners(sides: int, extract_params: ExtractParams) -> None:
    """A chipped, ground edge (~1 px of roughness on a 60 px polygon) is still one edge."""
    from qshape.synthetic.effects import roughen  # noqa: PLC0415

    p = extract_params.outline
    plain = dataclasses.replace(p, roughness_sigmas=0.0, min_corner_deg=0.0)
    ang = np.linspace(0.0, 2.0 * np.pi, sides, endpoint=False)
    v = 60.0 * np.stack([np.cos(ang), np.sin(ang)], axis=1) + 200.0
    dense = np.concatenate(
        [
            v[i] + (v[(i + 1) % sides] - v[i]) * np.linspace(0, 1, 200, endpoint=False)[:, None]
            for i in range(sides)
        ]
    )
    rng = np.random.default_rng(sides)
    good = bad_plain = 0
    for _ in range(10):
        rough = roughen(dense, 1.0, 2.5, rng)
        pts, mask = simplify_outline(rough, p)
        good += len(pts) == sides and not mask.any()
        pts0, mask0 = simplify_outline(rough, plain)
        bad_plain += len(pts0) != sides or bool(mask0.any())
    assert good >= 8
    assert good >= 10 - bad_plain  # the roughness checks never lose what plain finds


def test_batch_cleaning_matches_one_by_one() -> None:
    """A batch with faulty outlines gives each outline what simplifying it alone gives."""
    from qshape.outline.simplify import simplify_outlines  # noqa: PLC0415

    rng = np.random.default_rng(SEED)
    square = dense_outline(L_TILE, [False] * 6, 0.5, rng, 0.05)
    repeated = np.repeat(square, 2, axis=0)  # every point twice: dropped, same outline
    bad_nan = square.copy()
    bad_nan[3, 1] = np.nan
    batch = [square, repeated, bad_nan, square.tolist(), square[:2], square.astype(np.int64)]
    got = simplify_outlines(batch)
    for dense, out in zip(batch, got, strict=True):
        try:
            alone = simplify_outline(dense)
        except InvalidFigureError as exc:
            assert (
                isinstance(out, InvalidFigureError)
                and str(out).split(":", 1)[1] == str(exc).split(":", 1)[1]
            )
            continue
        assert not isinstance(out, InvalidFigureError)
        # Batched arc lengths are offset per outline: the same points to rounding.
        np.testing.assert_allclose(out[0], alone[0], rtol=0.0, atol=1e-9)
        np.testing.assert_array_equal(out[1], alone[1])
    assert isinstance(got[2], InvalidFigureError) and "finite" in str(got[2])
    np.testing.assert_allclose(got[1][0], got[0][0], rtol=0.0, atol=1e-9)  # type: ignore[index]


def test_corners_of_all_outlines_are_the_greedy_corners_of_each() -> None:
    """Batched corner picking equals the one-outline greedy rule (strongest first, spaced)."""
    from qshape.outline.corners import corners_many  # noqa: PLC0415

    rng = np.random.default_rng(SEED)
    n, spacing, threshold = 96, 5, 20.0
    change = rng.uniform(0.0, 60.0, (7, n))
    change[2] = 0.0  # no candidate at all
    change[3, ::7] = 45.0  # ties: the first of equal values wins
    got = corners_many(change, threshold, spacing)
    for row, corners in zip(change, got, strict=True):
        vals = np.where(row > threshold, row, -np.inf)
        want = []
        while np.isfinite(vals.max()):
            k = int(np.argmax(vals))
            want.append(k)
            d = np.abs(np.arange(n) - k)
            vals[np.minimum(d, n - d) <= spacing] = -np.inf
        np.testing.assert_array_equal(corners, sorted(want))
    assert len(got[2]) == 0


def test_roll_last_equals_numpy_roll() -> None:
    from qshape.outline.samples import roll_last  # noqa: PLC0415

    a = np.random.default_rng(2).normal(size=(2, 3, 7))
    for shift in range(-15, 16):
        np.testing.assert_array_equal(roll_last(a, shift), np.roll(a, shift, axis=-1))
    np.testing.assert_array_equal(roll_last(a[0], 3), np.roll(a[0], 3, axis=1))


def test_row_medians_equal_numpy_median() -> None:
    from qshape.outline.samples import row_medians  # noqa: PLC0415

    rng = np.random.default_rng(4)
    for n in (1, 2, 7, 384, 385):
        a = np.abs(rng.normal(size=(5, n)))
        a[0] = 1.0  # ties
        np.testing.assert_array_equal(row_medians(a), np.median(a, axis=1))


PX_PER_MM = 2.5  # the synthetic belt camera's scale
STEP_PX = 0.5  # spacing of the drawn outline samples, as a traced contour gives them
ROUGH_LENGTH_MM = 1.0  # correlation length of the drawn edge roughness
HEX_RADIUS_MM = 18.0  # the bundled hexagon tile's circumradius (= its side)
SAMPLES = 384  # samples of the unit tests' outlines
BEND = BendTest(min_turn_deg=45.0, arm=12)  # the bundled turn; arm: the spacing at 384 samples


def _dense(poly: np.ndarray) -> np.ndarray:
    """Samples every `STEP_PX` along the closed polygon ``poly``, shape (m, 2)."""
    closed = np.vstack([poly, poly[:1]])
    cum = np.r_[0.0, np.cumsum(np.hypot(*np.diff(closed, axis=0).T))]
    s = np.arange(0.0, cum[-1], STEP_PX)
    return np.stack([np.interp(s, cum, closed[:, 0]), np.interp(s, cum, closed[:, 1])], axis=1)


def _rounded_hexagon(radius_mm: float) -> np.ndarray:
    """The hexagon tile [mm] with corners rounded by arcs of ``radius_mm`` (as blur rounds them)."""
    pts = []
    for a in np.arange(6) * np.pi / 3:
        centre = (HEX_RADIUS_MM - radius_mm / np.sin(np.pi / 3)) * np.array([np.cos(a), np.sin(a)])
        for t in np.linspace(a - np.pi / 6, a + np.pi / 6, 8):
            pts.append(centre + radius_mm * np.array([np.cos(t), np.sin(t)]))
    return np.array(pts)


def _traced(poly_mm: np.ndarray, sigma_mm: float, rng: np.random.Generator) -> np.ndarray:
    """``poly_mm`` turned at random, in pixels, with rough edges, on whole pixels (traced)."""
    turn = rng.uniform(0.0, 2.0 * np.pi)
    offset = rng.uniform(200.0, 210.0, 2)
    rot = np.array([[np.cos(turn), -np.sin(turn)], [np.sin(turn), np.cos(turn)]])
    dense = _dense(poly_mm * PX_PER_MM @ rot.T) + offset
    rough = np.round(roughen(dense, sigma_mm * PX_PER_MM, ROUGH_LENGTH_MM * PX_PER_MM, rng))
    keep = np.r_[True, np.any(np.diff(rough, axis=0) != 0, axis=1)]
    return rough[keep]


def _params(on: bool) -> OutlineParams:
    """The bundled pixel-outline parameters, with or without the bent-run test."""
    params = ExtractParams.load().outline
    assert params.fit_split_turn_deg > 0.0
    return params if on else dataclasses.replace(params, fit_split_turn_deg=0.0)


def _hexagon_figure(sample: np.ndarray, on: bool) -> Figure:
    (fig,) = figures_from_outlines([sample], [[]], [None], _params(on), y_down=True)
    assert isinstance(fig, Figure)
    return fig


def _bent(points: np.ndarray, lo: int, hi: int) -> tuple[bool, int]:
    """`bent_runs` of the run [lo, hi) of the closed outline ``points`` (SAMPLES, 2)."""
    mom = outline_moments(points[None], np.array([np.ptp(points, axis=0).max()]))
    one = np.zeros(1, dtype=np.int64)
    bent, split = bent_runs(mom, one, one + lo, one + hi, BEND)
    return bool(bent[0]), int(split[0])


def _walk(poly: np.ndarray) -> np.ndarray:
    """`SAMPLES` samples uniform in arc length along the closed polygon ``poly`` (k, 2)."""
    closed = np.vstack([poly, poly[:1]])
    cum = np.r_[0.0, np.cumsum(np.hypot(*np.diff(closed, axis=0).T))]
    s = np.arange(SAMPLES) * cum[-1] / SAMPLES
    return np.stack([np.interp(s, cum, closed[:, 0]), np.interp(s, cum, closed[:, 1])], axis=1)


def test_two_edges_are_bent_at_their_corner() -> None:
    """A run over two sides of a hexagon (64 samples each) is bent, split at their corner."""
    hexagon = _walk(45.0 * np.array([[np.cos(a), np.sin(a)] for a in np.arange(6) * np.pi / 3]))
    bent, split = _bent(hexagon, 8, 120)  # the corner at sample 64
    assert bent
    assert abs(split - 64) <= 1
    assert not _bent(hexagon, 8, 60)[0]  # one side: straight


@pytest.mark.parametrize("degrees", [60, 90, 120, 180, 240])
def test_arcs_are_not_bent(degrees: int) -> None:
    """Runs along a circle, whatever they turn by, are arcs, not two edges."""
    t = np.arange(SAMPLES) * 2.0 * np.pi / SAMPLES
    circle = 40.0 * np.stack([np.cos(t), np.sin(t)], axis=1)
    assert not _bent(circle, 0, SAMPLES * degrees // 360)[0]


def test_a_shallow_bend_is_not_a_corner() -> None:
    """Two edges meeting at 30 deg (under the 45 deg turn) are not split."""
    poly = np.array([[0.0, 0.0], [60.0, 0.0], [60.0 + 60.0 * np.cos(np.pi / 6), 60.0 * 0.5]])
    poly = np.vstack([poly, [[30.0, -40.0]]])
    walk = _walk(poly)
    corner = int(np.argmin(np.hypot(*(walk - [60.0, 0.0]).T)))
    assert not _bent(walk, corner - 60, corner + 60)[0]


@pytest.mark.parametrize(("rounding_mm", "sigma_mm", "index"), [(3.0, 0.4, 5), (1.5, 0.6, 2)])
def test_rough_hexagons_that_became_circles_keep_six_corners(
    rounding_mm: float, sigma_mm: float, index: int
) -> None:
    """Seeded rough hexagons with blur-rounded corners that the arc merge turned into a circle
    (two semicircles): a bent run keeps its neighbours' corners and gets its own back."""
    rng = np.random.default_rng(1)
    poly = _rounded_hexagon(rounding_mm)
    for _ in range(index):
        _traced(poly, sigma_mm, rng)
    sample = _traced(poly, sigma_mm, rng)
    before = _hexagon_figure(sample, on=False)
    assert before.curve_mask.any()  # the failure: curves (a circle)
    after = _hexagon_figure(sample, on=True)
    assert len(after.points) == 6
    assert not after.curve_mask.any()
    tol = Tolerances.load(joint_width=2.0 * PX_PER_MM, point_tolerance=0.5 * PX_PER_MM)
    ref = describe(Figure.regular_polygon(6, HEX_RADIUS_MM * PX_PER_MM), tol)
    assert match(ref, describe(after, tol), tol, False) is not None


def test_rough_hexagons_are_recognised_more_often() -> None:
    """60 rough (0.4 mm) hexagons with corners rounded over 3 mm: 58 recognised, none with a
    curve (56 and 2 with curves without the bent-run test)."""
    tol = Tolerances.load(joint_width=2.0 * PX_PER_MM, point_tolerance=0.5 * PX_PER_MM)
    ref = describe(Figure.regular_polygon(6, HEX_RADIUS_MM * PX_PER_MM), tol)
    poly = _rounded_hexagon(3.0)
    counts = {}
    for on in (True, False):
        rng = np.random.default_rng(1)
        figs = [_hexagon_figure(_traced(poly, 0.4, rng), on) for _ in range(60)]
        good = sum(match(ref, describe(f, tol), tol, False) is not None for f in figs)
        counts[on] = (good, sum(bool(f.curve_mask.any()) for f in figs))
    assert counts[True][0] >= 58, counts
    assert counts[True][0] > counts[False][0], counts
    assert counts[True][1] == 0, counts


@pytest.mark.parametrize("sigma_mm", [0.4, 0.6])
def test_round_tiles_simplify_as_before(sigma_mm: float) -> None:
    """Rough circles, semicircles and rings (the bundled 21, 24 and 24 / 13 mm tiles) give
    the same figures with the bent-run test as without it: their runs are arcs."""
    t = np.linspace(0.0, 2.0 * np.pi, 400, endpoint=False)
    unit = np.stack([np.cos(t), np.sin(t)], axis=1)
    half = np.vstack([unit[:201] * 24.0, [[0.0, 0.0]]])
    rng = np.random.default_rng(3)
    changed = 0
    for _ in range(10):
        outlines = [_traced(unit * 21.0, sigma_mm, rng), _traced(half, sigma_mm, rng)]
        outlines.append(_traced(unit * 24.0, sigma_mm, rng))
        hole = _traced(unit * 13.0, sigma_mm, rng)  # moved into the ring's outer outline:
        holes = [[], [], [hole - hole.mean(axis=0) + outlines[2].mean(axis=0)]]
        figs = {
            on: figures_from_outlines(outlines, holes, [None] * 3, _params(on), y_down=True)
            for on in (True, False)
        }
        for a, b in zip(figs[True], figs[False], strict=True):
            assert isinstance(a, Figure)
            assert isinstance(b, Figure)
            same = np.array_equal(a.points, b.points) and all(
                np.array_equal(h.points, g.points) for h, g in zip(a.holes, b.holes, strict=True)
            )
            changed += not same
    assert changed == 0


def _recognised(design: Design, img, ep: ExtractParams, s: float) -> tuple[int, int]:
    """(tiles of the right class, tiles of a wrong class) among the whole tiles drawn."""
    tol = Tolerances.load(joint_width=design.joint * s, point_tolerance=0.5 * s)
    refs = {}
    for slot in design.slots:
        if slot.shape_key not in refs:
            fig = slot.figure()
            refs[slot.shape_key] = describe(
                Figure.from_polygon(fig.points * s, curve_mask=fig.curve_mask), tol
            )
    figs = extract_detailed(img.image, ep).figures
    cents = np.array([f.centroid for f in figs])
    right = wrong = 0
    for t in img.tiles:
        if t.partial:
            continue
        cand = describe(figs[int(np.argmin(np.hypot(*(cents - t.center_px).T)))], tol)
        scored = [(m.score, k) for k, r in refs.items() if (m := match(r, cand, tol, False))]
        key = min(scored)[1] if scored else None
        right += key == t.slot.shape_key
        wrong += key is not None and key != t.slot.shape_key
    return right, wrong


def test_rough_hexagons_keep_their_six_corners(
    synth_params: SynthParams, extract_params: ExtractParams
):
    # 0.4 mm rough edges (1 mm correlation) spread a 60 deg corner over more samples than a
    # 2.5 % window sees: it turned by < 25 deg there, the corner was lost and two sides
    # became an arc (or the whole outline a circle). The bundled, wider window keeps them.
    # The windows are compared without the bent-run test (fit_split_turn_deg), which gives a
    # missed corner back and so rescues some of the narrow window's hexagons too (27 of 28).
    sp = synth_params
    s = sp.px_per_mm
    design = Design.load("hexagon")
    ep = extract_params
    alone = replace(ep, outline=replace(ep.outline, fit_split_turn_deg=0.0))
    narrow = replace(alone, outline=replace(alone.outline, corner_window=0.025))
    whole = right = right_alone = right_narrow = 0
    for seed in (1, 3):
        img = generate(
            design,
            14,
            np.random.default_rng(seed),
            replace(sp, effects=CameraEffects(edge_roughness_mm=0.4)),
        )
        whole += sum(not t.partial for t in img.tiles)
        r, wrong = _recognised(design, img, ep, s)
        ra, wrong_alone = _recognised(design, img, alone, s)
        rn, wrong_narrow = _recognised(design, img, narrow, s)
        assert wrong == wrong_alone == wrong_narrow == 0
        right, right_alone, right_narrow = right + r, right_alone + ra, right_narrow + rn
    assert right >= whole - 1
    assert right_alone >= right_narrow + 2
