"""Which glaze colours the configured cell can tell from its input belt.

The cell's camera finds a tile by how far its colour stands off the belt's, unless the env
gives the picture's height too (``depth=True``: a 3D camera beside the colour one, a cue that
does not depend on colour; `qshape.extract_detailed`'s ``height``). Without it, a glaze within
the vision's largest foreground threshold (``extract.threshold_max`` of
``configs/vision.yaml``, largest channel difference in 0-255 levels) of the belt's colour may
never be seen: `check_glazes` warns about each such slot when a design is loaded for the cell.
Both colours render at their own value under the cell's exposure-normalised light
(``scenery.exposure``), so they are compared as configured.
"""

from __future__ import annotations

import warnings
from typing import TYPE_CHECKING

import numpy as np

from envs.cell.config import CellConfig
from envs.errors import EnvError

if TYPE_CHECKING:
    from qshape.design import Design

LEVELS = 255.0
"""Levels of one 8-bit channel, the scale of the vision's thresholds."""


class GlazeWarning(EnvError, UserWarning):
    """A design's tile colour the configured cell cannot separate from its belt (named)."""


def unseparable_glazes(design: Design, cell: CellConfig, threshold: float) -> list[str]:
    """Names of the slots whose colour stands less than ``threshold`` levels off the belt."""
    belt = np.asarray(cell.scenery.belt_rgba[:3], dtype=float)
    out = []
    for s in design.slots:
        gap = float(np.max(np.abs(np.asarray(s.color, dtype=float) - belt))) * LEVELS
        if gap < threshold:
            out.append(s.name)
    return out


def check_glazes(design: Design, cell: CellConfig, height_cue: bool) -> None:
    """Warn (`GlazeWarning`) about the slots whose colour the cell cannot tell from its belt.

    Nothing is said with a height cue (``depth=True``): a tile is then found by its height.
    """
    if height_cue:
        return
    from qshape.vision.params import default_params  # noqa: PLC0415 - keep `import envs` light

    threshold = default_params().threshold_max
    names = unseparable_glazes(design, cell, threshold)
    if names:
        belt = cell.scenery.belt_rgba[:3]
        warnings.warn(
            f"design {design.name!r}: the cell's camera may not tell slot(s) {names} from the "
            f"input belt (colour within {threshold:g} levels of the belt's "
            f"{tuple(round(c, 3) for c in belt)}); give the env depth=True (a height cue that "
            "does not depend on colour) or another belt colour (scenery.belt_rgba)",
            GlazeWarning,
            stacklevel=3,
        )


__all__ = ["GlazeWarning", "check_glazes", "unseparable_glazes"]
