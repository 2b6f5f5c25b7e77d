"""Fine in-plane turns: turning crops and feature maps, and which rotation index a turn names.

A crop (`agents.camera.crops.world_crop`) is world-aligned, north up, so turning it
counter-clockwise on the page turns what it shows counter-clockwise in the world. The policy
scores ``turns`` fine turns ``phi_k = 2 pi k / turns``; `turn_maps` turns a batch of maps by
all of them: the turns below a quarter by bilinear resampling, the rest as exact quarter turns
of those (``torch.rot90``), so a quarter turn of the input turns the scores by exactly
``turns / 4`` steps.

Which discrete rotation index ``r`` a fine turn stands for depends on the env's
``rotation_frame`` (`envs.indexing`): if turning tile ``i``'s crop by ``phi`` lays it on slot
``j``, the tile lies ``d = -phi`` from the slot, counted modulo ``P`` (a full turn for
``tile``; the slot figure's symmetry period for ``shape``) into ``(-P/2, P/2]``; the env
counts ``r`` from the slot-aligned pose nearest, ``round(d / step)`` steps away, so the right
index is ``r = -round(d / step) mod bins``. For ``slot`` it is 0, as for a round figure.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from agents.errors import AgentError
from spatial.angles import TWO_PI, symmetry_period

FRAMES = ("tile", "shape", "slot")
"""Rotation frames the decoding knows (the env's ``rotation_frame`` values)."""


def fine_angles(turns: int) -> np.ndarray:
    """The fine turns ``2 pi k / turns`` [rad], shape (turns,)."""
    return np.arange(turns) * TWO_PI / turns


def turn_maps(x: Any, turns: int) -> Any:
    """Maps (N, C, G, G) turned counter-clockwise by every fine turn: (N, turns, C, G, G).

    Args:
        x: A float tensor of square maps.
        turns: Fine turns (a multiple of 4).
    """
    import torch  # noqa: PLC0415
    import torch.nn.functional as F  # noqa: N812, PLC0415

    quarter = turns // 4
    n = x.shape[0]
    base = [x]
    for k in range(1, quarter):
        a = TWO_PI * k / turns
        c, s = math.cos(a), math.sin(a)
        # theta maps each output pixel to the input point it samples; with y down on the
        # page this one turns the content counter-clockwise (the tests check it against rot90)
        theta = torch.tensor([[c, -s, 0.0], [s, c, 0.0]], dtype=x.dtype).expand(n, 2, 3)
        grid = F.affine_grid(theta, list(x.shape), align_corners=False)
        base.append(
            F.grid_sample(x, grid, mode="bilinear", padding_mode="zeros", align_corners=False)
        )
    first = torch.stack(base, dim=1)  # (N, quarter, C, G, G)
    return torch.cat([torch.rot90(first, q, dims=(-2, -1)) for q in range(4)], dim=1)


def period_of(frame: str, symmetry: int) -> float:
    """The period ``P`` [rad] the frame counts a tile's offset from its slot in (0: any turn)."""
    if frame == "tile":
        return TWO_PI
    if frame == "shape":
        return symmetry_period(symmetry)
    return 0.0


def rotation_of_turns(turns: int, bins: int, frame: str, symmetry: int) -> np.ndarray:
    """The rotation index each fine turn stands for, shape (turns,) int.

    Args:
        turns: Fine turns.
        bins: The env's ``rotation_bins``.
        frame: The env's ``rotation_frame`` (one of `FRAMES`).
        symmetry: The slot figure's rotational symmetry order (0: round).
    """
    if frame not in FRAMES:
        raise AgentError(f"unknown rotation frame {frame!r}; allowed: {list(FRAMES)}")
    period = period_of(frame, symmetry)
    if frame == "slot" or period == 0:
        return np.zeros(turns, int)
    step = TWO_PI / bins
    d = np.remainder(-fine_angles(turns) + period / 2, period) - period / 2
    return (-np.round(d / step + 1e-9).astype(int)) % bins


def right_turns(turn: float, symmetry: int, turns: int, tolerance: float) -> np.ndarray:
    """Fine turns within ``tolerance`` [rad] of ``turn`` modulo the figure's symmetry.

    Returns:
        Shape (turns,) bool; the nearest turn alone where none is that close.
    """
    period = symmetry_period(symmetry)
    if period == 0:
        return np.ones(turns, bool)
    off = np.remainder(fine_angles(turns) - turn + period / 2, period) - period / 2
    out = np.abs(off) <= tolerance
    if not out.any():
        out[int(np.argmin(np.abs(off)))] = True
    return out


__all__ = ["FRAMES", "fine_angles", "period_of", "right_turns", "rotation_of_turns", "turn_maps"]
