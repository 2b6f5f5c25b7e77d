"""What a real production line adds to a picture of tiles.

Rough and chipped edges, motion blur on the moving belt, radial lens distortion, shadows,
glaze highlights, JPEG. Outline effects (`roughen`, `chip_corners`) change a tile's dense
outline before it is drawn; image effects (`soft_shadow`, `glaze_highlights`,
`motion_blur`, `lens_distort`, `jpeg`) change the picture. `CameraEffects` holds their
sizes; every effect is off at its default, so ``CameraEffects()`` leaves a synthetic
picture as it was. Lens distortion follows OpenCV's radial model: a normalised point x
(about the principal point, divided by the focal length) is seen at x (1 + k1 r^2 + k2 r^4).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, fields
from typing import Any

import cv2
import numpy as np

from configs.checks import check_fields, checked
from qshape.errors import QShapeError
from qshape.geometry import FloatArray
from spatial.units import MM_PER_M

_S_PER_MS = 1e-3


@dataclass(frozen=True)
class CameraEffects:
    """Sizes of the line's effects on a synthetic picture (every default: off).

    Attributes:
        edge_roughness_mm: Standard deviation of the outline's displacement along its normal
            (chipped, ground tile edges), in [mm].
        roughness_length_mm: Correlation length of that displacement along the edge, in [mm].
        chip_probability: Chance that a tile corner is chipped, in [0, 1].
        chip_size_mm: Largest distance from the corner at which a chip's cut meets the edges,
            in [mm] (each chip draws uniformly from half of it to all of it).
        belt_speed_m_s: Belt speed, in [m/s].
        exposure_ms: Camera exposure time, in [ms]; the blur length is speed x exposure.
        belt_direction_deg: Direction of the belt's motion in the picture, in [deg] from +x
            (image axes).
        lens_k1: Radial distortion coefficient k1 (OpenCV model), dimensionless.
        lens_k2: Radial distortion coefficient k2, dimensionless.
        focal_px: Focal length, in [px]; 0 takes the picture's width.
        shadow_strength: Fraction of the light a soft shadow takes away, in [0, 1).
        shadow_softness_px: Width (Gaussian sigma) of the shadow's edge, in [px].
        shadow_width_fraction: Width of the shadow band, fraction of the picture's diagonal.
        highlight_strength: Peak blend of a glaze highlight towards white, in [0, 1].
        highlight_size_mm: Gaussian sigma of a highlight, in [mm].
        highlight_probability: Chance that a tile shows a highlight, in [0, 1].
        touching_probability: Chance that a tile is laid against another one, in [0, 1].
        partial_probability: Chance that a tile is laid across the picture's border, in [0, 1].
        jpeg_quality: JPEG quality of the stored picture, 1..100; 0: not compressed.
    """

    edge_roughness_mm: float = checked(0.0, ge=0)
    roughness_length_mm: float = checked(1.0, ge=0)
    chip_probability: float = checked(0.0, ge=0, le=1)
    chip_size_mm: float = checked(0.0, ge=0)
    belt_speed_m_s: float = checked(0.0, ge=0)
    exposure_ms: float = checked(0.0, ge=0)
    belt_direction_deg: float = 0.0
    lens_k1: float = checked(0.0, finite=True)
    lens_k2: float = checked(0.0, finite=True)
    focal_px: float = checked(0.0, ge=0)
    shadow_strength: float = checked(0.0, ge=0, lt=1)
    shadow_softness_px: float = checked(25.0, ge=0)
    shadow_width_fraction: float = checked(0.35, ge=0)
    highlight_strength: float = checked(0.0, ge=0, le=1)
    highlight_size_mm: float = checked(4.0, ge=0)
    highlight_probability: float = checked(0.0, ge=0, le=1)
    touching_probability: float = checked(0.0, ge=0, le=1)
    partial_probability: float = checked(0.0, ge=0, le=1)
    jpeg_quality: int = checked(0, ge=0, le=100)  # JPEG's scale; 0: off

    def __post_init__(self) -> None:
        """Raise `QShapeError` naming the field and its allowed range."""
        check_fields(self, QShapeError)

    def blur_px(self, px_per_mm: float) -> float:
        """Motion blur length on the picture, in [px]: belt speed x exposure x scale."""
        return self.belt_speed_m_s * MM_PER_M * self.exposure_ms * _S_PER_MS * px_per_mm

    def between(self, high: CameraEffects, rng: np.random.Generator) -> CameraEffects:
        """Each field drawn uniformly between this value and ``high``'s (integers rounded)."""
        values: dict[str, Any] = {}
        for f in fields(self):
            lo, hi = getattr(self, f.name), getattr(high, f.name)
            v = lo if lo == hi else float(rng.uniform(min(lo, hi), max(lo, hi)))
            values[f.name] = round(v) if isinstance(lo, int) else v
        return CameraEffects(**values)


