"""The belt model's polynomial fit equals least squares, also where the belt cells leave it loose.

The fit solves the normal equations when they are well conditioned and falls back to
``numpy.linalg.lstsq`` when they are not; both cases are held to the SVD solution here.
"""

from __future__ import annotations

import importlib

import numpy as np

background_module = importlib.import_module("qshape.vision.background")


def _lstsq_model(small: np.ndarray, keep: np.ndarray, degree: int) -> np.ndarray:
    gh, gw = keep.shape
    basis = background_module._polynomial_basis(gh, gw, degree)
    flat = keep.ravel()
    coef = np.linalg.lstsq(basis[flat], small.reshape(-1, 3)[flat], rcond=None)[0]
    return (basis @ coef).reshape(gh, gw, 3)


def test_polynomial_fit_over_scattered_belt_cells_equals_least_squares() -> None:
    rng = np.random.default_rng(5)
    yy, xx = np.mgrid[0:30, 0:41]
    # A light falling off across the belt, plus sensor noise.
    light = 150.0 + 40.0 * (xx / 41.0) - 25.0 * (yy / 30.0) ** 2
    small = (light[..., None] * [1.0, 0.9, 0.7] + rng.normal(0.0, 2.0, (30, 41, 3))).astype(
        np.float32
    )
    keep = rng.random((30, 41)) > 0.4
    got = background_module._polynomial_fit(small, keep, 3)
    np.testing.assert_allclose(got, _lstsq_model(small, keep, 3), rtol=0.0, atol=1e-8)
    assert np.abs(got[..., 0] - light).max() < 3.0  # it models the light, not the noise


def test_polynomial_fit_over_one_row_of_belt_cells_stays_finite_and_fits_it() -> None:
    rng = np.random.default_rng(6)
    small = (100.0 + rng.normal(0.0, 1.0, (30, 41, 3))).astype(np.float32)
    keep = np.zeros((30, 41), dtype=bool)
    keep[7, :] = True  # every monomial in v is undetermined: lstsq's minimum-norm solution
    got = background_module._polynomial_fit(small, keep, 3)
    assert np.isfinite(got).all()
    np.testing.assert_allclose(got, _lstsq_model(small, keep, 3), rtol=0.0, atol=1e-6)
    assert np.abs(got[7] - 100.0).max() < 3.0
