"""The tiles' height above the belt from a depth picture: the colour-free cue of perception.

A real line sees a tile whose glaze is the belt's colour (black on a dark belt) by another cue
than colour; here a 3D (depth) camera beside the colour camera, whose picture is the env's
``input_depth`` observation (``depth=True``), aligned pixel for pixel with ``input_camera``.
`HeightMap` turns it into the height above the belt plane in millimetres that
`qshape.extract_detailed` takes (``height``): per pixel, the depth at which that pixel's ray
meets the belt plane (through the camera model, lens included) minus the measured depth.
"""

from __future__ import annotations

import numpy as np

from envs.cell.cameras import CameraModel
from spatial.units import MM_PER_M


class HeightMap:
    """Height above a plane from depth pictures of one camera (the plane's depth cached).

    Args:
        camera: The camera model of the depth picture (calibrated or true).
        plane_z: World height of the belt's surface [m] (``TaskSpec.pick.surface_z``).
    """

    def __init__(self, camera: CameraModel, plane_z: float) -> None:
        self.camera, self.plane_z = camera, float(plane_z)
        self._plane: dict[tuple[int, int], np.ndarray] = {}

    def plane_depth(self, shape: tuple[int, int]) -> np.ndarray:
        """Depth [m] of the plane at every pixel of a (height, width) picture, float32."""
        if shape not in self._plane:
            h, w = shape
            cam = self.camera
            sx, sy = cam.width / w, cam.height / h  # a picture at another size than the model's
            v, u = np.mgrid[0:h, 0:w]
            uv = np.column_stack([(u.ravel() + 0.5) * sx - 0.5, (v.ravel() + 0.5) * sy - 0.5])
            pts = cam.unproject_to_plane(uv, self.plane_z)
            depth = pts @ cam.world_to_camera[2, :3] + cam.world_to_camera[2, 3]
            self._plane[shape] = depth.reshape(h, w).astype(np.float32)
        return self._plane[shape]

    def height_mm(self, depth: np.ndarray) -> np.ndarray:
        """Height above the plane [mm], float32 (H, W), of a depth picture [m] (H, W[, 1])."""
        d = np.asarray(depth, dtype=np.float32)
        if d.ndim == 3:  # noqa: PLR2004 - (H, W, 1) observation
            d = d[..., 0]
        return (self.plane_depth((d.shape[0], d.shape[1])) - d) * np.float32(MM_PER_M)


__all__ = ["HeightMap"]
