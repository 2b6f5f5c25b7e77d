"""Servo commands that make position + velocity actuators track a joint trajectory closely.

The arm's servos are a MuJoCo ``position`` actuator (force ``kp (q_cmd - q)``) and a ``velocity``
actuator (force ``kv (qd_cmd - qd)``) per joint. Feeding the reference velocity as ``qd_cmd``
removes the damping lag; the torque the motion needs (inertia, Coriolis, damping minus gravity
compensation: MuJoCo's inverse dynamics) is folded into the position command as
``q_cmd = q_ref + tau / kp``, so at perfect tracking the actuators produce exactly that torque.
MuJoCo evaluates actuator forces at the start of each step, so commands are the reference at
the step's start time (no lead).
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
import numpy.typing as npt

from planners.config import N_JOINTS
from planners.errors import PlannerError
from planners.trajectory import JointTrajectory

Array = npt.NDArray[np.float64]


@dataclass(frozen=True)
class ServoCommands:
    """Per-control-step servo targets.

    Attributes:
        times: Times the commands apply from, shape (n,) [s].
        q: Position-actuator targets, shape (n, 6) [rad] (reference + feed-forward offset).
        qd: Velocity-actuator targets, shape (n, 6) [rad/s].
        q_ref: The reference positions at ``times``, shape (n, 6) [rad] (for error measures).
    """

    times: Array
    q: Array
    qd: Array
    q_ref: Array


class ServoFeedForward:
    """Computes `ServoCommands` for a robot model (arm-only, six hinge joints).

    Args:
        model: Arm-only MuJoCo model with one position and one velocity actuator per joint.

    Raises:
        PlannerError: The model lacks a position (affine bias ``-kp q``) or velocity actuator
            on one of its joints.
    """

    def __init__(self, model: mujoco.MjModel) -> None:
        if model.nv != N_JOINTS:
            raise PlannerError(f"servo feed-forward needs an arm-only model, got nv={model.nv}")
        self.model = model
        self.data = mujoco.MjData(model)
        kp = np.zeros(N_JOINTS)
        for a in range(model.nu):
            j = int(model.actuator_trnid[a, 0])
            if model.actuator_biasprm[a, 1] < 0.0 and 0 <= j < N_JOINTS:
                kp[model.jnt_dofadr[j]] = model.actuator_gainprm[a, 0]
        if np.any(kp <= 0.0):
            missing = [i + 1 for i in np.flatnonzero(kp <= 0.0)]
            raise PlannerError(f"no position actuator (kp) found for joints {missing}")
        self.kp = kp

    def torques(self, q: Array, qd: Array, qdd: Array) -> Array:
        """Joint torques [N m] the motion needs, shape (n, 6), from inverse dynamics."""
        m, d = self.model, self.data
        out = np.empty_like(q)
        for k in range(q.shape[0]):
            d.qpos[:] = q[k]
            d.qvel[:] = qd[k]
            d.qacc[:] = qdd[k]
            mujoco.mj_inverse(m, d)
            out[k] = d.qfrc_inverse
        return out

    def commands(self, traj: JointTrajectory, period: float) -> ServoCommands:
        """Servo targets every ``period`` [s] along ``traj``.

        Raises:
            PlannerError: ``period`` not positive.
        """
        if not period > 0.0:
            raise PlannerError(f"control period must be positive, got {period!r}")
        n = int(np.floor(traj.duration / period + 1e-9)) + 1
        times = np.arange(n, dtype=np.float64) * period
        states = [traj.at(float(t)) for t in times]
        q = np.array([s[0] for s in states])
        qd = np.array([s[1] for s in states])
        qdd = np.array([s[2] for s in states])
        tau = self.torques(q, qd, qdd)
        return ServoCommands(times, q + tau / self.kp, qd, q)


__all__ = ["ServoCommands", "ServoFeedForward"]
