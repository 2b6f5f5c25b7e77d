"""View culling: leave out of a camera's scene the geoms that cannot show in its image.

A software (Mesa llvmpipe) renderer pays for every geom it is given, seen or not: the floor
plane under the belts, the other belt, the bin and the arm out of view cost about as much as
what the camera sees. For a model camera (`ViewCuller.hidden`):

- a geom whose bounding sphere lies wholly outside the view frustum is left out (every
  sample of the image, multisampled or not, lies inside the frustum);
- a static geom (welded to the world) that shows in no pixel of a segmentation image at
  `PROBE_SCALE` times the image size, drawn without the moving bodies, is left out: other
  static geoms hide it, and moving bodies can only hide more of it. The probe is redone when
  the camera's pose changes; cameras on moving bodies, and images too large for a probe
  (beyond the offscreen buffer), get the frustum test only.

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
SCENE_SPARE = 100
"""Scene slots beyond the model's geoms (decorations) in the probe's scene."""


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
        self._scene: mujoco.MjvScene | None = None

    def hidden(self, renderer: mujoco.Renderer, data: mujoco.MjData, camera: int) -> np.ndarray:
        """Geoms that cannot show in ``camera``'s image by ``renderer`` now, shape (ngeom,).

        Args:
            renderer: The renderer of the image (its size; it draws the probes).
            data: The state to render (positions up to date, as for rendering).
            camera: Model camera id.
        """
        height, width = renderer.height, renderer.width
        out = self._outside(data, camera, width / height)
        if self._model.body_weldid[self._model.cam_bodyid[camera]] != 0:
            return out  # a camera on a moving body: no probe (it would be redone every frame)
        pose = np.concatenate([data.cam_xpos[camera], data.cam_xmat[camera]])
        key = (camera, height, width)
        probe = self._probes.get(key)
        if probe is None or not np.array_equal(probe.pose, pose):
            probe = _Probe(pose, self._probe(renderer, data, camera, height, width))
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

    def _probe(
        self, renderer: mujoco.Renderer, data: mujoco.MjData, camera: int, height: int, width: int
    ) -> np.ndarray:
        """Static geoms in no pixel of a fine segmentation image without moving bodies.

        Drawn with ``renderer``'s own GL context into its offscreen buffer (no second context,
        no extra memory); its next `render` draws its whole image afresh.
        """
        m = self._model
        size = (PROBE_SCALE * height, PROBE_SCALE * width)
        if size[0] > m.vis.global_.offheight or size[1] > m.vis.global_.offwidth:
            return np.zeros(m.ngeom, bool)  # no probe finer than the image: frustum only
        if self._scene is None:
            self._scene = mujoco.MjvScene(m, maxgeom=m.ngeom + SCENE_SPARE)
        scene, view = self._scene, mujoco.MjvCamera()
        view.type = mujoco.mjtCamera.mjCAMERA_FIXED
        view.fixedcamid = camera
        alpha = m.geom_rgba[:, 3].copy()
        see_through = (alpha > 0) & (alpha < 1)  # they hide nothing behind them
        try:
            m.geom_rgba[~self._static | see_through, 3] = 0.0
            mujoco.mjv_updateScene(
                m, data, mujoco.MjvOption(), None, view, mujoco.mjtCatBit.mjCAT_ALL, scene
            )
        finally:
            m.geom_rgba[:, 3] = alpha
        scene.flags[mujoco.mjtRndFlag.mjRND_SEGMENT] = True
        scene.flags[mujoco.mjtRndFlag.mjRND_IDCOLOR] = True
        rect = mujoco.MjrRect(0, 0, size[1], size[0])
        context = renderer._mjr_context  # noqa: SLF001 - draw with the renderer's context
        if renderer._gl_context:  # noqa: SLF001
            renderer._gl_context.make_current()  # noqa: SLF001
        mujoco.mjr_render(rect, scene, context)
        rgb = np.empty((*size, 3), np.uint8)
        mujoco.mjr_readPixels(rgb, None, rect, context)
        segid = (
            rgb[..., 0] + (rgb[..., 1].astype(np.int64) << 8) + (rgb[..., 2].astype(np.int64) << 16)
        )
        shown = set(np.unique(segid).tolist())  # segment id + 1; 0 is the background
        seen = see_through.copy()
        for g in scene.geoms[: scene.ngeom]:
            if g.segid + 1 in shown and g.objtype == mujoco.mjtObj.mjOBJ_GEOM:
                seen[g.objid] = True
        return self._static & ~seen


__all__ = ["ViewCuller"]
