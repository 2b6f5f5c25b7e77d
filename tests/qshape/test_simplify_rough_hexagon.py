"""A rough hexagon stays a hexagon: bent runs (two edges) are not arcs (`fit_split_turn_deg`)."""

import dataclasses

import numpy as np
import pytest

from qshape import Figure, OutlineParams, Tolerances, describe, match
from qshape.outline.fit import BendTest, bent_runs, outline_moments
from qshape.synthetic.effects import roughen
from qshape.theory.figure import figures_from_outlines
from qshape.vision.params import ExtractParams

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
