"""The network: rotation-equivariant encoders and a correlation over fine turns.

Two encoders embed a tile crop (mask and masked RGB, 4 channels) and a slot (the output
camera's crop of it, plus its figure drawn from the task description) into dense feature maps
of ``features`` channels on the crop grid. Each encoder is a stack of plain bias-free 3 x 3
convolutions made equivariant to quarter turns by averaging over turned copies
(``E(x) = 1/4 sum_q rot(-q) e(rot(q) x)``): turning the input a quarter turn turns the map a
quarter turn, exactly, and an empty crop maps to zeros. The score of (tile i, slot j, fine turn
k) is the cosine of the tile's map turned by ``phi_k`` (`agents.equivariant.turns.turn_maps`)
with the slot's map, times a learned temperature:

    s(i, j, k) = tau * <turn(E_t(tile_i), phi_k), E_s(slot_j)> / (|E_t(tile_i)| |E_s(slot_j)|)

plus a colour term: the squared distance between the tile's mean colour and the slot's (its
design colour where the template is given, else the output picture's), times a learned
weight ``alpha`` (``colour_weight`` at start), the same for every turn:

    - alpha * |rgb(tile_i) - rgb(slot_j)|^2

Where a design's slots of one shape differ only by colour (a hexagon mosaic) the colour
decides; where all tiles have one colour the term is the same for every pair and changes
nothing. One matching function, shared by every tile, slot and turn: it compares local shape
and colour, not identities, which is what lets it place shapes it never saw.
"""

from __future__ import annotations

import math
from typing import Any

from agents.equivariant.config import EquivariantConfig
from agents.equivariant.turns import turn_maps

TILE_CHANNELS = 4
"""Channels of a tile crop: foreground mask, then red, green, blue inside it."""


def build_network(cfg: EquivariantConfig) -> Any:
    """The scorer (a torch module: ``forward(tiles, slots) -> (B, n, k, turns)``)."""
    import torch  # noqa: PLC0415

    def stack(cin: int) -> Any:
        w = cfg.width
        return torch.nn.Sequential(
            torch.nn.Conv2d(cin, w, 3, padding=1, bias=False),
            torch.nn.ReLU(),
            torch.nn.Conv2d(w, w, 3, padding=1, bias=False),
            torch.nn.ReLU(),
            torch.nn.Conv2d(w, w, 3, padding=2, dilation=2, bias=False),
            torch.nn.ReLU(),
            torch.nn.Conv2d(w, cfg.features, 1, bias=False),
        )

    class Equivariant(torch.nn.Module):
        """``E(x) = 1/4 sum_q rot(-q) e(rot(q) x)`` for a plain stack ``e``."""

        def __init__(self, cin: int) -> None:
            super().__init__()
            self.e = stack(cin)

        def forward(self, x: Any) -> Any:
            turned = torch.cat([torch.rot90(x, q, dims=(-2, -1)) for q in range(4)])
            out = self.e(turned).chunk(4)
            return sum(torch.rot90(o, -q, dims=(-2, -1)) for q, o in enumerate(out)) / 4

    class Scorer(torch.nn.Module):
        def __init__(self) -> None:
            super().__init__()
            self.tile_net = Equivariant(TILE_CHANNELS)
            self.slot_net = Equivariant(cfg.slot_channels)
            self.log_tau = torch.nn.Parameter(torch.tensor(math.log(cfg.temperature)))
            self.log_alpha = torch.nn.Parameter(torch.tensor(math.log(cfg.colour_weight)))

        def forward(self, tiles: Any, slots: Any) -> Any:
            """Scores: tiles (B, n, 4, G, G), slots (B, k, C, G, G) -> (B, n, k, turns).

            Each map is scaled to unit norm before the tile maps are turned (a turn keeps a
            map's norm up to the resampling of its corners, where an object centred in its
            crop has no features).
            """
            b, n = tiles.shape[:2]
            k = slots.shape[1]
            eps = 1e-6
            ft = self.tile_net(tiles.flatten(0, 1))
            ft = ft / (ft.flatten(1).norm(dim=1)[:, None, None, None] + eps)
            fs = self.slot_net(slots.flatten(0, 1)).flatten(1)
            fs = (fs / (fs.norm(dim=1, keepdim=True) + eps)).reshape(b, k, -1)
            turned = turn_maps(ft, cfg.turns).reshape(b, n * cfg.turns, -1)
            out = torch.bmm(turned, fs.transpose(1, 2)).reshape(b, n, cfg.turns, k)
            shape = out.permute(0, 1, 3, 2) * self.log_tau.exp()
            colour = mean_colour(tiles, 0, 1)[:, :, None] - slot_colour(slots)[:, None]
            return shape - self.log_alpha.exp() * (colour**2).sum(-1)[..., None]

    def slot_colour(slots: Any) -> Any:
        """A slot's colour: its template's (design colour) if given, else the picture's."""
        return mean_colour(slots, 4, 5) if cfg.template else mean_colour(slots, 0, 1)

    return Scorer()


def mean_colour(x: Any, mask: int, rgb: int) -> Any:
    """Mean RGB inside a crop's mask: x (B, m, C, G, G), channels ``mask`` and ``rgb..rgb+3``.

    The RGB channels are stored multiplied by the mask, so the mean is their sum over the
    mask's; an empty crop gives black.
    """
    w = x[:, :, mask].sum((-2, -1))
    return x[:, :, rgb : rgb + 3].sum((-2, -1)) / (w[..., None] + 1e-6)


__all__ = ["TILE_CHANNELS", "build_network"]
