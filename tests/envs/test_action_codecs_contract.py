"""Contract tests of the action codecs (`envs.task_spec`): `Area`, `PickPlaceCommand`,
`PickPlaceCodec` (both layouts) and `DiscreteCodec`, on hand-made areas with binary-exact
corners so each expected value is exact.

Each test names the bug it guards against; they need no cell and run in milliseconds.
"""

from __future__ import annotations

import math
import re
from decimal import Decimal
from fractions import Fraction

import numpy as np
import pytest

from envs.task_spec import (
    RANGE_SLACK,
    ActionError,
    Area,
    DiscreteCodec,
    PickPlaceCodec,
    PickPlaceCommand,
    rotation_step,
)

PICK = Area(np.array([0.25, -0.5]), np.array([0.75, 0.5]), 0.5, 0.5078125)
"""A pick area 0.5 m x 1 m centred on (0.5, 0) [m]."""
PLACE = Area(np.array([-1.0, 0.0]), np.array([0.0, 0.25]), 0.25, 0.2578125)
"""A place area 1 m x 0.25 m centred on (-0.5, 0.125) [m]."""


def test_area_maps_its_corners_centre_and_outside_points_linearly() -> None:
    """to_unit / from_unit: corners at -1 and +1, the centre at 0, outside points outside.

    Guards against a wrong scale or offset (``2 *`` dropped, ``- 1`` lost, lo and hi swapped).
    """
    np.testing.assert_array_equal(PICK.centre, [0.5, 0.0])
    np.testing.assert_array_equal(PICK.to_unit(PICK.lo), [-1.0, -1.0])
    np.testing.assert_array_equal(PICK.to_unit(PICK.hi), [1.0, 1.0])
    np.testing.assert_array_equal(PICK.to_unit([0.5, 0.0]), [0.0, 0.0])
    np.testing.assert_array_equal(PICK.to_unit([1.0, -1.0]), [2.0, -2.0])  # outside maps outside
    np.testing.assert_array_equal(PICK.to_unit([0.375, 0.25]), [-0.5, 0.5])
    np.testing.assert_array_equal(PICK.from_unit([-1.0, -1.0]), PICK.lo)
    np.testing.assert_array_equal(PICK.from_unit([1.0, 1.0]), PICK.hi)
    np.testing.assert_array_equal(PICK.from_unit([-0.5, 0.5]), [0.375, 0.25])
    np.testing.assert_array_equal(PLACE.from_unit([0.0, 0.0]), PLACE.centre)
    np.testing.assert_array_equal(PLACE.from_unit([2.0, -3.0]), [0.5, -0.25])
    rows = np.array([[0.25, 0.5], [0.75, -0.5]])  # several points at once, one per row
    np.testing.assert_array_equal(PICK.to_unit(rows), [[-1.0, 1.0], [1.0, -1.0]])
    np.testing.assert_array_equal(PICK.from_unit(PICK.to_unit(rows)), rows)


@pytest.mark.parametrize("number", [Fraction, Decimal])
def test_area_converts_any_real_numbers_to_float(number: type) -> None:
    """Coordinates given as exact numbers (fractions, decimals read from a file) come back as
    float64 arrays.

    Guards against dropping the float conversion: numpy then keeps Python objects (Decimal
    cannot be mixed with float at all, Fraction gives an object array).
    """
    u = PICK.to_unit([number("0.375"), number("0.25")])
    assert u.dtype == np.float64
    np.testing.assert_array_equal(u, [-0.5, 0.5])
    xy = PICK.from_unit([number("-0.5"), number("0.5")])
    assert xy.dtype == np.float64
    np.testing.assert_array_equal(xy, [0.375, 0.25])


