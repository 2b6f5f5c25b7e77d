"""White balance: the colour gain that maps a camera's measured colours onto a design's palette.

Camera calibration, not shape recognition: `agents.scripted.perception` applies the gain to the
figures it describes; qshape compares colours as given.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from agents.scripted.config import PerceptionConfig
from qshape import Figure


def recolour(figure: Figure, measured: tuple[float, float, float], gain: np.ndarray) -> Figure:
    """``figure`` with the colour ``measured`` x ``gain`` (per channel, clipped to [0, 1])."""
    c = np.clip(np.asarray(measured) * gain, 0.0, 1.0)
    return dataclasses.replace(figure, color=(float(c[0]), float(c[1]), float(c[2])))


def color_gain(
    measured: np.ndarray,
    palette: np.ndarray,
    cfg: PerceptionConfig | None = None,
    per_channel: bool = True,
) -> np.ndarray:
    """Per-channel gain mapping measured colours onto a known palette (white balance).

    Each round assigns every measured colour (after the current gain) to its nearest palette
    colour and takes the per-channel median of palette / measured.

    This is camera calibration, not shape recognition, so it lives here and not in qshape:
    qshape.extract reports the colour the camera measured (corrected only for uneven light
    across the image, which it can see on the belt), and qshape.match compares colours as
    given. How much brighter the cell's lights and camera make every tile (10-40 % per
    channel) is a property of this cell, fitted against the one thing the cell knows and
    qshape does not: the design's palette.

    With few colours a per-channel gain can map any colour onto any palette colour, so it
    only repeats the raw nearest-colour guess; ``per_channel=False`` fits one brightness gain
    instead, which keeps each colour's hue: every colour goes to the palette colour its best
    scaled copy lies nearest to, and the gain is the median of those scales.

    Args:
        measured: Measured colours, shape (n, 3), RGB in [0, 1].
        palette: Known colours (the design's), shape (m, 3), RGB in [0, 1].
        cfg: Rounds and gain clip.
        per_channel: Fit a gain per channel (True) or one for all three.

    Returns:
        Gain, shape (3,); ones when there is nothing to fit.
    """
    cfg = cfg or PerceptionConfig()
    meas = np.asarray(measured, dtype=float).reshape(-1, 3)
    pal = np.asarray(palette, dtype=float).reshape(-1, 3)
    gain = np.ones(3)
    if len(meas) == 0 or len(pal) == 0:
        return gain
    lo, hi = 1.0 / cfg.max_color_gain, cfg.max_color_gain
    if not per_channel:
        norm2 = np.maximum(np.einsum("ij,ij->i", meas, meas), 1e-12)
        scale = (meas @ pal.T) / norm2[:, None]  # (n, m): best scale onto each palette colour
        resid = np.linalg.norm(scale[..., None] * meas[:, None, :] - pal[None], axis=2)
        best = scale[np.arange(len(meas)), np.argmin(resid, axis=1)]
        return np.full(3, float(np.clip(np.median(best), lo, hi)))
    # Saturated channels say nothing about the gain; near-black ones are all noise.
    usable = (meas > 1.0 / 255.0) & (meas < 1.0 - 1.0 / 255.0)
    for _ in range(cfg.color_balance_iterations):
        adj = np.clip(meas * gain, 0.0, 1.0)
        nearest = np.argmin(np.linalg.norm(adj[:, None] - pal[None], axis=2), axis=1)
        ratio = pal[nearest] / np.maximum(meas, 1e-6)
        med = np.array(
            [np.median(ratio[usable[:, c], c]) if usable[:, c].any() else 1.0 for c in range(3)]
        )
        gain = np.clip(med, lo, hi)
    return gain


__all__ = ["color_gain", "recolour"]
