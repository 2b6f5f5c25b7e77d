"""Parameters of image extraction (`qshape.vision.extract`): section ``extract`` of the config."""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from configs.checks import check_fields, checked
from qshape.config_sections import load_section
from qshape.errors import QShapeError
from qshape.outline.params import OutlineParams


class ImageError(QShapeError):
    """The image cannot be processed (wrong type, shape or size)."""


@dataclass(frozen=True)
class ExtractParams:
    """Parameters of `extract`. Pixel values are on the 0-255 scale.

    Attributes:
        min_size_px: Smallest accepted image height and width, in [px].
        max_size_px: Largest accepted image height and width, in [px].
        uniform_range: An image whose every channel spans at most this many levels is "one
            colour": an empty belt (or a covered camera, see `image_health`); it has no
            figures, in [levels].
        blur_sigma_px: Gaussian blur before everything, in [px] (0: none).
        background_bins: Histogram bins per channel used to find the dominant colour.
        background_border_px: The dominant colour is taken from a band of this width along
            the image border (belt or grout shows there even when tiles cover most of the
            image), in [px]; 0 uses the whole image.
        background_sample_step: Every n-th pixel (each axis) enters the colour histogram.
        min_background_fraction: Fewer of the sampled border pixels than this fraction within
            ``background_tolerance`` of the dominant colour: no dominant background (noise,
            or one object filling the view), so no figures, in [0, 1].
        illumination_cell_px: Cell size of the downsampled image the illumination model is
            fitted on, in [px].
        illumination_degree: Degree of the per-channel polynomial illumination model (0: flat);
            the fallback where no background cell is near.
        illumination_local_sigma_cells: Width (Gaussian sigma) over which the background
            colour is averaged from the background cells near each cell, in [cells] (0: the
            polynomial alone). It follows a shadow band or a steep light gradient that a
            low-order polynomial cannot.
        illumination_min_weight: Cells whose Gaussian weight of background cells is below this
            keep the polynomial model (dimensionless, in (0, 1]).
        illumination_blend: Such a cell blends the belt near it with the polynomial instead,
            the polynomial standing in only for the missing weight (weight w: w / min_weight
            of the local average), so the model has no step where a shadow's edge passes under
            a tile: a degree-2 polynomial smooths a soft shadow away, and a step to it lit a
            third of a dark tile 7 levels too bright.
        illumination_blend_min_change: ... only where the blend moves the cell's model by more
            than this (max over channels), in [levels] >= 0; smaller changes keep the
            polynomial (and with it every outline the step does not disturb).
        illumination_min_cells: Fewer trusted background cells than this (cells whose
            neighbours are all background): every background cell is used, in [cells].
        background_chroma_tolerance: A cell of the illumination grid is belt when its colour
            is within this distance (max over channels) of the dominant colour scaled to the
            cell's brightness, in [levels]: a shadow changes the belt's brightness, a tile its
            hue.
        belt_gain_min: ...and its brightness is at least this fraction of the dominant's (a
            cell brighter than the dominant colour must also be within
            ``background_tolerance`` of it: a grey tile has the belt's hue).
        normalize_shading: Multiply colour distances by the shading gain (belt as fully lit /
            belt as modelled here), so a tile in a shadow stands out as much as in full light.
        lit_percentile: The reference light (shading gain 1, and the light tile colours are
            corrected to) is this percentile of the modelled brightness over the picture, in
            [%] (50: the light in the middle of a gradient, and outside a shadow band
            covering less than half the picture).
        background_tolerance: A cell is background for the model fit when its colour is within
            this distance (max over channels) of the dominant colour, in [levels].
        threshold_min: Lowest foreground threshold on the colour distance, in [levels].
        threshold_max: Highest foreground threshold (Otsu's value is clamped to the range).
        otsu_sample_step: Otsu's threshold is taken from the histogram of every n-th pixel
            (each axis) of the colour distance; the mask is then thresholded at every pixel.
        open_px: Size of the square opening that removes specks from the mask, in [px] (0: none).
        edge_fraction: Each region's outline is traced where the colour distance is this
            fraction of the region's median distance (its contrast; 0.5: the middle of a
            blurred edge), dimensionless; 0: at the global threshold.
        edge_threshold_max: Upper clamp of that per-region level, in [levels] (the global
            threshold is the lower one).
        edge_sample_step: Every n-th pixel (each axis) of a region enters its median distance.
        split_touching: Remove Canny edges found inside the foreground (splits touching tiles).
        canny_low: Canny hysteresis low threshold, on the blurred RGB image.
        canny_high: Canny hysteresis high threshold.
        canny_reduction: The split's Canny runs on the blurred picture reduced by this factor
            per axis (area average; 1: full size), its edges scaled back (each a block of
            ``canny_reduction`` px), dimensionless.
        restore_iterations: After the Canny cut, pixels on the cut are given back to a
            neighbouring piece by this many label dilations.
        min_area_px: Regions smaller than this are ignored, in [px^2].
        min_hole_area_px: Holes smaller than this are ignored, in [px^2].
        min_hole_width_px: Holes thinner than this (2 x area / perimeter) are ignored (slits
            left by noise), in [px].
        hole_belt_fraction: A hole is kept only when the colour distance inside it reaches
            down to this fraction of the threshold (it shows the belt), dimensionless.
        hole_belt_percentile: ...at this percentile of the hole's pixels, in [%].
        max_outline_excess: A region whose traced outline is longer than this multiple of its
            figure's perimeter is mostly noise (a ragged splash, not a tile edge) and gives no
            figure, dimensionless (the pixel staircase alone gives up to ~1.08; edges rough by
            0.6 mm at 2.5 px/mm ~1.16).
        border_margin_px: Regions reaching this close to the image border are partial tiles,
            in [px].
        boundary_offset_px: Outlines are moved outwards by this much (traced contours run
            through the centres of the outermost region pixels), in [px].
        color_erode_px: Erosion before taking the median colour, in [px].
        color_sample_step: Every n-th pixel (each axis) of a tile enters its median colour.
        height_levels_per_mm: With a height picture (`extract_detailed`'s ``height``: the
            tiles' height above the belt from a 3D camera, a cue that does not depend on
            colour), a tile's height counts as this many colour-distance levels per mm where
            its colour does not stand off the belt (a black tile on a dark belt, a glaze of the
            belt's own colour), in [levels/mm].
        height_grow_px: The height cue covers each such raised region grown by this many
            pixels (its blurred edge), in [px].
        correct_illumination: Divide tile colours by the modelled relative illumination.
        resample_per_px: The picture's outlines are resampled to this many samples per
            traced pixel of its longest whole-tile outline, in [samples/px], and at most
            ``outline.resample_points`` (0: always ``outline.resample_points``). Small tiles
            in a coarse picture carry fewer pixels; sampling them more densely than that
            adds work, not information.
        outline: Slope-comparison simplification parameters for pixel outlines.
    """

    min_size_px: int = checked(16, ge=1)
    max_size_px: int = 8192
    uniform_range: int = 2
    blur_sigma_px: float = checked(1.0, ge=0)
    background_bins: int = checked(16, ge=2, le=256)
    background_border_px: int = 4
    background_sample_step: int = checked(4, ge=1)
    min_background_fraction: float = checked(0.25, ge=0, le=1)
    illumination_cell_px: int = checked(16, ge=1)
    illumination_degree: int = checked(2, ge=0, le=3)
    illumination_local_sigma_cells: float = checked(1.5, ge=0)
    illumination_min_weight: float = checked(0.05, gt=0, le=1)
    illumination_blend: bool = True
    illumination_blend_min_change: float = checked(3.0, ge=0)
    illumination_min_cells: int = 12
    background_chroma_tolerance: float = 12.0
    belt_gain_min: float = checked(0.25, gt=0, le=1)
    normalize_shading: bool = True
    lit_percentile: float = checked(50.0, ge=0, le=100)
    background_tolerance: float = 40.0
    threshold_min: float = checked(20.0, gt=0)
    threshold_max: float = 60.0
    otsu_sample_step: int = checked(1, ge=1)
    open_px: int = checked(3, ge=0)
    edge_fraction: float = 0.5
    edge_threshold_max: float = 60.0
    edge_sample_step: int = checked(2, ge=1)
    split_touching: bool = True
    canny_low: float = 60.0
    canny_high: float = 150.0
    canny_reduction: int = checked(1, ge=1)
    restore_iterations: int = checked(3, ge=0)
    min_area_px: float = checked(150.0, ge=0)
    min_hole_area_px: float = checked(40.0, ge=0)
    min_hole_width_px: float = 3.0
    hole_belt_fraction: float = 0.5
    hole_belt_percentile: float = 10.0
    max_outline_excess: float = checked(1.3, ge=1)
    border_margin_px: int = checked(1, ge=0)
    boundary_offset_px: float = 0.5
    color_erode_px: int = checked(3, ge=0)
    color_sample_step: int = 2
    height_levels_per_mm: float = checked(40.0, gt=0)
    height_grow_px: int = checked(2, ge=0)
    correct_illumination: bool = True
    resample_per_px: float = checked(0.0, ge=0)
    outline: OutlineParams = field(default_factory=OutlineParams)

    def __post_init__(self) -> None:
        """Raise `ImageError` on out-of-range values."""
        check_fields(self, ImageError)
        if not self.min_size_px <= self.max_size_px:
            raise ImageError(
                f"need min_size_px <= max_size_px, got {self.min_size_px} > {self.max_size_px}"
            )
        if not self.threshold_min <= self.threshold_max:
            raise ImageError(
                f"need threshold_min <= threshold_max, got {self.threshold_min} > "
                f"{self.threshold_max}"
            )

    @classmethod
    def load(cls, name_or_path: str | Path | None = None, **overrides: Any) -> ExtractParams:
        """Load the ``extract`` section of ``configs/vision.yaml`` (or another file).

        Raises:
            configs.ConfigError: Unknown key or wrong type.
        """
        return load_section(cls, "extract", name_or_path, overrides)


@functools.cache
def default_params() -> ExtractParams:
    """Bundled parameters (``configs/vision.yaml``), loaded once."""
    return ExtractParams.load()


__all__ = ["ExtractParams", "ImageError", "default_params"]
