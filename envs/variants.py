"""Per-episode tile variants: manufacturing noise re-drawn at every reset without a rebuild.

Each tile's free body holds the geoms of all its pre-built noisy variants, one child body per
variant (`envs.scene`). `TileVariants` shows one variant per tile: the others get zero mass
and inertia, no contacts and invisible visuals; the model's derived constants are refreshed.
"""

from __future__ import annotations

from collections.abc import Sequence

import mujoco
import numpy as np

from envs.scene import SceneIds, set_tile_rotation_lengths
from envs.tiles import PhysicalTile, jitter_colors

_SWAPPED_BODY_FIELDS = ("body_mass", "body_inertia", "body_contype", "body_conaffinity")
"""Body fields a hidden variant gets 0 in (massless, no contacts)."""


class TileVariants:
    """The pool of built variants of a cell's tiles and which one each tile shows.

    Args:
        model: The built scene (every variant's body as built).
        pool: Every built tile, ``[variant][tile]``.
        body_color: RGB in [0, 1] of the tiles' ceramic body (sides and bottom).
        color_jitter: Std of the glaze colour noise drawn with each variant choice.
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        pool: Sequence[Sequence[PhysicalTile]],
        body_color: Sequence[float],
        color_jitter: float,
    ) -> None:
        self.pool = tuple(tuple(v) for v in pool)
        self.count = len(self.pool)
        """Variants built per tile."""
        self._built = {f: getattr(model, f).copy() for f in _SWAPPED_BODY_FIELDS}
        self._built_geoms = (model.geom_contype.copy(), model.geom_conaffinity.copy())
        self._body_rgba = np.array([*body_color, 1.0])
        self._color_jitter = color_jitter

    def draw(self, rng: np.random.Generator) -> tuple[np.ndarray, Sequence[PhysicalTile]] | None:
        """A random variant per tile with fresh colour noise; None with a single variant."""
        if self.count == 1:
            return None
        variant = rng.integers(self.count, size=len(self.pool[0]))
        tiles = [self.pool[v][i] for i, v in enumerate(variant)]
        return variant, jitter_colors(tiles, self._color_jitter, rng)

    def show(
        self, model: mujoco.MjModel, data: mujoco.MjData, ids: SceneIds, variant: np.ndarray
    ) -> None:
        """Make variant ``variant[i]`` of each tile i the physical one (no-op with one variant).

        Args:
            model: The scene's model (changed in place).
            data: Its data (for `mujoco.mj_setConst`).
            ids: The scene's ids.
            variant: Shown variant per tile, shape (n,).
        """
        if self.count == 1:
            return  # as built
        bodies = ids.variant_body
        hidden = np.arange(len(bodies))[:, None] != variant[None, :]
        for field, built in self._built.items():
            value = getattr(model, field)
            value[bodies] = built[bodies]
            value[bodies[hidden]] = 0
        off = np.zeros(model.nbody, bool)
        off[bodies[hidden]] = True
        contype, conaffinity = self._built_geoms
        model.geom_contype[:] = np.where(off[model.geom_bodyid], 0, contype)
        model.geom_conaffinity[:] = np.where(off[model.geom_bodyid], 0, conaffinity)
        mujoco.mj_setConst(model, data)  # constants derived from the masses (solver weights)
        set_tile_rotation_lengths(model, ids)  # mj_setConst measured them to the origin

    def paint(self, model: mujoco.MjModel, ids: SceneIds, tiles: Sequence[PhysicalTile]) -> None:
        """Visual colours as built: the shown tiles in theirs, the other variants hidden."""
        if not len(tiles):
            return
        rgba = model.geom_rgba
        rgba[ids.variant_visual, 3] = 0.0
        rgba[ids.tile_visual[:, 0]] = self._body_rgba
        rgba[ids.tile_visual[:, 1], :3] = [t.color for t in tiles]
        rgba[ids.tile_visual[:, 1], 3] = 1.0


__all__ = ["TileVariants"]
