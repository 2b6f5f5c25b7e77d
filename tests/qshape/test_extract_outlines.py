"""Extraction's picture-dependent resample count and its one-colour shortcut.

Outlines are resampled to ``resample_per_px`` x the traced length of the picture's longest whole
outline, capped at ``outline.resample_points``; a picture whose border sample already spans more
levels than ``uniform_range`` is not read whole to prove it is not one colour.
"""

from __future__ import annotations

import importlib
import math
from dataclasses import replace
from typing import Any

import numpy as np
import pytest

from qshape.design import Design
from qshape.synthetic.synth import SynthParams, generate
from qshape.vision.extract import extract_detailed
from qshape.vision.params import ExtractParams, ImageError

extract_module = importlib.import_module("qshape.vision.extract")


def _picture(design: str, px_per_mm: float, seed: int = 4) -> np.ndarray:
    sp = SynthParams.load()
    return generate(Design.load(design), 10, seed, replace(sp, px_per_mm=px_per_mm)).image


def _counts(image: np.ndarray, p: ExtractParams, monkeypatch: pytest.MonkeyPatch) -> list[int]:
    """The resample count extraction chose for each batch of outlines.

    Read from the outline parameters extraction hands `qshape.figures_from_outlines` (spied,
    not altered).
    """
    seen: list[int] = []
    real = extract_module.figures_from_outlines

    def spy(*args: Any, **kwargs: Any) -> Any:  # noqa: ANN401
        seen.append(args[3].resample_points)
        return real(*args, **kwargs)

    with monkeypatch.context() as patch:
        patch.setattr(extract_module, "figures_from_outlines", spy)
        extract_detailed(image, p)
    return seen


def test_small_tiles_are_resampled_per_traced_pixel(
    monkeypatch: pytest.MonkeyPatch, extract_params: ExtractParams
) -> None:
    p = extract_params
    assert p.resample_per_px > 0.0
    image = _picture("hexagon", 1.8)
    res = extract_detailed(image, p)
    longest = max(
        float(np.hypot(*np.diff(np.vstack([o, o[:1]]), axis=0).T).sum()) for o in res.outlines
    )
    (n,) = _counts(image, p, monkeypatch)
    # The traced length counts a diagonal pixel step as sqrt(2): within 1 % of the outline's.
    assert n < p.outline.resample_points
    assert n == pytest.approx(p.resample_per_px * longest, rel=0.01)


def test_large_tiles_keep_the_full_count_and_the_same_figures(
    monkeypatch: pytest.MonkeyPatch,
    extract_params: ExtractParams,
) -> None:
    p = extract_params
    image = _picture("paper_mixed", 2.5)
    assert _counts(image, p, monkeypatch) == [p.outline.resample_points]
    fixed = extract_detailed(image, replace(p, resample_per_px=0.0)).figures
    chosen = extract_detailed(image, p).figures
    assert len(chosen) == len(fixed) > 0
    for a, b in zip(chosen, fixed, strict=True):
        assert np.array_equal(a.points, b.points)


def test_small_tiles_keep_their_shape_at_the_lower_count(extract_params: ExtractParams) -> None:
    """The same corners (and curves) at 1.8 px/mm with the picture's count as with the cap."""
    p = extract_params
    image = _picture("square_grid", 1.8, seed=9)
    fixed = extract_detailed(image, replace(p, resample_per_px=0.0)).figures
    chosen = extract_detailed(image, p).figures
    assert len(chosen) == len(fixed) > 5
    same = sum(
        len(a.points) == len(b.points) and np.array_equal(a.curve_mask, b.curve_mask)
        for a, b in zip(chosen, fixed, strict=True)
    )
    assert same == len(fixed)


@pytest.mark.parametrize("bad", [-1.0, math.nan, math.inf])
def test_bad_resample_density_is_refused(bad: float, extract_params: ExtractParams) -> None:
    with pytest.raises(ImageError, match="resample_per_px"):
        replace(extract_params, resample_per_px=bad)


def test_a_uniform_border_around_a_tile_is_still_read_whole() -> None:
    """A border sample of one level does not make the picture one colour: the tile is found."""
    image = np.full((200, 240, 3), 90, np.uint8)
    image[60:140, 80:160] = (200, 60, 50)
    res = extract_detailed(image)
    assert len(res.figures) == 1 and len(res.figures[0].points) == 4
    assert res.threshold > 0.0


def test_a_faint_mark_inside_a_uniform_border_is_within_the_uniform_range() -> None:
    """Two levels of difference anywhere: one colour, as when the whole picture was read."""
    image = np.full((200, 240, 3), 90, np.uint8)
    image[60:140, 80:160] = 92
    res = extract_detailed(image)
    assert res.figures == [] and res.threshold == 0.0
    assert res.background == pytest.approx((90 / 255.0,) * 3)
