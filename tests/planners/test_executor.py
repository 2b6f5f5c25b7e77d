"""The one trajectory executor (planners.executor) on the arm model."""

from __future__ import annotations

import mujoco
import numpy as np

from planners.config import load_planner_config
from planners.executor import TimedEvent, TrajectoryExecutor
from planners.joints import JointState
from planners.robot import ROBOT_XML
from planners.trajectory import chain


def test_tracks_a_move_and_fires_events_on_their_step() -> None:
    model = mujoco.MjModel.from_xml_path(str(ROBOT_XML))
    data = mujoco.MjData(model)
    home = model.key("home").qpos.copy()
    data.qpos[:] = home
    mujoco.mj_forward(model, data)
    cfg = load_planner_config()
    target = home + np.array([0.6, -0.3, 0.4, 0.5, -0.4, 1.0])
    traj = chain(JointState.at_rest(home), [(target, None, "move")], cfg.limits, ()).sample(
        cfg.trajectory.sample_dt
    )
    dt = float(model.opt.timestep)
    ex = TrajectoryExecutor(model, dt)
    cmds = ex.commands(traj)
    pos_act = np.flatnonzero(model.actuator_biasprm[:, 1] < 0)
    vel_act = np.flatnonzero(
        (model.actuator_biasprm[:, 2] < 0) & (model.actuator_biasprm[:, 1] == 0)
    )
    fired: list[float] = []
    err = np.zeros(len(cmds.times))

    def actuate(q: np.ndarray, qd: np.ndarray, _ref: np.ndarray) -> None:
        data.ctrl[pos_act] = q
        data.ctrl[vel_act] = qd

    def measure(k: int) -> None:
        err[k] = np.abs(data.qpos - cmds.q_ref[k]).max()

    half = traj.duration / 2
    ex.run(
        cmds,
        actuate,
        lambda: mujoco.mj_step(model, data),
        events=(TimedEvent(half, lambda: fired.append(data.time)),),
        before_step=measure,
    )
    assert len(fired) == 1 and abs(fired[0] - half) <= dt  # on the step at its time
    assert np.degrees(err.max()) < 1.0  # servo feed-forward keeps within a degree
    assert np.abs(data.qpos - target).max() < np.radians(0.5)
