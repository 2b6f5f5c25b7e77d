"""The ``objects`` observation as pair-scorer rows (`agents.pair.scorer.PairRows`).

``tiles`` and ``slots`` are entity rows without class ids (`envs.observations.objects`): colour,
area, hole area, position, yaw, a flag, a validity bit and the outline as P points [mm] about the
centroid, turned as the entity lies. Matching has to come from shape and colour, so per
(tile, slot) pair the adapter compares them:

- for each rotation bin r, the tile outline turned by the candidate turn of that bin against
  the slot outline: the symmetric chamfer distance [mm] (mean nearest-point distance both
  ways) and its value relative to the slot's size. With ``rotation_frame="tile"``
  (`envs.indexing`) bin r turns the tile by ``r * 2 pi / bins - e``, where e is the tile's yaw
  relative to the slot wrapped into the nearest bin, so the bin whose turned tile lies on the
  slot outline is the right one, with no boundary at 45 deg;
- the colour difference |rgb_t - rgb_s| (3 values) and the area and hole-area differences
  [cm2] (scaled by `AREA_SCALE_CM2`).

Tile rows give the scorer their pickable flag, slot rows their filled flag; tile and slot masks
are the rows' own flags (and valid bits): a tile may be picked when its flag is 1, a slot
filled while its flag is 0.
"""

from __future__ import annotations

from typing import Any

import torch

from agents.pair.scorer import PairRows
from envs.env_config import DEFAULT_ROTATION_BINS
from envs.observations.fields import column
from envs.observations.objects import OBJECT_FIELDS
from envs.task_spec import rotation_step

FIELDS: dict[str, Any] = {
    "rgb": OBJECT_FIELDS["rgb"],
    "area": column(OBJECT_FIELDS, "area"),
    "hole_area": column(OBJECT_FIELDS, "hole_area"),
    "yaw": OBJECT_FIELDS["yaw"],
    "flag": column(OBJECT_FIELDS, "flag"),
    "valid": column(OBJECT_FIELDS, "valid"),
    "points": OBJECT_FIELDS["points"].start,
}
"""Columns of an entity row read here (the env's `envs.observations.objects.OBJECT_FIELDS`; the
points from their first column to the row's end, whatever ``objects_points``)."""
ROTATION_BINS = DEFAULT_ROTATION_BINS
"""Rotation bins of the ``pick_place_discrete`` action this adapter serves."""
CHAMFER_SCALE_MM = 5.0
"""Chamfer distances are divided by this [mm] before they enter the scorer."""
AREA_SCALE_CM2 = 10.0
"""Area differences are divided by this [cm2]."""
OBJECTS_TILE_FEATURES = 1
"""Tile row features given to the scorer: pickable flag."""
OBJECTS_SLOT_FEATURES = 1
"""Slot row features given to the scorer: filled flag."""
OBJECTS_PAIR_FEATURES = 2 * ROTATION_BINS + 5
"""Pair features: chamfer per bin [scaled mm], relative chamfer per bin, |d rgb| (3), d area,
d hole area."""
CHUNK = 32
"""Observations whose outlines are compared at once (bounds the memory of the distances)."""
FLAG = 0.5
"""Threshold of the 0/1 flags."""


def outline_points(rows: torch.Tensor) -> torch.Tensor:
    """The outline points of entity rows, shape (..., P, 2) [mm]."""
    pts = rows[..., FIELDS["points"] :]
    return pts.reshape(*pts.shape[:-1], -1, 2)


def yaw(rows: torch.Tensor) -> torch.Tensor:
    """Yaw of entity rows from their (cos, sin) columns [rad], shape (...)."""
    cs = rows[..., FIELDS["yaw"]]
    return torch.atan2(cs[..., 1], cs[..., 0])


def bin_turns(tiles: torch.Tensor, slots: torch.Tensor, bins: int = ROTATION_BINS) -> torch.Tensor:
    """The turn each rotation bin applies to each tile for each slot [rad], shape (B, n, k, bins).

    With ``rotation_frame="tile"`` the env turns the tile to the slot-aligned pose nearest its
    yaw, then ``r`` more steps of ``2 pi / bins``: turn = r * step - e, e the tile's yaw
    relative to the slot wrapped into [-step / 2, step / 2].
    """
    step = rotation_step(bins)
    d = yaw(tiles)[:, :, None] - yaw(slots)[:, None, :]
    e = d - step * torch.round(d / step)
    r = torch.arange(bins, dtype=tiles.dtype) * step
    return r - e[..., None]


