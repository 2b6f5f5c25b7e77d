"""The scripted cell on the default design, end to end from camera images (interim main job).

Run ``python -m agents.main`` (options: ``--help``). The paper's loop ("The prototype", steps
1-7): describe the design's slots; take an input-camera picture; extract and describe the tiles;
assign them to open slots (optimal, colour-aware by default); pick each at its centroid (or the
pad's best point) and place it at its slot's centre, turned by the matched rotation, through the
planners' time-optimal cycles and the cell's servos; take a new picture; repeat until the design
is finished or nothing placeable remains. The cameras are calibrated from rendered checkerboard
images first (``agents.calibration``) and the estimated models are what perception uses.

Decisions use only images, the calibrated cameras and cell layout facts (belt top, mesh centre);
the cell's ground truth is read only to score the run. Writes, under ``out/``: ``report.json``,
``report.txt``, ``input_camera_annotated.png`` (recognised relevant points, centres and the
slot each tile goes to), ``output_camera_annotated.png`` (the empty mesh: relevant points the
output camera recognises, design slot centres projected through the calibrated camera),
``output_camera_final.png`` (the assembled mosaic) and ``cell.mp4`` (when the cycles run).
``tiles_per_min`` counts correctly placed tiles per simulated minute from the first picture to
the last release.

This is the interim driver over `envs.cell.Cell`; the final scripted agent drives the Gymnasium
env's ``pick_place`` action with the same perception and placement.
"""

from __future__ import annotations

import argparse
import json
import math
import shutil
import subprocess
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from agents.calibration import calibrate_cell_camera
from agents.cell_adapter import build_design_cell, yaw_error
from agents.config import AgentsConfig, RunConfig, load_agents_config
from agents.errors import AgentError
from agents.perception import (
    CameraLike,
    Perception,
    SlotTarget,
    balance_colors,
    perceive_tiles,
    project,
    slot_targets,
)
from agents.placement import PickPlace, PlacementPlan, plan_placements
from configs import ConfigError
from envs.cell import Cell
from qshape import QShapeError
from qshape.design import Design

ROOT = Path(__file__).resolve().parents[1]
CONTINUOUS_SYMMETRY_STEPS = 12
"""Equivalent yaws the planner may choose from for a circle or ring."""

# Drawing colours (BGR for OpenCV).
_CORNER = (0, 0, 255)
_CURVE = (255, 255, 0)
_OUTLINE = (255, 255, 255)
_CENTRE = (0, 255, 0)
_GRASP = (255, 0, 255)
_REJECT = (0, 165, 255)


@dataclass
class RunStats:
    """Counters of one run (mutable while running)."""

    pictures: int = 0
    cycles: int = 0
    grasped: int = 0
    not_planned: list[str] = field(default_factory=list)
    unplaced: list[dict[str, Any]] = field(default_factory=list)
    recognition: list[dict[str, Any]] = field(default_factory=list)
    unrecognised: list[str] = field(default_factory=list)


class VideoSink:
    """Collects overview frames at a fixed simulated frame rate and writes an MP4 with ffmpeg.

    Args:
        cell: The cell to render.
        cfg: Frame rate and size.
    """

    def __init__(self, cell: Cell, cfg: RunConfig) -> None:
        self.cell = cell
        self.period = 1.0 / cfg.video_fps
        self.size = cfg.video_size
        self.fps = cfg.video_fps
        self.next_t = cell.time
        self.frames: list[np.ndarray] = []

    def maybe_capture(self) -> None:
        """Render a frame if the simulated time reached the next frame's time."""
        if self.cell.time + 1e-9 >= self.next_t:
            h, w = self.size
            self.frames.append(self.cell.render("overview", h, w))
            self.next_t += self.period

    def write(self, path: Path) -> Path | None:
        """Encode the frames (ffmpeg H.264, else OpenCV mp4v); returns the file or None."""
        if not self.frames:
            return None
        h, w = self.size
        if shutil.which("ffmpeg"):
            cmd = [
                "ffmpeg", "-y", "-loglevel", "error", "-f", "rawvideo", "-pix_fmt", "rgb24",
                "-s", f"{w}x{h}", "-r", f"{self.fps:g}", "-i", "-", "-pix_fmt", "yuv420p",
                "-vcodec", "libx264", str(path),
            ]  # fmt: skip
            proc = subprocess.run(
                cmd, input=np.stack(self.frames).tobytes(), capture_output=True, check=False
            )
            if proc.returncode == 0:
                return path
        fourcc = cv2.VideoWriter_fourcc(*"mp4v")  # type: ignore[attr-defined]
        writer = cv2.VideoWriter(str(path), fourcc, self.fps, (w, h))
        for f in self.frames:
            writer.write(cv2.cvtColor(f, cv2.COLOR_RGB2BGR))
        writer.release()
        return path


