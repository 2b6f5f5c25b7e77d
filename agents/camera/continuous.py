"""The camera policy in the continuous ``pick_place`` action mode.

It answers with the world points and the turn, not indices. Each step:

1. **Which tile and slot** (`agents.camera.crop_scorer.CameraPolicy`, the trained crop scorer): the
   best-scored ``(tile i, slot j, quarter turn r)``. The scorer reads images at the size it was
   trained on; a larger observation is averaged down to it (``INTER_AREA``) with the camera
   models scaled to match.
   ``pick_place`` has no action mask: a scorer that takes one (the equivariant policy,
   `agents.equivariant.policy`) is not offered the slots this policy placed into earlier in
   the episode (`reset` at each episode start); the crop scorer plays as it always did.
2. **Where the tile is and how it lies** (`agents.camera.tile_fit.fit_tile`): slot ``j``'s published
   figure fitted to tile ``i``'s pixels in the full-size input image, through the input camera
   model: the tile's area centroid (x, y) on the tiles' top plane and its yaw relative to the
   slot, ``theta``, modulo the figure's symmetry, both sub-pixel.
3. **The command**: pick at the fitted centroid (the pad's grasp point is the tile's area
   centroid), place at the slot's area centroid (`TaskSpec.slots`), turn by the rotation that
   brings the fitted pose onto the slot's, ``-theta + k * 2 pi / symmetry``, with ``k`` taking
   the one nearest to the scorer's ``r`` quarter turns (the scorer only breaks ties between
   turns the figure makes equivalent; a round tile is not turned). ``TaskSpec.codec`` encodes
   it (the ``-v0`` Box(6) layout carries the fitted tile yaw, ``-v1`` Box(5) does not).

Only the observation's images and the public `TaskSpec` are read; the env's state never.
"""

from __future__ import annotations

import dataclasses
import inspect
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from agents.camera.crop_scorer import CameraPolicy
from agents.camera.crops import belt_tiles, mesh_order
from agents.camera.tile_fit import FitConfig, TileFit, fit_tile
from agents.errors import AgentError
from configs import load_config
from envs.cell.cameras import CameraModel
from envs.task_spec import CameraName, PickPlaceCommand, TaskSpec
from spatial.angles import symmetry_period

TILE_FIT_CONFIG = "tile_fit"
"""Bundled config name of the pose fit (``configs/tile_fit.yaml``)."""
CAMERAS: tuple[CameraName, ...] = ("input_camera", "output_camera")
"""The observation's images the policy reads."""
QUARTER = math.pi / 2
"""The scorer's turn step [rad]."""
QUARTER_TURNS = 4
"""Rotation indices of the scorer's logits in ``pick_place`` (quarter turns)."""


def load_fit_config(name_or_path: str | Path = TILE_FIT_CONFIG, **overrides: Any) -> FitConfig:
    """Load a `FitConfig` strictly from ``configs/`` (by name) or a path."""
    return load_config(FitConfig, name_or_path, **overrides)


@dataclass(frozen=True)
class Decision:
    """What the policy chose in one step.

    Attributes:
        tile: The scorer's tile index (rank of the blob on the belt).
        slot: Design index of the slot (`TaskSpec.slots`).
        quarter_turns: The scorer's quarter turn ``r``.
        fit: The tile's fitted pose.
        command: The world command sent.
        action: The normalised action, shape (codec size,) float32.
    """

    tile: int
    slot: int
    quarter_turns: int
    fit: TileFit
    command: PickPlaceCommand
    action: np.ndarray


def scaled_camera(camera: CameraModel, height: int, width: int) -> CameraModel:
    """The same camera at another image size (pixel centres kept: ``u' = (u + 0.5) s - 0.5``)."""
    sx, sy = width / camera.width, height / camera.height
    k = camera.K.copy()
    k[0, 0], k[0, 1], k[1, 1] = k[0, 0] * sx, k[0, 1] * sx, k[1, 1] * sy
    k[0, 2], k[1, 2] = (k[0, 2] + 0.5) * sx - 0.5, (k[1, 2] + 0.5) * sy - 0.5
    return dataclasses.replace(camera, width=width, height=height, K=k)


def at_size(
    obs: dict[str, Any], spec: TaskSpec, size: tuple[int, int]
) -> tuple[dict[str, Any], TaskSpec]:
    """The observation's images averaged down to ``size`` (h, w) and the spec's cameras to match."""
    h, w = size
    if tuple(np.asarray(obs["input_camera"]).shape[:2]) == (h, w):
        return obs, spec
    small = dict(obs)
    cameras = dict(spec.cameras)
    for name in CAMERAS:
        small[name] = cv2.resize(np.asarray(obs[name]), (w, h), interpolation=cv2.INTER_AREA)
        cameras[name] = scaled_camera(spec.camera(name), h, w)
    return small, dataclasses.replace(spec, cameras=cameras, image_size=(h, w))


