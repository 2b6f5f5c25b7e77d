"""Pinhole models of the cell's cameras and reusable renderers.

Pixel convention (OpenCV): u to the right, v down, pixel centres at integer coordinates, so
pixel ``image[row, col]`` is centred at ``(u, v) = (col, row)``. Camera frame (OpenCV): x right,
y down, z forward (along the view).

Renderers a program leaves open (an env never closed) are freed at interpreter exit by an
`atexit` hook, before EGL terminates and before module teardown (where freeing them prints
"Exception ignored ... TypeError: 'NoneType' object is not callable").
"""

from __future__ import annotations

import atexit
import functools
import math
import os
import weakref
from dataclasses import dataclass

import mujoco
import numpy as np

from envs.cell_config import RenderConfig
from envs.errors import CellError
from envs.view_culling import ViewCuller

# MuJoCo cameras look along their -z with +y up; OpenCV's look along +z with +y down.
_MJ_TO_CV = np.diag([1.0, -1.0, -1.0])


@dataclass(frozen=True, eq=False)
class CameraModel:
    """Intrinsics and extrinsics of one camera.

    Attributes:
        name: Camera name in the model.
        width: Image width [px].
        height: Image height [px].
        K: Intrinsic matrix, shape (3, 3) [px].
        world_to_camera: Extrinsic transform, shape (4, 4): camera = T @ world (OpenCV frame).
    """

    name: str
    width: int
    height: int
    K: np.ndarray
    world_to_camera: np.ndarray

    def project(self, points_world: np.ndarray) -> np.ndarray:
        """Project world points to pixels.

        Args:
            points_world: Shape (n, 3) or (3,) [m].

        Returns:
            Pixel coordinates (u, v), shape (n, 2) or (2,) [px].
        """
        pts = np.asarray(points_world, dtype=float)
        single = pts.ndim == 1
        pts = np.atleast_2d(pts)
        cam = pts @ self.world_to_camera[:3, :3].T + self.world_to_camera[:3, 3]
        uvw = cam @ self.K.T
        uv = uvw[:, :2] / uvw[:, 2:3]
        return uv[0] if single else uv

    def unproject_to_plane(self, uv: np.ndarray, z: float) -> np.ndarray:
        """World points on the horizontal plane at height z seen at pixels uv.

        Args:
            uv: Pixel coordinates, shape (n, 2) [px].
            z: Plane height [m].

        Returns:
            World points, shape (n, 3) [m].
        """
        uv = np.atleast_2d(np.asarray(uv, dtype=float))
        rays_cam = np.column_stack([uv, np.ones(len(uv))]) @ np.linalg.inv(self.K).T
        r = self.world_to_camera[:3, :3]
        origin = -r.T @ self.world_to_camera[:3, 3]
        rays = rays_cam @ r  # camera -> world directions
        s = (z - origin[2]) / rays[:, 2]
        return origin + s[:, None] * rays


def camera_model(
    model: mujoco.MjModel, data: mujoco.MjData, camera: int, width: int, height: int
) -> CameraModel:
    """Pinhole model of a MuJoCo camera at an image size (square pixels, centred)."""
    fy = (height / 2) / math.tan(math.radians(model.cam_fovy[camera]) / 2)
    k = np.array([[fy, 0.0, width / 2 - 0.5], [0.0, fy, height / 2 - 0.5], [0.0, 0.0, 1.0]])
    r_wc = data.cam_xmat[camera].reshape(3, 3)  # camera axes in world (MuJoCo convention)
    r = _MJ_TO_CV @ r_wc.T
    t = np.eye(4)
    t[:3, :3] = r
    t[:3, 3] = -r @ data.cam_xpos[camera]
    name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_CAMERA, camera) or str(camera)
    return CameraModel(name, width, height, k, t)


_OPEN_RIGS: weakref.WeakSet[CameraRig] = weakref.WeakSet()
"""Rigs holding renderers (weak references: a rig that is collected frees its own)."""


def _close_open_rigs() -> None:
    """Free every open rig's renderers (run at interpreter exit)."""
    for rig in list(_OPEN_RIGS):
        rig.close()


