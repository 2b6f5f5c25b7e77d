"""Vacuum pad: a weld equality switched at run time, gated by a seal check, with a force limit.

Why a weld (see NOTES): MuJoCo's adhesion actuator lets a held tile creep 9-13 mm across the pad
during fast moves. Here, when the vacuum is on and the pad face is close to and flat on a tile
(centre of the pad over tile material, not a hole), the weld is pointed at that tile with the
current relative pose and activated. Each update measures the net force the tool exerts on the
tile: the weld's constraint force plus the contact forces of the pad body's geoms on the held tile.
(The tile is sealed where the pad pressed it, slightly inside the soft pad contact, so the pad
contact keeps pushing the tile out while the weld holds it in: an internal force of up to ~18 N
that the weld alone would report as pull. A real cup's vacuum force is balanced by the rim's
reaction in the same way, and the tile separates when the net pull exceeds the vacuum force.)
If the pull along the pad axis exceeds the vacuum force
(pressure x pad area) or the shear exceeds friction x (vacuum force - pull), the tile is dropped
and the drop is reported. After a drop the pad does not re-seal until the vacuum is switched
off and on again (the controller sees the pressure switch open). Torques are not limited (a
simplification).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import mujoco
import numpy as np
import shapely
from shapely.geometry import Polygon

from envs.cell.config import SuctionConfig
from envs.cell.scene import SceneIds
from envs.cell.tiles.tile import PhysicalTile

WELD_ANCHOR = slice(0, 3)
WELD_RELPOS = slice(3, 6)
WELD_RELQUAT = slice(6, 10)
SEAL_REACH_SLACK = 1e-6
"""Relative margin of the seal check's reach (`Suction.seal_candidate`): far above rounding."""


@dataclass(frozen=True)
class SuctionEvent:
    """Something the pressure switch saw.

    Attributes:
        time: Simulation time [s].
        kind: "grasp", "release" or "drop".
        tile: Tile index.
        pull: Filtered pull along the pad axis at the event [N].
        shear: Filtered shear at the event [N].
    """

    time: float
    kind: str
    tile: int
    pull: float = 0.0
    shear: float = 0.0


