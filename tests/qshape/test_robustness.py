"""qshape refuses bad and oversized input with its own errors, and stays precise far away.

Caps come from ``configs/qshape.yaml`` (``limits``); inputs at a cap give the correct result,
inputs above it a typed `qshape.LimitError` (timings at the caps:
``benchmarks/theory/robustness.py``).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import qshape
from configs import ConfigError, load_config, parse_yaml
from qshape import (
    Design,
    DesignError,
    Figure,
    FigureLimitError,
    InvalidFigureError,
    LimitError,
    MatchError,
    ParseError,
    QShapeError,
    TextLimitError,
    ToleranceError,
    Tolerances,
    assign,
    describe,
    match,
    parse,
)
from qshape import geometry as geo
from qshape.limits import Limits, default_limits

SQUARE = np.array([[0.0, 0.0], [40.0, 0.0], [40.0, 40.0], [0.0, 40.0]])
LIMITS = default_limits()


def star(n: int, r_out: float = 40.0, r_in: float = 30.0) -> np.ndarray:
    t = np.linspace(0.0, 2.0 * math.pi, n, endpoint=False)
    r = np.where(np.arange(n) % 2 == 0, r_out, r_in)
    return np.stack([r * np.cos(t), r * np.sin(t)], axis=1)


@pytest.fixture(scope="module")
def square_text() -> str:
    return str(describe(Figure.from_polygon(SQUARE)))


# ------------------------------------------------------------------------------ precision
@pytest.mark.parametrize("offset", [1e3, 1e6, 1e9, 1e11])
def test_far_square_keeps_its_area_centroid_and_labels(offset: float) -> None:
    near = describe(Figure.from_polygon(SQUARE))
    fig = Figure.from_polygon(SQUARE + offset)
    assert fig.area == 1600.0
    np.testing.assert_allclose(fig.centroid, [offset + 20.0, offset + 20.0], rtol=0, atol=1e-3)
    far = describe(fig)
    assert far.nodes == near.nodes
    assert match(near, far) is not None


def test_unrepresentable_figures_are_refused_by_name() -> None:
    with pytest.raises(FigureLimitError, match="max_coordinate"):
        Figure.from_polygon(SQUARE + 1e14)
    tiny = SQUARE * 1e-9 + 1e3  # float64 rounds its points by more than 1e-6 of its size
    with pytest.raises(FigureLimitError, match="cannot be represented"):
        Figure.from_polygon(tiny)
    assert issubclass(FigureLimitError, InvalidFigureError)


def test_signed_area_is_exact_far_from_origin_and_unchanged_near_it() -> None:
    assert geo.signed_area(SQUARE + 1e11) == 1600.0
    assert geo.signed_area(SQUARE[::-1] + 1e11) == -1600.0
    np.testing.assert_array_equal(geo.reference_point(SQUARE + 100.0), [0.0, 0.0])
    np.testing.assert_allclose(geo.polygon_centroid(SQUARE + 1e11), [1e11 + 20.0] * 2)


# ------------------------------------------------------------------------------- caps
def test_points_cap_at_and_above() -> None:
    n = LIMITS.max_points - LIMITS.max_points % 2
    fig = Figure.from_polygon(star(n))
    assert len(fig.points) == n
    d = describe(fig)
    m = match(d, d)
    assert m is not None and m.rotation == pytest.approx(0.0, abs=1e-12)
    with pytest.raises(FigureLimitError, match="max_points"):
        Figure.from_polygon(star(n + 2))


def test_self_crossing_is_found_in_a_large_outline_quickly() -> None:
    n = LIMITS.max_points - LIMITS.max_points % 2
    pts = star(n)
    pts[10:20] = pts[10:20][::-1].copy()  # a reversed run: the outline crosses itself
    with pytest.raises(InvalidFigureError, match="crosses"):
        Figure.from_polygon(pts)


def test_holes_cap() -> None:
    disc = Figure.regular_polygon(64, 40.0).points
    hole = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    k = LIMITS.max_holes
    spots = [hole + [3.0 * (i % 8) - 12.0, 3.0 * (i // 8) - 12.0] for i in range(k + 1)]
    assert len(Figure.from_polygon(disc, spots[:k]).holes) == k
    with pytest.raises(FigureLimitError, match="max_holes"):
        Figure.from_polygon(disc, spots)


def test_dense_outline_cap() -> None:
    cap = LIMITS.max_dense_points
    t = np.linspace(0.0, 2.0 * math.pi, cap, endpoint=False)
    ring = np.stack([np.cos(t), np.sin(t)], axis=1) * 200.0
    fig = Figure.from_outline(ring)
    assert fig.perimeter == pytest.approx(2 * math.pi * 200.0, rel=0.01)
    t1 = np.linspace(0.0, 2.0 * math.pi, cap + 1, endpoint=False)
    with pytest.raises(FigureLimitError, match="max_dense_points"):
        Figure.from_outline(np.stack([np.cos(t1), np.sin(t1)], axis=1) * 200.0)


def test_text_caps(square_text: str) -> None:
    assert parse(square_text) == describe(Figure.from_polygon(SQUARE))
    with pytest.raises(TextLimitError, match="max_text_chars"):
        parse(square_text + " " * LIMITS.max_text_chars)
    too_many = square_text.replace("nodes: 4", f"nodes: {LIMITS.max_points + 1}")
    with pytest.raises(TextLimitError, match="max_points"):
        parse(too_many)
    assert issubclass(TextLimitError, ParseError) and issubclass(TextLimitError, LimitError)


@pytest.mark.parametrize(
    "edit",
    [
        lambda t: t.replace("nodes: 4", "nodes: ²"),
        lambda t: t.replace("nodes: 4", "nodes: " + "9" * 5000),
        lambda t: t.replace("nodes: 4", "nodes: ٤"),  # a non-ASCII digit
        lambda t: t.replace("area: ", "area: " + "1" * 10_000, 1),
        lambda t: t.replace("area: ", "area: 1_6", 1),
        lambda t: t.replace("@ (", "@ (" + "1" * 10_000 + "x", 1),
        lambda t: t.replace("@ (", "@ (" + "1" * 10_000 + ".5e", 1),
        lambda t: t.replace(">", ">>", 1),
    ],
)
def test_adversarial_text_gives_parse_error(square_text: str, edit) -> None:
    with pytest.raises(ParseError):
        parse(edit(square_text))


def test_long_space_runs_inside_a_node_line_still_parse(square_text: str) -> None:
    spaced = square_text.replace("@ (", "@" + " " * 10_000 + "(")
    assert parse(spaced) == parse(square_text)
    padded = square_text.replace("<", "<" + " " * 10_000, 1)
    assert parse(padded) == parse(square_text)


def test_limits_config_is_strict() -> None:
    assert Limits.load() == LIMITS
    with pytest.raises(ToleranceError):
        Limits(max_points=0)
    with pytest.raises(ToleranceError):
        Limits(max_points="10")  # type: ignore[arg-type]
    with pytest.raises(ToleranceError):
        Limits(max_coordinate=math.inf)


# ----------------------------------------------------------------------- builtin leaks
@pytest.mark.parametrize(
    ("call", "error"),
    [
        (lambda: describe("abc"), InvalidFigureError),  # type: ignore[arg-type]
        (lambda: describe(None), InvalidFigureError),  # type: ignore[arg-type]
        (lambda: describe(Figure.rectangle(2, 1), tolerances="x"), ToleranceError),
        (lambda: qshape.describe_many(None), InvalidFigureError),  # type: ignore[arg-type]
        (lambda: qshape.describe_many([None]), InvalidFigureError),  # type: ignore[list-item]
        (lambda: match(Figure.rectangle(2, 1), Figure.rectangle(2, 1), 3), ToleranceError),
        (lambda: match(Figure.rectangle(2, 1), None), MatchError),  # type: ignore[arg-type]
        (lambda: match(Figure.rectangle(2, 1), Figure.rectangle(2, 1), None, "no"), MatchError),
        (lambda: assign(None, []), MatchError),  # type: ignore[arg-type]
        (lambda: assign([Figure.rectangle(2, 1)], "ab"), MatchError),
        (lambda: assign([1], [Figure.rectangle(2, 1)]), MatchError),  # type: ignore[list-item]
        (lambda: Figure.from_polygon(SQUARE, holes=None), InvalidFigureError),  # type: ignore[arg-type]
        (lambda: Figure.from_polygon(SQUARE + 1j), InvalidFigureError),
        (lambda: Figure.from_polygon([["1", "0"], ["0", "1"], ["0", "0"]]), InvalidFigureError),
        (lambda: Figure.from_polygon(np.ones((3, 2), dtype=bool)), InvalidFigureError),
        (lambda: Figure.from_polygon([[1, 0], [0, 1], [0, None]]), InvalidFigureError),
        (lambda: Tolerances(joint_width="2"), ToleranceError),  # type: ignore[arg-type]
        (lambda: Tolerances(check_size="no"), ToleranceError),  # type: ignore[arg-type]
        (lambda: Tolerances(check_size=1), ToleranceError),  # type: ignore[arg-type]
        (lambda: Tolerances(color_distance=math.nan), ToleranceError),
        (lambda: Tolerances(right_angle_deg=("85", "95")), ToleranceError),  # type: ignore[arg-type]
        (lambda: Tolerances(max_key_variants=2.5), ToleranceError),  # type: ignore[arg-type]
        (lambda: Design.load(None), DesignError),  # type: ignore[arg-type]
        (lambda: Design.load(3), DesignError),  # type: ignore[arg-type]
        (lambda: parse(None), ParseError),  # type: ignore[arg-type]
    ],
)
def test_bad_arguments_give_qshape_errors(call, error) -> None:
    with pytest.raises(error):
        call()


def test_complex_points_are_refused_not_truncated() -> None:
    with pytest.raises(InvalidFigureError, match="complex"):
        Figure.from_polygon(SQUARE.astype(complex))


def test_tolerances_accept_numpy_numbers_and_lists() -> None:
    tol = Tolerances(joint_width=np.float64(2.5), right_angle_deg=[84, 96], max_key_variants=8)
    assert tol.joint_width == 2.5 and tol.right_angle_deg == (84.0, 96.0)
    assert isinstance(tol.right_angle_deg[0], float)


# ---------------------------------------------------------------------- duplicate keys
def test_duplicate_yaml_keys_are_refused_with_the_key_named() -> None:
    with pytest.raises(Exception, match="duplicate key 'joint_width'"):
        parse_yaml("tolerances:\n  joint_width: 2.0\n  joint_width: 3.0\n")
    with pytest.raises(Exception, match="duplicate key 'a'"):
        parse_yaml("x: {a: 1, a: 2}\n")
    assert parse_yaml("b: &b {a: 1}\nc:\n  <<: *b\n  a: 2\n")["c"] == {"a": 2}


def test_duplicate_keys_in_config_and_design_files(tmp_path: Path) -> None:
    cfg = tmp_path / "tol.yaml"
    cfg.write_text("tolerances:\n  check_size: true\n  check_size: false\n", encoding="utf-8")
    with pytest.raises(ConfigError, match="duplicate key 'check_size'"):
        Tolerances.load(cfg)
    with pytest.raises(ConfigError, match="duplicate key"):
        load_config(Tolerances, cfg)
    bundled = Path("configs/designs/paper_mixed.yaml").read_text(encoding="utf-8")
    doubled = bundled.replace("joint:", "joint: 2.0\njoint:", 1)
    design = tmp_path / "design.yaml"
    design.write_text(doubled, encoding="utf-8")
    with pytest.raises(DesignError, match="duplicate key 'joint'"):
        Design.load(design)


def test_every_error_is_a_qshape_error() -> None:
    for cls in (FigureLimitError, TextLimitError, LimitError, DesignError, MatchError):
        assert issubclass(cls, QShapeError)


def test_key_variants_at_the_cap_are_expanded_not_coarse() -> None:
    # Pinned by mutation testing: exactly max_key_variants combinations still get real keys.
    d = describe(Figure.rectangle(40.0, 20.0))
    variants = math.prod(math.prod(len(a) for a in node.admissible) for node in d.nodes)
    tol = Tolerances(max_key_variants=variants)
    keys = qshape.canonical_keys(d, tol)
    assert keys and not any(k.startswith("K:") for k in keys)
    if variants > 1:
        coarse = qshape.canonical_keys(d, Tolerances(max_key_variants=variants - 1))
        assert all(k.startswith("K:") for k in coarse)
