"""`DesignFileParams`: how SVG and DXF designs are read and written.

Bundled values: the ``design_files`` section of ``configs/vision.yaml``.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from qshape.config_sections import load_section
from qshape.errors import DesignError, DesignFileWarning


@dataclass(frozen=True)
class DesignFileParams:
    """How drawn outlines become design slots, and how designs are written back.

    Attributes:
        curve_tolerance_mm: Curves that are not circular arcs (Beziers, elliptical arcs,
            splines) become circular arcs (bulges) within this distance of the curve, in [mm]
            (at most 0.05), so the qualitative description keeps its curve points.
        curve_step_mm: Spacing of the samples of such a curve that the arcs are fitted to and
            checked against, in [mm].
        close_tolerance_mm: A path or polyline ending this close to its start counts as
            closed, in [mm]; a farther end is an open path (`DesignError`).
        same_shape_tolerance_mm: Drawn tiles whose outlines and holes coincide within this
            after a turn are one shape class (one shape, each slot with its turn), in [mm].
        default_joint_mm: Joint width of a file that states none (an SVG without
            ``data-joint``, a DXF without the ``joint`` custom property), in [mm]; loading
            warns (`qshape.errors.DesignFileWarning`).
        decimals: Digits after the decimal point of the coordinates `Design.to_svg` and
            `Design.to_dxf` write (4: 0.1 um).
    """

    curve_tolerance_mm: float = 0.05
    curve_step_mm: float = 0.1
    close_tolerance_mm: float = 0.01
    same_shape_tolerance_mm: float = 0.02
    default_joint_mm: float = 2.0
    decimals: int = 4

    def __post_init__(self) -> None:
        """Raise `DesignError` on out-of-range values."""
        if not 0.0 < self.curve_tolerance_mm <= 0.05:
            raise DesignError(
                f"curve_tolerance_mm must be in (0, 0.05], got {self.curve_tolerance_mm}"
            )
        positive = ("curve_step_mm", "close_tolerance_mm", "same_shape_tolerance_mm")
        for name in (*positive, "default_joint_mm"):
            if not getattr(self, name) > 0.0:
                raise DesignError(f"{name} must be > 0, got {getattr(self, name)}")
        if not 2 <= self.decimals <= 9:
            raise DesignError(f"decimals must be in [2, 9], got {self.decimals}")

    @classmethod
    def load(cls, name_or_path: str | Path | None = None, **overrides: Any) -> DesignFileParams:
        """Load the ``design_files`` section of ``configs/vision.yaml`` (or another file).

        Raises:
            configs.ConfigError: Unknown key or wrong type.
        """
        return load_section(cls, "design_files", name_or_path, overrides, default="vision")


__all__ = ["DesignFileParams"]


def drawing_joint(raw: Any, missing: str, bad: str, params: DesignFileParams) -> float:
    """The joint a drawing states [mm], or the default with a `DesignFileWarning`.

    Args:
        raw: The drawing's value (None: not stated).
        missing: What the warning says is missing (``"<source>: no data-joint on <svg>"``).
        bad: What the error names for a value that is no positive number.
        params: The default joint.

    Raises:
        DesignError: A joint that is not a positive number of millimetres.
    """
    if raw is None:
        warnings.warn(
            f"{missing}; the joint is {params.default_joint_mm} mm", DesignFileWarning, stacklevel=4
        )
        return params.default_joint_mm
    try:
        joint = float(raw)
    except ValueError:
        joint = float("nan")
    if not (math.isfinite(joint) and joint > 0.0):
        raise DesignError(f"{bad}: a positive number of mm")
    return joint
