"""Where every real tile is: one state per tile fed, the counts summing to the tiles fed.

`tile_states` sorts the real tiles fed into the cell into exactly one of `TILE_STATES`, in one
pass over the tiles (it runs on every env step). The order of the tests decides ties: a held tile is
held wherever it is; a tile released over the reject bin (or taken off the belt with its batch)
is rejected; a tile on the floor or in the bin is dropped if the pad let go of it in transit,
else lost; a tile over the mesh is correct or misplaced; one on the input belt is on the input;
one the pad dropped elsewhere is dropped; anything else (beside the mesh on the output belt,
tilted over its edge, on a frame) is stranded. Tiles not fed yet are counted apart as waiting.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

TILE_STATES = (
    "on_input",
    "held",
    "correct",
    "misplaced",
    "stranded",
    "dropped_tiles",
    "lost_tiles",
    "rejected",
)
"""The states of a real tile fed into the cell (each fed real tile is in exactly one)."""

ON_INPUT, HELD, CORRECT, MISPLACED, STRANDED, DROPPED, LOST, REJECTED = range(len(TILE_STATES))
WAITING = -1
"""State code of a real tile not fed yet."""
NOT_COUNTED = -2
"""State code of a distractor (distractors are counted by the task apart)."""


@dataclass(frozen=True, eq=False)
class TileFlags:
    """Per-tile facts `account` sorts from, each shape (n,) bool.

    Attributes:
        real: The design needs the tile (not a distractor).
        fed: The tile has been put into the cell (on stage now, or taken off with its batch).
        held: The pad holds the tile.
        rejected: Released by the pad over the reject bin, or taken off with its batch.
        lost: Past the input belt's end or fallen below belt level (and not rejected).
        was_dropped: The pad last let go of the tile by a drop.
        on_mesh: Over the mesh, not held.
        correct: Filling its slot correctly.
        on_input: On the input belt, not held.
    """

    real: np.ndarray
    fed: np.ndarray
    held: np.ndarray
    rejected: np.ndarray
    lost: np.ndarray
    was_dropped: np.ndarray
    on_mesh: np.ndarray
    correct: np.ndarray
    on_input: np.ndarray


def tile_states(f: TileFlags) -> np.ndarray:
    """The state code of every tile (an index of `TILE_STATES`, `WAITING` or `NOT_COUNTED`).

    Returns:
        Shape (n,) int8.
    """
    # The first true condition of the module docstring's priority order decides (plain
    # Python per tile: a tile's flags are a handful of booleans, cheaper than array calls).
    flags = np.column_stack(
        (f.real, f.fed, f.held, f.rejected, f.lost, f.was_dropped, f.on_mesh, f.correct, f.on_input)
    )
    states = []
    for real, fed, held, rejected, lost, dropped, on_mesh, correct, on_input in flags.tolist():
        if not real:
            code = NOT_COUNTED
        elif not fed:
            code = WAITING
        elif held:
            code = HELD
        elif rejected:
            code = REJECTED
        elif lost:
            code = DROPPED if dropped else LOST
        elif on_mesh:
            code = CORRECT if correct else MISPLACED
        elif on_input:
            code = ON_INPUT
        else:
            code = DROPPED if dropped else STRANDED
        states.append(code)
    return np.array(states, np.int8)


def state_counts(states: np.ndarray) -> dict[str, int]:
    """Count of each of `TILE_STATES` in a `tile_states` array (their sum: the real tiles fed)."""
    counts = np.bincount(states[states >= 0], minlength=len(TILE_STATES)).tolist()
    return dict(zip(TILE_STATES, counts, strict=True))


__all__ = [
    "CORRECT",
    "DROPPED",
    "HELD",
    "LOST",
    "MISPLACED",
    "NOT_COUNTED",
    "ON_INPUT",
    "REJECTED",
    "STRANDED",
    "TILE_STATES",
    "WAITING",
    "TileFlags",
    "state_counts",
    "tile_states",
]
