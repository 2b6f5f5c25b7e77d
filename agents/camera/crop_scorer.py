"""A decision-level policy that reads the two camera images: a (tile, slot, turn) crop scorer.

Transporter-like in spirit, object-centric in form. `agents.camera.crops` cuts the
observation into world-aligned crops: one per tile seen on the input belt (at the 4 quarter
turns) and one per slot of the output image, and draws each slot's figure from the public
`TaskSpec` on the same grid. Two small convolutional encoders embed them: ``tile_net`` a
turned tile crop, ``slot_net`` a slot's template stacked with its output-image crop (which shows
the slot's printed outline and whether a tile already fills it). The logit of the discrete
action ``(tile i, slot j, rotation r)`` is

    <tile_net(turn(crop_i, r)), slot_net(slot_j)> / sqrt(embed) + bias(slot_j)

plus, with ``correlate``, a Transporter-style correlation of the two crops' dense feature maps
at zero offset (both crops are centred on the object, world-aligned):

    + w * mean over cells <dense_t(turn(crop_i, r)), dense_s(slot_j)>

where ``dense_t`` and ``dense_s`` are the encoders' first convolution (3 x 3 cells, full
resolution) followed by a 1 x 1 projection: a local overlap of shape and colour that does not
depend on which shapes training showed. One matching function serves every pair and every
turn, and the policy plays any number of
tiles and slots. Rotation ``r`` of ``pick_place_discrete`` (``rotation_frame: tile``) turns the
tile by about ``r`` quarter turns counter-clockwise from where it lies, which is what turning
its world-aligned crop by ``r`` quarter turns shows. The policy never reads the env's state: the
tile index is the rank of the blob on the belt (`agents.camera.crops.belt_tiles`), the slot
index the slot's rank in raster order on the mesh.

`CameraPolicy.load` plays a saved file (``.pt`` with ``kind: camera_crops``);
`agents.camera.crop_bc` trains it from demonstrations.
"""

from __future__ import annotations

import math
import pickle
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from agents.camera.crops import CHANNELS, CropConfig, slot_templates, step_crops
from agents.errors import AgentError
from configs import load_config
from envs.env_config import DEFAULT_ROTATION_BINS

KIND = "camera_crops"
"""The ``kind`` entry of a saved camera policy (how `agents.policies` recognises the file)."""
CAMERA_BC_CONFIG = "camera_bc"
"""Bundled config name (``configs/camera_bc.yaml``)."""
TURNS = DEFAULT_ROTATION_BINS
"""Turns scored per tile: quarter turns of the crop (the env's default ``rotation_bins``)."""


@dataclass(frozen=True)
class CameraBCConfig:
    """Crops, network and behaviour-cloning settings of the camera policy.

    Attributes:
        grid: Crop cells per side.
        pitch: Crop cell size [m].
        foreground: Colour distance from the belt's median colour marking a tile pixel [0-255].
        min_blob_px: Smallest blob counted as a tile [px].
        supersample: Template anti-aliasing factor.
        width: Channels of the encoders' first convolution (the others use twice as many).
        embed: Embedding size of a tile crop and of a slot.
        steps: Gradient steps.
        batch_size: Observations per gradient step.
        learning_rate: Adam step size.
        weight_decay: Adam L2 penalty.
        augment: Turn every crop of a batch by one random quarter turn (labels unchanged).
        eval_every: Gradient steps between two points of the training curve (0: none).
        correlate: Add the dense correlation term of the crops to the score (module
            docstring); files written without it keep playing as they were.
    """

    grid: int = 20
    pitch: float = 0.003
    foreground: float = 40.0
    min_blob_px: int = 6
    supersample: int = 4
    width: int = 16
    embed: int = 64
    steps: int = 1500
    batch_size: int = 16
    learning_rate: float = 2e-3
    weight_decay: float = 1e-5
    augment: bool = True
    eval_every: int = 0
    correlate: bool = False

    def crop(self) -> CropConfig:
        """The crop settings."""
        return CropConfig(
            self.grid, self.pitch, self.foreground, self.min_blob_px, self.supersample
        )


