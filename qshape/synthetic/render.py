"""Render designs (and tiles at any pose) to RGB images, with an optional relevant-point overlay.

Images are RGB uint8 (H, W, 3), y down. A design point (x, y) in mesh millimetres (y up) lands
at pixel ``(x * s, (mesh_height - y) * s)`` with ``s`` the scale in px/mm; integer pixel
coordinates are pixel centres (OpenCV's convention).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from configs.checks import check_fields, checked
from qshape.config_sections import load_section
from qshape.design import Design
from qshape.errors import QShapeError
from qshape.geometry import FloatArray


@dataclass(frozen=True)
class RenderParams:
    """How designs are drawn.

    Attributes:
        px_per_mm: Scale, in [px/mm].
        subpixel_bits: Fractional bits of the polygon coordinates given to OpenCV (precision
            1 / 2**bits px).
        antialias: Anti-aliased tile edges.
        corner_color: RGB in [0, 1] of the overlay's vertex markers.
        curve_color: RGB in [0, 1] of the overlay's maximum-curvature markers.
        marker_radius_px: Overlay marker radius, in [px].
        label_scale: Font scale of the overlay's slot names (0: no names).
        label_color: RGB in [0, 1] of the overlay's text.
    """

    px_per_mm: float = checked(3.0, gt=0)
    subpixel_bits: int = checked(4, ge=0, le=8)
    antialias: bool = True
    corner_color: tuple[float, float, float] = (0.0, 0.0, 0.0)
    curve_color: tuple[float, float, float] = (1.0, 1.0, 1.0)
    marker_radius_px: int = 3
    label_scale: float = 0.35
    label_color: tuple[float, float, float] = (0.1, 0.1, 0.1)

    def __post_init__(self) -> None:
        """Raise `QShapeError` on out-of-range values."""
        check_fields(self, QShapeError)

    @classmethod
    def load(cls, name_or_path: str | Path | None = None, **overrides: Any) -> RenderParams:
        """Load the ``render`` section of ``configs/vision.yaml`` (or another file)."""
        return load_section(cls, "render", name_or_path, overrides)


def to_uint8(rgb: Sequence[float]) -> tuple[int, int, int]:
    """RGB in [0, 1] -> integer RGB in [0, 255]."""
    r, g, b = (int(round(255.0 * min(max(float(v), 0.0), 1.0))) for v in rgb)
    return (r, g, b)


def fill_tiles(
    image: np.ndarray,
    tiles: Sequence[tuple[FloatArray, Sequence[FloatArray]]],
    colors: Sequence[Sequence[float]],
    params: RenderParams | None = None,
) -> np.ndarray:
    """Fill tiles (outline and holes, pixel coordinates) into ``image`` in place.

    Args:
        image: RGB uint8 (H, W, 3), modified in place and returned.
        tiles: For each tile (outline (m, 2), [hole outlines (k, 2), ...]) in [px], y down.
        colors: RGB in [0, 1] per tile; the holes show what lies under them.
        params: Drawing parameters.
    """
    p = params or RenderParams()
    mult = float(1 << p.subpixel_bits)
    line = cv2.LINE_AA if p.antialias else cv2.LINE_8
    for (outline, holes), color in zip(tiles, colors, strict=False):
        rings = [np.round(np.asarray(r) * mult).astype(np.int32) for r in (outline, *holes)]
        if not holes:
            cv2.fillPoly(image, rings, to_uint8(color), line, p.subpixel_bits)
            continue
        # Holes keep the pixels below: paint the tile through a mask.
        mask = np.zeros(image.shape[:2], np.uint8)
        cv2.fillPoly(mask, rings, 255, line, p.subpixel_bits)
        alpha = (mask.astype(np.float32) / 255.0)[..., None]
        tile = np.empty_like(image)
        tile[:] = to_uint8(color)
        image[:] = (image * (1.0 - alpha) + tile * alpha + 0.5).astype(np.uint8)
    return image


def mm_to_px(points: FloatArray, mesh_height_mm: float, px_per_mm: float) -> FloatArray:
    """Mesh millimetres (y up) -> image pixels (y down), shape (m, 2)."""
    pts = np.asarray(points, dtype=np.float64)
    return np.stack([pts[:, 0] * px_per_mm, (mesh_height_mm - pts[:, 1]) * px_per_mm], axis=1)


def render_design(
    design: Design,
    px_per_mm: float | None = None,
    *,
    overlay: bool = False,
    params: RenderParams | None = None,
) -> np.ndarray:
    """Draw a design: tiles in their colours on the grout colour.

    Args:
        design: The design.
        px_per_mm: Scale in [px/mm]; None uses ``params.px_per_mm``.
        overlay: Also draw each slot's relevant points (vertices dark, curve points light) and
            its name.
        params: Drawing parameters (None: defaults).

    Returns:
        RGB uint8 image of shape (round(height * s), round(width * s), 3).
    """
    p = params or RenderParams()
    s = float(px_per_mm if px_per_mm is not None else p.px_per_mm)
    if not s > 0.0:
        raise QShapeError(f"px_per_mm must be > 0, got {s}")
    w_mm, h_mm = design.mesh_size
    image = np.empty((round(h_mm * s), round(w_mm * s), 3), np.uint8)
    image[:] = to_uint8(design.grout_color)
    tiles = [
        (mm_to_px(slot.outline_mm(), h_mm, s), [mm_to_px(h, h_mm, s) for h in slot.holes_mm()])
        for slot in design.slots
    ]
    fill_tiles(image, tiles, [slot.color for slot in design.slots], p)
    if overlay:
        draw_overlay(image, design, s, p)
    return image


def draw_overlay(
    image: np.ndarray, design: Design, px_per_mm: float, params: RenderParams | None = None
) -> np.ndarray:
    """Draw every slot's relevant points and name onto a rendering, in place."""
    p = params or RenderParams()
    h_mm = design.mesh_size[1]
    for slot in design.slots:
        fig = slot.figure()
        boundaries = [(fig.points, fig.curve_mask)] + [(h.points, h.curve_mask) for h in fig.holes]
        for pts, mask in boundaries:
            draw_points(image, mm_to_px(pts, h_mm, px_per_mm), mask, p)
        if p.label_scale > 0.0:
            cx, cy = mm_to_px(np.array([[slot.x, slot.y]]), h_mm, px_per_mm)[0]
            cv2.putText(
                image,
                slot.name,
                (int(cx) - 20, int(cy)),
                cv2.FONT_HERSHEY_SIMPLEX,
                p.label_scale,
                to_uint8(p.label_color),
                1,
                cv2.LINE_AA,
            )
    return image


