"""A features extractor of ``state`` observations with fixed normalisation, stored in the model.

Low-level policies read raw world coordinates in metres (tool, tile and slot positions), where
the few millimetres that decide a seal are a tiny fraction of the inputs' spread.
`NormalizedStateExtractor` flattens a Dict observation (the space's key order), optionally
appends relative vectors (tile minus tool, slot minus tile, and the turn from the tile's yaw
to the slot's as cosines and sines of its 1, 2 and 4 multiples: what a servo acts on; the
position vectors also squashed at millimetre scales, where the seal and the placement are
decided; a
tile's symmetry makes the turn it needs a sawtooth of the yaw difference, which these
harmonics let a small network build), and
standardises every feature with a fixed mean and standard deviation, computed once from the
demonstrations (`feature_stats`). The statistics are constructor arguments, so SB3 saves them
with the model (``policy_kwargs``) and a saved model plays without the dataset.

In a training config (``apps.train`` fills ``mean``/``std`` from ``demos`` when
``normalize_obs`` is on)::

    demos: mosaic/one-tile-lowlevel-dart-v2
    normalize_obs: true
    policy_kwargs: {features_extractor_kwargs: {relative: true}}
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np
import torch
from stable_baselines3.common.torch_layers import BaseFeaturesExtractor

from agents.errors import AgentError
from envs.observations.fields import ROBOT_FIELDS, SLOT_DIM, SLOT_FIELDS, TILE_DIM, TILE_FIELDS

TOOL_POS = ROBOT_FIELDS["tool_pos"]
"""Tool position (x, y, z) [m] in the ``robot`` vector."""
STD_FLOOR = 1e-3
"""Smallest standard deviation used (features constant in the data are divided by this)."""
FINE_SCALES = (0.002, 0.01)
"""Scales [m] of the fine copies tanh(d / scale) of the relative position vectors d: within a
few millimetres of a target these change by order one where the standardised d barely moves."""
YAW_HARMONICS = (1, 2, 4)
"""Multiples k of the slot-minus-tile yaw difference given as cos(k d), sin(k d)."""
RELATIVE_DIM = 5 * (1 + len(FINE_SCALES)) + 2 * len(YAW_HARMONICS)
"""Relative features: tile minus tool (x, y, z) and slot minus tile (x, y) [m], their fine
copies, the yaw harmonics."""


def _flat_dim(space: gym.spaces.Dict) -> int:
    return sum(int(np.prod(s.shape or (1,))) for s in space.spaces.values())


class NormalizedStateExtractor(BaseFeaturesExtractor):
    """Flatten a ``state`` Dict observation, add relative vectors, standardise.

    Args:
        observation_space: The env's Dict observation space (``robot``, ``tiles``, ``slots``
            for ``relative``).
        mean: Per-feature mean, length `features_dim` (None: zeros).
        std: Per-feature standard deviation (None: ones); floored at `STD_FLOOR`.
        relative: Append the first tile's position minus the tool's, the first slot's
            (x, y) minus the first tile's [m], their fine copies (`FINE_SCALES`) and the
            harmonics of their yaw difference.

    Raises:
        AgentError: Not a Dict space, missing keys for ``relative``, or statistics of the
            wrong length.
    """

    def __init__(
        self,
        observation_space: gym.spaces.Dict,
        mean: Sequence[float] | None = None,
        std: Sequence[float] | None = None,
        relative: bool = False,
    ) -> None:
        if not isinstance(observation_space, gym.spaces.Dict):
            raise AgentError(
                f"NormalizedStateExtractor needs a Dict space, got {observation_space}"
            )
        if relative and not {"robot", "tiles", "slots"} <= set(observation_space.spaces):
            raise AgentError(
                "relative features need the robot, tiles and slots rows, the space has "
                f"{list(observation_space.spaces)}"
            )
        dim = _flat_dim(observation_space) + (RELATIVE_DIM if relative else 0)
        super().__init__(observation_space, features_dim=dim)
        self.keys = list(observation_space.spaces)
        self.relative = bool(relative)
        for name, values, default in (("mean", mean, 0.0), ("std", std, 1.0)):
            arr = np.full(dim, default) if values is None else np.asarray(values, float)
            if arr.shape != (dim,):
                raise AgentError(f"{name} has {arr.size} values, the features are {dim}")
            if name == "std":
                arr = np.maximum(arr, STD_FLOOR)
            self.register_buffer(name, torch.as_tensor(arr, dtype=torch.float32))

    def raw_features(self, observations: dict[str, torch.Tensor]) -> torch.Tensor:
        """The features before standardisation, shape (batch, features_dim)."""
        parts = [observations[k].flatten(1).float() for k in self.keys]
        if self.relative:
            tool = observations["robot"][:, TOOL_POS]
            tile = observations["tiles"][:, :TILE_DIM]
            slot = observations["slots"][:, :SLOT_DIM]
            s_yaw, t_yaw = SLOT_FIELDS["yaw"].start, TILE_FIELDS["yaw"].start
            diff = torch.atan2(slot[:, s_yaw + 1], slot[:, s_yaw]) - torch.atan2(
                tile[:, t_yaw + 1], tile[:, t_yaw]
            )
            turns = [f(k * diff) for k in YAW_HARMONICS for f in (torch.cos, torch.sin)]
            rel = torch.cat([tile[:, :3] - tool, slot[:, :2] - tile[:, :2]], 1)
            fine = [torch.tanh(rel / scale) for scale in FINE_SCALES]
            parts += [rel, *fine, torch.stack(turns, 1)]
        return torch.cat(parts, dim=1)

    def forward(self, observations: dict[str, torch.Tensor]) -> torch.Tensor:
        """Standardised features, shape (batch, features_dim)."""
        mean, std = self.get_buffer("mean"), self.get_buffer("std")
        return (self.raw_features(observations) - mean) / std


def feature_stats(
    observations: dict[str, np.ndarray], space: gym.spaces.Dict, relative: bool = False
) -> dict[str, list[float]]:
    """Mean and standard deviation of `NormalizedStateExtractor`'s features over the data.

    Args:
        observations: Per key, shape (n, ...) (e.g.
            `agents.learning.demos.Transitions.observations`).
        space: The observation space.
        relative: As the extractor's.

    Returns:
        ``{"mean": [...], "std": [...]}``, ready for ``features_extractor_kwargs``.
    """
    ext = NormalizedStateExtractor(space, relative=relative)
    with torch.no_grad():
        raw = ext.raw_features({k: torch.as_tensor(np.asarray(v)) for k, v in observations.items()})
    x = raw.double().numpy()
    return {"mean": x.mean(0).tolist(), "std": x.std(0).tolist()}


def normalized_policy_kwargs(
    policy_kwargs: dict[str, Any], observations: dict[str, np.ndarray], space: gym.spaces.Dict
) -> dict[str, Any]:
    """``policy_kwargs`` with `NormalizedStateExtractor` and the data's statistics filled in.

    Keeps any ``features_extractor_kwargs`` given (``relative``).
    """
    extra = dict(policy_kwargs.get("features_extractor_kwargs") or {})
    stats = feature_stats(observations, space, bool(extra.get("relative", False)))
    return {
        **policy_kwargs,
        "features_extractor_class": NormalizedStateExtractor,
        "features_extractor_kwargs": {**extra, **stats},
    }


__all__ = [
    "FINE_SCALES",
    "RELATIVE_DIM",
    "STD_FLOOR",
    "YAW_HARMONICS",
    "NormalizedStateExtractor",
    "feature_stats",
    "normalized_policy_kwargs",
]
