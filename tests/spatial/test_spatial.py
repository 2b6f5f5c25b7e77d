"""`spatial`: the wrap at exactly pi as v0 had it for each caller, yaw conversions, units."""

from __future__ import annotations

import math

import numpy as np
import pytest

import qshape.geometry as qgeo
from spatial.angles import rotate_xy, wrap_angle, wrap_angles, yaw_error
from spatial.rotations import quat_from_yaw, yaw_from_matrix, yaw_from_quat
from spatial.units import M_PER_MM, MM_PER_M

PI = math.pi
EDGES = [PI, -PI, 3 * PI, -3 * PI, 0.0, 2 * PI, -2 * PI, 1e-300, -1e-300]


def _samples() -> np.ndarray:
    rng = np.random.default_rng(0)
    return np.concatenate([EDGES, rng.uniform(-20, 20, 2000), np.arange(-8, 9) * PI / 4])


def test_planners_envs_convention_is_half_open_above() -> None:
    assert wrap_angle(PI) == -PI and wrap_angle(-PI) == -PI
    assert wrap_angle(3 * PI) == -PI
    for a in _samples():
        w = wrap_angle(float(a))
        assert isinstance(w, float) and -PI <= w < PI
        # v0's planners.angles.wrap_angle for a float, kept here as the oracle:
        r = math.remainder(float(a), 2 * PI)
        assert w == (-PI if r == PI else r)


def test_qshape_convention_is_half_open_below() -> None:
    assert qgeo.wrap_angle(PI) == PI and qgeo.wrap_angle(-PI) == PI
    for a in _samples():
        w = qgeo.wrap_angle(float(a))
        assert -PI < w <= PI
        # v0's qshape.geometry.wrap_angle, kept here as the oracle:
        r = math.remainder(float(a), 2 * PI)
        assert w == (PI if r == -PI else r)


def test_array_wraps_match_v0_both_ways() -> None:
    a = _samples()
    w = np.remainder(a + PI, 2 * PI) - PI  # v0's array expressions (both modules)
    np.testing.assert_array_equal(wrap_angles(a), w)
    np.testing.assert_array_equal(wrap_angle(a), w)
    np.testing.assert_array_equal(qgeo.wrap_angles(a), np.where(w <= -PI, PI, w))
    assert qgeo.wrap_angles(np.array([-PI]))[0] == PI
    assert wrap_angle(np.float64(PI)) == -PI  # a 0-d input is wrapped as a float


def test_yaw_error_modulo_symmetry() -> None:
    assert yaw_error(0.1, 0.1 + PI / 2, 4) == pytest.approx(0.0, abs=1e-12)
    assert yaw_error(0.3, 0.0, 0) == 0.0
    assert yaw_error(PI, 0.0, 1) == pytest.approx(PI)
    errs = yaw_error(np.array([0.0, 0.2]), np.array([0.1, 0.0]), np.array([1, 2]))
    np.testing.assert_allclose(errs, [0.1, 0.2])
    assert qgeo.yaw_error(0.2, 0.0, 2) == yaw_error(0.2, 0.0, 2)
    np.testing.assert_array_equal(qgeo.yaw_errors([0.2], [0.0], [2]), [yaw_error(0.2, 0.0, 2)])


def test_yaw_quaternion_and_matrix_round_trip() -> None:
    yaw = np.linspace(-PI + 1e-6, PI - 1e-6, 41)
    q = quat_from_yaw(yaw)
    assert q.shape == (41, 4)
    np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0)
    np.testing.assert_allclose(yaw_from_quat(q), yaw, atol=1e-12)
    for a in yaw[::5]:
        c, s = math.cos(a), math.sin(a)
        rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        assert yaw_from_matrix(rot) == pytest.approx(a, abs=1e-12)
        np.testing.assert_allclose(rotate_xy([1.0, 0.0], a), [c, s], atol=1e-15)
    assert quat_from_yaw(0.3).shape == (4,)


def test_millimetres_per_metre() -> None:
    assert MM_PER_M == 1000.0 and M_PER_MM == 1e-3  # the very double of the literal
    assert 0.25 * MM_PER_M == 250.0
