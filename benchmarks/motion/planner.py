"""Planner benchmark: full designs picked and placed by the planners in the simulated cell.

Run ``python -m benchmarks.motion.planner``; prints the figures and writes
``out/planner_bench.json`` with, for each layout and belt speed: ``tiles_per_min`` (correctly
placed tiles per minute of simulated time), ``cycle_s`` (simulated seconds per tile), ``bound_s``
(the planners' lower bound per cycle, same limits, no dwell, no approach points), ``ratio`` (cycle
over bound),
``placed_within_tolerance`` (tiles within the position and yaw tolerances), ``tiles``, ``plan_ms``
(median wall-clock planning per cycle: IK + trajectories), plus tracking and placement errors.
``bound_s`` includes the two vacuum dwells (process time no motion can overlap) and, for the
last cycle, the time-optimal final retreat its plan ends with;
``motion_bound_s`` and ``ratio_motion`` are the same without them. ``standard_cycle_s`` and
``standard_cycle_blended_s`` check the acceleration assumption against ABB's catalogue cycle.

Targets: paper layout (belts 1 m apart) >= 24 tiles/min with every tile placed within
tolerance (issue 6) and within 3% of the bound with dwells (issue 14); tool tracking error
<= 1 mm along full-speed cycles; placement within 1 mm and 1 degree. Also reported: compact
layout (0.5 m) and a moving input belt at 0.1 and 0.2 m/s.

Execution runs through `planners.executor.TrajectoryExecutor`, the same executor the env's
``pick_place`` action uses: the cell's servo actuators get the planned positions (plus an
inverse-dynamics feed-forward) and velocities every physics step, the vacuum switches at the
plan's event times. Tile-to-slot assignment and pick poses come from the cell's
ground truth (this benchmarks planning and execution, not vision).
"""

from __future__ import annotations

import json
import math
import platform
import time
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from apps.cli import CommandParser, run_cli
from benchmarks.motion.standard_cycle import standard_cycle_blended_s, standard_cycle_s
from configs.files import write_text
from envs.cell.cell import Cell
from envs.cell.config import CellConfig, load_cell_config
from envs.cell.scene import build_arm_model
from envs.cell.tiles.shapes import design_mesh_size, tile_shapes_from_design
from envs.episode_setup import build_cell
from planners.config import PlannerConfig, load_planner_config
from planners.cycle.plan import CyclePlan
from planners.errors import LimitError, PlannerError
from planners.executor import TimedEvent, TrajectoryExecutor
from planners.ik import IKSolver
from planners.joints import JointState
from planners.limit_checks import validate
from planners.pick_place import PickPlacePlanner
from qshape.design import Design
from spatial.angles import wrap_angle, yaw_error

OUT = Path(__file__).resolve().parents[1] / "out" / "planner_bench.json"
POSITION_TOL = 1e-3
"""Placement position tolerance [m] (issue 6)."""
YAW_TOL_DEG = 1.0
"""Placement yaw tolerance [deg] (issue 6), modulo the tile's symmetry."""
TRACKING_TOL = 1e-3
"""Tool tracking error target [m]."""
CONTINUOUS_SYMMETRY_STEPS = 12
"""Equivalent yaws tried for a tile with continuous symmetry (circle, ring)."""
SETTLE_S = 0.3
"""Simulated settling time after the last release before measuring placements [s]."""
WAIT_STEP_S = 0.05
"""Waiting step when no tile is reachable yet on a moving belt [s]."""
MAX_WAIT_S = 10.0
"""Give up waiting for a reachable tile after this long [s]."""
BELT_END_MARGIN = 0.01
"""A moving tile is only picked if its predicted contact leaves this margin to the belt end [m]."""
BELT_SPEED_MATCH = 0.01
"""A moving-belt tile is picked once its speed is within this fraction of the belt's."""
LAYOUT_SEED_TRIES = 20
"""Layout seeds tried until the design's tiles fit the input belt's tile area."""
TARGET_TILES_PER_MIN = 24.0
TARGET_RATIO = 1.03
"""Paper layout: cycle over its lower bound, vacuum dwells included (issue 14)."""
LAYOUTS = {
    "paper": {"belt_separation": 1.0, "work_x": 0.0},
    # Tool-down poses at belt height are out of reach closer than ~0.33 m to the base axis:
    # work_x 0.47 keeps the whole tile area and mesh reachable with the belts 0.5 m apart.
    # A 0.6 m input belt keeps its upstream end clear of the robot base.
    "compact": {"belt_separation": 0.5, "work_x": 0.47, "input_belt_length": 0.6},
}


