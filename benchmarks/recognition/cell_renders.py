"""Recognition benchmark of the scripted cell's perception on real cell renders.

Run ``python -m benchmarks.recognition.cell_renders [--seeds N] [--true-camera]``: for N layouts of
the default design, renders the input camera (656 x 492), perceives and assigns (optimal,
colour-aware) and scores against the cell's ground truth: tiles assigned to a slot of their
class, pick-position error (mm), place-yaw error modulo symmetry (deg), wall time per image.
Writes ``out/bench_perception.json``.
"""

from __future__ import annotations

import json
import math
import time
from pathlib import Path
from typing import Any

import numpy as np

from agents.scripted.calibration import calibrate
from agents.scripted.config import load_agents_config
from agents.scripted.perception import balance_colors, perceive_tiles, slot_targets
from agents.scripted.placement import plan_placements
from apps.cli import CommandParser, run_cli
from benchmarks.design_cell import build_design_cell, nearest_tile
from configs.files import write_text
from envs.cell.calibration_board import render_calibration_views
from envs.cell.cameras import CameraModel
from envs.cell.config import load_cell_config
from envs.task_spec import work_areas, world_slots
from qshape.design import Design
from spatial.angles import yaw_error

ROOT = Path(__file__).resolve().parents[1]
SETTLE_STEPS = 100
"""Physics steps before the picture (tiles come to rest)."""


def bench(
    seeds: int, true_camera: bool, design_name: str = "paper_mixed", max_slots: int = 0
) -> dict[str, Any]:
    """Run the benchmark; returns the figures.

    Args:
        seeds: Layouts rendered.
        true_camera: Use the simulator's camera model instead of the calibrated one.
        design_name: Bundled design name or path.
        max_slots: Use only the design's first slots (designs larger than one belt load).
    """
    cfg = load_agents_config()
    design = Design.load(design_name)
    if max_slots:
        design = design.with_slots(design.slots[:max_slots])
    camera: CameraModel | None = None
    cal = None
    if not true_camera:
        views = render_calibration_views(load_cell_config(), "input_camera", cfg.calibration.target)
        cal = calibrate(views, cfg.calibration)
        camera = cal.camera
    tiles = ok = 0
    pos, yaw, wall, failures = [], [], [], []
    seed = 0
    for _ in range(seeds):
        cell, used = build_design_cell(design, seed=seed)
        seed = used + 1
        try:
            cell.step(SETTLE_STEPS)
            cam = camera if camera is not None else cell.camera_model("input_camera")
            slots = slot_targets(world_slots(cell, design))
            image = cell.render("input_camera")
            t0 = time.perf_counter()
            tile_top = work_areas(cell)[0].tile_top_z
            per = perceive_tiles(image, cam, tile_top, cfg=cfg.perception)
            per, _ = balance_colors(per, np.array([s.color for s in slots]), cfg.perception)
            plan = plan_placements(per.tiles, slots, cfg.placement)
            wall.append(time.perf_counter() - t0)
            truth = cell.tile_poses()
            tiles += len(design.slots)
            for c in plan.commands:
                i, d = nearest_tile(cell, np.array(c.pick[:2]))
                t = cell.tiles[i]
                e = float(yaw_error(truth.yaw[i] + c.rotation, c.place[2], t.shape.symmetry))
                good = t.shape.name == design.slots[c.slot].class_key
                ok += int(good)
                pos.append(1e3 * d)
                yaw.append(math.degrees(e))
                if not good:
                    failures.append(f"seed {used}: tile {i} to {c.slot_name}")
            failures += [f"seed {used}: open slot {slots[k].name}" for k in plan.open_slots]
        finally:
            cell.close()
    return {
        "design": design_name,
        "slots": len(design.slots),
        "layouts": seeds,
        "camera": "true" if true_camera else "calibrated",
        "calibration": cal.summary() if cal is not None else None,
        "tiles": tiles,
        "assigned_to_own_class": ok,
        "recognition_accuracy": ok / tiles if tiles else 0.0,
        "pick_error_mm_median": float(np.median(pos)) if pos else math.nan,
        "pick_error_mm_max": float(np.max(pos)) if pos else math.nan,
        "yaw_error_deg_median": float(np.median(yaw)) if yaw else math.nan,
        "yaw_error_deg_max": float(np.max(yaw)) if yaw else math.nan,
        "wall_ms_per_image_median": 1e3 * float(np.median(wall)) if wall else math.nan,
        "failures": failures,
    }


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Command line."""
    parser = CommandParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=20)
    parser.add_argument("--true-camera", action="store_true")
    parser.add_argument("--design", default="paper_mixed")
    parser.add_argument("--max-slots", type=int, default=0, help="first slots only (0: all)")
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "bench_perception.json")
    args = parser.parse_args(argv)
    r = bench(args.seeds, args.true_camera, args.design, args.max_slots)
    print(
        f"{r['design']} ({r['slots']} slots), {r['layouts']} layouts, {r['camera']} camera: "
        f"{r['assigned_to_own_class']}/{r['tiles']} tiles to a slot of their class; pick error "
        f"median {r['pick_error_mm_median']:.2f} mm, max {r['pick_error_mm_max']:.2f} mm; "
        f"place-yaw error median {r['yaw_error_deg_median']:.2f} deg, max "
        f"{r['yaw_error_deg_max']:.2f} deg; {r['wall_ms_per_image_median']:.0f} ms per image"
    )
    for f in r["failures"]:
        print("  " + f)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    write_text(args.out, json.dumps(r, indent=2))
    return r


if __name__ == "__main__":
    run_cli(main)
