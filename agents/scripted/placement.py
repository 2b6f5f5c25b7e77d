"""Assignments to pick-and-place commands: where to pick, where to place, and the yaws.

Conventions. Tile figures come from `agents.scripted.perception` in world millimetres (x, y of the
world, y up) and slot figures from the design in mesh millimetres with the mesh's axes along the
world's, so `qshape.assign`'s rotation (counter-clockwise in the y-up frame, turning the tile
about its centroid onto the slot) is the world yaw the tile must turn by, seen from above.
(Had we matched the pixel figures, the same holds: extract's figures are ``y_down`` and qshape
works in ``(u, -v)``, which for the cell's cameras is the world's (x, y) up to a translation and
scale; `tests/test_placement.py` checks the sign on a real render.)

A command picks with pad yaw ``yaw_pick`` and places with pad yaw ``yaw_place``; the tile turns
by ``yaw_place - yaw_pick``. We report ``yaw_pick`` as the tile's estimated yaw in the slot
shape's frame (slot yaw minus rotation, so it is comparable with a ground-truth tile yaw modulo
symmetry) and ``yaw_place`` as the slot's yaw. ``place_yaws`` lists every equivalent place yaw
(the tile's symmetries) so a planner can choose the cheapest wrist motion.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from scipy.optimize import minimize_scalar
from scipy.spatial import cKDTree

import qshape
from agents.scripted.centre_fit import tile_centre
from agents.scripted.config import PlacementConfig
from agents.scripted.outline_fit import TileOutline, area_centroid, boundary_points, fit_outline
from agents.scripted.perception import PerceivedTile, SlotTarget
from envs.task_spec import PickPlaceCommand
from qshape.theory.assign import feasible_pairs
from spatial.angles import TWO_PI, equivalent_yaws, rotate_xy, symmetry_period, wrap_angle
from spatial.units import MM_PER_M


def wrap(angle: float) -> float:
    """Angle wrapped to [-pi, pi) [rad] (`spatial.angles.wrap_angle` for one float)."""
    return float(wrap_angle(angle))


@dataclass(frozen=True)
class PickPlace:
    """One tile to move into one slot.

    Attributes:
        tile: Index of the perceived tile.
        slot: Index of the design slot.
        slot_name: Design name of the slot.
        pick: (x, y, yaw_pick) [m, m, rad]: tile centroid and its estimated yaw.
        place: (x, y, yaw_place) [m, m, rad]: slot centroid and the slot's yaw.
        grasp_pick: Where the pad seals at the pick, (x, y) [m] (the centroid unless the
            centroid has too little material around it, e.g. a ring).
        grasp_place: Where that pad point ends at the place, (x, y) [m].
        rotation: Yaw the tile turns by, ``yaw_place - yaw_pick`` wrapped [rad].
        place_yaws: Every equivalent ``yaw_place`` [rad] (symmetries), the chosen one first.
        symmetry: Rotational symmetry order of the slot shape (1: none, 0: continuous).
        score: qshape alignment residual of the pair (dimensionless, lower is better).
    """

    tile: int
    slot: int
    slot_name: str
    pick: tuple[float, float, float]
    place: tuple[float, float, float]
    grasp_pick: tuple[float, float]
    grasp_place: tuple[float, float]
    rotation: float
    place_yaws: tuple[float, ...]
    symmetry: int
    score: float

    @property
    def command(self) -> PickPlaceCommand:
        """The world command for the env's codec: pad points, the tile's yaw, the rotation."""
        return PickPlaceCommand(self.grasp_pick, self.pick[2], self.grasp_place, self.rotation)


UnplacedReason = Literal["shape_absent", "color_absent", "slots_taken"]
"""Why a perceived tile is not placed (`REASONS` explains each)."""


@dataclass(frozen=True)
class Unplaced:
    """A perceived tile that will not be placed, and why.

    Attributes:
        tile: Index of the perceived tile.
        reason: One of `REASONS`' keys.
        detail: Human-readable explanation.
    """

    tile: int
    reason: UnplacedReason
    detail: str


REASONS: dict[UnplacedReason, str] = {
    "shape_absent": "no design slot has this shape",
    "color_absent": "slots of this shape exist, but none of this colour",
    "slots_taken": "every matching slot is taken by another tile",
}
"""Why a tile is not placed."""


@dataclass(frozen=True)
class PlacementPlan:
    """The commands for one picture.

    Attributes:
        commands: Pick-and-place commands, in the assignment's tile order.
        unplaced: Tiles left out with their reason.
        open_slots: Slot indices no tile was assigned to.
        method: "optimal" or "greedy".
        use_color: Colour was matched.
    """

    commands: tuple[PickPlace, ...]
    unplaced: tuple[Unplaced, ...]
    open_slots: tuple[int, ...]
    method: Literal["optimal", "greedy"]
    use_color: bool


def outline_residual(tile: qshape.Figure, slot: qshape.Figure, rotation: float) -> float:
    """Mean distance from the rotated tile outline to the slot outline (both centred) [unit].

    Args:
        tile: Tile figure (y-up units, e.g. world mm).
        slot: Slot figure in the same units.
        rotation: Rotation of the tile about its centroid [rad], CCW.
    """
    a = rotate_xy(np.asarray(tile.outer.dense()) - tile.centroid, rotation)
    b = np.asarray(slot.outer.dense()) - slot.centroid
    return float(np.mean(cKDTree(b).query(a)[0]))


def refine_rotation(
    tile: qshape.Figure,
    slot: qshape.Figure,
    rotation: float,
    span: float,
    tolerance: float = 1e-4,
    *,
    points: np.ndarray | None = None,
    spacing: float = 0.5,
    scan: float = math.radians(1.0),
) -> float:
    """The rotation within +-``span`` of ``rotation`` whose turned tile outline fits best [rad].

    A precision step, not a choice between rotations: qshape's rotation comes from the
    relevant points alone, which fix the turn of a curved tile only to a degree or two (and a
    crescent's rounded tips to several); the mean distance from the turned tile outline to the
    slot outline (both sampled at most ``spacing`` apart along every edge, straight ones
    included) is scanned every ``scan`` over the span and refined at the best; the result is
    kept only when it does fit better than ``rotation``.

    Args:
        tile: Tile figure (y-up units, e.g. world mm).
        slot: Slot figure, same units.
        rotation: qshape's rotation of the pair [rad].
        span: Half width of the refinement interval [rad] (0: ``rotation`` as it is).
        tolerance: Refinement precision [rad].
        points: The tile's outer boundary to fit instead of ``tile``'s (e.g. its traced
            outline), shape (k, 2), same units; centred on the area centroid of that
            boundary less ``tile``'s holes.
        spacing: Largest distance between the outline points compared [units of the figures].
        scan: Step of the scan over the span [rad].
    """
    if span <= 0:
        return rotation
    if points is None:
        a = boundary_points([tile.outer.dense()], spacing) - tile.centroid
    else:
        a = boundary_points([np.asarray(points)], spacing) - _centroid(points, tile)
    tree = cKDTree(boundary_points([slot.outer.dense()], spacing / 2.0) - slot.centroid)

    def cost(r: float) -> float:
        return float(np.mean(tree.query(rotate_xy(a, r))[0]))

    turns = rotation + np.arange(-span, span + 0.5 * scan, scan)
    coarse = [cost(float(r)) for r in turns]
    best = float(turns[int(np.argmin(coarse))])
    res = minimize_scalar(
        cost,
        bounds=(best - scan, best + scan),
        method="bounded",
        options={"xatol": tolerance},
    )
    found = float(res.x) if float(res.fun) <= min(coarse) else best
    return found if cost(found) <= cost(rotation) else rotation


def _centroid(outer: np.ndarray, figure: qshape.Figure) -> np.ndarray:
    """Area centroid of the boundary ``outer`` (k, 2) less ``figure``'s holes."""
    return area_centroid(outer, [h.dense() for h in figure.holes])


@dataclass(eq=False)
class FeasiblePairs:
    """Which tiles of one picture could fill which design slots: found once per colour mode.

    `qshape.theory.assign.feasible_pairs` of every perceived tile against every slot given,
    run at most once with colour and once without for the picture, on first use. A slot with
    a seen description (`SlotTarget.seen`) matches a tile that either of its descriptions
    matches. Whether a
    pair matches depends on that tile and that slot alone, so every subset a caller asks about
    (the tiles left out against the open and filled slots, a tile against the filled slots)
    reads the same answer as a run on that subset.

    Args:
        tiles: The picture's perceived tiles (positions are the indices asked about).
        slots: Design slots (by `SlotTarget.index`).
        tolerances: qshape tolerances (bundled when None).
    """

    def __init__(
        self,
        tiles: Sequence[PerceivedTile],
        slots: Sequence[SlotTarget],
        tolerances: qshape.Tolerances | None = None,
    ) -> None:
        self._tiles = [t.description for t in tiles]
        self._slots = [d for s in slots for d in s.descriptions]
        self._slot_index = np.array(
            [s.index for s in slots for _ in s.descriptions], dtype=np.int64
        )
        self._tol = _tol(tolerances)
        self._found: dict[bool, dict[int, set[int]]] = {}

    def _table(self, use_color: bool) -> dict[int, set[int]]:
        """Slot indices per tile position with a match (tiles without one absent)."""
        if use_color not in self._found:
            table: dict[int, set[int]] = {}
            if self._tiles and self._slots:
                t, s, _, _ = feasible_pairs(self._tiles, self._slots, self._tol, use_color)
                for ti, si in zip(t.tolist(), self._slot_index[s].tolist(), strict=True):
                    table.setdefault(ti, set()).add(si)
            self._found[use_color] = table
        return self._found[use_color]

    def slots_of(self, tile: int, use_color: bool) -> set[int]:
        """Indices of the slots the tile at position ``tile`` matches."""
        return set(self._table(use_color).get(tile, ()))


def plan_placements(
    tiles: Sequence[PerceivedTile],
    slots: Sequence[SlotTarget],
    cfg: PlacementConfig | None = None,
    tolerances: qshape.Tolerances | None = None,
    *,
    filled: Sequence[SlotTarget] = (),
    pairs: FeasiblePairs | None = None,
) -> PlacementPlan:
    """Assign perceived tiles to slots and turn each pair into a pick-and-place command.

    Tiles matching no slot (distractors, shapes or colours absent from the design) and tiles
    left over when every matching slot is taken are reported in ``unplaced`` and never placed.

    Args:
        tiles: Perceived tiles (world figures in mm).
        slots: Open design slots (already filled ones left out by the caller).
        cfg: Method and colour option (bundled defaults when None).
        tolerances: qshape tolerances (bundled when None).
        filled: The design's slots already filled: a left-over tile matching one of them is
            reported as ``slots_taken`` (not as absent from the design).
        pairs: The picture's feasible pairs (``tiles`` against at least ``slots`` and
            ``filled``, same tolerances), shared by the calls on one picture; None: found here.

    Returns:
        The plan.

    Raises:
        qshape.MatchError: Unknown method.
    """
    cfg = cfg or PlacementConfig()
    result, by_seen = _assigned(tiles, slots, cfg, tolerances)
    commands = tuple(
        _command(tiles[a.tile], slots[a.slot], a, cfg, seen=a.tile in by_seen) for a in result
    )
    assigned = {a.tile for a in result}
    left = [k for k in range(len(tiles)) if k not in assigned]
    unplaced: tuple[Unplaced, ...] = ()
    if left:
        pairs = pairs or FeasiblePairs(tiles, [*slots, *filled], tolerances)
        every = {s.index for s in (*slots, *filled)}
        unplaced = tuple(
            Unplaced(tiles[k].index, r, REASONS[r])
            for k, r in zip(left, _reasons(left, pairs, every, cfg.use_color), strict=True)
        )
    assigned_slots = {a.slot for a in result}
    open_slots = tuple(s.index for k, s in enumerate(slots) if k not in assigned_slots)
    return PlacementPlan(commands, unplaced, open_slots, cfg.method, cfg.use_color)


def _assigned(
    tiles: Sequence[PerceivedTile],
    slots: Sequence[SlotTarget],
    cfg: PlacementConfig,
    tolerances: qshape.Tolerances | None,
) -> tuple[list[qshape.Assignment], set[int]]:
    """`qshape.assign` on the slots' design descriptions, then the rest on their seen ones.

    The tiles left out by the first assignment are assigned to the slots it left open that
    have a seen outline (`SlotTarget.seen`), by its description: a tile whose picture cannot
    show a design corner still matches the outline the picture shows.

    Returns:
        (the assignments, indices into ``tiles`` and ``slots``; the tiles assigned by a seen
        description).
    """
    tdesc = [t.description for t in tiles]
    result = qshape.assign(
        tdesc, [s.description for s in slots], tolerances, cfg.method, cfg.use_color
    )
    used_t = {a.tile for a in result}
    used_s = {a.slot for a in result}
    rest_t = [k for k in range(len(tiles)) if k not in used_t]
    rest_s = [k for k, s in enumerate(slots) if k not in used_s and s.seen is not None]
    if not rest_t or not rest_s:
        return result, set()
    more = qshape.assign(
        [tdesc[k] for k in rest_t],
        [slots[k].seen.description for k in rest_s],  # type: ignore[union-attr]
        tolerances,
        cfg.method,
        cfg.use_color,
    )
    more = [dataclasses.replace(a, tile=rest_t[a.tile], slot=rest_s[a.slot]) for a in more]
    return sorted(result + more, key=lambda a: a.tile), {a.tile for a in more}


def _command(
    t: PerceivedTile,
    s: SlotTarget,
    a: qshape.Assignment,
    cfg: PlacementConfig,
    *,
    seen: bool = False,
) -> PickPlace:
    """The pick-and-place of one assigned (tile, slot) pair (rotation refined, yaws wrapped).

    ``seen``: the pair matched by the slot's seen outline (`SlotTarget.seen`). The tile's
    figure then has the seen figure's relevant points, and both the arcs through three points
    that make their area. With the tile's traced outline (``outline_mm``) the rotation is
    refined by fitting that outline (the tile's own boundary) to the design's, and a tile
    matched by a seen outline is centred by its traced area centroid. Without it, the
    rotation is refined against the seen figure and the tile's centre moved by the design
    centroid's offset from the seen figure's (turned into the tile's frame). Either way the
    tile's own area centroid lands on the slot's.
    """
    span = math.radians(cfg.refine_span_deg)
    step = math.radians(cfg.refine_tolerance_deg)
    scan = math.radians(cfg.refine_scan_deg)
    spacing = cfg.refine_spacing_mm
    if t.outline_mm is not None:
        turn = a.rotation
        if seen:
            turn = _checked_turn(t, s, turn, cfg)
        rot = wrap(
            refine_rotation(
                t.figure,
                s.figure,
                turn,
                span,
                step,
                points=t.outline_mm,
                spacing=spacing,
                scan=scan,
            )
        )
        centre = t.centre
        if seen:
            centre = _centroid(t.outline_mm, t.figure) / MM_PER_M
        else:
            centre = tile_centre(t.centre, t.outline_mm, s.figure, rot, cfg)
        return fitted_command(t, s, rot, centre, score=a.score, cfg=cfg)
    ref = s.seen.figure if seen and s.seen is not None else s.figure
    rot = wrap(refine_rotation(t.figure, ref, a.rotation, span, step, spacing=spacing, scan=scan))
    centre = t.centre
    if ref is not s.figure:
        offset = (np.asarray(s.figure.centroid) - np.asarray(ref.centroid)) / MM_PER_M
        centre = t.centre + rotate_xy(offset, -rot)
    return fitted_command(t, s, rot, centre, score=a.score, cfg=cfg)


def _checked_turn(t: PerceivedTile, s: SlotTarget, turn: float, cfg: PlacementConfig) -> float:
    """The turn of a pair matched by a seen outline, checked against the traced outline's fit.

    A seen outline is a noise-free picture's simplification of the slot and may turn onto
    itself more nearly than the slot does (a rounded heptagon seen as seven near-equal arcs):
    the match's turn can then be one of those near turns. The tile's traced outline is fitted
    over the whole circle (`agents.scripted.outline_fit.fit_outline`); when that fit is tight and
    unambiguous (the ``fit_*`` thresholds) and lies farther than ``fit_turn_window_deg`` from
    the match's turn (modulo the slot's symmetry), the fit's turn is taken instead.
    """
    outline = TileOutline.of(t)
    if cfg.fit_max_residual <= 0 or outline is None:
        return turn
    fit = fit_outline(outline, s, cfg, cfg.fit_spacing_mm)
    if fit.residual > cfg.fit_max_residual or fit.runner_up < cfg.fit_margin:
        return turn
    period = symmetry_period(s.symmetry) or TWO_PI  # a round slot: one full turn
    off = abs(math.remainder(fit.rotation - turn, period))
    return fit.rotation if off > math.radians(cfg.fit_turn_window_deg) else turn


def fitted_command(
    t: PerceivedTile,
    s: SlotTarget,
    rotation: float,
    centre: np.ndarray,
    *,
    score: float,
    cfg: PlacementConfig,
) -> PickPlace:
    """The pick-and-place of a tile turned by ``rotation`` [rad] about ``centre`` onto ``s``.

    Args:
        t: The perceived tile (its grasp point is kept).
        s: The slot.
        rotation: Turn of the tile onto the slot, CCW [rad].
        centre: The tile's area centroid, world (x, y) [m]: it lands on the slot's.
        score: The pair's residual (dimensionless).
        cfg: Placement settings (``continuous_yaw_steps``).
    """
    rot = wrap(rotation)
    yaw_place = float(s.pose[2])
    yaw_pick = wrap(yaw_place - rot)
    g_off = rotate_xy(t.grasp - centre, rot)
    g_place = s.pose[:2] + g_off
    return PickPlace(
        tile=t.index,
        slot=s.index,
        slot_name=s.name,
        pick=(float(centre[0]), float(centre[1]), yaw_pick),
        place=(float(s.pose[0]), float(s.pose[1]), yaw_place),
        grasp_pick=(float(t.grasp[0]), float(t.grasp[1])),
        grasp_place=(float(g_place[0]), float(g_place[1])),
        rotation=rot,
        place_yaws=tuple(
            wrap(float(y)) for y in equivalent_yaws(yaw_place, s.symmetry, cfg.continuous_yaw_steps)
        ),
        symmetry=s.symmetry,
        score=score,
    )


def _reasons(
    left: Sequence[int], pairs: FeasiblePairs, every: set[int], use_color: bool
) -> list[UnplacedReason]:
    """Why each tile left out (by position) is not placed, against the slots ``every``."""
    out: list[UnplacedReason] = []
    for k in left:
        if not pairs.slots_of(k, False) & every:
            out.append("shape_absent")
        elif use_color and not pairs.slots_of(k, True) & every:
            out.append("color_absent")
        else:
            out.append("slots_taken")
    return out


def _tol(tolerances: qshape.Tolerances | None) -> qshape.Tolerances:
    from qshape.theory.tolerances import default_tolerances  # noqa: PLC0415

    return default_tolerances() if tolerances is None else tolerances


__all__ = [
    "REASONS",
    "FeasiblePairs",
    "PickPlace",
    "PlacementPlan",
    "Unplaced",
    "UnplacedReason",
    "fitted_command",
    "outline_residual",
    "plan_placements",
    "refine_rotation",
    "wrap",
]
