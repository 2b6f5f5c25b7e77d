"""What the design file format and the layout checks read of a design.

A protocol rather than `qshape.design.model.Design` itself, so that `model` can use `checks` and
`fileformat` without either importing `model` back.
"""

from __future__ import annotations

from typing import Protocol

from qshape.design.rules import DesignRules
from qshape.design.slot import Slot


class DesignFields(Protocol):
    """The fields of a design (see `qshape.design.model.Design` for their meaning and units)."""

    @property
    def name(self) -> str:
        """Design name."""
        ...

    @property
    def mesh_size(self) -> tuple[float, float]:
        """(width, height) of the mesh, in [mm]."""
        ...

    @property
    def joint(self) -> float:
        """Joint width between neighbouring tiles, in [mm]."""
        ...

    @property
    def slots(self) -> tuple[Slot, ...]:
        """The slots."""
        ...

    @property
    def grout_color(self) -> tuple[float, float, float]:
        """RGB in [0, 1] of the joints."""
        ...

    @property
    def description(self) -> str:
        """Free text."""
        ...

    @property
    def rules(self) -> DesignRules:
        """Sampling and validation rules."""
        ...


__all__ = ["DesignFields"]
