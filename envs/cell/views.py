"""The cell's cameras as the cell uses them: pinhole models and pictures, blur on a moving belt.

`CellViews` holds the cell's `CameraRig` (renderers opened lazily, lenses from the camera
configs) and the input camera's motion blur (`envs.cell.camera_effects.BeltBlur`), remade when
the image size or the camera's pose changes.
"""

from __future__ import annotations

import functools
from collections.abc import Callable

import mujoco
import numpy as np

from envs.cell.belts import input_speed
from envs.cell.calibration_board import (
    CalibrationTarget,
    CalibrationViews,
    render_calibration_views,
)
from envs.cell.camera_effects import BeltBlur
from envs.cell.cameras import CameraModel, CameraRig, camera_model
from envs.cell.config import CameraConfig, CellConfig
from envs.cell.geometry import CellGeometry
from envs.cell.scene import SceneIds
from envs.errors import CellError

CAMERAS = ("input_camera", "output_camera")
"""Names of the observation cameras."""
BELT_DIRECTION = np.array([1.0, 0.0, 0.0])
"""Direction of travel of the input belt in the world."""


class CellViews:
    """Pictures and camera models of one cell.

    Args:
        model: The compiled cell.
        cfg: Its configuration (cameras, render settings, input belt).
        ids: Its ids (cameras and the input belt's geom are read).
        geometry: Where its parts are.
    """

    def __init__(
        self, model: mujoco.MjModel, cfg: CellConfig, ids: SceneIds, geometry: CellGeometry
    ) -> None:
        self.model, self.cfg, self.ids, self.geometry = model, cfg, ids, geometry
        self.rig = CameraRig(  # renderers open lazily; lenses from the camera configs
            model, cfg.render, {CAMERAS[0]: cfg.input_camera, CAMERAS[1]: cfg.output_camera}
        )
        self._blurs: dict[tuple[object, ...], BeltBlur] = {}

    def camera_config(self, name: str) -> CameraConfig:
        """The configuration of ``input_camera`` or ``output_camera``.

        Raises:
            CellError: Unknown camera.
        """
        if name == CAMERAS[0]:
            return self.cfg.input_camera
        if name == CAMERAS[1]:
            return self.cfg.output_camera
        raise CellError(f"unknown camera {name!r}; allowed: {list(CAMERAS)}")

    def camera_model(
        self, data: mujoco.MjData, name: str, height: int | None, width: int | None
    ) -> CameraModel:
        """Intrinsics/extrinsics of an observation camera at an image size (configured: None).

        Raises:
            CellError: Unknown camera.
        """
        cam_cfg = self.camera_config(name)
        cid = self.ids.input_camera if name == CAMERAS[0] else self.ids.output_camera
        return camera_model(
            self.model,
            data,
            cid,
            width or cam_cfg.width,
            height or cam_cfg.height,
            distortion=cam_cfg.distortion,
        )

    def calibration_views(
        self,
        camera: str,
        target: CalibrationTarget | None = None,
        size: tuple[int, int] | None = None,
    ) -> CalibrationViews:
        """Pictures of a checkerboard target before one camera, for calibrating it.

        What a real cell's calibration takes (`envs.cell.calibration_board`): the board at
        several tilted, lifted and shifted poses, then lying flat at its fixture position,
        rendered through the camera's lens in a copy of the cell's scene without tiles (the
        cell's state is not touched).

        Args:
            camera: ``"input_camera"`` or ``"output_camera"``.
            target: Board and poses (defaults when None).
            size: Image (height, width) [px]; the camera's configured size when None.

        Raises:
            CellError: Unknown camera (the message lists the allowed names).
        """
        return render_calibration_views(self.cfg, camera, target, size, self.geometry)

    def belt_blur(
        self, data: mujoco.MjData, height: int, width: int
    ) -> Callable[[np.ndarray], np.ndarray] | None:
        """The input camera's motion blur at the belt's current speed (None: a still picture)."""
        exposure = self.cfg.input_camera.exposure_time
        if exposure <= 0.0:
            return None
        speed = input_speed(self.model, self.ids)
        if speed <= 0.0:
            return None
        cid = self.ids.input_camera
        key = (height, width, *self.model.cam_pos[cid], *self.model.cam_quat[cid])
        blur = self._blurs.get(key)
        if blur is None:
            pinhole = camera_model(self.model, data, cid, width, height)
            blur = BeltBlur(pinhole, self._belt_corners(), BELT_DIRECTION)
            self._blurs = {key: blur}  # one pose at a time (a jittered camera moves per reset)
        return functools.partial(blur.apply, speed=speed, exposure_time=exposure)

    def _belt_corners(self) -> np.ndarray:
        """The input belt's top face, shape (4, 3) [m], in order around it."""
        g, belt = self.geometry, self.cfg.input_belt
        x0, x1 = g.input_belt_end - belt.length, g.input_belt_end
        y0, y1 = g.input_y - belt.width / 2, g.input_y + belt.width / 2
        return np.array(
            [
                [x0, y0, g.belt_top],
                [x1, y0, g.belt_top],
                [x1, y1, g.belt_top],
                [x0, y1, g.belt_top],
            ]
        )

    def render(
        self,
        data: mujoco.MjData,
        name: str,
        height: int | None,
        width: int | None,
        *,
        depth: bool = False,
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """Render ``input_camera``, ``output_camera`` or ``overview`` (see `Cell.render`)."""
        if name == "overview":
            h, w = self.cfg.render.overview_size
            return self.rig.render(data, "overview", height or h, width or w, depth=depth, out=out)
        cam_cfg = self.camera_config(name)
        h, w = height or cam_cfg.height, width or cam_cfg.width
        blur = self.belt_blur(data, h, w) if name == CAMERAS[0] and not depth else None
        return self.rig.render(data, name, h, w, depth=depth, out=out, effect=blur)

    def close(self) -> None:
        """Free the renderers."""
        self.rig.close()


__all__ = ["BELT_DIRECTION", "CAMERAS", "CellViews"]
