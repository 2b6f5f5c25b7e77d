"""Settings of the scripted cell's belt scheduler (`agents.scripted.belt_schedule`), with units.

Bundled defaults live in ``configs/belt_schedule.yaml``; `load_belt_schedule_config` loads them
strictly (an unknown key is a `configs.ConfigError`) and applies keyword overrides; a value out
of its range is a `BeltScheduleError` naming the field and what is allowed::

    cfg = load_belt_schedule_config(reach_s=1.3)
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from agents.errors import AgentError
from configs import ConfigError, load_config
from configs.checks import check_fields, checked

BELT_SCHEDULE_CONFIG = "belt_schedule"
"""Bundled config name (``configs/belt_schedule.yaml``)."""


class BeltScheduleError(AgentError, ConfigError):
    """A belt-scheduler setting out of its range (the message names it and the allowed range)."""


@dataclass(frozen=True)
class BeltScheduleConfig:
    """How the scripted cell orders, tracks and gives up tiles on a moving belt.

    Attributes:
        first_reach_s: Time from the episode's first picture (the arm at home) to the pad's
            contact with the tile it picks [s].
        reach_s: Time from a picture (the arm at the last place contact) to the next pick's
            contact [s]: the planner's return swing and descent, taken on the long side.
        first_cycle_s: First estimate of the time from the episode's first picture to the
            second [s] (the first cycle starts at home).
        cycle_s: First estimate of the time between two pictures (one pick-and-place cycle)
            [s]; every measured interval refines it (`cycle_smoothing`).
        cycle_smoothing: Weight of a measured interval in the running cycle estimate, in
            (0, 1] (1: the last measurement alone).
        end_margin: The pick contact must happen this far before the input belt's end [m]
            (the pad travels with the belt through the vacuum dwell, and the tile must still
            rest on the belt).
        match_gate_x: Largest gap along the belt between a track's predicted position and a
            seen tile it is matched to [m], before the interval is measured.
        match_tolerance_x: The same gap once the interval is measured from the matches [m].
        match_gate_y: Largest gap across the belt between a track and its tile [m] (a tile
            on a belt keeps its place across it).
        match_color: Largest RGB distance (RGB in [0, 1]) between a track's and a tile's
            measured colours.
        match_area: Largest relative difference between a track's and a tile's areas.
        view_margin: A tracked tile whose whole outline is predicted at least this far inside
            the camera's view must be seen there [m]; unseen, it left the belt (picked, or
            fallen); further out it is tracked on from its last sighting.
        min_interval_s: Shortest interval between two pictures the measurement accepts [s].
        last_chance_reach_s: The shortest reach measured [s]: when no tile can be picked on
            time with ``reach_s``, the most urgent one this shorter reach still gets to in time
            is tried (the cycle would be empty otherwise, so the try costs no other tile).
    """

    first_reach_s: float = checked(0.7, gt=0)
    reach_s: float = checked(1.2, gt=0)
    first_cycle_s: float = checked(1.8, gt=0)
    cycle_s: float = checked(2.3, gt=0)
    cycle_smoothing: float = checked(0.5, gt=0, le=1)
    end_margin: float = checked(0.02, ge=0)
    match_gate_x: float = checked(0.06, gt=0)
    match_tolerance_x: float = checked(0.006, gt=0)
    match_gate_y: float = checked(0.004, gt=0)
    match_color: float = checked(0.15, gt=0)
    match_area: float = checked(0.25, gt=0)
    view_margin: float = checked(0.004, ge=0)
    min_interval_s: float = checked(0.5, gt=0)
    last_chance_reach_s: float = checked(1.0, gt=0)

    def __post_init__(self) -> None:
        """Raise `BeltScheduleError` on a value out of its range."""
        check_fields(self, BeltScheduleError, qualify=True)
        if self.match_tolerance_x > self.match_gate_x:
            raise BeltScheduleError(
                "BeltScheduleConfig.match_tolerance_x must be at most match_gate_x, got "
                f"{self.match_tolerance_x!r} > {self.match_gate_x!r}"
            )
        if self.last_chance_reach_s > self.reach_s:
            raise BeltScheduleError(
                "BeltScheduleConfig.last_chance_reach_s must be at most reach_s, got "
                f"{self.last_chance_reach_s!r} > {self.reach_s!r}"
            )
        for name in ("first_reach_s", "reach_s"):
            if getattr(self, name) >= getattr(self, name.replace("reach", "cycle")):
                raise BeltScheduleError(
                    f"BeltScheduleConfig.{name} must be shorter than its cycle "
                    f"({name.replace('reach', 'cycle')}), got {getattr(self, name)!r}"
                )


def load_belt_schedule_config(
    name_or_path: str | Path | None = BELT_SCHEDULE_CONFIG, **overrides: Any
) -> BeltScheduleConfig:
    """Load the belt scheduler's settings.

    Args:
        name_or_path: Bundled name or YAML path; None: the dataclass defaults.
        **overrides: Fields replacing the file's values.

    Raises:
        configs.ConfigError: Unknown key or wrong type.
        BeltScheduleError: A value out of its range.
    """
    return load_config(BeltScheduleConfig, name_or_path, **overrides)


__all__ = [
    "BELT_SCHEDULE_CONFIG",
    "BeltScheduleConfig",
    "BeltScheduleError",
    "load_belt_schedule_config",
]
