"""What varies a camera's picture beyond the lens: motion blur along the belt, pose jitter.

`BeltBlur` smears the belt's region of the input camera's picture by the belt's travel over an
exposure; `CameraJitter` draws camera poses per episode about the built ones (domain
randomisation). The pinhole model they use is `envs.cell.cameras.CameraModel`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import cv2
import mujoco
import numpy as np

from envs.cell.cameras import CameraModel

MIN_BLUR_PX = 0.05
"""Blur lengths below this [px] change no pixel level of a uint8 picture: skipped."""


class BeltBlur:
    """Motion blur of a moving belt: a directional blur of the belt's region of the picture.

    Every tile resting on the belt moves at exactly the belt speed (the belt carries it through
    ``geom_surfacevel``), and the belt, its rails and the tiles' shading do not change along
    the belt, so over an exposure the picture of the belt region is the render smeared along
    the belt's image direction by speed x exposure time: one `cv2.filter2D` with a line kernel
    instead of a dozen sub-frame renders (each ~10 ms at 656 x 492 in software rendering).
    The exposure is centred on the render time, so a blurred tile keeps its centroid. The
    belt's surroundings stay sharp; whatever is seen over the belt's region is smeared, so an
    arm passing through the view would be blurred as if it moved with the belt (the scripted
    cell takes its pictures with the arm out of the view).

    Args:
        model: Camera model of the ideal render (pinhole, at the image size).
        belt_corners: The belt's top face in the world, shape (4, 3) [m], in order around it.
        direction: The belt's direction of travel in the world, shape (3,).
    """

    def __init__(self, model: CameraModel, belt_corners: np.ndarray, direction: np.ndarray) -> None:
        pinhole = CameraModel(model.name, model.width, model.height, model.K, model.world_to_camera)
        corners = pinhole.project(belt_corners)
        mask = np.zeros((model.height, model.width), np.uint8)
        cv2.fillPoly(mask, [np.round(corners).astype(np.int32)], 1)
        self.mask = mask.astype(bool)
        """Pixels showing the belt's top, shape (height, width)."""
        centre = belt_corners.mean(axis=0)
        a, b = pinhole.project(np.stack([centre, centre + np.asarray(direction, float)]))
        self.px_per_m = float(np.linalg.norm(b - a))
        """Image displacement per metre of belt travel near the belt's centre [px/m]."""
        self.unit = (b - a) / self.px_per_m

    def kernel(self, length_px: float) -> np.ndarray:
        """Line kernel of ``length_px`` along the belt's image direction (sums to 1)."""
        half = int(math.ceil(length_px / 2)) + 1
        size = 2 * half + 1
        ker = np.zeros((size, size), np.float32)
        steps = max(int(math.ceil(length_px * 4)), 1) + 1
        for s in np.linspace(-length_px / 2, length_px / 2, steps):
            x, y = half + s * self.unit[0], half + s * self.unit[1]
            x0, y0 = int(math.floor(x)), int(math.floor(y))
            fx, fy = x - x0, y - y0
            ker[y0, x0] += (1 - fx) * (1 - fy)
            ker[y0, x0 + 1] += fx * (1 - fy)
            ker[y0 + 1, x0] += (1 - fx) * fy
            ker[y0 + 1, x0 + 1] += fx * fy
        return ker / ker.sum()

    def apply(self, image: np.ndarray, speed: float, exposure_time: float) -> np.ndarray:
        """The picture taken over ``exposure_time`` [s] with the belt at ``speed`` [m/s]."""
        length = abs(speed) * exposure_time * self.px_per_m
        if length < MIN_BLUR_PX:
            return image
        blurred = cv2.filter2D(image, -1, self.kernel(length), borderType=cv2.BORDER_REPLICATE)
        return np.where(self.mask[..., None], blurred, image)


class CameraJitter:
    """Camera poses drawn per episode about the built ones (domain randomisation).

    Each camera is shifted by a uniform draw in [-position_bound, position_bound] per world
    axis and turned by a rotation vector drawn uniformly in [-angle_bound, angle_bound] per
    axis of its own frame. Images move with the camera; camera models published at build
    time keep the nominal pose (what a policy trained for robustness must not rely on).

    Args:
        model: The compiled cell (its ``cam_pos``, ``cam_quat`` are changed in place).
        cameras: Camera ids to move.
    """

    def __init__(self, model: mujoco.MjModel, cameras: Sequence[int]) -> None:
        self._model = model
        self.cameras = np.asarray(cameras, dtype=int)
        self.nominal_pos = model.cam_pos[self.cameras].copy()
        """Built positions, shape (k, 3) [m] (in each camera's parent frame)."""
        self.nominal_quat = model.cam_quat[self.cameras].copy()
        """Built orientations, shape (k, 4) (w, x, y, z)."""

    def draw(
        self,
        data: mujoco.MjData,
        rng: np.random.Generator,
        position_bound: float,
        angle_bound_deg: float,
    ) -> None:
        """Move every camera to a fresh pose within the bounds ([m], [deg]).

        The cameras' world poses in ``data`` are updated at once from their parent bodies:
        neither stepping nor `mujoco.mj_camlight` recomputes a camera fixed to a sleeping or
        static body.
        """
        k = len(self.cameras)
        shift = rng.uniform(-position_bound, position_bound, (k, 3))
        turn = np.radians(rng.uniform(-angle_bound_deg, angle_bound_deg, (k, 3)))
        for i, cam in enumerate(self.cameras):
            dq = np.zeros(4)
            mujoco.mju_axisAngle2Quat(
                dq, turn[i] / max(np.linalg.norm(turn[i]), 1e-300), float(np.linalg.norm(turn[i]))
            )
            q = np.zeros(4)
            mujoco.mju_mulQuat(q, self.nominal_quat[i], dq)
            self._model.cam_quat[cam] = q
            self._model.cam_pos[cam] = self.nominal_pos[i] + shift[i]
        self._update(data)

    def _update(self, data: mujoco.MjData) -> None:
        """World poses of the cameras (fixed to their parent bodies) into ``data``."""
        m = self._model
        for cam in self.cameras:
            body = int(m.cam_bodyid[cam])
            r_body = data.xmat[body].reshape(3, 3)
            r_cam = np.zeros(9)
            mujoco.mju_quat2Mat(r_cam, m.cam_quat[cam])
            data.cam_xpos[cam] = data.xpos[body] + r_body @ m.cam_pos[cam]
            data.cam_xmat[cam] = (r_body @ r_cam.reshape(3, 3)).ravel()

    def restore(self, data: mujoco.MjData) -> None:
        """Put every camera back at its built pose (in the model and in ``data``)."""
        self._model.cam_pos[self.cameras] = self.nominal_pos
        self._model.cam_quat[self.cameras] = self.nominal_quat
        self._update(data)


__all__ = ["MIN_BLUR_PX", "BeltBlur", "CameraJitter"]
