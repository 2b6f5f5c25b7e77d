"""Validation of a design's layout: slot outlines, slots inside the mesh, joints between slots."""

from __future__ import annotations

import numpy as np
import shapely

from qshape import geometry as geo
from qshape.design.features import check_small_features
from qshape.design.fields import DesignFields
from qshape.design.turn_cues import check_turn_cues
from qshape.errors import DesignError, DesignLimitError, InvalidFigureError
from qshape.geometry import FloatArray
from qshape.limits import default_limits


def validate(design: DesignFields, source: str = "") -> None:
    """Check every slot and the layout.

    Raises:
        DesignError: Duplicate names, degenerate or self-crossing outlines, bad holes,
            slots outside the mesh (by more than ``rules.mesh_margin_mm``), or two slots
            closer than ``rules.min_gap_fraction`` x joint; arcs below the smallest the camera
            recognises, or slots whose turn it may not fix (`qshape.design.turn_cues`), with
            ``rules.small_features == "refuse"`` (with ``"warn"``: a
            `qshape.errors.SmallFeatureWarning` per slot).
        DesignLimitError: A mesh side or tile outline above the ``max_design_mm`` cap.
    """
    pre = f"{source}: " if source else f"design {design.name!r}: "
    names = [s.name for s in design.slots]
    dupes = sorted({n for n in names if names.count(n) > 1})
    if dupes:
        raise DesignError(f"{pre}duplicate slot name(s) {dupes}")
    w, h = design.mesh_size
    for side, value in (("width", w), ("height", h)):
        default_limits().check_length(float(value), f"{pre}mesh {side}")
    margin = design.rules.mesh_margin_mm
    outlines = []
    checked: dict[str, FloatArray] = {}  # per shape: its outline about the centroid, checked once
    for s in design.slots:
        try:
            local = checked.get(s.shape_key)
            if local is None:
                local = s.local_path.outer.dense(design.rules.check_step_mm)
                if geo.self_intersects(local):
                    raise DesignError("its outline crosses itself")
                s.local_path.figure(s.color, design.rules.max_arc_deg)
                checked[s.shape_key] = local
        except DesignLimitError as exc:
            raise DesignLimitError(f"{pre}{exc}") from exc
        except (DesignError, InvalidFigureError) as exc:
            text = str(exc)
            named = text if text.startswith(f"slot {s.name!r}") else f"slot {s.name!r}: {text}"
            raise DesignError(f"{pre}{named}") from exc
        dense = geo.rotate(local, np.radians(s.angle)) + s.centroid
        lo, hi = dense.min(axis=0), dense.max(axis=0)
        if lo[0] < margin or lo[1] < margin or hi[0] > w - margin or hi[1] > h - margin:
            raise DesignError(
                f"{pre}slot {s.name!r} lies outside the {w} x {h} mm mesh (extent x "
                f"{lo[0]:.1f}..{hi[0]:.1f}, y {lo[1]:.1f}..{hi[1]:.1f} mm; margin {margin} mm)"
            )
        outlines.append(dense)
    check_small_features(design.slots, design.rules, pre)
    check_turn_cues(design.slots, design.rules, pre)
    min_gap = design.rules.min_gap_fraction * design.joint
    ii, jj = _near_pairs(outlines, min_gap)
    for i, j in zip(ii.tolist(), jj.tolist(), strict=False):
        gap = _outline_gap(outlines[i], outlines[j])
        if gap < min_gap:
            what = "overlap" if gap < 0 else f"are {gap:.2f} mm apart"
            raise DesignError(
                f"{pre}slots {design.slots[i].name!r} and {design.slots[j].name!r} {what}; the "
                f"joint is {design.joint} mm (at least {min_gap:.2f} mm required)"
            )


def _near_pairs(outlines: list[FloatArray], gap: float) -> tuple[np.ndarray, np.ndarray]:
    """Index pairs (i < j) of outlines closer than ``gap`` or overlapping, O(n log n).

    Outlines are taken relative to the first one's first point (as `_outline_gap`).
    """
    if not outlines:
        return np.zeros(0, int), np.zeros(0, int)
    ref = outlines[0][0]
    counts = np.array([len(d) for d in outlines])
    coords = np.concatenate(outlines) - ref
    rings = shapely.linearrings(coords, indices=np.repeat(np.arange(len(outlines)), counts))
    polys = shapely.polygons(rings)
    tree = shapely.STRtree(polys)
    a, b = tree.query(polys, predicate="dwithin", distance=gap)
    keep = a < b
    return a[keep], b[keep]


def _outline_gap(a: FloatArray, b: FloatArray) -> float:
    """Smallest distance between two closed outlines; negative when they overlap.

    O((m + n) log(m + n)) (GEOS), relative to a's first point.
    """
    ref = a[0]
    pa = shapely.Polygon(a - ref)
    pb = shapely.Polygon(b - ref)
    if pa.is_valid and pb.is_valid and pa.intersection(pb).area > 0.0:
        return -1.0
    if geo.points_in_polygon(a[:1], b).any() or geo.points_in_polygon(b[:1], a).any():
        return -1.0
    return float(shapely.LinearRing(a - ref).distance(shapely.LinearRing(b - ref)))


__all__ = ["validate"]
