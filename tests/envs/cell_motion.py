"""Test helpers: a small Jacobian IK and straight-down pick/place motions for the cell.

Only for the cell's tests; the real planners (mink, ruckig) live in `planners/`. The IK of a
cell comes from the ``arm_ik`` fixture (``conftest.py``), which compiles the arm model once per
test module and cell configuration.
"""

from __future__ import annotations

from collections.abc import Callable

import mujoco
import numpy as np

from envs.cell.cell import Cell
from envs.cell.scene import build_arm_model

CONTROL_STEPS = 5
"""Physics steps per servo update (10 ms at the default timestep)."""
DOWN = np.diag([1.0, -1.0, -1.0])
"""Tool-down orientation at yaw 0: tcp x = world x, tcp z = world -z."""


def tool_down(yaw: float) -> np.ndarray:
    """Rotation matrix of the tcp pointing down, turned by yaw about world z."""
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]) @ DOWN


class ArmIK:
    """Damped least-squares IK of the tcp site on an arm-only model."""

    def __init__(self, cell: Cell) -> None:
        self.model = build_arm_model(cell.cfg, with_cell=False)
        self.data = mujoco.MjData(self.model)
        self.site = self.model.site("tcp").id
        self.lo, self.hi = self.model.jnt_range[:6, 0], self.model.jnt_range[:6, 1]

    def fk(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        self.data.qpos[:] = q
        mujoco.mj_kinematics(self.model, self.data)
        return self.data.site_xpos[self.site].copy(), self.data.site_xmat[self.site].reshape(3, 3)

    def solve(
        self, pos: np.ndarray, rot: np.ndarray, q0: np.ndarray, iters: int = 200
    ) -> np.ndarray:
        """Joint angles putting the tcp at pos with rotation rot; seeds q0, then a heuristic."""
        heuristic = np.array([np.arctan2(pos[1], pos[0]), 0.2, 0.2, 0.0, 1.2, q0[5]])
        rng = np.random.default_rng(0)
        restarts = [heuristic + rng.normal(0, 0.3, 6) * [0, 1, 1, 1, 1, 1] for _ in range(5)]
        for seed in (q0, heuristic, *restarts):
            q = self._solve(pos, rot, seed, iters)
            if q is not None:
                # Keep joint 6 near the seed (the tool's yaw wraps every 2 pi).
                q[5] = q0[5] + (q[5] - q0[5] + np.pi) % (2 * np.pi) - np.pi
                return np.clip(q, self.lo, self.hi)
        raise AssertionError(f"IK did not converge to {pos}")

    def _solve(
        self, pos: np.ndarray, rot: np.ndarray, q0: np.ndarray, iters: int
    ) -> np.ndarray | None:
        q = np.array(q0, float)
        jp, jr = np.zeros((3, 6)), np.zeros((3, 6))
        qt, qc, er = np.zeros(4), np.zeros(4), np.zeros(3)
        mujoco.mju_mat2Quat(qt, rot.ravel())
        for _ in range(iters):
            p, r = self.fk(q)
            ep = pos - p
            mujoco.mju_mat2Quat(qc, r.ravel())
            mujoco.mju_subQuat(er, qt, qc)  # rotation from current to target, current frame
            e = np.concatenate([ep, r @ er])
            if np.linalg.norm(ep) < 1e-6 and np.linalg.norm(er) < 1e-5:
                return q
            mujoco.mj_comPos(self.model, self.data)
            mujoco.mj_jacSite(self.model, self.data, jp, jr, self.site)
            j = np.vstack([jp, jr])
            dq = j.T @ np.linalg.solve(j @ j.T + 1e-6 * np.eye(6), e)
            step = np.max(np.abs(dq))
            if step > 0.3:
                dq *= 0.3 / step
            q = np.clip(q + dq, self.lo, self.hi)
        return None


ArmIKFor = Callable[[Cell], ArmIK]
"""The ``arm_ik`` fixture's type: the IK of a cell's arm, built once per configuration."""


def move(cell: Cell, q_to: np.ndarray, speed_scale: float = 0.9, settle: float = 0.05) -> float:
    """Quintic joint move at ``speed_scale`` of the axis speed limits; returns peak tcp speed."""
    q_from = cell.qpos
    dq = q_to - q_from
    vmax = cell.max_joint_speed * speed_scale
    duration = max(float(np.max(np.abs(dq) / vmax)) * 1.875, 0.05)
    dt = cell.model.opt.timestep * CONTROL_STEPS
    peak = 0.0
    prev = cell.tcp_pose()[0]
    for t in np.arange(dt, duration + dt / 2, dt):
        s = min(t / duration, 1.0)
        f = 10 * s**3 - 15 * s**4 + 6 * s**5
        fd = (30 * s**2 - 60 * s**3 + 30 * s**4) / duration
        cell.set_servo(q_from + f * dq, fd * dq)
        cell.step(CONTROL_STEPS)
        now = cell.tcp_pose()[0]
        peak = max(peak, float(np.linalg.norm(now - prev)) / dt)
        prev = now
    cell.set_servo(q_to)
    cell.step(max(1, int(settle / cell.model.opt.timestep)))
    return peak


def world_grasp(cell: Cell, i: int) -> tuple[np.ndarray, float]:
    """World position of tile i's grasp point on its top face, and its yaw."""
    poses = cell.tile_poses()
    yaw = float(poses.yaw[i])
    g = cell.tiles[i].grasp
    c, s = np.cos(yaw), np.sin(yaw)
    p = poses.pos[i] + [c * g[0] - s * g[1], s * g[0] + c * g[1], cell.cfg.tiles.thickness / 2]
    return p, yaw


def pick(cell: Cell, ik: ArmIK, i: int, approach: float = 0.05) -> bool:
    """Straight-down pick of tile i; returns whether the pad holds it after lifting."""
    p, yaw = world_grasp(cell, i)
    rot = tool_down(yaw)
    q_above = ik.solve(p + [0, 0, approach], rot, cell.qpos)
    q_touch = ik.solve(p + [0, 0, 0.0005], rot, q_above)
    move(cell, q_above)
    move(cell, q_touch, speed_scale=0.3)
    cell.vacuum(True)
    cell.step(CONTROL_STEPS)
    move(cell, q_above, speed_scale=0.3)
    return cell.held_tile == i


def place(
    cell: Cell,
    ik: ArmIK,
    i: int,
    target: tuple[float, float, float],
    surface_z: float,
    *,
    approach: float = 0.05,
    speed_scale: float = 0.9,
) -> float:
    """Carry held tile i so its centroid lands at target (x, y, yaw) on a surface; release.

    Returns:
        Peak tcp speed of the transfer move [m/s].
    """
    target_xy, target_yaw = target[:2], target[2]
    g = cell.tiles[i].grasp
    c, s = np.cos(target_yaw), np.sin(target_yaw)
    p = np.array(
        [
            target_xy[0] + c * g[0] - s * g[1],
            target_xy[1] + s * g[0] + c * g[1],
            surface_z + cell.cfg.tiles.thickness + 0.0005,
        ]
    )
    # Tile yaw relative to the pad is kept from the pick (pad yaw = tile yaw at pick).
    rot = tool_down(target_yaw)
    q_above = ik.solve(p + [0, 0, approach], rot, cell.qpos)
    q_down = ik.solve(p, rot, q_above)
    peak = move(cell, q_above, speed_scale=speed_scale)
    move(cell, q_down, speed_scale=0.3)
    cell.vacuum(False)
    cell.step(CONTROL_STEPS)
    move(cell, q_above, speed_scale=0.3)
    return peak