@dataclass(frozen=True)
class CycleRun:
    """What one executed cycle measured.

    Attributes:
        tile: Tile index.
        duration: Planned cycle duration [s].
        bound: Lower bound of the cycle, vacuum dwells included [s].
        motion_bound: Lower bound of the cycle's motion alone (no dwell) [s].
        plan_ms: Planning wall-clock time [ms].
        tracking_max: Largest tool position error against the plan along the cycle [m].
        tracking_rms: RMS tool position error [m].
        grasped: The pad sealed on the intended tile.
        placed_at: Simulation time the tile was placed (end of the release dwell) [s].
        tcp_speed_max: Peak planned tool speed [m/s] (datasheet limit 2.5 m/s).
        limits_ok: The sampled trajectory respects every joint limit (`validate`).
    """

    tile: int
    duration: float
    bound: float
    motion_bound: float
    plan_ms: float
    tracking_max: float
    tracking_rms: float
    grasped: bool
    placed_at: float
    tcp_speed_max: float
    limits_ok: bool


class CellRunner:
    """Plans and executes pick-and-place cycles in a `Cell`.

    Args:
        cell: The cell.
        planner_config: Planner settings.
        dynamic: Execute through the servo actuators (True) or kinematically (joint positions
            set each step, no arm dynamics).
    """

    def __init__(self, cell: Cell, planner_config: PlannerConfig, dynamic: bool = True) -> None:
        self.cell = cell
        self.dynamic = dynamic
        arm = build_arm_model(cell.cfg, with_cell=False)
        self.ik = IKSolver(arm, planner_config.ik, planner_config.limits)
        self.planner = PickPlacePlanner(self.ik, planner_config)
        self.dt = float(cell.model.opt.timestep)
        self.executor = TrajectoryExecutor(arm, self.dt)
        self.limits = self.ik.limits
        self.limit_tolerance = planner_config.trajectory.limit_tolerance
        self.thickness = cell.cfg.tiles.thickness
        self.mesh_top = cell.geometry.mesh_top
        self.slots = cell.slot_poses_world()

    def pick_pose(self, i: int) -> tuple[np.ndarray, float]:
        """Top-face centre (3,) [m] and yaw [rad] of tile i now (ground truth)."""
        poses = self.cell.tile_poses()
        top = poses.pos[i] + np.array([0.0, 0.0, self.thickness / 2])
        return top, float(poses.yaw[i])

    def plan(self, i: int, slot: int, start: JointState, at_contact: bool, last: bool) -> CyclePlan:
        """Plan the cycle moving tile i into slot ``slot``."""
        top, yaw = self.pick_pose(i)
        sx, sy, syaw = self.slots[slot]
        order = self.cell.tiles[i].shape.symmetry
        order = CONTINUOUS_SYMMETRY_STEPS if order == 0 else order
        place = np.array([sx, sy, self.mesh_top + self.thickness])
        return self.planner.plan_cycle(
            start,
            top,
            place,
            float(wrap_angle(syaw - yaw)),
            symmetry_order=order,
            grasp_offset=self.cell.tiles[i].grasp,
            object_yaw=yaw,
            belt_velocity=(self.cell.belt_speed, 0.0, 0.0),
            start_at_contact=at_contact,
            end_retreat=last,
        )

    def execute(self, plan: CyclePlan, tile: int) -> CycleRun:
        """Run a planned cycle in the cell through the planners' executor; its measurements."""
        cell = self.cell
        cmds = self.executor.commands(plan.trajectory)
        n = len(cmds.times)
        ref = np.array([self.ik.fk(cmds.q_ref[k])[0] for k in range(n)])
        speed = np.linalg.norm(np.diff(ref, axis=0), axis=1) / self.dt
        try:
            validate(plan.trajectory, self.limits, self.limit_tolerance)
            limits_ok = True
        except LimitError:
            limits_ok = False
        err = np.zeros(n)
        grasped = [False]
        placed_at = [math.nan]

        def release() -> None:
            grasped[0] = grasped[0] or cell.held_tile == tile
            cell.vacuum(False)

        def placed() -> None:
            placed_at[0] = cell.time

        def actuate(q: np.ndarray, qd: np.ndarray, q_ref: np.ndarray) -> None:
            if self.dynamic:
                cell.set_servo(q, qd)
            else:
                cell.set_qpos(q_ref)

        def measure(k: int) -> None:
            # FK of the current joints (the cell's site poses lag one step after mj_step).
            err[k] = float(np.linalg.norm(self.ik.fk(cell.qpos)[0] - ref[k]))

        t_placed = min(plan.piecewise.end_time("dwell_place"), float(cmds.times[-1]))
        self.executor.run(
            cmds,
            actuate,
            lambda: cell.step(1),
            events=(
                TimedEvent(plan.vacuum_on, lambda: cell.vacuum(True)),
                TimedEvent(plan.vacuum_off, release),
                TimedEvent(t_placed, placed),
            ),
            before_step=measure,
        )
        grasped_ok, placed_time = grasped[0], placed_at[0]
        return CycleRun(
            tile,
            plan.duration,
            plan.bound,
            plan.motion_bound,
            plan.plan_ms,
            float(err.max()),
            float(np.sqrt(np.mean(err**2))),
            grasped_ok,
            placed_time,
            float(speed.max()) if speed.size else 0.0,
            limits_ok,
        )

    def placement_errors(self, tile: int, slot: int) -> tuple[float, float]:
        """Position error [m] and yaw error [deg] (modulo symmetry) of a placed tile."""
        poses = self.cell.tile_poses()
        sx, sy, syaw = self.slots[slot]
        d = float(np.hypot(poses.pos[tile, 0] - sx, poses.pos[tile, 1] - sy))
        e = yaw_error(float(poses.yaw[tile]), syaw, self.cell.tiles[tile].shape.symmetry)
        return d, math.degrees(float(e))


