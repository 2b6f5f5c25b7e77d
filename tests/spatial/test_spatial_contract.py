"""Contract tests of `spatial`: each documented return type, range, error and edge of the
angle helpers, the yaw conversions off the z axis, and the tolerances' units.

Each test names the bug it guards against; they are part of the mutation selection.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from spatial.angles import (
    TWO_PI,
    equivalent_yaws,
    rotate_xy,
    symmetry_period,
    wrap_angle,
    wrap_angles,
    yaw_error,
)
from spatial.rotations import quat_from_yaw, yaw_from_matrix, yaw_from_quat
from spatial.tolerance import (
    MADE_TILE_DEVIATION_M,
    MADE_TILE_DEVIATION_MM,
    PLACEMENT_POSITION_TOLERANCE_M,
    PLACEMENT_POSITION_TOLERANCE_MM,
    PLACEMENT_YAW_TOLERANCE_DEG,
)

PI = math.pi


def test_symmetry_period_values_and_error_message() -> None:
    """One full turn for no symmetry, 2 pi / k for k-fold, 0 for a round figure; a negative
    order is refused with a message saying what is allowed and what was given (a bare error
    leaves the caller guessing)."""
    assert symmetry_period(1) == TWO_PI
    assert symmetry_period(4) == TWO_PI / 4
    assert symmetry_period(6) == pytest.approx(PI / 3, abs=0.0)
    assert symmetry_period(0) == 0.0
    with pytest.raises(ValueError, match=r"symmetry order must be >= 0 \(0: continuous\), got -2"):
        symmetry_period(-2)


def test_equivalent_yaws_lists_the_symmetry_and_refuses_bad_orders() -> None:
    """``yaw`` first, then its k - 1 equivalents a period apart, not wrapped; a round figure
    at ``continuous_steps`` yaws; a negative order or no yaw to list is an error naming both."""
    np.testing.assert_allclose(equivalent_yaws(0.5, 4), 0.5 + np.arange(4) * PI / 2)
    assert equivalent_yaws(3.0, 2)[1] == pytest.approx(3.0 + PI)  # beyond pi: not wrapped
    np.testing.assert_array_equal(equivalent_yaws(0.2, 1), [0.2])
    np.testing.assert_allclose(
        equivalent_yaws(0.0, 0, continuous_steps=3), [0, TWO_PI / 3, 2 * TWO_PI / 3]
    )
    assert len(equivalent_yaws(1.0, 0)) == 1
    with pytest.raises(ValueError, match=r"got -1 and -1"):
        equivalent_yaws(0.0, -1)
    with pytest.raises(ValueError, match=r"got 0 and 0"):
        equivalent_yaws(0.0, 0, continuous_steps=0)


def test_yaw_error_types_ranges_and_broadcasting() -> None:
    """A float for scalar inputs (a 0-d array would not compare or format like the float the
    callers store), an array of the broadcast shape otherwise; always in [0, pi / k]."""
    e = yaw_error(0.25, 0.0, 1)
    assert type(e) is float and e == pytest.approx(0.25)
    assert type(yaw_error(np.float64(0.1), np.float64(0.0), np.int64(2))) is float
    arr = yaw_error(np.array([0.1, 3.0, -3.0]), 0.0, 1)
    assert isinstance(arr, np.ndarray) and arr.dtype == np.float64 and arr.shape == (3,)
    np.testing.assert_allclose(arr, [0.1, 3.0, 3.0], atol=1e-12)
    assert yaw_error(3.5, 0.0, 1) == pytest.approx(TWO_PI - 3.5)
    rng = np.random.default_rng(5)
    yaw, target = rng.uniform(-10, 10, 500), rng.uniform(-10, 10, 500)
    for k in (1, 2, 3, 4, 6):
        err = yaw_error(yaw, target, k)
        assert np.all(err >= 0.0) and np.all(err <= PI / k + 1e-12)
        # the error is the distance to the nearest equivalent turn
        d = np.abs(np.remainder(yaw - target + PI / k, TWO_PI / k) - PI / k)
        np.testing.assert_allclose(err, d, atol=1e-9)
    np.testing.assert_array_equal(yaw_error(yaw[:3], target[:3], np.array([0, 0, 0])), [0.0] * 3)
    mixed = yaw_error(np.array([0.3, 0.3]), 0.0, np.array([0, 1]))
    np.testing.assert_allclose(mixed, [0.0, 0.3])


def test_wrap_angle_returns_a_float_for_scalars_and_an_array_of_the_same_shape() -> None:
    """A scalar comes back a float, unchanged when already in range; arrays keep their shape
    and dtype float64 (ints are wrapped as floats) under both conventions."""
    for a in (0.5, -3.0, 3.1):
        assert wrap_angle(a) == a and wrap_angle(a, include_pi=True) == a
    assert type(wrap_angle(np.int64(7))) is float and wrap_angle(np.int64(7)) == pytest.approx(
        7 - TWO_PI
    )
    grid = np.arange(12, dtype=np.int64).reshape(3, 4)
    for include_pi in (False, True):
        w = wrap_angle(grid, include_pi=include_pi)
        assert isinstance(w, np.ndarray) and w.shape == (3, 4) and w.dtype == np.float64
        np.testing.assert_allclose(np.cos(w), np.cos(grid), atol=1e-12)
    assert wrap_angles([PI], include_pi=True)[0] == PI and wrap_angles([PI])[0] == -PI
    edges = np.array([[PI, -PI], [3 * PI, 0.5]])
    np.testing.assert_array_equal(wrap_angle(edges, include_pi=True), [[PI, PI], [PI, 0.5]])
    np.testing.assert_array_equal(wrap_angle(edges), [[-PI, -PI], [-PI, 0.5]])
    single = wrap_angles(np.array([0.25, 7.0], dtype=np.float32))  # computed in float64
    assert single.dtype == np.float64 and single[0] == 0.25
    assert single[1] == np.remainder(7.0 + PI, TWO_PI) - PI
    assert wrap_angles(-PI, include_pi=True).shape == ()


def test_rotate_xy_turns_counter_clockwise_rows_and_vectors() -> None:
    """A quarter turn takes x to y and y to -x, row by row for (n, 2) input."""
    np.testing.assert_allclose(rotate_xy([1.0, 0.0], PI / 2), [0.0, 1.0], atol=1e-15)
    pts = rotate_xy([[1.0, 0.0], [0.0, 1.0], [2.0, 2.0]], PI / 2)
    np.testing.assert_allclose(pts, [[0.0, 1.0], [-1.0, 0.0], [-2.0, 2.0]], atol=1e-15)
    np.testing.assert_allclose(
        rotate_xy([[3.0, 4.0]], -0.7), rotate_xy([3.0, 4.0], -0.7)[None], atol=0
    )


def test_yaw_from_quat_of_general_rotations_and_batches() -> None:
    """The yaw of a rotation that also tilts (x, y components) is its x axis' heading: the
    formula's mixed terms matter there, not for pure yaw quaternions."""
    rng = np.random.default_rng(9)
    q = rng.normal(size=(50, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    w, x, y, z = q.T
    # rotation matrix column 0 (the x axis) of each quaternion
    r00 = 1 - 2 * (y**2 + z**2)
    r10 = 2 * (x * y + w * z)
    np.testing.assert_allclose(yaw_from_quat(q), np.arctan2(r10, r00), atol=1e-12)
    assert yaw_from_quat(q).shape == (50,)
    assert yaw_from_quat(q.reshape(5, 10, 4)).shape == (5, 10)
    mats = [np.array([[r00[i], 0, 0], [r10[i], 0, 0], [0, 0, 1.0]]) for i in range(3)]
    for i, m in enumerate(mats):
        assert yaw_from_matrix(m) == pytest.approx(math.atan2(r10[i], r00[i]), abs=1e-12)
    half = quat_from_yaw(np.array([[0.0, PI]]))
    assert half.shape == (1, 2, 4)
    np.testing.assert_allclose(half[0, 1], [0.0, 0.0, 0.0, 1.0], atol=1e-15)


def test_tolerances_in_both_units() -> None:
    """The placement tolerance is 1.5 mm and 2 deg, the made tile's deviation 0.2 mm; the
    metre forms are the same lengths (a slip of units moves every benchmark's verdict)."""
    assert PLACEMENT_POSITION_TOLERANCE_MM == 1.5 and PLACEMENT_YAW_TOLERANCE_DEG == 2.0
    assert MADE_TILE_DEVIATION_MM == 0.2
    assert PLACEMENT_POSITION_TOLERANCE_M == pytest.approx(0.0015, abs=1e-15)
    assert MADE_TILE_DEVIATION_M == pytest.approx(0.0002, abs=1e-15)


def test_yaw_conversions_compute_in_double_precision() -> None:
    """Single-precision input is converted to double first: a quaternion or a yaw given as
    float32 gives the double-precision result of the same numbers (computing in float32 loses
    about 1e-7 rad, a hundredth of the placement tolerance's margin)."""
    yaw32 = np.array([0.3, -2.9, 1.7], dtype=np.float32)
    q = quat_from_yaw(yaw32)
    assert q.dtype == np.float64
    np.testing.assert_array_equal(q, quat_from_yaw(yaw32.astype(np.float64)))
    back = yaw_from_quat(q.astype(np.float32))
    assert back.dtype == np.float64
    np.testing.assert_array_equal(back, yaw_from_quat(q.astype(np.float32).astype(np.float64)))
