"""Declarative checks of configuration fields: each field states its allowed values once.

A frozen configuration dataclass declares a field's default and its rule together::

    @dataclass(frozen=True)
    class Motion:
        speed: float = checked(0.5, gt=0)                  # [m/s]
        share: float = checked(0.3, ge=0, le=1)            # dimensionless
        mode: str = checked("fast", choices=("fast", "safe"))
        z_range: tuple[float, float] = checked((0.0, 0.3), length=2, ge=0, increasing=True)

        def __post_init__(self) -> None:
            check_fields(self, MotionError)

`check_fields` walks the fields in declaration order and raises the given error type for the
first value outside its rule, with a message naming the field, the rule and the value
(``speed must be > 0, got -1.0``; ``share must be in [0, 1], got 1.5``; ``unknown mode
'slow'; allowed: 'fast', 'safe'``). A rule on a sequence applies to every element. A bound
also asks for a finite real number (not a bool). Types are `configs.check_field_types`'s job;
these rules are the ranges, lengths and choices. Rules between fields (a low below a high)
stay as code in ``__post_init__``.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
from collections.abc import Callable, Collection
from dataclasses import dataclass
from typing import Any

CHECK_KEY = "check"
"""The key of a field's `Rule` in its dataclass field metadata."""


@dataclass(frozen=True)
class Rule:
    """What values a field allows (None: no such bound).

    Attributes:
        gt: Each value must be greater than this.
        ge: ... at least this.
        lt: ... less than this.
        le: ... at most this.
        choices: The value must be one of these (None allowed only when listed).
        length: A sequence value must have this many elements.
        increasing: A sequence value must be strictly increasing.
        integer: Each value must be an int (not a bool).
        finite: Each value must be a finite number (implied by any bound).
        optional: None is allowed besides the values the rule allows.
    """

    gt: float | None = None
    ge: float | None = None
    lt: float | None = None
    le: float | None = None
    choices: Collection[Any] | None = None
    length: int | None = None
    increasing: bool = False
    integer: bool = False
    finite: bool = False
    optional: bool = False

    def problem(self, name: str, value: Any) -> str | None:
        """Why ``value`` breaks the rule (a message naming ``name``), or None."""
        if value is None and self.optional:
            return None
        if self.choices is not None:
            if value not in self.choices:
                allowed = ", ".join(repr(c) for c in self.choices)
                return f"unknown {name} {value!r}; allowed: {allowed}"
            return None
        values = _elements(value)
        if self.length is not None and len(values) != self.length:
            return f"{name} needs {self.length} values, got {value!r}"
        if self.integer and not all(isinstance(v, int) and not isinstance(v, bool) for v in values):
            return self._broken(name, value)
        if self._bounded() and not all(self._within(v) for v in values):
            return self._broken(name, value)
        if self.increasing and any(b <= a for a, b in zip(values, values[1:], strict=False)):
            return f"{name} must be increasing, got {value!r}"
        return None

    def describe(self) -> str:
        """The allowed values in words (``>= 0``, ``in (0, 1]``, ``an int >= 1``)."""
        lower = (">", self.gt) if self.gt is not None else (">=", self.ge)
        upper = ("<", self.lt) if self.lt is not None else ("<=", self.le)
        kind = "an int " if self.integer else ""
        if lower[1] is not None and upper[1] is not None:
            left = "(" if lower[0] == ">" else "["
            right = ")" if upper[0] == "<" else "]"
            return f"{kind}in {left}{_number(lower[1])}, {_number(upper[1])}{right}"
        bounds = [f"{op} {_number(b)}" for op, b in (lower, upper) if b is not None]
        if not bounds:
            return "an int" if self.integer else "a finite number"
        return kind + " ".join(bounds)

    def _bounded(self) -> bool:
        return self.finite or any(b is not None for b in (self.gt, self.ge, self.lt, self.le))

    def _within(self, value: Any) -> bool:
        if not _finite_number(value):
            return False
        v = float(value)
        return (
            (self.gt is None or v > self.gt)
            and (self.ge is None or v >= self.ge)
            and (self.lt is None or v < self.lt)
            and (self.le is None or v <= self.le)
        )

    def _broken(self, name: str, value: Any) -> str:
        words = self.describe()
        plain = all(_finite_number(v) for v in _elements(value))
        if not (plain or self.integer or words.startswith("a finite")):
            words = f"a finite number {words}"
        return f"{name} must be {words}, got {value!r}"


def _finite_number(value: Any) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool) and math.isfinite(value)


def _elements(value: Any) -> list[Any]:
    if isinstance(value, tuple | list):
        return list(value)
    return [value]


def _number(bound: float) -> str:
    whole = float(bound).is_integer() and abs(bound) < 1e6  # noqa: PLR2004 - beyond: 1e+15
    return str(int(bound)) if whole else repr(float(bound))


def checked(
    default: Any = dataclasses.MISSING,
    *,
    gt: float | None = None,
    ge: float | None = None,
    lt: float | None = None,
    le: float | None = None,
    choices: Collection[Any] | None = None,
    length: int | None = None,
    increasing: bool = False,
    integer: bool = False,
    finite: bool = False,
    optional: bool = False,
    factory: Callable[[], Any] | None = None,
) -> Any:
    """A dataclass field with ``default`` (or ``factory``) and the `Rule` its values must keep."""
    rule = Rule(gt, ge, lt, le, choices, length, increasing, integer, finite, optional)
    if factory is not None:
        return dataclasses.field(default_factory=factory, metadata={CHECK_KEY: rule})
    return dataclasses.field(default=default, metadata={CHECK_KEY: rule})


def check_fields(
    obj: Any, error: type[Exception], prefix: str = "", *, qualify: bool = False
) -> None:
    """Raise ``error`` for the first field of ``obj`` whose value breaks its `Rule`.

    Args:
        obj: A dataclass instance whose fields were declared with `checked`.
        error: The exception type to raise (the package's configuration error).
        prefix: Put before the message (e.g. ``"run: "`` for a section of a file).
        qualify: Name fields with their class (``InputBeltConfig.speed``), for sections
            whose field names repeat (each belt has a ``length``).
    """
    owner = f"{type(obj).__name__}." if qualify else ""
    for f in dataclasses.fields(obj):
        rule = f.metadata.get(CHECK_KEY)
        if rule is not None:
            problem = rule.problem(owner + f.name, getattr(obj, f.name))
            if problem is not None:
                raise error(prefix + problem)


__all__ = ["CHECK_KEY", "Rule", "check_fields", "checked"]
