"""Design slots described as the pictures' outline simplification sees them.

A design puts a relevant point at every corner and at both ends of every arc; a picture shows
a corner only where the outline turns enough (`qshape.vision.seen`). Each slot whose outline a
noise-free picture would describe otherwise gets that description too (`SeenSlot`), and the
scripted agent lets a tile matching no slot's own description match it
(`agents.scripted.placement.plan_placements`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

import qshape
from agents.errors import PerceptionError
from envs.cell.cameras import CameraModel
from envs.errors import CellError
from envs.task_spec import WorldSlot
from qshape import Description, Figure
from qshape.vision.seen import near_turns, seen_figure
from spatial.units import MM_PER_M


def camera_scale(camera: CameraModel, z: float) -> float:
    """The camera's scale on the plane at height ``z`` at the image centre, [px/mm].

    Raises:
        PerceptionError: A ray parallel to the plane or the plane behind the camera.
    """
    c = np.array([[camera.width / 2.0, camera.height / 2.0]])
    step = 10.0  # [px] a span measured across the image centre
    try:
        ends = camera.unproject_to_plane(np.vstack([c - step / 2.0, c + step / 2.0]), z)
    except CellError as exc:
        raise PerceptionError(str(exc)) from exc
    span_mm = float(np.linalg.norm(ends[1, :2] - ends[0, :2])) * MM_PER_M
    return step * math.sqrt(2.0) / span_mm


@dataclass(frozen=True, eq=False)
class SeenSlot:
    """A slot's outline as a picture's outline simplification sees it.

    Attributes:
        figure: `qshape.vision.seen.seen_figure` of the slot's figure (mesh millimetres, y up,
            the slot's frame): its relevant points are where a picture puts them, its area
            and centroid those of its arcs through three points, not the design's.
        description: Its qshape description.
    """

    figure: Figure
    description: Description


def seen_outlines(
    slots: Sequence[WorldSlot],
    descs: Sequence[Description],
    tolerances: qshape.Tolerances | None,
    seen: tuple[qshape.OutlineParams, float, float] | None,
) -> list[SeenSlot | None]:
    """Per slot, its seen outline where it matches no turn of the design's (else None).

    Args:
        slots: The world slots.
        descs: Their descriptions (as `qshape.describe_many` gives them).
        tolerances: qshape tolerances (bundled when None).
        seen: (the pictures' outline parameters, the camera's scale on the tile tops
            [px/mm], the near-turn residual of `_seen_one`); None: no seen outlines.

    Each slot's own (its figure is turned by its yaw, and a match's rotation is read off it).
    """
    if seen is None:
        return [None] * len(slots)
    return [
        _seen_one(s.figure, d, s.symmetry, seen, tolerances)
        for s, d in zip(slots, descs, strict=True)
    ]


def _seen_one(
    figure: Figure,
    desc: Description,
    symmetry: int,
    seen: tuple[qshape.OutlineParams, float, float],
    tolerances: qshape.Tolerances | None,
) -> SeenSlot | None:
    """The seen outline of one slot figure; None when it matches the design's description.

    None too when the seen figure has more turns onto itself than the design's ``symmetry``
    (1: none, 0: continuous), by its description or nearly (`near_turns` within
    ``turn_residual``): a random octagon whose corners all turn too little is seen as a
    circle, a seven-point arc polygon as four points nearly two-fold symmetric, and a match
    with it would leave the tile's turn open where the slot's is not.
    """
    params, px_per_mm, turn_residual = seen
    try:
        fig = seen_figure(figure, params, px_per_mm)
        sd = qshape.describe(fig, tolerances)
        if qshape.match(desc, sd, tolerances) is not None:
            return None
        itself = qshape.match(sd, sd, tolerances)
    except qshape.QShapeError:
        return None
    if itself is None or (itself.continuous and symmetry != 0):
        return None
    if symmetry != 0 and max(len(itself.rotations), near_turns(fig, turn_residual)) > symmetry:
        return None
    return SeenSlot(fig, sd)


__all__ = ["SeenSlot", "camera_scale", "seen_outlines"]