def _next_tile(runner: CellRunner, todo: list[int], belt_speed: float) -> int | None:
    """The tile to pick next: any on a static belt; the most downstream reachable one moving."""
    cell = runner.cell
    if belt_speed == 0.0:
        return todo[0]
    pos = cell.tile_poses().pos
    vx = cell.data.qvel[cell.ids.tile_dof_index[:, 0]]
    settled = np.abs(vx - belt_speed) <= BELT_SPEED_MATCH * belt_speed
    # Only tiles already carried at the belt's speed (a fresh one is still speeding up).
    on = [i for i in todo if cell.on_stage[i] and not cell.lost[i] and settled[i]]
    # Downstream first; the planner raises for tiles that will be out of reach at contact.
    return max(on, key=lambda i: pos[i, 0]) if on else None


def _play_design(
    runner: CellRunner, n_tiles: int, belt_speed: float
) -> tuple[list[CycleRun], list[int], list[int]]:
    """Pick and place every tile in turn; the cycles run, the tiles skipped and missed."""
    cell = runner.cell
    todo = list(range(n_tiles))
    start = JointState.at_rest(cell.qpos)
    at_contact = False
    runs: list[CycleRun] = []
    skipped: list[int] = []
    missed: list[int] = []
    waited = 0.0
    while todo:
        todo = [k for k in todo if not cell.lost[k]]
        if not todo:
            break
        i = _next_tile(runner, todo, belt_speed)
        if i is None:
            if waited > MAX_WAIT_S:
                break
            cell.step(int(round(WAIT_STEP_S / runner.dt)))
            waited += WAIT_STEP_S
            continue
        waited = 0.0
        try:
            plan = runner.plan(i, i, start, at_contact, last=len(todo) == 1)
        except PlannerError as exc:
            print(f"  tile {i}: not planned ({type(exc).__name__}: {exc})")
            todo.remove(i)
            skipped.append(i)
            continue
        end_x = cell.geometry.input_belt_end - cell.tiles[i].radius - BELT_END_MARGIN
        if plan.pick_position[0] > end_x:  # would be picked past the belt's end: let it go
            todo.remove(i)
            missed.append(i)
            continue
        runs.append(runner.execute(plan, i))
        todo.remove(i)
        start = JointState.at_rest(plan.end.q)
        at_contact = not (len(todo) == 0)
    return runs, skipped, missed


