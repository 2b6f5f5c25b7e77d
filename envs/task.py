"""The mosaic task: which tile belongs where, placement evaluation and rewards.

`MosaicTask.evaluate` returns one `Evaluation` the reward, the episode end and ``info`` all read
(``info["evaluation"]`` is its `Evaluation.as_dict`; ``info["tiles_per_min"]`` its
`Evaluation.tiles_per_min`). `MosaicTask.initialize_episode` is the
episode set-up hook: layout (with retries), per-episode colour and light randomisation, belt
speed and optional settling.
Tiles and slots are matched by class name (the design's shape-and-colour class); distractors are
never correct. A tile counts as placed when it lies over the mesh (not held, at any height: flat
on the sheet, stacked on another tile or tilted); it fills the nearest slot when it lies flat on
the sheet and class, position and yaw (modulo the tile's symmetry) are within tolerance. Every
other placed real tile is misplaced.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from envs.cell.accounting import ON_INPUT, WAITING, TileFlags, state_counts, tile_states
from envs.cell.camera_effects import CameraJitter
from envs.cell.cell import Cell
from envs.env_config import EnvConfig
from envs.episode_setup import retry_layout
from envs.errors import CellError, EnvError
from envs.rewards import STAGES, SlotProgress, StagedReward, load_staged_config
from spatial.angles import yaw_periods
from spatial.units import MM_PER_M

REWARD_TERMS = (
    "correct",
    "success",
    "misplaced",
    "dropped",
    "lost",
    "distractor",
    "failed_action",
    "reach",
    "grasp",
    "carry",
    *(f"stage_{s}" for s in STAGES),
)
"""Names of the reward terms (each is reported in ``info`` as ``reward_<name>``)."""


SEED_BOUND = 2**63
"""Exclusive bound of the layout seeds drawn from the episode generator at each reset."""


@dataclass(frozen=True)
class Placement:
    """Placement of every tile at one instant.

    Attributes:
        on_mesh: Tiles over the mesh, fed and not held, shape (n,) bool (any height above the
            sheet: a tile stacked on another one is on the mesh too).
        flat: Tiles on the mesh lying flat on the sheet (height and tilt within tolerance),
            shape (n,) bool.
        slot: Nearest slot of each tile on the mesh (of two at the same distance the first;
            -1 off the mesh), shape (n,).
        position_error: Distance of each tile's centroid to that slot's [m], NaN off the mesh.
        yaw_error: Yaw error modulo the tile's symmetry [rad], NaN off the mesh.
        correct: Tiles filling their nearest slot correctly, shape (n,) bool.
        slot_filled: Slots filled correctly, shape (k,) bool.
    """

    on_mesh: np.ndarray
    flat: np.ndarray
    slot: np.ndarray
    position_error: np.ndarray
    yaw_error: np.ndarray
    correct: np.ndarray
    slot_filled: np.ndarray


@dataclass(frozen=True)
class Evaluation:
    """The task's state at one instant.

    Attributes:
        success: Every slot is filled correctly.
        failure: Not a success and no remaining real tile can fill an open slot (the episode
            cannot succeed any more).
        correct: Slots filled correctly.
        misplaced: Real tiles on the mesh not filling a slot (wrong class, pose beyond
            tolerance, stacked on another tile, e.g. put into a filled slot, or tilted).
        dropped: Drop events: times the pad lost a tile in transit (a tile dropped, picked up
            again and dropped again counts twice).
        stranded: Real tiles fed that lie out of every other state: beside the mesh on the
            output belt, tilted over its edge, on a frame (out of the pick area: not placeable).
        lost: Tiles lost off the input belt (distractors included; the ``lost`` reward term).
        fed: Real tiles fed into the cell so far; the sum of ``on_input``, ``held``,
            ``correct``, ``misplaced``, ``stranded``, ``dropped_tiles``, ``lost_tiles`` and
            ``rejected`` (`envs.cell.accounting`: each real tile fed is in exactly one state).
        waiting: Real tiles not fed yet.
        on_input: Real tiles on the input belt, not held.
        held: Real tiles on the pad (0 or 1).
        dropped_tiles: Real tiles the pad let go of in transit, lying off the input belt and
            the mesh (on the floor included).
        lost_tiles: Real tiles lost off the input belt (past its end or onto the floor).
        rejected: Real tiles put into the reject bin (released there by the pad, or taken
            off the belt with their batch).
        distractors_placed: Distractor tiles on the mesh.
        slots: Number of slots.
        slot_filled: Per slot: filled correctly.
        placeable: Open slots a real tile of the right class on the input belt, held or
            waiting to be fed could still fill (stranded, dropped, lost and rejected tiles
            cannot: the pick area covers the input belt only).
        position_error_mm: Mean position error of the tiles on the mesh [mm] (None: none).
        position_error_mm_max: Largest of those [mm].
        yaw_error_deg: Mean yaw error modulo symmetry of the tiles on the mesh [deg].
        yaw_error_deg_max: Largest of those [deg].
    """

    success: bool
    failure: bool
    correct: int
    misplaced: int
    dropped: int
    stranded: int
    lost: int
    fed: int
    waiting: int
    on_input: int
    held: int
    dropped_tiles: int
    lost_tiles: int
    rejected: int
    distractors_placed: int
    slots: int
    slot_filled: tuple[bool, ...]
    placeable: int
    position_error_mm: float | None
    position_error_mm_max: float | None
    yaw_error_deg: float | None
    yaw_error_deg_max: float | None

    def as_dict(self) -> dict[str, Any]:
        """The fields as a plain dict (``slot_filled`` as a list), as ``info["evaluation"]``."""
        d = {f.name: getattr(self, f.name) for f in _EVALUATION_FIELDS}  # flat: no deep copy
        d["slot_filled"] = list(self.slot_filled)
        return d

    @classmethod
    def from_info(cls, info: Mapping[str, Any]) -> Evaluation:
        """The evaluation in a step's ``info`` (`as_dict` read back; `EnvError` if absent)."""
        d = info.get("evaluation")
        if not isinstance(d, Mapping) or any(f.name not in d for f in _EVALUATION_FIELDS):
            raise EnvError("info has no complete 'evaluation' (a MosaicAssembly step's info)")
        fields = {f.name: d[f.name] for f in _EVALUATION_FIELDS}
        return cls(**{**fields, "slot_filled": tuple(bool(x) for x in d["slot_filled"])})

    def tiles_per_min(self, sim_s: float, horizon_s: float = 0.0) -> float:
        """Correct tiles per simulated minute over `throughput_span`: the one definition."""
        return tiles_per_minute(self.correct, self.throughput_span(sim_s, horizon_s))

    def throughput_span(self, sim_s: float, horizon_s: float = 0.0) -> float:
        """``sim_s`` [s] for a success, else ``max(sim_s, horizon_s)``: stopping early is slow."""
        return sim_s if self.success else max(sim_s, horizon_s)


