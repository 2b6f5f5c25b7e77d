"""Object-centric crops of the two camera images for the crop scorer (`agents.camera.crop_scorer`).

Everything here reads only an observation's ``input_camera`` and ``output_camera`` images and
the env's public `TaskSpec` (camera models at the observation size, the slots' figures, colours
and poses, the areas' heights):

- **Tiles** (`belt_tiles`): pixels of the input-belt image that differ from the belt's colour
  (the image's median colour) form connected blobs; each blob's centroid is mapped onto the
  tiles' top plane through the input camera model. Tile index ``i`` of the discrete action is
  the ``i``-th blob counted from the belt's downstream end (largest world x first, then y), the
  env's documented ``tile_order: belt``.
- **Crops** (`world_crop`): a square grid of world points around a position, ``grid`` x
  ``grid`` cells of ``pitch`` metres, world-aligned (row 0 at the largest y, column 0 at the
  smallest x), sampled bilinearly from an image through its camera model. A quarter turn of a
  crop (``np.rot90``) is a quarter turn in the world (counter-clockwise seen from above).
- **Slot templates** (`slot_template`): each slot's figure drawn on the same grid (its mask and
  its design colour), at the slot's yaw, centred on its area centroid.
- **Slot order** (`mesh_order`): slot index ``j`` of the discrete action is the ``j``-th slot in
  raster order on the mesh (top row first, left to right), the env's ``slot_order: mesh``.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from shapely.geometry import Polygon

from envs.cell.cameras import CameraModel
from envs.indexing import raster_order
from envs.task_spec import TaskSpec, WorldSlot
from spatial.units import MM_PER_M

CHANNELS = 4
"""Channels of a tile crop and a slot template: foreground mask, then red, green, blue in [0, 1]."""


@dataclass(frozen=True)
class CropConfig:
    """How the images are cut into object-centric crops.

    Attributes:
        grid: Cells per side of a crop.
        pitch: Cell size [m] (a crop spans ``grid * pitch`` metres).
        foreground: Colour distance from the belt's median colour that marks a tile pixel
            [0-255 per channel, max over channels].
        min_blob_px: Smallest blob counted as a tile [px].
        supersample: Template drawing resolution over the grid's (anti-aliasing factor).
    """

    grid: int = 20
    pitch: float = 0.003
    foreground: float = 40.0
    min_blob_px: int = 6
    supersample: int = 4


@dataclass(frozen=True)
class BeltTiles:
    """The tiles seen on the input belt, in the env's tile order.

    Attributes:
        xy: World (x, y) of each blob's centroid on the tiles' top plane, shape (n, 2) [m].
        labels: Blob label of every input-image pixel (0: belt; blob ``i`` is ``i + 1``),
            shape (H, W) int32.
    """

    xy: np.ndarray
    labels: np.ndarray


def foreground_mask(image: np.ndarray, cfg: CropConfig) -> np.ndarray:
    """Pixels that differ from the image's median colour by more than ``cfg.foreground``, (H, W)."""
    img = np.asarray(image, np.int16)
    belt = np.median(img.reshape(-1, 3), axis=0)
    return np.abs(img - belt).max(axis=2) > cfg.foreground


def belt_tiles(image: np.ndarray, camera: CameraModel, z: float, cfg: CropConfig) -> BeltTiles:
    """Segment the input-belt image into tiles, ordered as the env orders tile indices.

    Args:
        image: The ``input_camera`` image, shape (H, W, 3) uint8.
        camera: The input camera model at the image's size.
        z: Height of a resting tile's top face [m] (``TaskSpec.pick.tile_top_z``).
        cfg: Segmentation settings.
    """
    mask = foreground_mask(image, cfg).astype(np.uint8)
    count, labels, stats, centroids = cv2.connectedComponentsWithStats(mask, connectivity=8)
    keep = [k for k in range(1, count) if stats[k, cv2.CC_STAT_AREA] >= cfg.min_blob_px]
    if not keep:
        return BeltTiles(np.zeros((0, 2)), np.zeros(mask.shape, np.int32))
    xy = camera.unproject_to_plane(centroids[keep], z)[:, :2]
    order = np.lexsort((xy[:, 1], -xy[:, 0]))
    relabel = np.zeros(count, np.int32)
    for rank, k in enumerate(order):
        relabel[keep[k]] = rank + 1
    return BeltTiles(xy[order], relabel[labels])


def grid_points(centre: np.ndarray, z: float, cfg: CropConfig) -> np.ndarray:
    """World points of a crop's cells, shape (grid, grid, 3) [m] (row 0: largest y)."""
    half = (cfg.grid - 1) / 2
    off = (np.arange(cfg.grid) - half) * cfg.pitch
    xs = centre[0] + off[None, :].repeat(cfg.grid, 0)
    ys = centre[1] - off[:, None].repeat(cfg.grid, 1)
    return np.stack([xs, ys, np.full_like(xs, z)], axis=-1)


def crop_planes(image: np.ndarray, cfg: CropConfig) -> np.ndarray:
    """The planes crops are sampled from: foreground mask, then RGB in [0, 1], (H, W, 4) float32."""
    fg = foreground_mask(image, cfg).astype(np.float32)
    return np.dstack([fg, np.asarray(image, np.float32) / 255.0])


