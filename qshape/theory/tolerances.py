"""Every band, threshold and margin of the qualitative labels and of matching.

The defaults come from SPEC section 3 (the reference implementation of the theory used a right
angle of 85-95 degrees, equal lengths at a ratio of 0.9-1.1 then 0.8-1.25, semicircles at
half-chord/sagitta 0.95-1.05, and colour distances up to 0.2-0.4 on the RGB/256 scale).
Bundled values live in ``configs/qshape.yaml``; load them with `Tolerances.load`.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypeVar

from configs import ConfigError, check_field_types
from configs.checks import check_fields, checked
from qshape.config_sections import load_section
from qshape.errors import ToleranceError

T = TypeVar("T")


@dataclass(frozen=True)
class Tolerances:
    """Bands and thresholds of the qualitative shape labels and of matching.

    A measurement lying within the ambiguity margin of a band edge gets both labels admissible
    (its own and the neighbouring one); matching accepts either, so two copies of a tile that
    land on opposite sides of an edge still match.

    Attributes:
        right_angle_deg: (low, high) interior angle band labelled "right", in [deg]. Below low:
            acute; above high: obtuse. Default 85-95, the reference implementation's first band,
            symmetric about 90 so a noise of a few degrees keeps squares right-angled.
        equal_length_ratio: (low, high) band of |V(i-1) V(i)| / |V(i) V(i+1)| labelled "equal"
            (dimensionless). Below: smaller; above: bigger. Default 0.8-1.25, the reference
            implementation's later band; the edges are reciprocal, so walking a boundary the
            other way swaps smaller and bigger exactly.
        semicircle_ratio: (low, high) band of half-chord / sagitta (da / db) labelled
            "semicircle" (dimensionless). Below: acute curve; above: plane curve. Default 0.9-1.1,
            wider than the reference 0.95-1.05 because a pixel of error on a 20 px sagitta is 5%.
        angle_margin_deg: Ambiguity margin around each right-angle band edge, in [deg].
        length_margin: Relative ambiguity margin around each equal-length band edge: a ratio r
            is ambiguous at edge e when e / (1 + m) <= r <= e * (1 + m). Dimensionless.
        semicircle_margin: Relative ambiguity margin around each semicircle band edge (as for
            `length_margin`). Dimensionless.
        convexity_margin_deg: A vertex whose boundary bends by at most this many degrees either
            way (nearly collinear neighbours) is both convex and concave, in [deg].
        cone_margin_deg: Angular margin used when comparing hole positions in the 8-cone frame:
            a hole edge within this margin of a cone border may or may not cover the next cone,
            in [deg].
        color_distance: Largest Euclidean RGB distance (RGB in [0, 1]) at which two colours are
            the same. Default 0.2, the paper's value; its reference implementation went up to 0.4.
        joint_width: Mosaic joint width, in the figures' length unit (mm for designs). Two
            figures have the same qualitative size when their areas differ by at most
            joint_width x mean perimeter (a band of the joint's width along the boundary).
        size_area_threshold: If set, an absolute area difference threshold in the figures'
            length unit squared, used instead of the joint rule.
        check_size: Compare qualitative size at all (False when tiles and slots are in
            different units, e.g. pixels against millimetres).
        symmetry_residual: Two rotations are equivalent (a symmetry of the shape) when their
            alignment residuals differ by at most this fraction of sqrt(area), and the
            reference is symmetric under the turn between them (``symmetry_tolerance``).
            Dimensionless.
        symmetry_tolerance: The reference figure is symmetric under a cyclic shift of its
            relevant points when, best turned onto themselves so shifted, they lie within
            this RMS distance of themselves, as a fraction of sqrt(area). The symmetry comes
            from the geometry, not from the labels: an isosceles triangle whose three edges
            all label "equal" (base 44, height 40 mm: 0.037) is not 3-fold symmetric, and its
            three label-compatible rotations are not equivalent. Dimensionless.
        max_key_variants: Largest number of admissible label combinations expanded into
            canonical keys for one figure; beyond it the figure is looked up by a coarse key.
        tie_tolerance: Fraction of the figure's size within which two vertices count as equally
            high when choosing the uppermost-left starting vertex. Dimensionless.
        point_tolerance: How far a measured tile's relevant points may lie from where its
            design puts them (manufacturing tolerance, edge roughness, pixels), in the
            figures' length unit (mm for designs; scale it with the camera, as `joint_width`).
            When a pair's labels disagree, each candidate label also admits its neighbouring
            label when its measurement lies within the configured margin plus the change such
            a displacement causes (more between short edges). Used by `qshape.match`; the
            canonical keys of `qshape.assign` stay on the labels alone. 0: off.
        uncertainty_residual: Pairs matched through `point_tolerance` must also align with
            a residual (as `Match.score`) of at most this fraction of sqrt(area).
            Dimensionless.
        curve_point_weight: Weight of a curve's maximum-curvature point in the least-squares
            rotation `qshape.match` returns (a vertex weighs 1; `qshape.assign` weighs all
            alike): on a flat maximum its place along the curve is measured much less well
            than a corner's. In [0, 1]. Dimensionless.
        rotation_corner_share: Share of the relevant points in the rotation `qshape.match`
            returns; the rest goes to the measured outline's edges. The rotation minimises
            ``share`` x (mean squared distance of the candidate's relevant points to the
            reference's) + (1 - ``share``) x (mean squared distance, per unit of outline
            length, of the candidate's edges to the reference's edge lines), edges touching a
            curve point weighing ``curve_point_weight``. A measured polygon's corners are
            intersections of edge lines fitted over whole edges, so its edges carry their
            directions even where a corner slid along its bisector. 1: relevant points alone
            (a weighted Procrustes). In [0, 1]. Dimensionless.
        weak_turn_deg: A measured corner between straight edges whose direction changes by at
            most this much either way is weak, in [deg]: blur and rough edges may have cut it
            from a corner (a chamfer), added it, or placed it along its edge. `qshape.match_best`
            tries the figure with one weak corner removed, merged or slid
            (`qshape.theory.neighbours`)
            when the figure as measured matches nothing. Below 90.
        weak_pair_fraction: Two adjacent weak corners turning the same way at most this
            fraction of the perimeter apart may be one corner cut by a chamfer. Dimensionless.
        weak_slide_fraction: How far along its edges a weak corner may lie from its place,
            as a fraction of the perimeter. Dimensionless.
        neighbour_residual: A structural neighbour matches only when its alignment residual
            (as `Match.score`) is at most this fraction of sqrt(area), and only when it matches
            exactly one reference. 0: structural neighbours off. Dimensionless.
    """

    right_angle_deg: tuple[float, ...] = checked(
        (85.0, 95.0), length=2, gt=0, increasing=True, lt=180
    )
    equal_length_ratio: tuple[float, ...] = checked((0.8, 1.25), length=2, gt=0, increasing=True)
    semicircle_ratio: tuple[float, ...] = checked((0.9, 1.1), length=2, gt=0, increasing=True)
    angle_margin_deg: float = checked(2.0, ge=0)
    length_margin: float = checked(0.05, ge=0)
    semicircle_margin: float = checked(0.03, ge=0)
    convexity_margin_deg: float = checked(2.0, ge=0, lt=90)
    cone_margin_deg: float = checked(5.0, ge=0, lt=22.5)  # half a cone
    color_distance: float = checked(0.2, gt=0)
    joint_width: float = checked(2.0, ge=0)
    size_area_threshold: float | None = checked(None, ge=0, optional=True)
    check_size: bool = True
    symmetry_residual: float = checked(0.05, ge=0)
    symmetry_tolerance: float = checked(0.02, ge=0)
    max_key_variants: int = checked(64, ge=1)
    tie_tolerance: float = checked(1e-6, ge=0)
    point_tolerance: float = checked(0.5, ge=0)
    uncertainty_residual: float = checked(0.05, ge=0)
    curve_point_weight: float = checked(0.25, ge=0, le=1)
    rotation_corner_share: float = checked(0.33, ge=0, le=1)
    weak_turn_deg: float = checked(40.0, ge=0, lt=90)
    weak_pair_fraction: float = checked(0.08, ge=0)
    weak_slide_fraction: float = checked(0.03, ge=0)
    neighbour_residual: float = checked(0.04, ge=0)

    def __post_init__(self) -> None:
        """Validate bands (ordered, positive) and margins (non-negative, narrower than bands).

        Raises:
            ToleranceError: Naming the field and the allowed range.
        """
        for name in ("right_angle_deg", "equal_length_ratio", "semicircle_ratio"):
            value = getattr(self, name)
            if not isinstance(value, str) and hasattr(value, "__len__"):
                object.__setattr__(self, name, tuple(value))  # lists, arrays: checked below
        try:
            check_field_types(self)
        except ConfigError as exc:
            raise ToleranceError(str(exc)) from None
        check_fields(self, ToleranceError)
        lo, hi = self.right_angle_deg
        if 2.0 * self.angle_margin_deg >= hi - lo:
            raise ToleranceError(
                f"angle_margin_deg={self.angle_margin_deg} must be less than half the right-angle "
                f"band width ({(hi - lo) / 2})"
            )
        if self.angle_margin_deg >= lo:
            raise ToleranceError(f"angle_margin_deg must be < right_angle_deg low ({lo})")
        for band_name, margin_name in (
            ("equal_length_ratio", "length_margin"),
            ("semicircle_ratio", "semicircle_margin"),
        ):
            blo, bhi = getattr(self, band_name)
            margin = getattr(self, margin_name)
            if (1.0 + margin) ** 2 >= bhi / blo:
                raise ToleranceError(
                    f"{margin_name}={margin} is too wide for {band_name}={(blo, bhi)}: "
                    f"(1 + margin)^2 must be < high / low = {bhi / blo:.4g}"
                )

    @classmethod
    def load(cls, name_or_path: str | Path | None = None, **overrides: Any) -> Tolerances:
        """Load tolerances from YAML (bundled name or path; None: ``configs/qshape.yaml``).

        Args:
            name_or_path: Bundled config name or YAML path. The file holds a ``tolerances``
                mapping (a file with only tolerance keys at top level is accepted too).
            **overrides: Field values replacing the file's.

        Raises:
            configs.ConfigError: Unknown key, wrong type or missing file.
            ToleranceError: Values out of range.
        """
        return load_section(cls, "tolerances", name_or_path, overrides, default="qshape")


@functools.cache
def default_tolerances() -> Tolerances:
    """The bundled tolerances (``configs/qshape.yaml``), loaded once."""
    return Tolerances.load()


def resolve_tolerances(tolerances: object) -> Tolerances:
    """``tolerances`` itself, or the bundled defaults for None.

    Raises:
        ToleranceError: Anything but None or a `Tolerances`.
    """
    if tolerances is None:
        return default_tolerances()
    if not isinstance(tolerances, Tolerances):
        raise ToleranceError(
            f"tolerances must be a qshape.Tolerances or None (the bundled defaults), got "
            f"{type(tolerances).__name__}"
        )
    return tolerances


def _load_section(
    cls: type[T], section: str, name_or_path: str | Path | None, overrides: dict[str, Any]
) -> T:
    """One section of ``configs/qshape.yaml`` (or another file); see `load_section`."""
    return load_section(cls, section, name_or_path, overrides, default="qshape")


__all__ = ["Tolerances", "default_tolerances", "resolve_tolerances"]
