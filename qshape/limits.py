"""Documented caps on the size of qshape's inputs, so every entry point stays fast.

Work in qshape grows with the number of relevant points (matching compares every cyclic offset:
n^2), with the length of a dense outline and of a description's text. Inputs above a cap are
refused with a typed error (`qshape.LimitError`, naming the cap and where to change it) before
any work is done; inputs at a cap run in well under a second (``benchmarks/theory/robustness.py``).
Bundled values live in the ``limits`` section of ``configs/qshape.yaml``.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from configs import ConfigError, check_field_types
from configs.checks import check_fields, checked
from qshape.config_sections import load_section
from qshape.errors import DesignLimitError, FigureLimitError, LimitError, ToleranceError
from qshape.geometry import MAX_COORDINATE


@dataclass(frozen=True)
class Limits:
    """Caps on input sizes and the numerical range qshape accepts.

    Attributes:
        max_points: Most relevant points in one figure, outer boundary and holes together
            [count]. Matching costs O(n^2) in them; a mosaic tile has a few dozen.
        max_holes: Most holes in one figure [count].
        max_dense_points: Most points of one dense outline given to `Figure.from_outline`
            [count] (a traced contour; a 656 x 492 image's longest is a few thousand).
        max_coordinate: Largest accepted coordinate magnitude, in the figure's length unit.
        coordinate_resolution: Largest float64 spacing of the coordinates (at their magnitude)
            as a fraction of the figure's size: a figure so small or so far from the origin
            that its points are rounded more coarsely than this is refused (dimensionless).
        max_text_chars: Longest text `qshape.parse` reads [characters].
        max_design_mm: Largest design length [mm]: each side of a design's mesh and the
            length of each tile outline (outer boundary plus holes). Outlines are sampled
            every fraction of a millimetre, so the work and memory of loading a design grow
            with these lengths; 10 m covers any wall mosaic the cell could lay.
    """

    max_points: int = checked(1000, ge=1)
    max_holes: int = checked(32, ge=1)
    max_dense_points: int = checked(100_000, ge=1)
    max_coordinate: float = checked(1e12, gt=0, le=MAX_COORDINATE)
    coordinate_resolution: float = checked(1e-6, gt=0, lt=1)
    max_text_chars: int = checked(1_000_000, ge=1)
    max_design_mm: float = checked(10_000.0, gt=0)

    def __post_init__(self) -> None:
        """Check types and ranges.

        Raises:
            ToleranceError: A field of the wrong type or out of range, naming it.
        """
        try:
            check_field_types(self)
        except ConfigError as exc:
            raise ToleranceError(str(exc)) from None
        check_fields(self, ToleranceError, qualify=True)

    @classmethod
    def load(cls, name_or_path: str | Path | None = None, **overrides: Any) -> Limits:
        """Load the ``limits`` section of ``configs/qshape.yaml`` (or another file).

        Raises:
            configs.ConfigError: Unknown key, wrong type or missing file.
            ToleranceError: Values out of range.
        """
        return load_section(cls, "limits", name_or_path, overrides, default="qshape")

    def check_count(
        self, count: int, cap: str, what: str, error: type[LimitError] = LimitError
    ) -> None:
        """Raise ``error`` (a `LimitError`) when ``count`` exceeds the cap called ``cap``."""
        limit = getattr(self, cap)
        if count > limit:
            raise error(
                f"{what}: {count} exceeds the cap {cap}={limit} (configs/qshape.yaml, limits)"
            )

    def check_range(self, magnitude: float, size: float, what: str) -> None:
        """Refuse coordinates too large, or too coarse for the figure's size.

        Args:
            magnitude: Largest absolute coordinate.
            size: Figure size (largest extent), same unit.
            what: Name of the boundary for the message.

        Raises:
            FigureLimitError: Magnitude above ``max_coordinate``, or float64 spacing at the
                magnitude coarser than ``coordinate_resolution`` x size.
        """
        if magnitude > self.max_coordinate:
            raise FigureLimitError(
                f"{what}: coordinates must be at most {self.max_coordinate:g} in magnitude, got "
                f"{magnitude:.6g} (cap max_coordinate, configs/qshape.yaml)"
            )
        if size > 0.0 and math.ulp(magnitude) > self.coordinate_resolution * size:
            raise FigureLimitError(
                f"{what}: a figure of size {size:.6g} at coordinates of magnitude "
                f"{magnitude:.6g} cannot be represented: float64 rounds its points by "
                f"{math.ulp(magnitude):.3g}, more than coordinate_resolution="
                f"{self.coordinate_resolution:g} of its size; move it nearer the origin"
            )

    def check_length(self, length_mm: float, what: str) -> None:
        """Raise `DesignLimitError` when a design length exceeds ``max_design_mm``.

        Call it before sampling or allocating anything of that length.
        """
        if not length_mm <= self.max_design_mm:
            raise DesignLimitError(
                f"{what}: {length_mm:.6g} mm exceeds the cap max_design_mm="
                f"{self.max_design_mm:g} mm (configs/qshape.yaml, limits)"
            )


@functools.cache
def default_limits() -> Limits:
    """The bundled limits (``configs/qshape.yaml``), loaded once."""
    return Limits.load()


__all__ = ["Limits", "default_limits"]
