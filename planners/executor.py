"""The one executor of planned motion: track a joint trajectory on a MuJoCo model.

`TrajectoryExecutor` turns a `JointTrajectory` into per-physics-step servo commands
(`ServoFeedForward`: reference velocity plus the inverse-dynamics torque folded into the
position target) and plays them: at every step it fires the events due (e.g. the vacuum at a
cycle's seal and release times), hands the commands to ``actuate`` and advances the simulation
one step with ``advance``. It knows nothing of tiles or tasks: the env's pick-and-place and the
planner benchmark both run their cycles through it, with their own callbacks.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import mujoco
import numpy as np

from planners.servo import Array, ServoCommands, ServoFeedForward
from planners.trajectory import JointTrajectory

EVENT_SLACK = 1e-9
"""Time slack [s] so an event falls on the physics step at (not after) its time."""


@dataclass(frozen=True)
class TimedEvent:
    """A callback due at a time along the trajectory.

    Attributes:
        time: When it is due [s from the trajectory's start]; fired before the first step
            that starts at or after it.
        fire: The callback.
    """

    time: float
    fire: Callable[[], object]


Actuate = Callable[[Array, Array, Array], None]
"""``actuate(q_cmd, qd_cmd, q_ref)``: apply one step's servo targets (6,) [rad, rad/s, rad]."""


class TrajectoryExecutor:
    """Plays joint trajectories through servo actuators, one physics step at a time.

    Args:
        model: Arm-only MuJoCo model (six hinges, a position and a velocity actuator each).
        period: Physics timestep of the simulation the commands drive [s].

    Raises:
        PlannerError: The model lacks the servo actuators, or ``period`` is not positive.
    """

    def __init__(self, model: mujoco.MjModel, period: float) -> None:
        self.servo = ServoFeedForward(model)
        self.period = float(period)

    def commands(self, trajectory: JointTrajectory) -> ServoCommands:
        """The servo commands of ``trajectory`` at every physics step."""
        return self.servo.commands(trajectory, self.period)

    def step_of(self, commands: ServoCommands, time: float) -> int:
        """Index of the first step starting at or after ``time`` [s]."""
        return int(np.searchsorted(commands.times, time - EVENT_SLACK))

    def run(
        self,
        commands: ServoCommands,
        actuate: Actuate,
        advance: Callable[[], object],
        *,
        events: Sequence[TimedEvent] = (),
        before_step: Callable[[int], None] | None = None,
        after_step: Callable[[int], None] | None = None,
    ) -> None:
        """Play ``commands`` one physics step at a time.

        Per step ``k``: the events due, ``actuate``, ``before_step(k)``, ``advance()``,
        ``after_step(k)``.

        Args:
            commands: From `commands`.
            actuate: Applies one step's targets.
            advance: Advances the simulation by one physics step.
            events: Callbacks at times along the trajectory (fired in time order).
            before_step: Called with the step index after the targets are set.
            after_step: Called with the step index after the step.
        """
        due: dict[int, list[TimedEvent]] = {}
        for ev in sorted(events, key=lambda e: e.time):
            due.setdefault(self.step_of(commands, ev.time), []).append(ev)
        for k in range(len(commands.times)):
            for ev in due.get(k, ()):
                ev.fire()
            actuate(commands.q[k], commands.qd[k], commands.q_ref[k])
            if before_step is not None:
                before_step(k)
            advance()
            if after_step is not None:
                after_step(k)


__all__ = ["EVENT_SLACK", "Actuate", "TimedEvent", "TrajectoryExecutor"]