def world_crops(
    planes: np.ndarray, camera: CameraModel, centres: np.ndarray, z: float, cfg: CropConfig
) -> np.ndarray:
    """World-aligned crops of one image's `crop_planes` around each centre on the plane at ``z``.

    Returns:
        Shape (m, CHANNELS, grid, grid) float32: the foreground mask, then RGB in [0, 1].
    """
    g = cfg.grid
    if len(centres) == 0:
        return np.zeros((0, CHANNELS, g, g), np.float32)
    pts = np.concatenate([grid_points(c, z, cfg).reshape(-1, 3) for c in centres])
    uv = camera.project(pts).astype(np.float32).reshape(len(centres) * g, g, 2)
    out = cv2.remap(planes, uv[..., 0], uv[..., 1], cv2.INTER_LINEAR, borderValue=0.0)
    return np.ascontiguousarray(
        np.transpose(out.reshape(len(centres), g, g, CHANNELS), (0, 3, 1, 2)), np.float32
    )


def world_crop(
    image: np.ndarray, camera: CameraModel, centre: np.ndarray, z: float, cfg: CropConfig
) -> np.ndarray:
    """A world-aligned crop of an image around ``centre`` on the plane at ``z``.

    Returns:
        Shape (CHANNELS, grid, grid) float32: the foreground mask, then RGB in [0, 1].
    """
    return world_crops(crop_planes(image, cfg), camera, np.asarray([centre]), z, cfg)[0]


def slot_template(slot: WorldSlot, cfg: CropConfig) -> np.ndarray:
    """A slot's figure drawn on a crop grid centred on its area centroid, at its yaw.

    Returns:
        Shape (CHANNELS, grid, grid) float32: the figure's mask, then its colour inside it.
    """
    pts = np.asarray(slot.figure.outer.dense(), float) / MM_PER_M
    centroid = np.asarray(Polygon(pts).centroid.coords[0])
    s = cfg.supersample
    half = (cfg.grid * s - 1) / 2
    cols = (pts[:, 0] - centroid[0]) / cfg.pitch * s + half
    rows = -(pts[:, 1] - centroid[1]) / cfg.pitch * s + half
    big = np.zeros((cfg.grid * s, cfg.grid * s), np.uint8)
    shift = 4
    poly = np.round(np.stack([cols, rows], 1) * (1 << shift)).astype(np.int32)
    cv2.fillPoly(big, [poly], 255, lineType=cv2.LINE_8, shift=shift)
    for hole in slot.figure.holes:
        hp = np.asarray(hole.dense(), float) / MM_PER_M
        hc = (hp[:, 0] - centroid[0]) / cfg.pitch * s + half
        hr = -(hp[:, 1] - centroid[1]) / cfg.pitch * s + half
        hpoly = np.round(np.stack([hc, hr], 1) * (1 << shift)).astype(np.int32)
        cv2.fillPoly(big, [hpoly], 0, lineType=cv2.LINE_8, shift=shift)
    mask = cv2.resize(big, (cfg.grid, cfg.grid), interpolation=cv2.INTER_AREA) / 255.0
    rgb = np.asarray(slot.color, np.float32)[:, None, None] * mask[None]
    return np.concatenate([mask[None], rgb]).astype(np.float32)


def mesh_order(spec: TaskSpec) -> np.ndarray:
    """Design slot index of each discrete slot index (raster order on the mesh), shape (k,)."""
    if not spec.slots:
        return np.zeros(0, int)
    return raster_order(np.stack([s.xy for s in spec.slots]))


@dataclass(frozen=True)
class StepCrops:
    """The crops of one observation.

    Attributes:
        tiles: Tile crops in tile-index order, shape (n, CHANNELS, grid, grid) float32.
        mesh: Output-image crops at each slot, in slot-index order, shape
            (k, CHANNELS, grid, grid) float32.
    """

    tiles: np.ndarray
    mesh: np.ndarray


def slot_templates(spec: TaskSpec, cfg: CropConfig) -> np.ndarray:
    """Templates of the slots in slot-index order, shape (k, CHANNELS, grid, grid)."""
    order = mesh_order(spec)
    return np.stack([slot_template(spec.slots[int(j)], cfg) for j in order])


def step_crops(
    obs: dict[str, np.ndarray], spec: TaskSpec, cfg: CropConfig
) -> tuple[StepCrops, BeltTiles]:
    """The tile and mesh crops of an observation (and the tiles it found)."""
    cam_in, cam_out = spec.camera("input_camera"), spec.camera("output_camera")
    found = belt_tiles(obs["input_camera"], cam_in, spec.pick.tile_top_z, cfg)
    planes_in = crop_planes(obs["input_camera"], cfg)
    tiles = world_crops(planes_in, cam_in, found.xy, spec.pick.tile_top_z, cfg)
    order = mesh_order(spec)
    centres = np.array([spec.slots[int(j)].xy for j in order])
    planes_out = crop_planes(obs["output_camera"], cfg)
    mesh = world_crops(planes_out, cam_out, centres, spec.place.tile_top_z, cfg)
    return StepCrops(tiles, mesh), found


__all__ = [
    "CHANNELS",
    "BeltTiles",
    "CropConfig",
    "StepCrops",
    "belt_tiles",
    "foreground_mask",
    "grid_points",
    "mesh_order",
    "slot_template",
    "slot_templates",
    "step_crops",
    "world_crop",
]
