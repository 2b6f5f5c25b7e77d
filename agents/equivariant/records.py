"""Demonstrated decision steps as crops, and their file.

A `StepRecords` holds, per demonstrated step, what the policy reads (the tile crops of the
input image, the slot crops of the output image, the slots' figure masks) and the answer: the
tile and slot indices of the env's discrete action and the in-plane turn that lays the tile's
crop on the slot's (``turn`` [rad], counter-clockwise; right modulo the slot's symmetry). The
turn, not a rotation index, is stored, so one file trains a policy for any ``rotation_frame``
and ``rotation_bins``.

Crops are stored as bytes (0-255) in a compressed ``.npz`` with a header naming the task, the
image size, the camera level, the data source and the crop settings; `load_records` refuses a
file whose header does not match what the training asks for, naming both.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from agents.camera.crops import slot_templates, step_crops
from agents.equivariant.config import EquivariantConfig
from agents.errors import AgentError

FORMAT = "equivariant-steps-1"
"""The ``format`` entry of a records file's header."""
CROP_KEYS = ("grid", "pitch", "foreground", "min_blob_px", "supersample", "template")
"""Settings that change the crops (a file must match the training's)."""
SOURCES = ("expert", "disassembly")
"""Where demonstrations come from (`agents.equivariant.collect`)."""


class RecordsError(AgentError):
    """A demonstrations file that is missing, unreadable or made for something else."""


@dataclass(frozen=True)
class Header:
    """What a records file was made for.

    Attributes:
        task: Task id the steps were recorded on (training designs of its rung).
        image_size: Camera image (height, width) [px].
        camera: Camera level name (``ideal``, ``realistic``).
        source: ``expert`` or ``disassembly``.
        crop: The crop settings (`CROP_KEYS` of `EquivariantConfig`).
        episodes: Episodes recorded.
    """

    task: str
    image_size: tuple[int, int]
    camera: str
    source: str
    crop: dict[str, Any]
    episodes: int


@dataclass(frozen=True)
class StepRecords:
    """Demonstrated steps as crops.

    Attributes:
        header: What they were made for.
        tiles: Tile crops, (N, n, 4, G, G) uint8 (zeros past the tiles seen).
        tile_ok: Tiles seen and allowed by the action mask, (N, n) bool.
        slots: Slot inputs, (N, k, C, G, G) uint8.
        slot_ok: Slots allowed by the action mask (open), (N, k) bool.
        symmetry: Each slot's figure symmetry order, (N, k) int (0: round).
        tile: Demonstrated tile index, (N,) int.
        slot: Demonstrated slot index, (N,) int.
        turn: Turn laying the tile's crop on the slot's [rad], (N,) float.
        episode: Episode number of each step, (N,) int.
    """

    header: Header
    tiles: np.ndarray
    tile_ok: np.ndarray
    slots: np.ndarray
    slot_ok: np.ndarray
    symmetry: np.ndarray
    tile: np.ndarray
    slot: np.ndarray
    turn: np.ndarray
    episode: np.ndarray

    def first_episodes(self, count: int) -> StepRecords:
        """The steps of the first ``count`` episodes (in recording order)."""
        kept = np.unique(self.episode)[:count]
        m = np.isin(self.episode, kept)
        h = self.header
        header = Header(h.task, h.image_size, h.camera, h.source, h.crop, len(kept))
        return StepRecords(
            header,
            *(getattr(self, f)[m] for f in ARRAYS),
        )


ARRAYS = ("tiles", "tile_ok", "slots", "slot_ok", "symmetry", "tile", "slot", "turn", "episode")
"""The array fields of `StepRecords`, in order."""


def crop_settings(cfg: EquivariantConfig) -> dict[str, Any]:
    """The settings of ``cfg`` that change the crops."""
    return {k: getattr(cfg, k) for k in CROP_KEYS}


def to_bytes(x: np.ndarray) -> np.ndarray:
    """Crops in [0, 1] as uint8."""
    return np.clip(np.round(x * 255), 0, 255).astype(np.uint8)


def from_bytes(x: np.ndarray) -> np.ndarray:
    """uint8 crops as float32 in [0, 1]."""
    return x.astype(np.float32) / 255