def rotation_for(theta: float, symmetry: int, quarter_turns: int) -> float:
    """Turn [rad] bringing a tile at ``theta`` from the slot onto it, nearest ``r`` quarter turns.

    The candidates are ``-theta + k * 2 pi / symmetry``; a round tile (symmetry 0) is not
    turned. The result is wrapped to (-pi, pi].
    """
    period = symmetry_period(symmetry)
    if period == 0:
        return 0.0
    want = quarter_turns * QUARTER
    k = round((want + theta) / period)
    return float(math.remainder(-theta + k * period, 2 * math.pi))


class ContinuousCameraPolicy:
    """The crop scorer's choice executed as a continuous ``pick_place`` action.

    Args:
        scorer: The trained crop scorer.
        fit: Pose fit settings.
    """

    def __init__(self, scorer: CameraPolicy, fit: FitConfig) -> None:
        self.scorer = scorer
        self.fit = fit
        self._placed: set[int] = set()
        self._masked = "masks" in inspect.signature(scorer.logits).parameters

    def reset(self) -> None:
        """Episode start: forget the slots placed into (see `decide`)."""
        self._placed.clear()

    @classmethod
    def load(cls, path: str | Path, fit: FitConfig | None = None) -> ContinuousCameraPolicy:
        """A saved camera policy with the bundled fit settings.

        The file's ``kind`` says which scorer: ``camera_crops`` (`CameraPolicy`) or
        ``equivariant`` (`agents.equivariant.policy.EquivariantPolicy`).
        """
        from agents.camera.crop_scorer import read_policy_file  # noqa: PLC0415
        from agents.equivariant.policy import KIND, EquivariantPolicy  # noqa: PLC0415

        scorer: Any = (
            EquivariantPolicy.load(path)
            if read_policy_file(path).get("kind") == KIND
            else CameraPolicy.load(path)
        )
        return cls(scorer, fit if fit is not None else load_fit_config())

    def decide(self, obs: dict[str, Any], spec: TaskSpec) -> Decision | None:
        """The step's choice, or None when no tile is seen.

        Raises:
            AgentError: The env has no ``pick_place`` codec (another action mode).
        """
        if spec.codec is None:
            raise AgentError(
                "the continuous camera policy needs action_mode pick_place, "
                f"not {spec.action_mode!r}"
            )
        small_obs, small_spec = at_size(obs, spec, self.scorer.image_size)
        crop = self.scorer.crop
        z = spec.pick.tile_top_z
        seen = belt_tiles(small_obs["input_camera"], small_spec.camera("input_camera"), z, crop)
        order = mesh_order(spec)
        if self._masked:  # a scorer that takes masks: not the slots it placed into already
            open_slots = np.array([int(j) not in self._placed for j in order])
            n = len(seen.xy)
            masks = np.concatenate([np.ones(n, bool), open_slots, np.ones(QUARTER_TURNS, bool)])
            scorer: Any = self.scorer  # an `EquivariantPolicy`
            scores = scorer.logits(small_obs, small_spec, masks)
        else:
            scores = self.scorer.logits(small_obs, small_spec)
        if scores.size == 0:
            return None
        i, j, r = (int(v) for v in np.unravel_index(int(scores.argmax()), scores.shape))
        camera = spec.camera("input_camera")
        full = belt_tiles(obs["input_camera"], camera, z, crop)
        label = int(np.linalg.norm(full.xy - seen.xy[i], axis=1).argmin()) + 1
        slot = spec.slots[int(order[j])]
        fit = fit_tile(
            obs["input_camera"],
            full.labels,
            label,
            camera=camera,
            area=spec.pick,
            slot=slot,
            cfg=self.fit,
        )
        rotation = rotation_for(fit.theta, slot.symmetry, r)
        command = PickPlaceCommand(
            (float(fit.xy[0]), float(fit.xy[1])),
            float(math.remainder(slot.yaw + fit.theta, 2 * math.pi)),
            (float(slot.xy[0]), float(slot.xy[1])),
            rotation,
        )
        self._placed.add(slot.index)
        return Decision(i, slot.index, r, fit, command, spec.codec.encode(command))

    def predict(self, obs: dict[str, Any], spec: TaskSpec) -> tuple[np.ndarray, None]:
        """The action (``gymnasium`` style); a pick at the area's centre when no tile is seen."""
        decision = self.decide(obs, spec)
        if decision is None:
            assert spec.codec is not None  # decide checked it
            return np.zeros(spec.codec.size, np.float32), None
        return decision.action, None


__all__ = [
    "TILE_FIT_CONFIG",
    "ContinuousCameraPolicy",
    "Decision",
    "at_size",
    "load_fit_config",
    "rotation_for",
    "scaled_camera",
]
