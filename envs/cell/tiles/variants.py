"""Per-episode tile variants: manufacturing noise re-drawn at every reset without a rebuild.

Each tile's free body holds the geoms of all its pre-built noisy variants, one child body per
variant (`envs.cell.scene`). `TileVariants` shows one variant per tile: the others get zero mass
and inertia, no contacts and invisible visuals. The model's constants derived from the masses
(what `mujoco.mj_setConst` computes: subtree masses, inverse weights, joint-space inertia at
qpos0) are computed once per variant when the cell is built; a reset copies each tile's rows
from its variant's table (every tile is its own kinematic tree), so no reset calls
`mujoco.mj_setConst`.
"""

from __future__ import annotations

from collections.abc import Sequence

import mujoco
import numpy as np

from envs.cell.scene import SceneIds, set_tile_rotation_lengths
from envs.cell.tiles.tile import PhysicalTile, jitter_colors

_SWAPPED_BODY_FIELDS = ("body_mass", "body_inertia", "body_contype", "body_conaffinity")
"""Body fields a hidden variant gets 0 in (massless, no contacts)."""
CONST_BODY_FIELDS = ("body_subtreemass", "body_invweight0")
"""Body fields `mujoco.mj_setConst` derives from the masses (tabled per variant)."""
CONST_DOF_FIELDS = ("dof_M0", "dof_invweight0")
"""Dof fields `mujoco.mj_setConst` derives from the masses (tabled per variant)."""
_COM_TRACKING = (
    mujoco.mjtCamLight.mjCAMLIGHT_TRACKCOM,
    mujoco.mjtCamLight.mjCAMLIGHT_TARGETBODYCOM,
)
"""Camera and light modes that read the model's centre of mass (not tabled)."""


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
        self._consts: _VariantConstants | None = None

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

        The first call tables the mass-derived constants of every variant (one
        `mujoco.mj_setConst` per variant); later calls copy rows from the table.

        Args:
            model: The scene's model (changed in place).
            data: Its data (for `mujoco.mj_setConst`).
            ids: The scene's ids.
            variant: Shown variant per tile, shape (n,).
        """
        if self.count == 1:
            return  # as built
        if self._consts is None:
            self._consts = _VariantConstants.measure(self, model, data, ids)
        self._swap(model, ids, variant)
        self._consts.apply(model, data, ids, variant)

    def _swap(self, model: mujoco.MjModel, ids: SceneIds, variant: np.ndarray) -> None:
        """Masses, inertias and contacts of variant ``variant[i]`` of each tile i."""
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

    def paint(self, model: mujoco.MjModel, ids: SceneIds, tiles: Sequence[PhysicalTile]) -> None:
        """Visual colours as built: the shown tiles in theirs, the other variants hidden."""
        if not len(tiles):
            return
        rgba = model.geom_rgba
        rgba[ids.variant_visual, 3] = 0.0
        rgba[ids.tile_visual[:, 0]] = self._body_rgba
        rgba[ids.tile_visual[:, 1], :3] = [t.color for t in tiles]
        rgba[ids.tile_visual[:, 1], 3] = 1.0


class _VariantConstants:
    """`mujoco.mj_setConst`'s mass-derived constants of every variant, per tile.

    A tile's free body hangs from the world, so its tree's constants depend on its own shown
    variant only; the world body's subtree mass is their sum. Cameras and lights that track a
    centre of mass would also need the whole model's centre of mass: with any of them (or a
    tile not hanging from the world) the table is not used and `apply` calls
    `mujoco.mj_setConst`.

    Args:
        body_rows: Per tile, its free body and its variants' bodies, shape (n, 1 + V).
        body: Per field of `CONST_BODY_FIELDS`, its values per variant, (V, nbody, ...).
        dof: Per field of `CONST_DOF_FIELDS`, its values per variant, (V, nv).
        exact: The table reproduces `mujoco.mj_setConst`.
    """

    def __init__(
        self,
        body_rows: np.ndarray,
        body: dict[str, np.ndarray],
        dof: dict[str, np.ndarray],
        exact: bool,
    ) -> None:
        self.body_rows = body_rows
        self.body = body
        self.dof = dof
        self.exact = exact

    @staticmethod
    def measure(
        variants: TileVariants, model: mujoco.MjModel, data: mujoco.MjData, ids: SceneIds
    ) -> _VariantConstants:
        """Show each variant on every tile in turn and keep what `mj_setConst` derives."""
        n = ids.variant_body.shape[1]
        free = model.body_parentid[ids.variant_body[0]]
        exact = (
            bool(np.all(model.body_parentid[free] == 0))
            and not np.isin(model.cam_mode, _COM_TRACKING).any()
            and not np.isin(model.light_mode, _COM_TRACKING).any()
        )
        tables: dict[str, list[np.ndarray]] = {f: [] for f in CONST_BODY_FIELDS + CONST_DOF_FIELDS}
        for v in range(variants.count):
            variants._swap(model, ids, np.full(n, v))
            mujoco.mj_setConst(model, data)
            for f, rows in tables.items():
                rows.append(getattr(model, f).copy())
        set_tile_rotation_lengths(model, ids)  # mj_setConst measured them to the origin
        body = {f: np.stack(tables[f]) for f in CONST_BODY_FIELDS}
        dof = {f: np.stack(tables[f]) for f in CONST_DOF_FIELDS}
        return _VariantConstants(np.column_stack([free, ids.variant_body.T]), body, dof, exact)

    def apply(
        self, model: mujoco.MjModel, data: mujoco.MjData, ids: SceneIds, variant: np.ndarray
    ) -> None:
        """Constants of the shown variants (after `TileVariants._swap`)."""
        if not self.exact:
            mujoco.mj_setConst(model, data)
            set_tile_rotation_lengths(model, ids)
            return
        rows, dofs = self.body_rows, ids.tile_dof_index
        for f, table in self.body.items():
            getattr(model, f)[rows] = table[variant[:, None], rows]
        mass, free = self.body["body_subtreemass"], rows[:, 0]
        model.body_subtreemass[0] = mass[0, 0] + np.sum(mass[variant, free] - mass[0, free])
        for f, table in self.dof.items():
            getattr(model, f)[dofs] = table[variant[:, None], dofs]


__all__ = ["CONST_BODY_FIELDS", "CONST_DOF_FIELDS", "TileVariants"]
