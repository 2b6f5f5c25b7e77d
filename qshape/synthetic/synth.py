"""Synthetic camera images of tiles with ground truth, for tests and the recognition benchmark.

Tiles are taken from design slots, given manufacturing noise (vertex jitter, arc jitter, colour
jitter), laid at random non-overlapping poses on a belt-coloured background, then photographed:
an illumination gradient, blur and sensor noise. The default image is the paper camera's
656 x 492 px. `SynthParams.effects` adds what a real line shows (`qshape.synthetic.effects`): rough
and
chipped edges, tiles touching each other or cut by the border, a soft shadow, glaze highlights,
motion blur on the moving belt, radial lens distortion and JPEG compression; all are off by
default.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from configs.checks import check_fields, checked
from qshape.design import Design, Slot, TilePath, load_section
from qshape.errors import QShapeError
from qshape.geometry import BoolArray, FloatArray, wrap_angle
from qshape.synthetic import effects as fx
from qshape.synthetic.render import RenderParams, fill_tiles


@dataclass(frozen=True)
class SynthParams:
    """How synthetic tile images are made.

    Attributes:
        width_px: Image width, in [px] (AVT Guppy F-033C: 656).
        height_px: Image height, in [px] (492).
        px_per_mm: Scale on the belt, in [px/mm].
        belt_color: Belt RGB in [0, 1].
        gap_mm: Smallest distance between two tiles, in [mm].
        margin_px: Smallest distance between a whole tile and the image border, in [px].
        placement_attempts: Random poses tried per tile before it is left out.
        vertex_jitter_mm: Largest vertex displacement (uniform in a disc), in [mm].
        bulge_jitter: Relative arc bulge change (uniform in +-), dimensionless.
        color_jitter: Standard deviation of the per-tile colour change per channel, RGB [0, 1].
        noise_std: Standard deviation of the per-pixel sensor noise, in [levels] (0-255).
        blur_sigma_px: Optical blur (Gaussian), in [px].
        illumination: Relative brightness change across the image (linear gradient in a random
            direction, from 1 - illumination to 1 + illumination), dimensionless.
        outline_step_px: Sampling step of the drawn outlines, in [px].
        effects: What a real line adds (all off by default; see `qshape.synthetic.effects`).
    """

    width_px: int = checked(656, ge=16)
    height_px: int = checked(492, ge=16)
    px_per_mm: float = checked(2.5, gt=0)
    belt_color: tuple[float, float, float] = (0.24, 0.26, 0.28)
    gap_mm: float = checked(3.0, ge=0)
    margin_px: int = 4
    placement_attempts: int = 300
    vertex_jitter_mm: float = checked(0.5, ge=0)
    bulge_jitter: float = checked(0.05, ge=0)
    color_jitter: float = checked(0.02, ge=0)
    noise_std: float = checked(3.0, ge=0)
    blur_sigma_px: float = checked(0.7, ge=0)
    illumination: float = checked(0.1, ge=0, lt=1)
    outline_step_px: float = 0.5
    effects: fx.CameraEffects = field(default_factory=fx.CameraEffects)

    def __post_init__(self) -> None:
        """Raise `QShapeError` on out-of-range values."""
        check_fields(self, QShapeError)

    @classmethod
    def load(cls, name_or_path: str | Path | None = None, **overrides: Any) -> SynthParams:
        """Load the ``synth`` section of ``configs/vision.yaml`` (or another file)."""
        return load_section(cls, "synth", name_or_path, overrides)

    def noise_level(self, level: float) -> SynthParams:
        """These parameters with every noise source scaled by ``level`` (0: clean)."""
        return replace(
            self,
            vertex_jitter_mm=self.vertex_jitter_mm * level,
            bulge_jitter=self.bulge_jitter * level,
            color_jitter=self.color_jitter * level,
            noise_std=self.noise_std * level,
            blur_sigma_px=self.blur_sigma_px * level,
            illumination=min(self.illumination * level, 0.9),
        )


@dataclass(frozen=True, eq=False)
class TileTruth:
    """Ground truth of one tile in a synthetic image.

    Attributes:
        slot: The design slot the tile was made from.
        slot_index: Index of that slot in its design.
        angle: Orientation of the tile's shape, [rad], CCW in the y-up frame, relative to the
            shape's local frame (the slot itself sits at ``radians(slot.angle)``).
        rotation: Rotation that turns the tile onto its slot, [rad], CCW y-up, wrapped to
            (-pi, pi] (the convention of ``qshape.Match.rotation``).
        center_px: Area centroid, shape (2,), [px], y down.
        points_px: True relevant points (after manufacturing noise), shape (n, 2), [px].
        curve_mask: Shape (n,), True at arc middles.
        hole_points_px: True relevant points of each hole, [px].
        hole_curve_masks: Curve mask of each hole.
        color: Tile colour after colour jitter, RGB in [0, 1].
        partial: True when the tile is cut by the image border.
        outline_px: The outline as drawn into the picture (manufacturing noise and edge wear
            included, before any lens), shape (m, 2), [px], y down; None before it is drawn.
    """

    slot: Slot
    slot_index: int
    angle: float
    rotation: float
    center_px: FloatArray
    points_px: FloatArray
    curve_mask: BoolArray
    hole_points_px: tuple[FloatArray, ...]
    hole_curve_masks: tuple[BoolArray, ...]
    color: tuple[float, float, float]
    partial: bool = False
    outline_px: FloatArray | None = None


@dataclass(frozen=True, eq=False)
class SynthImage:
    """A synthetic image and its tiles.

    Attributes:
        image: RGB uint8, shape (height_px, width_px, 3).
        tiles: Ground truth of every tile drawn.
        px_per_mm: Scale, in [px/mm].
    """

    image: np.ndarray
    tiles: list[TileTruth]
    px_per_mm: float


def place_path(path: TilePath, angle: float, center_px: Any, px_per_mm: float) -> TilePath:
    """Tile-local path (mm, y up) placed in an image (px, y down).

    Rotated by ``angle`` rad CCW (y up), scaled by ``px_per_mm``, flipped to y down and moved
    so that the local origin lands on ``center_px`` (2,).
    """
    placed = path.transformed(angle, (0.0, 0.0), px_per_mm)

    def flip(loop: Any) -> Any:
        v = loop.vertices * np.array([1.0, -1.0]) + np.asarray(center_px, dtype=np.float64)
        return type(loop)(v, -loop.bulges)  # mirroring reverses the arcs' sense

    return TilePath(flip(placed.outer), tuple(flip(h) for h in placed.holes))


def generate(
    slots: Design | Sequence[Slot],
    n_tiles: int,
    rng: np.random.Generator | int,
    params: SynthParams | None = None,
) -> SynthImage:
    """Draw ``n_tiles`` tiles (slots picked at random, with repeats) on a belt image.

    Tiles that cannot be placed without overlap after ``placement_attempts`` tries are left
    out (the truth lists only the tiles drawn). With ``params.effects`` some tiles are laid
    against another tile or across the border (``TileTruth.partial``), outlines are
    roughened and chipped, and the picture gets the line's effects; truth points and centres
    are then where the distorting lens shows them.

    Args:
        slots: A design (its slots) or a list of slots.
        n_tiles: Number of tiles wanted.
        rng: Generator or seed.
        params: Image parameters (None: ``configs/vision.yaml`` section ``synth``).

    Raises:
        QShapeError: No slots, or a negative tile count.
    """
    p = params or SynthParams.load()
    e = p.effects
    gen = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    pool = list(slots.slots if isinstance(slots, Design) else slots)
    if not pool or n_tiles < 0:
        raise QShapeError("generate needs at least one slot and n_tiles >= 0")
    s = p.px_per_mm
    w, h = p.width_px, p.height_px
    layout = _Layout(np.zeros((h, w), np.uint8), np.zeros((h, w), np.uint8))
    truths: list[TileTruth] = []
    drawn: list[tuple[FloatArray, list[FloatArray]]] = []
    colors: list[tuple[float, float, float]] = []
    radii: list[float] = []
    for _ in range(n_tiles):
        idx = int(gen.integers(len(pool)))
        slot = pool[idx]
        local = slot.local_path.jittered(gen, p.vertex_jitter_mm, p.bulge_jitter)
        _, c = local.area_centroid(slot.rules.outline_step_mm)
        local = local.transformed(0.0, -c)
        radius = float(np.max(np.hypot(*local.outer.dense(1.0).T))) * s
        mode = _placement_mode(e, truths, gen)
        pose = _place(local, radius, mode, (truths, radii, layout), p, gen)
        if pose is None:
            continue
        truth, worn, holes = _tile_truth(slot, idx, pose, p, gen)
        truths.append(truth)
        drawn.append((worn, holes))
        colors.append(truth.color)
        radii.append(radius)
    image = np.empty((h, w, 3), np.uint8)
    image[:] = [round(255 * v) for v in p.belt_color]
    fill_tiles(image, drawn, colors, RenderParams())
    picture = _camera(image, gen, p, _glaze(drawn, e, h, w), [t.center_px for t in truths], radii)
    if e.lens_k1 != 0.0 or e.lens_k2 != 0.0:
        truths = [_distorted_truth(t, e, w, h) for t in truths]
    return SynthImage(picture, truths, s)


_Pose = tuple[float, FloatArray, TilePath, FloatArray]
"""A drawn tile's angle [rad], centre (2,) [px], placed path and dense outline (k, 2) [px]."""


