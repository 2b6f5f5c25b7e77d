"""The ``state`` observation as pair-scorer rows (`agents.pair.scorer.PairRows`).

``tiles`` is n rows of (x, y, z [m], cos yaw, sin yaw, class index, present) and ``slots`` k
rows of (x, y [m], cos yaw, sin yaw, class index, filled correctly), flattened, in the order
of the ``pick_place_discrete`` action's indices (`envs.observations.spaces`). Per pair the adapter
gives:

- whether the tile's class index equals the slot's (the ``state`` observation's answer to
  "which tile goes where"; an observation without class ids gets learned matching instead);
- the tile's yaw relative to the slot, d = tile yaw - slot yaw, as (cos d, sin d, cos 2d,
  sin 2d): with ``rotation_frame="tile"`` (`envs.indexing`) the right rotation index is
  ``-round(d / (2 pi / bins)) mod bins``, a function of d alone whose value flips where d
  crosses an odd multiple of 45 deg (4 bins).

Tile rows keep their position (x, y [m]) and present flag, slot rows their position and
filled flag; class ids enter through the pair feature only. The masks come from the
observation's own flags: a tile may be picked when present and not lying on a slot
(within `ON_SLOT_M`; a tile set down on the mesh, in its slot or misplaced, is off the input belt,
so the env refuses it too), a slot may be filled while not filled correctly. The env's own mask
(``env.action_masks()``) is what RL training uses instead.
"""

from __future__ import annotations

import torch

from agents.pair.scorer import PairRows
from envs.observations.fields import SLOT_DIM, SLOT_FIELDS, TILE_DIM, TILE_FIELDS, column

T_CLASS, T_PRESENT = column(TILE_FIELDS, "class"), column(TILE_FIELDS, "present")
T_YAW = TILE_FIELDS["yaw"]
S_CLASS, S_FILLED = column(SLOT_FIELDS, "class"), column(SLOT_FIELDS, "filled")
S_XY, S_YAW = SLOT_FIELDS["xy"], SLOT_FIELDS["yaw"]
STATE_TILE_FEATURES = 3
"""Tile row features given to the scorer: x, y [m], present."""
STATE_SLOT_FEATURES = 3
"""Slot row features given to the scorer: x, y [m], filled."""
STATE_PAIR_FEATURES = 5
"""Pair features: class equal, cos d, sin d, cos 2d, sin 2d."""
ON_SLOT_M = 0.005
"""A tile whose centre lies this close to a slot's centre [m] lies on the mesh, in that slot."""
FLAG = 0.5
"""Threshold of the 0/1 flags."""


def state_rows(tiles: torch.Tensor, slots: torch.Tensor) -> PairRows:
    """Rows of a batch of ``state`` observations.

    Args:
        tiles: Flat ``tiles`` observations, shape (B, n * 7) (or (n * 7,)).
        slots: Flat ``slots`` observations, shape (B, k * 6) (or (k * 6,)).
    """
    t = tiles.float().reshape(tiles.shape[0] if tiles.dim() > 1 else 1, -1, TILE_DIM)
    s = slots.float().reshape(t.shape[0], -1, SLOT_DIM)
    same = (t[:, :, None, T_CLASS] - s[:, None, :, S_CLASS]).abs() < FLAG
    t_yaw = torch.atan2(t[..., T_YAW.start + 1], t[..., T_YAW.start])
    s_yaw = torch.atan2(s[..., S_YAW.start + 1], s[..., S_YAW.start])
    d = t_yaw[:, :, None] - s_yaw[:, None, :]
    pairs = torch.stack(
        [same.float(), torch.cos(d), torch.sin(d), torch.cos(2 * d), torch.sin(2 * d)], dim=-1
    )
    filled = s[..., S_FILLED] > FLAG
    gap = torch.cdist(t[..., :2], s[..., S_XY])
    on_slot = (gap < ON_SLOT_M).any(-1)
    return PairRows(
        tiles=torch.stack([t[..., 0], t[..., 1], t[..., T_PRESENT]], dim=-1),
        slots=torch.stack([s[..., S_XY.start], s[..., S_XY.start + 1], s[..., S_FILLED]], dim=-1),
        pairs=pairs,
        tile_mask=(t[..., T_PRESENT] > FLAG) & ~on_slot,
        slot_mask=~filled,
    )


__all__ = [
    "ON_SLOT_M",
    "STATE_PAIR_FEATURES",
    "STATE_SLOT_FEATURES",
    "STATE_TILE_FEATURES",
    "state_rows",
]
