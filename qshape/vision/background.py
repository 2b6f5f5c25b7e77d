"""The belt under the cell's light: its dominant colour and a model of it over the picture.

The most frequent colour of the border band is the belt; on a grid of cells, cells whose colour
is that colour brought to their own brightness are belt, and each cell's belt colour is averaged
from the belt cells near it, with a low-order polynomial where none is near (step 2 of
`qshape.vision.extract`).
"""

from __future__ import annotations

import functools
from collections.abc import Sequence

import cv2
import numpy as np

from qshape.vision.params import ExtractParams

GAIN_SCALE = 32.0
"""Fixed-point scale of the shading gain image (uint8): gains up to 255 / 32 ~ 8."""


def channel_span(image: np.ndarray) -> int:
    """Largest range of levels over the three channels."""
    return max(int(hi - lo) for lo, hi, *_ in (cv2.minMaxLoc(c) for c in cv2.split(image)))


_BLUR_TAP_MIN = 1.0 / 512.0
"""Gaussian taps below this share of the kernel are dropped (they round to zero in OpenCV's
8-bit fixed-point blur, whose weights have 8 fractional bits)."""


@functools.cache
def blur_size(sigma: float) -> int:
    """Odd kernel size [px] of the Gaussian pre-blur of ``sigma`` [px].

    OpenCV's own choice for 8-bit images (about 3 sigma each side) less the outer taps below
    `_BLUR_TAP_MIN`: for sigma 0.5 px 3, not 5, with the same output and a third less work.
    """
    default = round(sigma * 6.0 + 1.0) | 1
    g = np.exp(-(np.arange(default // 2 + 1) ** 2) / (2.0 * sigma * sigma))
    share = g / (g[0] + 2.0 * g[1:].sum())
    return min(default, 2 * int(np.flatnonzero(share >= _BLUR_TAP_MIN)[-1]) + 1)


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


def dominant_color(img: np.ndarray, p: ExtractParams) -> tuple[np.ndarray, float, int]:
    """Dominant colour of the border band, its share, and the sample's channel span.

    Returns:
        The median colour (3,) [levels] of the most populated coarse colour bin, the
        fraction of sampled pixels within ``background_tolerance`` of it, and the largest
        range of levels over the channels among the sampled pixels.
    """
    b, step = p.background_border_px, p.background_sample_step
    if b > 0 and 2 * b < min(img.shape[:2]):
        sample = np.concatenate(
            [
                img[:b, ::step].reshape(-1, 3),
                img[-b:, ::step].reshape(-1, 3),
                img[b:-b:step, :b].reshape(-1, 3),
                img[b:-b:step, -b:].reshape(-1, 3),
            ]
        )
    else:
        sample = img[::step, ::step].reshape(-1, 3)
    q = (sample.astype(np.int32) * p.background_bins) >> 8
    code = (q[:, 0] * p.background_bins + q[:, 1]) * p.background_bins + q[:, 2]
    top = int(np.argmax(np.bincount(code, minlength=p.background_bins**3)))
    dominant = np.asarray(np.median(sample[code == top], axis=0), dtype=np.float64)
    # Channel-major (3, N): numpy reduces an axis of 3 many times slower than three planes.
    planes = np.ascontiguousarray(sample.T)
    off = np.abs(planes - dominant[:, None])
    near = channel_max(off.T) <= p.background_tolerance
    span = int((planes.max(axis=1).astype(np.int32) - planes.min(axis=1)).max())
    return dominant, float(near.mean()), span


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
    if eig[0] > eig[-1] / _MAX_GRAM_CONDITION:
        coef = np.linalg.solve(gram, used.T @ values)
    else:
        coef = np.linalg.lstsq(used, values, rcond=None)[0]
    return np.asarray((basis @ coef).reshape(gh, gw, 3))


_MAX_GRAM_CONDITION = 1e8
"""Largest condition number of the polynomial fit's normal equations solved as they are (1e-8
relative error at most in float64); above it, the fit takes `numpy.linalg.lstsq`."""


@functools.cache
def box_kernel(size: int) -> np.ndarray:
    """Square structuring element of ``size`` x ``size`` px (uint8 ones), made once."""
    kernel = cv2.getStructuringElement(cv2.MORPH_RECT, (size, size))
    kernel.setflags(write=False)
    return kernel


def local_fill(
    small: np.ndarray, keep: np.ndarray, base: np.ndarray, p: ExtractParams
) -> np.ndarray:
    """Background colour of every cell from the ``keep`` cells near it (normalised convolution).

    A Gaussian-weighted mean of the background cells around each cell, so a shadow band or a
    steep gradient is followed at the scale of ``illumination_local_sigma_cells``; where
    background cells weigh less than ``illumination_min_weight``, ``base`` (the polynomial)
    is kept, or with ``illumination_blend`` makes up only the missing weight (see
    `_blend_far`).
    """
    sigma = p.illumination_local_sigma_cells
    weight = cv2.GaussianBlur(keep.astype(np.float32), (0, 0), sigma)
    acc = cv2.GaussianBlur(small * keep[..., None].astype(np.float32), (0, 0), sigma)
    ok = weight >= p.illumination_min_weight
    out = base.astype(np.float32).copy()
    out[ok] = acc[ok] / weight[ok, None]
    if p.illumination_blend and not ok.all():
        _blend_far(out, ~ok, weight, acc, p)
    return out


def _blend_far(
    out: np.ndarray, far: np.ndarray, weight: np.ndarray, acc: np.ndarray, p: ExtractParams
) -> None:
    """Blend the belt near each ``far`` cell into its polynomial model ``out``, in place.

    With w0 = ``illumination_min_weight`` and a cell's belt weight w < w0, the model becomes
    (acc + (w0 - w) x polynomial) / w0: the local average at weight w / w0, the polynomial for
    the rest, equal to the local average at w = w0 and to the polynomial at w = 0 (no step).
    Cells it moves by at most ``illumination_blend_min_change`` keep the polynomial.

    Args:
        out: Model (gh, gw, 3) float32 [levels], the polynomial at the ``far`` cells.
        far: Cells (gh, gw) bool whose belt weight is below w0.
        weight: Gaussian weight of belt cells (gh, gw) float32.
        acc: Gaussian-weighted sum of belt colours (gh, gw, 3) float32.
        p: Parameters.
    """
    w0 = p.illumination_min_weight
    blended = (acc + (w0 - weight)[..., None] * out) * (1.0 / w0)
    moved = far & (channel_max(np.abs(blended - out)) > p.illumination_blend_min_change)
    out[moved] = blended[moved]


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


def illumination(
    planes: Sequence[np.ndarray], dominant: np.ndarray, p: ExtractParams
) -> tuple[tuple[np.ndarray, ...], np.ndarray, np.ndarray]:
    """Background model of the belt under the cell's light, from the picture's three channels.

    Returns:
        The model image as its three channels, each (H, W) uint8 (the colour distance and the
        tile colours read it plane by plane); the belt's colour under the reference light (3,) in
        levels (tile colours are corrected to that light); and the shading gain (H, W) uint8
        in units of 1 / ``GAIN_SCALE`` (the reference brightness over the modelled one,
        saturating), by which colour distances are multiplied so that a tile in a shadow
        stands out as much as in full light.
    """
    h, w = planes[0].shape[:2]
    gh, gw = max(2, h // p.illumination_cell_px), max(2, w // p.illumination_cell_px)
    small = cell_means(planes, gh, gw)
    dom = dominant.astype(np.float32)
    # The belt under any light is the dominant colour times a gain: compare each cell with
    # the dominant colour brought to the cell's brightness (a tile differs in hue, a shadow
    # only in brightness).
    ratio = channel_sum(small) / max(float(dom.sum()), 1.0)
    shaded = channel_max(np.abs(small - ratio[..., None] * dom))
    # Darker than the dominant colour: any shadow down to belt_gain_min; brighter: only
    # within background_tolerance (a grey tile is the belt's hue, but much brighter).
    brighter_ok = channel_max(np.abs(small - dom)) <= p.background_tolerance
    is_bg = (
        (shaded <= p.background_chroma_tolerance)
        & (ratio >= p.belt_gain_min)
        & ((ratio <= 1.0) | brighter_ok)
    ).astype(np.uint8)
    # Cells beside a non-background cell are partly tile (mixed colours): not trusted.
    core = cv2.erode(is_bg, box_kernel(3), borderType=cv2.BORDER_REPLICATE)
    keep = core.view(bool) if int(core.sum()) >= p.illumination_min_cells else is_bg.view(bool)
    poly = polynomial_fit(small, keep, p.illumination_degree)
    model = np.broadcast_to(dominant, small.shape) if poly is None else poly
    if p.illumination_local_sigma_cells > 0.0 and keep.any():
        model = local_fill(small, keep, model, p)
    model = np.asarray(model, dtype=np.float32)
    light = channel_sum(model)
    lit = float(np.percentile(light, p.lit_percentile))
    gain = lit / np.maximum(light, 1.0)
    if not p.normalize_shading:
        gain[:] = 1.0
    gain8 = np.clip(gain * GAIN_SCALE + 0.5, 0, 255).astype(np.uint8)
    model8 = np.clip(model + 0.5, 0, 255).astype(np.uint8)
    # Resized plane by plane: the same levels as resizing the colour image.
    up = tuple(cv2.resize(c, (w, h), interpolation=cv2.INTER_LINEAR) for c in cv2.split(model8))
    return (
        up,
        model.reshape(-1, 3).mean(axis=0).astype(np.float64) * lit / max(float(light.mean()), 1.0),
        cv2.resize(gain8, (w, h), interpolation=cv2.INTER_LINEAR),
    )


__all__ = [
    "GAIN_SCALE",
    "blur_size",
    "box_kernel",
    "cell_means",
    "channel_max",
    "channel_span",
    "channel_sum",
    "dominant_color",
    "illumination",
    "local_fill",
    "polynomial_basis",
    "polynomial_fit",
]