def _placement_mode(e: fx.CameraEffects, truths: list[TileTruth], gen: np.random.Generator) -> str:
    """How the next tile is laid: "touch" (a laid tile), "partial" (the border) or "free"."""
    if e.touching_probability > 0.0 and truths and gen.random() < e.touching_probability:
        return "touch"
    if e.partial_probability > 0.0 and gen.random() < e.partial_probability:
        return "partial"
    return "free"


def _place(  # noqa: PLR0917
    local: TilePath,
    radius: float,
    mode: str,
    laid: tuple[list[TileTruth], list[float], _Layout],
    p: SynthParams,
    gen: np.random.Generator,
) -> _Pose | None:
    """A pose for one tile, marked in the layout; None when none fits in the attempts.

    ``laid``: the tiles laid so far, their radii [px] and the layout's masks.
    """
    truths, radii, layout = laid
    w, h = p.width_px, p.height_px
    gap_px = max(1, int(math.ceil(p.gap_mm * p.px_per_mm)))
    for _attempt in range(p.placement_attempts):
        angle = float(gen.uniform(-math.pi, math.pi))
        lo = radius + p.margin_px
        if w - 2 * lo <= 0 or h - 2 * lo <= 0:
            return None
        if mode == "touch":
            found = _touching_pose(local, angle, radius, truths, radii, layout, p, gen)
            if found is None:
                continue
            center, placed, outline = found
            local_mask = _tile_mask(outline, 0, w, h)
        else:
            if mode == "partial":
                center = _border_center(radius, w, h, gen)
            else:
                center = np.array([gen.uniform(lo, w - lo), gen.uniform(lo, h - lo)])
            placed = place_path(local, angle, center, p.px_per_mm)
            outline = placed.outer.dense(p.outline_step_px)
            local_mask = _tile_mask(outline, gap_px, w, h)
            if local_mask is None or layout.hits(local_mask, layout.occupied):
                continue
        solid = _tile_mask(outline, 0, w, h)
        if local_mask is None or solid is None:
            continue
        layout.add(local_mask, solid)
        return angle, center, placed, outline
    return None


