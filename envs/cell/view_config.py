"""Configuration of what the cell's cameras see: the cameras, rendering and the scenery.

Part of the cell's configuration (`envs.cell.config.CellConfig` holds these sections); the same
conventions: frozen dataclasses with units in the docstrings, validated in ``__post_init__``
(a `CellError` naming the field and what is allowed), bundled values in ``configs/cell.yaml``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from configs.checks import check_fields, checked
from envs.errors import CellError


@dataclass(frozen=True)
class CameraConfig:
    """One downward-looking camera above a belt's working area.

    Attributes:
        width: Image width [px] (paper: 656).
        height: Image height [px] (paper: 492).
        height_above_belt: Camera height above the belt top [m].
        fovy_deg: Vertical field of view [deg].
        offset: Camera position offset (x, y) from the working-area centre [m].
        distortion: Lens distortion in OpenCV's model, (k1, k2, p1, p2, k3) on normalised
            image coordinates (dimensionless); all zero: an ideal pinhole. The rendered image
            is warped by it (`envs.cell.cameras.LensWarp`).
        exposure_time: Shutter time [s]: tiles on a moving belt blur over belt speed x this
            (`envs.cell.camera_effects.BeltBlur`); 0: a still picture.
    """

    width: int = checked(656, gt=0)
    height: int = checked(492, gt=0)
    height_above_belt: float = checked(0.5, gt=0)
    fovy_deg: float = checked(27.0, gt=0, lt=170)
    offset: tuple[float, ...] = checked((0.0, 0.0), length=2)
    distortion: tuple[float, ...] = checked((0.0, 0.0, 0.0, 0.0, 0.0), length=5, finite=True)
    exposure_time: float = checked(0.0, ge=0)

    def __post_init__(self) -> None:
        check_fields(self, CellError, qualify=True)

    @property
    def pixels_per_metre(self) -> float:
        """Image scale on the belt plane [px/m]."""
        view = 2 * self.height_above_belt * math.tan(math.radians(self.fovy_deg) / 2)
        return self.height / view


@dataclass(frozen=True)
class RenderConfig:
    """Rendering options.

    Attributes:
        shadows: Render shadows (slow in software rendering; off for observations).
        reflections: Render reflections.
        overview_size: Overview image (height, width) [px].
        cull: Leave geoms a model camera cannot see out of its scene (same image, faster in
            software rendering; `envs.cell.view_culling`).
        samples: Multisamples per pixel of every rendered image not supersampled
            (anti-aliasing; MuJoCo's ``offsamples``). 0 renders small images about 40 % faster
            in software rendering, with stair-stepped edges.
        supersample: With ``samples`` > 0, small RGB images are anti-aliased by
            supersampling instead: rendered at this factor times the size without
            multisampling, then each factor x factor block averaged (``cv2.INTER_AREA``); 1
            turns it off. In software rendering a 72 x 96 image costs about half of a
            4-sample multisampled one, with edges as smooth (tested against it).
        supersample_max_pixels: Largest image (height x width [px]) supersampled; larger ones
            (where multisampling is the cheaper of the two) and depth images use ``samples``.
        lens_max_iterations: Iterations of the solver inverting a lens distortion (once per
            camera and image size).
        lens_tolerance: Its convergence tolerance, in normalised image units (1 px ~ 1 / the
            focal length in px).
        reuse_unchanged: A model camera whose scene did not change since its last picture
            at the same size returns that picture again instead of drawing it (the same
            pixels; `envs.cell.render_memo`).
    """

    shadows: bool = False
    reflections: bool = False
    overview_size: tuple[int, ...] = checked((480, 640), length=2, gt=0)
    cull: bool = True
    samples: int = checked(4, ge=0)
    supersample: int = checked(2, gt=0)
    supersample_max_pixels: int = checked(40000, ge=0)
    lens_max_iterations: int = checked(40, gt=0)
    lens_tolerance: float = checked(1e-9, gt=0)
    reuse_unchanged: bool = True

    def __post_init__(self) -> None:
        check_fields(self, CellError, qualify=True)


@dataclass(frozen=True)
class SceneryConfig:
    """What the cell looks like around the working parts: floor, light, frames, bin, colours.

    Attributes:
        floor_half_size: Half side of the square floor plane [m].
        floor_checker: The floor texture's two checker colours, RGB in [0, 1] each (2, 3).
        floor_texture_px: Checker texture side [px].
        floor_texture_repeat: Texture repeats across the floor.
        light_pos: Position of the directional top light [m] (3,).
        light_diffuse: Diffuse weight of the top light (relative; see ``exposure``).
        light_specular: Specular intensity of the top light (0: diffuse lighting, as a vision
            cell's dome gives; > 0 puts a glaze highlight on every tile).
        headlight_ambient: Ambient weight of the viewer's headlight (relative).
        headlight_diffuse: Diffuse weight of the headlight (relative).
        exposure: Grey level, in (0, 1], at which a white matte face looking up renders: the
            ambient and diffuse intensities above are scaled so that they sum to it, so a
            glaze renders at its own colour times ``exposure`` (1: the glaze colour itself)
            instead of over-brightened or saturated.
        belt_rgba: Belt colour, RGBA in [0, 1].
        frame_rgba: Colour of rails and stands.
        sheet_rgba: Colour of the mesh sheet.
        bin_floor_rgba: Colour of the bin's floor.
        bin_wall_rgba: Colour of the bin's walls.
        slot_white: White mixed into each slot mark's tile colour, in [0, 1].
        rail_gap: Gap between the input belt's edge and each side rail's centre [m].
        rail_half_width: Half width of a side rail [m].
        rail_height: Half height of a side rail [m].
        stand_inset: How much narrower than its belt a stand is, (along, across) per side [m].
        bin_gap: Gap between the input belt's end and the bin [m].
        bin_side_margin: How much wider than the belt the bin is, per side [m].
        bin_wall: Half thickness of the bin's floor and walls [m].
        bin_stand_inset: How much smaller than the bin its stand is, per side [m].
        overview_pos: Position of the overview camera [m] (3,).
        overview_xyaxes: The overview camera's image x and y axes in the world (MuJoCo
            ``xyaxes``) (6,).
    """

    floor_half_size: float = checked(4.0, gt=0)
    floor_checker: tuple[tuple[float, ...], ...] = ((0.33, 0.35, 0.38), (0.28, 0.3, 0.33))
    floor_texture_px: int = checked(256, gt=0)
    floor_texture_repeat: int = checked(8, gt=0)
    light_pos: tuple[float, ...] = checked((0.3, 0.0, 2.5), length=3)
    light_diffuse: float = checked(0.45, ge=0)
    light_specular: float = checked(0.0, ge=0)
    headlight_ambient: float = checked(0.3, ge=0)
    headlight_diffuse: float = checked(0.35, ge=0)
    exposure: float = checked(1.0, gt=0, le=1)
    belt_rgba: tuple[float, ...] = checked((0.12, 0.12, 0.13, 1.0), length=4)
    frame_rgba: tuple[float, ...] = checked((0.55, 0.57, 0.6, 1.0), length=4)
    sheet_rgba: tuple[float, ...] = checked((0.22, 0.22, 0.24, 1.0), length=4)
    bin_floor_rgba: tuple[float, ...] = checked((0.35, 0.25, 0.15, 1.0), length=4)
    bin_wall_rgba: tuple[float, ...] = checked((0.45, 0.33, 0.2, 1.0), length=4)
    slot_white: float = checked(0.45, ge=0)
    rail_gap: float = checked(0.01, ge=0)
    rail_half_width: float = checked(0.01, gt=0)
    rail_height: float = checked(0.01, gt=0)
    stand_inset: tuple[float, ...] = checked((0.05, 0.03), length=2, ge=0)
    bin_gap: float = checked(0.005, ge=0)
    bin_side_margin: float = checked(0.05, ge=0)
    bin_wall: float = checked(0.005, gt=0)
    bin_stand_inset: float = checked(0.02, ge=0)
    overview_pos: tuple[float, ...] = checked((1.45, 0.0, 1.35), length=3)
    overview_xyaxes: tuple[float, ...] = checked((0.0, 1.0, 0.0, -0.62, 0.0, 0.78), length=6)

    def __post_init__(self) -> None:
        check_fields(self, CellError, qualify=True)
        if len(self.floor_checker) != 2 or any(len(c) != 3 for c in self.floor_checker):  # noqa: PLR2004
            raise CellError(
                f"SceneryConfig.floor_checker needs two RGB colours, got {self.floor_checker}"
            )
        if self.light_weight_sum <= 0.0:
            raise CellError(
                "SceneryConfig: light_diffuse, headlight_ambient and headlight_diffuse must have "
                f"a positive sum (what exposure {self.exposure} rescales), got "
                f"{self.light_weight_sum}"
            )

    @property
    def light_weight_sum(self) -> float:
        """Sum of the ambient and diffuse light weights (what ``exposure`` rescales to)."""
        return self.light_diffuse + self.headlight_ambient + self.headlight_diffuse

    @property
    def light_scale(self) -> float:
        """Factor applied to every configured ambient and diffuse intensity."""
        return self.exposure / self.light_weight_sum


__all__ = ["CameraConfig", "RenderConfig", "SceneryConfig"]
