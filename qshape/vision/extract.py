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
names with ``from qshape.vision.extract import extract_detailed, ...`` and the parameters with
``from qshape.vision.params import ExtractParams``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from qshape.errors import InvalidFigureError
from qshape.geometry import FloatArray
from qshape.outline.params import MIN_RESAMPLE_POINTS, OutlineParams
from qshape.theory.figure import Color, Figure, figures_from_outlines
from qshape.vision.background import (
    blur_size,
    box_kernel,
    channel_span,
    dominant_color,
    illumination,
)
from qshape.vision.params import ExtractParams, ImageError, default_params
from qshape.vision.segment import Segmentation, compact_labels, label_medians, samples, segment


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


def _tile_colours(
    planes: Sequence[np.ndarray],
    model: Sequence[np.ndarray],
    mean_light: np.ndarray,
    seg: Segmentation,
    p: ExtractParams,
) -> np.ndarray:
    """Median colour of every label (count, 3) [levels], under the reference light.

    ``planes`` and ``model``: the picture's and the belt model's three channels, each (H, W)
    uint8.
    """
    labels, pieces = seg.labels, seg.pieces
    if p.color_erode_px > 0:
        region = cv2.erode(pieces, box_kernel(2 * p.color_erode_px + 1))
    else:
        region = pieces
    lut, k = compact_labels(seg.present)
    st = max(1, p.color_sample_step)
    medians, seen = label_medians(*samples(region, labels, lut, st, *planes, *model), k)
    # Tiles eroded away entirely fall back to their whole region.
    if not seen[1:].all():
        again = label_medians(*samples(pieces, labels, lut, 1, *planes, *model), k)[0]
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
    seg: Segmentation,
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


def extract_detailed(
    image: np.ndarray, params: ExtractParams | None = None, height: np.ndarray | None = None
) -> ExtractResult:
    """Tiles in an image: whole tiles as figures, border-touching ones as partial tiles.

    Args:
        image: RGB uint8, shape (H, W, 3): tiles on a roughly uniform background (belt or
            grout), possibly shaded.
        params: Parameters; None loads ``configs/vision.yaml``.
        height: The tiles' height above the belt, in [mm], shape (H, W), aligned with
            ``image`` (a 3D camera's picture), or None. A cue that does not depend on colour:
            a tile whose glaze is the belt's colour (black on a dark belt) is found by its
            height (`qshape.vision.segment.height_cue`); every other tile as without it.

    Returns:
        An `ExtractResult`; an image with no tiles gives empty lists, and so does a
        single-colour image (an empty belt) and an image without a dominant background colour
        (noise; its reason is in ``rejected``).

    Raises:
        ImageError: Invalid image (see `check_image`).
    """
    p = default_params() if params is None else params
    raw = check_image(image, p)
    levels = _height_levels(height, raw.shape[:2], p)
    img = raw
    if p.blur_sigma_px > 0.0:
        size = blur_size(p.blur_sigma_px)
        img = cv2.GaussianBlur(raw, (size, size), p.blur_sigma_px)
    dominant, share, seen_span = dominant_color(img, p)
    # The blur keeps every level within the picture's range: a border sample spanning more
    # than uniform_range proves the picture is not one colour without reading all of it.
    raised = levels is not None and float(levels.max()) >= p.threshold_min
    if not raised and seen_span <= p.uniform_range and channel_span(raw) <= p.uniform_range:
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
    model, mean_light, gain = illumination(planes, dominant, p)
    seg = segment(img, planes, model, gain, p, height=levels)
    contours, hierarchy = _trace(seg.pieces)
    if seg.count <= 1 or hierarchy is None:
        return ExtractResult([], [], [], [], background, seg.threshold)
    colors = _tile_colours(planes, model, mean_light, seg, p)
    todo, partial = _outlines(contours, hierarchy[0], colors, seg, shape=img.shape[:2], p=p)
    figures, outlines, rejected = _figures(todo, p)
    return ExtractResult(figures, outlines, partial, rejected, background, seg.threshold)


def _height_levels(
    height: np.ndarray | None, shape: tuple[int, ...], p: ExtractParams
) -> np.ndarray | None:
    """A height picture [mm] as colour-distance levels, uint8 (H, W); None without one.

    Raises:
        ImageError: Not a finite (H, W) or (H, W, 1) array of the image's size.
    """
    if height is None:
        return None
    h = np.asarray(height, dtype=np.float32)
    if h.ndim == 3 and h.shape[2] == 1:  # noqa: PLR2004
        h = h[..., 0]
    if h.shape != tuple(shape) or not np.all(np.isfinite(h)):
        raise ImageError(
            f"height picture must be finite, shape {tuple(shape)} (the image's), got {h.shape}"
        )
    levels = h * np.float32(p.height_levels_per_mm)
    return np.asarray(np.clip(levels, 0.0, 255.0), dtype=np.uint8)


def extract(image: np.ndarray, params: ExtractParams | None = None) -> list[Figure]:
    """Whole tiles in an RGB uint8 image as figures (pixel coordinates, ``y_down=True``).

    Tiles touching the image border are left out (see `extract_detailed`).

    Raises:
        ImageError: Invalid image.
    """
    return extract_detailed(image, params).figures


__all__ = [
    "ExtractResult",
    "PartialTile",
    "check_image",
    "extract",
    "extract_detailed",
    "read_image",
]