class CropCutter:
    """Cuts an observation into the policy's inputs (keeps the slot figures per task spec)."""

    def __init__(self, cfg: EquivariantConfig) -> None:
        self.cfg = cfg
        self.crop = cfg.crop()
        self._spec: Any = None
        self._figures: np.ndarray | None = None

    def __call__(self, obs: dict[str, Any], spec: Any) -> tuple[np.ndarray, np.ndarray, Any]:
        """(tile crops (m, 4, G, G), slot inputs (k, C, G, G), the blobs found), floats in [0, 1].

        A tile crop is its mask and the RGB inside it; a slot's input the output image's crop
        (mask and RGB inside it) and, with ``template``, the slot's figure mask. Tiles are the
        blobs of the input image in the env's tile order; slots in raster order on the mesh.
        """
        crops, found = step_crops(obs, spec, self.crop)
        tiles = crops.tiles.copy()
        tiles[:, 1:] *= tiles[:, :1]
        mesh = crops.mesh.copy()
        mesh[:, 1:] *= mesh[:, :1]
        if self.cfg.template:
            if self._spec is not spec:  # the spec itself is kept: a freed one's id can recur
                self._spec, self._figures = spec, slot_templates(spec, self.crop)
            assert self._figures is not None
            mesh = np.concatenate([mesh, self._figures], axis=1)
        return tiles, mesh, found


def save_records(path: str | Path, rec: StepRecords) -> Path:
    """Write records (compressed ``.npz`` with a JSON header); returns the path."""
    from configs.files import atomic_path  # noqa: PLC0415

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    h = rec.header
    head = {
        "format": FORMAT,
        "task": h.task,
        "image_size": list(h.image_size),
        "camera": h.camera,
        "source": h.source,
        "crop": h.crop,
        "episodes": h.episodes,
    }
    with atomic_path(path) as tmp, open(tmp, "wb") as f:
        np.savez_compressed(
            f, header=np.array(json.dumps(head)), **{k: getattr(rec, k) for k in ARRAYS}
        )
    return path


def load_records(
    path: str | Path,
    *,
    task: str | None = None,
    cfg: EquivariantConfig | None = None,
    image_size: tuple[int, int] | None = None,
) -> StepRecords:
    """Read a records file, refusing one made for another task, crop or image size.

    Raises:
        RecordsError: No such file, not a records file, or a header that differs from what
            is asked for (the message names both).
    """
    try:
        with np.load(path, allow_pickle=False) as z:
            head = json.loads(str(z["header"]))
            arrays = {k: z[k] for k in ARRAYS}
    except (OSError, KeyError, ValueError) as exc:
        raise RecordsError(f"{path} is not a demonstrations file ({type(exc).__name__})") from exc
    if head.get("format") != FORMAT:
        raise RecordsError(f"{path}: format {head.get('format')!r}, expected {FORMAT!r}")
    header = Header(
        str(head["task"]),
        (int(head["image_size"][0]), int(head["image_size"][1])),
        str(head["camera"]),
        str(head["source"]),
        dict(head["crop"]),
        int(head["episodes"]),
    )
    if task is not None and header.task != task:
        raise RecordsError(f"{path} holds demonstrations of {header.task}, not of {task}")
    if cfg is not None and header.crop != crop_settings(cfg):
        raise RecordsError(
            f"{path} was cut with crop settings {header.crop}; the training uses "
            f"{crop_settings(cfg)}"
        )
    if image_size is not None and header.image_size != tuple(image_size):
        raise RecordsError(
            f"{path} holds {header.image_size[0]}x{header.image_size[1]} images; expected "
            f"{image_size[0]}x{image_size[1]}"
        )
    return StepRecords(header, *(arrays[k] for k in ARRAYS))


def join_records(parts: list[StepRecords]) -> StepRecords:
    """Records of several runs as one (same task, crops and shapes); episodes renumbered.

    Raises:
        RecordsError: No part, or parts made for different things.
    """
    if not parts:
        raise RecordsError("no demonstrations to join")
    first = parts[0].header
    for p in parts[1:]:
        h = p.header
        if (h.task, h.image_size, h.camera, h.crop) != (
            first.task,
            first.image_size,
            first.camera,
            first.crop,
        ):
            raise RecordsError(f"cannot join records of {h} with records of {first}")
    offset, eps = 0, []
    for p in parts:
        eps.append(p.episode + offset)
        offset += int(p.episode.max()) + 1 if len(p.episode) else 0
    header = Header(
        first.task,
        first.image_size,
        first.camera,
        "+".join(sorted({p.header.source for p in parts})),
        first.crop,
        sum(p.header.episodes for p in parts),
    )
    cat = {k: np.concatenate([getattr(p, k) for p in parts]) for k in ARRAYS}
    cat["episode"] = np.concatenate(eps)
    return StepRecords(header, *(cat[k] for k in ARRAYS))


__all__ = [
    "ARRAYS",
    "CROP_KEYS",
    "FORMAT",
    "SOURCES",
    "CropCutter",
    "Header",
    "RecordsError",
    "StepRecords",
    "crop_settings",
    "from_bytes",
    "join_records",
    "load_records",
    "save_records",
    "to_bytes",
]
