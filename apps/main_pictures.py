"""Pictures and video of the main job: camera views annotated with what the cell recognised.

`draw_perception` marks the input camera's relevant points, centres and target slots;
`draw_slots` projects the design's slots into the output camera; `CellVideo` records the cell
overview beside both camera views while the episode runs.
"""

from __future__ import annotations

import shutil
import subprocess
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import cv2
import gymnasium as gym
import numpy as np

from agents.scripted.agent import ScriptedAgent
from agents.scripted.config import RunConfig
from agents.scripted.perception import Perception, SlotTarget
from agents.scripted.placement import PlacementPlan
from configs.files import atomic_path
from envs.cell.cameras import CameraModel
from spatial.units import MM_PER_M

# Drawing colours (BGR for OpenCV).
_CORNER = (0, 0, 255)
_CURVE = (255, 255, 0)
_OUTLINE = (255, 255, 255)
_CENTRE = (0, 255, 0)
_TARGET = (255, 0, 255)
_REJECT = (0, 165, 255)
_FILLED = (0, 200, 0)


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


__all__ = ["CellVideo", "draw_perception", "draw_slots"]
