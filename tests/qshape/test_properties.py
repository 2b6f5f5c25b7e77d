"""Property-based tests of qshape (Hypothesis, derandomized: the same examples every run).

- describe + match are invariant under rotation, translation, start vertex and orientation,
  and give the rotation that undoes the turn;
- the text form round-trips exactly;
- every generated bad figure, text and tolerance set gives qshape's own error or a correct
  result, never a builtin exception, within a deadline.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import qshape
from configs import ConfigError, from_dict
from qshape import Figure, QShapeError, Tolerances, describe, match, parse
from qshape.geometry import rotate, wrap_angle

SETTINGS = settings(
    derandomize=True,
    deadline=2000,
    max_examples=60,
    suppress_health_check=[HealthCheck.too_slow],
)


@st.composite
def star_polygons(draw: st.DrawFn) -> np.ndarray:
    """Simple star-shaped polygons: n vertices at increasing angles, radii 10-40 mm."""
    n = draw(st.integers(3, 12))
    gaps = np.array(draw(st.lists(st.floats(0.3, 1.0), min_size=n, max_size=n)))
    angles = 2.0 * math.pi * np.cumsum(gaps) / gaps.sum()
    radii = np.array(draw(st.lists(st.floats(10.0, 40.0), min_size=n, max_size=n)))
    return np.stack([radii * np.cos(angles), radii * np.sin(angles)], axis=1)


@st.composite
def poses(draw: st.DrawFn) -> tuple[float, np.ndarray, int, bool]:
    """(turn [rad], shift (2,) [mm], start-vertex roll, reversed walk)."""
    theta = draw(st.floats(-math.pi, math.pi))
    shift = np.array(draw(st.lists(st.floats(-1e4, 1e4), min_size=2, max_size=2)))
    return theta, shift, draw(st.integers(0, 11)), draw(st.booleans())


def _posed(points: np.ndarray, pose: tuple[float, np.ndarray, int, bool]) -> np.ndarray:
    theta, shift, roll, flip = pose
    moved = rotate(points, theta) + shift
    moved = np.roll(moved, roll % len(points), axis=0)
    return moved[::-1] if flip else moved


@SETTINGS
@given(star_polygons(), poses())
def test_match_is_invariant_and_finds_the_turn(points: np.ndarray, pose) -> None:
    try:
        ref = Figure.from_polygon(points, color=(0.4, 0.5, 0.6))
    except QShapeError:
        return  # a generated outline may be degenerate; that is a correct answer
    cand = Figure.from_polygon(_posed(points, pose), color=(0.4, 0.5, 0.6))
    assert cand.area == pytest.approx(ref.area, rel=1e-9)
    d_ref, d_cand = describe(ref), describe(cand)
    assert qshape.canonical_keys(d_ref) & qshape.canonical_keys(d_cand)
    m = match(d_ref, d_cand)
    assert m is not None
    # The candidate was turned by theta: the match turns it back by -theta (mod a symmetry).
    assert min(abs(wrap_angle(r + pose[0])) for r in m.rotations) < 1e-6
    # The exact turn, or (a nearly regular polygon) a turn its geometry makes equivalent.
    exact = abs(wrap_angle(m.rotation + pose[0])) < 1e-6
    assert m.score < (1e-6 if exact else Tolerances().symmetry_residual)


@SETTINGS
@given(star_polygons(), poses())
def test_labels_are_invariant_up_to_the_cyclic_start(points: np.ndarray, pose) -> None:
    try:
        ref = describe(Figure.from_polygon(points))
    except QShapeError:
        return
    cand = describe(Figure.from_polygon(_posed(points, pose)))
    a = [n.labels for n in ref.nodes]
    b = [n.labels for n in cand.nodes]
    # Same cyclic string, or differing only where a label is admissibly ambiguous.
    ok = any(
        all(
            x == y or any(len(adm) > 1 for adm in ref.nodes[i].admissible)
            for i, (x, y) in enumerate(zip(a, b[k:] + b[:k], strict=True))
        )
        for k in range(len(b))
    )
    assert ok


@st.composite
def figures(draw: st.DrawFn) -> Figure:
    """Polygons, curved figures, holed figures, with or without colour."""
    kind = draw(st.sampled_from(["star", "circle", "semicircle", "ring", "holed"]))
    color = draw(st.none() | st.tuples(*[st.floats(0.0, 1.0)] * 3))
    if kind == "star":
        return Figure.from_polygon(draw(star_polygons()), color=color)
    r = draw(st.floats(5.0, 50.0))
    if kind == "circle":
        return Figure.circle(r, color, angle=draw(st.floats(-3.0, 3.0)))
    if kind == "semicircle":
        return Figure.semicircle(r, color, angle=draw(st.floats(-3.0, 3.0)))
    if kind == "ring":
        return Figure.ring(r, r * draw(st.floats(0.2, 0.8)), color)
    hole = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]) * r * 0.3
    return Figure.from_polygon(
        [[-r, -r], [r, -r], [r, r], [-r, r]], [hole + draw(st.floats(-0.6, 0.2)) * r], color
    )


@SETTINGS
@given(figures())
def test_text_form_round_trips_exactly(fig: Figure) -> None:
    d = describe(fig)
    text = str(d)
    back = parse(text)
    assert back == d
    assert str(back) == text
    assert match(d, back) is not None


_JUNK = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-(10**30), 10**30),
    st.floats(allow_nan=True, allow_infinity=True),
    st.complex_numbers(),
    st.text(max_size=8),
)


@SETTINGS
@given(
    st.one_of(
        st.lists(st.lists(_JUNK, min_size=0, max_size=3), max_size=6),
        st.lists(st.tuples(st.floats(), st.floats()), max_size=8),
        _JUNK,
    ),
    st.one_of(st.none(), st.lists(st.lists(st.lists(st.floats(), max_size=2), max_size=4))),
)
def test_bad_figures_give_qshape_errors(points, holes) -> None:
    try:
        fig = Figure.from_polygon(points, () if holes is None else holes)
    except QShapeError:
        return
    assert fig.area > 0.0
    describe(fig)


_SAMPLE = str(describe(Figure.from_polygon([[0, 0], [30, 0], [30, 20], [10, 35]], [], (1, 0, 0))))


@SETTINGS
@given(
    st.integers(0, len(_SAMPLE)),
    st.integers(0, 40),
    st.text(max_size=40) | st.sampled_from(["9" * 5000, " " * 5000, "²", "nan", "1e999", "<"]),
)
def test_bad_texts_give_parse_errors(at: int, cut: int, insert: str) -> None:
    text = _SAMPLE[:at] + insert + _SAMPLE[at + cut :]
    try:
        d = parse(text)
    except qshape.ParseError:
        return
    assert isinstance(d, qshape.Description)
    assert parse(str(d)) == d


_FIELDS = [f for f in Tolerances.__dataclass_fields__]


@SETTINGS
@given(
    st.dictionaries(
        st.sampled_from(_FIELDS),
        st.one_of(_JUNK, st.lists(_JUNK, max_size=3), st.floats(0.0, 200.0)),
        max_size=4,
    )
)
def test_bad_tolerances_give_qshape_or_config_errors(values: dict) -> None:
    for build in (lambda: Tolerances(**values), lambda: from_dict(Tolerances, values)):
        try:
            tol = build()
        except (QShapeError, ConfigError):
            continue
        assert isinstance(tol.check_size, bool)
        assert all(math.isfinite(v) for v in tol.right_angle_deg)
        describe(Figure.rectangle(20.0, 10.0), tol)