def _tile_truth(
    slot: Slot, idx: int, pose: _Pose, p: SynthParams, gen: np.random.Generator
) -> tuple[TileTruth, FloatArray, list[FloatArray]]:
    """The truth of a placed tile, its worn outline and its holes (dense, [px])."""
    angle, center, placed, outline = pose
    s, step = p.px_per_mm, p.outline_step_px
    color = np.clip(np.array(slot.color) + gen.normal(0.0, p.color_jitter, 3), 0, 1)
    rgb = (float(color[0]), float(color[1]), float(color[2]))
    pts, mask = placed.outer.relevant(slot.rules.max_arc_deg)
    hole_rel = [hl.relevant(slot.rules.max_arc_deg) for hl in placed.holes]
    holes = [hl.dense(step) for hl in placed.holes]
    worn, holes = _worn_edges(placed, outline, holes, p.effects, s, gen)
    truth = TileTruth(
        slot=slot,
        slot_index=idx,
        angle=angle,
        rotation=wrap_angle(math.radians(slot.angle) - angle),
        center_px=center,
        points_px=pts,
        curve_mask=mask,
        hole_points_px=tuple(hp for hp, _ in hole_rel),
        hole_curve_masks=tuple(hm for _, hm in hole_rel),
        color=rgb,
        partial=_cut_by_border(outline, p.width_px, p.height_px),
        outline_px=worn,
    )
    return truth, worn, holes