class Executor:
    """Plans cycles with the planners and runs them through the cell's servos.

    Args:
        cell: The cell.
        video: Frame sink (or None).
    """

    def __init__(self, cell: Cell, video: VideoSink | None) -> None:
        from agents.bench_planner import CellRunner  # noqa: PLC0415 (mink/ruckig: heavy)
        from planners.config import load_planner_config  # noqa: PLC0415
        from planners.trajectory import JointState  # noqa: PLC0415

        self.cell = cell
        self.video = video
        self.runner = CellRunner(cell, load_planner_config(), dynamic=True)
        self.start = JointState.at_rest(cell.qpos)
        self._at_rest = JointState.at_rest
        self.at_contact = False
        self.last_release = cell.time

    def run(self, cmd: PickPlace, perceived: Perception, last: bool) -> bool:
        """Plan and execute one command; returns True when the pad sealed on a tile.

        Raises:
            planners.errors.PlannerError: No plan (unreachable, limits).
        """
        cell = self.cell
        tile = next(t for t in perceived.tiles if t.index == cmd.tile)
        pick = np.array([cmd.pick[0], cmd.pick[1], perceived.plane_z])
        place = np.array(
            [
                cmd.place[0],
                cmd.place[1],
                cell.geometry.mesh_top + perceived_thickness(perceived, cell),
            ]
        )
        order = CONTINUOUS_SYMMETRY_STEPS if cmd.symmetry == 0 else max(cmd.symmetry, 1)
        plan = self.runner.planner.plan_cycle(
            self.start,
            pick,
            place,
            cmd.rotation,
            symmetry_order=order,
            grasp_offset=tile.grasp - tile.centre,
            object_yaw=0.0,
            start_at_contact=self.at_contact,
            end_retreat=last,
        )
        cmds = self.runner.servo.commands(plan.trajectory, self.runner.dt)
        k_on = int(np.searchsorted(cmds.times, plan.vacuum_on - 1e-9))
        k_off = int(np.searchsorted(cmds.times, plan.vacuum_off - 1e-9))
        grasped = False
        for k in range(len(cmds.times)):
            if k == k_on:
                cell.vacuum(True)
            if k == k_off:
                grasped = cell.held_tile >= 0
                cell.vacuum(False)
                self.last_release = cell.time
            cell.set_servo(cmds.q[k], cmds.qd[k])
            cell.step(1)
            if self.video is not None:
                self.video.maybe_capture()
        self.start = self._at_rest(plan.end.q)
        self.at_contact = not last
        return grasped

    def settle(self, seconds: float) -> None:
        """Let simulated time pass with the arm holding still."""
        n = max(1, int(round(seconds / self.runner.dt)))
        for _ in range(n):
            self.cell.step(1)
            if self.video is not None:
                self.video.maybe_capture()


def perceived_thickness(perceived: Perception, cell: Cell) -> float:
    """Tile thickness the place height uses [m]: plane height minus the belt top."""
    return perceived.plane_z - cell.geometry.belt_top


def draw_perception(
    image: np.ndarray, perceived: Perception, plan: PlacementPlan | None, cfg: RunConfig
) -> np.ndarray:
    """The input-camera image (RGB) with outlines, relevant points, centres and labels drawn."""
    out = cv2.cvtColor(image, cv2.COLOR_RGB2BGR)
    names = {c.tile: c.slot_name for c in plan.commands} if plan else {}
    why = {u.tile: u.reason for u in plan.unplaced} if plan else {}
    r = cfg.marker_radius_px
    for t in perceived.tiles:
        _draw_figure(out, np.asarray(t.figure_px.points), np.asarray(t.figure_px.curve_mask), r)
        for h in t.figure_px.holes:
            _draw_figure(out, np.asarray(h.points), np.asarray(h.curve_mask), r)
        c = np.asarray(t.figure_px.centroid)
        cv2.drawMarker(out, _pt(c), _CENTRE, cv2.MARKER_CROSS, 4 * r, 1)
        label = names.get(t.index, "X " + why.get(t.index, "?"))
        cv2.putText(out, label, _pt(c + [-4 * r, -3 * r]), cv2.FONT_HERSHEY_SIMPLEX, 0.35,
                    _OUTLINE if t.index in names else _REJECT, 1, cv2.LINE_AA)  # fmt: skip
    return out


