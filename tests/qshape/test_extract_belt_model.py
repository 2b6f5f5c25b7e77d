"""The belt model: the belt's dominant colour, its model under the cell's light (local belt
average, polynomial where none is near), the colour distance to it and Otsu's threshold.

Under tiles near a soft shadow's edge the model has no step to the polynomial: cells of the
illumination grid far from any trusted belt cell (under a large tile or a crowd of tiles) fall
back on a degree-2 polynomial, which smooths a soft shadow away. Switching to it outright made
a step in the model: under a dark tile beside a shadow the model was 7 levels brighter than the
belt beside it, and the tile lost a third of its outline. The blend hands over from the local
belt average to the polynomial smoothly (see ``illumination_blend``).
"""

from __future__ import annotations

import math
from dataclasses import replace

import cv2
import numpy as np
import pytest

from benchmarks.recognition.realistic import DesignClasses, RealisticBench, seen_picture, synth_for
from configs import load_config
from qshape import Tolerances, describe
from qshape.design import Design
from qshape.synthetic.synth import SynthParams, generate
from qshape.vision.background import (
    GAIN_SCALE,
    dominant_color,
    illumination,
    local_fill,
    polynomial_fit,
)
from qshape.vision.extract import extract_detailed
from qshape.vision.params import ExtractParams, ImageError
from qshape.vision.segment import colour_distance


def _dominant_reference(img: np.ndarray, p: ExtractParams) -> tuple[np.ndarray, float, int]:
    """The dominant colour as plain (N, 3) reductions compute it (the definition)."""
    b, step = p.background_border_px, p.background_sample_step
    sample = np.concatenate(
        [
            img[:b, ::step].reshape(-1, 3),
            img[-b:, ::step].reshape(-1, 3),
            img[b:-b:step, :b].reshape(-1, 3),
            img[b:-b:step, -b:].reshape(-1, 3),
        ]
    )
    q = (sample.astype(np.int32) * p.background_bins) >> 8
    code = (q[:, 0] * p.background_bins + q[:, 1]) * p.background_bins + q[:, 2]
    top = int(np.argmax(np.bincount(code, minlength=p.background_bins**3)))
    dominant = np.median(sample[code == top], axis=0)
    off = np.abs(sample.astype(np.float64) - dominant)
    near = off.max(axis=1) <= p.background_tolerance
    span = int((sample.max(axis=0).astype(np.int32) - sample.min(axis=0)).max())
    return dominant, float(near.mean()), span


@pytest.mark.parametrize(("design", "seed"), [("hexagon", 0), ("paper_mixed", 3), ("trencadis", 5)])
def test_dominant_colour_from_planes_matches_the_plain_reductions(
    design: str, seed: int, synth_params: SynthParams, extract_params: ExtractParams
) -> None:
    p = extract_params
    sp = replace(synth_params, px_per_mm=1.8)
    img = generate(Design.load(design), 30, seed, sp).image
    dominant, share, span = dominant_color(img, p)
    ref_dominant, ref_share, ref_span = _dominant_reference(img, p)
    np.testing.assert_array_equal(dominant, ref_dominant)
    assert share == ref_share
    assert span == ref_span
    # A real belt: most of the border sample is near the dominant colour, and the tiles or
    # noise make it span some levels.
    assert share > 0.5
    assert span > 0


def test_colour_distance_from_planes_equals_the_colour_image_difference(
    synth_params: SynthParams, extract_params: ExtractParams, design: Design
) -> None:
    p = extract_params
    sp = replace(synth_params, px_per_mm=1.8)
    img = generate(design, 30, 2, sp).image
    dominant = dominant_color(img, p)[0]
    model, _, gain = illumination(cv2.split(img), dominant, p)
    dist, thr, mask = colour_distance(cv2.split(img), model, gain, p)
    # The definition: the largest channel of |picture - model|, scaled by the shading gain.
    diff = cv2.absdiff(img, cv2.merge(model))
    want = cv2.multiply(diff.max(axis=2), gain, scale=1.0 / GAIN_SCALE)
    np.testing.assert_array_equal(dist, want)
    assert thr > 0.0
    assert 0.05 < np.count_nonzero(mask) / mask.size < 0.9  # tiles found, not everything


