"""A hole's cut-off corner is judged at its figure's size, not at the hole's own."""

import numpy as np
import pytest

from qshape.extract import ExtractParams
from qshape.figure import figures_from_outlines
from qshape.simplify import simplify_outlines

STEP_PX = 0.5  # spacing of the drawn outline samples, as a traced contour gives them


def _square(centre: tuple[float, float], size: float, cut: float = 0.0) -> np.ndarray:
    """Corners (k, 2) of an axis-aligned square, one corner cut off by legs of ``cut``."""
    cx, cy = centre
    h = size / 2.0
    pts = [(cx - h, cy - h), (cx + h, cy - h), (cx + h, cy + h)]
    if cut > 0.0:
        pts += [(cx - h + cut, cy + h), (cx - h, cy + h - cut)]
    else:
        pts.append((cx - h, cy + h))
    return np.array(pts)


def _dense(poly: np.ndarray) -> np.ndarray:
    """Samples every `STEP_PX` along the closed polygon ``poly``, shape (m, 2)."""
    closed = np.vstack([poly, poly[:1]])
    cum = np.r_[0.0, np.cumsum(np.hypot(*np.diff(closed, axis=0).T))]
    s = np.arange(0.0, cum[-1], STEP_PX)
    return np.stack([np.interp(s, cum, closed[:, 0]), np.interp(s, cum, closed[:, 1])], axis=1)


@pytest.mark.parametrize("cut", [6.0, 8.0, 10.0])
def test_a_small_holes_cut_corner_is_one_corner_of_the_figure(cut: float) -> None:
    """The holed square's 45 px hole with a corner cut 8.5-14 px long (as blur and rough edges
    cut it) is a square: the cut is under 3 % of the figure's perimeter (15 px), though over
    3 % of the hole's own (5.4 px), which alone keeps it as an edge."""
    params = ExtractParams.load().outline
    outer = _dense(_square((125.0, 125.0), 125.0))
    hole = _dense(_square((100.0, 100.0), 45.0, cut))
    (fig,) = figures_from_outlines([outer], [[hole]], [None], params, y_down=True)
    assert not isinstance(fig, Exception)
    assert len(fig.points) == 4
    assert len(fig.holes[0].points) == 4
    (alone,) = simplify_outlines([hole], params)
    assert not isinstance(alone, Exception)
    assert len(alone[0]) == 5


def test_a_holes_edge_longer_than_the_figures_limit_stays() -> None:
    """A cut 17 px long (over 3 % of the figure's 500 px) is an edge of the hole."""
    params = ExtractParams.load().outline
    outer = _dense(_square((125.0, 125.0), 125.0))
    hole = _dense(_square((100.0, 100.0), 45.0, 12.0))
    (fig,) = figures_from_outlines([outer], [[hole]], [None], params, y_down=True)
    assert not isinstance(fig, Exception)
    assert len(fig.holes[0].points) == 5


def test_parents_leave_outer_outlines_alone() -> None:
    """Outer outlines simplify the same with or without the hole's parent given."""
    params = ExtractParams.load().outline
    outer = _dense(_square((125.0, 125.0), 125.0, 5.0))
    hole = _dense(_square((100.0, 100.0), 45.0))
    plain = simplify_outlines([outer, hole], params)
    linked = simplify_outlines([outer, hole], params, parents=[None, 0])
    for a, b in zip(plain, linked, strict=True):
        assert not isinstance(a, Exception)
        assert not isinstance(b, Exception)
        np.testing.assert_array_equal(a[0], b[0])
