"""Extraction's image operations against the plain OpenCV and numpy calls they replace: the same
edges, sums, means, labels and medians, bit for bit or as stated, on rendered pictures and
seeded noise; the belt model's polynomial equals least squares.

Canny is handed the 3 x 3 Sobel derivatives (border replicated, as Canny takes them itself)
because that path is cheaper; numpy reduces a short last axis (the 3 colour channels) several
times slower than it adds three planes. The polynomial fit solves the normal equations when they
are well conditioned and falls back to ``numpy.linalg.lstsq`` when they are not; both cases are
held to the SVD solution.
"""

from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np
import pytest

from qshape.design import Design
from qshape.synthetic.synth import SynthParams, generate
from qshape.vision.background import (
    blur_size,
    cell_means,
    channel_sum,
    polynomial_basis,
    polynomial_fit,
)
from qshape.vision.params import ExtractParams
from qshape.vision.segment import canny, label_medians, label_pieces


@pytest.mark.parametrize(("design", "seed"), [("hexagon", 1), ("paper_mixed", 4)])
def test_canny_from_derivatives_equals_canny_on_rendered_channels(
    design: str, seed: int, synth_params: SynthParams, extract_params: ExtractParams
) -> None:
    p = extract_params
    sp = replace(synth_params, px_per_mm=1.8)
    img = generate(Design.load(design), 30, seed, sp).image
    for plane in cv2.split(img):
        want = cv2.Canny(plane, p.canny_low, p.canny_high)
        assert np.count_nonzero(want) > 1000  # the tiles' outlines are there
        np.testing.assert_array_equal(canny(plane, p.canny_low, p.canny_high), want)


def test_canny_from_derivatives_equals_canny_on_noise_up_to_the_border() -> None:
    rng = np.random.default_rng(11)
    at_border = 0
    for k in range(60):
        h, w = (int(v) for v in rng.integers(3, 90, size=2))
        plane = rng.integers(0, 256, (h, w), dtype=np.uint8)
        if k % 2:
            plane = cv2.GaussianBlur(plane, (5, 5), 1.5)
        want = cv2.Canny(plane, 30.0, 90.0)
        at_border += bool(want[[0, -1], :].any() or want[:, [0, -1]].any())
        np.testing.assert_array_equal(canny(plane, 30.0, 90.0), want)
    assert at_border > 40  # the border handling was really exercised


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("shape", [(30, 41, 3), (492, 656, 3)])
def test_channel_sum_equals_numpys_sum_bit_for_bit(dtype: type, shape: tuple[int, ...]) -> None:
    rng = np.random.default_rng(7)
    # Values of very different sizes side by side: any change of summation order would show.
    scale = rng.choice([1e-3, 1.0, 255.0, 1e6], size=shape[:-1] + (1,))
    values = (rng.random(shape) * scale).astype(dtype)
    got = channel_sum(values)
    assert got.dtype == values.dtype
    np.testing.assert_array_equal(got, values.sum(axis=-1))


@pytest.mark.parametrize("size", [(656, 492), (641, 479)])
def test_belt_model_resized_plane_by_plane_equals_the_colour_resize(size: tuple[int, int]) -> None:
    rng = np.random.default_rng(3)
    grid = rng.integers(0, 256, (30, 41, 3), dtype=np.uint8)
    whole = cv2.resize(grid, size, interpolation=cv2.INTER_LINEAR)
    planes = [cv2.resize(c, size, interpolation=cv2.INTER_LINEAR) for c in cv2.split(grid)]
    for k in range(3):
        np.testing.assert_array_equal(planes[k], whole[..., k])


def _lstsq_model(small: np.ndarray, keep: np.ndarray, degree: int) -> np.ndarray:
    gh, gw = keep.shape
    basis = polynomial_basis(gh, gw, degree)
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
    got = polynomial_fit(small, keep, 3)
    np.testing.assert_allclose(got, _lstsq_model(small, keep, 3), rtol=0.0, atol=1e-8)
    assert np.abs(got[..., 0] - light).max() < 3.0  # it models the light, not the noise


