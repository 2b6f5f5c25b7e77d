"""View culling: leave out of a camera's scene the geoms that cannot show in its image.

A software (Mesa llvmpipe) renderer pays for every geom it is given, seen or not: the floor
plane under the belts, the other belt, the bin and the arm out of view cost about as much as
what the camera sees. For a fixed model camera (`ViewCuller.hidden`):

- a geom whose bounding sphere lies wholly outside the view frustum is left out (every
  sample of the image, multisampled or not, lies inside the frustum);
- a static geom (welded to the world) that shows in no pixel of a segmentation image at
  `PROBE_SCALE` times the image size with every moving body removed is left out: only moving
  bodies could uncover it and they are rendered in front, never removed from between. The probe
  is redone when the camera's pose changes. Images too large for such a probe (beyond the
  offscreen buffer) get the frustum test only.

The image is the same, pixel for pixel (tested), at a fraction of the rendering time.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

PROBE_SCALE = 4
"""Segmentation probe resolution / image resolution (finer than the 4x multisampling grid)."""
MARGIN = 1e-3
"""Extra radius [m] given to every bounding sphere (rounding in the frustum test)."""


@dataclass(frozen=True)
class _Probe:
    """Static geoms a camera cannot see, from one segmentation image.

    Attributes:
        pose: The camera's position (3,) and rotation matrix (9,) when probed, shape (12,).
        hidden: Static geoms not in the image, shape (ngeom,) bool.
    """

    pose: np.ndarray
    hidden: np.ndarray


class ViewCuller:
    """Which geoms a model camera cannot see.

    Args:
        model: The compiled model (read at every call: alpha, bounding radii).
    """

    def __init__(self, model: mujoco.MjModel) -> None:
        self._model = model
        body_static = model.body_weldid == 0
        self._static = body_static[model.geom_bodyid]
        self._probes: dict[tuple[int, int, int], _Probe] = {}
        self._probe_renderers: dict[tuple[int, int], mujoco.Renderer] = {}

    def hidden(self, data: mujoco.MjData, camera: int, height: int, width: int) -> np.ndarray:
        """Geoms that cannot show in ``camera``'s (height x width) image now, shape (ngeom,).

        Args:
            data: The state to render (positions up to date, as for rendering).
            camera: Model camera id.
            height: Image height [px].
            width: Image width [px].
        """
        out = self._outside(data, camera, width / height)
        pose = np.concatenate([data.cam_xpos[camera], data.cam_xmat[camera]])
        key = (camera, height, width)
        probe = self._probes.get(key)
        if probe is None or not np.array_equal(probe.pose, pose):
            probe = _Probe(pose, self._probe(data, camera, height, width))
            self._probes[key] = probe
        return out | probe.hidden

    def _outside(self, data: mujoco.MjData, camera: int, aspect: float) -> np.ndarray:
        """Geoms whose bounding sphere is wholly outside the camera's frustum (ngeom,) bool."""
        m = self._model
        rot = data.cam_xmat[camera].reshape(3, 3)
        p = (data.geom_xpos - data.cam_xpos[camera]) @ rot  # camera frame: looks along -z
        depth = -p[:, 2]
        r = m.geom_rbound + MARGIN
        tan_y = np.tan(np.radians(m.cam_fovy[camera]) / 2)
        tan_x = tan_y * aspect
        cy, sy = 1 / np.hypot(1, tan_y), tan_y / np.hypot(1, tan_y)
        cx, sx = 1 / np.hypot(1, tan_x), tan_x / np.hypot(1, tan_x)
        outside = (np.abs(p[:, 0]) * cx - depth * sx > r) | (np.abs(p[:, 1]) * cy - depth * sy > r)
        outside |= depth < -r
        return outside & (m.geom_rbound > 0)  # planes (radius 0) are unbounded

    def _probe(self, data: mujoco.MjData, camera: int, height: int, width: int) -> np.ndarray:
        """Static geoms in no pixel of a fine segmentation image without moving bodies."""
        m = self._model
        size = (PROBE_SCALE * height, PROBE_SCALE * width)
        if size[0] > m.vis.global_.offheight or size[1] > m.vis.global_.offwidth:
            return np.zeros(m.ngeom, bool)  # no probe finer than the image: frustum only
        r = self._probe_renderers.get(size)
        if r is None:
            r = mujoco.Renderer(m, *size)
            r.enable_segmentation_rendering()
            self._probe_renderers[size] = r
        alpha = m.geom_rgba[:, 3].copy()
        see_through = (alpha > 0) & (alpha < 1)  # they hide nothing behind them
        try:
            m.geom_rgba[~self._static | see_through, 3] = 0.0
            r.update_scene(data, camera=camera)
        finally:
            m.geom_rgba[:, 3] = alpha
        seg = r.render()
        geoms = seg[..., 0][seg[..., 1] == mujoco.mjtObj.mjOBJ_GEOM]
        seen = see_through.copy()
        seen[geoms[geoms >= 0]] = True
        return self._static & ~seen

    def close(self) -> None:
        """Free the probe renderers (safe to call twice)."""
        for r in self._probe_renderers.values():
            r.close()
        self._probe_renderers.clear()


__all__ = ["ViewCuller"]
