"""The pair scorer's row adapters by name: observation -> `agents.pair.scorer.PairRows`.

- ``state``: class ids and relative yaws of the privileged ``state`` observation
  (`agents.pair.state_rows`);
- ``objects``: outlines, colours and areas of ``objects`` entity rows (`agents.pair.objects_rows`);
- ``stream``: the ``state`` rows plus each tile's time left on a moving belt
  (`agents.pair.stream_rows`); it needs its belt's `BeltTiming` (``args``).

A clone file names its adapter (and a stream adapter's settings), so the policy that plays it
builds the same rows it was trained on.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from typing import Any

import torch

from agents.errors import AgentError
from agents.pair.objects_rows import (
    OBJECTS_PAIR_FEATURES,
    OBJECTS_SLOT_FEATURES,
    OBJECTS_TILE_FEATURES,
    objects_rows,
)
from agents.pair.scorer import PairRows
from agents.pair.state_rows import (
    STATE_PAIR_FEATURES,
    STATE_SLOT_FEATURES,
    STATE_TILE_FEATURES,
    state_rows,
)
from agents.pair.stream_rows import (
    STREAM_PAIR_FEATURES,
    STREAM_SLOT_FEATURES,
    STREAM_TILE_FEATURES,
    BeltTiming,
    stream_rows,
)

Adapter = Callable[[torch.Tensor, torch.Tensor], PairRows]
"""(tiles, slots) tensors -> rows."""

ADAPTERS: dict[str, Callable[..., PairRows]] = {
    "state": state_rows,
    "objects": objects_rows,
    "stream": stream_rows,
}
"""Adapters by name (``stream`` takes its ``timing`` as a keyword)."""
FEATURE_DIMS = {
    "state": (STATE_TILE_FEATURES, STATE_SLOT_FEATURES, STATE_PAIR_FEATURES),
    "objects": (OBJECTS_TILE_FEATURES, OBJECTS_SLOT_FEATURES, OBJECTS_PAIR_FEATURES),
    "stream": (STREAM_TILE_FEATURES, STREAM_SLOT_FEATURES, STREAM_PAIR_FEATURES),
}
"""(tile_dim, slot_dim, pair_dim) of each adapter's rows."""
NEEDS_TIMING = frozenset({"stream"})
"""Adapters that read a belt's `BeltTiming`."""


def row_adapter(name: str, args: dict[str, Any] | None = None) -> Adapter:
    """The adapter ``name``, with its settings bound (a stream adapter's belt timing).

    Raises:
        AgentError: An unknown adapter, or a stream adapter without its timing.
    """
    if name not in ADAPTERS:
        raise AgentError(f"unknown pair-row adapter {name!r}; allowed: {sorted(ADAPTERS)}")
    if name in NEEDS_TIMING:
        if not args:
            raise AgentError(
                f"the {name!r} adapter needs its belt timing (belt_speed, last_x, pick_y)"
            )
        return partial(ADAPTERS[name], timing=BeltTiming.from_dict(args))
    return ADAPTERS[name]


__all__ = ["ADAPTERS", "FEATURE_DIMS", "NEEDS_TIMING", "Adapter", "row_adapter"]