def tiles_per_minute(correct: int, span_s: float) -> float:
    """``correct`` tiles over ``span_s`` simulated seconds, per minute (0 for no time)."""
    return 60.0 * correct / span_s if span_s > 0 else 0.0  # 60 s per minute


_EVALUATION_FIELDS = dataclasses.fields(Evaluation)


@dataclass(frozen=True, eq=False)
class GroundTruth:
    """Privileged state of the tiles (scoring and reports only, never for decisions).

    Attributes:
        xy: Tile area-centroid positions, shape (n, 2) [m].
        yaw: Tile yaws, shape (n,) [rad].
        class_name: Each tile's shape-and-colour class.
        distractor: Tiles the design lacks, shape (n,) bool.
        symmetry: Rotational symmetry order of each tile, shape (n,) (0: continuous).
        on_stage: Tiles fed into the cell (not parked), shape (n,) bool.
        slot_class: Each slot's class.
    """

    xy: np.ndarray
    yaw: np.ndarray
    class_name: tuple[str, ...]
    distractor: np.ndarray
    symmetry: np.ndarray
    on_stage: np.ndarray
    slot_class: tuple[str, ...]

    def nearest(self, xy: np.ndarray) -> tuple[int, float]:
        """The fed tile nearest to a world point: (index, distance [m])."""
        d = np.linalg.norm(self.xy - np.asarray(xy, float)[None], axis=1)
        d[~self.on_stage] = np.inf
        i = int(np.argmin(d))
        return i, float(d[i])


