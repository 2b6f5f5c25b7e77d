"""Relevant points of tiles from a camera (or design) image: the paper's hybrid method.

Pipeline, all O(height x width) image operations in OpenCV plus linear work per outline:

1. Validate the RGB uint8 image; light Gaussian blur. A single-colour image (an empty belt, or
   a covered camera: `image_health` tells them apart for the caller) has no figures.
2. Background: the most frequent colour of the border band, then a model of the belt under
   the cell's light on a grid of cells: cells whose colour is the dominant colour brought to
   their own brightness (a shadow changes brightness, a tile hue) are belt; each cell's belt
   colour is averaged from the belt cells near it (so a shadow band or a steep gradient is
   followed), with a low-order polynomial where none is near. Without a dominant background
   colour (noise, or a picture filled by one object) there is nothing to segment against: no
   figures, and the reason in ``ExtractResult.rejected``.
3. Segmentation: per-pixel colour distance to the belt model, times the shading gain (so a
   tile in a shadow stands out as much as in the light), thresholded (Otsu, clamped), cleaned
   by a morphological opening. Canny edges inside the foreground (found per channel on the
   picture reduced ``canny_reduction`` times per axis) split tiles of different colours that
   touch. Each region's outline is then taken where the distance reaches half
   of the region's own contrast (the middle of a blurred edge, faint or bright tile alike).
4. Contour tracing with hierarchy (``cv2.findContours``), so holes are the children of outer
   contours; a hole counts only if it shows the belt (a dark spot of glaze is no hole).
   Outlines touching the image border are partial tiles, reported apart.
5. Slope-comparison simplification of each outline to relevant points, with curve detection
   (`qshape.Figure.from_outline` with pixel-tuned `qshape.OutlineParams`). A region whose
   traced outline is much longer than its figure's perimeter is mostly noise: no figure, and
   the reason in ``ExtractResult.rejected``.
6. Colour: per-tile median inside the eroded region (one histogram pass for all tiles),
   divided by the median belt model under the tile, times the reference light.

Figures are in pixel coordinates with ``y_down=True``.

Note: ``qshape.extract`` (the package attribute) is the function; import this module's other
names with ``from qshape.extract import ExtractParams, extract_detailed, ...``.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from qshape.config_sections import load_section
from qshape.errors import InvalidFigureError, QShapeError
from qshape.geometry import FloatArray
from qshape.outline.simplify import MIN_RESAMPLE_POINTS, OutlineParams
from qshape.theory.figure import Color, Figure, figures_from_outlines

_GAIN_SCALE = 32.0
"""Fixed-point scale of the shading gain image (uint8): gains up to 255 / 32 ~ 8."""


class ImageError(QShapeError):
    """The image cannot be processed (wrong type, shape or size)."""


@dataclass(frozen=True)
class ExtractParams:
    """Parameters of `extract`. Pixel values are on the 0-255 scale.

    Attributes:
        min_size_px: Smallest accepted image height and width, in [px].
        max_size_px: Largest accepted image height and width, in [px].
        uniform_range: An image whose every channel spans at most this many levels is "one
            colour": an empty belt (or a covered camera, see `image_health`); it has no
            figures, in [levels].
        blur_sigma_px: Gaussian blur before everything, in [px] (0: none).
        background_bins: Histogram bins per channel used to find the dominant colour.
        background_border_px: The dominant colour is taken from a band of this width along
            the image border (belt or grout shows there even when tiles cover most of the
            image), in [px]; 0 uses the whole image.
        background_sample_step: Every n-th pixel (each axis) enters the colour histogram.
        min_background_fraction: Fewer of the sampled border pixels than this fraction within
            ``background_tolerance`` of the dominant colour: no dominant background (noise,
            or one object filling the view), so no figures, in [0, 1].
        illumination_cell_px: Cell size of the downsampled image the illumination model is
            fitted on, in [px].
        illumination_degree: Degree of the per-channel polynomial illumination model (0: flat);
            the fallback where no background cell is near.
        illumination_local_sigma_cells: Width (Gaussian sigma) over which the background
            colour is averaged from the background cells near each cell, in [cells] (0: the
            polynomial alone). It follows a shadow band or a steep light gradient that a
            low-order polynomial cannot.
        illumination_min_weight: Cells whose Gaussian weight of background cells is below this
            keep the polynomial model (dimensionless, in (0, 1]).
        illumination_blend: Such a cell blends the belt near it with the polynomial instead,
            the polynomial standing in only for the missing weight (weight w: w / min_weight
            of the local average), so the model has no step where a shadow's edge passes under
            a tile: a degree-2 polynomial smooths a soft shadow away, and a step to it lit a
            third of a dark tile 7 levels too bright.
        illumination_blend_min_change: ... only where the blend moves the cell's model by more
            than this (max over channels), in [levels] >= 0; smaller changes keep the
            polynomial (and with it every outline the step does not disturb).
        illumination_min_cells: Fewer trusted background cells than this (cells whose
            neighbours are all background): every background cell is used, in [cells].
        background_chroma_tolerance: A cell of the illumination grid is belt when its colour
            is within this distance (max over channels) of the dominant colour scaled to the
            cell's brightness, in [levels]: a shadow changes the belt's brightness, a tile its
            hue.
        belt_gain_min: ...and its brightness is at least this fraction of the dominant's (a
            cell brighter than the dominant colour must also be within
            ``background_tolerance`` of it: a grey tile has the belt's hue).
        normalize_shading: Multiply colour distances by the shading gain (belt as fully lit /
            belt as modelled here), so a tile in a shadow stands out as much as in full light.
        lit_percentile: The reference light (shading gain 1, and the light tile colours are
            corrected to) is this percentile of the modelled brightness over the picture, in
            [%] (50: the light in the middle of a gradient, and outside a shadow band
            covering less than half the picture).
        background_tolerance: A cell is background for the model fit when its colour is within
            this distance (max over channels) of the dominant colour, in [levels].
        threshold_min: Lowest foreground threshold on the colour distance, in [levels].
        threshold_max: Highest foreground threshold (Otsu's value is clamped to the range).
        otsu_sample_step: Otsu's threshold is taken from the histogram of every n-th pixel
            (each axis) of the colour distance; the mask is then thresholded at every pixel.
        open_px: Size of the square opening that removes specks from the mask, in [px] (0: none).
        edge_fraction: Each region's outline is traced where the colour distance is this
            fraction of the region's median distance (its contrast; 0.5: the middle of a
            blurred edge), dimensionless; 0: at the global threshold.
        edge_threshold_max: Upper clamp of that per-region level, in [levels] (the global
            threshold is the lower one).
        edge_sample_step: Every n-th pixel (each axis) of a region enters its median distance.
        split_touching: Remove Canny edges found inside the foreground (splits touching tiles).
        canny_low: Canny hysteresis low threshold, on the blurred RGB image.
        canny_high: Canny hysteresis high threshold.
        canny_reduction: The split's Canny runs on the blurred picture reduced by this factor
            per axis (area average; 1: full size), its edges scaled back (each a block of
            ``canny_reduction`` px), dimensionless.
        restore_iterations: After the Canny cut, pixels on the cut are given back to a
            neighbouring piece by this many label dilations.
        min_area_px: Regions smaller than this are ignored, in [px^2].
        min_hole_area_px: Holes smaller than this are ignored, in [px^2].
        min_hole_width_px: Holes thinner than this (2 x area / perimeter) are ignored (slits
            left by noise), in [px].
        hole_belt_fraction: A hole is kept only when the colour distance inside it reaches
            down to this fraction of the threshold (it shows the belt), dimensionless.
        hole_belt_percentile: ...at this percentile of the hole's pixels, in [%].
        max_outline_excess: A region whose traced outline is longer than this multiple of its
            figure's perimeter is mostly noise (a ragged splash, not a tile edge) and gives no
            figure, dimensionless (the pixel staircase alone gives up to ~1.08; edges rough by
            0.6 mm at 2.5 px/mm ~1.16).
        border_margin_px: Regions reaching this close to the image border are partial tiles,
            in [px].
        boundary_offset_px: Outlines are moved outwards by this much (traced contours run
            through the centres of the outermost region pixels), in [px].
        color_erode_px: Erosion before taking the median colour, in [px].
        color_sample_step: Every n-th pixel (each axis) of a tile enters its median colour.
        correct_illumination: Divide tile colours by the modelled relative illumination.
        resample_per_px: The picture's outlines are resampled to this many samples per
            traced pixel of its longest whole-tile outline, in [samples/px], and at most
            ``outline.resample_points`` (0: always ``outline.resample_points``). Small tiles
            in a coarse picture carry fewer pixels; sampling them more densely than that
            adds work, not information.
        outline: Slope-comparison simplification parameters for pixel outlines.
    """

    min_size_px: int = 16
    max_size_px: int = 8192
    uniform_range: int = 2
    blur_sigma_px: float = 1.0
    background_bins: int = 16
    background_border_px: int = 4
    background_sample_step: int = 4
    min_background_fraction: float = 0.25
    illumination_cell_px: int = 16
    illumination_degree: int = 2
    illumination_local_sigma_cells: float = 1.5
    illumination_min_weight: float = 0.05
    illumination_blend: bool = True
    illumination_blend_min_change: float = 3.0
    illumination_min_cells: int = 12
    background_chroma_tolerance: float = 12.0
    belt_gain_min: float = 0.25
    normalize_shading: bool = True
    lit_percentile: float = 50.0
    background_tolerance: float = 40.0
    threshold_min: float = 20.0
    threshold_max: float = 60.0
    otsu_sample_step: int = 1
    open_px: int = 3
    edge_fraction: float = 0.5
    edge_threshold_max: float = 60.0
    edge_sample_step: int = 2
    split_touching: bool = True
    canny_low: float = 60.0
    canny_high: float = 150.0
    canny_reduction: int = 1
    restore_iterations: int = 3
    min_area_px: float = 150.0
    min_hole_area_px: float = 40.0
    min_hole_width_px: float = 3.0
    hole_belt_fraction: float = 0.5
    hole_belt_percentile: float = 10.0
    max_outline_excess: float = 1.3
    border_margin_px: int = 1
    boundary_offset_px: float = 0.5
    color_erode_px: int = 3
    color_sample_step: int = 2
    correct_illumination: bool = True
    resample_per_px: float = 0.0
    outline: OutlineParams = field(default_factory=OutlineParams)

    def __post_init__(self) -> None:
        """Raise `ImageError` on out-of-range values."""
        if not 1 <= self.min_size_px <= self.max_size_px:
            raise ImageError("need 1 <= min_size_px <= max_size_px")
        if not 2 <= self.background_bins <= 256 or self.background_sample_step < 1:
            raise ImageError("background_bins must be in 2..256, background_sample_step >= 1")
        if not 0.0 <= self.min_background_fraction <= 1.0:
            raise ImageError("min_background_fraction must be in [0, 1]")
        if self.illumination_cell_px < 1 or not 0 <= self.illumination_degree <= 3:
            raise ImageError("illumination_cell_px must be >= 1, illumination_degree in 0..3")
        if not 0.0 < self.belt_gain_min <= 1.0:
            raise ImageError(f"belt_gain_min must be in (0, 1], got {self.belt_gain_min}")
        if self.max_outline_excess < 1.0:
            raise ImageError("max_outline_excess must be >= 1")
        if not 0.0 <= self.lit_percentile <= 100.0:
            raise ImageError("lit_percentile must be in [0, 100]")
        weight = self.illumination_min_weight
        if self.illumination_local_sigma_cells < 0.0 or not 0.0 < weight <= 1.0:
            raise ImageError(
                "illumination_local_sigma_cells must be >= 0, illumination_min_weight in (0, 1]"
            )
        if self.illumination_blend_min_change < 0.0:
            raise ImageError(
                "illumination_blend_min_change must be >= 0 [levels], got "
                f"{self.illumination_blend_min_change}"
            )
        if not 0.0 < self.threshold_min <= self.threshold_max:
            raise ImageError("need 0 < threshold_min <= threshold_max")
        if self.otsu_sample_step < 1 or self.edge_sample_step < 1:
            raise ImageError(
                "otsu_sample_step and edge_sample_step must be >= 1 [px], got "
                f"{self.otsu_sample_step} and {self.edge_sample_step}"
            )
        sizes = (self.open_px, self.restore_iterations, self.color_erode_px, self.border_margin_px)
        if min(sizes) < 0:
            raise ImageError("pixel sizes must be >= 0")
        if not (math.isfinite(self.resample_per_px) and self.resample_per_px >= 0.0):
            raise ImageError(f"resample_per_px must be >= 0, got {self.resample_per_px}")
        if self.canny_reduction < 1:
            raise ImageError(f"canny_reduction must be >= 1, got {self.canny_reduction}")
        if self.blur_sigma_px < 0.0 or self.min_area_px < 0.0 or self.min_hole_area_px < 0.0:
            raise ImageError("blur_sigma_px, min_area_px and min_hole_area_px must be >= 0")

    @classmethod
    def load(cls, name_or_path: str | Path | None = None, **overrides: Any) -> ExtractParams:
        """Load the ``extract`` section of ``configs/vision.yaml`` (or another file).

        Raises:
            configs.ConfigError: Unknown key or wrong type.
        """
        return load_section(cls, "extract", name_or_path, overrides)


@dataclass(frozen=True, eq=False)
class PartialTile:
    """A region touching the image border: part of a tile, not described as a whole one.

    Attributes:
        outline: Traced outline, shape (k, 2), [px], y down.
        area: Visible area, in [px^2].
        centroid: Centroid of the visible part, shape (2,), [px].
        color: Median colour, RGB in [0, 1].
    """

    outline: FloatArray
    area: float
    centroid: FloatArray
    color: tuple[float, float, float]


@dataclass(frozen=True, eq=False)
class ExtractResult:
    """Everything `extract_detailed` found.

    Attributes:
        figures: Whole tiles, pixel coordinates, ``y_down=True``.
        outlines: Dense traced outline of each figure (same order), shape (k, 2), [px].
        partial: Regions touching the image border.
        rejected: Messages for regions whose outline could not be made into a figure.
        background: Dominant (background) colour, RGB in [0, 1].
        threshold: Colour-distance threshold used for the foreground, in [levels].
    """

    figures: list[Figure]
    outlines: list[FloatArray]
    partial: list[PartialTile]
    rejected: list[str]
    background: tuple[float, float, float]
    threshold: float


@functools.cache
def default_params() -> ExtractParams:
    """Bundled parameters (``configs/vision.yaml``), loaded once."""
    return ExtractParams.load()


def read_image(path: str | Path) -> np.ndarray:
    """Read an image file as RGB uint8 (H, W, 3) (alpha dropped, grey expanded).

    Raises:
        ImageError: Missing or unreadable file.
    """
    data = cv2.imread(str(path), cv2.IMREAD_COLOR)
    if data is None:
        raise ImageError(f"cannot read image file {str(path)!r} (missing or not an image)")
    return np.ascontiguousarray(cv2.cvtColor(data, cv2.COLOR_BGR2RGB))


def check_image(image: Any, params: ExtractParams) -> np.ndarray:
    """Validate an RGB uint8 image, returning it as a contiguous array.

    Raises:
        ImageError: Not an array, wrong dtype, wrong shape or channel count, or size out of
            range.
    """
    if not isinstance(image, np.ndarray):
        raise ImageError(f"image must be a numpy array (H, W, 3) uint8, got {type(image).__name__}")
    if image.dtype != np.uint8:
        raise ImageError(f"image must have dtype uint8 (0-255), got {image.dtype}")
    if image.ndim != 3 or image.shape[2] != 3:
        raise ImageError(f"image must have shape (H, W, 3) RGB, got {image.shape}")
    h, w = image.shape[:2]
    lo, hi = params.min_size_px, params.max_size_px
    if not (lo <= h <= hi and lo <= w <= hi):
        raise ImageError(f"image size {w} x {h} px is outside the accepted {lo}..{hi} px per side")
    return np.ascontiguousarray(image)


def _channel_span(image: np.ndarray) -> int:
    """Largest range of levels over the three channels."""
    return max(int(hi - lo) for lo, hi, *_ in (cv2.minMaxLoc(c) for c in cv2.split(image)))


_BLUR_TAP_MIN = 1.0 / 512.0
"""Gaussian taps below this share of the kernel are dropped (they round to zero in OpenCV's
8-bit fixed-point blur, whose weights have 8 fractional bits)."""


@functools.cache
def _blur_size(sigma: float) -> int:
    """Odd kernel size [px] of the Gaussian pre-blur of ``sigma`` [px].

    OpenCV's own choice for 8-bit images (about 3 sigma each side) less the outer taps below
    `_BLUR_TAP_MIN`: for sigma 0.5 px 3, not 5, with the same output and a third less work.
    """
    default = round(sigma * 6.0 + 1.0) | 1
    g = np.exp(-(np.arange(default // 2 + 1) ** 2) / (2.0 * sigma * sigma))
    share = g / (g[0] + 2.0 * g[1:].sum())
    return min(default, 2 * int(np.flatnonzero(share >= _BLUR_TAP_MIN)[-1]) + 1)


def _channel_max(values: np.ndarray) -> np.ndarray:
    """Maximum over the last axis of (..., 3) values, from the three planes.

    numpy's reduction over an axis of 3 costs ~45 us on the (30, 41, 3) cell grid, the planes
    ~5 us; the result is the same.
    """
    out: np.ndarray = np.maximum(np.maximum(values[..., 0], values[..., 1]), values[..., 2])
    return out


def _channel_sum(values: np.ndarray) -> np.ndarray:
    """Sum over the last axis of (..., 3) values, from the three planes.

    The same sums as ``values.sum(axis=-1)`` (numpy adds three values left to right too), at
    a fifth of its cost on the cell grid.
    """
    out: np.ndarray = values[..., 0] + values[..., 1] + values[..., 2]
    return out


def _dominant_color(img: np.ndarray, p: ExtractParams) -> tuple[np.ndarray, float, int]:
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
    near = _channel_max(off.T) <= p.background_tolerance
    span = int((planes.max(axis=1).astype(np.int32) - planes.min(axis=1)).max())
    return dominant, float(near.mean()), span


@functools.cache
def _polynomial_basis(gh: int, gw: int, degree: int) -> np.ndarray:
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


def _polynomial_fit(small: np.ndarray, keep: np.ndarray, degree: int) -> np.ndarray | None:
    """Per-channel polynomial of the cell grid (gh, gw, 3) fitted on ``keep`` cells, or None."""
    gh, gw = keep.shape
    terms = (degree + 1) * (degree + 2) // 2
    if degree <= 0 or int(keep.sum()) < 2 * terms:
        return None
    basis = _polynomial_basis(gh, gw, degree)
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
def _box(size: int) -> np.ndarray:
    """Square structuring element of ``size`` x ``size`` px (uint8 ones), made once."""
    kernel = cv2.getStructuringElement(cv2.MORPH_RECT, (size, size))
    kernel.setflags(write=False)
    return kernel


def _local_fill(
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
    moved = far & (_channel_max(np.abs(blended - out)) > p.illumination_blend_min_change)
    out[moved] = blended[moved]


def _grid_at(size: int, cells: int) -> tuple[np.ndarray, np.ndarray]:
    """Whole pixel and fraction (cells + 1,) of each edge of ``cells`` cells across ``size`` px."""
    edge = np.arange(cells + 1) * (size / cells)
    whole = np.minimum(edge.astype(np.intp), size - 1)
    return whole, edge - whole


def _cell_means(planes: Sequence[np.ndarray], gh: int, gw: int) -> np.ndarray:
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


def _illumination(
    planes: Sequence[np.ndarray], dominant: np.ndarray, p: ExtractParams
) -> tuple[tuple[np.ndarray, ...], np.ndarray, np.ndarray]:
    """Background model of the belt under the cell's light, from the picture's three channels.

    Returns:
        The model image as its three channels, each (H, W) uint8 (the colour distance and the
        tile colours read it plane by plane); the belt's colour under the reference light (3,) in
        levels (tile colours are corrected to that light); and the shading gain (H, W) uint8
        in units of 1 / ``_GAIN_SCALE`` (the reference brightness over the modelled one,
        saturating), by which colour distances are multiplied so that a tile in a shadow
        stands out as much as in full light.
    """
    h, w = planes[0].shape[:2]
    gh, gw = max(2, h // p.illumination_cell_px), max(2, w // p.illumination_cell_px)
    small = _cell_means(planes, gh, gw)
    dom = dominant.astype(np.float32)
    # The belt under any light is the dominant colour times a gain: compare each cell with
    # the dominant colour brought to the cell's brightness (a tile differs in hue, a shadow
    # only in brightness).
    ratio = _channel_sum(small) / max(float(dom.sum()), 1.0)
    shaded = _channel_max(np.abs(small - ratio[..., None] * dom))
    # Darker than the dominant colour: any shadow down to belt_gain_min; brighter: only
    # within background_tolerance (a grey tile is the belt's hue, but much brighter).
    brighter_ok = _channel_max(np.abs(small - dom)) <= p.background_tolerance
    is_bg = (
        (shaded <= p.background_chroma_tolerance)
        & (ratio >= p.belt_gain_min)
        & ((ratio <= 1.0) | brighter_ok)
    ).astype(np.uint8)
    # Cells beside a non-background cell are partly tile (mixed colours): not trusted.
    core = cv2.erode(is_bg, _box(3), borderType=cv2.BORDER_REPLICATE)
    keep = core.view(bool) if int(core.sum()) >= p.illumination_min_cells else is_bg.view(bool)
    poly = _polynomial_fit(small, keep, p.illumination_degree)
    model = np.broadcast_to(dominant, small.shape) if poly is None else poly
    if p.illumination_local_sigma_cells > 0.0 and keep.any():
        model = _local_fill(small, keep, model, p)
    model = np.asarray(model, dtype=np.float32)
    light = _channel_sum(model)
    lit = float(np.percentile(light, p.lit_percentile))
    gain = lit / np.maximum(light, 1.0)
    if not p.normalize_shading:
        gain[:] = 1.0
    gain8 = np.clip(gain * _GAIN_SCALE + 0.5, 0, 255).astype(np.uint8)
    model8 = np.clip(model + 0.5, 0, 255).astype(np.uint8)
    # Resized plane by plane: the same levels as resizing the colour image.
    up = tuple(cv2.resize(c, (w, h), interpolation=cv2.INTER_LINEAR) for c in cv2.split(model8))
    return (
        up,
        model.reshape(-1, 3).mean(axis=0).astype(np.float64) * lit / max(float(light.mean()), 1.0),
        cv2.resize(gain8, (w, h), interpolation=cv2.INTER_LINEAR),
    )


def _label_medians(
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


def _samples(
    region: np.ndarray, labels: np.ndarray, lut: np.ndarray, step: int, *planes: np.ndarray
) -> tuple[np.ndarray, list[np.ndarray]]:
    """Compact labels (N,) and values of every ``step``-th pixel (each axis) set in ``region``.

    Args:
        region: uint8 (H, W) mask.
        labels: int (H, W) labels.
        lut: Map of a label to its compact index.
        step: Sampling step, in [px].
        planes: uint8 (H, W) single-channel images sampled.

    Returns:
        The compact labels (N,) and, per plane, its values (N,).
    """
    w = region.shape[1]
    found = cv2.findNonZero(np.ascontiguousarray(region[::step, ::step]))
    if found is None:
        return np.zeros(0, lut.dtype), [np.zeros(0, np.uint8) for _ in planes]
    xy = found.reshape(-1, 2)
    at = xy[:, 1].astype(np.intp) * (step * w)
    at += xy[:, 0] * step
    values = [np.take(c.ravel(), at) for c in planes]
    return np.take(lut, np.take(labels.ravel(), at)), values


def _compact(present: np.ndarray) -> tuple[np.ndarray, int]:
    """Map of labels to compact indices (1.. for present labels, 0 for the rest), and the count."""
    lut = np.zeros(len(present), np.int64)
    k = int(np.count_nonzero(present))
    lut[present] = np.arange(1, k + 1)
    return lut, k + 1


def _at_half_contrast(
    pieces: np.ndarray,
    labels: np.ndarray,
    dist: np.ndarray,
    present: np.ndarray,
    *,
    thr: float,
    p: ExtractParams,
) -> np.ndarray:
    """Each region's pixels (uint8 mask) at or above its own edge level of the colour distance.

    The global threshold finds every tile, a dark glaze in a shadow too; but a blurred edge
    lies where the distance is at half the tile's own contrast. Each region keeps the pixels
    whose distance reaches ``edge_fraction`` x its median distance, clamped to
    [``thr``, ``edge_threshold_max``], so a bright tile's outline is where it was with a
    high global threshold and a faint tile's where its own contrast puts it.
    """
    count = len(present)
    lut, k = _compact(present)
    lab, val = _samples(pieces, labels, lut, p.edge_sample_step, dist)
    median = np.zeros(count)
    median[present] = _label_medians(lab, val, k)[0][1:, 0]
    level = np.clip(p.edge_fraction * median, thr, max(thr, p.edge_threshold_max))
    if not (level > thr).any():
        return pieces
    if count <= 256:  # noqa: PLR2004 (labels fit a byte: one table look-up per pixel)
        table = np.zeros(256, np.uint8)
        table[:count] = np.ceil(level)
        per_pixel = cv2.LUT(labels.astype(np.uint8, copy=False), table)
        keep = cv2.compare(dist, per_pixel, cv2.CMP_GE)
    else:
        per_pixel = np.take(level.astype(np.float32), np.asarray(labels, dtype=np.intp))
        keep = cv2.compare(dist.astype(np.float32), per_pixel, cv2.CMP_GE)
    return cv2.bitwise_and(pieces, keep)


def _canny(plane: np.ndarray, low: float, high: float) -> np.ndarray:
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


def _color_edges(
    img: np.ndarray, p: ExtractParams, planes: Sequence[np.ndarray] | None = None
) -> np.ndarray:
    """Canny edges of any channel: the union of one single-channel Canny per channel, uint8.

    Colour tiles that touch differ in at least one channel. OpenCV's single-channel Canny is
    several times faster than its three-channel one (which thresholds the largest channel
    gradient); the union marks the same boundaries. With ``canny_reduction`` f > 1 the edges
    are found on the picture reduced f times per axis (a quarter of the work at f = 2) and
    each is a block of f x f px here: the
    cut only has to part the pieces, and the label dilations that give the cut pixels back
    fill a band of that width from both sides. ``planes``: the picture's channels when already
    split.
    """
    f = p.canny_reduction
    h, w = img.shape[:2]
    small = img if f == 1 else cv2.resize(img, (w // f, h // f), interpolation=cv2.INTER_AREA)
    low, high = p.canny_low, p.canny_high
    r, g, b = planes if f == 1 and planes is not None else cv2.split(small)
    edges = _canny(r, low, high)
    cv2.bitwise_or(edges, _canny(g, low, high), dst=edges)
    cv2.bitwise_or(edges, _canny(b, low, high), dst=edges)
    if f == 1:
        return edges
    full = np.zeros((h, w), np.uint8)
    full[: (h // f) * f, : (w // f) * f] = cv2.resize(
        edges, ((w // f) * f, (h // f) * f), interpolation=cv2.INTER_NEAREST
    )
    return full


def _shows_belt(dist: np.ndarray, hole: np.ndarray, limit: float, percentile: float) -> bool:
    """True when the colour distance inside a traced hole (k, 1, 2) reaches down to the belt.

    A real hole shows the belt: its core is at distance near 0 (``percentile`` of the inside
    at most ``limit``) however thin the hole and blurred its rim. A dip of a dark or shaded
    glaze below the threshold is tile material, its distances just under the threshold.
    """
    x, y, bw, bh = cv2.boundingRect(hole)
    inside = np.zeros((bh, bw), np.uint8)
    cv2.fillPoly(inside, [hole - np.array([x, y], np.int32)], 255)
    values = dist[y : y + bh, x : x + bw][inside > 0]
    return values.size > 0 and float(np.percentile(values, percentile)) <= limit


def _offset_outline(contour: FloatArray, offset: float, outward_sign: float) -> FloatArray:
    """Move a closed outline along its normals by ``offset`` (outwards for the given sign)."""
    if offset == 0.0 or len(contour) < 3:
        return contour
    tangent = np.roll(contour, -1, axis=0) - np.roll(contour, 1, axis=0)
    norm = np.hypot(tangent[:, 0], tangent[:, 1])
    norm[norm == 0.0] = 1.0
    normal = np.stack([tangent[:, 1], -tangent[:, 0]], axis=1) / norm[:, None]
    return contour + outward_sign * offset * normal


def _signed_area(c: FloatArray) -> float:
    x, y = c[:, 0], c[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


@dataclass(frozen=True, eq=False)
class _Segmentation:
    """What the image stages hand to outline tracing (internal).

    Attributes:
        dist: Colour distance to the belt model times the shading gain, (H, W) uint8 [levels].
        threshold: Foreground threshold on ``dist``, in [levels].
        labels: Region label of every pixel (0: none), (H, W) uint8 when ``count`` <= 256,
            else int32.
        count: Number of labels (background included).
        present: Which labels are regions (not background, not a crumb), (count,) bool.
        pieces: Region pixels, each region apart from its neighbours, (H, W) uint8 0/255.
    """

    dist: np.ndarray
    threshold: float
    labels: np.ndarray
    count: int
    present: np.ndarray
    pieces: np.ndarray


def _colour_distance(
    planes: Sequence[np.ndarray], model: Sequence[np.ndarray], gain: np.ndarray, p: ExtractParams
) -> tuple[np.ndarray, float, np.ndarray]:
    """Colour distance to the belt model (uint8), its threshold, and the opened foreground mask.

    ``planes`` and ``model``: the picture's and the model's channels, each (H, W) uint8 (plane
    by plane, the largest channel difference needs no split of a difference image).
    """
    # Two picture-sized buffers, each written several times (fewer fresh buffers to fault in).
    dist = cv2.absdiff(planes[0], model[0])
    other = cv2.absdiff(planes[1], model[1])
    cv2.max(dist, other, dst=dist)
    cv2.max(dist, cv2.absdiff(planes[2], model[2], dst=other), dst=dist)
    cv2.multiply(dist, gain, dst=dist, scale=1.0 / _GAIN_SCALE)
    st = p.otsu_sample_step
    sample = dist if st == 1 else np.ascontiguousarray(dist[::st, ::st])
    otsu, mask = cv2.threshold(sample, 0, 255, cv2.THRESH_BINARY + cv2.THRESH_OTSU)
    thr = float(np.clip(otsu, p.threshold_min, p.threshold_max))
    if st > 1 or thr != otsu:
        _, mask = cv2.threshold(dist, thr, 255, cv2.THRESH_BINARY)
    if p.open_px > 1:
        mask = cv2.morphologyEx(mask, cv2.MORPH_OPEN, _box(p.open_px))
    return dist, thr, mask


def _label_pieces(cut: np.ndarray) -> tuple[int, np.ndarray]:
    """4-connected scan-order labels of a uint8 mask: (count, labels (H, W) uint16 or int32).

    16-bit labels when they fit (OpenCV writes them about a quarter faster); OpenCV refuses
    to overflow them (a noisy mask of more than 65535 pieces), and then they are 32-bit. The
    labels are the same either way.
    """
    try:
        return cv2.connectedComponentsWithAlgorithm(cut, 4, cv2.CV_16U, cv2.CCL_SAUF)
    except cv2.error:
        return cv2.connectedComponentsWithAlgorithm(cut, 4, cv2.CV_32S, cv2.CCL_SAUF)


def _split_regions(
    img: np.ndarray, mask: np.ndarray, p: ExtractParams, planes: Sequence[np.ndarray] | None = None
) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]:
    """Label the foreground, touching tiles of different colours apart.

    Cut the foreground along Canny edges, label the pieces, give the cut pixels (and crumbs
    smaller than a tile) back to a neighbouring piece, then separate touching pieces by
    dropping the pixels that border a piece with a higher label. ``planes``: the picture's
    channels when already split.

    Returns:
        (count, labels (H, W) (uint8 when count <= 256, else int32), present (count,) bool,
        pieces (H, W) uint8).
    """
    if not p.split_touching:
        count, labels = cv2.connectedComponents(mask, connectivity=8)
        present = np.ones(count, bool)
        present[0] = False
        return count, labels, present, mask
    edges = _color_edges(img, p, planes)
    cut = cv2.bitwise_and(mask, cv2.bitwise_not(edges))
    # Scan-order labels as connectedComponents gives them; its 4-connected default is slower.
    count, labels = _label_pieces(cut)
    # Up to 256 labels fit a byte: histogram, look-up and dilations in OpenCV's uint8 paths
    # (a dilation of labels is a maximum filter: the same in any type that holds them).
    small = count <= 256  # noqa: PLR2004
    lab: np.ndarray = labels.astype(np.uint8) if small else labels.astype(np.float32)
    if small:
        sizes = cv2.calcHist([lab], [0], None, [256], [0, 256]).ravel()[:count]
    else:
        sizes = np.bincount(labels.ravel(), minlength=count)
    present = sizes >= p.min_area_px
    present[0] = False
    if not present[1:].all():  # crumbs (pieces smaller than a tile) to label 0
        lut = np.where(present, np.arange(count), 0).astype(lab.dtype)
        if small:
            lab = cv2.LUT(lab, np.pad(lut, (0, 256 - count)))
        else:
            lab = np.take(lut, np.asarray(labels, dtype=np.intp))
    kernel3 = _box(3)
    zero = np.zeros(1, lab.dtype)
    lost = cv2.bitwise_and(mask, cv2.compare(lab, zero, cv2.CMP_EQ))
    left = cv2.countNonZero(lost)
    for _ in range(p.restore_iterations):
        if left == 0:
            break
        lab = cv2.copyTo(cv2.dilate(lab, kernel3), lost, lab)
        lost = cv2.bitwise_and(mask, cv2.compare(lab, zero, cv2.CMP_EQ))
        before, left = left, cv2.countNonZero(lost)
        if left == before:  # the rest touches no piece (a speck): nothing more to give back
            break
    border = cv2.compare(cv2.dilate(lab, kernel3), lab, cv2.CMP_GT)
    pieces = cv2.bitwise_and(cv2.compare(lab, zero, cv2.CMP_GT), cv2.bitwise_not(border))
    return count, (lab if small else lab.astype(np.int32)), present, pieces


def _segment(
    img: np.ndarray,
    planes: Sequence[np.ndarray],
    model: Sequence[np.ndarray],
    gain: np.ndarray,
    p: ExtractParams,
) -> _Segmentation:
    """Image stages after the belt model: distance, threshold, regions, per-region edge level.

    ``planes``: the picture's channels; ``model``: the belt model's.
    """
    dist, thr, mask = _colour_distance(planes, model, gain, p)
    count, labels, present, pieces = _split_regions(img, mask, p, planes)
    if p.edge_fraction > 0.0:
        pieces = _at_half_contrast(pieces, labels, dist, present, thr=thr, p=p)
    return _Segmentation(dist, thr, labels, count, present, pieces)


def _tile_colours(
    planes: Sequence[np.ndarray],
    model: Sequence[np.ndarray],
    mean_light: np.ndarray,
    seg: _Segmentation,
    p: ExtractParams,
) -> np.ndarray:
    """Median colour of every label (count, 3) [levels], under the reference light.

    ``planes`` and ``model``: the picture's and the belt model's three channels, each (H, W)
    uint8.
    """
    labels, pieces = seg.labels, seg.pieces
    if p.color_erode_px > 0:
        region = cv2.erode(pieces, _box(2 * p.color_erode_px + 1))
    else:
        region = pieces
    lut, k = _compact(seg.present)
    st = max(1, p.color_sample_step)
    medians, seen = _label_medians(*_samples(region, labels, lut, st, *planes, *model), k)
    # Tiles eroded away entirely fall back to their whole region.
    if not seen[1:].all():
        again = _label_medians(*_samples(pieces, labels, lut, 1, *planes, *model), k)[0]
        medians[~seen] = again[~seen]
    compact = medians[:, :3].astype(np.float64)
    if p.correct_illumination:  # each tile's median colour under its median light
        compact = compact * mean_light / np.maximum(medians[:, 3:], 1.0)
    colors = np.zeros((seg.count, 3))
    colors[seg.present] = compact[1:]
    return colors


def _trace(pieces: np.ndarray) -> tuple[Any, np.ndarray | None]:
    """Outer contours and holes (two-level hierarchy) of the region mask."""
    return cv2.findContours(pieces, cv2.RETR_CCOMP, cv2.CHAIN_APPROX_NONE)


_Todo = tuple[FloatArray, list[FloatArray], Color, str, float]


def _outlines(
    contours: Any,
    hier: np.ndarray,
    colors: np.ndarray,
    seg: _Segmentation,
    *,
    shape: tuple[int, int],
    p: ExtractParams,
) -> tuple[list[_Todo], list[PartialTile]]:
    """Whole regions' outlines with their holes and colours, and the partial tiles.

    Returns:
        Per whole region (outline (k, 2), holes, colour, where, traced length [px]), and the
        regions touching the border.
    """
    h, w = shape
    m = p.border_margin_px
    partial: list[PartialTile] = []
    todo: list[_Todo] = []
    unit = np.clip(colors / 255.0, 0.0, 1.0).tolist()  # every label's colour, RGB in [0, 1]
    parent = hier[:, 3].tolist()
    for i, cnt in enumerate(contours):
        if parent[i] != -1:
            continue  # a hole; handled with its parent
        area = cv2.contourArea(cnt)
        if area < p.min_area_px:
            continue
        pts = cnt[:, 0, :].astype(np.float64)
        x0, y0 = int(cnt[0, 0, 0]), int(cnt[0, 0, 1])
        bx, by, bw, bh = cv2.boundingRect(cnt)
        r, g, b = unit[int(seg.labels[y0, x0])]
        color3 = (r, g, b)
        if bx <= m or by <= m or bx + bw >= w - m or by + bh >= h - m:
            mom = cv2.moments(cnt)
            cen = np.array([mom["m10"], mom["m01"]]) / max(mom["m00"], 1e-9)
            partial.append(PartialTile(pts, float(area), cen, color3))
            continue
        holes = []
        child = hier[i][2]
        while child != -1:
            hole = contours[child]
            h_area = cv2.contourArea(hole)
            h_len = cv2.arcLength(hole, True)
            if (
                h_area >= p.min_hole_area_px
                and 2.0 * h_area >= p.min_hole_width_px * h_len
                and _shows_belt(
                    seg.dist, hole, seg.threshold * p.hole_belt_fraction, p.hole_belt_percentile
                )
            ):
                hp = hole[:, 0, :].astype(np.float64)
                # A hole's outward (away from the tile material) is into the hole.
                sign = 1.0 if _signed_area(hp) > 0 else -1.0
                holes.append(_offset_outline(hp, p.boundary_offset_px, -sign))
            child = hier[child][0]
        if p.boundary_offset_px != 0.0:
            sign = 1.0 if _signed_area(pts) > 0 else -1.0
            pts = _offset_outline(pts, p.boundary_offset_px, sign)
        where = f"region at ({x0}, {y0}) px, area {area:.0f} px^2"
        todo.append((pts, holes, color3, where, cv2.arcLength(cnt, True)))
    return todo, partial


def _outline_params(todo: list[_Todo], p: ExtractParams) -> OutlineParams:
    """The outline parameters with the picture's resample count (see ``resample_per_px``)."""
    cap = p.outline.resample_points
    if p.resample_per_px <= 0.0 or not todo:
        return p.outline
    longest = max(t[4] for t in todo)
    n = min(cap, max(MIN_RESAMPLE_POINTS, math.ceil(p.resample_per_px * longest)))
    return p.outline if n == cap else replace(p.outline, resample_points=n)