def draw_slots(
    image: np.ndarray, camera: CameraLike, slots: tuple[SlotTarget, ...], z: float, cfg: RunConfig
) -> np.ndarray:
    """The output-camera image with the design's slots projected (relevant points, centres)."""
    import qshape  # noqa: PLC0415

    out = cv2.cvtColor(image, cv2.COLOR_RGB2BGR)
    r = cfg.marker_radius_px
    res = qshape.extract_detailed(image)
    for f in res.figures:  # what the output camera recognises on the mesh
        _draw_figure(out, np.asarray(f.points), np.asarray(f.curve_mask), r)
        for h in f.holes:
            _draw_figure(out, np.asarray(h.points), np.asarray(h.curve_mask), r)
    for s in slots:
        centre = project(camera, np.array([[s.pose[0], s.pose[1], z]]))[0]
        cv2.drawMarker(out, _pt(centre), _CENTRE, cv2.MARKER_CROSS, 4 * r, 1)
        cv2.putText(out, s.name, _pt(centre + [-6 * r, 4 * r]), cv2.FONT_HERSHEY_SIMPLEX, 0.3,
                    _OUTLINE, 1, cv2.LINE_AA)  # fmt: skip
    return out


def _pt(p: np.ndarray) -> tuple[int, int]:
    return int(round(float(p[0]))), int(round(float(p[1])))


def _draw_figure(out: np.ndarray, pts: np.ndarray, mask: np.ndarray, r: int) -> None:
    from qshape.figure import densify  # noqa: PLC0415

    dense = densify(np.asarray(pts, dtype=float), np.asarray(mask, dtype=bool))
    cv2.polylines(out, [np.round(dense).astype(np.int32)], True, _OUTLINE, 1, cv2.LINE_AA)
    for p, is_curve in zip(pts, mask, strict=True):
        cv2.circle(out, _pt(p), r, _CURVE if is_curve else _CORNER, -1, cv2.LINE_AA)


def score(cell: Cell, design: Design, cfg: RunConfig) -> dict[str, Any]:
    """Ground-truth scoring (report only): correct, misplaced, dropped per slot and tile."""
    poses = cell.tile_poses()
    slots = cell.slot_poses_world()
    keys = [s.class_key for s in design.slots]
    on_mesh = np.abs(poses.pos[:, 1] - cell.geometry.output_centre[1]) < max(
        cell.cfg.output_belt.mesh_size
    )
    correct_slots: set[int] = set()
    correct_tiles: set[int] = set()
    yaw_tol = math.radians(cfg.yaw_tolerance_deg)
    for j, (sx, sy, syaw) in enumerate(slots):
        d = np.hypot(poses.pos[:, 0] - sx, poses.pos[:, 1] - sy)
        for i in np.flatnonzero(d < cfg.position_tolerance).tolist():
            t = cell.tiles[i]
            if t.shape.name == keys[j] and not t.distractor:
                if yaw_error(poses.yaw[i], syaw, t.shape.symmetry) < yaw_tol:
                    correct_slots.add(j)
                    correct_tiles.add(i)
    moved = set(np.flatnonzero(on_mesh).tolist())
    return {
        "correct": len(correct_slots),
        "misplaced": len(moved - correct_tiles),
        "dropped": int(cell.n_dropped),
        "lost": int(cell.n_lost),
    }