# ------------------------------------------------------------------------------ outlines
def roughen(
    outline: FloatArray, sigma_px: float, length_px: float, rng: np.random.Generator
) -> FloatArray:
    """A closed dense outline (m, 2) moved along its normals by smooth random noise.

    The displacement is white noise smoothed circularly with a Gaussian of ``length_px``
    along the outline, rescaled to standard deviation ``sigma_px`` (both in [px]).
    """
    m = len(outline)
    if sigma_px <= 0.0 or m < 3:  # noqa: PLR2004 (a closed outline's fewest points)
        return outline
    step = np.roll(outline, -1, axis=0) - outline
    spacing = float(np.hypot(step[:, 0], step[:, 1]).mean())
    white = rng.normal(0.0, 1.0, m)
    k = max(1, round(length_px / max(spacing, 1e-9)))
    reps = math.ceil(3 * k / m) + 1
    tiled = np.tile(white, 2 * reps + 1).reshape(1, -1).astype(np.float64)
    smooth = cv2.GaussianBlur(tiled, (0, 0), sigmaX=float(k), sigmaY=0.1)[
        0, reps * m : reps * m + m
    ]
    std = float(smooth.std())
    disp = smooth * (sigma_px / std) if std > 0.0 else smooth
    tangent = np.roll(outline, -1, axis=0) - np.roll(outline, 1, axis=0)
    norm = np.hypot(tangent[:, 0], tangent[:, 1])
    norm[norm == 0.0] = 1.0
    normal = np.stack([tangent[:, 1], -tangent[:, 0]], axis=1) / norm[:, None]
    return np.asarray(outline + disp[:, None] * normal)


def chip_corners(
    outline: FloatArray,
    corners: FloatArray,
    probability: float,
    size_px: float,
    rng: np.random.Generator,
) -> FloatArray:
    """Cut chips off corners of a closed dense outline (m, 2), in [px].

    Each corner (k, 2) is chipped with ``probability``: the outline samples within a radius
    (uniform in [size_px / 2, size_px]) of the corner are moved onto the straight cut that
    joins the first and last of them, as a flake broken off the corner leaves it.
    """
    if probability <= 0.0 or size_px <= 0.0 or len(corners) == 0:
        return outline
    out = outline.copy()
    m = len(out)
    chipped = rng.random(len(corners)) < probability
    radii = rng.uniform(0.5 * size_px, size_px, len(corners))
    for corner, radius in zip(corners[chipped], radii[chipped], strict=True):
        d = np.hypot(*(out - corner).T)
        near = d <= radius
        if not near.any() or near.all():
            continue
        # The run of near samples around the closest one, followed circularly.
        centre = int(np.argmin(d))
        lo = hi = centre
        while near[(lo - 1) % m] and (centre - lo) < m:
            lo -= 1
        while near[(hi + 1) % m] and (hi - centre) < m:
            hi += 1
        idx = np.arange(lo, hi + 1) % m
        a, b = out[idx[0]], out[idx[-1]]
        ab = b - a
        denom = float(ab @ ab)
        if denom == 0.0:
            continue
        t = np.clip(((out[idx] - a) @ ab) / denom, 0.0, 1.0)
        out[idx] = a + t[:, None] * ab
    return out


# ------------------------------------------------------------------------------ picture
def soft_shadow(image: np.ndarray, e: CameraEffects, rng: np.random.Generator) -> np.ndarray:
    """A float32 picture darkened by a soft-edged band across it (an arm's or a rail's shadow)."""
    if e.shadow_strength <= 0.0:
        return image
    h, w = image.shape[:2]
    theta = rng.uniform(0.0, math.pi)
    nx, ny = math.cos(theta), math.sin(theta)
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    along = (xx - w / 2.0) * nx + (yy - h / 2.0) * ny
    diag = math.hypot(w, h)
    centre = rng.uniform(-0.3, 0.3) * diag
    half = 0.5 * e.shadow_width_fraction * diag
    inside = (np.abs(along - centre) <= half).astype(np.float32)
    if e.shadow_softness_px > 0.0:
        inside = cv2.GaussianBlur(inside, (0, 0), e.shadow_softness_px)
    return np.asarray(image * (1.0 - e.shadow_strength * inside)[..., None])