def _glaze(
    drawn: list[tuple[FloatArray, list[FloatArray]]], e: fx.CameraEffects, h: int, w: int
) -> np.ndarray | None:
    """Where glaze highlights may fall (uint8 (h, w), 1 on tiles less their holes), or None."""
    if not (e.highlight_strength > 0.0 and e.highlight_probability > 0.0):
        return None
    glaze = np.zeros((h, w), np.uint8)
    rings = [np.round(o).astype(np.int32) for o, _ in drawn]
    cv2.fillPoly(glaze, rings, 1)
    for _, hs in drawn:
        if hs:
            cv2.fillPoly(glaze, [np.round(hh).astype(np.int32) for hh in hs], 0)
    return glaze


@dataclass
class _Layout:
    """Occupancy of the picture while tiles are laid: with the gap around tiles, and without."""

    occupied: np.ndarray
    solid: np.ndarray

    @staticmethod
    def hits(window: tuple[int, int, np.ndarray], grid: np.ndarray) -> bool:
        x0, y0, m = window
        return bool(np.any(grid[y0 : y0 + m.shape[0], x0 : x0 + m.shape[1]] & m))

    def add(self, gapped: tuple[int, int, np.ndarray], solid: tuple[int, int, np.ndarray]) -> None:
        for (x0, y0, m), grid in ((gapped, self.occupied), (solid, self.solid)):
            grid[y0 : y0 + m.shape[0], x0 : x0 + m.shape[1]] |= m


def _tile_mask(
    outline: FloatArray, gap_px: int, w: int, h: int
) -> tuple[int, int, np.ndarray] | None:
    """(x0, y0, mask) of a tile outline grown by ``gap_px``, clipped to the picture (or None)."""
    x0, y0 = np.floor(outline.min(axis=0)).astype(int) - gap_px
    x1, y1 = np.ceil(outline.max(axis=0)).astype(int) + gap_px + 1
    x0, y0, x1, y1 = max(x0, 0), max(y0, 0), min(x1, w), min(y1, h)
    if x1 <= x0 or y1 <= y0:
        return None
    local_mask = np.zeros((y1 - y0, x1 - x0), np.uint8)
    ring = np.round(outline - [x0, y0]).astype(np.int32)
    cv2.fillPoly(local_mask, [ring], 255)
    if gap_px > 0:
        cv2.polylines(local_mask, [ring], True, 255, 2 * gap_px + 1)
    return int(x0), int(y0), local_mask


def _touching_pose(  # noqa: PLR0913, PLR0917
    local: TilePath,
    angle: float,
    radius: float,
    truths: list[TileTruth],
    radii: list[float],
    layout: _Layout,
    p: SynthParams,
    gen: np.random.Generator,
) -> tuple[FloatArray, TilePath, FloatArray] | None:
    """A pose against a random laid tile: slid towards it until the outlines meet (or None)."""
    k = int(gen.integers(len(truths)))
    bearing = gen.uniform(0.0, 2.0 * math.pi)
    direction = np.array([math.cos(bearing), math.sin(bearing)])
    w, h = p.width_px, p.height_px
    lo, hi = 0.0, radii[k] + radius + 2.0
    base = truths[k].center_px
    best: tuple[FloatArray, TilePath, FloatArray] | None = None
    for _ in range(10):  # bisection of the distance to half a pixel in ~10 steps
        mid = 0.5 * (lo + hi)
        center = base + mid * direction
        placed = place_path(local, angle, center, p.px_per_mm)
        outline = placed.outer.dense(p.outline_step_px)
        mask = _tile_mask(outline, 0, w, h)
        if mask is not None and not layout.hits(mask, layout.solid):
            hi, best = mid, (center, placed, outline)
        else:
            lo = mid
    if best is None:
        return None
    center, placed, outline = best
    inside = radius + p.margin_px
    if not (inside <= center[0] <= w - inside and inside <= center[1] <= h - inside):
        return None
    return best