@functools.cache
def _close_at_exit() -> None:
    """Register `_close_open_rigs` with atexit, once, after the first renderer is made.

    atexit runs hooks last-in first-out, and MuJoCo's EGL backend registers its
    ``eglTerminate`` when it makes its first context: registered after it, the hook runs first.
    """
    atexit.register(_close_open_rigs)


_GL_PID: list[int] = []
"""Id of the process that created the first renderer (its GL state does not survive fork)."""


def _check_not_forked() -> None:
    """Raise `CellError` in a forked child of a process that rendered (EGL would hang there).

    Records the current process the first time a renderer is made.
    """
    if not _GL_PID:
        _GL_PID.append(os.getpid())
    elif _GL_PID[0] != os.getpid():
        raise CellError(
            "this process was forked from one that had rendered already; its GL state does not "
            "survive fork (EGL hangs): start workers with the 'spawn' method, e.g. "
            "gym.make_vec(..., vectorization_mode='async', vector_kwargs={'context': 'spawn'}) "
            "or SubprocVecEnv(..., start_method='spawn')"
        )


class CameraRig:
    """Renders named cameras with one `mujoco.Renderer` per image size (reused).

    Args:
        model: The compiled cell.
        cfg: Render options (shadows, reflections).
    """

    def __init__(self, model: mujoco.MjModel, cfg: RenderConfig) -> None:
        self._model = model
        self._cfg = cfg
        self._renderers: dict[tuple[int, int], mujoco.Renderer] = {}
        self._depth: dict[tuple[int, int], mujoco.Renderer] = {}
        self._culler = ViewCuller(model)
        self._camera_ids: dict[str, int] = {}
        self._closed = False

    def _renderer(self, height: int, width: int, depth: bool) -> mujoco.Renderer:
        if self._closed:
            raise CellError("the camera rig is closed")
        pool = self._depth if depth else self._renderers
        key = (height, width)
        r = pool.get(key)
        _check_not_forked()
        if r is None:
            r = mujoco.Renderer(self._model, height, width)
            r.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = self._cfg.shadows
            r.scene.flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = self._cfg.reflections
            if depth:
                r.enable_depth_rendering()
            pool[key] = r
            _OPEN_RIGS.add(self)
            _close_at_exit()
        return r

    def render(
        self,
        data: mujoco.MjData,
        camera: int | str | mujoco.MjvCamera,
        height: int,
        width: int,
        *,
        depth: bool = False,
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """Render one view.

        Args:
            data: State to render.
            camera: Camera id, name, or a free `MjvCamera`.
            height: Image height [px].
            width: Image width [px].
            depth: Depth image [m] instead of RGB.
            out: Optional preallocated output, shape (height, width, 3) uint8 or
                (height, width) float32 for depth.

        Returns:
            RGB uint8 (height, width, 3) or depth float32 (height, width) [m].
        """
        r = self._renderer(height, width, depth)
        cam = self._camera_id(camera)
        if cam is None or not self._cfg.cull:
            r.update_scene(data, camera=camera)
            return r.render(out=out)
        rgba = self._model.geom_rgba
        alpha = rgba[:, 3].copy()
        try:  # geoms it cannot see are left out of the scene (`envs.view_culling`)
            rgba[self._culler.hidden(r, data, cam), 3] = 0.0
            r.update_scene(data, camera=camera)
        finally:
            rgba[:, 3] = alpha
        return r.render(out=out)

    def _camera_id(self, camera: int | str | mujoco.MjvCamera) -> int | None:
        """Model camera id of a name or id; None for a free camera."""
        if isinstance(camera, mujoco.MjvCamera):
            return None
        if isinstance(camera, str):
            cam = self._camera_ids.get(camera)
            if cam is None:
                cam = mujoco.mj_name2id(self._model, mujoco.mjtObj.mjOBJ_CAMERA, camera)
                self._camera_ids[camera] = cam
            return cam if cam >= 0 else None
        return int(camera)

    def close(self) -> None:
        """Free every renderer (safe to call twice)."""
        for pool in (self._renderers, self._depth):
            for r in pool.values():
                r.close()
            pool.clear()
        _OPEN_RIGS.discard(self)
        self._closed = True


__all__ = ["CameraModel", "CameraRig", "camera_model"]
