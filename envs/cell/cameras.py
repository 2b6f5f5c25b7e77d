"""Pinhole models of the cell's cameras and reusable renderers.

Pixel convention (OpenCV): u to the right, v down, pixel centres at integer coordinates, so
pixel ``image[row, col]`` is centred at ``(u, v) = (col, row)``. Camera frame (OpenCV): x right,
y down, z forward (along the view). Motion blur and per-episode pose jitter:
`envs.cell.camera_effects`.

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
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import cv2
import mujoco
import numpy as np

from envs.cell.config import CameraConfig, RenderConfig
from envs.cell.render_memo import LastPictures, memo_possible, scene_key
from envs.cell.view_culling import PROBE_SCALE, ViewCuller
from envs.errors import CellError

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
        distortion: Lens distortion (k1, k2, p1, p2, k3), OpenCV's model, shape (5,); zeros:
            an ideal pinhole.
    """

    name: str
    width: int
    height: int
    K: np.ndarray
    world_to_camera: np.ndarray
    distortion: np.ndarray = field(default_factory=lambda: np.zeros(5))

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
        xy = distort_normalised(cam[:, :2] / cam[:, 2:3], self.distortion)
        uv = xy @ self.K[:2, :2].T + self.K[:2, 2]
        return uv[0] if single else uv

    def unproject_to_plane(self, uv: np.ndarray, z: float) -> np.ndarray:
        """World points on the horizontal plane at height z seen at pixels uv.

        Args:
            uv: Pixel coordinates, shape (n, 2) [px].
            z: Plane height [m].

        Returns:
            World points, shape (n, 3) [m].

        Raises:
            CellError: A ray parallel to the plane, or the plane behind the camera.
        """
        uv = np.atleast_2d(np.asarray(uv, dtype=float))
        if np.any(self.distortion):  # pixels through the lens -> ideal pinhole pixels
            uv = cv2.undistortPoints(uv.reshape(-1, 1, 2), self.K, self.distortion, P=self.K)
            uv = uv.reshape(-1, 2).astype(float)
        rays_cam = np.column_stack([uv, np.ones(len(uv))]) @ np.linalg.inv(self.K).T
        r = self.world_to_camera[:3, :3]
        origin = -r.T @ self.world_to_camera[:3, 3]
        rays = rays_cam @ r  # camera -> world directions (rows)
        with np.errstate(divide="ignore", invalid="ignore"):
            s = (z - origin[2]) / rays[:, 2]
        if not np.all(np.isfinite(s)) or np.any(s <= 0):
            raise CellError(
                f"the plane z = {z} m is not in front of camera {self.name!r} for every pixel"
            )
        return origin + s[:, None] * rays


def distort_normalised(xy: np.ndarray, coefficients: np.ndarray) -> np.ndarray:
    """OpenCV's lens model applied to ideal normalised image points.

    Args:
        xy: Undistorted normalised coordinates (x / z, y / z), shape (n, 2).
        coefficients: (k1, k2, p1, p2, k3), shape (5,).

    Returns:
        Distorted normalised coordinates, shape (n, 2).
    """
    k1, k2, p1, p2, k3 = (float(c) for c in np.asarray(coefficients, dtype=float).ravel()[:5])
    x, y = xy[:, 0], xy[:, 1]
    r2 = x * x + y * y
    radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))
    xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x)
    yd = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y
    return np.column_stack([xd, yd])


def intrinsics(fovy_deg: float, width: int, height: int) -> np.ndarray:
    """Intrinsic matrix of a MuJoCo camera's render (square pixels, centred), (3, 3) [px]."""
    fy = (height / 2) / math.tan(math.radians(fovy_deg) / 2)
    return np.array([[fy, 0.0, width / 2 - 0.5], [0.0, fy, height / 2 - 0.5], [0.0, 0.0, 1.0]])


def camera_model(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    camera: int,
    width: int,
    height: int,
    *,
    distortion: tuple[float, ...] | np.ndarray = (0.0, 0.0, 0.0, 0.0, 0.0),
) -> CameraModel:
    """Model of a MuJoCo camera at an image size, with the lens distortion its images carry."""
    k = intrinsics(float(model.cam_fovy[camera]), width, height)
    r_wc = data.cam_xmat[camera].reshape(3, 3)  # camera axes in world (MuJoCo convention)
    r = _MJ_TO_CV @ r_wc.T
    t = np.eye(4)
    t[:3, :3] = r
    t[:3, 3] = -r @ data.cam_xpos[camera]
    name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_CAMERA, camera) or str(camera)
    return CameraModel(name, width, height, k, t, np.asarray(distortion, dtype=float).copy())