def test_sampled_otsu_gives_the_same_extraction_on_a_rendered_picture(
    synth_params: SynthParams, extract_params: ExtractParams, design: Design
) -> None:
    """Otsu's threshold from every other pixel per axis is the full histogram's here, and the
    mask (from every pixel) gives the very same outlines and figures."""
    p = extract_params
    assert p.otsu_sample_step == 2  # the configured value is the one tested
    img = generate(design, 30, 8, replace(synth_params, px_per_mm=1.8))
    full = extract_detailed(img.image, replace(p, otsu_sample_step=1))
    sampled = extract_detailed(img.image, p)
    assert sampled.threshold == full.threshold
    assert len(sampled.outlines) == len(full.outlines) >= 10  # tiles found
    for a, b in zip(sampled.outlines, full.outlines, strict=True):
        np.testing.assert_array_equal(a, b)
    assert [f.points.tolist() for f in sampled.figures] == [f.points.tolist() for f in full.figures]


def test_sampled_otsu_is_within_a_level_or_two_where_it_decides(
    synth_params: SynthParams, extract_params: ExtractParams
) -> None:
    """With the clamp opened wide Otsu's own value sets the threshold: from a quarter of the
    pixels it lands within two levels of the full histogram's, and the tiles found differ only
    on the blurred rims' pixels between the two (areas within 1 %)."""
    p = replace(extract_params, threshold_min=1.0, threshold_max=250.0)
    for seed in range(3):
        sp = replace(synth_params, px_per_mm=1.8)
        img = generate(Design.load("square_grid"), 24, seed, sp).image
        full = extract_detailed(img, replace(p, otsu_sample_step=1))
        sampled = extract_detailed(img, p)
        assert p.threshold_min < full.threshold < p.threshold_max  # Otsu decides here
        assert abs(sampled.threshold - full.threshold) <= 2.0
        assert len(sampled.figures) == len(full.figures) > 0
        area = sum(f.area for f in full.figures)
        assert abs(sum(f.area for f in sampled.figures) - area) <= 0.01 * area


@pytest.mark.parametrize("field", ["otsu_sample_step", "edge_sample_step"])
def test_sample_steps_below_one_are_refused(field: str, extract_params: ExtractParams) -> None:
    with pytest.raises(ImageError, match=field):
        replace(extract_params, **{field: 0})


_BELT = np.array([72.0, 77.0, 83.0], np.float32)  # lit belt colour [levels]


