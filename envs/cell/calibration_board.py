"""Calibration pictures of the cell's cameras: a checkerboard target rendered at known poses.

A real cell calibrates its cameras from pictures of a checkerboard; the simulated cell takes
those pictures here, so an agent calibrates from images without knowing how the scene is made
(the env publishes them as an extra, ``env.get_wrapper_attr("calibration_views")``, which is
`envs.cell.views.CellViews.calibration_views`).

The target (a white plate with black square tiles, one mocap body) is added to the cell's own
scene (`envs.cell.scene.build_spec`, so the camera's configuration and pose are exactly the
cell's) and rendered by one camera through its lens at several tilted, lifted and shifted poses,
then once lying flat on the belt (or mesh) at its fixture position: the view that fixes the
extrinsics. The board has an even by odd count of squares so its colour pattern is not
symmetric under a half turn; the square at its corner -x, -y is black.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from envs.cell.cameras import CameraModel, CameraRig, camera_model
from envs.cell.config import CellConfig
from envs.cell.scene import CellGeometry, build_spec, cell_geometry
from envs.errors import CellError

BOARD = "calibration_board"
"""Name of the target's mocap body."""

_WHITE = (0.92, 0.92, 0.92, 1.0)
_BLACK = (0.04, 0.04, 0.04, 1.0)
_YAW_STEP_DEG = 10.0
"""In-plane turn between consecutive intrinsic views [deg]."""


@dataclass(frozen=True)
class CalibrationTarget:
    """The checkerboard and the poses it is pictured at.

    Attributes:
        squares: Squares of the board along its x and y, (nx, ny); inner corners are one less.
        square_size: Side of one square [m].
        border: White margin around the squares [m].
        plate_thickness: Thickness of the white plate [m].
        square_height: Height of the black squares above the plate [m].
        tilts_deg: Board tilts of the intrinsic views [deg] (about x and y in turn).
        lift: Heights of the board's top above the surface for the intrinsic views [m]
            (cycled).
        shifts: In-plane offsets (x, y) of the board centre for the intrinsic views [m]
            (cycled).
    """

    squares: tuple[int, int] = (10, 7)
    square_size: float = 0.016
    border: float = 0.012
    plate_thickness: float = 0.003
    square_height: float = 0.0002
    tilts_deg: tuple[float, ...] = (0.0, 20.0, -20.0, 30.0, -30.0, 15.0, -15.0, 25.0)
    lift: tuple[float, ...] = (0.02, 0.05, 0.08)
    shifts: tuple[tuple[float, float], ...] = ((0.0, 0.0), (0.02, -0.015), (-0.02, 0.015))

    def corners(self) -> np.ndarray:
        """Inner corners in the board frame (origin at the board centre, on its top), (n, 3) [m].

        Ordered as OpenCV reports them: along the board's x first, then y.
        """
        nx, ny = self.squares
        s = self.square_size
        i, j = np.meshgrid(np.arange(1, nx), np.arange(1, ny))
        x = i.ravel() * s - nx * s / 2
        y = j.ravel() * s - ny * s / 2
        return np.column_stack([x, y, np.zeros_like(x)])


@dataclass(frozen=True, eq=False)
class CalibrationViews:
    """Rendered calibration pictures of one camera.

    Attributes:
        intrinsic: RGB images of the tilted board, each (h, w, 3) uint8.
        flat: RGB image of the board lying flat at its fixture pose.
        flat_pose: World position of the flat board's frame (3,) [m] (its yaw is 0).
        true_camera: The simulator's camera model (for comparing an estimate with, only).
    """

    intrinsic: tuple[np.ndarray, ...]
    flat: np.ndarray
    flat_pose: np.ndarray
    true_camera: CameraModel


def add_board(spec: mujoco.MjSpec, target: CalibrationTarget) -> None:
    """Add the checkerboard (white plate + black squares) as a mocap body to a scene spec.

    The body frame is at the centre of the plate's top face; black squares sit on it and the
    square at the corner -x, -y is black.
    """
    nx, ny = target.squares
    s = target.square_size
    body = spec.worldbody.add_body(name=BOARD, mocap=True)
    half = [nx * s / 2 + target.border, ny * s / 2 + target.border, target.plate_thickness / 2]
    plate = body.add_geom(
        type=mujoco.mjtGeom.mjGEOM_BOX, size=half, pos=[0, 0, -target.plate_thickness / 2]
    )
    plate.rgba = _WHITE
    plate.contype = plate.conaffinity = 0
    h = target.square_height / 2
    for ix in range(nx):
        for iy in range(ny):
            if (ix + iy) % 2:
                continue
            g = body.add_geom(
                type=mujoco.mjtGeom.mjGEOM_BOX,
                size=[s / 2, s / 2, h],
                pos=[(ix + 0.5) * s - nx * s / 2, (iy + 0.5) * s - ny * s / 2, h],
            )
            g.rgba = _BLACK
            g.contype = g.conaffinity = 0


