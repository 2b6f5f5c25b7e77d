"""Corners of rough tile outlines: the window of the slope comparison (extract.outline)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from qshape import Figure, Tolerances, describe, match
from qshape.design import Design
from qshape.synthetic.effects import CameraEffects
from qshape.synthetic.synth import SynthParams, generate
from qshape.vision.extract import extract_detailed
from qshape.vision.params import ExtractParams


def _recognised(design: Design, img, ep: ExtractParams, s: float) -> tuple[int, int]:
    """(tiles of the right class, tiles of a wrong class) among the whole tiles drawn."""
    tol = Tolerances.load(joint_width=design.joint * s, point_tolerance=0.5 * s)
    refs = {}
    for slot in design.slots:
        if slot.shape_key not in refs:
            fig = slot.figure()
            refs[slot.shape_key] = describe(
                Figure.from_polygon(fig.points * s, curve_mask=fig.curve_mask), tol
            )
    figs = extract_detailed(img.image, ep).figures
    cents = np.array([f.centroid for f in figs])
    right = wrong = 0
    for t in img.tiles:
        if t.partial:
            continue
        cand = describe(figs[int(np.argmin(np.hypot(*(cents - t.center_px).T)))], tol)
        scored = [(m.score, k) for k, r in refs.items() if (m := match(r, cand, tol, False))]
        key = min(scored)[1] if scored else None
        right += key == t.slot.shape_key
        wrong += key is not None and key != t.slot.shape_key
    return right, wrong


def test_rough_hexagons_keep_their_six_corners():
    # 0.4 mm rough edges (1 mm correlation) spread a 60 deg corner over more samples than a
    # 2.5 % window sees: it turned by < 25 deg there, the corner was lost and two sides
    # became an arc (or the whole outline a circle). The bundled, wider window keeps them.
    # The windows are compared without the bent-run test (fit_split_turn_deg), which gives a
    # missed corner back and so rescues some of the narrow window's hexagons too (27 of 28).
    sp = SynthParams.load()
    s = sp.px_per_mm
    design = Design.load("hexagon")
    ep = ExtractParams.load()
    alone = replace(ep, outline=replace(ep.outline, fit_split_turn_deg=0.0))
    narrow = replace(alone, outline=replace(alone.outline, corner_window=0.025))
    whole = right = right_alone = right_narrow = 0
    for seed in (1, 3):
        img = generate(
            design,
            14,
            np.random.default_rng(seed),
            replace(sp, effects=CameraEffects(edge_roughness_mm=0.4)),
        )
        whole += sum(not t.partial for t in img.tiles)
        r, wrong = _recognised(design, img, ep, s)
        ra, wrong_alone = _recognised(design, img, alone, s)
        rn, wrong_narrow = _recognised(design, img, narrow, s)
        assert wrong == wrong_alone == wrong_narrow == 0
        right, right_alone, right_narrow = right + r, right_alone + ra, right_narrow + rn
    assert right >= whole - 1
    assert right_alone >= right_narrow + 2