def glaze_highlights(  # noqa: PLR0917
    image: np.ndarray,
    tiles_mask: np.ndarray,
    centres_px: list[FloatArray],
    radii_px: list[float],
    e: CameraEffects,
    px_per_mm: float,
    rng: np.random.Generator,
) -> np.ndarray:
    """A float32 picture with Gaussian specular spots on the glaze of some tiles.

    Args:
        image: Float32 RGB picture (H, W, 3) in levels.
        tiles_mask: Float32 (H, W), 1 on tile material, 0 elsewhere.
        centres_px: Tile centres, each (2,) in [px].
        radii_px: Tile radii (largest centre-to-outline distance), in [px].
        e: Effect sizes.
        px_per_mm: Scale, in [px/mm].
        rng: Random generator.
    """
    if e.highlight_strength <= 0.0 or e.highlight_probability <= 0.0 or not centres_px:
        return image
    h, w = image.shape[:2]
    spots = np.zeros((h, w), np.float32)
    sigma = max(e.highlight_size_mm * px_per_mm, 0.5)
    for centre, radius in zip(centres_px, radii_px, strict=True):
        if rng.random() >= e.highlight_probability:
            continue
        r = 0.5 * radius * math.sqrt(rng.random())
        a = rng.uniform(0.0, 2.0 * math.pi)
        x, y = centre[0] + r * math.cos(a), centre[1] + r * math.sin(a)
        x0, x1 = max(0, int(x - 3 * sigma)), min(w, int(x + 3 * sigma) + 1)
        y0, y1 = max(0, int(y - 3 * sigma)), min(h, int(y + 3 * sigma) + 1)
        if x0 >= x1 or y0 >= y1:
            continue
        yy, xx = np.mgrid[y0:y1, x0:x1].astype(np.float32)
        g = np.exp(-((xx - x) ** 2 + (yy - y) ** 2) / (2.0 * sigma * sigma))
        np.maximum(spots[y0:y1, x0:x1], g, out=spots[y0:y1, x0:x1])
    blend = (e.highlight_strength * spots * tiles_mask)[..., None]
    return np.asarray(image + blend * (255.0 - image))


def motion_kernel(length_px: float, direction_deg: float) -> np.ndarray:
    """Normalised float32 line kernel of a uniform motion of ``length_px`` (box along it)."""
    half = int(math.ceil(length_px / 2.0)) + 1
    size = 2 * half + 1
    kernel = np.zeros((size, size), np.float32)
    samples = max(2, int(math.ceil(length_px * 8)))
    t = np.linspace(-length_px / 2.0, length_px / 2.0, samples)
    c, s = math.cos(math.radians(direction_deg)), math.sin(math.radians(direction_deg))
    xs, ys = half + t * c, half + t * s
    # Bilinear splat of each sample: fractional lengths are honoured.
    x0, y0 = np.floor(xs).astype(int), np.floor(ys).astype(int)
    fx, fy = xs - x0, ys - y0
    for dx, dy, wgt in (
        (0, 0, (1 - fx) * (1 - fy)),
        (1, 0, fx * (1 - fy)),
        (0, 1, (1 - fx) * fy),
        (1, 1, fx * fy),
    ):
        np.add.at(kernel, (y0 + dy, x0 + dx), wgt.astype(np.float32))
    return kernel / float(kernel.sum())


def motion_blur(image: np.ndarray, length_px: float, direction_deg: float) -> np.ndarray:
    """A float32 picture smeared along the belt by ``length_px`` (no change below 0.05 px)."""
    if length_px < 0.05:  # noqa: PLR2004 (a twentieth of a pixel: nothing to see)
        return image
    kernel = motion_kernel(length_px, direction_deg)
    return np.asarray(cv2.filter2D(image, -1, kernel, borderType=cv2.BORDER_REFLECT))


def camera_matrix(width: int, height: int, focal_px: float) -> np.ndarray:
    """Pinhole camera matrix (3, 3) with the principal point at the picture's centre."""
    f = float(focal_px) if focal_px > 0.0 else float(width)
    return np.array([[f, 0.0, (width - 1) / 2.0], [0.0, f, (height - 1) / 2.0], [0.0, 0.0, 1.0]])


def distort_points(points_px: FloatArray, e: CameraEffects, width: int, height: int) -> FloatArray:
    """Where ideal pinhole pixels (k, 2) are seen through the distorting lens, (k, 2) [px]."""
    pts = np.asarray(points_px, dtype=np.float64).reshape(-1, 2)
    if e.lens_k1 == 0.0 and e.lens_k2 == 0.0:
        return pts
    k = camera_matrix(width, height, e.focal_px)
    f, cx, cy = k[0, 0], k[0, 2], k[1, 2]
    xn, yn = (pts[:, 0] - cx) / f, (pts[:, 1] - cy) / f
    r2 = xn * xn + yn * yn
    g = 1.0 + e.lens_k1 * r2 + e.lens_k2 * r2 * r2
    return np.stack([xn * g * f + cx, yn * g * f + cy], axis=1)