def test_between_yaws_wraps_the_turn_and_keeps_the_points() -> None:
    """The turn from yaw 3 to yaw -3 is 2 pi - 6 (the short way), points and pick yaw kept.

    Guards against an unwrapped turn (-6) or the yaws' order swapped.
    """
    cmd = PickPlaceCommand.between_yaws((0.25, 0.5), 3.0, (-0.75, 0.125), -3.0)
    assert cmd == PickPlaceCommand((0.25, 0.5), 3.0, (-0.75, 0.125), 2 * math.pi - 6.0)
    assert PickPlaceCommand.between_yaws((0, 0), 0.5, (0, 0), 1.0).rotation == 0.5


def test_decode_with_the_pick_yaw_entry_maps_each_entry() -> None:
    """Box(6): pick (x, y) over the pick area, yaw / pi, place (x, y) over the place area,
    rotation / pi.

    Guards against entries read from the wrong index or an area mixed up.
    """
    codec = PickPlaceCodec(PICK, PLACE)
    assert codec.size == 6  # noqa: PLR2004
    cmd = codec.decode(np.array([1.0, -0.5, 0.5, -1.0, 1.0, -0.25]))
    assert cmd == PickPlaceCommand((0.75, -0.25), math.pi / 2, (-1.0, 0.25), -math.pi / 4)
    for v in (*cmd.pick_xy, cmd.pick_yaw, *cmd.place_xy, cmd.rotation):
        assert type(v) is float


def test_decode_without_the_pick_yaw_entry_reads_five_entries() -> None:
    """Box(5) (``-v1``): pick (x, y), place (x, y), rotation / pi; pick yaw 0.

    Guards against the missing yaw inserted at the wrong place (place x read as the yaw) or
    not at all (the place read one entry early, the rotation out of range).
    """
    codec = PickPlaceCodec(PICK, PLACE, pick_yaw=False)
    assert codec.size == 5  # noqa: PLR2004
    action = np.array([1.0, -0.5, -1.0, 1.0, -0.25])
    cmd = codec.decode(action)
    assert cmd == PickPlaceCommand((0.75, -0.25), 0.0, (-1.0, 0.25), -math.pi / 4)
    np.testing.assert_array_equal(action, [1.0, -0.5, -1.0, 1.0, -0.25])  # input untouched
    turned = codec.decode([0.0, 0.0, 0.5, -0.5, 0.75])
    assert turned == PickPlaceCommand((0.5, 0.0), 0.0, (-0.25, 0.0625), 0.75 * math.pi)


def test_decode_computes_in_double_precision() -> None:
    """A float32 action (what the Box space holds) decodes in float64: the yaw and the rotation
    are exactly float64(entry) * pi.

    Guards against decoding in the action's own float32 precision (a float32 product rounds
    the angle by up to ~1e-7 rad), and against exact numbers left as objects.
    """
    codec = PickPlaceCodec(PICK, PLACE)
    a = np.array([0.1, 0.2, 0.1, -0.3, 0.7, 0.3], np.float32)
    cmd = codec.decode(a)
    assert cmd.pick_yaw == float(np.float64(a[2]) * math.pi)
    assert cmd.rotation == float(np.float64(a[5]) * math.pi)
    exact = codec.decode([Decimal(1), Decimal("-0.5"), Decimal("0.5"), 0, 0, Decimal("0.25")])
    assert exact == PickPlaceCommand((0.75, -0.25), math.pi / 2, (-0.5, 0.125), math.pi / 4)
    short = PickPlaceCodec(PICK, PLACE, pick_yaw=False).decode(
        np.array([0.1, 0.2, -0.3, 0.7, 0.3], np.float32)
    )
    assert short.rotation == float(np.float64(np.float32(0.3)) * math.pi)


