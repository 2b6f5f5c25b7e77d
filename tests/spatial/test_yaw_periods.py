"""`yaw_periods` and `yaw_error`'s precomputed ``period``: the same errors, bit for bit."""

from __future__ import annotations

import math

import numpy as np

from spatial.angles import symmetry_period, yaw_error, yaw_periods


def test_periods_are_the_symmetry_periods_with_one_for_round_shapes() -> None:
    orders = np.array([0, 1, 2, 3, 4, 6])
    got = yaw_periods(orders)
    assert got[0] == 1.0
    assert got[1:].tolist() == [symmetry_period(int(k)) for k in orders[1:]]
    assert math.isclose(got[4], math.pi / 2)


def test_precomputed_periods_give_the_same_errors_bit_for_bit() -> None:
    rng = np.random.default_rng(7)
    orders = rng.integers(0, 7, 500)
    yaw = rng.uniform(-10, 10, 500)
    target = rng.uniform(-4, 4, 500)
    plain = yaw_error(yaw, target, orders)
    given = yaw_error(yaw, target, orders, yaw_periods(orders))
    assert isinstance(given, np.ndarray)
    assert np.array_equal(plain, given)
    assert np.all(given[orders == 0] == 0.0)
    assert np.all(given <= math.pi / np.maximum(orders, 1) + 1e-12)
