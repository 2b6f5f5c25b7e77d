"""The task description the env publishes to agents: one frozen value, the agent-env boundary.

`TaskSpec` holds every fact a policy may rely on besides the observations: the design's slots
in the world (the one conversion from design millimetres to world metres), the pick and place
areas with their heights (the one home of the tile thickness as seen by an agent), the camera
models at the observation size, the input-belt motion and the ``pick_place`` action codec.
Agents are built from it (``ScriptedAgent.from_env``); they never read the env's internals.

`PickPlaceCodec` is the one conversion between a world pick-and-place command and the
normalised ``pick_place`` action: the env decodes with it, agents encode with it.
`DiscreteCodec` is the ``pick_place_discrete`` action's: its index ranges, what a rotation index
turns and the flat index of a (tile, slot, rotation) triple. `StateFields` and
``TaskSpec.object_fields`` say what each column of the ``state`` and ``objects`` rows means.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Literal

import numpy as np

from envs.cell.cameras import CameraModel
from envs.cell.config import FeedMode
from envs.errors import EnvError
from envs.observations.fields import ROBOT_FIELDS, SLOT_FIELDS, TILE_FIELDS, FieldMap
from envs.observations.objects import object_fields
from spatial.angles import TWO_PI, wrap_angle
from spatial.units import MM_PER_M

if TYPE_CHECKING:
    from envs.cell.cell import Cell
    from envs.env_config import ActionMode, EnvConfig, RotationFrame
    from qshape.design import Design
    from qshape.theory.figure import Figure

RANGE_SLACK = 1e-6
"""Allowed excess over [-1, 1] for float rounding in normalised actions."""

CameraName = Literal["input_camera", "output_camera"]


class ActionError(EnvError, ValueError):
    """An action the space does not allow (wrong shape, dtype, NaN/inf, out of range).

    Also a ``pick_place_discrete`` action its mask forbids, with ``invalid_actions="refuse"``.
    """


@dataclass(frozen=True, eq=False)
class WorldSlot:
    """One design slot in the world.

    Attributes:
        index: Slot index in the design (and in the env's ``slots``).
        name: The design's slot name.
        class_name: Shape-and-colour class (tiles of this class fill it).
        xy: World x, y of the slot's area centroid, shape (2,) [m].
        yaw: Slot yaw [rad] (the design angle, counter-clockwise seen from above).
        symmetry: Rotational symmetry order of the shape (1: none, 0: continuous).
        color: Design RGB in [0, 1].
        figure: The slot's outline as a qshape figure in design millimetres (y up; mesh axes
            are the world's).
    """

    index: int
    name: str
    class_name: str
    xy: np.ndarray
    yaw: float
    symmetry: int
    color: tuple[float, float, float]
    figure: Figure


@dataclass(frozen=True, eq=False)
class Area:
    """A working area: where pad points may go and at which heights.

    Attributes:
        lo: Lower (x, y) corner [m].
        hi: Upper (x, y) corner [m].
        surface_z: Height of the surface tiles rest on (belt top, mesh sheet top) [m].
        tile_top_z: Height of a resting tile's top face [m] (``surface_z`` + tile thickness):
            where the pad seals and the plane a camera sees tiles on.
    """

    lo: np.ndarray
    hi: np.ndarray
    surface_z: float
    tile_top_z: float

    @property
    def centre(self) -> np.ndarray:
        """Centre (x, y) [m], shape (2,)."""
        return (self.lo + self.hi) / 2

    def to_unit(self, xy: np.ndarray) -> np.ndarray:
        """World (x, y) [m] -> [-1, 1]^2 over the area (outside points map outside)."""
        return 2 * (np.asarray(xy, float) - self.lo) / (self.hi - self.lo) - 1

    def from_unit(self, u: np.ndarray) -> np.ndarray:
        """[-1, 1]^2 -> world (x, y) [m]."""
        return self.lo + (np.asarray(u, float) + 1) / 2 * (self.hi - self.lo)


@dataclass(frozen=True)
class PickPlaceCommand:
    """One pick-and-place in world terms: where to seal, where to release, how much to turn.

    The rotation travels as one relative angle from the matcher to the executor (nobody turns
    it into absolute yaws and back). ``pick_yaw``, the tile's yaw on the belt (the agent's
    estimate), only lets the planner choose among the tile's symmetric wrist solutions.

    Attributes:
        pick_xy: Pad point at the pick, shape (2,) [m].
        pick_yaw: The tile's yaw at the pick [rad].
        place_xy: Pad point at the place, shape (2,) [m].
        rotation: The tile's turn from pick to place, counter-clockwise seen from above [rad].
    """

    pick_xy: tuple[float, float]
    pick_yaw: float
    place_xy: tuple[float, float]
    rotation: float

    @staticmethod
    def between_yaws(
        pick_xy: tuple[float, float],
        pick_yaw: float,
        place_xy: tuple[float, float],
        place_yaw: float,
    ) -> PickPlaceCommand:
        """The command turning a tile at ``pick_yaw`` to ``place_yaw`` (absolute yaws) [rad]."""
        return PickPlaceCommand(
            pick_xy, pick_yaw, place_xy, float(wrap_angle(place_yaw - pick_yaw))
        )


@dataclass(frozen=True, eq=False)
class PickPlaceCodec:
    """Normalised ``pick_place`` action in [-1, 1] <-> `PickPlaceCommand`.

    Layout with ``pick_yaw`` (the ``-v0`` ids), shape (6,): pick (x, y) over ``pick``
    (linear), the tile's yaw / pi, place (x, y) over ``place``, the rotation / pi. Without it
    (``-v1``), shape (5,): pick (x, y), place (x, y), the rotation / pi; decoded commands have
    ``pick_yaw`` 0 (the executor has no use for it: it would only turn a grasp offset, which is
    always zero) and `encode` drops a command's ``pick_yaw``.

    Attributes:
        pick: The pick area (input tile area grown by the pick margin; up to the belt's end
            when the belt moves).
        place: The place area (the mesh grown by the place margin).
        pick_yaw: The layout carries the pick-yaw entry (``pick_yaw_entry`` of the env).
    """

    pick: Area
    place: Area
    pick_yaw: bool = True

    @property
    def size(self) -> int:
        """Entries of an action: 6 with the pick-yaw entry, else 5."""
        return 6 if self.pick_yaw else 5

    def decode(self, action: np.ndarray) -> PickPlaceCommand:
        """Normalised action (`size`,) -> world command."""
        a = np.asarray(action, float)
        if not self.pick_yaw:
            a = np.insert(a, 2, 0.0)
        p = self.pick.from_unit(a[:2])
        q = self.place.from_unit(a[3:5])
        return PickPlaceCommand(
            (float(p[0]), float(p[1])),
            float(a[2] * math.pi),
            (float(q[0]), float(q[1])),
            float(a[5] * math.pi),
        )

    def encode(self, cmd: PickPlaceCommand) -> np.ndarray:
        """World command -> the normalised (`size`,) float32 action (angles wrapped).

        Raises:
            ActionError: A position outside its area.
        """
        p = self.pick.to_unit(np.asarray(cmd.pick_xy))
        q = self.place.to_unit(np.asarray(cmd.place_xy))
        if np.any(np.abs(p) > 1 + RANGE_SLACK) or np.any(np.abs(q) > 1 + RANGE_SLACK):
            raise ActionError(
                f"pick {np.round(cmd.pick_xy, 4).tolist()} or place "
                f"{np.round(cmd.place_xy, 4).tolist()} outside the areas: pick "
                f"{self.pick.lo.tolist()}..{self.pick.hi.tolist()}, place "
                f"{self.place.lo.tolist()}..{self.place.hi.tolist()} [m]"
            )
        yaw = float(wrap_angle(cmd.pick_yaw)) / math.pi
        turn = float(wrap_angle(cmd.rotation)) / math.pi
        out = np.array([p[0], p[1], yaw, q[0], q[1], turn])
        if not self.pick_yaw:
            out = np.delete(out, 2)
        return np.clip(out, -1, 1).astype(np.float32)


def discrete_codec(cell: Cell, config: EnvConfig) -> DiscreteCodec:
    """The ``pick_place_discrete`` codec of a cell (at least one tile and one slot index)."""
    n, k = max(len(cell.tiles), 1), max(len(cell.slots), 1)
    return DiscreteCodec(n, k, config.rotation_bins, config.rotation_frame)


def rotation_step(bins: int) -> float:
    """The turn of one ``pick_place_discrete`` rotation index, ``2 pi / bins`` [rad]."""
    return TWO_PI / bins


@dataclass(frozen=True)
class DiscreteCodec:
    """The ``pick_place_discrete`` action: MultiDiscrete((tiles, slots, rotation_bins)).

    Which tile and slot an index names is the env's ``tile_order`` / ``slot_order``
    (`envs.indexing`); rotation ``r`` turns the tile by ``r`` steps of `rotation_step` from the
    slot-aligned pose nearest the tile's yaw (``rotation_frame`` ``tile``) or from the slot's
    own yaw (``slot``).

    Attributes:
        tiles: Tile indices (the episode's maximum tile count).
        slots: Slot indices.
        rotation_bins: Rotation indices.
        rotation_frame: ``tile`` or ``slot``: what rotation 0 means.
    """

    tiles: int
    slots: int
    rotation_bins: int
    rotation_frame: RotationFrame

    @property
    def nvec(self) -> tuple[int, int, int]:
        """The MultiDiscrete sizes (tiles, slots, rotation_bins)."""
        return (self.tiles, self.slots, self.rotation_bins)

    @property
    def rotation_step(self) -> float:
        """The turn of one rotation index [rad]."""
        return rotation_step(self.rotation_bins)

    def turn(self, rotation: int) -> float:
        """The turn rotation index ``rotation`` adds to its frame's zero [rad]."""
        return rotation * TWO_PI / self.rotation_bins

    def nearest_rotation(self, turn: float) -> int:
        """The rotation index whose turn is nearest ``turn`` [rad] (modulo a full turn)."""
        return round(turn / self.rotation_step) % self.rotation_bins

    def flat(self, action: tuple[int, int, int] | np.ndarray) -> int:
        """The flat index of (tile, slot, rotation), row-major (rotation fastest)."""
        return int(np.ravel_multi_index(tuple(int(a) for a in action), self.nvec))

    def unflat(self, index: int) -> np.ndarray:
        """(tile, slot, rotation) of a flat index, shape (3,) int64."""
        return np.array(np.unravel_index(int(index), self.nvec), np.int64)


@dataclass(frozen=True)
class StateFields:
    """What each column of the ``state`` observation's vectors means (`envs.observations.fields`).

    Attributes:
        robot: Field -> slice of the ``robot`` vector.
        tile: Field -> slice of one ``tiles`` row.
        slot: Field -> slice of one ``slots`` row.
    """

    robot: FieldMap = field(default_factory=lambda: ROBOT_FIELDS)
    tile: FieldMap = field(default_factory=lambda: TILE_FIELDS)
    slot: FieldMap = field(default_factory=lambda: SLOT_FIELDS)


@dataclass(frozen=True, eq=False)
class TaskSpec:
    """What an agent may know about an env besides its observations.

    Attributes:
        design: The design's name or path (as configured); ``procedural`` and the reset's
            draw with a procedural design source.
        slots: The design's slots in the world, in slot order.
        pick: The pick area (input belt side).
        place: The place area (mesh side).
        tile_thickness: Tile thickness [m] (``place.tile_top_z - place.surface_z``).
        mesh_centre: World (x, y) of the mesh centre [m], shape (2,).
        belt_speed: Input belt speed [m/s] along +x.
        feed: How tiles arrive: ``all`` at reset, a ``stream`` or in batches (``batch``).
        action_mode: The env's action mode.
        image_size: Observation image (height, width) [px].
        cameras: Camera models at ``image_size``, by name.
        codec: The ``pick_place`` action codec (None in the other action modes).
        tool_step: ``cartesian``: the tool move of a full action (1.0) in one control period,
            (dx, dy, dz, dyaw) [m, m, m, rad] (tool speed and yaw rate x the period); None in
            the other action modes.
        joint_step: ``joint``: the joint target move of a full action (1.0) in one control
            period, shape (6,) [rad] (each axis' speed limit x the period); None in the other
            action modes.
        discrete: The ``pick_place_discrete`` codec (None in the other action modes).
        state_fields: What each column of the ``state`` vectors means.
        object_fields: Field -> column slice of an ``objects`` row at the env's
            ``objects_points`` (`envs.observations.objects.object_fields`).
    """

    design: str
    slots: tuple[WorldSlot, ...]
    pick: Area
    place: Area
    tile_thickness: float
    mesh_centre: np.ndarray
    belt_speed: float
    feed: FeedMode
    action_mode: ActionMode
    image_size: tuple[int, int]
    cameras: dict[str, CameraModel]
    codec: PickPlaceCodec | None
    tool_step: tuple[float, float, float, float] | None = None
    joint_step: tuple[float, ...] | None = None
    discrete: DiscreteCodec | None = None
    state_fields: StateFields = field(default_factory=StateFields)
    object_fields: FieldMap = field(default_factory=object_fields)

    def camera(self, name: CameraName) -> CameraModel:
        """The camera model of ``name`` at the observation size.

        Raises:
            KeyError: Unknown camera (the message lists the allowed names).
        """
        if name not in self.cameras:
            raise KeyError(f"unknown camera {name!r}; allowed: {sorted(self.cameras)}")
        return self.cameras[name]


def work_areas(cell: Cell, config: EnvConfig | None = None) -> tuple[Area, Area]:
    """The pick and the place area of a cell, with their heights.

    Pick: the input tile area grown by ``pick_margin`` (up to the belt's end when it moves);
    place: the mesh grown by ``place_margin``. Without an env configuration: no margins and a
    static belt.
    """
    g, c = cell.geometry, cell.cfg
    t = c.tiles.thickness
    pick_margin = config.pick_margin if config is not None else 0.0
    place_margin = config.place_margin if config is not None else 0.0
    half_in = np.asarray(c.input_belt.tile_area) / 2 + pick_margin
    half_mesh = g.mesh_size / 2 + place_margin
    pick_hi = g.input_centre[:2] + half_in
    if (
        config is not None and config.belt_speed > 0
    ):  # tiles travel downstream: up to the belt's end
        pick_hi[0] = max(pick_hi[0], g.input_belt_end)
    pick = Area(g.input_centre[:2] - half_in, pick_hi, g.belt_top, g.belt_top + t)
    place = Area(
        g.output_centre[:2] - half_mesh, g.output_centre[:2] + half_mesh, g.mesh_top, g.mesh_top + t
    )
    return pick, place


def world_slots(cell: Cell, design: Design) -> tuple[WorldSlot, ...]:
    """The cell's slots in the world, with the design's figures (slot ``k`` = design slot ``k``).

    The world poses are the cell's (`Cell.slot_poses_world`): the one design-to-world
    conversion.
    """
    poses = cell.slot_poses_world()
    out = []
    for k, (spec, slot) in enumerate(zip(cell.slots, design.slots, strict=False)):
        rgb = (float(slot.color[0]), float(slot.color[1]), float(slot.color[2]))
        out.append(
            WorldSlot(
                k,
                slot.name,
                spec.shape.name,
                poses[k, :2].copy(),
                float(poses[k, 2]),
                int(spec.shape.symmetry),
                rgb,
                slot.figure(),
            )
        )
    return tuple(out)


def build_task_spec(cell: Cell, config: EnvConfig, design: Design) -> TaskSpec:
    """The task description of an env's cell and configuration."""
    pick, place = work_areas(cell, config)
    h, w = config.image_size
    cameras = {name: cell.camera_model(name, h, w) for name in ("input_camera", "output_camera")}
    codec = (
        PickPlaceCodec(pick, place, config.pick_yaw_entry)
        if config.action_mode == "pick_place"
        else None
    )
    feed: FeedMode = cell.cfg.tiles.feed
    dt = float(cell.model.opt.timestep)
    period = max(1, round(config.control_dt / dt)) * dt
    tool_step = joint_step = None
    if config.action_mode == "cartesian":
        step = config.tool_speed * period
        tool_step = (step, step, step, config.tool_yaw_rate * period)
    if config.action_mode == "joint":
        joint_step = tuple(float(v) * period for v in cell.max_joint_speed)
    discrete = None
    if config.action_mode == "pick_place_discrete":
        discrete = discrete_codec(cell, config)
    return TaskSpec(
        design=config.design if config.design_source == "fixed" else design.name,
        slots=world_slots(cell, design),
        pick=pick,
        place=place,
        tile_thickness=float(cell.cfg.tiles.thickness),
        mesh_centre=cell.geometry.output_centre[:2].copy(),
        belt_speed=float(config.belt_speed),
        feed=feed,
        action_mode=config.action_mode,
        image_size=(int(h), int(w)),
        cameras=cameras,
        codec=codec,
        tool_step=tool_step,
        joint_step=joint_step,
        discrete=discrete,
        object_fields=object_fields(config.objects_points),
    )


__all__ = [
    "MM_PER_M",
    "ActionError",
    "Area",
    "CameraName",
    "DiscreteCodec",
    "FeedMode",
    "PickPlaceCodec",
    "PickPlaceCommand",
    "StateFields",
    "TaskSpec",
    "WorldSlot",
    "build_task_spec",
    "discrete_codec",
    "rotation_step",
    "work_areas",
    "world_slots",
]