def test_encode_maps_each_field_and_wraps_the_angles() -> None:
    """Box(6): the inverse of decode; yaw and rotation wrapped into [-pi, pi) then / pi; float32.

    Guards against an unwrapped angle (3 pi / 2 -> 1.5, clipped to 1), a field in the wrong
    entry, or a float64 action.
    """
    codec = PickPlaceCodec(PICK, PLACE)
    a = codec.encode(PickPlaceCommand((0.75, -0.25), 1.5 * math.pi, (-1.0, 0.25), -1.5 * math.pi))
    assert a.dtype == np.float32 and a.shape == (6,)
    np.testing.assert_allclose(a, [1.0, -0.5, -0.5, -1.0, 1.0, 0.5], atol=1e-7)
    b = codec.encode(
        PickPlaceCommand((0.375, 0.25), -0.25 * math.pi, (-0.5, 0.125), 0.75 * math.pi)
    )
    np.testing.assert_allclose(b, [-0.5, 0.5, -0.25, 0.0, 0.0, 0.75], atol=1e-7)
    back = codec.decode(b)
    np.testing.assert_allclose(back.pick_xy, (0.375, 0.25), atol=1e-7)
    np.testing.assert_allclose(back.place_xy, (-0.5, 0.125), atol=1e-7)


def test_encode_without_the_pick_yaw_entry_drops_it() -> None:
    """Box(5): pick (x, y), place (x, y), rotation / pi; the command's pick yaw is dropped.

    Guards against the yaw kept (six entries) or another entry dropped.
    """
    codec = PickPlaceCodec(PICK, PLACE, pick_yaw=False)
    cmd = PickPlaceCommand((0.375, 0.25), 2.0, (-0.5, 0.125), 0.75 * math.pi)
    a = codec.encode(cmd)
    assert a.dtype == np.float32 and a.shape == (5,)
    np.testing.assert_allclose(a, [-0.5, 0.5, 0.0, 0.0, 0.75], atol=1e-7)
    assert codec.decode(a).pick_yaw == 0.0


def test_encode_allows_float_rounding_past_an_edge_and_clips_it() -> None:
    """A point up to RANGE_SLACK (in unit terms) past an area's edge encodes as exactly +-1.

    Guards against the slack dropped (an edge point rounded outward refused) or the result
    left unclipped.
    """
    codec = PickPlaceCodec(PICK, PLACE)
    half = RANGE_SLACK / 2  # in unit terms; the pick area's x half-width is 0.25 m
    cmd = PickPlaceCommand(
        (0.75 + 0.25 * half, -0.5 - 0.5 * half), 0.0, (0.0 + 0.5 * half, 0.0), math.pi
    )
    a = codec.encode(cmd)
    assert a.tolist() == [1.0, -1.0, 0.0, 1.0, -1.0, -1.0]
    assert np.all(np.abs(a) <= 1.0)


def test_encode_accepts_a_point_exactly_at_the_slack() -> None:
    """A point whose unit coordinate is exactly -(1 + RANGE_SLACK) is still inside (the check is
    strict), in either area.

    Guards against ``>=`` for ``>`` in the pick or the place check.
    """
    edge = -(1 + RANGE_SLACK)
    x = float(PICK.from_unit([edge, 0.0])[0])
    y = float(PLACE.from_unit([0.0, edge])[1])
    assert PICK.to_unit([x, 0.0])[0] == edge  # exactly on the edge in float64
    assert PLACE.to_unit([-0.5, y])[1] == edge
    codec = PickPlaceCodec(PICK, PLACE)
    a = codec.encode(PickPlaceCommand((x, 0.0), 0.0, (-0.5, y), 0.0))
    assert a.tolist() == [-1.0, 0.0, 0.0, 0.0, -1.0, 0.0]


@pytest.mark.parametrize(
    ("pick", "place"),
    [
        ((0.75 + 0.25 * 2 * RANGE_SLACK, 0.0), (-0.5, 0.125)),  # pick x past hi
        ((0.5, -0.5 - 0.5 * 2 * RANGE_SLACK), (-0.5, 0.125)),  # pick y below lo
        ((0.5, 0.0), (-1.0 - 0.5 * 2 * RANGE_SLACK, 0.125)),  # place x below lo
        ((0.5, 0.0), (-0.5, 0.25 + 0.125 * 2 * RANGE_SLACK)),  # place y past hi
    ],
)
def test_encode_refuses_a_point_past_the_slack(
    pick: tuple[float, float], place: tuple[float, float]
) -> None:
    """Twice the slack past any edge of either area is an ActionError.

    Guards against one of the four checks (pick / place, low / high side) lost.
    """
    with pytest.raises(ActionError, match="outside the areas"):
        PickPlaceCodec(PICK, PLACE).encode(PickPlaceCommand(pick, 0.0, place, 0.0))