@functools.lru_cache(maxsize=8)
def _undistort_maps(
    width: int, height: int, k1: float, k2: float, focal_px: float
) -> tuple[np.ndarray, np.ndarray]:
    """For each seen (distorted) pixel, the ideal pixel it shows: two float32 (H, W) maps."""
    k = camera_matrix(width, height, focal_px)
    yy, xx = np.mgrid[0:height, 0:width].astype(np.float64)
    pts = np.stack([xx.ravel(), yy.ravel()], axis=1).reshape(-1, 1, 2)
    dist = np.array([k1, k2, 0.0, 0.0, 0.0])
    criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 20, 1e-4)
    ideal = cv2.undistortPoints(pts, k, dist, R=None, P=k, criteria=criteria)
    ideal = ideal.reshape(height, width, 2)
    return ideal[..., 0].astype(np.float32), ideal[..., 1].astype(np.float32)


def lens_distort(image: np.ndarray, e: CameraEffects) -> np.ndarray:
    """The picture as the distorting lens shows it (OpenCV radial model, same size)."""
    if e.lens_k1 == 0.0 and e.lens_k2 == 0.0:
        return image
    h, w = image.shape[:2]
    mx, my = _undistort_maps(w, h, e.lens_k1, e.lens_k2, e.focal_px)
    return np.asarray(cv2.remap(image, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE))


@functools.lru_cache(maxsize=8)
def _distort_maps(
    width: int, height: int, k1: float, k2: float, focal_px: float
) -> tuple[np.ndarray, np.ndarray]:
    """For each ideal pixel, the seen (distorted) pixel showing it: two float32 (H, W) maps."""
    e = CameraEffects(lens_k1=k1, lens_k2=k2, focal_px=focal_px)
    yy, xx = np.mgrid[0:height, 0:width].astype(np.float64)
    seen = distort_points(np.stack([xx.ravel(), yy.ravel()], axis=1), e, width, height)
    seen = seen.reshape(height, width, 2)
    return seen[..., 0].astype(np.float32), seen[..., 1].astype(np.float32)


def undistort(image: np.ndarray, e: CameraEffects) -> np.ndarray:
    """A picture through the distorting lens brought back to the pinhole camera (same size).

    What a calibrated cell does before extraction, with the lens model calibration found.
    """
    if e.lens_k1 == 0.0 and e.lens_k2 == 0.0:
        return image
    h, w = image.shape[:2]
    mx, my = _distort_maps(w, h, e.lens_k1, e.lens_k2, e.focal_px)
    return np.asarray(cv2.remap(image, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE))


def undistort_points(
    points_px: FloatArray, e: CameraEffects, width: int, height: int
) -> FloatArray:
    """Ideal pinhole pixels (k, 2) of pixels (k, 2) seen through the distorting lens, [px]."""
    pts = np.asarray(points_px, dtype=np.float64).reshape(-1, 2)
    if e.lens_k1 == 0.0 and e.lens_k2 == 0.0:
        return pts
    k = camera_matrix(width, height, e.focal_px)
    dist = np.array([e.lens_k1, e.lens_k2, 0.0, 0.0, 0.0])
    criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 20, 1e-4)
    out = cv2.undistortPoints(pts.reshape(-1, 1, 2), k, dist, R=None, P=k, criteria=criteria)
    return np.asarray(out.reshape(-1, 2), dtype=np.float64)


def jpeg(image: np.ndarray, quality: int) -> np.ndarray:
    """An RGB uint8 picture after JPEG compression at ``quality`` (0: unchanged)."""
    if quality <= 0:
        return image
    ok, buf = cv2.imencode(
        ".jpg", cv2.cvtColor(image, cv2.COLOR_RGB2BGR), [cv2.IMWRITE_JPEG_QUALITY, int(quality)]
    )
    if not ok:
        raise QShapeError(f"JPEG encoding at quality {quality} failed")
    decoded = cv2.imdecode(buf, cv2.IMREAD_COLOR)
    if decoded is None:
        raise QShapeError(f"JPEG decoding at quality {quality} failed")
    return np.ascontiguousarray(cv2.cvtColor(decoded, cv2.COLOR_BGR2RGB))


__all__ = [
    "CameraEffects",
    "camera_matrix",
    "chip_corners",
    "distort_points",
    "glaze_highlights",
    "jpeg",
    "lens_distort",
    "motion_blur",
    "motion_kernel",
    "roughen",
    "soft_shadow",
    "undistort",
    "undistort_points",
]
