"""Exact, faster equivalents of OpenCV and numpy image operations, as extraction uses them.

Each function gives what a plain OpenCV or numpy call gives (bit for bit, or as stated) on the
images extraction works with, on a cheaper path: per-channel reductions from the colour planes,
Canny from ready-made Sobel derivatives, area means from one integral image, 16-bit labels where
they fit, per-label medians from one histogram, a trimmed Gaussian kernel. The belt model's
least-squares polynomial over a grid of cells is here too. No function knows about tiles.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from typing import Any

import cv2
import numpy as np

BLUR_TAP_MIN = 1.0 / 512.0
"""Gaussian taps below this share of the kernel are dropped (they round to zero in OpenCV's
8-bit fixed-point blur, whose weights have 8 fractional bits)."""


@functools.cache
def blur_size(sigma: float) -> int:
    """Odd kernel size [px] of the Gaussian pre-blur of ``sigma`` [px].

    OpenCV's own choice for 8-bit images (about 3 sigma each side) less the outer taps below
    `BLUR_TAP_MIN`: for sigma 0.5 px 3, not 5, with the same output and a third less work.
    """
    default = round(sigma * 6.0 + 1.0) | 1
    g = np.exp(-(np.arange(default // 2 + 1) ** 2) / (2.0 * sigma * sigma))
    share = g / (g[0] + 2.0 * g[1:].sum())
    return min(default, 2 * int(np.flatnonzero(share >= BLUR_TAP_MIN)[-1]) + 1)


def channel_max(values: np.ndarray) -> np.ndarray:
    """Maximum over the last axis of (..., 3) values, from the three planes.

    numpy's reduction over an axis of 3 costs ~45 us on the (30, 41, 3) cell grid, the planes
    ~5 us; the result is the same.
    """
    out: np.ndarray = np.maximum(np.maximum(values[..., 0], values[..., 1]), values[..., 2])
    return out


def channel_sum(values: np.ndarray) -> np.ndarray:
    """Sum over the last axis of (..., 3) values, from the three planes.

    The same sums as ``values.sum(axis=-1)`` (numpy adds three values left to right too), at
    a fifth of its cost on the cell grid.
    """
    out: np.ndarray = values[..., 0] + values[..., 1] + values[..., 2]
    return out


@functools.cache
def polynomial_basis(gh: int, gw: int, degree: int) -> np.ndarray:
    """Monomials u^i v^j (i + j <= degree) of the cell centres of a (gh, gw) grid, (gh*gw, terms).

    u, v are the centres' positions in [-0.5, 0.5]; depends only on the grid and the degree,
    so it is computed once per camera size (read-only).
    """
    yy, xx = np.mgrid[0:gh, 0:gw]
    u, v = (xx.ravel() + 0.5) / gw - 0.5, (yy.ravel() + 0.5) / gh - 0.5
    basis = np.stack(
        [u**i * v**j for i in range(degree + 1) for j in range(degree + 1 - i)], axis=1
    )
    basis.setflags(write=False)
    return basis


def polynomial_fit(small: np.ndarray, keep: np.ndarray, degree: int) -> np.ndarray | None:
    """Per-channel polynomial of the cell grid (gh, gw, 3) fitted on ``keep`` cells, or None."""
    gh, gw = keep.shape
    terms = (degree + 1) * (degree + 2) // 2
    if degree <= 0 or int(keep.sum()) < 2 * terms:
        return None
    basis = polynomial_basis(gh, gw, degree)
    flat = keep.ravel()
    used, values = basis[flat], small.reshape(-1, 3)[flat]
    # Least squares by the normal equations where they are well conditioned: the monomials of
    # cell centres spread over the grid are (condition number about 50 for a cubic on 60 % of
    # the cells, ~3e3 for the normal equations; the model agrees with an SVD solution to 1e-11
    # levels), and solving them costs half of lstsq. Background cells that leave a monomial
    # nearly undetermined (all in a few rows, say) take lstsq's minimum-norm solution.
    gram = used.T @ used
    eig = np.linalg.eigvalsh(gram)
    if eig[0] > eig[-1] / MAX_GRAM_CONDITION:
        coef = np.linalg.solve(gram, used.T @ values)
    else:
        coef = np.linalg.lstsq(used, values, rcond=None)[0]
    return np.asarray((basis @ coef).reshape(gh, gw, 3))


MAX_GRAM_CONDITION = 1e8
"""Largest condition number of the polynomial fit's normal equations solved as they are (1e-8
relative error at most in float64); above it, the fit takes `numpy.linalg.lstsq`."""


def _grid_at(size: int, cells: int) -> tuple[np.ndarray, np.ndarray]:
    """Whole pixel and fraction (cells + 1,) of each edge of ``cells`` cells across ``size`` px."""
    edge = np.arange(cells + 1) * (size / cells)
    whole = np.minimum(edge.astype(np.intp), size - 1)
    return whole, edge - whole


def cell_means(planes: Sequence[np.ndarray], gh: int, gw: int) -> np.ndarray:
    """Mean colour of each cell of a (gh, gw) grid over the image, (gh, gw, 3) float32 levels.

    The area average of ``cv2.resize(..., INTER_AREA)`` (a pixel on a cell edge counts by the
    share of it inside the cell), rounded to whole levels as that gives them, from the image's
    integral (one OpenCV pass at any cell size: OpenCV's area resize takes a slow path when a
    side is not a whole number of cells, e.g. 492 px rows in 30 cells). ``planes``: the
    image's three channels, each (H, W) uint8 (three one-channel integrals cost less than
    one of the colour image).
    """
    h, w = planes[0].shape[:2]
    iy, ty = _grid_at(h, gh)
    ix, tx = _grid_at(w, gw)
    rows = np.concatenate((iy, iy + 1))
    cols = np.concatenate((ix, ix + 1)) if tx.any() else ix
    # Sums above and left of the pixel corners next to each cell edge, (2 (gh + 1), ., 3).
    total = np.stack(
        [np.take(np.take(cv2.integral(c), rows, axis=0), cols, axis=1) for c in planes], axis=-1
    ).astype(np.float64)
    # The integral of a piecewise-constant image is bilinear inside each pixel: along x at
    # the cell edges first (exact when they fall on pixel edges), then along y.
    edge = total[:, : gw + 1]
    if tx.any():
        edge = edge * (1.0 - tx)[None, :, None]
        edge += total[:, gw + 1 :] * tx[None, :, None]
    at = edge[: gh + 1] * (1.0 - ty)[:, None, None]
    at += edge[gh + 1 :] * ty[:, None, None]
    box = np.diff(np.diff(at, axis=0), axis=1) * (gh * gw / (h * w))
    return np.asarray(np.rint(box), dtype=np.float32)


def label_medians(
    lab: np.ndarray, values: Sequence[np.ndarray], k: int
) -> tuple[np.ndarray, np.ndarray]:
    """Median of each channel per label, from one (label, level) histogram per channel.

    Args:
        lab: int (N,) labels below ``k``.
        values: uint8 (N,) samples, one array per channel (C channels).
        k: Number of labels.

    Returns:
        The medians (k, C) in levels (0 for a label without samples; the lower middle level
        of an even count), and which labels had a sample (k,) bool.
    """
    channels = len(values)
    # OpenCV's 2-D histogram of (label, level) pairs, exact for whole-number bins; 8-bit
    # images when the labels fit, else float (all images of one call share a depth).
    small = k <= 256  # noqa: PLR2004
    depth = np.uint8 if small else np.float32
    row = np.ascontiguousarray(lab, dtype=depth).reshape(1, -1)
    hist = np.empty((k, channels, 256), np.float32)
    for c, v in enumerate(values):
        pair: list[Any] = [row, np.asarray(v, dtype=depth).reshape(1, -1)]
        hist[:, c] = cv2.calcHist(pair, [0, 1], None, [k, 256], [0, k, 0, 256])
    # Counts are whole numbers (exact in float32 below 2^24 samples); int32 sums are faster.
    cum = np.cumsum(hist.reshape(k * channels, 256).astype(np.int32), axis=1)
    median = np.argmax(cum >= np.maximum((cum[:, -1:] + 1) // 2, 1), axis=1)
    return median.reshape(k, channels), cum[::channels, -1] > 0


def canny(plane: np.ndarray, low: float, high: float) -> np.ndarray:
    """``cv2.Canny`` of one uint8 channel, given the 3 x 3 Sobel derivatives it would take.

    Canny's image path computes those derivatives itself, with the border replicated; its
    path taking them ready-made gives the same edges. They come from ``cv2.spatialGradient``
    (both derivatives in one pass) on the channel padded by one replicated pixel, so that its
    own border rule only reaches the pad: 0.1-0.15 ms less per 656 x 492 channel than Canny
    on the channel itself.
    """
    pad = cv2.copyMakeBorder(plane, 1, 1, 1, 1, cv2.BORDER_REPLICATE)
    dx, dy = cv2.spatialGradient(pad)
    return cv2.Canny(dx[1:-1, 1:-1], dy[1:-1, 1:-1], low, high)


def label_pieces(cut: np.ndarray) -> tuple[int, np.ndarray]:
    """4-connected scan-order labels of a uint8 mask: (count, labels (H, W) uint16 or int32).

    16-bit labels when they fit (OpenCV writes them about a quarter faster); OpenCV refuses
    to overflow them (a noisy mask of more than 65535 pieces), and then they are 32-bit. The
    labels are the same either way.
    """
    try:
        return cv2.connectedComponentsWithAlgorithm(cut, 4, cv2.CV_16U, cv2.CCL_SAUF)
    except cv2.error:
        return cv2.connectedComponentsWithAlgorithm(cut, 4, cv2.CV_32S, cv2.CCL_SAUF)


__all__ = [
    "BLUR_TAP_MIN",
    "MAX_GRAM_CONDITION",
    "blur_size",
    "canny",
    "cell_means",
    "channel_max",
    "channel_sum",
    "label_medians",
    "label_pieces",
    "polynomial_basis",
    "polynomial_fit",
]