class MosaicTask:
    """Placement evaluation and rewards of one cell and design.

    Args:
        cell: The cell (its ``slots`` are the mesh; its tiles the feed).
        config: Environment configuration (tolerances and reward weights).
    """

    def __init__(self, cell: Cell, config: EnvConfig) -> None:
        self.cell = cell
        self.cfg = config
        slot_names = [s.shape.name for s in cell.slots]
        classes = sorted(set(slot_names) | {t.shape.name for t in cell.tiles})
        self.class_names = tuple(classes)
        index = {c: i for i, c in enumerate(classes)}
        self.slot_class = np.array([index[n] for n in slot_names], dtype=int)
        self.tile_class = np.array([index[t.shape.name] for t in cell.tiles], dtype=int)
        self.distractor = cell.is_distractor.copy()
        self.symmetry = np.array([t.shape.symmetry for t in cell.tiles], dtype=int)
        self._yaw_period = yaw_periods(self.symmetry)  # fixed with the tiles: never stale
        self.slot_xyyaw = cell.slot_poses_world()
        self._mesh_lo, self._mesh_hi = cell.geometry.mesh_lo, cell.geometry.mesh_hi
        self._rest_z = cell.geometry.mesh_top + cell.cfg.tiles.thickness / 2
        self._yaw_tol = math.radians(config.yaw_tolerance_deg)
        self._flat = math.cos(math.radians(config.max_tilt_deg))
        self._real = ~self.distractor
        # Plain-float copies for `_lie` (fixed with the cell's tiles and slots, never stale).
        self._slot_xy = self.slot_xyyaw[:, :2].tolist()
        self._slot_yaw = self.slot_xyyaw[:, 2].tolist()
        self._slot_classes = self.slot_class.tolist()
        self._classes = self.tile_class.tolist()
        self._reals = self._real.tolist()
        self._orders = self.symmetry.tolist()
        self._periods = self._yaw_period.tolist()
        self._lies: list[tuple[list[float], tuple[bool, int, float, float, bool] | None] | None]
        self._lies = [None] * len(cell.tiles)
        self._base_light = cell.model.light_diffuse.copy()
        self._camera_jitter = CameraJitter(
            cell.model, [cell.ids.input_camera, cell.ids.output_camera]
        )
        self._settle_steps = round(config.reset_settle / float(cell.model.opt.timestep))
        self.staged = (
            StagedReward(self, load_staged_config()) if config.reward_mode == "staged" else None
        )
        self._prev = self.evaluate()

    def initialize_episode(self, rng: np.random.Generator) -> None:
        """Set an episode up (the env's ``reset``): all randomness from ``rng``.

        The cell is reset with a fresh layout (redrawn up to ``layout_tries`` times when the
        tiles do not fit; its feed lays out the initial tiles and its variants are redrawn),
        tile colours, lights and camera poses are randomised (``color_randomization``,
        ``light_randomization``, ``camera_position_jitter``, ``camera_angle_jitter_deg``),
        the input belt is set running and, with ``reset_settle`` > 0, physics runs that long
        (the tiles are laid at their contact height, at rest: 0 needs no settling).

        Raises:
            CellError: No layout draw fits.
        """
        cell, cfg = self.cell, self.cfg

        def draw(_attempt: int) -> None:
            cell.reset(seed=np.random.default_rng(rng.integers(SEED_BOUND)))

        retry_layout(draw, cfg.layout_tries, retry_on=CellError)  # `envs.episode_setup`
        self._randomize(rng)
        cell.belt_speed = cfg.belt_speed
        if self._settle_steps:
            cell.step(self._settle_steps)
        self.reset()

    def _randomize(self, rng: np.random.Generator) -> None:
        """Per-episode colour, light and camera changes (the cell's reset restored the colours).

        Each randomisation draws from ``rng`` only when it is on, so turning one on leaves
        the episodes of the others unchanged.
        """
        m, cfg = self.cell.model, self.cfg
        visual = self.cell.ids.tile_visual.ravel()
        if cfg.color_randomization > 0 and len(visual):
            f = 1 + rng.normal(0.0, cfg.color_randomization, (len(visual), 3))
            m.geom_rgba[visual, :3] = np.clip(m.geom_rgba[visual, :3] * f, 0.0, 1.0)
        if cfg.light_randomization > 0 and m.nlight:
            f = 1 + rng.normal(0.0, cfg.light_randomization, (m.nlight, 1))
            m.light_diffuse[:] = np.clip(self._base_light * f, 0.0, 1.0)
        if cfg.camera_position_jitter > 0 or cfg.camera_angle_jitter_deg > 0:
            self._camera_jitter.draw(
                self.cell.data, rng, cfg.camera_position_jitter, cfg.camera_angle_jitter_deg
            )

    @property
    def last_evaluation(self) -> Evaluation:
        """The evaluation `reset` or the last `rewards` call was given or took."""
        return self._prev

    def reset(self) -> None:
        """Forget the counts of the previous step (call after the cell's reset)."""
        self._prev = self.evaluate()
        if self.staged is not None:
            self.staged.reset(self._prev)

    def placement(self) -> Placement:
        """Where every tile lies relative to the slots now.

        One read of the tiles' poses; each tile on the stage and off the pad is looked up in
        `_lie` (remembered per tile while its pose stays the same), then the slots are shared
        out: the closest correct tile fills a slot, the others in it are misplaced.
        """
        cell = self.cell
        # Per tile: position, quaternion (w, x, y, z).
        rows = cell.data.qpos[cell.ids.tile_qpos_index].tolist()
        n, k = len(rows), len(self.slot_class)
        on_stage = cell.on_stage.tolist()
        held = cell.held_tile
        on_mesh = [False] * n
        flat = [False] * n
        slot = [-1] * n
        perr = [math.nan] * n
        yerr = [math.nan] * n
        fills: list[int] = []
        lies = self._lies
        for i, row in enumerate(rows):
            if not on_stage[i] or i == held:
                continue
            kept = lies[i]
            lie = kept[1] if kept is not None and kept[0] == row else self._lie(i, row)
            if lie is None:
                continue
            on_mesh[i], flat[i] = True, lie[0]
            if k:
                slot[i], perr[i], yerr[i] = lie[1], lie[2], lie[3]
                if lie[4]:
                    fills.append(i)
        correct = np.zeros(n, bool)
        filled = np.zeros(k, bool)
        # One tile per slot: the closest correct tile fills it, others are misplaced.
        for i in sorted(fills, key=lambda t: (slot[t], perr[t])):
            if not filled[slot[i]]:
                filled[slot[i]] = correct[i] = True
        return Placement(
            np.array(on_mesh),
            np.array(flat),
            np.array(slot),
            np.array(perr),
            np.array(yerr),
            correct,
            filled,
        )

    def _lie(self, i: int, row: list[float]) -> tuple[bool, int, float, float, bool] | None:
        """How tile ``i`` lies at qpos ``row`` (position, quaternion), None when not over the mesh.

        Over the mesh: (flat on the sheet, nearest slot, its centroid distance [m], the yaw
        error modulo the tile's symmetry [rad], fills that slot correctly), on plain floats
        (the same arithmetic, bit for bit, as the arrays it replaced; the yaw by
        `numpy.arctan2`, whose last bit differs from `math.atan2`'s). Kept in ``_lies[i]`` with
        its ``row``, which `placement` looks up first: what it is computed from besides
        ``row`` (slots, classes, tolerances, the mesh) is fixed for the task, so only a new
        pose of the tile invalidates it (the tiles resting while another one is moved are
        looked up); it replaces the tile's entry (one entry per tile).
        """
        x, y, z, w, qx, qy, qz = row
        dz = z - self._rest_z
        tol = self.cfg.mesh_height_tolerance
        lo, hi = self._mesh_lo, self._mesh_hi
        lie: tuple[bool, int, float, float, bool] | None = None
        if lo[0] <= x <= hi[0] and lo[1] <= y <= hi[1] and dz >= -tol:
            up = 1 - 2 * (qx * qx + qy * qy)  # z component of the tile's z axis
            flat = dz <= tol and up > self._flat
            nearest, err = -1, math.inf
            for j, (sx, sy) in enumerate(self._slot_xy):
                dx, dy = x - sx, y - sy
                d = math.sqrt(dx * dx + dy * dy)
                if d < err:
                    nearest, err = j, d
            yaw_err = math.nan
            fills = False
            if nearest >= 0:
                yaw = float(np.arctan2(2 * (w * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz)))
                period = self._periods[i]
                yaw_err = 0.0
                if self._orders[i] > 0:
                    d = yaw - self._slot_yaw[nearest]
                    yaw_err = abs((d + period / 2) % period - period / 2)
                fills = (
                    flat
                    and self._classes[i] == self._slot_classes[nearest]
                    and self._reals[i]
                    and err <= self.cfg.position_tolerance
                    and yaw_err <= self._yaw_tol
                )
            lie = (flat, nearest, err, yaw_err, fills)
        self._lies[i] = (row, lie)
        return lie

    def evaluate(self) -> Evaluation:
        """The task's state now (also ``info["evaluation"]``, as a dict)."""
        p = self.placement()
        cell = self.cell
        states = self.tile_states(p)
        counts_by_state = state_counts(states)
        distractors = int(np.count_nonzero(p.on_mesh & self.distractor))
        # Tiles still available: real tiles on the input belt, held or waiting to be fed
        # (pick areas cover the input belt only).
        avail = [s in (ON_INPUT, WAITING) for s in states.tolist()]
        held = cell.held_tile
        if held >= 0 and self._reals[held]:
            avail[held] = True
        filled = p.slot_filled.tolist()
        counts = [0] * len(self.class_names)
        for i, c in enumerate(self._classes):
            counts[c] += avail[i]
        need = [0] * len(self.class_names)
        for j, c in enumerate(self._slot_classes):
            need[c] += not filled[j]
        placeable = sum(map(min, counts, need))
        on = p.on_mesh
        pe = p.position_error[on] * MM_PER_M
        ye = np.degrees(p.yaw_error[on])
        n_on = len(pe)
        n_filled = sum(filled)
        success = n_filled == len(filled) and len(filled) > 0
        return Evaluation(
            success=success,
            failure=not success and placeable == 0,
            correct=n_filled,
            misplaced=counts_by_state["misplaced"],
            dropped=int(cell.n_dropped),
            stranded=counts_by_state["stranded"],
            lost=int(cell.n_lost),
            fed=sum(counts_by_state.values()),
            waiting=int(np.count_nonzero(states == WAITING)),
            on_input=counts_by_state["on_input"],
            held=counts_by_state["held"],
            dropped_tiles=counts_by_state["dropped_tiles"],
            lost_tiles=counts_by_state["lost_tiles"],
            rejected=counts_by_state["rejected"],
            distractors_placed=distractors,
            slots=len(filled),
            slot_filled=tuple(filled),
            placeable=placeable,
            position_error_mm=float(pe.sum()) / n_on if n_on else None,
            position_error_mm_max=float(pe.max()) if n_on else None,
            yaw_error_deg=float(ye.sum()) / n_on if n_on else None,
            yaw_error_deg_max=float(ye.max()) if n_on else None,
        )

    def tile_states(self, placement: Placement | None = None) -> np.ndarray:
        """State code of every tile now (`envs.cell.accounting.tile_states`), shape (n,) int8."""
        p = placement if placement is not None else self.placement()
        cell = self.cell
        held = np.arange(len(cell.tiles)) == cell.held_tile  # none for -1
        retired = cell.retired
        rejected = cell.lost_tracker.rejected
        return tile_states(
            TileFlags(
                real=self._real,
                fed=cell.on_stage | retired,
                held=held,
                rejected=rejected | retired,
                lost=cell.lost_tracker.lost,
                was_dropped=cell.suction.was_dropped,
                on_mesh=p.on_mesh,
                correct=p.correct,
                on_input=cell.input_side(),
            )
        )

    def ground_truth(self) -> GroundTruth:
        """Privileged tile poses and classes now (scoring and reports only)."""
        cell = self.cell
        poses = cell.tile_poses()
        return GroundTruth(
            xy=poses.pos[:, :2],
            yaw=poses.yaw,
            class_name=tuple(t.shape.name for t in cell.tiles),
            distractor=self.distractor.copy(),
            symmetry=self.symmetry.copy(),
            on_stage=cell.on_stage.copy(),
            slot_class=tuple(s.shape.name for s in cell.slots),
        )

    def wanted_tiles(self, evaluation: SlotProgress) -> np.ndarray:
        """Real tiles on the input side whose class fills an open slot, shape (n,) bool."""
        filled = np.asarray(evaluation.slot_filled, bool)
        open_classes = np.unique(self.slot_class[~filled])
        p_on = self.placement().on_mesh
        return (
            ~self.distractor
            & self.cell.on_stage
            & ~self.cell.lost
            & ~p_on
            & np.isin(self.tile_class, open_classes)
        )

    def rewards(self, evaluation: Evaluation, failed_action: bool) -> dict[str, float]:
        """Reward terms of a step, from the change since the previous call.

        Args:
            evaluation: `evaluate()` after the step.
            failed_action: The action could not execute (unreachable pose, no tile, ...).

        Returns:
            Every term of `REWARD_TERMS` (dense terms are 0 in sparse mode); their sum is the
            reward.
        """
        c, prev = self.cfg, self._prev
        terms = dict.fromkeys(REWARD_TERMS, 0.0)
        e = evaluation
        terms["correct"] = c.reward_correct * (e.correct - prev.correct)
        terms["success"] = c.reward_success * float(e.success and not prev.success)
        terms["misplaced"] = -c.penalty_misplaced * max(e.misplaced - prev.misplaced, 0)
        terms["dropped"] = -c.penalty_dropped * (e.dropped - prev.dropped)
        terms["lost"] = -c.penalty_lost * (e.lost - prev.lost)
        terms["distractor"] = -c.penalty_distractor * max(
            e.distractors_placed - prev.distractors_placed, 0
        )
        terms["failed_action"] = -c.penalty_failed_action * float(failed_action)
        if c.reward_mode == "dense":
            terms.update(self._dense(evaluation))
        if self.staged is not None:
            terms.update(self.staged.terms(evaluation))
        self._prev = evaluation
        return terms

    def _dense(self, evaluation: Evaluation) -> dict[str, float]:
        """Shaping toward picking a wanted tile and carrying it to a free slot of its class."""
        cell, c = self.cell, self.cfg
        tool = cell.tcp_pose()[0]
        held = cell.held_tile
        out = {"reach": 0.0, "grasp": 0.0, "carry": 0.0}
        filled = np.asarray(evaluation.slot_filled, bool)
        if held >= 0 and not self.distractor[held]:
            free = np.flatnonzero(~filled & (self.slot_class == self.tile_class[held]))
            if len(free):
                out["grasp"] = c.dense_grasp
                pos = cell.tile_poses().pos[held, :2]
                d = np.linalg.norm(self.slot_xyyaw[free, :2] - pos, axis=1).min()
                out["carry"] = -c.dense_carry * float(d)
            return out
        wanted = np.flatnonzero(self.wanted_tiles(evaluation))
        if len(wanted):
            pos = cell.tile_poses().pos[wanted]
            out["reach"] = -c.dense_reach * float(np.linalg.norm(pos - tool, axis=1).min())
        return out


__all__ = ["REWARD_TERMS", "Evaluation", "GroundTruth", "MosaicTask", "Placement"]
