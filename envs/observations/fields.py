"""What each entry of the ``state`` observation's vectors means: the published field maps.

``robot`` is one vector; ``tiles`` and ``slots`` are flat vectors of rows, one row per agent
tile / slot index (row ``i`` is ``tiles[i * TILE_DIM:(i + 1) * TILE_DIM]``). Each map names a
field and its column slice in a row, in row order. Learned code reads these maps (through
`envs.task_spec.TaskSpec.state_fields` or this module), never column numbers of its own.

- ``robot`` (`ROBOT_FIELDS`): joint positions [rad] (6), joint velocities [rad/s] (6), tool
  position [m] (3), tool yaw as (cos, sin) (2), vacuum on (1), tile held (1).
- ``tiles`` rows (`TILE_FIELDS`): position x, y, z [m], yaw as (cos, sin), class index, present
  (on the belts and not lost, 0/1).
- ``slots`` rows (`SLOT_FIELDS`): position x, y [m], yaw as (cos, sin), class index, filled
  correctly (0/1).

The ``objects`` observation's rows have their own map (`envs.observations.objects.object_fields`).
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType

FieldMap = Mapping[str, slice]
"""Field name -> column slice of a row."""


def _layout(*fields: tuple[str, int]) -> FieldMap:
    out: dict[str, slice] = {}
    start = 0
    for name, width in fields:
        out[name] = slice(start, start + width)
        start += width
    return MappingProxyType(out)


ROBOT_FIELDS: FieldMap = _layout(
    ("joint_pos", 6), ("joint_vel", 6), ("tool_pos", 3), ("tool_yaw", 2), ("vacuum", 1), ("held", 1)
)
"""Fields of the ``robot`` vector."""
TILE_FIELDS: FieldMap = _layout(("xyz", 3), ("yaw", 2), ("class", 1), ("present", 1))
"""Fields of a ``tiles`` row (``state``)."""
SLOT_FIELDS: FieldMap = _layout(("xy", 2), ("yaw", 2), ("class", 1), ("filled", 1))
"""Fields of a ``slots`` row (``state``)."""


def width(fields: FieldMap) -> int:
    """Length of a row laid out by ``fields`` (the end of its last field)."""
    return max(s.stop for s in fields.values())


def column(fields: FieldMap, name: str) -> int:
    """The one column of a width-1 field (``class``, ``present``, ``filled``, ...).

    Raises:
        KeyError: Unknown field, or a field wider than one column (the message lists the
            allowed names).
    """
    ones = sorted(k for k, s in fields.items() if s.stop - s.start == 1)
    if name not in ones:
        raise KeyError(f"no one-column field {name!r}; allowed: {ones}")
    return fields[name].start


ROBOT_DIM = width(ROBOT_FIELDS)
"""Length of the ``robot`` vector (19)."""
TILE_DIM = width(TILE_FIELDS)
"""Features per tile in ``tiles`` (7)."""
SLOT_DIM = width(SLOT_FIELDS)
"""Features per slot in ``slots`` (6)."""

__all__ = [
    "ROBOT_DIM",
    "ROBOT_FIELDS",
    "SLOT_DIM",
    "SLOT_FIELDS",
    "TILE_DIM",
    "TILE_FIELDS",
    "FieldMap",
    "column",
    "width",
]