def run(cfg: AgentsConfig, out_dir: Path, quiet: bool = False) -> dict[str, Any]:
    """Run the scripted cell once and write the report and images.

    Raises:
        AgentError: The design does not fit the belt, or calibration failed.
    """
    from tqdm import tqdm  # noqa: PLC0415

    rc = cfg.run
    t_wall = time.perf_counter()
    out_dir.mkdir(parents=True, exist_ok=True)
    design = Design.load(rc.design)
    cell, seed = build_design_cell(design, seed=rc.seed, tries=rc.layout_seed_tries)
    bar = tqdm(total=len(design.slots), desc="tiles placed", unit="tile", disable=quiet)
    try:
        report: dict[str, Any] = {"design": design.name, "layout_seed": seed}
        cams: dict[str, CameraLike] = {}
        for name in ("input_camera", "output_camera"):
            if rc.calibrate:
                bar.set_postfix_str(f"calibrating {name}")
                cal = calibrate_cell_camera(cell.cfg, name, cfg.calibration)
                cams[name] = cal.camera
                report[f"calibration_{name}"] = cal.summary()
            else:
                cams[name] = cell.camera_model(name)
        bar.set_postfix_str("picking and placing")
        slots = slot_targets(design, cell.geometry.output_centre[:2])
        palette = np.array([s.color for s in slots])
        video = VideoSink(cell, rc) if rc.execute else None
        executor = Executor(cell, video) if rc.execute else None
        if executor is not None:
            executor.settle(rc.settle_s)
        else:
            cell.step(max(1, int(round(rc.settle_s / cell.model.opt.timestep))))
        stats = RunStats()
        output_before = cell.render("output_camera")
        open_slots = list(slots)
        t_sim0 = cell.time
        first: tuple[np.ndarray, Perception, PlacementPlan] | None = None
        while open_slots:
            image = cell.render("input_camera")
            perceived = perceive_tiles(
                image, cams["input_camera"], cell.geometry.belt_top, cfg=cfg.perception
            )
            if cfg.perception.color_balance:
                perceived, gain = balance_colors(perceived, palette, cfg.perception)
                report["color_gain"] = gain.round(4).tolist()
            plan = plan_placements(perceived.tiles, open_slots, cfg.placement)
            stats.pictures += 1
            if first is None:
                first = (image, perceived, plan)
                stats.recognition = recognition(cell, perceived, plan, design)
            stats.unplaced = [asdict(u) for u in plan.unplaced]
            stats.unrecognised = list(perceived.unrecognised)
            if executor is None:  # vision only: the slots no tile was assigned to stay open
                open_slots = [s for s in open_slots if s.index in plan.open_slots]
                break
            if not plan.commands:
                break
            filled: set[int] = set()
            for k, c in enumerate(plan.commands):
                last = k == len(plan.commands) - 1 and len(plan.commands) == len(open_slots)
                try:
                    ok = executor.run(c, perceived, last)
                except Exception as exc:  # PlannerError and its kinds: report, go on
                    stats.not_planned.append(f"{c.slot_name}: {type(exc).__name__}: {exc}")
                    continue
                stats.cycles += 1
                stats.grasped += int(ok)
                filled.add(c.slot)
                bar.update(1)
            if not filled:
                break
            open_slots = [s for s in open_slots if s.index not in filled]
        sim_total = cell.time - t_sim0
        sim_s = executor.last_release - t_sim0 if executor is not None else 0.0
        if executor is not None:
            executor.settle(rc.settle_s)
        scored = score(cell, design, rc)
        img_in, per_in, plan_in = first if first is not None else (None, None, None)
        if img_in is not None and per_in is not None:
            cv2.imwrite(
                str(out_dir / "input_camera_annotated.png"),
                draw_perception(img_in, per_in, plan_in, rc),
            )
        cv2.imwrite(
            str(out_dir / "output_camera_annotated.png"),
            draw_slots(
                output_before, cams["output_camera"], tuple(slots), cell.geometry.mesh_top, rc
            ),
        )
        cell.set_qpos(np.asarray(cell.cfg.robot.home))  # out of the view, for the picture only
        cv2.imwrite(
            str(out_dir / "output_camera_final.png"),
            cv2.cvtColor(cell.render("output_camera"), cv2.COLOR_RGB2BGR),
        )
        video_path = video.write(out_dir / "cell.mp4") if video is not None else None
        n = len(design.slots)
        rec_ok = sum(1 for r in stats.recognition if r["class_ok"])
        report.update(
            {
                "tiles_total": n,
                "correct": scored["correct"],
                "misplaced": scored["misplaced"],
                "dropped": scored["dropped"],
                "lost": scored["lost"],
                "success": scored["correct"] == n,
                "tiles_per_min": 60.0 * scored["correct"] / sim_s if sim_s > 0 else 0.0,
                "sim_s": sim_s,
                "sim_s_with_final_retreat": sim_total,
                "wall_s": time.perf_counter() - t_wall,
                "executed": executor is not None,
                "pictures": stats.pictures,
                "cycles": stats.cycles,
                "grasped": stats.grasped,
                "recognised_tiles": len(stats.recognition),
                "recognised_correct_class": rec_ok,
                "recognition_accuracy": rec_ok / n if n else 0.0,
                "pick_error_max_mm": max(
                    (r["pick_error_mm"] for r in stats.recognition), default=math.nan
                ),
                "yaw_error_max_deg": max(
                    (r["yaw_error_deg"] for r in stats.recognition), default=math.nan
                ),
                "unplaced": stats.unplaced,
                "unrecognised": stats.unrecognised,
                "open_slots": [s.name for s in open_slots],
                "not_planned": stats.not_planned,
                "placement": asdict(cfg.placement),
                "video": str(video_path) if video_path else None,
                "per_tile": stats.recognition,
            }
        )
        (out_dir / "report.json").write_text(json.dumps(report, indent=2, default=float))
        (out_dir / "report.txt").write_text(report_text(report))
        return report
    finally:
        bar.close()
        cell.close()


