"""The task cards' space tables: what each action and observation entry means, with real bounds.

Read from a live env: the published field maps (`TaskSpec.state_fields`,
`TaskSpec.object_fields`), the codecs (`TaskSpec.discrete`, `TaskSpec.codec`, ``tool_step``,
``joint_step``), the pick and place areas, and the arm's joint and velocity limits from the
MuJoCo model. A Box's declared bounds (``-1000`` to ``1000`` for the state vectors) are only a
container; these tables give the ranges the entries really take. Used by ``gen_tasks.py``.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping
from typing import Any

import gymnasium as gym
import mujoco
import numpy as np

ROBOT_MEANINGS = {
    "joint_pos": ("joint angles of axes 1-6", "rad"),
    "joint_vel": ("joint velocities of axes 1-6", "rad/s"),
    "tool_pos": ("vacuum pad position x, y, z (world frame, robot base at the origin)", "m"),
    "tool_yaw": ("pad yaw as (cos, sin)", "-"),
    "vacuum": ("vacuum on (1) or off (0)", "-"),
    "held": ("a tile is sealed to the pad (1) or not (0)", "-"),
}
"""Meaning and unit of each field of the ``robot`` vector (`envs.observations.fields`)."""
TILE_MEANINGS = {
    "xyz": ("tile position x, y, z (world frame)", "m"),
    "yaw": ("tile yaw as (cos, sin)", "-"),
    "class": ("the tile's class index (privileged: equal to its slot's)", "-"),
    "present": ("on the belts and not lost (1), else 0; 0 in a padding row", "-"),
}
SLOT_MEANINGS = {
    "xy": ("slot position x, y (world frame)", "m"),
    "yaw": ("yaw the slot wants its tile at, as (cos, sin)", "-"),
    "class": ("the class index the slot wants", "-"),
    "filled": ("filled correctly (1) or not (0)", "-"),
}
OBJECT_MEANINGS = {
    "rgb": ("glaze colour (tile: as built; slot: its class's nominal colour)", "-"),
    "area": ("area, holes subtracted", "cm^2"),
    "hole_area": ("summed area of the holes (0: none)", "cm^2"),
    "xy": ("area centroid x, y (world frame)", "m"),
    "yaw": ("yaw as (cos, sin)", "-"),
    "flag": ("tile: on the input belt and pickable now; slot: filled correctly", "-"),
    "valid": ("1 for a real row, 0 for a padding row (all zeros)", "-"),
    "points": ("outer outline as points (x, y) about the centroid, counter-clockwise", "mm"),
}
"""Meanings of the ``objects`` row fields (`envs.observations.objects`)."""


def _fmt(values: np.ndarray, digits: int = 3) -> str:
    lo, hi = float(np.min(values)), float(np.max(values))
    if lo == hi:
        return f"{lo:.{digits}g}"
    return f"{lo:.{digits}g} to {hi:.{digits}g}"


def _arm_limits(env: gym.Env[Any, Any]) -> tuple[np.ndarray, np.ndarray]:
    """(6, 2) joint ranges [rad] and (6, 2) velocity command ranges [rad/s] of the arm."""
    model = env.get_wrapper_attr("cell").model
    pos, vel = [], []
    for a in range(model.nu):
        joint = int(model.actuator_trnid[a, 0])
        kind = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_ACTUATOR, a) or ""
        if kind.startswith("vel"):
            vel.append(model.actuator_ctrlrange[a])
        elif kind.startswith("pos"):
            pos.append(model.jnt_range[joint])
    return np.asarray(pos), np.asarray(vel)


def _table(head: tuple[str, ...], rows: Iterator[tuple[str, ...]]) -> str:
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(lines)


def _columns(s: slice) -> str:
    return str(s.start) if s.stop - s.start == 1 else f"{s.start}-{s.stop - 1}"


def _field_table(
    fields: Mapping[str, slice],
    meanings: Mapping[str, tuple[str, str]],
    ranges: Mapping[str, str],
) -> str:
    """The table of a published field map: columns, field, meaning, unit, real range.

    Raises:
        KeyError: A published field without a documented meaning.
    """
    missing = sorted(set(fields) - set(meanings))
    if missing:
        raise KeyError(f"fields without a documented meaning: {missing}; add them to card_tables")
    return _table(
        ("columns", "field", "meaning", "unit", "range"),
        ((_columns(s), f"`{k}`", *meanings[k], ranges[k]) for k, s in fields.items()),
    )


def robot_table(env: gym.Env[Any, Any]) -> str:
    """The ``robot`` vector: columns, meaning, unit, real range."""
    spec = env.get_wrapper_attr("task_spec")
    fields = spec.state_fields.robot
    pos, vel = _arm_limits(env)
    ranges = {
        "joint_pos": "; ".join(f"{lo:.2f} to {hi:.2f}" for lo, hi in pos),
        "joint_vel": "; ".join(f"+-{hi:.2f}" for _, hi in vel) + " (commanded)",
        "tool_pos": "within the arm's reach (0.81 m)",
        "tool_yaw": "-1 to 1",
        "vacuum": "0 or 1",
        "held": "0 or 1",
    }
    return _field_table(fields, ROBOT_MEANINGS, ranges)


def _area(area: Any, axis: int) -> str:
    return f"{area.lo[axis]:.3f} to {area.hi[axis]:.3f}"


def _xy(area: Any) -> str:
    return f"x {_area(area, 0)}, y {_area(area, 1)} m"


def state_row_table(env: gym.Env[Any, Any], key: str) -> str:
    """A ``tiles`` or ``slots`` row of the ``state`` observation."""
    spec = env.get_wrapper_attr("task_spec")
    fields = spec.state_fields.tile if key == "tiles" else spec.state_fields.slot
    meanings = TILE_MEANINGS if key == "tiles" else SLOT_MEANINGS
    classes = len({s.class_name for s in spec.slots})
    pick, place = spec.pick, spec.place
    ranges = {
        "xyz": (
            f"x {_area(pick, 0)}, y {_area(pick, 1)} on the input belt; x {_area(place, 0)}, "
            f"y {_area(place, 1)} on the mesh; z from {pick.surface_z:.3f} (belt) up while held"
        ),
        "xy": f"x {_area(place, 0)}, y {_area(place, 1)} (the mesh)",
        "yaw": "-1 to 1",
        "class": f"0 to {classes - 1} ({classes} classes in this design)",
        "present": "0 or 1",
        "filled": "0 or 1",
    }
    return _field_table(fields, meanings, ranges)


def objects_row_table(env: gym.Env[Any, Any]) -> str:
    """A ``tiles`` or ``slots`` row of the ``objects`` observation."""
    spec = env.get_wrapper_attr("task_spec")
    fields = spec.object_fields
    place, pick = spec.place, spec.pick
    ranges = {
        "rgb": "0 to 1",
        "area": "> 0 (0 in padding)",
        "hole_area": ">= 0",
        "xy": f"the input belt (x {_area(pick, 0)}, y {_area(pick, 1)}) or the mesh "
        f"(x {_area(place, 0)}, y {_area(place, 1)})",
        "yaw": "-1 to 1",
        "flag": "0 or 1",
        "valid": "0 or 1",
        "points": "within the tile's size about the centroid",
    }
    return _field_table(fields, OBJECT_MEANINGS, ranges)


def observation_section(env: gym.Env[Any, Any]) -> str:
    """Every key of the observation: its space, then the table of what its entries mean."""
    space = env.observation_space
    assert isinstance(space, gym.spaces.Dict)
    spec = env.get_wrapper_attr("task_spec")
    state = "tiles" in space.spaces and space["tiles"].shape is not None
    objects = state and len(space["tiles"].shape) == 2
    out = []
    for key, sub in space.spaces.items():
        out.append(f"### `{key}`: `{sub}`\n")
        if key == "robot":
            out.append(robot_table(env))
        elif key in ("tiles", "slots") and objects:
            rows, width = sub.shape
            out.append(
                f"{rows} rows of {width} (row `i` is the `{key[:-1]}` the discrete action's "
                f"index `i` names):\n\n{objects_row_table(env)}"
            )
        elif key in ("tiles", "slots") and state:
            fields = spec.state_fields.tile if key == "tiles" else spec.state_fields.slot
            width = max(s.stop for s in fields.values())
            rows = sub.shape[0] // width
            out.append(
                f"{rows} row{'s' if rows > 1 else ''} of {width}, flattened (row `i` is "
                f"`{key}[i * {width}:(i + 1) * {width}]`, the {key[:-1]} the discrete action's "
                f"index `i` names; rows past the episode's {key} are zeros):\n\n"
                + state_row_table(env, key)
            )
        elif isinstance(sub, gym.spaces.Box) and sub.dtype == np.uint8:
            out.append("The camera's RGB picture, (height, width, 3), 0 to 255.")
        else:
            out.append(f"Declared bounds {_fmt(sub.low)} to {_fmt(sub.high)}.")
        out.append("")
    return "\n".join(out)


def action_section(env: gym.Env[Any, Any]) -> str:
    """The action space and a table of what each entry means."""
    spec = env.get_wrapper_attr("task_spec")
    space = env.action_space
    head = ("entry", "meaning", "range")
    if spec.discrete is not None:
        c = spec.discrete
        step = math.degrees(c.rotation_step)
        rows = [
            (
                "0",
                "tile index: the tile row of that index (`envs.indexing`)",
                f"0 to {c.tiles - 1}",
            ),
            ("1", "slot index: the slot row of that index", f"0 to {c.slots - 1}"),
            (
                "2",
                f"rotation index r: turn by r x {step:g} deg from the {c.rotation_frame}-aligned "
                "pose (`rotation_frame`)",
                f"0 to {c.rotation_bins - 1}",
            ),
        ]
        note = (
            '`env.action_masks()` and `info["action_mask"]` give the allowed indices '
            "(sb3-contrib's flat mask)."
        )
    elif spec.codec is not None:
        pick, place = spec.codec.pick, spec.codec.place
        rows = [
            ("0, 1", f"pick x, y over the pick area ({_xy(pick)})", "-1 to 1"),
        ]
        if spec.codec.pick_yaw:
            rows.append(
                ("2", "the tile's yaw at the pick / pi (does nothing; not at -v1)", "-1 to 1")
            )
        k = 3 if spec.codec.pick_yaw else 2
        rows += [
            (f"{k}, {k + 1}", f"place x, y over the mesh ({_xy(place)})", "-1 to 1"),
            (str(k + 2), "rotation of the tile / pi", "-1 to 1"),
        ]
        note = "One step is one whole pick-and-place cycle planned by the planners."
    elif spec.tool_step is not None:
        dx, dy, dz, dyaw = spec.tool_step
        rows = [
            (
                "0-2",
                f"tool dx, dy, dz, x {dx * 1e3:g}, {dy * 1e3:g}, {dz * 1e3:g} mm per step",
                "-1 to 1",
            ),
            ("3", f"tool dyaw, x {math.degrees(dyaw):.1f} deg per step", "-1 to 1"),
            ("4", "vacuum (> 0: on)", "-1 to 1"),
        ]
        note = "The pad stays pointing down (the planners' IK)."
    elif spec.joint_step is not None:
        steps = ", ".join(f"{math.degrees(s):.2f}" for s in spec.joint_step)
        rows = [
            ("0-5", f"joint target deltas of axes 1-6, x ({steps}) deg per step", "-1 to 1"),
            ("6", "vacuum (> 0: on)", "-1 to 1"),
        ]
        note = "Each axis' step is its speed limit times the control period."
    else:
        return f"`{space}`"
    return f"`{space}`\n\n{_table(head, iter(rows))}\n\n{note}"


__all__ = ["action_section", "observation_section"]