def _cycle_figures(
    runs: list[CycleRun],
    errs: list[tuple[float, float]],
    tiles: int,
    sim: tuple[float, float],
) -> dict[str, Any]:
    """The cycle figures of a design's run, in the order of the benchmark's JSON.

    ``sim``: simulated time to the last placement, and with the final retreat [s].
    """
    sim_s, sim_total = sim
    ok = [
        d <= POSITION_TOL and y <= YAW_TOL_DEG and r.grasped
        for (d, y), r in zip(errs, runs, strict=True)
    ]
    n_ok = int(sum(ok))
    busy = sum(r.duration for r in runs)
    # Steady state: cycles between the first (from home) and the last (final retreat).
    middle = [r.duration for r in runs[1:-1]]
    steady = float(np.median(middle)) if middle else math.nan
    bound = sum(r.bound for r in runs)
    motion_bound = sum(r.motion_bound for r in runs)
    steady_ratio = (
        sum(r.duration for r in runs[1:-1]) / sum(r.bound for r in runs[1:-1])
        if len(runs) > 2
        else math.nan
    )
    return {
        "tiles": tiles,
        "cycles": len(runs),
        "placed_within_tolerance": n_ok,
        "all_placed_within_tolerance": n_ok == tiles,
        "tiles_per_min": 60.0 * n_ok / sim_s if sim_s > 0 else 0.0,
        "sim_s": sim_s,
        "sim_s_with_final_retreat": sim_total,
        "cycle_s": busy / max(len(runs), 1),
        "bound_s": bound / max(len(runs), 1),
        "ratio": busy / bound if bound > 0 else math.nan,
        "motion_bound_s": motion_bound / max(len(runs), 1),
        "ratio_motion": busy / motion_bound if motion_bound > 0 else math.nan,
        "steady_ratio": steady_ratio,
        "plan_ms": float(np.median([r.plan_ms for r in runs])) if runs else math.nan,
        "plan_ms_max": float(np.max([r.plan_ms for r in runs])) if runs else math.nan,
        "steady_cycle_s": steady,
        "steady_tiles_per_min": 60.0 / steady if steady > 0 else math.nan,
        "tcp_speed_max_m_s": max((r.tcp_speed_max for r in runs), default=math.nan),
        "all_trajectories_within_limits": all(r.limits_ok for r in runs),
        "tracking_max_mm": 1e3 * max((r.tracking_max for r in runs), default=math.nan),
        "tracking_rms_mm": 1e3 * float(np.sqrt(np.mean([r.tracking_rms**2 for r in runs])))
        if runs
        else math.nan,
        "place_err_max_mm": 1e3 * max((d for d, _ in errs), default=math.nan),
        "place_err_median_mm": 1e3 * float(np.median([d for d, _ in errs])) if errs else math.nan,
        "yaw_err_max_deg": max((y for _, y in errs), default=math.nan),
    }


def run_design(
    design: str,
    layout: str,
    belt_speed: float,
    planner_config: PlannerConfig,
    *,
    seed: int = 0,
    dynamic: bool = True,
    max_tiles: int | None = None,
    stream_period: float = 2.5,
) -> dict[str, Any]:
    """Pick and place a whole design; returns the figures for one layout and belt speed."""
    loaded = Design.load(design)
    shapes, slots = tile_shapes_from_design(loaded)
    if max_tiles is not None:
        shapes, slots = shapes[:max_tiles], slots[:max_tiles]
    cfg = cell_config(layout, belt_speed, stream_period)
    cell = build_cell(
        cfg, shapes, slots, seed, LAYOUT_SEED_TRIES, mesh_size=design_mesh_size(loaded)
    )
    try:
        cell.belt_speed = belt_speed
        runner = CellRunner(cell, planner_config, dynamic)
        cell.step(int(round(SETTLE_S / runner.dt)))
        t0 = cell.time
        runs, skipped, missed = _play_design(runner, len(slots), belt_speed)
        sim_total = cell.time - t0
        cell.step(int(round(SETTLE_S / runner.dt)))
        sim_s = (runs[-1].placed_at - t0) if runs else sim_total
        errs = [runner.placement_errors(r.tile, r.tile) for r in runs]
        return {
            "design": design,
            "layout": layout,
            "belt_separation_m": LAYOUTS[layout]["belt_separation"],
            "work_x_m": LAYOUTS[layout]["work_x"],
            "belt_speed_m_s": belt_speed,
            "execution": "dynamic" if dynamic else "kinematic",
            **_cycle_figures(runs, errs, len(slots), (sim_s, sim_total)),
            "dropped": cell.n_dropped,
            "lost": cell.n_lost,
            "skipped_unreachable": len(skipped),
            "missed_past_belt_end": len(missed),
            "warnings": cell.warnings(),
        }
    finally:
        cell.close()


