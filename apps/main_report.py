"""The main job's report: `RunReport` (``report.json``), its text form, the recognition rows.

Figures derive from the episode's `envs.task.Evaluation` (the one outcome record).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from agents.scripted.agent import ScriptedAgent
from agents.scripted.config import PlacementConfig
from agents.scripted.placement import Unplaced
from envs.task import GroundTruth
from envs.task_spec import FeedMode
from spatial.angles import yaw_error
from spatial.units import MM_PER_M


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


__all__ = ["RecognitionRow", "RunReport", "recognition", "report_text"]
