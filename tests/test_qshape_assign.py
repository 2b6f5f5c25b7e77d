import math
import subprocess
import sys

import numpy as np
import pytest
from scipy.optimize import linear_sum_assignment

import qshape
from qshape import Assignment, Figure, MatchError, Tolerances, assign, describe, match
from qshape.assign import feasible_pairs

SEED = 11


def test_greedy_loses_a_tile_that_optimal_places():
    grey, blue = (0.5, 0.5, 0.5), (0.5, 0.5, 0.8)
    slots = [Figure.rectangle(20, 10, grey), Figure.rectangle(20, 10, blue)]
    tiles = [
        Figure.rectangle(20, 10, (0.5, 0.5, 0.65), angle=0.3),  # matches both slots
        Figure.rectangle(20, 10, (0.5, 0.5, 0.4), angle=-1.0),  # matches the grey slot only
    ]
    greedy = assign(tiles, slots, method="greedy")
    assert [(a.tile, a.slot) for a in greedy] == [(0, 0)]  # the paper's loop: tile 1 is lost
    optimal = assign(tiles, slots, method="optimal")
    assert [(a.tile, a.slot) for a in optimal] == [(0, 1), (1, 0)]
    rot = {a.tile: a.rotation for a in optimal}
    assert abs(math.remainder(rot[1] - 1.0, math.pi)) < 1e-9  # rectangle: modulo half a turn


def test_optimal_minimises_residual_among_equal_counts():
    slots = [Figure.rectangle(20, 10.3), Figure.rectangle(20, 10)]
    tiles = [Figure.rectangle(20, 10, angle=0.2), Figure.rectangle(20, 10.3, angle=0.5)]
    optimal = assign(tiles, slots)
    assert [(a.tile, a.slot) for a in optimal] == [(0, 1), (1, 0)]
    greedy = assign(tiles, slots, method="greedy")
    assert [(a.tile, a.slot) for a in greedy] == [(0, 0), (1, 1)]
    assert sum(a.score for a in optimal) < sum(a.score for a in greedy)


def test_assign_descriptions_and_figures_and_rotation():
    slots = [
        Figure.from_polygon([[0, 0], [20, 0], [20, 8], [8, 8], [8, 20], [0, 20]]),
        Figure.semicircle(8.0, (1, 0, 0)),
        Figure.ring(9.0, 3.0),
    ]
    tiles = [
        Figure.ring(9.0, 3.0, angle=1.0),
        Figure.semicircle(8.0, (1, 0, 0), angle=2.0),
        Figure.from_polygon(
            np.array([[0, 0], [20, 0], [20, 8], [8, 8], [8, 20], [0, 20]])
            @ np.array([[0.0, 1.0], [-1.0, 0.0]])
        ),
    ]
    for method in ("optimal", "greedy"):
        out = assign([describe(t) for t in tiles], slots, method=method)
        assert [(a.tile, a.slot) for a in out] == [(0, 2), (1, 1), (2, 0)]
        assert isinstance(out[0], Assignment)
        assert abs(math.remainder(out[1].rotation + 2.0, 2 * math.pi)) < 1e-9
        assert abs(math.remainder(out[2].rotation + math.pi / 2, 2 * math.pi)) < 1e-9


def test_unmatched_tiles_are_left_out_and_empty_inputs():
    slots = [Figure.rectangle(10, 10)]
    tiles = [Figure.regular_polygon(3, 6.0), Figure.rectangle(10, 10, angle=0.1)]
    out = assign(tiles, slots)
    assert [(a.tile, a.slot) for a in out] == [(1, 0)]
    assert assign([], slots) == []
    assert assign(tiles, []) == []


def test_unknown_method():
    with pytest.raises(MatchError, match="optimal, greedy"):
        assign([Figure.rectangle(1, 1)], [Figure.rectangle(1, 1)], method="best")


def test_use_color_switch():
    slots = [Figure.rectangle(10, 10, (1, 0, 0))]
    tiles = [Figure.rectangle(10, 10, (0, 0, 1))]
    assert assign(tiles, slots) == []
    assert len(assign(tiles, slots, use_color=False)) == 1


def _random_classes(rng: np.random.Generator, count: int) -> list[tuple[np.ndarray, tuple]]:
    palette = [(0.9, 0.1, 0.1), (0.1, 0.1, 0.9), (0.1, 0.8, 0.2)]
    out = []
    while len(out) < count:
        n = int(rng.integers(3, 9))
        t = np.sort(rng.uniform(0, 2 * math.pi, n))
        gaps = np.diff(np.r_[t, t[0] + 2 * math.pi])
        if gaps.min() < 0.4 or gaps.max() > 2.5:
            continue
        r = rng.uniform(8, 14, n)
        out.append((np.stack([r * np.cos(t), r * np.sin(t)], 1), palette[len(out) % 3]))
    return out


