"""Render only what changed: a camera's last picture, kept with what it was drawn from.

A camera's picture is a function of what its scene holds: the geoms it can see (`ViewCuller`),
their poses, sizes and looks, the materials, the lights, the sites, the camera's pose and lens,
the render settings. `SceneKey` packs every one of those that can change while a model lives
(poses in ``MjData``; colours, lights, camera poses and sizes in ``MjModel``, which a reset's
randomisation writes) into bytes; `LastPictures` keeps, per camera and image size, the last
picture with its key, and a render whose key equals the kept one returns a copy of the kept
picture instead of drawing it again: the same pixels (tested against full renders).

A decision step moves a tile under both cameras and changes both pictures; what is saved is
the picture of a camera whose view did not change: the input camera while the arm works over
the output belt in ``joint`` and ``cartesian`` modes, both cameras after a failed or refused
action, a second ``render`` of the same state.

Not kept (drawn every time): free cameras, pictures with an effect that has its own state
(the motion blur of a moving belt), and models with tendons, flexes or skins (drawn from
arrays not in the key).
"""

from __future__ import annotations

import mujoco
import numpy as np

_MODEL_GEOM = ("geom_rgba", "geom_size", "geom_type", "geom_dataid", "geom_matid", "geom_group")
"""Per-geom model arrays that set how a geom looks (all geoms: cheap and safe)."""
_MODEL_ALL = (
    "mat_rgba",
    "mat_emission",
    "mat_specular",
    "mat_shininess",
    "mat_reflectance",
    "mat_texid",
    "mat_texrepeat",
    "light_active",
    "light_ambient",
    "light_diffuse",
    "light_specular",
    "light_castshadow",
    "light_attenuation",
    "light_cutoff",
    "light_exponent",
    "light_type",
    "light_intensity",
    "site_rgba",
    "site_size",
    "site_type",
    "site_group",
)
"""Model arrays that set how materials, lights and sites look."""
_DATA_ALL = ("light_xpos", "light_xdir")
"""State arrays of the lights (all of them)."""
_SITES_SHOWN = np.asarray(mujoco.MjvOption().sitegroup, bool)
"""Site groups a renderer's default options draw (the cell's cameras use them)."""
_CAMERA = ("cam_fovy", "cam_ipd", "cam_intrinsic", "cam_sensorsize", "cam_projection")
"""Per-camera model arrays of its projection."""
MAX_PICTURES = 16
"""Pictures kept by one `LastPictures` at most: one per (camera, size, kind) in use, the
oldest dropped first (an observation camera at one size needs one)."""


def memo_possible(model: mujoco.MjModel) -> bool:
    """Whether every array a picture of ``model`` is drawn from is in `SceneKey`."""
    return model.ntendon == 0 and model.nflex == 0 and model.nskin == 0


def scene_key(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    camera: int,
    hidden: np.ndarray,
    flags: np.ndarray,
) -> bytes:
    """Everything ``camera``'s picture is drawn from now, as bytes.

    Args:
        model: The compiled model (its looks, lights, camera projection, visual options).
        data: The state to render (positions up to date).
        camera: Model camera id.
        hidden: Geoms left out of the picture, shape (ngeom,) bool.
        flags: The renderer's scene flags (shadows, reflections, ...).
    """
    shown = ~hidden
    parts: list[np.ndarray] = [
        hidden,
        flags,
        data.geom_xpos[shown],
        data.geom_xmat[shown],
        data.cam_xpos[camera],
        data.cam_xmat[camera],
    ]
    parts += [getattr(model, name) for name in _MODEL_GEOM]
    parts += [getattr(model, name) for name in _MODEL_ALL]
    parts += [getattr(data, name) for name in _DATA_ALL]
    drawn = _SITES_SHOWN[np.clip(model.site_group, 0, len(_SITES_SHOWN) - 1)]
    drawn &= (model.site_group >= 0) & (model.site_group < len(_SITES_SHOWN))
    parts += [data.site_xpos[drawn], data.site_xmat[drawn]]
    parts += [getattr(model, name)[camera] for name in _CAMERA]
    vis, stat = model.vis, model.stat
    head = vis.headlight
    parts.append(
        np.concatenate(
            [
                head.ambient,
                head.diffuse,
                head.specular,
                [head.active],
                [vis.map.znear, vis.map.zfar, vis.map.fogstart, vis.map.fogend, vis.map.haze],
                vis.rgba.fog,
                vis.rgba.haze,
                [stat.extent],
                stat.center,
            ]
        )
    )
    return b"".join(np.ascontiguousarray(p).tobytes() for p in parts)


class LastPictures:
    """The last picture of each (camera, size, kind) with the `scene_key` it was drawn from.

    At most `MAX_PICTURES` pictures (the least recently drawn dropped first); each is a few
    tens of kB at observation sizes (72 x 96 x 3 bytes = 20 kB).
    """

    def __init__(self) -> None:
        self._kept: dict[tuple[object, ...], tuple[bytes, np.ndarray]] = {}
        self.hits = 0
        """Pictures returned from memory."""
        self.misses = 0
        """Pictures drawn."""

    def get(self, slot: tuple[object, ...], key: bytes) -> np.ndarray | None:
        """A copy of the picture kept in ``slot`` if it was drawn from ``key``, else None."""
        kept = self._kept.get(slot)
        if kept is None or kept[0] != key:
            self.misses += 1
            return None
        self.hits += 1
        return kept[1].copy()

    def put(self, slot: tuple[object, ...], key: bytes, picture: np.ndarray) -> None:
        """Keep a copy of ``picture``, drawn from ``key``, in ``slot``."""
        self._kept.pop(slot, None)
        self._kept[slot] = (key, picture.copy())
        while len(self._kept) > MAX_PICTURES:
            del self._kept[next(iter(self._kept))]

    def __len__(self) -> int:
        return len(self._kept)

    def clear(self) -> None:
        """Forget every picture."""
        self._kept.clear()


__all__ = ["MAX_PICTURES", "LastPictures", "memo_possible", "scene_key"]
