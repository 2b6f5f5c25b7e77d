"""configs.checks: a field's rule, declared with its default, refuses what it does not allow."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import pytest

from configs.checks import Rule, check_fields, checked


class MotionError(ValueError):
    """The error type a package would raise for its configuration."""


@dataclass(frozen=True)
class Motion:
    speed: float = checked(0.5, gt=0)
    share: float = checked(0.3, ge=0, le=1)
    angle_deg: float = checked(10.0, ge=0, lt=90)
    mode: str = checked("fast", choices=("fast", "safe"))
    camera: str | None = checked(None, choices=(None, "top", "side"))
    repeats: int = checked(1, ge=1, integer=True)
    z_range: tuple[float, ...] = checked((0.0, 0.3), length=2, ge=0, increasing=True)
    offset: float | None = checked(None, ge=0, optional=True)
    label: str = "free"

    def __post_init__(self) -> None:
        check_fields(self, MotionError)


def test_defaults_and_values_inside_every_rule_are_kept() -> None:
    m = Motion(share=1.0, angle_deg=0.0, mode="safe", camera="side", repeats=3, offset=2.5)
    assert (m.share, m.angle_deg, m.mode, m.camera, m.repeats, m.offset) == (
        1.0,
        0.0,
        "safe",
        "side",
        3,
        2.5,
    )
    assert Motion().z_range == (0.0, 0.3)


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"speed": 0.0}, "speed must be > 0, got 0.0"),
        ({"speed": -1.5}, "speed must be > 0, got -1.5"),
        ({"speed": math.inf}, "speed must be a finite number > 0, got inf"),
        ({"speed": math.nan}, "speed must be a finite number > 0, got nan"),
        ({"speed": True}, "speed must be a finite number > 0, got True"),
        ({"speed": "fast"}, "speed must be a finite number > 0, got 'fast'"),
        ({"share": 1.5}, "share must be in [0, 1], got 1.5"),
        ({"share": -0.1}, "share must be in [0, 1], got -0.1"),
        ({"angle_deg": 90.0}, "angle_deg must be in [0, 90), got 90.0"),
        ({"mode": "slow"}, "unknown mode 'slow'; allowed: 'fast', 'safe'"),
        ({"camera": "back"}, "unknown camera 'back'; allowed: None, 'top', 'side'"),
        ({"repeats": 0}, "repeats must be an int >= 1, got 0"),
        ({"repeats": 2.0}, "repeats must be an int >= 1, got 2.0"),
        ({"z_range": (0.0,)}, "z_range needs 2 values, got (0.0,)"),
        ({"z_range": (-0.1, 0.3)}, "z_range must be >= 0, got (-0.1, 0.3)"),
        ({"z_range": (0.3, 0.1)}, "z_range must be increasing, got (0.3, 0.1)"),
        ({"offset": -1.0}, "offset must be >= 0, got -1.0"),
    ],
)
def test_a_value_outside_its_rule_raises_the_given_error_naming_field_rule_and_value(
    changes, message
) -> None:
    with pytest.raises(MotionError, match=f"^{re.escape(message)}$"):
        Motion(**changes)


def test_the_first_failing_field_in_declaration_order_is_named() -> None:
    with pytest.raises(MotionError, match="^speed "):
        Motion(repeats=0, speed=-1.0, mode="slow")
    with pytest.raises(MotionError, match="^unknown mode"):
        Motion(repeats=0, mode="slow")


def test_prefix_and_class_qualified_names() -> None:
    m = Motion()
    object.__setattr__(m, "share", 2.0)
    with pytest.raises(KeyError, match=re.escape("run: share must be in [0, 1], got 2.0")):
        check_fields(m, KeyError, prefix="run: ")
    with pytest.raises(MotionError, match=re.escape("Motion.share must be in [0, 1]")):
        check_fields(m, MotionError, qualify=True)


def test_unchecked_fields_are_left_alone() -> None:
    assert Motion(label="").label == ""


def test_describe_puts_the_rule_in_words() -> None:
    assert Rule(ge=0).describe() == ">= 0"
    assert Rule(gt=0, le=1).describe() == "in (0, 1]"
    assert Rule(ge=2, le=256, integer=True).describe() == "an int in [2, 256]"
    assert Rule(lt=0.5).describe() == "< 0.5"
    assert Rule(gt=0, le=1e4).describe() == "in (0, 10000]"
    assert Rule(gt=0, le=1e100).describe() == "in (0, 1e+100]"
    assert Rule(integer=True).describe() == "an int"
    assert Rule(finite=True).describe() == "a finite number"


BUILT: list[int] = []


def _home() -> tuple[float, ...]:
    BUILT.append(1)
    return (0.0, 1.5)


@dataclass(frozen=True)
class Lens:
    k1: float = checked(0.0, finite=True)
    home: tuple[float, ...] = checked(factory=_home, length=2, finite=True)
    steps: int = checked(3, integer=True)

    def __post_init__(self) -> None:
        check_fields(self, MotionError, qualify=True)


def test_finite_only_factory_defaults_and_int_only_rules() -> None:
    before = len(BUILT)
    assert Lens().home == (0.0, 1.5) and Lens().home == (0.0, 1.5)
    assert len(BUILT) == before + 2  # the default is built per instance
    assert Lens(k1=-3.0).k1 == -3.0  # no bound: any finite number
    with pytest.raises(MotionError, match=re.escape("Lens.k1 must be a finite number, got nan")):
        Lens(k1=math.nan)
    with pytest.raises(MotionError, match=re.escape("Lens.home must be a finite number, got")):
        Lens(home=(0.0, math.inf))
    with pytest.raises(MotionError, match=re.escape("Lens.home needs 2 values, got (0.0,)")):
        Lens(home=(0.0,))
    with pytest.raises(MotionError, match=re.escape("Lens.steps must be an int, got 2.5")):
        Lens(steps=2.5)  # type: ignore[arg-type]
