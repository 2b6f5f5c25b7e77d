"""Design from a design image: tiles on a joint colour, found by `qshape.extract`.

`design_mapping` turns the extracted figures (pixels, y down) into a design file mapping
(mesh millimetres, y up) whose slots are ``polygon`` shapes with arcs as bulges; `Design.from_image`
reads it like any design file.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from qshape import geometry as geo
from qshape.design.paths import Loop, TilePath
from qshape.design.rules import DesignRules
from qshape.design.values import color_hex, number, round_mm
from qshape.errors import DesignError
from qshape.geometry import BoolArray, FloatArray
from qshape.theory.figure import Figure
from qshape.vision.extract import extract_detailed, read_image

_UNKNOWN_COLOR = (0.5, 0.5, 0.5)
"""Colour of a slot whose tile has no extracted colour (RGB in [0, 1])."""


def design_mapping(
    image: str | Path | np.ndarray,
    mm_per_px: float,
    joint_mm: float,
    *,
    name: str = "from_image",
    params: Any = None,
    rules: DesignRules | None = None,
) -> dict[str, Any]:
    """The design file mapping of a design image (see `qshape.Design.from_image`).

    Raises:
        DesignError: Bad scale or joint, or no whole tiles found.
        qshape.vision.params.ImageError: Unreadable file or malformed image.
    """
    scale = number(mm_per_px, "mm_per_px")
    joint = number(joint_mm, "joint_mm")
    arr = read_image(image) if isinstance(image, str | Path) else image
    result = extract_detailed(arr, params)
    if not result.figures:
        raise DesignError("design image: no whole tiles found")
    height_px = arr.shape[0]
    step = (rules or DesignRules()).outline_step_mm
    return {
        "name": name,
        "mesh": {"width": arr.shape[1] * scale, "height": height_px * scale},
        "joint": joint,
        "grout_color": color_hex(result.background),
        "slots": [
            _slot_mapping(fig, k, scale, height_px, step) for k, fig in enumerate(result.figures)
        ],
    }


def _bulges_from_relevant(pts: FloatArray, mask: BoolArray) -> tuple[FloatArray, FloatArray]:
    """Vertices and bulges (CCW, y-up) from relevant points whose curve points are arc middles."""
    keep = ~mask
    v = pts[keep]
    b = np.zeros(len(v))
    idx = np.flatnonzero(keep)
    n = len(pts)
    for e, i in enumerate(idx):
        j = (i + 1) % n
        if mask[j]:
            k = (j + 1) % n
            chord = pts[k] - pts[i]
            c = float(np.hypot(*chord))
            mid = 0.5 * (pts[i] + pts[k])
            out = np.array([chord[1], -chord[0]]) / c  # outward for a CCW loop
            sag = float((pts[j] - mid) @ out)
            b[e] = 2.0 * sag / c
    return v, b


def _slot_mapping(fig: Figure, k: int, scale: float, height_px: int, step: float) -> dict[str, Any]:
    """A polygon slot mapping (mesh mm, y up) from an extracted pixel figure (y down)."""

    def to_mm(p: FloatArray) -> FloatArray:
        return np.stack([p[:, 0] * scale, (height_px - p[:, 1]) * scale], axis=1)

    def loop_of(points: FloatArray, mask: BoolArray) -> Loop:
        mm = to_mm(np.asarray(points))
        m = np.asarray(mask, dtype=bool)
        if geo.signed_area(mm) < 0:
            mm, m = mm[::-1].copy(), m[::-1].copy()
        v, b = _bulges_from_relevant(mm, m)
        return Loop.make(v, b)

    outer = loop_of(fig.points, fig.curve_mask)
    holes = [loop_of(h.points, h.curve_mask) for h in fig.holes]
    _, c = TilePath(outer, tuple(holes)).area_centroid(step)

    def rows(loop: Loop) -> list[list[float]]:
        v = loop.vertices - c
        return [
            [round_mm(x), round_mm(y)] + ([round_mm(b)] if b != 0.0 else [])
            for (x, y), b in zip(v, loop.bulges, strict=False)
        ]

    shape: dict[str, Any] = {"kind": "polygon", "vertices": rows(outer)}
    if holes:
        shape["holes"] = [{"kind": "polygon", "vertices": rows(h)} for h in holes]
    return {
        "name": f"tile_{k:03d}",
        "shape": shape,
        "color": color_hex(fig.color if fig.color is not None else _UNKNOWN_COLOR),
        "pose": {"x": round_mm(float(c[0])), "y": round_mm(float(c[1])), "angle": 0.0},
    }


__all__ = ["design_mapping"]