def test_polynomial_fit_over_one_row_of_belt_cells_stays_finite_and_fits_it() -> None:
    rng = np.random.default_rng(6)
    small = (100.0 + rng.normal(0.0, 1.0, (30, 41, 3))).astype(np.float32)
    keep = np.zeros((30, 41), dtype=bool)
    keep[7, :] = True  # every monomial in v is undetermined: lstsq's minimum-norm solution
    got = polynomial_fit(small, keep, 3)
    assert np.isfinite(got).all()
    np.testing.assert_allclose(got, _lstsq_model(small, keep, 3), rtol=0.0, atol=1e-6)
    assert np.abs(got[7] - 100.0).max() < 3.0


@pytest.mark.parametrize(("labels", "count"), [(7, 8), (300, 310)])
def test_label_medians_are_lower_medians(labels: int, count: int) -> None:
    """The histogram medians equal sorted lower medians, per label and channel.

    More labels than a byte holds take the float histogram; labels above ``labels`` have no
    sample.
    """

    rng = np.random.default_rng(11)
    lab = rng.integers(0, labels, 20000)
    both = np.concatenate(
        [rng.integers(0, 256, (20000, 3)), rng.integers(0, 9, (20000, 1))], axis=1
    ).astype(np.uint8)
    medians, seen = label_medians(lab, [both[:, c] for c in range(4)], count)
    assert medians.shape == (count, 4)
    for k in range(count):
        rows = np.sort(both[lab == k], axis=0)
        assert seen[k] == (len(rows) > 0)
        want = rows[(len(rows) - 1) // 2] if len(rows) else np.zeros(4)
        np.testing.assert_array_equal(medians[k], want)


@pytest.mark.parametrize(
    ("h", "w", "gh", "gw"), [(492, 656, 30, 41), (64, 80, 4, 5), (97, 61, 7, 3)]
)
def test_cell_means_are_opencv_area_means(h: int, w: int, gh: int, gw: int) -> None:
    """The illumination grid's cell means equal OpenCV's area resize (ties within a level)."""

    rng = np.random.default_rng(5)
    img = cv2.GaussianBlur(rng.integers(0, 256, (h, w, 3), dtype=np.uint8), (0, 0), 2.0)
    want = cv2.resize(img, (gw, gh), interpolation=cv2.INTER_AREA).astype(np.float32)
    got = cell_means(cv2.split(img), gh, gw)
    assert got.shape == want.shape and got.dtype == np.float32
    diff = np.abs(got - want)
    assert diff.max() <= 1.0 and (diff > 0).mean() < 0.01  # off by one only at a tie


@pytest.mark.parametrize("sigma", [0.3, 0.5, 0.8, 1.0, 1.5, 2.0])
def test_trimmed_pre_blur_is_opencvs_blur(sigma: float) -> None:
    """The pre-blur's trimmed kernel gives exactly OpenCV's default-size Gaussian blur."""

    img = np.random.default_rng(3).integers(0, 256, (90, 120, 3), dtype=np.uint8)
    size = blur_size(sigma)
    assert size % 2 == 1 and size <= (round(6 * sigma + 1) | 1)
    want = cv2.GaussianBlur(img, (0, 0), sigma)
    np.testing.assert_array_equal(cv2.GaussianBlur(img, (size, size), sigma), want)


def test_piece_labels_are_16_bit_when_they_fit_else_32_bit() -> None:

    rng = np.random.default_rng(5)
    blobs = cv2.GaussianBlur(rng.integers(0, 256, (120, 160), dtype=np.uint8), (0, 0), 3.0)
    mask = np.where(blobs > 128, 255, 0).astype(np.uint8)
    count, labels = label_pieces(mask)
    want_count, want = cv2.connectedComponents(mask, connectivity=4)
    assert labels.dtype == np.uint16
    assert count == want_count > 10
    np.testing.assert_array_equal(labels, want)
    # A checkerboard of 492 x 656 px: 161377 labels in 4-connectivity do not fit 16 bits.
    yy, xx = np.mgrid[0:492, 0:656]
    board = (((yy + xx) % 2) * 255).astype(np.uint8)
    count, labels = label_pieces(board)
    assert labels.dtype == np.int32
    assert count == 492 * 656 // 2 + 1
    assert int(labels.max()) == count - 1
