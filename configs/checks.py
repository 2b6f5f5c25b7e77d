"""Declarative checks of configuration fields: each field states its allowed values once.

A frozen configuration dataclass declares a field's default and its rule together::

    @dataclass(frozen=True)
    class Motion:
        speed: float = checked(0.5, gt=0)                  # [m/s]
        mode: str = checked("fast", choices=("fast", "safe"))
        z_range: tuple[float, float] = checked((0.0, 0.3), length=2, ge=0, increasing=True)

        def __post_init__(self) -> None:
            check_fields(self, MotionError)

`check_fields` walks the fields in declaration order and raises the given error type for the
first value outside its rule, with a message naming the field, the rule and the value
(``speed must be > 0, got -1.0``; ``unknown mode 'slow'; allowed: ['fast', 'safe']``). A rule
on a sequence applies to every element. Types are `configs.check_field_types`'s job; these
rules are the ranges, lengths and choices.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Collection
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
    """

    gt: float | None = None
    ge: float | None = None
    lt: float | None = None
    le: float | None = None
    choices: Collection[Any] | None = None
    length: int | None = None
    increasing: bool = False
    integer: bool = False

    def problem(self, name: str, value: Any) -> str | None:
        """Why ``value`` breaks the rule (a message naming ``name``), or None."""
        if self.choices is not None:
            if value not in self.choices:
                return f"unknown {name} {value!r}; allowed: {list(self.choices)}"
            return None
        values = _elements(value)
        if self.length is not None and len(values) != self.length:
            return f"{name} must have {self.length} values, got {value!r}"
        if self.increasing and any(b <= a for a, b in zip(values, values[1:], strict=False)):
            return f"{name} must be increasing, got {value!r}"
        kind = "an int " if self.integer else ""
        if self.integer and not all(isinstance(v, int) and not isinstance(v, bool) for v in values):
            bounds = " ".join(f"{op} {_number(b)}" for op, b in self._bounds())
            return f"{name} must be an int {bounds}, got {value!r}".replace(" ,", ",")
        for bound, op, ok in (
            (self.gt, ">", lambda v, b: v > b),
            (self.ge, ">=", lambda v, b: v >= b),
            (self.lt, "<", lambda v, b: v < b),
            (self.le, "<=", lambda v, b: v <= b),
        ):
            if bound is not None and not all(ok(v, bound) for v in values):
                return f"{name} must be {kind}{op} {_number(bound)}, got {value!r}"
        return None

    def _bounds(self) -> list[tuple[str, float]]:
        pairs = ((">", self.gt), (">=", self.ge), ("<", self.lt), ("<=", self.le))
        return [(op, b) for op, b in pairs if b is not None]


def _elements(value: Any) -> list[Any]:
    if isinstance(value, tuple | list):
        return list(value)
    return [value]


def _number(bound: float) -> str:
    return str(int(bound)) if float(bound).is_integer() and math.isfinite(bound) else repr(bound)


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
) -> Any:
    """A dataclass field with ``default`` and the `Rule` its values must keep."""
    rule = Rule(gt, ge, lt, le, choices, length, increasing, integer)
    return dataclasses.field(default=default, metadata={CHECK_KEY: rule})


def check_fields(obj: Any, error: type[Exception], prefix: str = "") -> None:
    """Raise ``error`` for the first field of ``obj`` whose value breaks its `Rule`.

    Args:
        obj: A dataclass instance whose fields were declared with `checked`.
        error: The exception type to raise (the package's configuration error).
        prefix: Put before the message (e.g. ``"run: "`` for a section of a file).
    """
    for f in dataclasses.fields(obj):
        rule = f.metadata.get(CHECK_KEY)
        if rule is not None:
            problem = rule.problem(f.name, getattr(obj, f.name))
            if problem is not None:
                raise error(prefix + problem)


__all__ = ["CHECK_KEY", "Rule", "check_fields", "checked"]
