"""Action masks of ``pick_place_discrete``: which (tile, slot, rotation) indices are allowed now.

The sb3-contrib convention (``MaskablePPO``): for a MultiDiscrete([tiles, slots, rotations])
space the mask is one flat boolean vector, the per-dimension masks concatenated, shape
(tiles + slots + rotations,):

- tile ``i`` (agent index, `envs.indexing`) is allowed when it lies on the input belt's side of
  the cell (`envs.cell.cell.Cell.input_half`: fed, not lost, not held), the same test that
  decides whether the action can execute (otherwise it fails as "not on the input belt");
- slot ``j`` is allowed while it is open (not yet filled correctly);
- every rotation is allowed.

While no tile lies on the input belt (a ``stream`` or ``batch`` feed between arrivals) every
tile index is allowed: the action is the one way to wait (it fails as "not on the input belt",
costing ``failed_action_time`` and the failed-action penalty, under either setting). With every
slot filled the episode has ended (the slot mask is all False).

``MosaicAssemblyEnv.action_masks()`` returns the mask and ``info["action_mask"]`` holds it after
reset and each step. With
``invalid_actions="refuse"`` a step whose tile or slot the mask forbids raises `ActionError`
(`check_allowed`) before any time passes; with ``fail`` (the default) it fails as before.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from envs.cell.cell import Cell
from envs.indexing import IndexMaps
from envs.task_spec import ActionError


def action_mask(
    cell: Cell, index: IndexMaps, slot_filled: Sequence[bool] | np.ndarray, nvec: np.ndarray
) -> np.ndarray:
    """The flat mask of a MultiDiscrete([tiles, slots, rotations]) action space.

    Args:
        cell: The cell (which tiles lie on the input belt's side).
        index: The agent's index maps, updated for the current observation.
        slot_filled: Per cell slot: filled correctly, shape (k,) bool.
        nvec: The space's sizes (tiles, slots, rotations); padded entries (an empty design
            still has one index) are forbidden.

    Returns:
        Bool mask, shape (sum(nvec),): tile entries, then slot entries, then rotations.
    """
    n, k, bins = (int(v) for v in nvec)
    tiles = np.zeros(n, bool)
    on_input = cell.input_half()
    tiles[: len(index.tiles)] = on_input[index.tiles]
    if not tiles.any():  # nothing to pick: any tile index waits
        tiles[: len(index.tiles)] = True
    slots = np.zeros(k, bool)
    slots[: len(index.slots)] = ~np.asarray(slot_filled, bool)[index.slots]
    return np.concatenate([tiles, slots, np.ones(bins, bool)])


def split_mask(mask: np.ndarray, nvec: np.ndarray) -> list[np.ndarray]:
    """The flat mask cut into its per-dimension masks (tiles, slots, rotations)."""
    cuts = np.cumsum(np.asarray(nvec, int))[:-1]
    return list(np.split(np.asarray(mask, bool), cuts))


def check_allowed(action: np.ndarray, mask: np.ndarray, space: Any, invalid_actions: str) -> None:
    """Refuse a (tile, slot, rotation) action the mask forbids (``invalid_actions="refuse"``).

    Args:
        action: Validated agent action, shape (3,) int.
        mask: The current flat mask (`action_mask`).
        space: The MultiDiscrete action space (its sizes ``nvec``).
        invalid_actions: ``refuse`` checks; ``fail`` lets the action fail when applied.

    Raises:
        ActionError: The tile or slot index is forbidden now; the message names it and the
            indices allowed now.
    """
    if invalid_actions != "refuse":
        return
    names = ("tile", "slot", "rotation")
    for name, value, allowed in zip(names, action, split_mask(mask, space.nvec), strict=True):
        if not allowed[int(value)]:
            why = "is not on the input belt" if name == "tile" else "is filled already"
            raise ActionError(
                f"{name} index {int(value)} {why}; allowed now: {name} in "
                f"{np.flatnonzero(allowed).tolist()} (env.action_masks(), "
                f"info['action_mask']); invalid_actions='refuse' refuses it"
            )


__all__ = ["action_mask", "check_allowed", "split_mask"]
