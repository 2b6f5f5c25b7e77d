"""Which tile the scripted cell picks next on a moving belt: earliest deadline first.

Every tile the cell knows of (seen in this picture, or followed out of the camera's view by
`agents.scripted.belt_tracks`) has a *deadline*: the time left before its pick contact would
come too late, i.e. before the belt carries it to ``end_margin`` short of the belt's end. The
cell picks one tile per cycle: the ``k``-th pick from now makes contact ``reach + k * cycle``
seconds after the picture (`BeltScheduleConfig`; from home the first reach is shorter).
`deadline_order` orders the tiles by deadline (earliest first, which saves every tile whenever
any order does for picks of equal length) and, where no order saves every tile, *defers* the
tiles that would come too late in it (the next picture decides on them again) and *rejects*
those no pick can reach in time: the cell does not spend a cycle on a tile it cannot save. When
that leaves the cycle empty, the most urgent rejected tile the shortest measured reach
(``last_chance_reach_s``) still gets to in time is tried: the try costs no other tile.

The pick itself meets the moving tile: the command carries the tile's pose at the picture
(for a followed tile, its last sighting advanced by the belt's travel since) and the planner
predicts the contact, arrives with the belt's velocity and travels with it through the vacuum
dwell (`planners.pick_place`). One picture is taken per cycle, as on a static belt.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from agents.scripted.belt_config import BeltScheduleConfig, load_belt_schedule_config
from agents.scripted.belt_tracks import BeltTracker, Track, View, shifted
from agents.scripted.perception import PartialRegion, PerceivedTile
from agents.scripted.placement import PickPlace
from envs.cell.cameras import CameraModel
from envs.task_spec import TaskSpec


@dataclass(frozen=True)
class Schedule:
    """The pick order of one picture's known tiles.

    Attributes:
        order: Indices of the tiles to pick, in pick order (each on time).
        deadlines: Time left per tile before its pick contact comes too late, shape (n,) [s].
        rejected: Tiles no pick can reach in time (their deadline is before the next contact).
        deferred: Tiles a pick could save alone, left out because no order saves every tile.
    """

    order: tuple[int, ...]
    deadlines: np.ndarray
    rejected: tuple[int, ...]
    deferred: tuple[int, ...]

    @property
    def saves_all(self) -> bool:
        """Every tile is picked on time."""
        return not self.rejected and not self.deferred


def deadline_order(
    x: Sequence[float] | np.ndarray,
    speed: float,
    last_x: float,
    reach_s: float,
    cycle_s: float,
) -> Schedule:
    """Earliest-deadline-first order of tiles at positions ``x`` along a belt.

    Args:
        x: Each tile's position along the belt now, shape (n,) [m].
        speed: Belt speed along +x [m/s], > 0.
        last_x: The farthest position at which a pick contact still saves a tile [m].
        reach_s: Time from now to the next pick's contact [s].
        cycle_s: Time between two picks' contacts [s].

    Returns:
        The order, with the tiles rejected (too late for any pick) and deferred (no order
        saves every tile: a tile that would be late in the order is left out of it; the more
        urgent ones keep their places, so the times taken on the long side never cost a
        tile that could still be saved).
    """
    xs = np.asarray(x, float).reshape(-1)
    deadlines = (last_x - xs) / speed
    kept: list[int] = []
    rejected: list[int] = []
    deferred: list[int] = []
    for i in np.argsort(deadlines, kind="stable").tolist():
        if deadlines[i] < reach_s:
            rejected.append(i)
            continue
        kept.append(i)
        if deadlines[i] < reach_s + (len(kept) - 1) * cycle_s:
            deferred.append(kept.pop())
    return Schedule(tuple(kept), deadlines, tuple(rejected), tuple(deferred))


def camera_view(camera: CameraModel, plane_z: float) -> View:
    """The rectangle a camera sees on the plane ``plane_z`` [m]: lower and upper corners [m].

    The largest axis-aligned rectangle inside its image's four corners on that plane.
    """
    w, h = camera.width, camera.height
    uv = np.array([[0.0, 0.0], [w, 0.0], [w, h], [0.0, h]])
    xy = np.sort(camera.unproject_to_plane(uv, plane_z)[:, :2], axis=0)
    return xy[1].copy(), xy[2].copy()


@dataclass(frozen=True)
class ScheduleTally:
    """What the scheduler did over an episode.

    Attributes:
        pictures: Pictures planned.
        picks: Commands given.
        ghost_picks: Of those, tiles picked out of the camera's view (followed).
        rejected: Tiles found too late for a pick on time (some then tried at the last
            chance).
        last_chances: Of the picks, tiles tried with the shortest reach (nothing else could
            be picked on time).
        deferred: Pictures in which no order saved every known tile.
        measured: Intervals between pictures measured from tiles seen twice.
        cycle_s: The running cycle estimate at the end [s].
    """

    pictures: int
    picks: int
    ghost_picks: int
    rejected: int
    last_chances: int
    deferred: int
    measured: int
    cycle_s: float


class BeltScheduler:
    """The scripted cell's choice of the next pick on a moving belt.

    Per picture: `observe` the perceived tiles (tracks, the interval), plan the open slots
    without `reserved` (the slots of followed tiles out of view), then `choose` among the
    plan's commands and the followed tiles'.

    Args:
        config: Settings.
        speed: Belt speed along +x [m/s], > 0.
        belt_end_x: Position of the input belt's end [m].
        view: The camera's view on the plane of the tile tops (`camera_view`).
    """

    def __init__(
        self,
        config: BeltScheduleConfig,
        speed: float,
        belt_end_x: float,
        view: View,
    ) -> None:
        self.cfg = config
        self.speed = float(speed)
        self.last_x = float(belt_end_x) - config.end_margin
        self.tracker = BeltTracker(config, speed, view, float(belt_end_x))
        self.last_schedule: Schedule | None = None
        self._taken = -1
        self._idle = False
        self._picks = 0
        self._ghost_picks = 0
        self._rejected: set[int] = set()
        self._deferred = 0
        self._last_chances = 0
        self._sure: list[bool] = []

    @classmethod
    def for_spec(
        cls, spec: TaskSpec, camera: CameraModel, config: BeltScheduleConfig | None = None
    ) -> BeltScheduler:
        """The scheduler of a task on a moving belt (its pick area reaches the belt's end)."""
        cfg = config or load_belt_schedule_config()
        view = camera_view(camera, spec.pick.tile_top_z)
        return cls(cfg, spec.belt_speed, float(spec.pick.hi[0]), view)

    def reset(self) -> None:
        """Forget the episode."""
        self.tracker.reset()
        self.last_schedule = None
        self._taken = -1
        self._idle = False
        self._picks = self._ghost_picks = self._deferred = self._last_chances = 0
        self._rejected = set()

    @property
    def reach_s(self) -> float:
        """Time from this picture to the next pick's contact [s]."""
        return self.cfg.first_reach_s if self.tracker.pictures <= 1 else self.cfg.reach_s

    def observe(
        self, tiles: Sequence[PerceivedTile], partial: Sequence[PartialRegion] = ()
    ) -> None:
        """Follow a new picture's whole tiles and regions cut by the view's edge.

        Called before the picture's slots are planned (`reserved` then holds).
        """
        self.tracker.observe(tiles, partial, taken=self._taken, idle=self._idle)

    def _ghost_x(self, tr: Track) -> float:
        return tr.x_at(self.tracker.clock, self.speed)

    def reserved(self) -> frozenset[int]:
        """Slots of followed tiles out of view that a pick can still save."""
        return frozenset(
            tr.command.slot
            for tr in self.tracker.ghosts()
            if tr.command is not None
            and (self.last_x - self._ghost_x(tr)) / self.speed >= self.reach_s
        )

    def choose(self, commands: Sequence[PickPlace]) -> PickPlace | None:
        """The next command: the earliest deadline among the plan's and the followed tiles'.

        Args:
            commands: This picture's plan (commands for tiles in view).

        Returns:
            The command, its pick moved to where a followed tile is now; None when no tile
            can be picked on time (the cell rests a cycle).
        """
        tr = self.tracker
        tr.remember(commands)
        key_of = {t.tile: t.key for t in tr.tracks if t.visible}
        keys: list[int] = []
        xs: list[float] = []
        cmds: list[PickPlace] = []
        for c in commands:
            if c.tile in key_of:
                keys.append(key_of[c.tile])
                xs.append(float(c.pick[0]))
                cmds.append(c)
        ghosts = set()
        for g in tr.ghosts():
            assert g.command is not None
            x = self._ghost_x(g)
            keys.append(g.key)
            xs.append(x)
            cmds.append(shifted(g.command, x - float(g.command.pick[0])))
            ghosts.add(g.key)
        self._sure = [True] * len(cmds)
        self._sure[len(cmds) - len(ghosts) :] = [g.sure for g in tr.ghosts()]
        sched = deadline_order(xs, self.speed, self.last_x, self.reach_s, tr.cycle)
        self.last_schedule = sched
        self._rejected.update(keys[i] for i in sched.rejected)
        self._deferred += bool(sched.deferred)
        first = sched.order[0] if sched.order else self._last_chance(sched)
        if first < 0:
            self._taken, self._idle = -1, True
            return None
        self._taken, self._idle = keys[first], False
        self._picks += 1
        self._ghost_picks += keys[first] in ghosts
        return cmds[first]

    def _last_chance(self, sched: Schedule) -> int:
        """The most urgent rejected tile the shortest reach still gets to in time (-1: none).

        Tried only when nothing can be picked on time (the cycle would be empty otherwise)
        and only where the tile's position is measured (`agents.scripted.belt_tracks.Track.sure`): a
        pick off the tile's centre would set it down off its slot.
        """
        late = [
            i
            for i in sched.rejected
            if sched.deadlines[i] >= self.cfg.last_chance_reach_s and self._sure[i]
        ]
        if not late:
            return -1
        self._last_chances += 1
        return min(late, key=lambda i: float(sched.deadlines[i]))

    def tally(self) -> ScheduleTally:
        """What the scheduler did since the episode started."""
        tr = self.tracker
        return ScheduleTally(
            tr.pictures,
            self._picks,
            self._ghost_picks,
            len(self._rejected),
            self._last_chances,
            self._deferred,
            tr.measured,
            tr.cycle,
        )


__all__ = [
    "BeltScheduler",
    "Schedule",
    "ScheduleTally",
    "deadline_order",
    "camera_view",
]