def recognition(
    cell: Cell, perceived: Perception, plan: PlacementPlan, design: Design
) -> list[dict[str, Any]]:
    """Per command of the first picture: class right?, pick and yaw errors (ground truth)."""
    from agents.cell_adapter import nearest_tile  # noqa: PLC0415

    poses = cell.tile_poses()
    rows = []
    for c in plan.commands:
        i, d = nearest_tile(cell, np.array(c.pick[:2]))
        t = cell.tiles[i]
        rows.append(
            {
                "slot": c.slot_name,
                "tile": i,
                "class_ok": t.shape.name == design.slots[c.slot].class_key,
                "pick_error_mm": 1e3 * d,
                "yaw_error_deg": math.degrees(
                    yaw_error(poses.yaw[i] + c.rotation, c.place[2], t.shape.symmetry)
                ),
            }
        )
    _ = perceived
    return rows


def report_text(r: dict[str, Any]) -> str:
    """Plain-text summary of a report."""
    lines = [
        f"design {r['design']} (layout seed {r['layout_seed']}), placement {r['placement']}",
        f"tiles {r['tiles_total']}: correct {r['correct']}, misplaced {r['misplaced']}, "
        f"dropped {r['dropped']}, lost {r['lost']}, success {r['success']}",
        f"tiles/min (simulated) {r['tiles_per_min']:.1f} over {r['sim_s']:.1f} s simulated; "
        f"wall {r['wall_s']:.1f} s; pictures {r['pictures']}, cycles {r['cycles']}",
        f"recognition: {r['recognised_correct_class']}/{r['tiles_total']} tiles to a slot of "
        f"their class; pick error max {r['pick_error_max_mm']:.2f} mm; place-yaw error max "
        f"{r['yaw_error_max_deg']:.2f} deg",
    ]
    for name in ("input_camera", "output_camera"):
        c = r.get(f"calibration_{name}")
        if c:
            lines.append(
                f"calibration {name}: reprojection {c['reprojection_px']:.3f} px, focal "
                f"{c['focal_error_pct']:+.3f} %, principal point "
                f"{c['principal_point_error_px']:.2f} px, position "
                f"{c['position_error_mm']:.2f} mm, angle {c['angle_error_deg']:.3f} deg"
            )
    for u in r["unplaced"]:
        lines.append(f"not placed: tile {u['tile']}: {u['detail']}")
    for msg in r.get("unrecognised", []):
        lines.append(f"not recognised: {msg}")
    if r.get("open_slots"):
        lines.append(f"slots left open: {', '.join(r['open_slots'])}")
    for s in r["not_planned"]:
        lines.append(f"not planned: {s}")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Command line: run the scripted cell and print the report."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", default="agents", help="bundled name or YAML path")
    parser.add_argument("--design", help="design name or path (default: config)")
    parser.add_argument("--seed", type=int, help="layout seed (default: config)")
    parser.add_argument("--greedy", action="store_true", help="the paper's greedy assignment")
    parser.add_argument("--shape-only", action="store_true", help="ignore colour")
    parser.add_argument("--no-execute", action="store_true", help="vision and planning only")
    parser.add_argument("--true-camera", action="store_true", help="skip calibration")
    parser.add_argument("--out", type=Path, help="output folder (default: config)")
    parser.add_argument("--quiet", action="store_true")
    args = parser.parse_args(argv)
    cfg = load_agents_config(args.config)
    run_over: dict[str, Any] = {}
    if args.design:
        run_over["design"] = args.design
    if args.seed is not None:
        run_over["seed"] = args.seed
    if args.no_execute:
        run_over["execute"] = False
    if args.true_camera:
        run_over["calibrate"] = False
    place_over: dict[str, Any] = {}
    if args.greedy:
        place_over["method"] = "greedy"
    if args.shape_only:
        place_over["use_color"] = False
    from dataclasses import replace  # noqa: PLC0415

    cfg = replace(
        cfg,
        run=replace(cfg.run, **run_over),
        placement=replace(cfg.placement, **place_over),
    )
    out = args.out or Path(cfg.run.out_dir)
    out = out if out.is_absolute() else ROOT / out
    try:
        report = run(cfg, out, quiet=args.quiet)
    except (AgentError, QShapeError, ConfigError) as exc:
        raise SystemExit(f"error: {exc}") from exc
    print(report_text(report), end="")
    print(f"wrote {out / 'report.json'}")
    return report


if __name__ == "__main__":
    main()