class LensWarp:
    """Lens distortion of rendered images: one `cv2.remap` with maps built once per size.

    MuJoCo renders an ideal pinhole image; a real lens bends it. Every pixel of the distorted
    picture looks up where its ray lands in the ideal render: the inverse of OpenCV's model,
    solved once per image size with `cv2.undistortPoints` (iterative). Rays that leave the rendered
    field (the corners of a barrel lens) repeat the border pixel.

    Args:
        fovy_deg: The camera's vertical field of view [deg].
        coefficients: (k1, k2, p1, p2, k3), OpenCV's model.
        criteria: (iterations, epsilon [px]) of the inverse's solver.
    """

    def __init__(
        self, fovy_deg: float, coefficients: tuple[float, ...], criteria: tuple[int, float]
    ) -> None:
        self.fovy_deg = fovy_deg
        self.coefficients = np.asarray(coefficients, dtype=float)
        self._criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, *criteria)
        self._maps: dict[tuple[int, int], tuple[np.ndarray, np.ndarray]] = {}

    def maps(self, height: int, width: int) -> tuple[np.ndarray, np.ndarray]:
        """The fixed-point remap tables for an image size (built on first use)."""
        key = (height, width)
        if key not in self._maps:
            k = intrinsics(self.fovy_deg, width, height)
            v, u = np.mgrid[0:height, 0:width].astype(np.float64)
            pts = np.stack([u.ravel(), v.ravel()], axis=1).reshape(-1, 1, 2)
            src = cv2.undistortPoints(pts, k, self.coefficients, None, None, k, self._criteria)
            src = src.reshape(height, width, 2).astype(np.float32)
            self._maps[key] = cv2.convertMaps(src[..., 0], src[..., 1], cv2.CV_16SC2)
        return self._maps[key]

    def apply(self, image: np.ndarray) -> np.ndarray:
        """The distorted picture of an ideal render, same shape and dtype."""
        m1, m2 = self.maps(image.shape[0], image.shape[1])
        return cv2.remap(image, m1, m2, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)


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

    Each renderer has an offscreen buffer of its own image size (not the model's largest one:
    less to clear and resolve per frame in software rendering, same pixels). Where the model
    multisamples (``offsamples`` > 0), small RGB images are anti-aliased by supersampling
    instead (``cfg.supersample``): rendered at that factor times the size without
    multisampling and block-averaged, which software rendering does in about half the time of
    4-sample multisampling; larger ones and depth images are multisampled.

    Args:
        model: The compiled cell.
        cfg: Render options (shadows, reflections, lens solver).
        cameras: The configurations of named cameras; those with a lens distortion have their
            RGB and depth images warped by it (`LensWarp`).

    Raises:
        CellError: A camera in ``cameras`` that the model lacks.
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        cfg: RenderConfig,
        cameras: Mapping[str, CameraConfig] | None = None,
    ) -> None:
        self._model = model
        self._cfg = cfg
        self._lenses: dict[int, LensWarp] = {}
        for name, cam_cfg in (cameras or {}).items():
            cid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, name)
            if cid < 0:
                raise CellError(f"camera {name!r} is not in the model")
            if any(cam_cfg.distortion):
                crit = (cfg.lens_max_iterations, cfg.lens_tolerance)
                self._lenses[cid] = LensWarp(float(model.cam_fovy[cid]), cam_cfg.distortion, crit)
        self._renderers: dict[tuple[int, int, int], mujoco.Renderer] = {}
        self._depth: dict[tuple[int, int, int], mujoco.Renderer] = {}
        self._culler = ViewCuller(model)
        self.pictures = LastPictures()
        """The last picture of each camera and size (`envs.cell.render_memo`)."""
        self._reuse = cfg.reuse_unchanged and memo_possible(model)
        self._camera_ids: dict[str, int] = {}
        self._closed = False

    def _renderer(
        self, height: int, width: int, depth: bool, samples: int | None = None
    ) -> mujoco.Renderer:
        """The renderer of an image size and multisampling (the model's when None), opened once."""
        if self._closed:
            raise CellError("the camera rig is closed")
        if samples is None:
            samples = int(self._model.vis.quality.offsamples)
        pool = self._depth if depth else self._renderers
        key = (height, width, samples)
        r = pool.get(key)
        _check_not_forked()
        if r is None:
            r = _open_renderer(self._model, height, width, samples)
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
        effect: Callable[[np.ndarray], np.ndarray] | None = None,
    ) -> np.ndarray:
        """Render one view (through the camera's lens, when it has a distortion).

        Args:
            data: State to render.
            camera: Camera id, name, or a free `MjvCamera`.
            height: Image height [px].
            width: Image width [px].
            depth: Depth image [m] instead of RGB.
            out: Optional preallocated output, shape (height, width, 3) uint8 or
                (height, width) float32 for depth.
            effect: Applied to the ideal RGB render before the lens (motion blur).

        Returns:
            RGB uint8 (height, width, 3) or depth float32 (height, width) [m].

        Raises:
            CellError: The image is larger than the model's offscreen buffer, or the rig is
                closed.
        """
        vis = self._model.vis.global_
        if height > vis.offheight or width > vis.offwidth:
            raise CellError(
                f"image ({height}, {width}) px exceeds the offscreen render buffer "
                f"({vis.offheight}, {vis.offwidth}) px (height, width); allowed: up to that size"
            )
        cfg, samples = self._cfg, int(self._model.vis.quality.offsamples)
        small = height * width <= cfg.supersample_max_pixels
        f = cfg.supersample if samples > 0 and small and not depth else 1
        r = self._renderer(height * f, width * f, depth, 0 if f > 1 else samples)
        cam = self._camera_id(camera)
        hidden = self._hidden(r, data, cam)
        memo: tuple[tuple[object, ...], bytes] | None = None
        if self._reuse and cam is not None and effect is None:
            slot = (cam, height, width, depth, f)
            key = scene_key(self._model, data, cam, hidden, r.scene.flags)
            kept = self.pictures.get(slot, key)
            if kept is not None:
                if out is None:
                    return kept
                out[...] = kept
                return out
            memo = (slot, key)
        self._update_scene(r, data, camera, hidden)
        lens = self._lens(camera)
        if f == 1 and lens is None and effect is None:
            image = r.render(out=out)
            if memo is not None:
                self.pictures.put(*memo, image)
            return image
        image = r.render()
        if f > 1:
            image = cv2.resize(image, (width, height), interpolation=cv2.INTER_AREA)
        if effect is not None and not depth:
            image = effect(image)
        if lens is not None:
            image = lens.apply(image)
        if memo is not None:
            self.pictures.put(*memo, image)
        if out is None:
            return image
        out[...] = image
        return out

    def _hidden(self, r: mujoco.Renderer, data: mujoco.MjData, cam: int | None) -> np.ndarray:
        """Geoms the model camera ``cam`` cannot see (`envs.cell.view_culling`), (ngeom,) bool.

        None of them without culling or for a free camera (``cam`` None).
        """
        if cam is None or not self._cfg.cull:
            return np.zeros(self._model.ngeom, bool)
        return self._culler.hidden(r, data, cam)

    def _update_scene(
        self,
        r: mujoco.Renderer,
        data: mujoco.MjData,
        camera: int | str | mujoco.MjvCamera,
        hidden: np.ndarray,
    ) -> None:
        """``r.update_scene`` without the ``hidden`` geoms."""
        if not hidden.any():
            r.update_scene(data, camera=camera)
            return
        rgba = self._model.geom_rgba
        alpha = rgba[:, 3].copy()
        try:
            rgba[hidden, 3] = 0.0
            r.update_scene(data, camera=camera)
        finally:
            rgba[:, 3] = alpha

    def _lens(self, camera: int | str | mujoco.MjvCamera) -> LensWarp | None:
        if not self._lenses or isinstance(camera, mujoco.MjvCamera):
            return None
        if isinstance(camera, str):
            camera = mujoco.mj_name2id(self._model, mujoco.mjtObj.mjOBJ_CAMERA, camera)
        return self._lenses.get(int(camera))

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
        self.pictures.clear()
        _OPEN_RIGS.discard(self)
        self._closed = True