def test_encode_error_names_both_points_and_both_areas() -> None:
    """The message gives both points rounded to 0.1 mm and both areas' corners in metres.

    Guards against a wrong rounding of either point or an area's corner missing.
    """
    cmd = PickPlaceCommand((0.123456, 0.3333333), 0.0, (-0.98765432, 0.4444444), 0.0)
    msg = (
        "pick [0.1235, 0.3333] or place [-0.9877, 0.4444] outside the areas: "
        "pick [0.25, -0.5]..[0.75, 0.5], place [-1.0, 0.0]..[0.0, 0.25] [m]"
    )
    with pytest.raises(ActionError, match=f"^{re.escape(msg)}$"):
        PickPlaceCodec(PICK, PLACE).encode(cmd)


def test_rotation_step_is_a_full_turn_over_the_bins() -> None:
    """``2 pi / bins``. Guards against a half turn or the bins multiplied."""
    assert rotation_step(8) == math.pi / 4
    assert rotation_step(1) == 2 * math.pi
    assert DiscreteCodec(2, 3, 6, "tile").rotation_step == math.pi / 3


def test_discrete_codec_sizes_turns_and_nearest_rotation() -> None:
    """nvec is (tiles, slots, bins); index r turns r steps; the nearest index wraps round.

    Guards against a size in the wrong place or a turn that is not r * 2 pi / bins.
    """
    codec = DiscreteCodec(3, 4, 8, "slot")
    assert codec.nvec == (3, 4, 8)
    assert codec.turn(0) == 0.0
    assert codec.turn(3) == pytest.approx(0.75 * math.pi, abs=1e-15)
    assert codec.turn(8) == pytest.approx(2 * math.pi, abs=1e-15)
    assert codec.nearest_rotation(0.75 * math.pi) == 3  # noqa: PLR2004
    assert codec.nearest_rotation(0.8 * math.pi) == 3  # noqa: PLR2004
    assert codec.nearest_rotation(-0.25 * math.pi) == 7  # noqa: PLR2004
    assert codec.nearest_rotation(2 * math.pi + 0.1) == 0
    assert codec.nearest_rotation(1.9 * math.pi) == 0


def test_flat_is_row_major_with_the_rotation_fastest() -> None:
    """flat((t, s, r)) = (t * slots + s) * bins + r; unflat is its inverse, int64 (3,).

    Guards against another order, the wrong sizes or a lost argument.
    """
    codec = DiscreteCodec(3, 4, 8, "tile")
    assert codec.flat((0, 0, 0)) == 0
    assert codec.flat((0, 0, 1)) == 1
    assert codec.flat((0, 1, 0)) == 8  # noqa: PLR2004
    assert codec.flat((1, 2, 3)) == 51  # noqa: PLR2004
    assert codec.flat(np.array([2, 3, 7], np.int64)) == 95  # noqa: PLR2004
    assert codec.flat(np.array([1.0, 2.0, 3.0])) == 51  # noqa: PLR2004 - float entries
    assert type(codec.flat((1, 2, 3))) is int
    u = codec.unflat(51)
    assert u.dtype == np.int64 and u.shape == (3,)
    assert u.tolist() == [1, 2, 3]
    assert codec.unflat(np.int64(95)).tolist() == [2, 3, 7]
    for i in range(3 * 4 * 8):
        assert codec.flat(codec.unflat(i)) == i
    with pytest.raises(ValueError, match="invalid entry"):
        codec.flat((3, 0, 0))
    with pytest.raises(ValueError, match="out of bounds"):
        codec.unflat(96)
