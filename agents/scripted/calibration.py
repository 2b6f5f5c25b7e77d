"""Camera calibration as a real cell does it: checkerboard images, OpenCV, reprojection error.

The pictures come from the env (``env.get_wrapper_attr("calibration_views")``, rendered on the
env's side by `envs.cell.calibration_board`): a checkerboard target at several tilted, lifted
and shifted poses before one camera, and once lying flat at its fixture position. OpenCV finds
the inner corners (`cv2.findChessboardCorners` + `cv2.cornerSubPix`) and estimates the intrinsics
(`cv2.calibrateCamera`: one focal length, principal point, OpenCV's lens distortion k1, k2,
p1, p2; k3 as configured: a camera with a lens distortion renders through it). A last
view of the board lying flat on the belt at its known fixture position gives the extrinsics
(`cv2.solvePnP` with the board's world corner coordinates): the pose of the belt plane.

The board has an even by odd count of squares so its colour pattern is not symmetric under a
half turn: the corner order is made unique by the colour of the square beyond the first corner
and by handedness (see `_orient`).

The estimated `envs.cell.cameras.CameraModel` (with the estimated distortion, which perception
removes from every point it unprojects) is what perception uses; the simulator's true model is
read only to report the differences (focal %, principal point px, position mm, angle deg, and
the worst pixel displacement between the true and the estimated lens over the image).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import cv2
import gymnasium as gym
import numpy as np

from agents.errors import CalibrationError
from agents.scripted.config import CalibrationConfig
from envs.cell.calibration_board import CalibrationViews
from envs.cell.cameras import CameraModel, distort_normalised
from envs.errors import CellError

_DARK_LEVEL = 128
"""Grey level (0-255) below which a sampled square counts as black."""


@dataclass(frozen=True, eq=False)
class CalibrationResult:
    """An estimated camera and how it compares with the simulator's.

    Attributes:
        camera: The estimated model (K from calibrateCamera, world_to_camera from solvePnP).
        true_camera: The simulator's model (for the comparison only).
        distortion: OpenCV distortion coefficients (k1, k2, p1, p2, k3).
        reprojection_px: RMS reprojection error of calibrateCamera over all views [px].
        pnp_reprojection_px: RMS reprojection error of the flat (extrinsic) view [px].
        views_used: Views in which the board was found.
        views_total: Views rendered.
        focal_error_pct: (f_est - f_true) / f_true [%].
        principal_point_error_px: Distance between estimated and true principal points [px].
        position_error_mm: Distance between estimated and true camera centres [mm].
        angle_error_deg: Angle of the rotation between estimated and true orientations [deg].
        lens_error_px: Largest distance, over a grid of image points, between where the true
            and the estimated lens put the same ray [px] (0 for two ideal pinholes).
    """

    camera: CameraModel
    true_camera: CameraModel
    distortion: np.ndarray
    reprojection_px: float
    pnp_reprojection_px: float
    views_used: int
    views_total: int
    focal_error_pct: float
    principal_point_error_px: float
    position_error_mm: float
    angle_error_deg: float
    lens_error_px: float = 0.0

    def summary(self) -> dict[str, float | int]:
        """The scalar figures as a dict (for reports)."""
        return {
            "reprojection_px": self.reprojection_px,
            "pnp_reprojection_px": self.pnp_reprojection_px,
            "views_used": self.views_used,
            "views_total": self.views_total,
            "focal_error_pct": self.focal_error_pct,
            "principal_point_error_px": self.principal_point_error_px,
            "position_error_mm": self.position_error_mm,
            "angle_error_deg": self.angle_error_deg,
            "lens_error_px": self.lens_error_px,
        }


def find_corners(image: np.ndarray, cfg: CalibrationConfig) -> np.ndarray | None:
    """Inner corners in a view, (n, 2) [px], in `CalibrationTarget.corners` order (None: none)."""
    grey = cv2.cvtColor(image, cv2.COLOR_RGB2GRAY)
    nx, ny = cfg.squares
    pattern = (nx - 1, ny - 1)
    found, corners = cv2.findChessboardCorners(
        grey, pattern, flags=cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
    )
    if not found:
        return None
    w = cfg.subpix_window_px
    crit = (
        cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER,
        cfg.subpix_iterations,
        cfg.subpix_epsilon_px,
    )
    corners = cv2.cornerSubPix(grey, corners, (w, w), (-1, -1), crit).reshape(-1, 2)
    grid = corners.reshape(ny - 1, nx - 1, 2)
    if grid.shape != (ny - 1, nx - 1, 2):
        return None
    return _orient(grid, grey)


def _orient(grid: np.ndarray, grey: np.ndarray) -> np.ndarray | None:
    """Put detected corners, shape (rows, cols, 2), into `CalibrationTarget.corners` order, (n, 2).

    The colour of the square beyond the first corner fixes the x direction (the board's
    corner squares differ in colour along x, not along y); the y direction follows from
    handedness: the camera sees the board's top face, and image axes (u right, v down) are a
    mirror of a view from above, so x cross y must be negative in pixel coordinates.
    """
    probe = grid[0, 0] - 0.5 * (grid[0, 1] - grid[0, 0]) - 0.5 * (grid[1, 0] - grid[0, 0])
    u, v = int(round(probe[0])), int(round(probe[1]))
    if not (0 <= v < grey.shape[0] and 0 <= u < grey.shape[1]):
        return None
    if grey[v, u] >= _DARK_LEVEL:
        grid = grid[:, ::-1]
    dx = grid[0, 1] - grid[0, 0]
    dy = grid[1, 0] - grid[0, 0]
    if dx[0] * dy[1] - dx[1] * dy[0] > 0:
        grid = grid[::-1]
    return np.ascontiguousarray(grid).reshape(-1, 2)


def _rotation_angle_deg(r: np.ndarray) -> float:
    c = (np.trace(r) - 1.0) / 2.0
    return math.degrees(math.acos(float(np.clip(c, -1.0, 1.0))))


def calibrate(views: CalibrationViews, cfg: CalibrationConfig | None = None) -> CalibrationResult:
    """Estimate the camera from rendered views and compare it with the true one.

    Raises:
        CalibrationError: Too few views with the board found, the flat view not found, or a
            reprojection error above ``max_reprojection_px``.
    """
    cfg = cfg or CalibrationConfig()
    true = views.true_camera
    obj = cfg.target.corners().astype(np.float32)
    img_pts, obj_pts = [], []
    for image in (*views.intrinsic, views.flat):
        c = find_corners(image, cfg)
        if c is not None:
            img_pts.append(c.astype(np.float32))
            obj_pts.append(obj)
    if len(img_pts) < cfg.min_views:
        raise CalibrationError(
            f"board found in {len(img_pts)} of {len(views.intrinsic) + 1} views; need at least "
            f"{cfg.min_views} (check the board size against the camera's view)"
        )
    flags = 0
    if cfg.fix_aspect_ratio:
        flags |= cv2.CALIB_FIX_ASPECT_RATIO
    if cfg.zero_tangential:
        flags |= cv2.CALIB_ZERO_TANGENT_DIST
    if cfg.fix_k3:
        flags |= cv2.CALIB_FIX_K3
    size = (true.width, true.height)
    rms, k, dist, _, _ = cv2.calibrateCamera(obj_pts, img_pts, size, np.eye(3), None, flags=flags)
    if not rms <= cfg.max_reprojection_px:
        raise CalibrationError(
            f"reprojection error {rms:.3f} px above the limit {cfg.max_reprojection_px} px"
        )
    flat = find_corners(views.flat, cfg)
    if flat is None:
        raise CalibrationError("the flat (extrinsic) view of the board was not found")
    world = cfg.target.corners() + views.flat_pose
    ok, rvec, tvec = cv2.solvePnP(world, flat.astype(np.float64), k, dist)
    if not ok:
        raise CalibrationError("solvePnP failed on the flat view")
    proj, _ = cv2.projectPoints(world, rvec, tvec, k, dist)
    pnp_rms = float(np.sqrt(np.mean(np.sum((proj.reshape(-1, 2) - flat) ** 2, axis=1))))
    r, _ = cv2.Rodrigues(rvec)
    t = np.eye(4)
    t[:3, :3] = r
    t[:3, 3] = tvec.ravel()
    dist_est = np.asarray(dist, dtype=float).ravel()
    est = CameraModel(true.name, true.width, true.height, np.asarray(k, dtype=float), t, dist_est)
    centre_est = -r.T @ tvec.ravel()
    r_true = true.world_to_camera[:3, :3]
    centre_true = -r_true.T @ true.world_to_camera[:3, 3]
    return CalibrationResult(
        camera=est,
        true_camera=true,
        distortion=dist_est,
        reprojection_px=float(rms),
        pnp_reprojection_px=pnp_rms,
        views_used=len(img_pts),
        views_total=len(views.intrinsic) + 1,
        focal_error_pct=100.0 * (float(k[1, 1]) - float(true.K[1, 1])) / float(true.K[1, 1]),
        principal_point_error_px=float(np.linalg.norm(k[:2, 2] - true.K[:2, 2])),
        position_error_mm=1e3 * float(np.linalg.norm(centre_est - centre_true)),
        angle_error_deg=_rotation_angle_deg(r @ r_true.T),
        lens_error_px=_lens_error_px(true, est, cfg.lens_grid),
    )


def _lens_error_px(true: CameraModel, est: CameraModel, grid: int) -> float:
    """Largest pixel gap between two lenses over a grid x grid of image points [px].

    Each grid pixel of the true camera is taken back to its ray (through the true lens) and
    projected again through the estimated intrinsics and lens.
    """
    u, v = np.meshgrid(np.linspace(0, true.width - 1, grid), np.linspace(0, true.height - 1, grid))
    uv = np.column_stack([u.ravel(), v.ravel()]).reshape(-1, 1, 2)
    rays = cv2.undistortPoints(uv, true.K, true.distortion).reshape(-1, 2)
    again = distort_normalised(rays, est.distortion) @ est.K[:2, :2].T + est.K[:2, 2]
    return float(np.max(np.linalg.norm(again - uv.reshape(-1, 2), axis=1)))


def calibrate_env_camera(
    env: gym.Env[Any, Any],
    camera: str,
    cfg: CalibrationConfig | None = None,
    size: tuple[int, int] | None = None,
) -> CalibrationResult:
    """Calibrate one camera of a `MosaicAssembly-v0` env from the pictures the env takes.

    The pictures come through Gymnasium's public API
    (``env.get_wrapper_attr("calibration_views")``); the solve is `calibrate`.

    Args:
        env: The env (wrapped or not).
        camera: "input_camera" or "output_camera".
        cfg: Board, poses and solver options.
        size: Image (height, width) [px] the camera will be used at (configured when None).

    Raises:
        CalibrationError: Unknown camera, or see `calibrate`.
    """
    cfg = cfg or CalibrationConfig()
    try:
        views = env.get_wrapper_attr("calibration_views")(camera, cfg.target, size)
    except CellError as exc:
        raise CalibrationError(str(exc)) from exc
    return calibrate(views, cfg)


__all__ = [
    "CalibrationResult",
    "calibrate",
    "calibrate_env_camera",
    "find_corners",
]
