"""Frame listeners: callbacks on a schedule of simulated time (videos of the motion in a step)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

TIME_SLACK = 1e-9
"""A frame due within this much simulated time [s] of now is called now (float rounding)."""


@dataclass
class FrameListener:
    """A callback and its simulated-time schedule [s]."""

    callback: Callable[[], None]
    period: float
    next_time: float


class FrameSchedule:
    """The env's frame listeners: each called once per period of simulated time at most."""

    def __init__(self) -> None:
        self.listeners: list[FrameListener] = []

    def __bool__(self) -> bool:
        return bool(self.listeners)

    def add(self, callback: Callable[[], None], period: float, now: float) -> None:
        """Call ``callback`` every ``period`` [s] from ``now`` [s] on."""
        self.listeners.append(FrameListener(callback, period, now))

    def restart(self, now: float) -> None:
        """Every schedule starts again at ``now`` [s] (an episode's start)."""
        for f in self.listeners:
            f.next_time = now

    def tick(self, now: float) -> None:
        """Call the listeners due at ``now`` [s]; each skips the frames it missed."""
        t = now + TIME_SLACK
        for f in self.listeners:
            if t >= f.next_time:
                f.callback()
                f.next_time += f.period * (1 + int((t - f.next_time) / f.period))


__all__ = ["FrameListener", "FrameSchedule"]