def draw_points(
    image: np.ndarray,
    points_px: FloatArray,
    curve_mask: np.ndarray,
    params: RenderParams | None = None,
) -> np.ndarray:
    """Mark relevant points (pixels, y down): filled dots at vertices, rings at curve points."""
    p = params or RenderParams()
    for (x, y), curve in zip(
        np.asarray(points_px), np.asarray(curve_mask, dtype=bool), strict=False
    ):
        color = to_uint8(p.curve_color if curve else p.corner_color)
        thickness = 1 if curve else -1
        cv2.circle(
            image,
            (round(x), round(y)),
            p.marker_radius_px + int(curve),
            color,
            thickness,
            cv2.LINE_AA,
        )
    return image


def save_png(image: np.ndarray, path: str | Path) -> Path:
    """Write an RGB uint8 image as PNG (creating the folder).

    Raises:
        QShapeError: The image is not RGB uint8 or cannot be written.
    """
    arr = np.asarray(image)
    if arr.dtype != np.uint8 or arr.ndim != 3 or arr.shape[2] != 3:
        raise QShapeError(
            f"save_png needs an RGB uint8 (H, W, 3) image, got {arr.dtype} {arr.shape}"
        )
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    if not cv2.imwrite(str(out), cv2.cvtColor(arr, cv2.COLOR_RGB2BGR)):
        raise QShapeError(f"could not write {out}")
    return out


__all__ = [
    "RenderParams",
    "draw_overlay",
    "draw_points",
    "fill_tiles",
    "mm_to_px",
    "render_design",
    "save_png",
    "to_uint8",
]
