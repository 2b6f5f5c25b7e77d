"""The belt model under tiles near a soft shadow's edge: no step to the polynomial.

Cells of the illumination grid far from any trusted belt cell (under a large tile or a crowd
of tiles) fall back on a degree-2 polynomial, which smooths a soft shadow away. Switching to it
outright made a step in the model: under a dark tile beside a shadow the model was 7 levels
brighter than the belt beside it, and the tile lost a third of its outline. The blend hands
over from the local belt average to the polynomial smoothly (see ``illumination_blend``).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from benchmarks.vision_realistic import RealisticBench, _Classes, _seen, _synth_for
from configs import load_config
from qshape import Tolerances, describe
from qshape.design import Design
from qshape.synthetic.synth import SynthParams, generate
from qshape.vision.background import _local_fill, _polynomial_fit
from qshape.vision.extract import extract_detailed
from qshape.vision.params import ExtractParams, ImageError

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
    base = _polynomial_fit(small, keep, p.illumination_degree)
    assert base is not None
    return _local_fill(small, keep, base, p)


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


def test_blend_min_change_is_validated() -> None:
    with pytest.raises(ImageError, match="illumination_blend_min_change"):
        ExtractParams.load(illumination_blend_min_change=-1.0)
    p = ExtractParams.load()
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


def test_dark_piece_at_a_shadow_edge_keeps_its_outline() -> None:
    bench = load_config(RealisticBench, "bench_vision_realistic")
    level = next(lv for lv in bench.levels if lv.effect == bench.target_level)
    sp = SynthParams.load()
    rng = np.random.default_rng()
    rng.bit_generator.state = _PICTURE_126
    design = Design.load("trencadis")
    params = _synth_for(level, sp, rng)
    img = generate(design, bench.tiles_per_image, rng, params)
    picture, centres = _seen(img, params.effects, bench)
    s = sp.px_per_mm
    tol = Tolerances.load(
        joint_width=design.joint * s, point_tolerance=Tolerances.load().point_tolerance * s
    )
    classes = _Classes(design, s, tol)
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
    assert all(recognised(ExtractParams.load()))
