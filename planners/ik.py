"""Inverse kinematics of the IRB 140 to tool-down poses with mink.

A target is a TCP position and a yaw with the tool pointing straight down (the TCP site's z
axis along world -z; yaw is the angle of the site's x axis in the world xy plane). The solver
runs mink's differential IK (a `FrameTask` on the TCP site with `ConfigurationLimit`,
`VelocityLimit` and optionally `CollisionAvoidanceLimit` against static obstacle geoms) on an
arm-only model: a model that also carries free tiles makes every iteration about 10x slower.

When an attempt does not converge (typically stuck at a wrist limit), the solver restarts from
the nearest known-good configuration it has solved before, then from perturbed seeds drawn from
its own seeded generator (deterministic). A target that no attempt reaches raises
`UnreachableError`; a wrong pose is never returned.

Because the tool axis is joint 6's axis, a tool-down solution for one yaw gives the solution for
any other yaw by turning joint 6 alone; `IKSolver.solve_yaws` uses this to choose, among a
tile's equivalent yaws (its rotational symmetry) and joint 6's turns, the one nearest the seed.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

import mink
import mujoco
import numpy as np
import numpy.typing as npt

from planners.config import N_JOINTS, IKConfig, JointLimits
from planners.errors import InvalidTargetError, PlannerError, UnreachableError
from planners.joints import as_joint_vector
from planners.robot import ROBOT_XML
from planners.tool_pose import tool_down_rotation
from spatial.angles import wrap_angle
from spatial.rotations import yaw_from_matrix
from spatial.units import MM_PER_M

Array = npt.NDArray[np.float64]

_TWO_PI = 2.0 * math.pi
_REACH_SLACK = 1e-3
"""Geometric reach pre-check slack [m] (the iterative solve decides near the boundary)."""


@dataclass(frozen=True)
class IKSolution:
    """A converged IK solution.

    Attributes:
        q: Joint angles, shape (6,) [rad].
        yaw: Tool yaw reached [rad] (one of the requested yaws).
        position_error: Distance of the TCP from the target [m].
        orientation_error: Rotation angle from the target orientation [rad].
        iterations: IK iterations over all attempts.
        attempts: Attempts used (1 = converged from the first seed).
    """

    q: Array
    yaw: float
    position_error: float
    orientation_error: float
    iterations: int
    attempts: int


class IKSolver:
    """Tool-down IK for the IRB 140 with mink (see the module docstring).

    Args:
        model: Arm-only MuJoCo model (may hold static cell geoms; no free bodies). None loads
            ``assets/irb140/irb140.xml``.
        config: IK settings; None uses the defaults.
        limits: Joint limits; velocity limits bound each iteration's step; None uses defaults.
        obstacles: Names of static geoms (belts, mesh) the arm's collision geoms keep
            ``config.collision_min_distance`` from; empty disables collision avoidance.

    Raises:
        PlannerError: The model lacks the configured site or joints, or has other joints.
    """

    def __init__(
        self,
        model: mujoco.MjModel | None = None,
        config: IKConfig | None = None,
        limits: JointLimits | None = None,
        obstacles: Sequence[str] = (),
    ) -> None:
        self.model = model if model is not None else mujoco.MjModel.from_xml_path(str(ROBOT_XML))
        self.config = config if config is not None else IKConfig()
        self.limits = limits if limits is not None else JointLimits()
        cfg, m = self.config, self.model
        if m.nq != N_JOINTS or m.nv != N_JOINTS:
            raise PlannerError(
                f"IK needs an arm-only model with {N_JOINTS} joints (static geoms allowed, no "
                f"free tiles); this model has nq={m.nq}, nv={m.nv}"
            )
        names = [m.joint(i).name for i in range(m.njnt)]
        if tuple(names) != tuple(cfg.joint_names):
            raise PlannerError(f"model joints {names} differ from IKConfig.joint_names")
        try:
            self.site_id = m.site(cfg.site).id
        except KeyError as exc:
            sites = [m.site(i).name for i in range(m.nsite)]
            raise PlannerError(f"no site {cfg.site!r} in the model; sites: {sites}") from exc
        self.lower = np.maximum(m.jnt_range[:, 0], self.limits.lower) + cfg.limit_margin
        self.upper = np.minimum(m.jnt_range[:, 1], self.limits.upper) - cfg.limit_margin
        self._lower_list: list[float] = self.lower.tolist()
        self._upper_list: list[float] = self.upper.tolist()
        self.configuration = mink.Configuration(m)
        self._data = mujoco.MjData(m)
        self.task = mink.FrameTask(
            cfg.site,
            "site",
            position_cost=cfg.position_cost,
            orientation_cost=cfg.orientation_cost,
            lm_damping=cfg.damping,
        )
        self.mink_limits: list[mink.Limit] = [
            mink.ConfigurationLimit(m, min_distance_from_limits=cfg.limit_margin),
            mink.VelocityLimit(
                m, dict(zip(cfg.joint_names, self.limits.max_velocity, strict=True))
            ),
        ]
        self._pairs = np.zeros((0, 2), dtype=int)
        if obstacles:
            robot_geoms = [
                i
                for i in range(m.ngeom)
                if m.geom_bodyid[i] != 0 and (m.geom_contype[i] or m.geom_conaffinity[i])
            ]
            self.mink_limits.append(
                mink.CollisionAvoidanceLimit(
                    m,
                    [(robot_geoms, list(obstacles))],
                    minimum_distance_from_collisions=cfg.collision_min_distance,
                    collision_detection_distance=cfg.collision_detection_distance,
                )
            )
            try:
                obstacle_ids = [m.geom(name).id for name in obstacles]
            except KeyError as exc:
                raise PlannerError(f"obstacle geom not in the model: {exc}") from exc
            self._pairs = np.array([(a, b) for a in robot_geoms for b in obstacle_ids], dtype=int)
        self._rng = np.random.default_rng(cfg.restart_seed)
        # Known-good solutions, a ring buffer: target (x, y, z, yaw) features and joint angles.
        self._known_feature = np.zeros((cfg.memory, 4))
        self._known_q = np.zeros((cfg.memory, N_JOINTS))
        self._n_known = 0
        self._next_known = 0
        self._home = 0.5 * (self.lower + self.upper)
        self._reach = self._reach_geometry()
        self._yaw_sign = self._joint6_yaw_sign()

    # ------------------------------------------------------------------ kinematics helpers

    def fk(self, q: npt.ArrayLike) -> tuple[Array, Array]:
        """TCP position (3,) [m] and rotation (3, 3) at configuration ``q`` (6,) [rad]."""
        d = self._data
        d.qpos[:] = q
        mujoco.mj_kinematics(self.model, d)
        return d.site_xpos[self.site_id].copy(), d.site_xmat[self.site_id].reshape(3, 3).copy()

    def jacobian(self, q: npt.ArrayLike) -> Array:
        """TCP Jacobian (6, 6) at ``q``: rows linear [m/rad] then angular [rad/rad], world."""
        d = self._data
        d.qpos[:] = q
        mujoco.mj_kinematics(self.model, d)
        mujoco.mj_comPos(self.model, d)
        jac = np.zeros((6, self.model.nv))
        mujoco.mj_jacSite(self.model, d, jac[:3], jac[3:], self.site_id)
        return jac

    def clearance(self, q: npt.ArrayLike) -> float:
        """Smallest distance [m] between the arm and the obstacle geoms at ``q`` (inf if none).

        Distances beyond ``collision_detection_distance`` count as that distance.
        """
        if self._pairs.size == 0:
            return math.inf
        d = self._data
        d.qpos[:] = q
        mujoco.mj_kinematics(self.model, d)
        dmax = self.config.collision_detection_distance
        return min(
            float(mujoco.mj_geomDistance(self.model, d, int(a), int(b), dmax, None))
            for a, b in self._pairs
        )

    def pose_error(self, q: Array, position: Array, yaw: float) -> tuple[float, float]:
        """Position error [m] and orientation error [rad] of ``q`` against a tool-down target."""
        self.fk(q)
        return self._error_from_data(self._data, np.asarray(position, dtype=np.float64), yaw)

    def _reach_geometry(self) -> tuple[Array, float, float, float]:
        """Shoulder anchor at q=0, upper-arm and forearm lengths, tool offset below the wrist."""
        d = self._data
        d.qpos[:] = 0.0
        mujoco.mj_kinematics(self.model, d)
        anchors = d.xanchor[:N_JOINTS].copy()
        upper = float(np.linalg.norm(anchors[2] - anchors[1]))
        fore = float(np.linalg.norm(anchors[4] - anchors[2]))
        tool = float(np.linalg.norm(d.site_xpos[self.site_id] - anchors[4]))
        return anchors[1], upper, fore, tool

    def _joint6_yaw_sign(self) -> float:
        """d(yaw)/d(q6) for a tool-down configuration (+1 or -1)."""
        q = 0.5 * (self.lower + self.upper)
        q[1] = q[2] = q[3] = 0.0
        q[4] = 0.5 * math.pi
        y0 = yaw_from_matrix(self.fk(q)[1])
        q[5] += 0.1
        y1 = yaw_from_matrix(self.fk(q)[1])
        return float(np.sign(wrap_angle(y1 - y0)))

    def check_reach(self, position: Array) -> None:
        """Raise `UnreachableError` if no arm posture puts the wrist over ``position``.

        The wrist centre of a tool-down pose is ``tool`` above the TCP; it must lie within the
        annulus the upper arm and forearm span around the shoulder axis.
        """
        shoulder, upper, fore, tool = self._reach
        x, y, z = np.asarray(position, dtype=np.float64).tolist()
        sx, sy, sz = shoulder.tolist()
        dist = math.hypot(math.hypot(x, y) - math.hypot(sx, sy), z + tool - sz)
        if dist > upper + fore + _REACH_SLACK or dist < abs(upper - fore) - _REACH_SLACK:
            raise UnreachableError(
                f"tool-down pose at {np.round(position, 4).tolist()} m is out of reach: wrist "
                f"centre {dist:.3f} m from the shoulder, reachable "
                f"[{abs(upper - fore):.3f}, {upper + fore:.3f}] m"
            )

    # ------------------------------------------------------------------ solving

    def _attempt(self, seed: Array, position: Array, yaw: float) -> tuple[Array, float, float, int]:
        cfg = self.config
        q = self._in_range(seed)
        self.fk(q)
        pos_err, ori_err = self._error_from_data(self._data, position, yaw)
        if self._within_tolerance(pos_err, ori_err):
            return q, pos_err, ori_err, 0  # already there: no QP set up
        conf = self.configuration
        conf.update(q)
        self.task.set_target(
            mink.SE3.from_rotation_and_translation(
                mink.SO3.from_matrix(tool_down_rotation(yaw)), position
            )
        )
        for it in range(1, cfg.max_iterations + 1):
            try:
                vel = mink.solve_ik(
                    conf,
                    [self.task],
                    cfg.step_dt,
                    cfg.solver,
                    damping=cfg.regularisation,
                    limits=self.mink_limits,
                )
            except mink.NoSolutionFound:
                return conf.q.copy(), pos_err, ori_err, it - 1
            conf.integrate_inplace(vel, cfg.step_dt)
            pos_err, ori_err = self._error_from_data(conf.data, position, yaw)
            if self._within_tolerance(pos_err, ori_err):
                return conf.q.copy(), pos_err, ori_err, it
        return conf.q.copy(), pos_err, ori_err, cfg.max_iterations

    def _within_tolerance(self, pos_err: float, ori_err: float) -> bool:
        """Position [m] and orientation [rad] errors both within the configured tolerances."""
        cfg = self.config
        return pos_err <= cfg.position_tolerance and ori_err <= math.radians(
            cfg.orientation_tolerance_deg
        )

    def _error_from_data(
        self, data: mujoco.MjData, position: Array, yaw: float
    ) -> tuple[float, float]:
        """Position error [m] and rotation angle [rad] from the tool-down target, from ``data``.

        The rotation angle of ``R_target^T R`` (from its trace): the one orientation-error
        formula of the solver (convergence, seeds, `pose_error`). With ``R_target`` =
        `tool_down_rotation` ``(yaw)`` = [[c, s, 0], [s, -c, 0], [0, 0, -1]], the trace is
        ``c (R00 - R11) + s (R01 + R10) - R22``: scalar arithmetic, no matrix built.
        """
        px, py, pz = data.site_xpos[self.site_id].tolist()
        r00, r01, _, r10, r11, _, _, _, r22 = data.site_xmat[self.site_id].tolist()
        tx, ty, tz = position.tolist()
        c, s = math.cos(yaw), math.sin(yaw)
        trace = c * (r00 - r11) + s * (r01 + r10) - r22
        cos_angle = min(max(0.5 * (trace - 1.0), -1.0), 1.0)
        dx, dy, dz = px - tx, py - ty, pz - tz
        return math.sqrt(dx * dx + dy * dy + dz * dz), math.acos(cos_angle)

    def _seeds(self, seed: Array | None, feature: Array, up: Array, exact: bool) -> Iterator[Array]:
        """Seeds to try after the geometric guess ``up``, made as needed.

        ``exact``: ``up`` already met the tolerances (and was tried first by `solve`). Given,
        nearest known, ``up`` unless exact, and default elbow down (nearest pose first); then
        random perturbations of the nearest.
        """
        cfg = self.config
        candidates: list[Array] = [] if seed is None else [seed]
        if self._n_known:
            d = self._feature_distance(self._known_feature[: self._n_known], feature)
            nearest = np.argsort(d)[:2]
            candidates.extend(self._known_q[i].copy() for i in nearest)
        if not exact:
            candidates.append(up)
        candidates.append(self._default_seed(feature, elbow_up=False))
        feats = np.empty((len(candidates), 4))
        for k, c in enumerate(candidates):
            p, r = self.fk(self._in_range(c))
            feats[k] = p[0], p[1], p[2], yaw_from_matrix(r)
        order = np.argsort(self._feature_distance(feats, feature), kind="stable")
        yield from (candidates[int(i)] for i in order)
        base = up if exact else candidates[int(order[0])]
        for _ in range(cfg.restarts):
            yield base + self._rng.normal(0.0, cfg.restart_spread, N_JOINTS)

    def _in_range(self, q: Array) -> Array:
        """``q`` clipped to the joint ranges (`np.clip` costs ~3x more on 6 values)."""
        out: Array = np.minimum(np.maximum(q, self.lower), self.upper)
        return out

    def _feature_distance(self, feats: Array, feature: Array) -> Array:
        """Distance [m] of (x, y, z, yaw) features, yaw weighted by the tool length."""
        diff = feats - feature
        diff[:, 3] = ((diff[:, 3] + math.pi) % _TWO_PI - math.pi) * self._reach[3]
        dist: Array = np.sqrt(np.einsum("ij,ij->i", diff, diff))
        return dist

    def _default_seed(self, feature: Array, elbow_up: bool = True) -> Array:
        """Geometric guess: elbow up (or down), wrist flat, tool down, facing the target.

        Planar two-link solution for the wrist centre (``tool`` above the target) in the arm's
        vertical plane, from the model's own link lengths; joint 5 then points the tool down
        and joint 6 sets the yaw. Only a seed: mink refines it (where it is not already exact).
        """
        shoulder, upper, fore, tool = self._reach
        fx, fy, fz, fyaw = feature.tolist()
        sx, sy, sz = shoulder.tolist()
        dr = math.hypot(fx, fy) - math.hypot(sx, sy)
        dz = fz + tool - sz
        d = max(math.hypot(dr, dz), 1e-9)
        cos_b = (upper**2 + d**2 - fore**2) / (2.0 * upper * d)
        beta = math.acos(min(max(cos_b, -1.0), 1.0))
        q1 = math.atan2(dr, dz) + (-beta if elbow_up else beta)
        er, ez = upper * math.sin(q1), upper * math.cos(q1)
        phi = math.atan2(-(dz - ez), dr - er)  # forearm angle below horizontal
        lo, hi = self._lower_list, self._upper_list
        angles = (math.atan2(fy, fx), q1, phi - q1, 0.0, 0.5 * math.pi - phi, 0.0)
        q = np.array([min(max(a, lo[i]), hi[i]) for i, a in enumerate(angles)])
        d_kin = self._data
        d_kin.qpos[:] = q
        mujoco.mj_kinematics(self.model, d_kin)
        r = d_kin.site_xmat[self.site_id]
        yaw0 = math.atan2(float(r[3]), float(r[0]))
        q[5] = min(max(self._yaw_sign * float(wrap_angle(fyaw - yaw0)), lo[5]), hi[5])
        return q

    def solve(
        self, position: npt.ArrayLike, yaw: float, seed: npt.ArrayLike | None = None
    ) -> IKSolution:
        """Joint angles putting the TCP at ``position`` with the tool down at ``yaw``.

        Args:
            position: TCP target, shape (3,) [m], world frame.
            yaw: Tool yaw [rad].
            seed: Start configuration, shape (6,) [rad]; None uses the nearest known solution
                or a default posture.

        Raises:
            InvalidTargetError: Non-finite or wrongly shaped target or seed.
            UnreachableError: Out of reach, or no attempt converged within tolerance (the
                message gives the pose and the best residual).
        """
        pos = np.asarray(position, dtype=np.float64)
        if pos.shape != (3,) or not all(map(math.isfinite, pos.tolist())):
            raise InvalidTargetError(f"position must be 3 finite numbers [m], got {position!r}")
        if not math.isfinite(yaw):
            raise InvalidTargetError(f"yaw must be finite, got {yaw!r}")
        seed_q = None if seed is None else as_joint_vector(seed, "seed")
        self.check_reach(pos)
        feature = np.array([*pos.tolist(), yaw])
        cfg = self.config
        # The geometric guess first: inside the joint ranges it is usually exact (no QP).
        up = self._default_seed(feature)
        self._data.qpos[:] = up
        mujoco.mj_kinematics(self.model, self._data)
        pe, oe = self._error_from_data(self._data, pos, yaw)
        exact = self._within_tolerance(pe, oe)
        if exact and self.clearance(up) >= cfg.collision_min_distance:
            self._remember(feature, up)
            return IKSolution(up, float(yaw), pe, oe, 0, 1)
        total_it = 0
        best = (pe, oe) if exact else (math.inf, math.inf)
        first = 2 if exact else 1  # attempt 1 was the exact guess (blocked by an obstacle)
        attempts = first - 1
        for attempts, s in enumerate(self._seeds(seed_q, feature, up, exact), start=first):
            q, pe, oe, it = self._attempt(s, pos, yaw)
            total_it += it
            if (
                pe <= cfg.position_tolerance
                and oe <= math.radians(cfg.orientation_tolerance_deg)
                and self.clearance(q) >= cfg.collision_min_distance
            ):
                self._remember(feature, q)
                return IKSolution(q, float(yaw), pe, oe, total_it, attempts)
            if pe + oe * self._reach[3] < best[0] + best[1] * self._reach[3]:
                best = (pe, oe)
        raise UnreachableError(
            f"no tool-down solution at position {np.round(pos, 4).tolist()} m, yaw "
            f"{math.degrees(yaw):.2f} deg after {attempts} attempts: best residual "
            f"{best[0] * MM_PER_M:.2f} mm / {math.degrees(best[1]):.2f} deg, tolerance "
            f"{cfg.position_tolerance * MM_PER_M:.2f} mm / {cfg.orientation_tolerance_deg:.2f} deg "
            "(joint limits, obstacles or a flipped tool)"
        )

    def _remember(self, feature: Array, q: Array) -> None:
        """Keep a solution as a seed (the oldest goes once ``memory`` are kept)."""
        i = self._next_known
        self._known_feature[i] = feature
        self._known_q[i] = q
        self._next_known = (i + 1) % len(self._known_q)
        self._n_known = min(self._n_known + 1, len(self._known_q))

    def solve_yaws(
        self,
        position: npt.ArrayLike,
        yaws: npt.ArrayLike,
        seed: npt.ArrayLike | None = None,
        reference: npt.ArrayLike | None = None,
    ) -> IKSolution:
        """Solve for the equivalent yaw that needs the least wrist travel.

        One solve for the first yaw; the others (and joint 6's extra turns) follow by turning
        joint 6 alone. The candidate inside joint 6's range nearest ``reference`` (default: the
        seed, else the first solution) in joint 6 wins.

        Args:
            position: TCP target, shape (3,) [m].
            yaws: Equivalent tool yaws, shape (k,) [rad] (e.g. `symmetric_yaws`).
            seed: IK seed, shape (6,) [rad].
            reference: Configuration whose joint 6 angle should change least, shape (6,).

        Raises:
            InvalidTargetError: Empty or non-finite yaws.
            UnreachableError: See `solve`; or no candidate fits joint 6's range.
        """
        yaw_arr = np.atleast_1d(np.asarray(yaws, dtype=np.float64))
        if yaw_arr.size == 0 or not np.all(np.isfinite(yaw_arr)):
            raise InvalidTargetError(f"yaws must be a non-empty set of finite angles, got {yaws!r}")
        sol = self.solve(position, float(yaw_arr[0]), seed)
        ref_q = (
            as_joint_vector(reference, "reference")
            if reference is not None
            else (as_joint_vector(seed, "seed") if seed is not None else sol.q)
        )
        j6_lo, j6_hi = self.lower[5], self.upper[5]
        best_q, best_yaw, best_cost = None, 0.0, math.inf
        for y in yaw_arr:
            base = sol.q[5] + self._yaw_sign * float(wrap_angle(y - yaw_arr[0]))
            k_lo = math.ceil((j6_lo - base) / _TWO_PI)
            k_hi = math.floor((j6_hi - base) / _TWO_PI)
            for k in range(k_lo, k_hi + 1):
                q6 = base + _TWO_PI * k
                cost = abs(q6 - ref_q[5])
                if cost < best_cost:
                    q = sol.q.copy()
                    q[5] = q6
                    best_q, best_yaw, best_cost = q, float(y), cost
        if best_q is None:
            raise UnreachableError(
                f"no yaw of {np.round(np.degrees(yaw_arr), 2).tolist()} deg fits joint 6's range "
                f"[{math.degrees(j6_lo):.1f}, {math.degrees(j6_hi):.1f}] deg at "
                f"{np.round(np.asarray(position), 4).tolist()} m"
            )
        pe, oe = self.pose_error(best_q, np.asarray(position, dtype=np.float64), best_yaw)
        tol_ori = math.radians(self.config.orientation_tolerance_deg)
        if pe > self.config.position_tolerance or oe > tol_ori:
            # Joint 6 is not exactly the tool axis in this model: solve the chosen yaw properly.
            return self.solve(position, best_yaw, best_q)
        return IKSolution(best_q, best_yaw, pe, oe, sol.iterations, sol.attempts)


__all__ = ["IKSolution", "IKSolver", "ROBOT_XML", "wrap_angle"]
