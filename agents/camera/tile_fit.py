"""Sub-pixel pose of a tile in a camera image: the published figure fitted to the picture.

A tile of a slot's class is that slot's figure (`envs.task_spec.WorldSlot.figure`) turned and
shifted on the belt. `fit_tile` finds the world pose ``(x, y, theta)`` at which the figure,
drawn into the image through the published camera model, best explains the pixels of one blob:

- **What the image says** (`tile_alpha`): every pixel of the blob's window unmixed between the
  belt's colour (the image's median) and the tile's (the blob's median), ``alpha`` in [0, 1]. An
  anti-aliased edge pixel half covered by the tile reads about 0.5, so the edges carry
  sub-pixel information. Pixels of other blobs get no weight.
- **What a pose predicts** (`coverage`): the share of each pixel covered by the tile's
  silhouette, drawn ``supersample`` times finer and averaged. The silhouette is the tile's prism
  (top face at ``tile_top_z``, bottom face at ``surface_z`` and the side walls between them):
  away from the optical axis the camera sees a side wall, which a top-face-only model would
  read as a shift of the tile.
- **The fit**: the squared difference of the two, summed over the window, minimised over
  ``theta`` on a coarse grid over one symmetry period (the position held at the blob's centroid
  unprojected), then over ``(x, y, theta)`` from the best grid minima with Nelder-Mead.

``theta`` is the tile's yaw minus the slot's, modulo ``2 pi / symmetry`` (0 for a round tile).
Nothing here reads the env's state: only the image, the camera model and the task description.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np
from scipy.optimize import minimize
from shapely.geometry import Polygon

from envs.cell.cameras import CameraModel
from envs.task_spec import Area, WorldSlot
from spatial.angles import symmetry_period
from spatial.units import MM_PER_M

SHIFT = 4
"""Fractional bits of the polygon vertices given to OpenCV (1/16 of a canvas pixel)."""


@dataclass(frozen=True)
class FitConfig:
    """Settings of the tile pose fit.

    Attributes:
        margin: Window margin around the blob's bounding box, as a share of its larger side.
        min_margin_px: Smallest window margin [px].
        canvas_px: Target side of the supersampled drawing canvas [px] (sets ``supersample``).
        min_supersample: Smallest drawing supersampling factor (the coverage moves in steps of
            1 / it of a pixel: a coarse one leaves the cost flat over a fraction of a pixel).
        max_supersample: Largest drawing supersampling factor.
        coarse_step_deg: Step of the coarse grid over theta [deg].
        starts: Best distinct coarse minima refined by Nelder-Mead.
        start_separation_deg: Two coarse minima closer than this count as one [deg].
        simplex_mm: Initial Nelder-Mead step of x and y [mm].
        simplex_deg: Initial Nelder-Mead step of theta [deg].
        tolerance: Nelder-Mead tolerance on the parameters (mm and deg) and the cost.
        max_evaluations: Largest number of cost evaluations of one Nelder-Mead run.
        prism: Draw the whole silhouette (top, bottom, side walls); False: the top face only.
    """

    margin: float = 0.25
    min_margin_px: int = 2
    canvas_px: int = 384
    min_supersample: int = 8
    max_supersample: int = 16
    coarse_step_deg: float = 2.0
    starts: int = 2
    start_separation_deg: float = 20.0
    simplex_mm: float = 0.5
    simplex_deg: float = 2.0
    tolerance: float = 0.01
    max_evaluations: int = 300
    prism: bool = False


@dataclass(frozen=True)
class TileFit:
    """A fitted tile pose.

    Attributes:
        xy: World (x, y) of the tile's area centroid, shape (2,) [m].
        theta: Tile yaw minus the slot's yaw, in [0, 2 pi / symmetry) [rad] (0: round tile).
        cost: Mean squared difference of the window's alpha and the fitted coverage.
    """

    xy: np.ndarray
    theta: float
    cost: float


def figure_outline(slot: WorldSlot) -> tuple[np.ndarray, list[np.ndarray]]:
    """A slot's figure about its area centroid at the slot's yaw [m]: outer (m, 2), holes."""
    outer = np.asarray(slot.figure.outer.dense(), float) / MM_PER_M
    centroid = np.asarray(Polygon(outer).centroid.coords[0])
    holes = [np.asarray(h.dense(), float) / MM_PER_M - centroid for h in slot.figure.holes]
    return outer - centroid, holes


class _Window:
    """One blob's image window: its alpha, weights and the coverage a pose predicts."""

    def __init__(
        self,
        image: np.ndarray,
        labels: np.ndarray,
        label: int,
        *,
        camera: CameraModel,
        area: Area,
        cfg: FitConfig,
    ) -> None:
        rows, cols = np.nonzero(labels == label)
        side = max(np.ptp(rows), np.ptp(cols)) + 1
        m = max(cfg.min_margin_px, math.ceil(cfg.margin * side))
        h, w = labels.shape
        self.v0, self.u0 = max(rows.min() - m, 0), max(cols.min() - m, 0)
        v1, u1 = min(rows.max() + m + 1, h), min(cols.max() + m + 1, w)
        self.shape = (v1 - self.v0, u1 - self.u0)
        self.s = int(
            np.clip(cfg.canvas_px // max(self.shape), cfg.min_supersample, cfg.max_supersample)
        )
        win = (slice(self.v0, v1), slice(self.u0, u1))
        self.alpha = tile_alpha(image, labels == label)[win]
        others = ((labels != 0) & (labels != label)).astype(np.uint8)
        others = cv2.dilate(others, np.ones((3, 3), np.uint8))[win]  # their edges too
        self.weight = (others == 0).astype(np.float32)
        self.camera, self.area, self.cfg = camera, area, cfg
        self.centroid = np.array([cols.mean(), rows.mean()])

    def canvas_points(self, xy_world: np.ndarray, z: float) -> np.ndarray:
        """World points (m, 2) on the plane at z -> fixed-point canvas vertices (m, 2) int32."""
        pts = np.column_stack([xy_world, np.full(len(xy_world), z)])
        uv = self.camera.project(pts) - (self.u0, self.v0)
        return np.round(((uv + 0.5) * self.s - 0.5) * (1 << SHIFT)).astype(np.int32)

    def coverage(
        self, outline: tuple[np.ndarray, list[np.ndarray]], pose: np.ndarray
    ) -> np.ndarray:
        """Share of each window pixel covered by the tile at pose (x, y, theta), (h, w) float32."""
        c, s = math.cos(pose[2]), math.sin(pose[2])
        rot = np.array([[c, -s], [s, c]])
        outer = outline[0] @ rot.T + pose[:2]
        canvas = np.zeros((self.shape[0] * self.s, self.shape[1] * self.s), np.uint8)
        top = self.canvas_points(outer, self.area.tile_top_z)
        polys = [top]
        if self.cfg.prism:
            bottom = self.canvas_points(outer, self.area.surface_z)
            nxt = np.roll(np.arange(len(top)), -1)
            polys += [bottom]
            polys += [np.stack([top[i], top[j], bottom[j], bottom[i]]) for i, j in enumerate(nxt)]
        for poly in polys:  # one call each: OpenCV fills several polygons even-odd
            cv2.fillPoly(canvas, [poly], 255, lineType=cv2.LINE_8, shift=SHIFT)
        for hole in outline[1]:
            pts = self.canvas_points(hole @ rot.T + pose[:2], self.area.tile_top_z)
            cv2.fillPoly(canvas, [pts], 0, lineType=cv2.LINE_8, shift=SHIFT)
        small = cv2.resize(canvas, self.shape[::-1], interpolation=cv2.INTER_AREA)
        return small.astype(np.float32) / 255.0

    def cost(self, outline: tuple[np.ndarray, list[np.ndarray]], pose: np.ndarray) -> float:
        """Weighted mean squared difference of the alpha and the coverage at a pose."""
        d = (self.coverage(outline, pose) - self.alpha) * self.weight
        return float((d * d).sum() / max(self.weight.sum(), 1.0))


def tile_alpha(image: np.ndarray, blob: np.ndarray) -> np.ndarray:
    """Each pixel unmixed between the belt colour and the blob's colour, (H, W) float32 in [0, 1].

    Args:
        image: RGB image, shape (H, W, 3) uint8.
        blob: The tile's pixels, shape (H, W) bool.
    """
    img = np.asarray(image, np.float32)
    belt = np.median(img.reshape(-1, 3), axis=0)
    tile = np.median(img[blob], axis=0)
    d = tile - belt
    a = ((img - belt) @ d) / max(float(d @ d), 1.0)
    return np.clip(a, 0.0, 1.0).astype(np.float32)


def fit_tile(
    image: np.ndarray,
    labels: np.ndarray,
    label: int,
    *,
    camera: CameraModel,
    area: Area,
    slot: WorldSlot,
    cfg: FitConfig,
) -> TileFit:
    """Fit the slot's figure to blob ``label`` of an image (see the module docstring).

    Args:
        image: RGB image, shape (H, W, 3) uint8.
        labels: Blob label of every pixel (0: background), shape (H, W) int.
        label: The tile's blob.
        camera: The image's camera model.
        area: The area the tile rests on (its surface and top heights).
        slot: A slot of the tile's class (its figure and yaw).
        cfg: Fit settings.
    """
    win = _Window(image, labels, label, camera=camera, area=area, cfg=cfg)
    outline = figure_outline(slot)
    xy0 = camera.unproject_to_plane(win.centroid[None], area.tile_top_z)[0, :2]
    period = symmetry_period(slot.symmetry)
    starts = [0.0]
    if period > 0:
        grid = np.arange(0.0, period, math.radians(cfg.coarse_step_deg))
        costs = np.array([win.cost(outline, np.array([*xy0, t])) for t in grid])
        starts = _distinct_minima(grid, costs, period, cfg)
    scale = np.array([1 / MM_PER_M, 1 / MM_PER_M, math.radians(1.0)])  # mm, mm, deg -> m, m, rad
    best: TileFit | None = None
    for t0 in starts:
        x0 = np.array([*xy0, t0]) / scale
        step = np.diag([cfg.simplex_mm, cfg.simplex_mm, cfg.simplex_deg])
        res = minimize(
            lambda p: win.cost(outline, p * scale),
            x0,
            method="Nelder-Mead",
            options={
                "initial_simplex": np.vstack([x0, x0 + step]),
                "xatol": cfg.tolerance,
                "fatol": cfg.tolerance * 1e-4,
                "maxfev": cfg.max_evaluations,
            },
        )
        pose = res.x * scale
        theta = float(pose[2] % period) if period > 0 else 0.0
        if best is None or res.fun < best.cost:
            best = TileFit(pose[:2].copy(), theta, float(res.fun))
    assert best is not None
    return best


def _distinct_minima(
    grid: np.ndarray, costs: np.ndarray, period: float, cfg: FitConfig
) -> list[float]:
    """The ``cfg.starts`` lowest grid points at least ``start_separation_deg`` apart (circular)."""
    sep = math.radians(cfg.start_separation_deg)
    chosen: list[float] = []
    for i in np.argsort(costs):
        t = float(grid[i])
        if all(abs(math.remainder(t - c, period)) >= sep for c in chosen):
            chosen.append(t)
        if len(chosen) == cfg.starts:
            break
    return chosen


__all__ = [
    "FitConfig",
    "TileFit",
    "figure_outline",
    "fit_tile",
    "tile_alpha",
]
