"""Assignment of tiles to slots (greedy and optimal), feasible pairs against pairwise matching,
slot classes; qshape's public API names and its imports (no simulator).
"""

import math
import subprocess
import sys

import numpy as np
import pytest
from scipy.optimize import linear_sum_assignment

import qshape
from qshape import Assignment, Figure, MatchError, Tolerances, assign, describe, match
from qshape.theory.assign import feasible_pairs

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
    # assign turns by the points alone; match also fits the edges unless the points' share is 1.
    tol = Tolerances(check_size=False, symmetry_residual=0.5, rotation_corner_share=1.0)
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


# ------------------------------------------------------------------ slot classes (large mosaics)
from qshape.theory.slot_classes import slot_classes, transport  # noqa: E402


def _posed(pts, color, rng, noise=0.0):
    a = rng.uniform(-math.pi, math.pi)
    c, s = math.cos(a), math.sin(a)
    p = np.asarray(pts, float) @ np.array([[c, s], [-s, c]])
    p = p + rng.uniform(-noise, noise, p.shape) + rng.uniform(-300, 300, 2)
    return Figure.from_polygon(p, color=color)


SQUARE = [[-10.0, -10], [10, -10], [10, 10], [-10, 10]]
RECT = [[-10.0, -5], [10, -5], [10, 5], [-10, 5]]
ELL = [[0.0, 0], [20, 0], [20, 8], [8, 8], [8, 20], [0, 20]]


def test_slot_classes_group_posed_copies_and_split_colour_and_size():
    rng = np.random.default_rng(SEED + 20)
    red, blue = (0.8, 0.1, 0.1), (0.1, 0.2, 0.8)
    kinds = [
        (SQUARE, red),
        (SQUARE, blue),
        (RECT, red),
        (ELL, red),
        (np.multiply(SQUARE, 1.2), red),
    ]
    labels = rng.integers(0, len(kinds), 60)
    slots = [describe(_posed(*kinds[k], rng)) for k in labels]
    classes = slot_classes(slots, Tolerances()).members
    got = sorted(sorted(labels[m].tolist()) for m in classes)
    assert len(classes) == len(set(labels.tolist()))  # every rotation / start vertex together
    assert all(len(set(g)) == 1 for g in got)
    assert all(np.all(np.diff(m) > 0) for m in classes)
    # shape only: the two colours of the square are one class
    shape_only = slot_classes(slots, Tolerances(), use_color=False).members
    assert len(shape_only) == len(classes) - int(0 in labels and 1 in labels)


def _brute(tiles, slots, tol, use_color=True):
    ok = np.zeros((len(tiles), len(slots)), bool)
    score = np.full(ok.shape, np.inf)
    for i, t in enumerate(tiles):
        for j, s in enumerate(slots):
            m = match(s, t, tol, use_color=use_color)
            if m is not None:
                ok[i, j], score[i, j] = True, m.score
    return ok, score


def _paper_loop(ok):
    taken, out = set(), []
    for t in range(ok.shape[0]):
        for s in range(ok.shape[1]):
            if s not in taken and ok[t, s]:
                taken.add(s)
                out.append((t, s))
                break
    return out


@pytest.mark.parametrize("n_tiles", [30, 45])  # fewer tiles than slots, and more
def test_class_assignment_equals_pairwise_on_a_mosaic_of_copies(n_tiles):
    # Many copies of few classes, plus a tile colour between grey and blue that fits both
    # classes of the grey/blue rectangle (a tile of several classes: the LP path).
    rng = np.random.default_rng(SEED + 21 + n_tiles)
    grey, blue, red = (0.5, 0.5, 0.5), (0.5, 0.5, 0.8), (0.8, 0.1, 0.1)
    between = (0.5, 0.5, 0.65)
    slot_kinds = [(RECT, grey), (RECT, blue), (SQUARE, red), (ELL, red)]
    tile_kinds = [*slot_kinds, (RECT, between)]
    tol = Tolerances(rotation_corner_share=1.0)  # match turns by the points alone, as assign
    slots = [describe(_posed(*slot_kinds[k], rng)) for k in rng.integers(0, 4, 36)]
    tiles = [describe(_posed(*tile_kinds[k], rng, 0.05)) for k in rng.integers(0, 5, n_tiles)]
    ok, score = _brute(tiles, slots, tol)
    assert (ok.sum(axis=1) > 0).sum() > 10 and (ok.any(axis=0)).sum() > 10
    greedy = assign(tiles, slots, tol, method="greedy")
    assert [(a.tile, a.slot) for a in greedy] == _paper_loop(ok)
    rows, cols = linear_sum_assignment(np.where(ok, score, 1e6))
    keep = ok[rows, cols]
    best_count, best_score = int(keep.sum()), float(score[rows[keep], cols[keep]].sum())
    optimal = assign(tiles, slots, tol)
    assert len(optimal) == best_count
    assert len({a.slot for a in optimal}) == len(optimal)
    assert all(ok[a.tile, a.slot] for a in optimal)
    assert sum(a.score for a in optimal) == pytest.approx(best_score, rel=1e-9, abs=1e-12)
    previous = assign(tiles, slots, tol, slot_classes=False)
    assert sum(a.score for a in previous) == pytest.approx(best_score, rel=1e-9, abs=1e-12)
    for a in optimal + greedy:  # each pair's own score and least rotation, as `match`
        m = match(slots[a.slot], tiles[a.tile], tol)
        assert a.score == pytest.approx(m.score, rel=1e-9, abs=1e-12)
        assert abs(math.remainder(a.rotation - m.rotation, 2 * math.pi)) < 1e-9


def test_one_class_more_tiles_than_slots_keeps_the_best_fits():
    rng = np.random.default_rng(SEED + 30)
    slots = [describe(_posed(SQUARE, (0.2, 0.6, 0.3), rng)) for _ in range(20)]
    tiles = [
        describe(_posed(SQUARE, (0.2, 0.6, 0.3), rng, noise)) for noise in rng.uniform(0, 0.8, 50)
    ]
    optimal = assign(tiles, slots)
    assert len(optimal) == 20
    residual = {a.tile: a.score for a in optimal}
    others = [match(slots[0], t).score for i, t in enumerate(tiles) if i not in residual]
    assert max(residual.values()) <= min(others) + 1e-9
    # within the class, chosen tiles take the slots in index order
    assert [a.slot for a in optimal] == list(range(20))


def test_transport_lp_against_brute_force():
    rng = np.random.default_rng(SEED + 31)
    for _ in range(20):
        n_t, n_c = 7, 3
        fits = rng.random((n_t, n_c)) < 0.5
        tile, cls = np.nonzero(fits)
        score = rng.random(len(tile)).round(3)
        capacity = rng.integers(1, 4, n_c)
        used = transport(tile, cls, score, capacity)
        assert np.bincount(tile[used], minlength=n_t).max(initial=0) <= 1
        assert np.all(np.bincount(cls[used], minlength=n_c) <= capacity)
        # brute force: expand each class into `capacity` columns
        cols = np.repeat(np.arange(n_c), capacity)
        cost = np.full((n_t, len(cols)), 1e6)
        for t, c, q in zip(tile, cls, score, strict=True):
            cost[t, cols == c] = q
        r, k = linear_sum_assignment(cost)
        good = cost[r, k] < 1e6
        assert used.sum() == good.sum()
        assert score[used].sum() == pytest.approx(cost[r, k][good].sum(), abs=1e-9)
