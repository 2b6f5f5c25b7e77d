"""The equivariant pixel policy: play a saved network on the two camera images.

Each step the observation is cut into crops (`agents.equivariant.records.CropCutter`), the
network scores every (tile seen, slot, fine turn), and the fine turns are pooled into the env's
rotation indices (`agents.equivariant.turns.rotation_of_turns`: which index each turn stands
for under the env's ``rotation_frame``, given the slot figure's symmetry): the logit of
(tile i, slot j, rotation r) is the log-sum-exp of the scores of the turns that stand for r.
The action mask, where given, removes tiles and slots the env would refuse. Only the images and
the public `TaskSpec` are read.

A file (``.pt``, ``kind: equivariant``) holds the weights, the settings, the image size, the
task and the camera level it was trained for; `EquivariantPolicy.load` refuses another kind,
and `logits` an observation of another mode or size, naming what it expects.
"""

from __future__ import annotations

from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from agents.camera.crop_scorer import read_policy_file
from agents.camera.crops import mesh_order
from agents.equivariant.config import EquivariantConfig
from agents.equivariant.network import build_network
from agents.equivariant.records import CropCutter
from agents.equivariant.turns import rotation_of_turns
from agents.errors import AgentError
from envs.env_config import DEFAULT_ROTATION_BINS

KIND = "equivariant"
"""The ``kind`` entry of a saved equivariant policy."""
NEG = -1e9
"""Logit of an action the mask or the decoding rules out."""


def save_policy(path: str | Path, net: Any, cfg: EquivariantConfig, meta: dict[str, Any]) -> Path:
    """Write a policy file (weights, settings and ``meta``: image_size, task, camera, ...)."""
    import torch  # noqa: PLC0415

    from configs.files import atomic_path  # noqa: PLC0415

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        torch.save(
            {"kind": KIND, "state_dict": net.state_dict(), "config": asdict(cfg), **meta}, tmp
        )
    return path


class EquivariantPolicy:
    """Plays a trained network (``predict(obs, spec, masks) -> (action, None)``).

    Args:
        net: The network (`agents.equivariant.network.build_network`).
        cfg: Its settings.
        image_size: Camera image (height, width) it was trained on [px].
        meta: The file's other entries (task, camera level, demonstrations).
    """

    def __init__(
        self,
        net: Any,
        cfg: EquivariantConfig,
        image_size: tuple[int, int],
        meta: dict[str, Any] | None = None,
    ) -> None:
        self.net = net.eval()
        self.cfg = cfg
        self.image_size = image_size
        self.meta = dict(meta or {})
        self.crop = cfg.crop()
        self.cut = CropCutter(cfg)
        """Cuts an observation into the network's inputs (`CropCutter`)."""

    @classmethod
    def load(cls, path: str | Path) -> EquivariantPolicy:
        """Play a file written by `save_policy`.

        Raises:
            AgentError: Not an equivariant policy file, or a wrong entry in it.
        """
        blob = read_policy_file(path, KIND, "an equivariant policy")
        try:
            cfg = EquivariantConfig(**blob["config"])
            net = build_network(cfg)
            net.load_state_dict(blob["state_dict"])
            size = (int(blob["image_size"][0]), int(blob["image_size"][1]))
        except (KeyError, TypeError, RuntimeError, AgentError) as exc:
            raise AgentError(
                f"{path}: missing or wrong entry ({type(exc).__name__}: {exc})"
            ) from exc
        meta = {k: v for k, v in blob.items() if k not in ("state_dict", "config", "kind")}
        return cls(net, cfg, size, meta)

    def turn_scores(self, obs: dict[str, Any], spec: Any) -> tuple[np.ndarray, Any]:
        """Scores of every (tile seen, slot, fine turn), (n, k, turns), and the blobs found.

        Raises:
            AgentError: No camera images in the observation, or images of another size.
        """
        import torch  # noqa: PLC0415

        if "input_camera" not in obs or "output_camera" not in obs:
            raise AgentError(
                "the equivariant policy reads obs_mode 'rgb' (input_camera and output_camera "
                f"images); got the keys {sorted(obs)}"
            )
        size = tuple(np.asarray(obs["input_camera"]).shape[:2])
        if size != self.image_size:
            raise AgentError(
                f"equivariant policy trained on {self.image_size[0]}x{self.image_size[1]} "
                f"images, got {size[0]}x{size[1]}; set the env's image_size to "
                f"{list(self.image_size)}"
            )
        tiles, slots, found = self.cut(obs, spec)
        if len(tiles) == 0:
            return np.zeros((0, len(slots), self.cfg.turns), np.float32), found
        with torch.no_grad():
            out = self.net(torch.as_tensor(tiles[None]), torch.as_tensor(slots[None]))
        return out[0].numpy(), found

    def logits(self, obs: dict[str, Any], spec: Any, masks: np.ndarray | None = None) -> np.ndarray:
        """Logits of every (tile seen, slot, rotation index), (n, k, bins).

        The rotation indices are the env's (``spec.discrete``: its bins and frame); an env
        without a discrete codec (``pick_place``) is read as the default quarter turns counted
        from the tile (``tile`` frame), where the index only breaks ties between turns the
        figure makes equivalent.
        """
        scores, _ = self.turn_scores(obs, spec)
        codec = getattr(spec, "discrete", None)
        bins = codec.rotation_bins if codec is not None else DEFAULT_ROTATION_BINS
        frame = codec.rotation_frame if codec is not None else "tile"
        n, k = scores.shape[:2]
        out = np.full((n, k, bins), NEG, np.float32)
        order = mesh_order(spec)
        for j in range(k):
            sym = int(spec.slots[int(order[j])].symmetry)
            r_of = rotation_of_turns(self.cfg.turns, bins, frame, sym)
            for r in np.unique(r_of):
                s = scores[:, j, r_of == r]
                top = s.max(axis=1, keepdims=True)
                out[:, j, r] = (top + np.log(np.exp(s - top).sum(axis=1, keepdims=True)))[:, 0]
        if masks is not None and n:
            m = np.asarray(masks, bool)
            nt = codec.tiles if codec is not None else n
            tile_ok = np.zeros(n, bool)  # blobs past the env's tile indices: not actions
            tile_ok[: min(n, nt)] = m[: min(n, nt)]
            slot_ok = m[nt : nt + k]
            rot_ok = m[nt + k : nt + k + bins]
            out[~tile_ok] = NEG
            out[:, ~slot_ok] = NEG
            out[:, :, ~rot_ok] = NEG
        return out

    def predict(
        self, obs: dict[str, Any], spec: Any, masks: np.ndarray | None = None
    ) -> tuple[np.ndarray, None]:
        """The best-scored ``(tile, slot, rotation)``; ``(0, 0, 0)`` when no tile is seen."""
        scores = self.logits(obs, spec, masks)
        if scores.size == 0:
            return np.zeros(3, np.int64), None
        return np.array(np.unravel_index(int(scores.argmax()), scores.shape), np.int64), None


__all__ = ["KIND", "EquivariantPolicy", "save_policy"]
