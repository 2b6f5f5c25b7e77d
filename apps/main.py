"""The main job: the scripted cell on a design, end to end from camera images, with its video.

Run ``python -m apps.main`` (options: ``--help``). The paper's loop ("The prototype", steps
1-7) through the Gymnasium env's public API: `MosaicAssembly-v1` in ``pick_place`` action mode
with full-resolution camera images, driven by `agents.scripted.agent.ScriptedAgent` (describe the
design's slots; take an input-camera picture; extract and describe the tiles; assign them to
open slots, optimal and colour-aware by default; map centroid and rotation to the world through
the calibrated camera; one ``pick_place`` step per tile; a new picture; until the design is
finished or nothing placeable remains). The cameras are calibrated from rendered checkerboard
images first (``agents.scripted.calibration``).

Decisions use only the observation images, the calibrated camera and the env's task
description (``task_spec``: slots in the world, areas, the action codec); the env's evaluation
scores the run, and its privileged ``ground_truth()`` is read only for the recognition figures
of the report. Every env access goes through Gymnasium's public API (``get_wrapper_attr``); the
arm goes home for the final picture with a planned move (``move_home``). Writes, under ``out/``:
``report.json`` and ``report.txt``; ``cell.mp4``: the cell overview beside the two camera
views, the input view with the recognised relevant points (corners red, curve points cyan),
centres and target slots of the latest picture, the output view with the design's slots
projected through the calibrated camera (open white, filled green, the current target magenta);
``input_camera_annotated.png`` and ``output_camera_annotated.png`` (the first picture and the
empty mesh at full resolution) and ``output_camera_final.png`` (the assembled mosaic).
``tiles_per_min`` counts correctly placed tiles per simulated minute of the episode
(`envs.task.Evaluation.tiles_per_min`, no horizon: the run is one episode to its end).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import cv2
import gymnasium as gym
import numpy as np

from agents.policies import parse_pairs
from agents.scripted.agent import ScriptedAgent
from agents.scripted.calibration import calibrate_env_camera
from agents.scripted.config import AgentsConfig, RunConfig, load_agents_config
from agents.scripted.perception import PerceivedTile, Perception
from agents.scripted.placement import PlacementPlan
from apps.cli import CommandParser, run_cli
from apps.main_pictures import CellVideo, draw_perception, draw_slots
from apps.main_report import RecognitionRow, RunReport, recognition, report_text
from configs.files import write_image, write_json, write_text
from envs.cell.accounting import TILE_STATES
from envs.cell.cameras import CameraModel
from envs.env_config import FEEDS
from envs.episode_setup import with_feed_fallback
from envs.task import Evaluation
from envs.task_spec import FeedMode, TaskSpec

ROOT = Path(__file__).resolve().parents[1]
ENV_ID = "envs:MosaicAssembly-v1"
"""Gymnasium id of the environment."""


# ------------------------------------------------------------------------------ the run
def make_env(
    rc: RunConfig, env_config: str | None = None, env_over: dict[str, Any] | None = None
) -> gym.Env[Any, Any]:
    """The env of the main job: ``pick_place``, full-resolution images, ``rgb_array`` frames.

    With the ``all`` feed, tiles that do not fit the input belt at once (many distractors)
    are fed in batches instead (the env's ``batch`` feed); the report names the feed used.
    ``env_config`` (an env YAML, bundled name or path; None: ``configs/env.yaml``) and
    ``env_over`` (env keys, e.g. ``{"cell": {"config": "my_cell.yaml"}}``) give the env and
    its cell; the run's own keys (design, feed, belt speed, ...) are set over them.

    Raises:
        QShapeError: The design does not load or validate.
        CellError: The design's tiles do not fit the input belt.
        ConfigError: A bad env setting.
    """
    from envs.env_config import load_env_config  # noqa: PLC0415

    cam = load_env_config(env_config or "env", **(env_over or {})).cell.input_camera
    over: dict[str, Any] = {
        "design": rc.design,
        "action_mode": "pick_place",
        "obs_mode": "rgb",
        "image_size": (cam.height, cam.width),
        "belt_speed": rc.belt_speed,
        "feed": rc.feed,
        "distractor_rate": rc.distractor_rate,
        "max_slots": rc.max_slots,
        # The height picture (agents.scripted.height): tiles of the belt's colour are seen too.
        "depth": True,
    }

    def make(feed: FeedMode) -> gym.Env[Any, Any]:
        kw = {**(env_over or {}), **over, "feed": feed}
        if env_config is not None:
            kw["config"] = env_config
        return gym.make(ENV_ID, max_episode_steps=None, render_mode="rgb_array", **kw)

    return with_feed_fallback(make, rc.feed)[0]


@dataclass
class _Episode:
    """What the main job's loop saw, for the report (counts, messages, the first picture)."""

    feed: FeedMode
    info: dict[str, Any] = field(default_factory=dict)
    first: tuple[np.ndarray, Perception, PlacementPlan] | None = None
    rec: list[RecognitionRow] = field(default_factory=list)
    steps: int = 0
    failed: int = 0
    waits: int = 0
    rejects: list[str] = field(default_factory=list)
    failures: list[str] = field(default_factory=list)


def run(
    cfg: AgentsConfig,
    out_dir: Path,
    quiet: bool = False,
    env_config: str | None = None,
    env_over: dict[str, Any] | None = None,
) -> RunReport:
    """Run the scripted cell for one episode and write the report, images and video.

    ``env_config`` and ``env_over`` give the env and its cell (`make_env`).

    Raises:
        AgentError: Calibration failed.
        QShapeError: The design does not load or validate.
        CellError: The design's tiles do not fit the input belt.
    """
    from tqdm import tqdm  # noqa: PLC0415

    rc = cfg.run
    t_wall = time.perf_counter()
    out_dir.mkdir(parents=True, exist_ok=True)
    env = make_env(rc, env_config, env_over)
    spec: TaskSpec = env.get_wrapper_attr("task_spec")
    bar = tqdm(total=len(spec.slots), desc="tiles placed", unit="tile", disable=quiet)
    try:
        bar.set_postfix_str("calibrating the cameras")
        agent = ScriptedAgent.from_env(env, cfg, calibrate=rc.calibrate)
        cal_in = cal_out = None
        if agent.calibration is not None:
            cal_in = agent.calibration.summary()
            out_cal = calibrate_env_camera(env, "output_camera", cfg.calibration)
            out_cam: CameraModel = out_cal.camera
            cal_out = out_cal.summary()
        else:
            out_cam = spec.camera("output_camera")
        video = CellVideo(env, agent, out_cam, rc, cfg.perception.mm_per_m) if rc.execute else None
        obs, info = env.reset(seed=rc.seed)
        output_before = obs["output_camera"]
        if video is not None:
            env.get_wrapper_attr("add_frame_listener")(video.capture, rc.video_fps)
            video.capture()
        bar.set_postfix_str("picking and placing")
        ep = _play(env, agent, spec, rc, obs, info, bar)
        _write_pictures(env, agent, spec, cfg, out_dir, ep, output_before, out_cam)
        video_path = video.write(out_dir / "cell.mp4") if video is not None else None
        report = _report(
            agent, spec, cfg, ep, time.perf_counter() - t_wall, video_path, (cal_in, cal_out)
        )
        write_json(out_dir / "report.json", report.as_dict(), default=float)
        write_text(out_dir / "report.txt", report_text(report))
        return report
    finally:
        bar.close()
        env.close()


def _play(  # noqa: PLR0913, PLR0917
    env: gym.Env[Any, Any],
    agent: ScriptedAgent,
    spec: TaskSpec,
    rc: RunConfig,
    obs: dict[str, np.ndarray],
    info: dict[str, Any],
    bar: Any,
) -> _Episode:
    """The episode's loop: one pick-and-place (or wait, or reject) per step."""
    ep = _Episode(feed=env.get_wrapper_attr("config").cell.tiles.feed, info=info)
    idle = 0
    limit = rc.max_steps_per_slot * max(1, len(spec.slots))
    while ep.steps < limit:
        action, _ = agent.predict(obs)
        if ep.first is None and agent.last_perception is not None and agent.last_plan:
            ep.first = (obs["input_camera"], agent.last_perception, agent.last_plan)
            ep.rec = recognition(env.get_wrapper_attr("ground_truth")(), agent)
        if not rc.execute:
            break  # vision only
        if agent.last_command is None:
            # Nothing to place in this picture: an empty belt before the next streamed
            # tile, or a picture not usable. Wait one cycle and look again; the env ends
            # the episode once nothing placeable is left.
            idle += 1
            if idle > rc.max_idle_steps:
                break
        else:
            idle = 0
        stuck = _tile_to_reject(agent, ep.feed, idle, rc.reject_after_idle)
        if stuck is not None:
            obs, _, terminated, truncated, ep.info = env.get_wrapper_attr("reject")(stuck.grasp)
            ep.rejects.append(
                f"tile at ({stuck.centre[0]:.3f}, {stuck.centre[1]:.3f}) m: "
                + ("rejected" if not ep.info["action_failed"] else ep.info["action_error"])
            )
            idle = 0
            if terminated or truncated:
                break
            continue
        obs, _, terminated, truncated, ep.info = env.step(action)
        if agent.last_command is None:
            ep.waits += 1
            if terminated or truncated:
                break
            continue
        ep.steps += 1
        if ep.info["action_failed"]:
            ep.failed += 1
            ep.failures.append(f"{agent.last_command.slot_name}: {ep.info['action_error']}")
        bar.update(ep.info["tiles_placed"] - bar.n)
        if terminated or truncated:
            break
    return ep


def _write_pictures(  # noqa: PLR0913, PLR0917
    env: gym.Env[Any, Any],
    agent: ScriptedAgent,
    spec: TaskSpec,
    cfg: AgentsConfig,
    out_dir: Path,
    ep: _Episode,
    output_before: np.ndarray,
    out_cam: CameraModel,
) -> None:
    """The annotated first pictures of both cameras and the assembled mosaic."""
    rc = cfg.run
    if ep.first is not None:
        write_image(out_dir / "input_camera_annotated.png", draw_perception(*ep.first, rc))
    write_image(
        out_dir / "output_camera_annotated.png",
        draw_slots(
            output_before,
            out_cam,
            agent.slots,
            spec.place.surface_z,
            rc,
            recognise=True,
            mm_per_m=cfg.perception.mm_per_m,
        ),
    )
    home_obs = env.get_wrapper_attr("move_home")()  # the arm out of the view
    write_image(
        out_dir / "output_camera_final.png",
        cv2.cvtColor(home_obs["output_camera"], cv2.COLOR_RGB2BGR),
    )


def _report(  # noqa: PLR0913, PLR0917
    agent: ScriptedAgent,
    spec: TaskSpec,
    cfg: AgentsConfig,
    ep: _Episode,
    wall_s: float,
    video_path: Path | None,
    calibrations: tuple[dict[str, float | int] | None, dict[str, float | int] | None],
) -> RunReport:
    """The run's report from the episode's last evaluation (`Evaluation.from_info`)."""
    rc = cfg.run
    evaluation = Evaluation.from_info(ep.info)
    sim_s = float(ep.info["sim_time"])
    n = evaluation.slots
    rec = ep.rec
    rec_ok = sum(1 for r in rec if r.class_ok)
    last = agent.last_perception
    return RunReport(
        design=spec.design,
        seed=rc.seed,
        tiles_total=n,
        correct=evaluation.correct,
        misplaced=evaluation.misplaced,
        dropped=evaluation.dropped,
        lost=evaluation.lost,
        distractors_placed=evaluation.distractors_placed,
        success=evaluation.success,
        tiles_per_min=evaluation.tiles_per_min(sim_s),
        sim_s=sim_s,
        wall_s=wall_s,
        executed=rc.execute,
        belt_speed=rc.belt_speed,
        feed=ep.feed,
        steps=ep.steps,
        waits=ep.waits,
        rejects=tuple(ep.rejects),
        tile_states={s: int(getattr(evaluation, s)) for s in TILE_STATES},
        failed_actions=ep.failed,
        failures=tuple(ep.failures),
        pictures=agent.pictures,
        position_error_mm_max=evaluation.position_error_mm_max,
        yaw_error_deg_max=evaluation.yaw_error_deg_max,
        recognition=tuple(rec),
        recognised_tiles=len(rec),
        recognised_correct_class=rec_ok,
        recognition_accuracy=rec_ok / n if n else 0.0,
        pick_error_max_mm=max((r.pick_error_mm for r in rec), default=math.nan),
        yaw_error_max_deg=max((r.yaw_error_deg for r in rec), default=math.nan),
        unplaced=agent.unplaced,
        unrecognised=last.unrecognised if last else (),
        open_slots=tuple(
            s.name for s, ok in zip(agent.slots, evaluation.slot_filled, strict=True) if not ok
        ),
        placement=cfg.placement,
        video=str(video_path) if video_path else None,
        calibration_input_camera=calibrations[0],
        calibration_output_camera=calibrations[1],
    )


def _tile_to_reject(agent: ScriptedAgent, feed: str, idle: int, after: int) -> PerceivedTile | None:
    """The tile to put into the reject bin now, or None.

    With the batch feed, after ``after`` waits in a row: the most downstream tile of the last
    picture that fits no open slot (it would hold the next batch back).
    """
    per, plan = agent.last_perception, agent.last_plan
    if feed != "batch" or after <= 0 or idle < after or per is None or plan is None:
        return None
    by_index = {t.index: t for t in per.tiles}
    unusable = [by_index[u.tile] for u in plan.unplaced if u.reason != "slots_taken"]
    return max(unusable, key=lambda t: float(t.centre[0]), default=None)


def main(argv: list[str] | None = None) -> dict[str, object]:
    """Command line: run the scripted cell and print the report; returns ``report.json``'s dict."""
    parser = CommandParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", default="agents", help="bundled name or YAML path")
    parser.add_argument(
        "--design", help="design name or file: .yaml, .svg or .dxf (default: config)"
    )
    parser.add_argument(
        "--env-config", help="env YAML, bundled name or path (default: env); its cell: the cell"
    )
    parser.add_argument(
        "--env",
        nargs="*",
        default=[],
        metavar="KEY=VALUE",
        help="env overrides, e.g. cell='{config: my_cell.yaml}' or belt_speed=0.1",
    )
    parser.add_argument("--seed", type=int, help="episode seed (default: config)")
    parser.add_argument("--belt-speed", type=float, help="input belt speed [m/s]")
    parser.add_argument("--feed", choices=FEEDS, help="tile feed")
    parser.add_argument("--distractor-rate", type=float, help="distractor tiles per real tile")
    parser.add_argument("--max-slots", type=int, help="first k slots of the design only")
    parser.add_argument("--greedy", action="store_true", help="the paper's greedy assignment")
    parser.add_argument("--shape-only", action="store_true", help="ignore colour")
    parser.add_argument("--no-execute", action="store_true", help="vision and planning only")
    parser.add_argument("--true-camera", action="store_true", help="skip calibration")
    parser.add_argument("--out", type=Path, help="output folder (default: config)")
    parser.add_argument("--quiet", action="store_true")
    args = parser.parse_args(argv)
    cfg = load_agents_config(args.config)
    run_over: dict[str, Any] = {
        k: v
        for k, v in (
            ("design", args.design),
            ("seed", args.seed),
            ("belt_speed", args.belt_speed),
            ("feed", args.feed),
            ("distractor_rate", args.distractor_rate),
            ("max_slots", args.max_slots),
        )
        if v is not None
    }
    if args.no_execute:
        run_over["execute"] = False
    if args.true_camera:
        run_over["calibrate"] = False
    place_over: dict[str, Any] = {}
    if args.greedy:
        place_over["method"] = "greedy"
    if args.shape_only:
        place_over["use_color"] = False
    cfg = replace(
        cfg,
        run=replace(cfg.run, **run_over),
        placement=replace(cfg.placement, **place_over),
    )
    out = args.out or Path(cfg.run.out_dir)
    out = out if out.is_absolute() else ROOT / out
    report = run(
        cfg, out, quiet=args.quiet, env_config=args.env_config, env_over=parse_pairs(args.env)
    )
    print(report_text(report), end="")
    print(f"wrote {out / 'report.json'}")
    return report.as_dict()


if __name__ == "__main__":
    run_cli(main)
