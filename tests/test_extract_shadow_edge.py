"""The belt model under tiles near a soft shadow's edge: no step to the polynomial.

Cells of the illumination grid far from any trusted belt cell (under a large tile or a crowd
of tiles) fall back on a degree-2 polynomial, which smooths a soft shadow away. Switching to it
outright made a step in the model: under a dark tile beside a shadow the model was 7 levels
brighter than the belt beside it, and the tile lost a third of its outline. The blend hands
over from the local belt average to the polynomial smoothly (see ``illumination_blend``).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from qshape.extract import (
    ExtractParams,
    ImageError,
    _local_fill,
    _polynomial_fit,
)

_BELT = np.array([72.0, 77.0, 83.0], np.float32)  # lit belt colour [levels]


def _shadowed_grid() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Cell means (30, 41, 3) of a belt under a soft shadow pool, the trusted cells, the truth.

    A crowd of tiles covers a block of cells reaching into the pool from above; the shadowed
    belt is visible below the block, the lit belt above and beside it.
    """
    gh, gw = 30, 41
    rows = np.arange(gh, dtype=np.float32)[:, None]
    cols = np.arange(gw, dtype=np.float32)[None, :]
    pool = np.exp(-(((cols - 20.0) / 9.0) ** 2)) / (1.0 + np.exp(-(rows - 20.0) / 1.2))
    light = (1.0 - 0.3 * rows / gh) * (1.0 - 0.4 * pool)
    truth = (_BELT * light[..., None]).astype(np.float32)
    keep = np.ones((gh, gw), bool)
    keep[17:28, 14:27] = False
    return truth, keep, truth


def _model(small: np.ndarray, keep: np.ndarray, **overrides: object) -> np.ndarray:
    p = ExtractParams.load(**overrides)
    base = _polynomial_fit(small, keep, p.illumination_degree)
    assert base is not None
    return _local_fill(small, keep, base, p)


def test_far_cells_beside_a_shadow_take_the_shadowed_belt() -> None:
    small, keep, truth = _shadowed_grid()
    # Two cells inside the crowd's lower edge: the shadowed belt is just below, but its
    # Gaussian weight there is under illumination_min_weight (the polynomial's cells).
    row, cols = 25, slice(18, 23)
    before = np.abs(_model(small, keep, illumination_blend=False) - truth)[row, cols]
    after = np.abs(_model(small, keep) - truth)[row, cols]
    assert before.max() > 12.0  # the polynomial: the shadow smoothed away
    assert after.max() < 2.0


def test_where_the_polynomial_fits_the_model_is_unchanged() -> None:
    gh, gw = 30, 41
    rows = np.arange(gh, dtype=np.float32)[:, None, None]
    small = (_BELT * (1.0 - 0.2 * rows / gh) * np.ones((gh, gw, 1), np.float32)).astype(
        np.float32
    )  # a smooth gradient: the polynomial is the belt everywhere
    keep = np.ones((gh, gw), bool)
    keep[8:22, 10:30] = False
    before = _model(small, keep, illumination_blend=False)
    assert np.array_equal(_model(small, keep), before)


def test_blend_min_change_is_validated() -> None:
    with pytest.raises(ImageError, match="illumination_blend_min_change"):
        ExtractParams.load(illumination_blend_min_change=-1.0)
    p = ExtractParams.load()
    assert p.illumination_blend and p.illumination_blend_min_change >= 0.0
    assert replace(p, illumination_blend=False).illumination_blend is False