def _border_center(radius: float, w: int, h: int, gen: np.random.Generator) -> FloatArray:
    """A tile centre within half a radius of a random picture edge (the tile crosses it)."""
    side = int(gen.integers(4))
    off = gen.uniform(-0.5, 0.5) * radius
    if side in (0, 1):  # left, right
        x = off if side == 0 else w - off
        return np.array([x, gen.uniform(radius, h - radius)])
    y = off if side == 2 else h - off  # noqa: PLR2004 (top)
    return np.array([gen.uniform(radius, w - radius), y])


def _cut_by_border(outline: FloatArray, w: int, h: int) -> bool:
    """True when the outline leaves the picture (w x h px)."""
    lo, hi = outline.min(axis=0), outline.max(axis=0)
    return bool(lo[0] < 0.0 or lo[1] < 0.0 or hi[0] > w - 1 or hi[1] > h - 1)


def _worn_edges(  # noqa: PLR0917
    placed: TilePath,
    outline: FloatArray,
    holes: list[FloatArray],
    e: fx.CameraEffects,
    px_per_mm: float,
    gen: np.random.Generator,
) -> tuple[FloatArray, list[FloatArray]]:
    """Outline and holes (px) with chipped corners and rough edges, as a real tile has them."""
    if e.chip_probability > 0.0 and e.chip_size_mm > 0.0:
        size = e.chip_size_mm * px_per_mm
        outline = fx.chip_corners(outline, placed.outer.vertices, e.chip_probability, size, gen)
        holes = [
            fx.chip_corners(hd, hl.vertices, e.chip_probability, size, gen)
            for hd, hl in zip(holes, placed.holes, strict=True)
        ]
    if e.edge_roughness_mm > 0.0:
        sigma, length = e.edge_roughness_mm * px_per_mm, e.roughness_length_mm * px_per_mm
        outline = fx.roughen(outline, sigma, length, gen)
        holes = [fx.roughen(hd, sigma, length, gen) for hd in holes]
    return outline, holes


def _distorted_truth(t: TileTruth, e: fx.CameraEffects, w: int, h: int) -> TileTruth:
    """Truth with every point where the distorting lens shows it.

    A tile the lens pushes across the border (a pincushion lens shows less than the pinhole
    view) is partial.
    """
    points = fx.distort_points(t.points_px, e, w, h)
    return replace(
        t,
        center_px=fx.distort_points(t.center_px[None, :], e, w, h)[0],
        points_px=points,
        hole_points_px=tuple(fx.distort_points(hp, e, w, h) for hp in t.hole_points_px),
        partial=t.partial or _cut_by_border(points, w, h),
    )


def _camera(  # noqa: PLR0913, PLR0917
    image: np.ndarray,
    gen: np.random.Generator,
    p: SynthParams,
    glaze: np.ndarray | None = None,
    centres: list[FloatArray] | None = None,
    radii: list[float] | None = None,
) -> np.ndarray:
    """Light (gradient, shadow, highlights), motion, lens, blur, noise and JPEG on a rendering."""
    h, w = image.shape[:2]
    e = p.effects
    out: np.ndarray = image.astype(np.float32)
    if p.illumination > 0.0:
        theta = gen.uniform(0.0, 2.0 * math.pi)
        yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
        u = ((xx / w - 0.5) * math.cos(theta) + (yy / h - 0.5) * math.sin(theta)) * 2.0
        out = out * (1.0 + p.illumination * np.clip(u, -1.0, 1.0))[..., None].astype(np.float32)
    if glaze is not None:
        tiles = cv2.GaussianBlur(glaze.astype(np.float32), (0, 0), 0.7)
        out = fx.glaze_highlights(out, tiles, centres or [], radii or [], e, p.px_per_mm, gen)
    out = fx.soft_shadow(out, e, gen)
    out = fx.motion_blur(out, e.blur_px(p.px_per_mm), e.belt_direction_deg)
    out = fx.lens_distort(out, e)
    if p.blur_sigma_px > 0.0:
        out = cv2.GaussianBlur(out, (0, 0), p.blur_sigma_px)
    if p.noise_std > 0.0:
        out += gen.normal(0.0, p.noise_std, out.shape).astype(np.float32)
    return fx.jpeg(np.clip(out + 0.5, 0, 255).astype(np.uint8), e.jpeg_quality)


__all__ = ["SynthImage", "SynthParams", "TileTruth", "generate", "place_path"]