def _shadowed_grid() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Cell means (30, 41, 3) of a belt under a soft shadow pool, the trusted cells, the truth.

    A crowd of tiles covers a block of cells reaching into the pool from above; the shadowed
    belt is visible below the block, the lit belt above and beside it.
    """
    gh, gw = 30, 41
    rows = np.arange(gh, dtype=np.float32)[:, None]
    cols = np.arange(gw, dtype=np.float32)[None, :]
    pool = np.exp(-(((cols - 20.0) / 9.0) ** 2)) / (1.0 + np.exp(-(rows - 20.0) / 1.2))
    light = (1.0 - 0.3 * rows / gh) * (1.0 - 0.4 * pool)
    truth = (_BELT * light[..., None]).astype(np.float32)
    keep = np.ones((gh, gw), bool)
    keep[17:28, 14:27] = False
    return truth, keep, truth


def _model(small: np.ndarray, keep: np.ndarray, **overrides: object) -> np.ndarray:
    p = ExtractParams.load(**overrides)
    base = polynomial_fit(small, keep, p.illumination_degree)
    assert base is not None
    return local_fill(small, keep, base, p)


def test_far_cells_beside_a_shadow_take_the_shadowed_belt() -> None:
    small, keep, truth = _shadowed_grid()
    # Two cells inside the crowd's lower edge: the shadowed belt is just below, but its
    # Gaussian weight there is under illumination_min_weight (the polynomial's cells).
    row, cols = 25, slice(18, 23)
    before = np.abs(_model(small, keep, illumination_blend=False) - truth)[row, cols]
    after = np.abs(_model(small, keep) - truth)[row, cols]
    assert before.max() > 12.0  # the polynomial: the shadow smoothed away
    assert after.max() < 2.0


def test_where_the_polynomial_fits_the_model_is_unchanged() -> None:
    gh, gw = 30, 41
    rows = np.arange(gh, dtype=np.float32)[:, None, None]
    small = (_BELT * (1.0 - 0.2 * rows / gh) * np.ones((gh, gw, 1), np.float32)).astype(
        np.float32
    )  # a smooth gradient: the polynomial is the belt everywhere
    keep = np.ones((gh, gw), bool)
    keep[8:22, 10:30] = False
    before = _model(small, keep, illumination_blend=False)
    assert np.array_equal(_model(small, keep), before)


def test_blend_min_change_is_validated(extract_params: ExtractParams) -> None:
    with pytest.raises(ImageError, match="illumination_blend_min_change"):
        ExtractParams.load(illumination_blend_min_change=-1.0)
    p = extract_params
    assert p.illumination_blend and p.illumination_blend_min_change >= 0.0
    assert replace(p, illumination_blend=False).illumination_blend is False


# The realistic benchmark's random generator just before its 127th realistic picture (a
# trencadis picture with a dark brown piece at a soft shadow's edge), recorded from the sweep.
_PICTURE_126 = {
    "bit_generator": "PCG64",
    "state": {
        "state": 115667472749554256899937443333607954512,
        "inc": 168635386100685449938534718985723470245,
    },
    "has_uint32": 0,
    "uinteger": 1178366455,
}


_DARK_PIECE = "0fe5fb"  # its shape class (key prefix)


def test_dark_piece_at_a_shadow_edge_keeps_its_outline(
    synth_params: SynthParams, extract_params: ExtractParams
) -> None:
    bench = load_config(RealisticBench, "bench_vision_realistic")
    level = next(lv for lv in bench.levels if lv.effect == bench.target_level)
    sp = synth_params
    rng = np.random.default_rng()
    rng.bit_generator.state = _PICTURE_126
    design = Design.load("trencadis")
    params = synth_for(level, sp, rng)
    img = generate(design, bench.tiles_per_image, rng, params)
    picture, centres = seen_picture(img, params.effects, bench)
    s = sp.px_per_mm
    tol = Tolerances.load(
        joint_width=design.joint * s, point_tolerance=Tolerances.load().point_tolerance * s
    )
    classes = DesignClasses(design, s, tol)
    dark = [
        (t, c)
        for t, c in zip(img.tiles, centres, strict=True)
        if not t.partial and t.slot.shape_key.startswith(_DARK_PIECE)
    ]
    assert dark

    def recognised(ep: ExtractParams) -> list[bool]:
        figs = extract_detailed(picture, ep).figures
        cents = np.array([f.centroid for f in figs]).reshape(-1, 2)
        out = []
        for t, centre in dark:
            k = int(np.argmin(np.hypot(*(cents - centre).T)))
            near = math.hypot(*(cents[k] - centre)) <= 0.3 * math.sqrt(t.slot.area) * s
            key, _ = classes.best(describe(figs[k], tol), classes.shape, tol, False)
            out.append(near and key == t.slot.shape_key)
        return out

    # Before the blend: one of the two pieces lost a third of its outline (no match).
    assert recognised(ExtractParams.load(illumination_blend=False)).count(False) == 1
    assert all(recognised(extract_params))
