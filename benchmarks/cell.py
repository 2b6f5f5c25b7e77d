"""Benchmark of the simulated cell: physics speed with resting tiles and camera rendering.

Run ``MUJOCO_GL=egl python -m benchmarks.cell``; prints the figures and writes
``out/bench_cell.json``. Targets (issue 4): physics with 40 resting tiles >= 20x real time on one
core; both cameras at 128 x 128 >= 100 frames/s in total; 656 x 492 reported.
"""

from __future__ import annotations

import platform
import time
from pathlib import Path

import mujoco
import numpy as np

from apps.cli import CommandParser, run_cli, write_result
from envs.cell.cell import CAMERAS, Cell
from envs.cell.config import CellConfig, InputBeltConfig, load_cell_config
from envs.cell.rendering import rendering_backend
from envs.cell.tiles.shapes import basic_shapes

N_TILES = 40
PHYSICS_TARGET_RTF = 20.0
RENDER_TARGET_FPS = 100.0


def _physics(cfg: CellConfig, seconds: float, moving_arm: bool) -> dict[str, float]:
    shapes = (basic_shapes() * 6)[:N_TILES]
    cell = Cell(cfg, shapes, seed=0)
    try:
        cell.step(500)  # 1 s: tiles settle (and fall asleep)
        steps_per_call = 5
        calls = int(seconds / (cell.model.opt.timestep * steps_per_call))
        home = np.asarray(cfg.robot.home)
        t0 = time.perf_counter()
        for k in range(calls):
            if moving_arm:
                phase = 2 * np.pi * 0.5 * k * steps_per_call * cell.model.opt.timestep
                cell.set_servo(home + 0.4 * np.sin(phase), 0.4 * np.pi * np.cos(phase) * np.ones(6))
            cell.step(steps_per_call)
        wall = time.perf_counter() - t0
        sim = calls * steps_per_call * cell.model.opt.timestep
        return {
            "tiles": len(cell.tiles),
            "sim_s": sim,
            "wall_s": wall,
            "realtime_factor": sim / wall,
            "steps_per_s": calls * steps_per_call / wall,
            "awake_trees_end": int(cell.data.ntree_awake),
            "trees": int(cell.model.ntree),
            "warnings": cell.warnings(),
        }
    finally:
        cell.close()


def _render(cfg: CellConfig, height: int, width: int, frames: int) -> dict[str, float]:
    cell = Cell(cfg, (basic_shapes() * 6)[:N_TILES], seed=0)
    try:
        bufs = {n: np.zeros((height, width, 3), np.uint8) for n in CAMERAS}
        for n in CAMERAS:
            cell.render(n, height, width, out=bufs[n])  # warm up
        t0 = time.perf_counter()
        for k in range(frames):
            name = CAMERAS[k % 2]
            cell.render(name, height, width, out=bufs[name])
        wall = time.perf_counter() - t0
        return {"height": height, "width": width, "frames": frames, "fps_total": frames / wall}
    finally:
        cell.close()


def main(argv: list[str] | None = None) -> dict:
    """Run the benchmark; returns the figures written to the JSON file."""
    parser = CommandParser(description=__doc__)
    parser.add_argument("--seconds", type=float, default=20.0, help="simulated seconds")
    parser.add_argument("--frames", type=int, default=400, help="frames per render size")
    parser.add_argument("--out", type=Path, default=Path("out/bench_cell.json"))
    args = parser.parse_args(argv)
    cfg = load_cell_config()
    no_sleep = load_cell_config(physics={"sleep": False})
    belt = CellConfig(input_belt=InputBeltConfig(speed=0.1))
    results = {
        "mujoco": mujoco.__version__,
        "machine": platform.processor() or platform.machine(),
        "gl": rendering_backend(),
        "physics_resting_arm_still": _physics(cfg, args.seconds, moving_arm=False),
        "physics_resting_arm_moving": _physics(cfg, args.seconds, moving_arm=True),
        "physics_resting_no_sleep": _physics(no_sleep, args.seconds / 4, moving_arm=False),
        "physics_moving_belt_0.1": _physics(belt, args.seconds / 4, moving_arm=False),
        "render_128": _render(cfg, 128, 128, args.frames),
        "render_656x492": _render(cfg, 492, 656, max(args.frames // 4, 20)),
        "targets": {
            "realtime_factor": PHYSICS_TARGET_RTF,
            "render_128_fps_total": RENDER_TARGET_FPS,
        },
    }
    rtf = results["physics_resting_arm_still"]["realtime_factor"]
    fps = results["render_128"]["fps_total"]
    results["pass"] = {"physics": rtf >= PHYSICS_TARGET_RTF, "render_128": fps >= RENDER_TARGET_FPS}
    for key, val in results.items():
        print(f"{key}: {val}")
    return write_result(args.out, results)


if __name__ == "__main__":
    run_cli(main)
