"""A height picture: tiles of the belt's own colour found, every other tile as without it."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from qshape.vision.extract import extract_detailed
from qshape.vision.params import ImageError

BELT = (31, 31, 33)  # the cell's belt, RGB 0.12 0.12 0.13
H, W = 240, 320


def _picture() -> tuple[np.ndarray, np.ndarray]:
    """A red square, a black square and a belt-coloured square on the belt, with heights."""
    img = np.empty((H, W, 3), np.uint8)
    img[:] = BELT
    height = np.zeros((H, W), np.float32)
    for (x, y), colour in (((40, 60), (192, 57, 43)), ((140, 60), (20, 20, 20)), ((230, 80), BELT)):
        cv2.rectangle(img, (x, y), (x + 60, y + 60), colour, -1)
        cv2.rectangle(height, (x, y), (x + 60, y + 60), 5.0, -1)  # a 5 mm tile
    return img, height


def test_tiles_of_the_belts_colour_are_found_by_their_height() -> None:
    img, height = _picture()
    without = extract_detailed(img)
    with_height = extract_detailed(img, height=height)
    assert len(without.figures) == 1  # only the red tile stands off the belt in colour
    assert len(with_height.figures) == 3
    centres = np.array(sorted(tuple(f.centroid) for f in with_height.figures))
    np.testing.assert_allclose(centres, [(70, 90), (170, 90), (260, 110)], atol=1.0)
    for f in with_height.figures:
        assert f.area == pytest.approx(61 * 61, rel=0.06)
    dark = [f for f in with_height.figures if f.color is not None and max(f.color) < 0.2]
    assert len(dark) == 2


def test_a_tile_the_colour_shows_is_extracted_exactly_as_without_height() -> None:
    img, height = _picture()
    red = extract_detailed(img).figures[0]
    again = [f for f in extract_detailed(img, height=height).figures if f.color[0] > 0.5][0]
    np.testing.assert_allclose(red.outer.points, again.outer.points, atol=1e-9)
    assert red.color == again.color


def test_an_all_belt_picture_with_a_raised_tile_is_not_taken_for_an_empty_belt() -> None:
    img = np.empty((H, W, 3), np.uint8)
    img[:] = BELT
    height = np.zeros((H, W), np.float32)
    cv2.rectangle(height, (100, 80), (160, 140), 5.0, -1)
    assert extract_detailed(img).figures == []
    assert len(extract_detailed(img, height=height).figures) == 1


def test_a_height_picture_of_another_size_is_refused() -> None:
    img, height = _picture()
    with pytest.raises(ImageError, match="height picture"):
        extract_detailed(img, height=height[:-1])