def _figures(
    todo: list[_Todo], p: ExtractParams
) -> tuple[list[Figure], list[FloatArray], list[str]]:
    """Every outline simplified at once into figures; noise-like outlines rejected."""
    made = figures_from_outlines(
        [t[0] for t in todo],
        [t[1] for t in todo],
        [t[2] for t in todo],
        _outline_params(todo, p),
        y_down=True,
    )
    figures: list[Figure] = []
    outlines: list[FloatArray] = []
    rejected: list[str] = []
    for (outline, _, _, where, traced), fig in zip(todo, made, strict=True):
        if isinstance(fig, InvalidFigureError):
            rejected.append(f"{where}: {fig}")
            continue
        if traced > p.max_outline_excess * fig.perimeter:
            rejected.append(
                f"{where}: outline mostly noise (traced length {traced / fig.perimeter:.2f} x the "
                f"perimeter of its relevant points; at most {p.max_outline_excess:g} allowed)"
            )
            continue
        figures.append(fig)
        outlines.append(outline)
    return figures, outlines, rejected


def extract_detailed(image: np.ndarray, params: ExtractParams | None = None) -> ExtractResult:
    """Tiles in an image: whole tiles as figures, border-touching ones as partial tiles.

    Args:
        image: RGB uint8, shape (H, W, 3): tiles on a roughly uniform background (belt or
            grout), possibly shaded.
        params: Parameters; None loads ``configs/vision.yaml``.

    Returns:
        An `ExtractResult`; an image with no tiles gives empty lists, and so does a
        single-colour image (an empty belt) and an image without a dominant background colour
        (noise; its reason is in ``rejected``).

    Raises:
        ImageError: Invalid image (see `check_image`).
    """
    p = default_params() if params is None else params
    raw = check_image(image, p)
    img = raw
    if p.blur_sigma_px > 0.0:
        size = _blur_size(p.blur_sigma_px)
        img = cv2.GaussianBlur(raw, (size, size), p.blur_sigma_px)
    dominant, share, seen_span = _dominant_color(img, p)
    # The blur keeps every level within the picture's range: a border sample spanning more
    # than uniform_range proves the picture is not one colour without reading all of it.
    if seen_span <= p.uniform_range and _channel_span(raw) <= p.uniform_range:
        level = raw[0, 0].astype(np.float64) / 255.0
        return ExtractResult([], [], [], [], (level[0], level[1], level[2]), 0.0)
    background = (
        float(dominant[0]) / 255.0,
        float(dominant[1]) / 255.0,
        float(dominant[2]) / 255.0,
    )
    if share < p.min_background_fraction:
        why = (
            f"no dominant background: {100 * share:.0f}% of the border is near its commonest "
            f"colour (at least {100 * p.min_background_fraction:.0f}% needed); nothing is "
            "segmented"
        )
        return ExtractResult([], [], [], [why], background, 0.0)
    planes = cv2.split(img)
    model, mean_light, gain = _illumination(planes, dominant, p)
    seg = _segment(img, planes, model, gain, p)
    contours, hierarchy = _trace(seg.pieces)
    if seg.count <= 1 or hierarchy is None:
        return ExtractResult([], [], [], [], background, seg.threshold)
    colors = _tile_colours(planes, model, mean_light, seg, p)
    todo, partial = _outlines(contours, hierarchy[0], colors, seg, shape=img.shape[:2], p=p)
    figures, outlines, rejected = _figures(todo, p)
    return ExtractResult(figures, outlines, partial, rejected, background, seg.threshold)


def extract(image: np.ndarray, params: ExtractParams | None = None) -> list[Figure]:
    """Whole tiles in an RGB uint8 image as figures (pixel coordinates, ``y_down=True``).

    Tiles touching the image border are left out (see `extract_detailed`).

    Raises:
        ImageError: Invalid image.
    """
    return extract_detailed(image, params).figures


__all__ = [
    "ExtractParams",
    "ExtractResult",
    "ImageError",
    "PartialTile",
    "check_image",
    "default_params",
    "extract",
    "extract_detailed",
    "read_image",
]