def load_camera_bc_config(
    name_or_path: str | Path = CAMERA_BC_CONFIG, **overrides: Any
) -> CameraBCConfig:
    """Load a `CameraBCConfig` strictly from ``configs/`` (by name) or a path."""
    return load_config(CameraBCConfig, name_or_path, **overrides)


def _encoder(in_channels: int, cfg: CameraBCConfig) -> Any:
    import torch  # noqa: PLC0415

    w = cfg.width
    side = math.ceil(math.ceil(cfg.grid / 2) / 2)
    return torch.nn.Sequential(
        torch.nn.Conv2d(in_channels, w, 3, padding=1),
        torch.nn.ReLU(),
        torch.nn.Conv2d(w, 2 * w, 3, stride=2, padding=1),
        torch.nn.ReLU(),
        torch.nn.Conv2d(2 * w, 2 * w, 3, stride=2, padding=1),
        torch.nn.ReLU(),
        torch.nn.Flatten(),
        torch.nn.Linear(2 * w * side * side, cfg.embed),
    )


def build_scorer(cfg: CameraBCConfig) -> Any:
    """The crop scorer (a torch module; see `score`)."""
    import torch  # noqa: PLC0415

    class Scorer(torch.nn.Module):
        def __init__(self) -> None:
            super().__init__()
            self.tile_net = _encoder(CHANNELS, cfg)
            self.slot_net = _encoder(2 * CHANNELS, cfg)
            self.bias = torch.nn.Linear(cfg.embed, 1)
            self.scale = 1.0 / math.sqrt(cfg.embed)
            if cfg.correlate:
                self.tile_dense = torch.nn.Conv2d(cfg.width, cfg.width, 1)
                self.slot_dense = torch.nn.Conv2d(cfg.width, cfg.width, 1)
                self.weight = torch.nn.Parameter(torch.ones(()))

        def forward(self, tiles: Any, slots: Any) -> Any:
            """Score: tiles (B, n, C, G, G), slots (B, k, 2C, G, G) -> logits (B, n, k, TURNS)."""
            b, n = tiles.shape[:2]
            k = slots.shape[1]
            four = turned(tiles).reshape(b * n * TURNS, *tiles.shape[2:])
            flat_slots = slots.reshape(b * k, *slots.shape[2:])
            ht, hs = self.tile_net[:2](four), self.slot_net[:2](flat_slots)
            et = self.tile_net[2:](ht).reshape(b, n, TURNS, -1)
            es = self.slot_net[2:](hs).reshape(b, k, -1)
            logits = torch.einsum("bntd,bkd->bnkt", et, es) * self.scale
            logits = logits + self.bias(es).reshape(b, 1, k, 1)
            if cfg.correlate:
                dt = self.tile_dense(ht).reshape(b, n, TURNS, -1)
                ds = self.slot_dense(hs).reshape(b, k, -1)
                corr = torch.einsum("bntd,bkd->bnkt", dt, ds) / ds.shape[-1]
                logits = logits + self.weight * corr
            return logits

    return Scorer()


def turned(crops: Any, turns: int = TURNS) -> Any:
    """Tile crops (..., C, G, G) -> (..., turns, C, G, G), turn ``q`` = ``q`` quarter turns CCW."""
    import torch  # noqa: PLC0415

    return torch.stack([torch.rot90(crops, q, dims=(-2, -1)) for q in range(turns)], dim=-4)


def save_policy(path: Path, net: Any, cfg: CameraBCConfig, meta: dict[str, Any]) -> None:
    """Write a camera policy file (weights, settings, the image size and task it was trained on)."""
    import torch  # noqa: PLC0415

    from configs.files import atomic_path  # noqa: PLC0415

    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        torch.save(
            {"kind": KIND, "state_dict": net.state_dict(), "config": asdict(cfg), **meta}, tmp
        )


