"""The main job: the scripted cell on a design, end to end from camera images, with its video.

Run ``python -m apps.main`` (options: ``--help``). The paper's loop ("The prototype", steps
1-7) through the Gymnasium env's public API: `MosaicAssembly-v0` in ``pick_place`` action mode
with full-resolution camera images, driven by `agents.scripted.ScriptedAgent` (describe the
design's slots; take an input-camera picture; extract and describe the tiles; assign them to
open slots, optimal and colour-aware by default; map centroid and rotation to the world through
the calibrated camera; one ``pick_place`` step per tile; a new picture; until the design is
finished or nothing placeable remains). The cameras are calibrated from rendered checkerboard
images first (``agents.calibration``).

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
import shutil
import subprocess
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

import cv2
import gymnasium as gym
import numpy as np

from agents.calibration import calibrate_env_camera
from agents.config import AgentsConfig, PlacementConfig, RunConfig, load_agents_config
from agents.perception import PerceivedTile, Perception, SlotTarget
from agents.placement import PlacementPlan, Unplaced
from agents.scripted import ScriptedAgent
from apps.cli import CommandParser, run_cli
from configs.files import atomic_path, write_image, write_json, write_text
from envs.cell.accounting import TILE_STATES
from envs.cell.cameras import CameraModel
from envs.env_config import FEEDS
from envs.episode_setup import with_feed_fallback
from envs.task import Evaluation, GroundTruth
from envs.task_spec import FeedMode, TaskSpec
from spatial.angles import yaw_error
from spatial.units import MM_PER_M

ROOT = Path(__file__).resolve().parents[1]
ENV_ID = "envs:MosaicAssembly-v0"
"""Gymnasium id of the environment."""

# Drawing colours (BGR for OpenCV).
_CORNER = (0, 0, 255)
_CURVE = (255, 255, 0)
_OUTLINE = (255, 255, 255)
_CENTRE = (0, 255, 0)
_TARGET = (255, 0, 255)
_REJECT = (0, 165, 255)
_FILLED = (0, 200, 0)


# ------------------------------------------------------------------------------ report
@dataclass(frozen=True)
class RecognitionRow:
    """One command of the first picture, scored against the ground truth (report only).

    Attributes:
        slot: Target slot name.
        tile: Index of the real tile nearest to the pick point.
        class_ok: That tile belongs in that slot (shape and colour class, not a distractor).
        pick_error_mm: Pick point to that tile's centroid [mm].
        yaw_error_deg: Place yaw error modulo the tile's symmetry [deg].
    """

    slot: str
    tile: int
    class_ok: bool
    pick_error_mm: float
    yaw_error_deg: float


@dataclass(frozen=True)
class RunReport:
    """What one run of the main job did (``report.json`` is `as_dict`).

    Attributes:
        design: Design name or path.
        seed: Episode seed.
        tiles_total: Slots of the design (as run).
        correct: Slots filled correctly.
        misplaced: Real tiles on the mesh filling no slot.
        dropped: Tiles the pad lost in transit.
        lost: Tiles lost off the input belt.
        distractors_placed: Distractors put on the mesh.
        success: Every slot filled correctly.
        tiles_per_min: Correct tiles per simulated minute.
        sim_s: Simulated time of the episode [s].
        wall_s: Wall-clock time of the run [s] (calibration, video and writing included).
        executed: Commands were executed (False: vision and planning only).
        belt_speed: Input belt speed [m/s].
        feed: Tile feed.
        steps: Pick-and-place steps taken.
        waits: Waiting steps taken (nothing to place in the picture; a new one follows).
        rejects: Tiles put into the reject bin (position and outcome).
        tile_states: Where the real tiles fed ended, per state (`envs.cell.accounting`; the
            counts sum to the tiles fed).
        failed_actions: Steps whose action failed.
        failures: Slot name and reason of each failed action.
        pictures: Input-camera pictures perceived.
        position_error_mm_max: Largest placement error of the tiles on the mesh [mm].
        yaw_error_deg_max: Largest placement yaw error [deg].
        recognition: The first picture's commands, scored.
        recognised_tiles: Commands of the first picture.
        recognised_correct_class: Of those, tiles sent to a slot of their class.
        recognition_accuracy: ``recognised_correct_class / tiles_total``.
        pick_error_max_mm: Largest pick error of the first picture [mm] (NaN: none).
        yaw_error_max_deg: Largest place-yaw error of the first picture [deg] (NaN: none).
        unplaced: Tiles the agent left out, and why.
        unrecognised: Regions of the last picture not made into tiles.
        open_slots: Slots not filled correctly at the end.
        placement: The placement settings used.
        video: Path of the video, if written.
        calibration_input_camera: Calibration figures of the input camera (None: not run).
        calibration_output_camera: Calibration figures of the output camera.
    """

    design: str
    seed: int
    tiles_total: int
    correct: int
    misplaced: int
    dropped: int
    lost: int
    distractors_placed: int
    success: bool
    tiles_per_min: float
    sim_s: float
    wall_s: float
    executed: bool
    belt_speed: float
    feed: FeedMode
    steps: int
    waits: int
    rejects: tuple[str, ...]
    tile_states: dict[str, int]
    failed_actions: int
    failures: tuple[str, ...]
    pictures: int
    position_error_mm_max: float | None
    yaw_error_deg_max: float | None
    recognition: tuple[RecognitionRow, ...]
    recognised_tiles: int
    recognised_correct_class: int
    recognition_accuracy: float
    pick_error_max_mm: float
    yaw_error_max_deg: float
    unplaced: tuple[Unplaced, ...]
    unrecognised: tuple[str, ...]
    open_slots: tuple[str, ...]
    placement: PlacementConfig
    video: str | None
    calibration_input_camera: dict[str, float | int] | None = None
    calibration_output_camera: dict[str, float | int] | None = None

    def as_dict(self) -> dict[str, object]:
        """JSON-ready dict (tuples as lists, nested values as dicts)."""
        return asdict(self)


# ------------------------------------------------------------------------------ drawing
def draw_perception(
    image: np.ndarray,
    perceived: Perception,
    plan: PlacementPlan | None,
    cfg: RunConfig,
    *,
    scale: float = 1.0,
    target_tile: int | None = None,
) -> np.ndarray:
    """An input-camera image (RGB) with outlines, relevant points, centres and labels drawn.

    Args:
        image: RGB image, (h, w, 3) uint8.
        perceived: What the agent perceived, in the pixels of the image it saw.
        plan: Its assignment (labels: the target slot, or X and the reason).
        cfg: Marker size.
        scale: ``image`` pixels per pixel of the perceived image.
        target_tile: Tile being moved now (drawn in magenta).

    Returns:
        The annotated image, BGR uint8.
    """
    out = cv2.cvtColor(image, cv2.COLOR_RGB2BGR)
    names = {c.tile: c.slot_name for c in plan.commands} if plan else {}
    why = {u.tile: u.reason for u in plan.unplaced} if plan else {}
    r = max(1, round(cfg.marker_radius_px * min(1.0, 2 * scale)))
    font = 0.35 * min(1.0, 2 * scale)
    for t in perceived.tiles:
        colour = _TARGET if t.index == target_tile else _OUTLINE
        fig = t.figure_px
        _draw_figure(out, fig.points, fig.curve_mask, r, scale=scale, colour=colour)
        for h in fig.holes:
            _draw_figure(out, h.points, h.curve_mask, r, scale=scale, colour=colour)
        c = scale * np.asarray(fig.centroid)
        cv2.drawMarker(out, _pt(c), _CENTRE, cv2.MARKER_CROSS, 4 * r, 1)
        label = names.get(t.index, "X " + why.get(t.index, "?"))
        cv2.putText(out, label, _pt(c + [-4 * r, -3 * r]), cv2.FONT_HERSHEY_SIMPLEX, font,
                    _OUTLINE if t.index in names else _REJECT, 1, cv2.LINE_AA)  # fmt: skip
    return out


def draw_slots(
    image: np.ndarray,
    camera: CameraModel,
    slots: Sequence[SlotTarget],
    z: float,
    cfg: RunConfig,
    *,
    filled: set[int] | None = None,
    target: int | None = None,
    scale: float = 1.0,
    recognise: bool = False,
    mm_per_m: float = MM_PER_M,
) -> np.ndarray:
    """An output-camera image with the design's slots projected through ``camera``.

    Args:
        image: RGB image, (h, w, 3) uint8.
        camera: Camera model of the image ``camera`` was calibrated at.
        slots: Design slots in the world.
        z: Height of the mesh top [m].
        cfg: Marker size.
        filled: Slots the agent has filled (green); others white.
        target: Slot being filled now (magenta).
        scale: ``image`` pixels per pixel of ``camera``.
        recognise: Also draw what qshape extracts from ``image`` (the empty mesh's slot marks).
        mm_per_m: Design units per metre.

    Returns:
        The annotated image, BGR uint8.
    """
    import qshape  # noqa: PLC0415

    out = cv2.cvtColor(image, cv2.COLOR_RGB2BGR)
    r = max(1, round(cfg.marker_radius_px * min(1.0, 2 * scale)))
    if recognise:
        for f in qshape.extract_detailed(image).figures:
            _draw_figure(out, f.points, f.curve_mask, r, scale=1.0, colour=_OUTLINE)
            for h in f.holes:
                _draw_figure(out, h.points, h.curve_mask, r, scale=1.0, colour=_OUTLINE)
    done = filled or set()
    for s in slots:
        colour = _TARGET if s.index == target else _FILLED if s.index in done else _OUTLINE
        pts = np.asarray(s.figure.points, dtype=float)
        world = s.pose[:2] + (pts - np.asarray(s.figure.centroid)) / mm_per_m
        uv = scale * camera.project(np.column_stack([world, np.full(len(world), z)]))
        cv2.polylines(out, [np.round(uv).astype(np.int32)], True, colour, 1, cv2.LINE_AA)
        for p in uv:
            cv2.circle(out, _pt(p), max(1, r - 1), colour, -1, cv2.LINE_AA)
        centre = scale * camera.project(np.array([[s.pose[0], s.pose[1], z]]))[0]
        cv2.drawMarker(out, _pt(centre), _CENTRE, cv2.MARKER_CROSS, 3 * r, 1)
        if scale >= 1.0:
            cv2.putText(out, s.name, _pt(centre + [-6 * r, 4 * r]), cv2.FONT_HERSHEY_SIMPLEX,
                        0.3, _OUTLINE, 1, cv2.LINE_AA)  # fmt: skip
    return out


def _pt(p: np.ndarray) -> tuple[int, int]:
    return int(round(float(p[0]))), int(round(float(p[1])))


def _draw_figure(
    out: np.ndarray,
    pts: np.ndarray,
    mask: np.ndarray,
    r: int,
    *,
    scale: float,
    colour: tuple[int, int, int],
) -> None:
    from qshape.theory.boundary import densify  # noqa: PLC0415

    p = np.asarray(pts, dtype=float)
    m = np.asarray(mask, dtype=bool)
    dense = scale * densify(p, m)
    cv2.polylines(out, [np.round(dense).astype(np.int32)], True, colour, 1, cv2.LINE_AA)
    for q, is_curve in zip(scale * p, m, strict=True):
        cv2.circle(out, _pt(q), r, _CURVE if is_curve else _CORNER, -1, cv2.LINE_AA)


# ------------------------------------------------------------------------------ video
class CellVideo:
    """Frames of the cell overview beside the annotated camera views, written as an MP4.

    The env renders each frame (``render_mode="rgb_array"``: the overview beside the input and
    output camera panels); the camera panels are annotated here.

    Args:
        env: The env (wrapped or not), rendering ``rgb_array`` frames.
        agent: The scripted agent (its latest picture, plan and command are drawn).
        output_camera: Output camera model at full resolution (calibrated or true).
        cfg: Frame rate and markers.
        mm_per_m: Design units per metre.
    """

    def __init__(
        self,
        env: gym.Env[Any, Any],
        agent: ScriptedAgent,
        output_camera: CameraModel,
        cfg: RunConfig,
        mm_per_m: float,
    ) -> None:
        self.env = env
        self.agent = agent
        self.output_camera = output_camera
        self.cfg = cfg
        self.mm_per_m = mm_per_m
        cell = env.get_wrapper_attr("config").cell
        h = cell.render.overview_size[0]
        cam = cell.input_camera
        self.panel = (h // 2, round(h // 2 * cam.width / cam.height))
        self.scale = self.panel[0] / cam.height
        self.surface_z = agent.spec.place.surface_z
        self.frames: list[np.ndarray] = []

    def capture(self) -> None:
        """Render one frame of the current state."""
        agent, (ph, pw) = self.agent, self.panel
        frame = np.asarray(self.env.render())
        overview, right = frame[:, :-pw], frame[:, -pw:]
        cmd = agent.last_command
        raw_in, raw_out = right[:ph], right[ph : 2 * ph]
        if agent.last_perception is not None:
            panel_in = draw_perception(
                raw_in,
                agent.last_perception,
                agent.last_plan,
                self.cfg,
                scale=self.scale,
                target_tile=cmd.tile if cmd else None,
            )
        else:
            panel_in = cv2.cvtColor(raw_in, cv2.COLOR_RGB2BGR)
        filled = set(agent.filled) - ({cmd.slot} if cmd else set())
        panel_out = draw_slots(
            raw_out,
            self.output_camera,
            agent.slots,
            self.surface_z,
            self.cfg,
            filled=filled,
            target=cmd.slot if cmd else None,
            scale=self.scale,
            mm_per_m=self.mm_per_m,
        )
        panels = np.concatenate([panel_in, panel_out], axis=0)
        out = np.concatenate([cv2.cvtColor(overview, cv2.COLOR_RGB2BGR), panels], axis=1)
        self.frames.append(cv2.cvtColor(out, cv2.COLOR_BGR2RGB))

    def write(self, path: Path) -> Path | None:
        """Encode the frames (ffmpeg H.264, else OpenCV mp4v); returns the file or None.

        The video is written whole or not at all (encoded under a temporary name, then renamed).
        """
        if not self.frames:
            return None
        with atomic_path(path) as tmp:
            self._encode(tmp)
        return path

    def _encode(self, path: Path) -> None:
        """Encode the frames to ``path`` (ffmpeg H.264, else OpenCV mp4v)."""
        h, w = self.frames[0].shape[:2]
        fps = self.cfg.video_fps
        if shutil.which("ffmpeg"):
            cmd = [
                "ffmpeg", "-y", "-loglevel", "error", "-f", "rawvideo", "-pix_fmt", "rgb24",
                "-s", f"{w}x{h}", "-r", f"{fps:g}", "-i", "-", "-pix_fmt", "yuv420p",
                "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-vcodec", "libx264", str(path),
            ]  # fmt: skip
            proc = subprocess.run(
                cmd, input=np.stack(self.frames).tobytes(), capture_output=True, check=False
            )
            if proc.returncode == 0:
                return
        fourcc = cv2.VideoWriter_fourcc(*"mp4v")  # type: ignore[attr-defined]
        writer = cv2.VideoWriter(str(path), fourcc, fps, (w, h))
        for f in self.frames:
            writer.write(cv2.cvtColor(f, cv2.COLOR_RGB2BGR))
        writer.release()


# ------------------------------------------------------------------------------ the run
def make_env(rc: RunConfig) -> gym.Env[Any, Any]:
    """The env of the main job: ``pick_place``, full-resolution images, ``rgb_array`` frames.

    With the ``all`` feed, tiles that do not fit the input belt at once (many distractors)
    are fed in batches instead (the env's ``batch`` feed); the report names the feed used.

    Raises:
        QShapeError: The design does not load or validate.
        CellError: The design's tiles do not fit the input belt.
        ConfigError: A bad env setting.
    """
    from envs.cell.config import load_cell_config  # noqa: PLC0415

    cam = load_cell_config().input_camera
    over: dict[str, Any] = {
        "design": rc.design,
        "action_mode": "pick_place",
        "obs_mode": "rgb",
        "image_size": (cam.height, cam.width),
        "belt_speed": rc.belt_speed,
        "feed": rc.feed,
        "distractor_rate": rc.distractor_rate,
        "max_slots": rc.max_slots,
    }

    def make(feed: FeedMode) -> gym.Env[Any, Any]:
        kw = {**over, "feed": feed}
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


def run(cfg: AgentsConfig, out_dir: Path, quiet: bool = False) -> RunReport:
    """Run the scripted cell for one episode and write the report, images and video.

    Raises:
        AgentError: Calibration failed.
        QShapeError: The design does not load or validate.
        CellError: The design's tiles do not fit the input belt.
    """
    from tqdm import tqdm  # noqa: PLC0415

    rc = cfg.run
    t_wall = time.perf_counter()
    out_dir.mkdir(parents=True, exist_ok=True)
    env = make_env(rc)
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


def recognition(truth: GroundTruth, agent: ScriptedAgent) -> list[RecognitionRow]:
    """Per command of a picture: class right?, pick and yaw errors (ground truth, report only)."""
    rows = []
    plan = agent.last_plan
    for c in plan.commands if plan else ():
        i, d = truth.nearest(np.array(c.pick[:2]))
        class_ok = truth.class_name[i] == truth.slot_class[c.slot] and not truth.distractor[i]
        err = yaw_error(truth.yaw[i] + c.rotation, c.place[2], int(truth.symmetry[i]))
        rows.append(
            RecognitionRow(c.slot_name, i, bool(class_ok), MM_PER_M * d, math.degrees(float(err)))
        )
    return rows


def report_text(r: RunReport) -> str:
    """Plain-text summary of a report."""
    lines = [
        f"design {r.design} (seed {r.seed}), belt {r.belt_speed} m/s, feed "
        f"{r.feed}, placement {asdict(r.placement)}",
        f"tiles {r.tiles_total}: correct {r.correct}, misplaced {r.misplaced}, "
        f"dropped {r.dropped}, lost {r.lost}, distractors placed "
        f"{r.distractors_placed}, success {r.success}",
        f"tiles/min (simulated) {r.tiles_per_min:.1f} over {r.sim_s:.1f} s simulated; "
        f"wall {r.wall_s:.1f} s; steps {r.steps} ({r.failed_actions} failed), waits {r.waits}, "
        f"pictures {r.pictures}",
        f"placement error max {_num(r.position_error_mm_max)} mm, {_num(r.yaw_error_deg_max)} deg",
        f"recognition (first picture): {r.recognised_correct_class}/{r.tiles_total} "
        f"tiles to a slot of their class; pick error max {r.pick_error_max_mm:.2f} mm; "
        f"place-yaw error max {r.yaw_error_max_deg:.2f} deg",
    ]
    for name, c in (
        ("input_camera", r.calibration_input_camera),
        ("output_camera", r.calibration_output_camera),
    ):
        if c:
            lines.append(
                f"calibration {name}: reprojection {c['reprojection_px']:.3f} px, focal "
                f"{c['focal_error_pct']:+.3f} %, principal point "
                f"{c['principal_point_error_px']:.2f} px, position "
                f"{c['position_error_mm']:.2f} mm, angle {c['angle_error_deg']:.3f} deg"
            )
    lines += [f"not placed: tile {u.tile}: {u.detail}" for u in r.unplaced]
    lines += [f"not recognised: {msg}" for msg in r.unrecognised]
    if r.open_slots:
        lines.append(f"slots not filled correctly: {', '.join(r.open_slots)}")
    lines += [f"failed action: {s}" for s in r.failures]
    lines += [f"reject bin: {s}" for s in r.rejects]
    lines.append("tiles fed: " + ", ".join(f"{k} {v}" for k, v in r.tile_states.items() if v))
    return "\n".join(lines) + "\n"


def _num(v: float | None) -> str:
    return "-" if v is None else f"{v:.2f}"


def main(argv: list[str] | None = None) -> dict[str, object]:
    """Command line: run the scripted cell and print the report; returns ``report.json``'s dict."""
    parser = CommandParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", default="agents", help="bundled name or YAML path")
    parser.add_argument("--design", help="design name or path (default: config)")
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
    report = run(cfg, out, quiet=args.quiet)
    print(report_text(report), end="")
    print(f"wrote {out / 'report.json'}")
    return report.as_dict()


if __name__ == "__main__":
    run_cli(main)
