"""Segmentation: the tiles apart from the belt and from each other.

Per-pixel colour distance to the belt model, times the shading gain, thresholded (Otsu, clamped)
and cleaned by a morphological opening; Canny edges inside the foreground split tiles of
different colours that touch; each region's outline is taken where the distance reaches half of
the region's own contrast (step 3 of `qshape.vision.extract`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import cv2
import numpy as np

from qshape.vision.background import (
    GAIN_SCALE,
    box_kernel,
)
from qshape.vision.params import ExtractParams


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


def samples(
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


def compact_labels(present: np.ndarray) -> tuple[np.ndarray, int]:
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
    lut, k = compact_labels(present)
    lab, val = samples(pieces, labels, lut, p.edge_sample_step, dist)
    median = np.zeros(count)
    median[present] = label_medians(lab, val, k)[0][1:, 0]
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


def color_edges(
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
    edges = canny(r, low, high)
    cv2.bitwise_or(edges, canny(g, low, high), dst=edges)
    cv2.bitwise_or(edges, canny(b, low, high), dst=edges)
    if f == 1:
        return edges
    full = np.zeros((h, w), np.uint8)
    full[: (h // f) * f, : (w // f) * f] = cv2.resize(
        edges, ((w // f) * f, (h // f) * f), interpolation=cv2.INTER_NEAREST
    )
    return full


@dataclass(frozen=True, eq=False)
class Segmentation:
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


def colour_distance(
    planes: Sequence[np.ndarray],
    model: Sequence[np.ndarray],
    gain: np.ndarray,
    p: ExtractParams,
    height: np.ndarray | None = None,
) -> tuple[np.ndarray, float, np.ndarray]:
    """Colour distance to the belt model (uint8), its threshold, and the opened foreground mask.

    ``planes`` and ``model``: the picture's and the model's channels, each (H, W) uint8 (plane
    by plane, the largest channel difference needs no split of a difference image).
    ``height``: the tiles' height above the belt in distance levels, uint8 (H, W), or None;
    raised regions whose colour nowhere reaches the threshold take it as their distance
    (`height_cue`), so a tile of the belt's colour is found by its height alone and every
    other tile exactly as without it.
    """
    # Two picture-sized buffers, each written several times (fewer fresh buffers to fault in).
    dist = cv2.absdiff(planes[0], model[0])
    other = cv2.absdiff(planes[1], model[1])
    cv2.max(dist, other, dst=dist)
    cv2.max(dist, cv2.absdiff(planes[2], model[2], dst=other), dst=dist)
    cv2.multiply(dist, gain, dst=dist, scale=1.0 / GAIN_SCALE)
    st = p.otsu_sample_step
    sample = dist if st == 1 else np.ascontiguousarray(dist[::st, ::st])
    otsu, mask = cv2.threshold(sample, 0, 255, cv2.THRESH_BINARY + cv2.THRESH_OTSU)
    thr = float(np.clip(otsu, p.threshold_min, p.threshold_max))
    redo = st > 1 or thr != otsu
    if height is not None:
        cue = height_cue(dist, height, thr, p)
        if cue is not None:
            cv2.max(dist, cue, dst=dist)
            redo = True
    if redo:
        _, mask = cv2.threshold(dist, thr, 255, cv2.THRESH_BINARY)
    if p.open_px > 1:
        mask = cv2.morphologyEx(mask, cv2.MORPH_OPEN, box_kernel(p.open_px))
    return dist, thr, mask


def height_cue(
    dist: np.ndarray, height: np.ndarray, thr: float, p: ExtractParams
) -> np.ndarray | None:
    """The height levels of the raised regions the colour distance misses, else 0 (uint8).

    A raised region (height at least ``thr``) in which the colour distance nowhere reaches
    ``thr`` is a tile the colour does not show; its height, over the region grown by
    ``height_grow_px`` (its edge), becomes its distance. None when there is no such region.
    """
    raised = np.where(height >= thr, np.uint8(255), np.uint8(0))
    count, lab = cv2.connectedComponents(raised, connectivity=8, ltype=cv2.CV_32S)
    if count <= 1:
        return None
    seen = np.zeros(count, np.uint8)
    np.maximum.at(seen, np.asarray(lab, dtype=np.intp).ravel(), dist.ravel())
    hidden = seen < thr
    hidden[0] = False
    if not hidden.any():
        return None
    keep = hidden[lab].astype(np.uint8) * np.uint8(255)
    if p.height_grow_px > 0:
        keep = np.asarray(cv2.dilate(keep, box_kernel(2 * p.height_grow_px + 1)), dtype=np.uint8)
    return np.asarray(cv2.bitwise_and(height, keep), dtype=np.uint8)


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


def split_regions(
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
    edges = color_edges(img, p, planes)
    cut = cv2.bitwise_and(mask, cv2.bitwise_not(edges))
    # Scan-order labels as connectedComponents gives them; its 4-connected default is slower.
    count, labels = label_pieces(cut)
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
    kernel3 = box_kernel(3)
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


def segment(
    img: np.ndarray,
    planes: Sequence[np.ndarray],
    model: Sequence[np.ndarray],
    gain: np.ndarray,
    p: ExtractParams,
    *,
    height: np.ndarray | None = None,
) -> Segmentation:
    """Image stages after the belt model: distance, threshold, regions, per-region edge level.

    ``planes``: the picture's channels; ``model``: the belt model's; ``height``: the tiles'
    height in distance levels (`colour_distance`).
    """
    dist, thr, mask = colour_distance(planes, model, gain, p, height)
    count, labels, present, pieces = split_regions(img, mask, p, planes)
    if p.edge_fraction > 0.0:
        pieces = _at_half_contrast(pieces, labels, dist, present, thr=thr, p=p)
    return Segmentation(dist, thr, labels, count, present, pieces)


__all__ = [
    "Segmentation",
    "canny",
    "color_edges",
    "colour_distance",
    "compact_labels",
    "label_medians",
    "height_cue",
    "label_pieces",
    "samples",
    "segment",
    "split_regions",
]
