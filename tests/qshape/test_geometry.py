"""Plane geometry helpers: signed area and orientation, centroids, self-intersection, points in a
polygon, arc areas.
"""

import math

import numpy as np
import pytest

from qshape import geometry as geo

SQUARE = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]])


def test_signed_area_and_orientation():
    assert geo.signed_area(SQUARE) == pytest.approx(4.0)
    assert geo.signed_area(SQUARE[::-1]) == pytest.approx(-4.0)
    assert geo.is_counter_clockwise(SQUARE)
    assert not geo.is_counter_clockwise(SQUARE[::-1])


def test_polygon_centroid():
    tri = np.array([[0.0, 0.0], [3.0, 0.0], [0.0, 3.0]])
    np.testing.assert_allclose(geo.polygon_centroid(tri), [1.0, 1.0])
    np.testing.assert_allclose(geo.polygon_centroid(SQUARE + 5.0), [6.0, 6.0])


def test_self_intersection():
    bowtie = np.array([[0.0, 0.0], [2.0, 2.0], [2.0, 0.0], [0.0, 2.0]])
    assert geo.self_intersects(bowtie)
    assert not geo.self_intersects(SQUARE)
    touching = np.array([[0, 0], [4, 0], [4, 4], [2, 0.0], [0, 4]], dtype=float)
    assert geo.self_intersects(touching)


def test_points_in_polygon():
    q = np.array([[1.0, 1.0], [3.0, 1.0], [-0.5, 0.5]])
    assert geo.points_in_polygon(q, SQUARE).tolist() == [True, False, False]


def test_arc_area_of_circle_and_semicircle():
    r = 3.0
    circle = np.array([[-r, 0.0], [0.0, r], [r, 0.0], [0.0, -r]])[::-1].copy()  # CCW
    mask = np.array([False, True, False, True])[::-1].copy()
    area, centroid, perimeter = geo.area_centroid_perimeter(circle, mask)
    assert area == pytest.approx(math.pi * r * r)
    assert perimeter == pytest.approx(2 * math.pi * r)
    np.testing.assert_allclose(centroid, [0.0, 0.0], atol=1e-12)
    semi = np.array([[r, 0.0], [0.0, r], [-r, 0.0]])
    area, centroid, perimeter = geo.area_centroid_perimeter(semi, np.array([False, True, False]))
    assert area == pytest.approx(math.pi * r * r / 2)
    assert perimeter == pytest.approx(math.pi * r + 2 * r)
    np.testing.assert_allclose(centroid, [0.0, 4 * r / (3 * math.pi)], atol=1e-12)
