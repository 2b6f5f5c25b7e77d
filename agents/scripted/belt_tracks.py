"""Tiles followed from picture to picture on a moving belt, and the time between pictures.

The scripted cell sees the input belt once per cycle and is never told the time. A tile on the
belt keeps its place across the belt and moves along it at the belt's speed, so the same tile
in two pictures is found by its place across the belt, its colour and its area, and the
distance it moved along the belt measures the interval between the pictures. The interval
places the tiles that left the camera's view since: a tile seen downstream of the view's
edge is still on the belt, at its last position plus the belt's travel (a *ghost* track),
and can still be picked there. A tile cut by the view's edge (a partial region: its visible
area and colour) is placed by sliding its outline, as last seen whole, to where the part left
inside the view has that area; such a tile measures the interval too. When no tile is seen
again at all, the running estimate of a cycle (`BeltScheduleConfig.cycle_s`, refined by every
measured interval) stands in.

The belt runs along +x (`envs.task_spec.TaskSpec.belt_speed`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from shapely.affinity import translate
from shapely.geometry import Polygon, box

from agents.scripted.belt_config import BeltScheduleConfig
from agents.scripted.perception import PartialRegion, PerceivedTile
from agents.scripted.placement import PickPlace
from spatial.units import MM_PER_M

BISECTIONS = 30
"""Bisection steps placing a tile cut by the view's edge (a 2^-30 part of its size)."""

View = tuple[np.ndarray, np.ndarray]
"""The camera's view on the plane of the tile tops: lower and upper (x, y) corners [m]."""


@dataclass(frozen=True, eq=False)
class Track:
    """One tile followed on the belt.

    Attributes:
        key: Stable number of the track in its episode.
        xy: The tile's area centroid when last placed, shape (2,) [m].
        seen_at: The agent's clock then [s] (time since the first picture).
        color: Its measured RGB in [0, 1].
        area: Its area on the plane of the tile tops [m^2].
        shape: Its material around the centroid [m] (outer boundary and holes).
        command: The last command planned for it (None: it fills no open slot).
        visible: Seen whole in the latest picture.
        tile: Its index in the latest picture's perceived tiles (-1 when not seen whole there).
        sure: Its position now rests on measurements only: seen (whole or cut by the view's
            edge) in the latest picture, or followed over measured intervals since.
    """

    key: int
    xy: np.ndarray
    seen_at: float
    color: tuple[float, float, float]
    area: float
    shape: Polygon
    command: PickPlace | None = None
    visible: bool = True
    tile: int = -1
    sure: bool = True

    @property
    def radius(self) -> float:
        """Farthest outline point from the centroid [m]."""
        x0, y0, x1, y1 = self.shape.bounds
        return float(np.hypot(max(-x0, x1), max(-y0, y1)))

    def x_at(self, clock: float, speed: float) -> float:
        """Predicted position along the belt at ``clock`` [s] for a belt ``speed`` [m/s]."""
        return float(self.xy[0]) + speed * (clock - self.seen_at)


def tile_shape(tile: PerceivedTile) -> Polygon:
    """A perceived tile's material around its centroid [m].

    Its figure's outer boundary and holes, arcs sampled.
    """
    centre = np.asarray(tile.centre, float)
    fig = tile.figure

    def ring(dense: np.ndarray) -> np.ndarray:
        return np.asarray(dense, float) / MM_PER_M - centre

    shape = Polygon(ring(fig.outer.dense()), [ring(h.dense()) for h in fig.holes])
    return shape if shape.is_valid else shape.buffer(0)


def slid_into_view(shape: Polygon, y: float, area: float, view: View) -> float | None:
    """Where along the belt a tile cut by the view's downstream edge is [m].

    The centroid position at which ``shape`` (around its centroid, at ``y`` across the belt)
    shows ``area`` [m^2] inside ``view``; None when no position does. The visible area falls
    as the shape slides out past the view's downstream edge (bisection).
    """
    lo, hi = view
    frame = box(float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1]))
    placed = translate(shape, yoff=y)
    if not 0.0 < area < float(placed.area):
        return None
    x0, _, x1, _ = shape.bounds
    a, b = float(hi[0]) - x1, float(hi[0]) - x0
    for _ in range(BISECTIONS):
        mid = 0.5 * (a + b)
        seen = float(translate(placed, xoff=mid).intersection(frame).area)
        a, b = (mid, b) if seen > area else (a, mid)
    return 0.5 * (a + b)