class _OwnContextRenderer(mujoco.Renderer):
    """A `mujoco.Renderer` that frees its GL objects in its own GL context.

    MuJoCo's ``close`` (also run when a renderer is collected) frees the rendering context's
    framebuffers and textures in whatever GL context is current, which is another renderer's
    after that one drew last: the other renderer then reads a freed buffer, and its camera
    returns a picture of another cell (seen with a fixed-design and a procedural-design env in
    one process, whose resets rebuild the model and close the old renderers). Making its own
    context current first frees the right objects.
    """

    def close(self) -> None:
        if self._gl_context and self._mjr_context:
            self._gl_context.make_current()
        super().close()


def _open_renderer(model: mujoco.MjModel, height: int, width: int, samples: int) -> mujoco.Renderer:
    """A ``height`` x ``width`` px renderer with ``samples`` and a buffer fitting its use.

    The offscreen buffer holds the image and the view culler's finer probe image
    (`envs.cell.view_culling.PROBE_SCALE` times the size) where the model's buffer held that probe,
    not more. MuJoCo sizes a rendering context's buffer from the model's visual options when
    the context is made; they are set for that moment only.
    """
    g, q = model.vis.global_, model.vis.quality
    saved = (g.offwidth, g.offheight, q.offsamples)
    probe = (PROBE_SCALE * height, PROBE_SCALE * width)
    fits = probe[0] <= g.offheight and probe[1] <= g.offwidth
    g.offheight, g.offwidth = probe if fits else (max(height, g.offheight), max(width, g.offwidth))
    q.offsamples = samples
    try:
        return _OwnContextRenderer(model, height, width)
    finally:
        g.offwidth, g.offheight, q.offsamples = saved


__all__ = [
    "CameraModel",
    "CameraRig",
    "LensWarp",
    "camera_model",
    "distort_normalised",
    "intrinsics",
]