def turned_chamfer(tiles: torch.Tensor, slots: torch.Tensor, turns: torch.Tensor) -> torch.Tensor:
    """Symmetric chamfer distance [mm] of each tile outline turned by each turn to each slot's.

    Args:
        tiles: Tile rows, shape (B, n, D).
        slots: Slot rows, shape (B, k, D).
        turns: Turns [rad], shape (B, n, k, R).

    Returns:
        Shape (B, n, k, R).
    """
    tp = outline_points(tiles)  # (B, n, P, 2)
    sp = outline_points(slots)  # (B, k, P, 2)
    c, s = torch.cos(turns), torch.sin(turns)  # (B, n, k, R)
    x, y = tp[..., 0][:, :, None, None, :], tp[..., 1][:, :, None, None, :]  # (B, n, 1, 1, P)
    rx = c[..., None] * x - s[..., None] * y  # (B, n, k, R, P)
    ry = s[..., None] * x + c[..., None] * y
    turned = torch.stack([rx, ry], dim=-1)  # (B, n, k, R, P, 2)
    target = sp[:, None, :, None, :, :]  # (B, 1, k, 1, P, 2)
    dist = (turned[..., :, None, :] - target[..., None, :, :]).norm(dim=-1)  # (..., P, P)
    return 0.5 * (dist.min(-1).values.mean(-1) + dist.min(-2).values.mean(-1))


def objects_rows(tiles: torch.Tensor, slots: torch.Tensor) -> PairRows:
    """Rows of a batch of ``objects`` observations (outlines compared `CHUNK` at a time).

    Args:
        tiles: ``tiles`` entity rows, shape (B, n, D) (or (n, D)).
        slots: ``slots`` entity rows, shape (B, k, D) (or (k, D)).
    """
    t = tiles.float() if tiles.dim() == 3 else tiles.float()[None]  # noqa: PLR2004
    s = slots.float() if slots.dim() == 3 else slots.float()[None]  # noqa: PLR2004
    chamfer = torch.cat(
        [
            turned_chamfer(
                t[i : i + CHUNK], s[i : i + CHUNK], bin_turns(t[i : i + CHUNK], s[i : i + CHUNK])
            )
            for i in range(0, len(t), CHUNK)
        ]
    )
    size = outline_points(s).norm(dim=-1).mean(-1).clamp_min(1.0)  # (B, k) mean radius [mm]
    rgb = (t[:, :, None, FIELDS["rgb"]] - s[:, None, :, FIELDS["rgb"]]).abs()
    d_area = t[:, :, None, FIELDS["area"]] - s[:, None, :, FIELDS["area"]]
    d_hole = t[:, :, None, FIELDS["hole_area"]] - s[:, None, :, FIELDS["hole_area"]]
    pairs = torch.cat(
        [
            chamfer / CHAMFER_SCALE_MM,
            chamfer / size[:, None, :, None],
            rgb,
            (d_area / AREA_SCALE_CM2)[..., None],
            (d_hole / AREA_SCALE_CM2)[..., None],
        ],
        dim=-1,
    )
    t_flag, s_flag = t[..., FIELDS["flag"]], s[..., FIELDS["flag"]]
    t_valid, s_valid = t[..., FIELDS["valid"]] > FLAG, s[..., FIELDS["valid"]] > FLAG
    return PairRows(
        tiles=t_flag[..., None],
        slots=s_flag[..., None],
        pairs=pairs,
        tile_mask=(t_flag > FLAG) & t_valid,
        slot_mask=(s_flag < FLAG) & s_valid,
    )


__all__ = [
    "AREA_SCALE_CM2",
    "CHAMFER_SCALE_MM",
    "OBJECTS_PAIR_FEATURES",
    "OBJECTS_SLOT_FEATURES",
    "OBJECTS_TILE_FEATURES",
    "bin_turns",
    "objects_rows",
    "outline_points",
    "turned_chamfer",
    "yaw",
]