class Suction:
    """State and logic of the vacuum pad for one compiled cell.

    Args:
        model: The compiled cell.
        ids: Its resolved ids.
        cfg: Suction configuration.
        tiles: The physical tiles, in body order (their outlines are used for the seal check).
        thickness: Tile thickness [m].
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        ids: SceneIds,
        cfg: SuctionConfig,
        tiles: Sequence[PhysicalTile],
        thickness: float,
    ) -> None:
        self._model = model
        self._ids = ids
        self.cfg = cfg
        self._half_t = thickness / 2
        self._radius = np.array([t.radius for t in tiles])
        self._radii = self._radius.tolist()
        self._seal_reach = float(
            (1 + SEAL_REACH_SLACK)
            * (self._radius.max(initial=0.0) ** 2 + (cfg.seal_max_gap + self._half_t) ** 2)
        )
        """Squared distance [m^2] from the pad face beyond which no tile centroid can pass the
        seal check (its in-plane offset within the tile's radius, its height within the gap
        plus half the thickness), with `SEAL_REACH_SLACK`; fixed with the tiles."""
        self._polys = [Polygon(t.outline, t.holes) for t in tiles]
        for p in self._polys:
            shapely.prepare(p)
        self._cos_tilt = math.cos(math.radians(cfg.seal_max_tilt_deg))
        self.holding_force = cfg.holding_force
        self.vacuum_on = False
        self._armed = False
        self.held = -1
        self.pull = 0.0
        self.shear = 0.0
        self.events: list[SuctionEvent] = []
        self.dropped = 0
        self.was_dropped = np.zeros(len(tiles), bool)
        """Tiles the pad last let go of by a drop (cleared when sealed again), shape (n,)."""
        rows = np.zeros(0, int)
        self._rows = rows

    @property
    def tile_held(self) -> bool:
        """What the pressure switch reports: vacuum on and a tile sealed."""
        return self.held >= 0

    def reset(self, data: mujoco.MjData) -> None:
        """Vacuum off, nothing held, counters cleared."""
        if self._ids.weld >= 0:
            data.eq_active[self._ids.weld] = 0
        self.vacuum_on = False
        self._armed = False
        self.held = -1
        self.pull = self.shear = 0.0
        self.events.clear()
        self.dropped = 0
        self.was_dropped[:] = False

    def set_vacuum(self, data: mujoco.MjData, on: bool) -> None:
        """Switch the vacuum; on tries to seal at once, off releases any held tile."""
        if on and not self.vacuum_on:
            self._armed = True
        self.vacuum_on = bool(on)
        if not self.vacuum_on and self.held >= 0:
            self._release(data, "release")
        elif self.vacuum_on and self.held < 0:
            self.try_seal(data)

    def seal_candidate(self, data: mujoco.MjData) -> int:
        """Index of the tile the pad would seal on now, or -1.

        The pad face (``tcp`` site) must be within ``seal_max_gap`` of a tile's face, its axis
        within ``seal_max_tilt_deg`` of the face normal, and its centre over tile material.
        Only the tiles whose centroid lies within `_seal_reach` of the pad face can pass (a
        tile's frame turns the pad's offset without changing its length), so those few are
        tested, on plain floats.
        """
        ids = self._ids
        if len(ids.tile_body) == 0:
            return -1
        px, py, pz = data.site_xpos[ids.tcp_site].tolist()
        ax, ay, az = data.site_xmat[ids.tcp_site, 2::3].tolist()  # the pad's axis (z column)
        reach = self._seal_reach
        found: list[tuple[float, int, float, float]] = []
        for i, (tx, ty, tz) in enumerate(data.xpos[ids.tile_body].tolist()):
            dx, dy, dz = px - tx, py - ty, pz - tz
            if dx * dx + dy * dy + dz * dz > reach:
                continue
            r00, r01, r02, r10, r11, r12, r20, r21, r22 = data.xmat[ids.tile_body[i]].tolist()
            lx = r00 * dx + r10 * dy + r20 * dz  # the pad face in the tile's frame
            ly = r01 * dx + r11 * dy + r21 * dz
            lz = r02 * dx + r12 * dy + r22 * dz
            gap = abs(lz) - self._half_t
            cos = abs(r02 * ax + r12 * ay + r22 * az)
            if (
                -self._half_t <= gap <= self.cfg.seal_max_gap
                and cos >= self._cos_tilt
                and float(np.hypot(lx, ly)) <= self._radii[i]
            ):
                found.append((gap, i, lx, ly))
        # Smallest gap first, ties as `numpy.argsort` orders them (its order, not the index's).
        for k in (
            np.argsort([f[0] for f in found]).tolist() if len(found) > 1 else (0,) * len(found)
        ):
            _, i, lx, ly = found[k]
            if shapely.contains_xy(self._polys[i], lx, ly):
                return i
        return -1

    def try_seal(self, data: mujoco.MjData) -> int:
        """Seal on the candidate tile if the vacuum is on; returns the held tile or -1."""
        if not (self.vacuum_on and self._armed) or self.held >= 0:
            return self.held
        i = self.seal_candidate(data)
        if i < 0:
            return -1
        ids, model = self._ids, self._model
        b1, b2 = ids.pad_body, int(ids.tile_body[i])
        r1 = data.xmat[b1].reshape(3, 3)
        qinv = np.zeros(4)
        mujoco.mju_negQuat(qinv, data.xquat[b1])
        rel = np.zeros(4)
        mujoco.mju_mulQuat(rel, qinv, data.xquat[b2])
        model.eq_obj2id[ids.weld] = b2
        model.eq_data[ids.weld, WELD_ANCHOR] = 0.0
        model.eq_data[ids.weld, WELD_RELPOS] = r1.T @ (data.xpos[b2] - data.xpos[b1])
        model.eq_data[ids.weld, WELD_RELQUAT] = rel
        data.eq_active[ids.weld] = 1
        self.held = i
        self.was_dropped[i] = False
        self.pull = self.shear = 0.0
        self.events.append(SuctionEvent(float(data.time), "grasp", i))
        return i

    def carry(self, data: mujoco.MjData) -> None:
        """Put the held tile where the weld holds it on the pad, at rest (kinematic moves).

        Reads the pad's pose from ``data`` (call after `mujoco.mj_kinematics`).
        """
        m, ids, held = self._model, self._ids, self.held
        b1 = ids.pad_body
        r1 = data.xmat[b1].reshape(3, 3)
        qa = ids.tile_qpos[held]
        data.qpos[qa : qa + 3] = data.xpos[b1] + r1 @ m.eq_data[ids.weld, 3:6]
        quat = np.zeros(4)
        mujoco.mju_mulQuat(quat, data.xquat[b1], m.eq_data[ids.weld, 6:10])
        data.qpos[qa + 3 : qa + 7] = quat
        data.qvel[ids.tile_dof_index[held]] = 0.0

    def _release(self, data: mujoco.MjData, kind: str) -> None:
        data.eq_active[self._ids.weld] = 0
        self.events.append(SuctionEvent(float(data.time), kind, self.held, self.pull, self.shear))
        if kind == "drop":
            self.dropped += 1
            self.was_dropped[self.held] = True
            self._armed = False
        self.held = -1

    def _pad_contact_force(self, data: mujoco.MjData) -> np.ndarray:
        """World force (3,) the pad body's geoms exert on the held tile through contacts [N]."""
        total = np.zeros(3)
        n = data.ncon
        if n == 0 or self.held < 0:
            return total
        model, ids = self._model, self._ids
        g0 = int(ids.tile_geom_start[self.held])
        g1 = g0 + int(ids.tile_geom_count[self.held])
        geom = data.contact.geom[:n]
        on_pad = model.geom_bodyid[geom] == ids.pad_body
        on_tile = (geom >= g0) & (geom < g1)
        f6 = np.zeros(6)
        # Normal from geom1 to geom2: the force acts on geom2 along +frame, on geom1 along -.
        for j, sign in (
            *((int(j), 1.0) for j in np.flatnonzero(on_pad[:, 0] & on_tile[:, 1])),
            *((int(j), -1.0) for j in np.flatnonzero(on_pad[:, 1] & on_tile[:, 0])),
        ):
            mujoco.mj_contactForce(model, data, j, f6)
            total += sign * (data.contact.frame[j].reshape(3, 3).T @ f6[:3])
        return total

    def measure(self, data: mujoco.MjData) -> tuple[float, float]:
        """Pull along the pad axis and shear the tool exerts on the held tile now [N].

        The tool's force is the weld's constraint force plus the pad's contact forces on the tile
        (see the module docstring): the weld alone also carries the internal push of the pad.
        """
        ids = self._ids
        rows = np.flatnonzero(
            (data.efc_type[: data.nefc] == mujoco.mjtConstraint.mjCNSTR_EQUALITY)
            & (data.efc_id[: data.nefc] == ids.weld)
        )
        if len(rows) < 3:
            return 0.0, 0.0
        force_on_tile = -data.efc_force[rows[:3]] + self._pad_contact_force(data)
        axis = data.site_xmat[ids.tcp_site].reshape(3, 3)[:, 2]
        along = float(force_on_tile @ axis)
        pull = -along
        shear = float(np.linalg.norm(force_on_tile - along * axis))
        return pull, shear

    def update(self, data: mujoco.MjData) -> SuctionEvent | None:
        """After stepping: check the holding force (drop if over), or try to seal.

        Returns:
            The event that happened in this update, if any.
        """
        if self.held >= 0:
            pull, shear = self.measure(data)
            w = self.cfg.force_filter
            self.pull = (1 - w) * self.pull + w * pull
            self.shear = (1 - w) * self.shear + w * shear
            limit = self.holding_force
            if self.pull > limit or self.shear > self.cfg.friction * (limit - self.pull):
                self._release(data, "drop")
                return self.events[-1]
            return None
        if self.vacuum_on and self.try_seal(data) >= 0:
            return self.events[-1]
        return None


__all__ = ["Suction", "SuctionEvent"]