def _quat(rx: float, ry: float, rz: float) -> np.ndarray:
    """Quaternion (w, x, y, z) of rotations about x, then y, then z (extrinsic) [rad]."""
    cx, sx, cy, sy, cz, sz = (
        math.cos(rx), math.sin(rx), math.cos(ry), math.sin(ry), math.cos(rz), math.sin(rz)
    )  # fmt: skip
    rot_x = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    rot_y = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rot_z = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, (rot_z @ rot_y @ rot_x).ravel())
    return q


def intrinsic_poses(
    target: CalibrationTarget, centre: np.ndarray
) -> list[tuple[np.ndarray, np.ndarray]]:
    """Board poses (position (3,) [m], quaternion (4,)) of the intrinsic views over ``centre``."""
    poses = []
    top = target.plate_thickness + target.square_height
    count = len(target.tilts_deg)
    for k, tilt in enumerate(target.tilts_deg):
        about_x = k % 2 == 0
        t = math.radians(tilt)
        yaw = math.radians(_YAW_STEP_DEG * (k - count / 2))  # varied in-plane turn
        quat = _quat(t if about_x else 0.0, 0.0 if about_x else t, yaw)
        dx, dy = target.shifts[k % len(target.shifts)]
        pos = centre + [dx, dy, target.lift[k % len(target.lift)] + top]
        poses.append((pos, quat))
    return poses


def render_calibration_views(
    cell_cfg: CellConfig,
    camera: str,
    target: CalibrationTarget | None = None,
    size: tuple[int, int] | None = None,
    geometry: CellGeometry | None = None,
) -> CalibrationViews:
    """Render the board at the calibration poses with one of the cell's cameras.

    Args:
        cell_cfg: The cell configuration (the scene is the cell's, without tiles).
        camera: ``"input_camera"`` or ``"output_camera"``.
        target: Board and poses (defaults when None).
        size: Image (height, width) [px]; the camera's configured size when None.
        geometry: The cell's geometry (its mesh sets the output camera's height); None:
            the configuration's largest mesh.

    Raises:
        CellError: Unknown camera.
    """
    target = target or CalibrationTarget()
    cams = {"input_camera": cell_cfg.input_camera, "output_camera": cell_cfg.output_camera}
    if camera not in cams:
        raise CellError(f"unknown camera {camera!r}; allowed: {sorted(cams)}")
    cam_cfg = cams[camera]
    height, width = size if size is not None else (cam_cfg.height, cam_cfg.width)
    geo = geometry or cell_geometry(cell_cfg)
    if camera == "input_camera":
        centre = np.array([geo.input_centre[0], geo.input_centre[1], geo.belt_top])
    else:
        centre = np.array([geo.output_centre[0], geo.output_centre[1], geo.mesh_top])
    spec = build_spec(cell_cfg, geometry=geo)
    add_board(spec, target)
    model = spec.compile()
    data = mujoco.MjData(model)
    mocap = int(model.body_mocapid[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, BOARD)])
    cam_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, camera)
    rig = CameraRig(model, cell_cfg.render, {camera: cam_cfg})  # through the camera's lens
    try:

        def shot(pos: np.ndarray, quat: np.ndarray) -> np.ndarray:
            data.mocap_pos[mocap] = pos
            data.mocap_quat[mocap] = quat
            mujoco.mj_forward(model, data)
            return rig.render(data, cam_id, height, width).copy()

        views = [shot(pos, quat) for pos, quat in intrinsic_poses(target, centre)]
        flat_pose = centre + [0.0, 0.0, target.plate_thickness + target.square_height]
        flat = shot(flat_pose, np.array([1.0, 0.0, 0.0, 0.0]))
        mujoco.mj_forward(model, data)
        true_cam = camera_model(model, data, cam_id, width, height, distortion=cam_cfg.distortion)
    finally:
        rig.close()
    return CalibrationViews(tuple(views), flat, flat_pose, true_cam)


__all__ = [
    "BOARD",
    "CalibrationTarget",
    "CalibrationViews",
    "add_board",
    "intrinsic_poses",
    "render_calibration_views",
]