def cell_config(layout: str, belt_speed: float, stream_period: float) -> CellConfig:
    """The bundled cell configuration with a layout and, on a moving belt, stream feeding."""
    base = load_cell_config()
    lay = LAYOUTS[layout]
    sections: dict[str, Any] = {
        "layout": replace(base.layout, belt_separation=lay["belt_separation"], work_x=lay["work_x"])
    }
    if "input_belt_length" in lay:
        sections["input_belt"] = replace(base.input_belt, length=lay["input_belt_length"])
    if belt_speed > 0.0:
        sections["tiles"] = replace(
            base.tiles, feed="stream", stream_initial=1, stream_period=stream_period
        )
    return replace(base, **sections)


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Run the benchmark and write ``out/planner_bench.json``."""
    parser = CommandParser(description=__doc__.splitlines()[0])
    parser.add_argument("--design", default="paper_mixed")
    parser.add_argument("--kinematic", action="store_true", help="no arm dynamics")
    parser.add_argument("--max-tiles", type=int, default=None)
    parser.add_argument("--quick", action="store_true", help="paper layout, static belt only")
    parser.add_argument("--out", type=Path, default=OUT)
    args = parser.parse_args(argv)
    pcfg = load_planner_config()
    cases = (
        [("paper", 0.0)]
        if args.quick
        else [("paper", 0.0), ("compact", 0.0), ("paper", 0.1), ("paper", 0.2)]
    )
    results = []
    for layout, speed in cases:
        t = time.perf_counter()
        r = run_design(
            args.design, layout, speed, pcfg, dynamic=not args.kinematic, max_tiles=args.max_tiles
        )
        r["wall_s"] = time.perf_counter() - t
        results.append(r)
        print(
            f"{layout:8s} belt {speed:.1f} m/s: {r['tiles_per_min']:.1f} tiles/min, cycle "
            f"{r['cycle_s']:.3f} s, bound {r['bound_s']:.3f} s, ratio {r['ratio']:.3f} (steady "
            f"{r['steady_ratio']:.3f}; motion bound {r['motion_bound_s']:.3f} s, ratio "
            f"{r['ratio_motion']:.3f}), placed "
            f"{r['placed_within_tolerance']}/{r['tiles']}, tracking max {r['tracking_max_mm']:.2f}"
            f" mm, place err max {r['place_err_max_mm']:.2f} mm / {r['yaw_err_max_deg']:.2f} deg,"
            f" plan {r['plan_ms']:.1f} ms"
        )
    paper = results[0]
    report = {
        "machine": platform.platform(),
        "note": "plan_ms is wall-clock on a shared 2-core machine: noisy.",
        "targets": {
            "tiles_per_min_paper": TARGET_TILES_PER_MIN,
            "ratio_max": TARGET_RATIO,
            "tracking_mm": 1e3 * TRACKING_TOL,
            "placement_mm_deg": [1e3 * POSITION_TOL, YAW_TOL_DEG],
        },
        "paper_meets_targets": bool(
            paper["tiles_per_min"] >= TARGET_TILES_PER_MIN
            and paper["ratio"] <= TARGET_RATIO
            and paper["all_placed_within_tolerance"]
        ),
        "standard_cycle_s": standard_cycle_s(pcfg),
        "standard_cycle_blended_s": standard_cycle_blended_s(pcfg),
        "planner_config": asdict(pcfg),
        "results": results,
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    write_text(args.out, json.dumps(report, indent=2, default=float))
    print(
        f"ABB standard cycle 25/300/25 mm: blended {report['standard_cycle_blended_s']:.3f} s, "
        f"stopping at every corner {report['standard_cycle_s']:.3f} s (ABB: about 0.85 s, "
        "blended)"
    )
    print(f"wrote {args.out}")
    return report


if __name__ == "__main__":
    run_cli(main)


__all__ = []
