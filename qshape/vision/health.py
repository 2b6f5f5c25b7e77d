"""Is the camera alive? A typed verdict on a picture, for the caller to act on.

`qshape.extract` treats a single-colour picture as a normal one with nothing on it (an empty
belt between tiles). Whether that single colour is the belt or a dead camera (covered lens, no
light, a stuck sensor) is the caller's decision: `image_health` measures the picture and names
what it looks like; ``ImageHealth.color`` lets the caller compare a uniform picture with the
belt colour it expects.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import cv2
import numpy as np

from configs.checks import check_fields, checked
from qshape.design import load_section
from qshape.vision.extract import check_image
from qshape.vision.params import ImageError, default_params

Verdict = Literal["ok", "uniform", "dark", "overexposed"]


@dataclass(frozen=True)
class HealthParams:
    """Thresholds of `image_health` (``configs/vision.yaml``, section ``health``).

    Attributes:
        uniform_range: A picture whose every channel spans at most this many levels is
            uniform, in [levels].
        dark_level: A picture whose mean level (all channels) is below this is dark, in
            [levels].
        saturated_level: A pixel with a channel at or above this level is clipped, in [levels].
        saturated_fraction: More clipped pixels than this fraction: overexposed, in [0, 1].
    """

    uniform_range: int = checked(2, ge=0, le=255)
    dark_level: float = checked(10.0, ge=0, le=255)
    saturated_level: int = checked(250, ge=1, le=255)
    saturated_fraction: float = checked(0.5, gt=0, le=1)

    def __post_init__(self) -> None:
        """Raise `ImageError` naming the field and its allowed range."""
        check_fields(self, ImageError)

    @classmethod
    def load(cls, name_or_path: str | Path | None = None, **overrides: Any) -> HealthParams:
        """Load the ``health`` section of ``configs/vision.yaml`` (or another file)."""
        return load_section(cls, "health", name_or_path, overrides)


@functools.cache
def default_health_params() -> HealthParams:
    """Bundled thresholds, loaded once."""
    return HealthParams.load()


@dataclass(frozen=True)
class ImageHealth:
    """What a picture looks like to the camera's user.

    Attributes:
        verdict: ``ok``; ``uniform`` (one colour: an empty belt when ``color`` is the belt's,
            else a covered or stuck camera); ``dark`` (no light or no exposure);
            ``overexposed`` (most pixels clipped).
        color: Mean colour, RGB in [0, 1].
        mean_level: Mean level over all channels, in [levels].
        channel_span: Largest range of levels over the channels, in [levels].
        saturated_fraction: Fraction of pixels with a clipped channel, in [0, 1].
        message: The verdict in words.
    """

    verdict: Verdict
    color: tuple[float, float, float]
    mean_level: float
    channel_span: int
    saturated_fraction: float
    message: str

    @property
    def ok(self) -> bool:
        """True when the picture shows a working camera's view (tiles or not)."""
        return self.verdict == "ok"


def image_health(image: Any, params: HealthParams | None = None) -> ImageHealth:
    """Measure an RGB uint8 picture and name what it looks like (see `ImageHealth`).

    Dark and overexposed take precedence over uniform: a black picture is ``dark``.

    Raises:
        ImageError: Not an RGB uint8 image of an accepted size.
    """
    p = default_health_params() if params is None else params
    img = check_image(image, default_params())
    mean = np.asarray(cv2.mean(img)[:3], dtype=np.float64)
    level = float(mean.mean())
    span = max(int(hi - lo) for lo, hi, *_ in (cv2.minMaxLoc(c) for c in cv2.split(img)))
    top = cv2.max(cv2.max(img[..., 0], img[..., 1]), img[..., 2])
    clipped = float(np.count_nonzero(np.asarray(top) >= p.saturated_level)) / top.size
    color = (float(mean[0]) / 255.0, float(mean[1]) / 255.0, float(mean[2]) / 255.0)
    verdict: Verdict
    if level < p.dark_level:
        verdict, why = (
            "dark",
            f"mean level {level:.1f} is below {p.dark_level:g}: no light or exposure",
        )
    elif clipped > p.saturated_fraction:
        verdict, why = (
            "overexposed",
            f"{100 * clipped:.0f}% of the pixels are clipped (more than "
            f"{100 * p.saturated_fraction:.0f}%)",
        )
    elif span <= p.uniform_range:
        verdict, why = (
            "uniform",
            f"one colour (channels span {span} levels): empty belt or covered lens",
        )
    else:
        verdict, why = "ok", "picture has content"
    return ImageHealth(verdict, color, level, span, float(clipped), why)


__all__ = ["HealthParams", "ImageHealth", "Verdict", "default_health_params", "image_health"]