class BeltTracker:
    """Follows the perceived tiles of successive pictures of one episode.

    Args:
        config: Scheduler settings (gates, cycle estimates).
        speed: Belt speed along +x [m/s], > 0.
        view: The camera's view on the plane of the tile tops.
        end_x: The input belt's end [m]: a tile followed past it has left the belt.
    """

    def __init__(
        self, config: BeltScheduleConfig, speed: float, view: View, end_x: float = np.inf
    ) -> None:
        self.cfg = config
        self.speed = float(speed)
        self.end_x = float(end_x)
        self.view = (np.asarray(view[0], float), np.asarray(view[1], float))
        self.tracks: list[Track] = []
        self.clock = 0.0
        """Agent's clock at the latest picture [s] (0 at the first)."""
        self.cycle = config.cycle_s
        """Running estimate of a pick-and-place cycle [s]."""
        self.pictures = 0
        self.measured = 0
        """Intervals measured from tiles seen again (the rest were estimated)."""
        self._next_key = 0

    def reset(self) -> None:
        """Forget the episode."""
        self.tracks = []
        self.clock = 0.0
        self.cycle = self.cfg.cycle_s
        self.pictures = 0
        self.measured = 0
        self._next_key = 0

    def observe(
        self,
        tiles: Sequence[PerceivedTile],
        partial: Sequence[PartialRegion] = (),
        *,
        taken: int = -1,
        idle: bool = False,
    ) -> None:
        """Advance to a new picture's perceived tiles.

        Args:
            tiles: The picture's whole tiles.
            partial: The picture's regions cut by the view's edge.
            taken: Key of the track the last command picked (-1: none); it is no longer
                followed (a failed pick leaves the tile in view: it is followed anew).
            idle: The last command picked nothing (its cycle is not a pick cycle, so it does
                not refine the cycle estimate).
        """
        cfg, v = self.cfg, self.speed
        old = [t for t in self.tracks if t.key != taken]
        prior = 0.0 if self.pictures == 0 else self._prior()
        interval, pairs = self._interval(old, tiles, prior)
        seen = {j: i for i, j in pairs}
        cut = self._cut(old, set(seen), partial, prior if interval is None else interval)
        if interval is None and cut:
            since = np.array([self.clock - old[j].seen_at for j in cut])
            xs = np.array([old[j].xy[0] for j in cut])
            gaps = (np.array(list(cut.values())) - xs) / v - since
            interval = float(np.median(gaps))
            if interval < cfg.min_interval_s:
                interval, cut = None, {}
        if interval is not None:
            self.measured += 1
            if self.pictures > 1 and not idle:
                self.cycle += cfg.cycle_smoothing * (interval - self.cycle)
        self.clock += prior if interval is None else interval
        self.pictures += 1
        by_tile = {i: j for j, i in seen.items()}
        tracks = [
            self._seen(old[by_tile[i]] if i in by_tile else None, t, i) for i, t in enumerate(tiles)
        ]
        lo, hi = self.view
        for j, tr in enumerate(old):
            if j in seen:
                continue
            if j in cut:  # placed by its visible part
                xy = np.array([cut[j], tr.xy[1]])
                placed = dataclasses.replace(tr, xy=xy, seen_at=self.clock, sure=True)
                tracks.append(dataclasses.replace(placed, visible=False, tile=-1))
                continue
            x = tr.x_at(self.clock, v)
            r = tr.radius + cfg.view_margin
            # Off the belt, or not seen where it would have been seen whole: gone.
            gone = x > self.end_x or (lo[0] < x - r and x + r < hi[0])
            if x > lo[0] and not gone:  # out of view downstream, still on the belt
                sure = tr.sure and interval is not None
                tracks.append(dataclasses.replace(tr, visible=False, tile=-1, sure=sure))
        self.tracks = tracks

    def _prior(self) -> float:
        return self.cfg.first_cycle_s if self.pictures == 1 else self.cycle

    def _seen(self, tr: Track | None, t: PerceivedTile, i: int) -> Track:
        key = tr.key if tr is not None else self._new_key()
        return Track(
            key,
            np.asarray(t.centre, float).copy(),
            self.clock,
            t.color,
            float(t.area),
            tile_shape(t),
            tr.command if tr is not None else None,
            True,
            i,
        )

    def _new_key(self) -> int:
        self._next_key += 1
        return self._next_key - 1

    def _cut(
        self,
        old: Sequence[Track],
        matched: set[int],
        partial: Sequence[PartialRegion],
        interval: float,
    ) -> dict[int, float]:
        """Tracks placed by a region cut by the view's downstream edge.

        Returns:
            Position in ``old`` -> the tile's centroid along the belt now [m].
        """
        cfg, v = self.cfg, self.speed
        mid_x = 0.5 * float(self.view[0][0] + self.view[1][0])
        out: dict[int, float] = {}
        used: set[int] = set()
        for j, tr in enumerate(old):
            if j in matched:
                continue
            pred = tr.x_at(self.clock + interval, v)
            for k, p in enumerate(partial):
                if k in used or p.centre[0] < mid_x:
                    continue
                if abs(p.centre[1] - tr.xy[1]) > tr.radius:
                    continue
                if np.linalg.norm(np.subtract(p.color, tr.color)) > cfg.match_color:
                    continue
                x = slid_into_view(tr.shape, float(tr.xy[1]), p.area, self.view)
                if x is not None and abs(x - pred) < cfg.match_gate_x:
                    out[j] = x
                    used.add(k)
                    break
        return out

    def _interval(
        self, old: Sequence[Track], tiles: Sequence[PerceivedTile], prior: float
    ) -> tuple[float | None, list[tuple[int, int]]]:
        """The measured interval since the last picture and the (tile, track) pairs it matched.

        Candidate pairs agree across the belt, in colour and area, and along the belt within
        ``match_gate_x`` of the prior interval's prediction; the interval is their median
        displacement over the belt speed; the pairs within ``match_tolerance_x`` of it are
        kept, one per tile and per track, nearest first.
        """
        cfg, v = self.cfg, self.speed
        if not old or not tiles:
            return None, []
        tx = np.array([t.centre[0] for t in tiles])
        ty = np.array([t.centre[1] for t in tiles])
        tc = np.array([t.color for t in tiles])
        ta = np.array([t.area for t in tiles])
        ox = np.array([tr.xy[0] for tr in old])
        oy = np.array([tr.xy[1] for tr in old])
        oc = np.array([tr.color for tr in old])
        oa = np.array([tr.area for tr in old])
        since = np.array([self.clock - tr.seen_at for tr in old])
        ok = (np.abs(ty[:, None] - oy[None]) < cfg.match_gate_y) & (
            np.linalg.norm(tc[:, None] - oc[None], axis=2) < cfg.match_color
        )
        ok &= np.abs(ta[:, None] / oa[None] - 1.0) < cfg.match_area
        moved = tx[:, None] - ox[None]
        ok &= np.abs(moved - v * (since[None] + prior)) < cfg.match_gate_x
        if not ok.any():
            return None, []
        gaps = moved / v - since[None]
        interval = float(np.median(gaps[ok]))
        if interval < cfg.min_interval_s:
            return None, []
        resid = np.where(ok, np.abs(moved - v * (since[None] + interval)), np.inf)
        pairs: list[tuple[int, int]] = []
        used_t: set[int] = set()
        used_o: set[int] = set()
        for flat in np.argsort(resid, axis=None).tolist():
            i, j = divmod(int(flat), resid.shape[1])
            if resid[i, j] > cfg.match_tolerance_x:
                break
            if i in used_t or j in used_o:
                continue
            used_t.add(i)
            used_o.add(j)
            pairs.append((i, j))
        if not pairs:
            return None, []
        return float(np.median([gaps[i, j] for i, j in pairs])), pairs

    def remember(self, commands: Sequence[PickPlace]) -> None:
        """Store the latest plan's commands on the tracks of their tiles.

        Kept for when they go out of view; a visible track without a command forgets its old
        one.
        """
        by_tile = {c.tile: c for c in commands}
        self.tracks = [
            dataclasses.replace(tr, command=by_tile.get(tr.tile)) if tr.visible else tr
            for tr in self.tracks
        ]

    def ghosts(self) -> list[Track]:
        """Tracks out of view (downstream) that still hold a command."""
        return [tr for tr in self.tracks if not tr.visible and tr.command is not None]


def shifted(cmd: PickPlace, dx: float) -> PickPlace:
    """A command whose pick (centroid and pad point) moved ``dx`` [m] along the belt."""
    p, g = cmd.pick, cmd.grasp_pick
    return dataclasses.replace(cmd, pick=(p[0] + dx, p[1], p[2]), grasp_pick=(g[0] + dx, g[1]))


__all__ = [
    "BISECTIONS",
    "BeltTracker",
    "Track",
    "View",
    "shifted",
    "slid_into_view",
    "tile_shape",
]
