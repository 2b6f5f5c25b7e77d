"""Parameters of outline simplification (`qshape.outline.simplify`): ``configs/vision.yaml``."""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from configs.checks import check_fields, checked
from qshape.errors import ToleranceError
from qshape.theory.tolerances import _load_section

MIN_RESAMPLE_POINTS = 16
"""Fewest uniform samples an outline is resampled to (`OutlineParams.resample_points`)."""


@dataclass(frozen=True)
class OutlineParams:
    """Parameters of `simplify_outline`. Lengths are fractions of the outline's size.

    Attributes:
        resample_points: Number of uniform arc-length samples the outline is resampled to.
        smooth_fraction: Half-width of the circular moving average, fraction of perimeter.
        corner_window: Arc length on each side of a point over which its direction change is
            measured, fraction of perimeter. Also the spacing kept between two corners.
        corner_angle_deg: Direction change that makes a corner, in [deg]. A circle measured over
            the default window turns by about 14 degrees; a square corner by 90.
        straight_sagitta_ratio: A run between corners is straight when its largest distance from
            its chord is below this fraction of the chord (or below the noise floor).
        noise_fraction: Distance from a chord always treated as noise, fraction of the outline's
            diameter (largest extent).
        max_curve_turn_deg: A curve turning more than this is split into equal-turn pieces, in
            [deg]. A full circle (360) becomes two semicircles; 240 keeps a noisy semicircle
            (whose measured turning can exceed 180) whole.
        merge_fraction: Corners closer than this fraction of the perimeter are merged.
        refine_corners: Move each corner between two straight edges to the intersection of
            lines fitted to those edges (sub-sample accuracy on clean polygons; at very acute
            corners small line errors can push the corner outwards).
        arc_turning_deg: A point whose outline turns by at least this much on both sides
            (the direction change measured 2 and 3 windows away, mean per side) lies inside an
            arc: only its change in excess of the smaller side's counts towards a corner, in
            [deg] (0: off). An arc turns by several degrees over every window and noise adds
            to that, while a corner's turning is concentrated: so the pixel staircase of a
            20 mm arc at 2 px/mm stays below ``corner_angle_deg``, and a shallow corner
            between straight edges keeps its full angle.
        circle_residual: An outline with a curve whose samples stay within this RMS radial
            distance of a fitted circle, as a fraction of its radius, is a circle: two equal
            semicircle arcs (dimensionless; 0: off). Where a traced closed curve is split
            depends on its noise, and two unequal halves label one arc acute and the other
            plane (a ring's hole seen through a thick tile, whose visible inner wall dents
            the outline, even gets shallow corners).
        chamfer_fraction: Two neighbouring corners joined by a straight edge shorter than
            this fraction of the perimeter are one corner cut off by noise: they become the
            intersection of the edges before and after them (dimensionless; 0: off).
        missed_corner_ratio: A run that is not straight but splits, at its sample farthest
            from the chord, into two halves each within this fraction of its own chord (or the
            noise floor) is two straight edges meeting at a corner the window measure missed
            (a shallow concave corner beside a pixel staircase), not a curve (dimensionless;
            0: off). Keep it below the halves of the shallowest arc that is not straight:
            with ``straight_sagitta_ratio`` 0.1 those are 0.049.
        roughness_sigmas: The noise floor of an outline is at least this many times its
            measured edge roughness (robust standard deviation of each sample's distance
            from the chord of its neighbours one corner window away, less the local mean
            that an arc's own sagitta gives), so a chipped, ground edge stays straight
            (dimensionless; 0: off).
        min_corner_deg: A corner between two straight runs whose fitted lines (total least
            squares over each run) meet at less than this angle is roughness on one edge,
            not a corner, and is dropped, weakest first, in [deg] (0: off). The lines are fitted
            over whole edges, so this holds where the window measure of
            ``corner_angle_deg`` is fooled by a rough edge; keep it below the shallowest real
            corner of the tiles (33 degrees in the bundled trencadis).
        fit_merge_chi2: Corners from fits (`qshape.outline.fit`), dimensionless, 0: off. A corner
            is dropped when the runs on both sides fit one line (or one arc, where a run is
            itself curved) with a squared residual at most this many times the outline's
            roughness variance per independent sample above their separate fits; the kept
            corners then move to the sample that best splits their runs, and an outline that
            one circle fits as well as its runs keeps no corner (a closed curve). The
            roughness is `roughness_sigmas`' measure, and one independent sample spans
            (1 + rho) / (1 - rho) samples for the lag-1 autocorrelation rho of the measure
            (a correlated bump counts once, however densely it is sampled).
        fit_split_turn_deg: With ``fit_merge_chi2``, a run between corners that is not
            straight is two edges meeting at a corner the window measure missed (or placed
            off, so the run took in part of the next edge) when two lines split at one of its
            samples (at least the corner spacing from its ends) fit it better than its arc
            and their directions differ by at least this, in [deg] (0: off). Such a run never
            lets an arc absorb its neighbours' corners (a rough hexagon merged side by side
            into a circle) and gets its corner back at the best split. Keep it well above
            the turn between a short arc piece's two chords (half the arc's turn): a longer
            arc is fitted far better by its arc than by two chords.
        fit_sigma_floor: Smallest roughness the fits assume, fraction of the outline's
            diameter (a clean traced outline still carries its pixel staircase).
        refine_trim_fraction: With ``refine_corners``, the samples left out at each end of
            a run before its line is fitted, fraction of the outline's samples (at least one
            sample; 0: ``corner_window``). A short trim fits the line to nearly the whole
            edge, which averages a rough edge's bumps out: keep it just above the rounding
            of a corner by blur.
        hole_corner_window: ``corner_window`` of an outline lying in another (a hole, see
            `simplify_outlines`' ``parents``), fraction of its own perimeter, but at most
            the figure outline's window in length (dimensionless; 0: ``corner_window``).
            Blur and rough edges round a small hole's corner over as many millimetres as
            the figure's, a larger share of the hole's short perimeter: over the figure's
            fraction the rounded corner turned twice, a corner gained.
    """

    resample_points: int = checked(256, ge=MIN_RESAMPLE_POINTS)
    smooth_fraction: float = checked(0.006, ge=0, lt=0.5)
    corner_window: float = checked(0.02, gt=0, lt=0.5)
    corner_angle_deg: float = checked(25.0, gt=0, lt=180)
    straight_sagitta_ratio: float = checked(0.03, ge=0, lt=0.5)
    noise_fraction: float = checked(0.006, ge=0, lt=0.5)
    max_curve_turn_deg: float = checked(240.0, ge=90, le=360)
    merge_fraction: float = checked(0.02, ge=0, lt=0.5)
    refine_corners: bool = False
    arc_turning_deg: float = checked(0.0, ge=0, lt=180)
    circle_residual: float = checked(0.0, ge=0, lt=0.5)
    chamfer_fraction: float = checked(0.0, ge=0, lt=0.5)
    missed_corner_ratio: float = checked(0.0, ge=0, lt=0.5)
    roughness_sigmas: float = checked(0.0, ge=0, le=20)
    min_corner_deg: float = checked(0.0, ge=0, lt=90)
    fit_merge_chi2: float = checked(0.0, ge=0, le=1e4)
    fit_sigma_floor: float = checked(0.0, ge=0, lt=0.5)
    fit_split_turn_deg: float = checked(0.0, ge=0, lt=180)
    refine_trim_fraction: float = checked(0.0, ge=0, lt=0.5)
    hole_corner_window: float = checked(0.0, ge=0, lt=0.5)

    def __post_init__(self) -> None:
        """Validate ranges.

        Raises:
            ToleranceError: Naming the field and the allowed range.
        """
        check_fields(self, ToleranceError)

    @classmethod
    def load(cls, name_or_path: str | Path | None = None, **overrides: Any) -> OutlineParams:
        """Load from YAML (section ``outline`` of ``configs/qshape.yaml`` by default).

        Raises:
            configs.ConfigError: Unknown key, wrong type or missing file.
            ToleranceError: Values out of range.
        """
        return _load_section(cls, "outline", name_or_path, overrides)


@functools.cache
def default_outline_params() -> OutlineParams:
    """Bundled outline parameters, loaded once."""
    return OutlineParams.load()


__all__ = ["MIN_RESAMPLE_POINTS", "OutlineParams", "default_outline_params"]
