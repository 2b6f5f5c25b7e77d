"""Demonstrations for the equivariant policy: from the privileged expert, or by disassembly.

- **expert**: each step the privileged expert (`MosaicAssemblyEnv.expert_action`) moves the
  first tile on the belt into an open slot of its class; the step is recorded, then played.
- **disassembly** (no expert): the episode's tiles are laid into their slots, a finished
  mosaic; the robot then takes them out one at a time, in a random order, and sets each down
  on the input belt (at the spot and yaw the env's own reset laid it at), the cameras looking
  after every move. Played backwards, each removal is a demonstration: from the picture after
  it, that tile into that slot, turned back by the turn the removal made. Nothing decides
  which tile goes where but the mosaic itself.

Both read the env's state only to cut labels: which tile and slot (the agent indices of the
env's current index maps) and the turn. Training designs come from the rung's own split
(`envs.tasks.BenchmarkTask.env_kwargs`): a new procedural design at every reset where the
split has one.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from typing import Any

import gymnasium as gym
import numpy as np

from agents.equivariant.config import EquivariantConfig
from agents.equivariant.records import (
    ARRAYS,
    SOURCES,
    CropCutter,
    Header,
    RecordsError,
    StepRecords,
    crop_settings,
    to_bytes,
)
from envs.actions import PickPlaceExecutor
from envs.task_spec import PickPlaceCommand
from spatial.angles import rotate_xy


def _env_for(
    task_id: str, index: int, image_size: tuple[int, int], cell: dict[str, Any]
) -> gym.Env:
    from envs.tasks import get_task  # noqa: PLC0415

    task = get_task(task_id)
    kwargs = {**task.env_kwargs("train", index), "obs_mode": "rgb", "image_size": list(image_size)}
    if cell:
        kwargs["cell"] = cell
    return gym.make(task_id, **kwargs)


class _Recorder:
    """Accumulates steps (padded to the env's tile and slot counts)."""

    def __init__(self, cfg: EquivariantConfig, n: int, k: int) -> None:
        self.cut = CropCutter(cfg)
        self.n, self.k, self.g = n, k, cfg.grid
        self.rows: dict[str, list[Any]] = {f: [] for f in ARRAYS}
        self.skipped = 0

    def add(
        self,
        env: gym.Env,
        obs: dict[str, Any],
        *,
        cell_tile: int,
        cell_slot: int,
        turn: float,
        episode: int,
    ) -> None:
        u: Any = env.unwrapped
        spec = env.get_wrapper_attr("task_spec")
        tiles, slots, found = self.cut(obs, spec)
        a = int(np.flatnonzero(u.index.tiles == cell_tile)[0])
        j = int(np.flatnonzero(u.index.slots == cell_slot)[0])
        m = min(len(found.xy), self.n)
        mask = np.asarray(u.action_masks(), bool)
        if a >= m or m != int(mask[: self.n].sum()):
            self.skipped += 1  # the blobs do not match the tiles on the belt (touching tiles)
            return
        pad = np.zeros((self.n, 4, self.g, self.g), np.uint8)
        pad[:m] = to_bytes(tiles[:m])
        order = np.asarray(u.index.slots)
        sym = np.array([int(spec.slots[int(s)].symmetry) for s in order])
        r = self.rows
        r["tiles"].append(pad)
        r["tile_ok"].append(mask[: self.n] & (np.arange(self.n) < m))
        r["slots"].append(to_bytes(slots))
        r["slot_ok"].append(mask[self.n : self.n + self.k])
        r["symmetry"].append(sym)
        r["tile"].append(a)
        r["slot"].append(j)
        r["turn"].append(float(math.remainder(turn, 2 * math.pi)))
        r["episode"].append(episode)

    def records(self, header: Header) -> StepRecords:
        if not self.rows["tile"]:
            raise RecordsError("no usable demonstrated step was recorded")
        return StepRecords(header, *(np.stack(self.rows[f]) for f in ARRAYS))


def _open_slot(u: Any, tile: int) -> int | None:
    """An open slot of the tile's class (its own design slot first)."""
    task, ev = u.task, u.evaluate()
    ok = (task.slot_class == task.tile_class[tile]) & ~np.asarray(ev.slot_filled, bool)
    if tile < len(ok) and ok[tile]:
        return tile
    free = np.flatnonzero(ok)
    return int(free[0]) if len(free) else None


def _expert_episode(env: gym.Env, seed: int, episode: int, rec: _Recorder) -> None:
    u: Any = env.unwrapped
    obs, _ = env.reset(seed=seed)
    for _ in range(len(u.cell.slots)):
        on_belt = [int(t) for t in u.index.tiles if u.cell.input_half()[int(t)]]
        pair = next(((t, s) for t in on_belt if (s := _open_slot(u, t)) is not None), None)
        if pair is None:
            return
        t, s = pair
        turn = float(u.cell.slot_poses_world()[s, 2] - u.cell.tile_poses().yaw[t])
        rec.add(env, obs, cell_tile=t, cell_slot=s, turn=turn, episode=episode)
        obs, _, terminated, truncated, _ = env.step(u.expert_action(t, s))
        if terminated or truncated:
            return


def _disassembly_episode(env: gym.Env, seed: int, episode: int, rec: _Recorder) -> None:
    u: Any = env.unwrapped
    env.reset(seed=seed)
    cell, spec = u.cell, env.get_wrapper_attr("task_spec")
    rng = np.random.default_rng(seed)
    belt = cell.tile_poses()
    spots = np.column_stack([belt.pos[:, :2], belt.yaw])  # where the reset laid each tile
    tiles = np.flatnonzero(cell.input_half())
    slots = cell.slot_poses_world()
    # the finished mosaic: every tile in its own slot (tile i is made from design slot i)
    cell.put_tiles(tiles, slots[tiles], spec.place.surface_z)
    cell.step(1)
    back = PickPlaceExecutor(
        cell, u.config, u.executor.pcfg, u.executor.ik, pick=spec.place, place=spec.pick
    )
    for tile in rng.permutation(tiles):
        t = int(tile)
        grasp = cell.tiles[t].grasp
        poses = cell.tile_poses()
        yaw, pos = float(poses.yaw[t]), poses.pos[t, :2]
        to_yaw = float(spots[t, 2])
        cmd = PickPlaceCommand.between_yaws(
            (float(pos[0] + rotate_xy(grasp, yaw)[0]), float(pos[1] + rotate_xy(grasp, yaw)[1])),
            yaw,
            (
                float(spots[t, 0] + rotate_xy(grasp, to_yaw)[0]),
                float(spots[t, 1] + rotate_xy(grasp, to_yaw)[1]),
            ),
            to_yaw,
        )
        if back.run(cmd).failed:
            return
        # played backwards, the picture after this removal shows the step "tile t into its
        # slot, turned back by the turn the removal made"
        obs = u.move_home()
        rec.add(
            env, obs, cell_tile=t, cell_slot=t, turn=float(slots[t, 2] - to_yaw), episode=episode
        )


def collect(
    task_id: str,
    source: str,
    episodes: int,
    cfg: EquivariantConfig,
    *,
    image_size: tuple[int, int],
    camera: str = "ideal",
    cell: dict[str, Any] | None = None,
    seed: int = 0,
    progress: Callable[[int], None] | None = None,
) -> StepRecords:
    """Record ``episodes`` demonstrations on the rung's training designs.

    Args:
        task_id: The rung (its ``train`` split gives the designs, in turn per episode).
        source: ``expert`` or ``disassembly``.
        episodes: Episodes to record.
        cfg: Crop settings.
        image_size: Camera image (height, width) [px].
        camera: Camera level name (recorded in the header).
        cell: Cell overrides of that camera level (lens, exposure), or None.
        seed: Seed of the first episode (episode e uses ``seed + e``).
        progress: Called with the episodes done.

    Raises:
        RecordsError: An unknown source, or nothing recorded.
    """
    if source not in SOURCES:
        raise RecordsError(f"unknown demonstration source {source!r}; allowed: {list(SOURCES)}")
    from envs.tasks import get_task  # noqa: PLC0415

    task = get_task(task_id)
    designs = len(task.designs("train"))
    envs_: dict[int, gym.Env] = {}  # built when first used
    rec: _Recorder | None = None
    play = _expert_episode if source == "expert" else _disassembly_episode
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            for e in range(episodes):
                d = e % designs
                if d not in envs_:
                    envs_[d] = _env_for(task_id, d, image_size, cell or {})
                if rec is None:
                    nvec = np.asarray(envs_[d].action_space.nvec)  # type: ignore[attr-defined]
                    rec = _Recorder(cfg, int(nvec[0]), int(nvec[1]))
                play(envs_[d], seed + e, e, rec)
                if progress is not None:
                    progress(e + 1)
    finally:
        for env in envs_.values():
            env.close()
    if rec is None:
        raise RecordsError(f"asked for {episodes} episodes; record at least one")
    header = Header(task_id, tuple(image_size), camera, source, crop_settings(cfg), episodes)  # type: ignore[arg-type]
    return rec.records(header)


__all__ = ["collect"]