def read_policy_file(path: str | Path, kind: str | None = None, what: str = "") -> dict[str, Any]:
    """The contents of a saved ``.pt`` policy (any kind, or only ``kind``).

    Args:
        path: The file.
        kind: The ``kind`` entry the file must have (None: any).
        what: The kind in words, for the error (``a camera policy``).

    Raises:
        AgentError: Not a readable torch file, or of another kind.
    """
    import torch  # noqa: PLC0415

    try:
        blob = torch.load(str(path), map_location="cpu", weights_only=True)
    except (
        OSError,
        RuntimeError,
        EOFError,
        pickle.UnpicklingError,
        LookupError,
        ValueError,
    ) as exc:
        # a file that is not a torch archive can fail anywhere in the unpickler (KeyError ...)
        what = "no such file" if isinstance(exc, FileNotFoundError) else "unreadable"
        raise AgentError(f"{path} is not a saved policy ({what}: {type(exc).__name__})") from exc
    if not isinstance(blob, dict):
        raise AgentError(f"{path} is not a saved policy (holds a {type(blob).__name__})")
    if kind is not None and blob.get("kind") != kind:
        raise AgentError(f"{path} is not {what or kind} (kind {blob.get('kind')!r})")
    return blob


class CameraPolicy:
    """A camera policy (``predict(obs, spec) -> (action, None)``).

    Args:
        net: The scorer (`build_scorer`).
        cfg: Its settings.
        image_size: Camera image (height, width) it was trained on [px].
    """

    def __init__(self, net: Any, cfg: CameraBCConfig, image_size: tuple[int, int]) -> None:
        self.net = net.eval()
        self.cfg = cfg
        self.image_size = image_size
        self.crop = cfg.crop()
        self._templates: tuple[Any, np.ndarray] | None = None

    @classmethod
    def load(cls, path: str | Path) -> CameraPolicy:
        """Play a file written by `save_policy` (``kind: camera_crops``).

        Raises:
            AgentError: Not a camera policy file, or a wrong entry in it.
        """
        blob = read_policy_file(path, KIND, "a camera policy")
        try:
            cfg = CameraBCConfig(**blob["config"])
            net = build_scorer(cfg)
            net.load_state_dict(blob["state_dict"])
            size = (int(blob["image_size"][0]), int(blob["image_size"][1]))
        except (KeyError, TypeError, RuntimeError) as exc:
            raise AgentError(
                f"{path}: missing or wrong entry ({type(exc).__name__}: {exc})"
            ) from exc
        return cls(net, cfg, size)

    def logits(self, obs: dict[str, Any], spec: Any) -> np.ndarray:
        """Scores of every (tile seen, slot, turn), shape (n, k, TURNS); n = 0: no tile seen."""
        import torch  # noqa: PLC0415

        size = tuple(np.asarray(obs["input_camera"]).shape[:2])
        if size != self.image_size:
            raise AgentError(
                f"camera policy trained on {self.image_size[0]}x{self.image_size[1]} images, "
                f"got {size[0]}x{size[1]}; set the env's image_size to {list(self.image_size)}"
            )
        if self._templates is None or self._templates[0] is not spec:
            # the spec itself is kept (not its id, which a new spec may reuse once it is freed)
            self._templates = (spec, slot_templates(spec, self.crop))
        crops, _ = step_crops(obs, spec, self.crop)
        if len(crops.tiles) == 0:
            return np.zeros((0, len(spec.slots), TURNS), np.float32)
        slots = np.concatenate([self._templates[1], crops.mesh], axis=1)
        with torch.no_grad():
            out = self.net(
                torch.as_tensor(crops.tiles[None]),
                torch.as_tensor(slots[None], dtype=torch.float32),
            )
        return out[0].numpy()

    def predict(self, obs: dict[str, Any], spec: Any) -> tuple[np.ndarray, None]:
        """The best-scored ``(tile, slot, rotation)``; ``(0, 0, 0)`` when no tile is seen."""
        scores = self.logits(obs, spec)
        if scores.size == 0:
            return np.zeros(3, np.int64), None
        return np.array(np.unravel_index(int(scores.argmax()), scores.shape), np.int64), None


__all__ = [
    "CAMERA_BC_CONFIG",
    "KIND",
    "TURNS",
    "CameraBCConfig",
    "CameraPolicy",
    "build_scorer",
    "load_camera_bc_config",
    "read_policy_file",
    "save_policy",
    "turned",
]