def test_optimal_count_equals_brute_force_maximum_matching():
    rng = np.random.default_rng(SEED)
    classes = _random_classes(rng, 6)
    classes.append((np.array([[-10.0, -10], [10, -10], [10, 10], [-10, 10]]), (0.5, 0.5, 0.5)))
    slot_cls = rng.integers(0, len(classes), 40)
    tile_cls = rng.integers(0, len(classes), 40)

    def fig(c: int, noise: float) -> Figure:
        pts, color = classes[c]
        a = rng.uniform(-math.pi, math.pi)
        c_, s_ = math.cos(a), math.sin(a)
        p = pts @ np.array([[c_, s_], [-s_, c_]]) + rng.uniform(-noise, noise, pts.shape)
        return Figure.from_polygon(p + rng.uniform(-100, 100, 2), color=color)

    slots = [describe(fig(c, 0.0)) for c in slot_cls]
    tiles = [describe(fig(c, 0.05)) for c in tile_cls]
    ok = np.array([[match(s, t) is not None for s in slots] for t in tiles])
    rows, cols = linear_sum_assignment(-ok.astype(float))
    best = int(ok[rows, cols].sum())
    out = assign(tiles, slots)
    assert len(out) == best
    assert all(ok[a.tile, a.slot] for a in out)
    assert len({a.slot for a in out}) == len(out)
    greedy = assign(tiles, slots, method="greedy")
    assert len(greedy) <= best
    assert all(ok[a.tile, a.slot] for a in greedy)
    # greedy reproduces the paper's loop exactly
    taken: set[int] = set()
    expected = []
    for t in range(len(tiles)):
        for s in range(len(slots)):
            if s not in taken and ok[t, s]:
                taken.add(s)
                expected.append((t, s))
                break
    assert [(a.tile, a.slot) for a in greedy] == expected


def test_assign_rotations_match_pairwise_match():
    rng = np.random.default_rng(SEED + 1)
    shapes = [
        Figure.rectangle(20, 10),
        Figure.regular_polygon(5, 9.0),
        Figure.from_polygon([[0, 0], [20, 0], [20, 8], [8, 8], [8, 20], [0, 20]]),
    ]
    slots = [describe(s) for s in shapes]
    tiles = []
    for s in shapes:
        a = rng.uniform(-3, 3)
        c, si = math.cos(a), math.sin(a)
        tiles.append(describe(Figure.from_polygon(s.points @ np.array([[c, si], [-si, c]]))))
    for a in assign(tiles, slots, Tolerances()):
        m = match(slots[a.slot], tiles[a.tile])
        assert m is not None
        assert abs(math.remainder(a.rotation - m.rotation, 2 * math.pi)) < 1e-9


def test_public_api_names():
    for name in (
        "Figure",
        "Tolerances",
        "describe",
        "parse",
        "match",
        "assign",
        "Match",
        "canonical_key",
        "Assignment",
        "QShapeError",
        "OutlineParams",
    ):
        assert hasattr(qshape, name)


def test_qshape_imports_no_simulator():
    code = (
        "import sys, qshape; bad = [m for m in ('mujoco', 'gymnasium', 'torch') "
        "if m in sys.modules]; assert not bad, bad"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_feasible_pairs_agree_with_pairwise_match_on_poor_fits():
    # No size check and a wide symmetry band: label-compatible but geometrically different
    # quadrilaterals, whose residuals are large (the dense block scoring must still pick only
    # compatible offsets, and the same score and least rotation as `match`).
    rng = np.random.default_rng(SEED + 7)
    tol = Tolerances(check_size=False, symmetry_residual=0.5)
    quads = []
    while len(quads) < 40:
        t = np.sort(rng.uniform(0.0, 2 * math.pi, 4))
        if np.diff(np.r_[t, t[0] + 2 * math.pi]).max() > 0.9 * math.pi:
            continue
        r = rng.uniform(2.0, 20.0, 4)
        pts = np.stack([r * np.cos(t), r * np.sin(t)], 1)
        quads.append(describe(Figure.from_polygon(pts), tol))
    ti, si, score, rot = feasible_pairs(quads[:20], quads[20:], tol, use_color=False)
    assert len(ti) > 5
    found = {
        (int(a), int(b)): (float(c), float(d))
        for a, b, c, d in zip(ti, si, score, rot, strict=True)
    }
    for a in range(20):
        for b in range(20):
            m = match(quads[20 + b], quads[a], tol, use_color=False)
            assert (m is not None) == ((a, b) in found)
            if m is not None:
                c, d = found[(a, b)]
                assert c == pytest.approx(m.score, rel=1e-9, abs=1e-12)
                assert abs(math.remainder(d - m.rotation, 2 * math.pi)) < 1e-9
