"""Edges and regions: touching tiles of different colours cut apart along Canny edges (found on
the reduced picture), crumbs given back, and each region's outline at its own edge level.
"""

from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np
import pytest

from qshape.design import Design
from qshape.synthetic.synth import SynthParams, generate
from qshape.vision.extract import extract_detailed
from qshape.vision.params import ExtractParams
from qshape.vision.segment import color_edges, split_regions


@pytest.mark.parametrize(("h", "w"), [(120, 160), (97, 61)])
def test_reduced_canny_edges_are_blocks_of_the_reduced_pictures_edges(
    h: int, w: int, extract_params: ExtractParams
) -> None:
    """With canny_reduction 2 each edge of the halved picture is a 2 x 2 block (odd sides: none
    in the last row/column), the union over the channels."""

    rng = np.random.default_rng(7)
    img = cv2.GaussianBlur(rng.integers(0, 256, (h, w, 3), dtype=np.uint8), (0, 0), 2.0)
    p = replace(extract_params, canny_reduction=2, canny_low=20.0, canny_high=50.0)
    got = color_edges(img, p)
    small = cv2.resize(img, (w // 2, h // 2), interpolation=cv2.INTER_AREA)
    want = np.zeros((h // 2, w // 2), np.uint8)
    for c in range(3):
        want |= cv2.Canny(np.ascontiguousarray(small[..., c]), 20.0, 50.0)
    assert got.shape == (h, w) and want.any()
    blocks = got[: h // 2 * 2, : w // 2 * 2].reshape(h // 2, 2, w // 2, 2)
    for dy in range(2):
        for dx in range(2):
            np.testing.assert_array_equal(blocks[:, dy, :, dx], want)
    assert not got[h // 2 * 2 :].any() and not got[:, w // 2 * 2 :].any()


def test_crumbs_beyond_a_byte_of_labels_leave_pieces_unchanged(
    extract_params: ExtractParams,
) -> None:
    """Regions are the same whether the labels fit a byte (OpenCV look-up) or not (numpy)."""

    p = extract_params
    img = np.full((200, 300, 3), 60, np.uint8)
    mask = np.zeros((200, 300), np.uint8)
    cv2.rectangle(img, (20, 20), (80, 90), (200, 40, 40), -1)
    cv2.rectangle(img, (81, 20), (140, 90), (40, 200, 40), -1)  # touching, other colour
    cv2.rectangle(mask, (20, 20), (140, 90), 255, -1)
    count, labels, present, pieces = split_regions(img, mask, p)
    assert count <= 256 and present.sum() == 2
    crumbs = mask.copy()
    crumbs[120::3, ::3] = 255  # 700 one-pixel crumbs below the tiles
    many, labels2, present2, pieces2 = split_regions(img, crumbs, p)
    assert many > 256 and present2.sum() == 2
    np.testing.assert_array_equal(pieces2, pieces)
    np.testing.assert_array_equal(labels2[:100] > 0, labels[:100] > 0)


def test_reduced_canny_cut_parts_touching_tiles_at_their_boundary(
    extract_params: ExtractParams,
) -> None:
    """Two touching rectangles of different colours: the cut of the halved picture's Canny is
    given back from both sides, so each piece ends within a pixel of the true boundary."""

    img = np.full((120, 200, 3), 50, np.uint8)
    img[30:90, 30:101] = (200, 60, 40)  # columns 30..100
    img[30:90, 101:170] = (60, 180, 60)  # columns 101..169, touching
    img = cv2.GaussianBlur(img, (0, 0), 0.8)
    mask = np.where(np.abs(img.astype(int) - 50).max(axis=2) > 20, 255, 0).astype(np.uint8)
    for reduction in (1, 2):
        p = replace(extract_params, canny_reduction=reduction)
        count, labels, present, pieces = split_regions(img, mask, p)
        assert present.sum() == 2
        row = labels[60] * (pieces[60] > 0)
        left, right = (np.flatnonzero(row == k) for k in np.flatnonzero(present))
        if left.mean() > right.mean():
            left, right = right, left
        # The colours change between columns 100 and 101; one pixel on the cut is dropped
        # (it borders the other piece): the gap is within a pixel of the change.
        assert 98 <= left.max() <= 100 and 100 <= right.min() <= 102
        assert right.min() - left.max() == 2


def test_edge_level_from_every_fourth_pixel_keeps_the_synthetic_figures(
    synth_params: SynthParams, extract_params: ExtractParams
) -> None:
    """A region's median distance from every 4th pixel per axis gives the same figures as from
    every pixel on a camera-like view: the same vertices, most of them bit for bit (a level
    one step off moves a few by about a tenth of a pixel)."""
    sp = synth_params
    img = generate(Design.load("hexagon"), 20, 11, sp).image
    every = extract_detailed(img, replace(extract_params, edge_sample_step=1)).figures
    fourth = extract_detailed(img, replace(extract_params, edge_sample_step=4)).figures
    assert len(fourth) == len(every) >= 15
    for a, b in zip(every, fourth, strict=True):
        assert len(a.points) == len(b.points)
        np.testing.assert_allclose(a.points, b.points, atol=0.25)
    same = [np.array_equal(a.points, b.points) for a, b in zip(every, fourth, strict=True)]
    assert sum(same) >= len(same) - 3
