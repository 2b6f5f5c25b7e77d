"""The ``state`` observation on a moving belt as pair-scorer rows: each tile's time left.

On a moving belt the choice is not only which tile goes where but which tile first: a tile the
cell does not pick in time is carried off the belt's end. The rows are the ``state`` adapter's
(`agents.pair.state_rows`), and each tile row also carries its **time left**: the time before
the belt carries it to ``last_x``, the farthest position at which a pick contact still saves it,
``(last_x - x) / belt_speed`` [s] (divided by `TIME_SCALE_S`, clipped to `TIME_CLIP`). The belt's
speed and ``last_x`` are the adapter's settings (`BeltTiming`), saved in the clone's file, so
the clone reads the same deadline the scheduler it imitates computes
(`agents.scripted.belt_schedule`).

Each pair also carries the rotation index the env's ``tile`` frame defines for it
(`envs.indexing`: ``-round(d / (2 pi / bins)) mod bins`` for the tile's yaw relative to the slot,
d), one-hot over the bins: a clone that has to learn where that index flips, at odd multiples of
45 deg, turned a tile lying 43.9 deg off by the wrong quarter (held-out seed 1000), and one wrong
tile of 16 fails a stream episode.

The tile mask keeps the tiles lying on the input belt: present, not lying on a slot, and inside
the pick area across the belt (``pick_y``). While none does (the stream between arrivals) every
tile index is allowed, as the env's own mask allows it (any index waits, `envs.masks`).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import torch

from agents.errors import AgentError
from agents.pair.scorer import PairRows
from agents.pair.state_rows import STATE_PAIR_FEATURES, STATE_SLOT_FEATURES, state_rows
from envs.env_config import DEFAULT_ROTATION_BINS
from envs.observations.fields import TILE_DIM

TIME_SCALE_S = 10.0
"""Times left are divided by this [s] before they enter the scorer."""
TIME_CLIP = (-1.0, 3.0)
"""Range of the scaled time left (a tile far upstream or long gone reads as its end)."""
STREAM_TILE_FEATURES = 4
"""Tile row features given to the scorer: x, y [m], present, scaled time left."""
ROTATION_BINS = DEFAULT_ROTATION_BINS
"""Rotation bins of the ``pick_place_discrete`` action this adapter serves."""
STREAM_SLOT_FEATURES = STATE_SLOT_FEATURES
"""Slot row features: as the ``state`` adapter's."""
STREAM_PAIR_FEATURES = STATE_PAIR_FEATURES + ROTATION_BINS
"""Pair features: the ``state`` adapter's and the tile frame's rotation index, one-hot."""


@dataclass(frozen=True)
class BeltTiming:
    """The belt a stream adapter reads deadlines on.

    Attributes:
        belt_speed: Input belt speed along +x [m/s], > 0.
        last_x: The farthest x at which a pick contact still saves a tile [m] (the belt's end
            less the scheduler's ``end_margin``).
        pick_y: The pick area across the belt, (low, high) y [m]: a present tile there lies on
            the input belt.
    """

    belt_speed: float
    last_x: float
    pick_y: tuple[float, float]

    def __post_init__(self) -> None:
        if not self.belt_speed > 0:
            raise AgentError(
                f"BeltTiming.belt_speed {self.belt_speed} m/s: a stream adapter needs a belt "
                "moving along +x (> 0)"
            )
        lo, hi = self.pick_y
        if not lo < hi:
            raise AgentError(f"BeltTiming.pick_y {self.pick_y}: low must be below high [m]")

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> BeltTiming:
        """From `as_dict` (a clone file's ``adapter_args``)."""
        lo, hi = d["pick_y"]
        return cls(float(d["belt_speed"]), float(d["last_x"]), (float(lo), float(hi)))

    def as_dict(self) -> dict[str, Any]:
        """Plain values, for a clone file."""
        out = asdict(self)
        out["pick_y"] = list(self.pick_y)
        return out


def stream_rows(tiles: torch.Tensor, slots: torch.Tensor, *, timing: BeltTiming) -> PairRows:
    """Rows of a batch of ``state`` observations on a moving belt.

    Args:
        tiles: Flat ``tiles`` observations, shape (B, n * 7) (or (n * 7,)).
        slots: Flat ``slots`` observations, shape (B, k * 6) (or (k * 6,)).
        timing: The belt (speed, last saving position, pick area across it).
    """
    base = state_rows(tiles, slots)
    t = tiles.float().reshape(base.tiles.shape[0], -1, TILE_DIM)
    x, y = t[..., 0], t[..., 1]
    left = (timing.last_x - x) / timing.belt_speed / TIME_SCALE_S
    lo, hi = timing.pick_y
    on_belt = base.tile_mask & (y >= lo) & (y <= hi)
    waiting = ~on_belt.any(-1, keepdim=True)
    d = torch.atan2(base.pairs[..., 2], base.pairs[..., 1])  # tile yaw - slot yaw
    index = torch.remainder(-torch.round(d / (2 * torch.pi / ROTATION_BINS)), ROTATION_BINS)
    one_hot = torch.nn.functional.one_hot(index.long(), ROTATION_BINS).to(base.pairs.dtype)
    return PairRows(
        tiles=torch.cat([base.tiles, left.clamp(*TIME_CLIP)[..., None]], dim=-1),
        slots=base.slots,
        pairs=torch.cat([base.pairs, one_hot], dim=-1),
        tile_mask=torch.where(waiting, torch.ones_like(on_belt), on_belt),
        slot_mask=base.slot_mask,
    )


__all__ = [
    "ROTATION_BINS",
    "STREAM_PAIR_FEATURES",
    "STREAM_SLOT_FEATURES",
    "STREAM_TILE_FEATURES",
    "TIME_CLIP",
    "TIME_SCALE_S",
    "BeltTiming",
    "stream_rows",
]
