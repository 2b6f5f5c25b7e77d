"""`envs.layout`: the batched layout sampler takes the same decisions as a plain one."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from shapely.geometry import Polygon

from envs.cell_config import load_cell_config
from envs.errors import CellError, LayoutError
from envs.layout import layout_capacity, sample_layout
from envs.tile_shapes import tile_shapes_from_design
from envs.tiles import make_tiles
from qshape.design import Design


def _reference(radii, half, gap, attempts, rng, *, outlines):
    """Candidate by candidate, as the sampler's docstring states it (one layout try)."""
    centres, rads, placed = np.zeros((0, 2)), np.zeros(0), []
    out = np.zeros((len(radii), 3))
    for i in np.argsort(-radii):
        lim = np.maximum(half - radii[i], 0.0)
        cand = rng.uniform(-lim, lim, size=(attempts, 2))
        yaws = rng.uniform(-np.pi, np.pi, attempts)
        d = np.linalg.norm(cand[:, None, :] - centres[None, :, :], axis=2)
        clear = d >= rads[None, :] + radii[i] + gap
        for c in range(attempts):
            co, si = np.cos(yaws[c]), np.sin(yaws[c])
            poly = Polygon(outlines[i] @ np.array([[co, si], [-si, co]]) + cand[c])
            x0, y0, x1, y1 = poly.bounds
            if not (x0 >= -half[0] and x1 <= half[0] and y0 >= -half[1] and y1 <= half[1]):
                continue
            near = [placed[k] for k in np.flatnonzero(~clear[c])]
            if not near or np.all(shapely.distance(poly, near) >= gap):
                break
        else:
            raise LayoutError("jammed")
        placed.append(poly)
        out[i] = (*cand[c], yaws[c])
        centres = np.vstack([centres, cand[c]])
        rads = np.append(rads, radii[i])
    return out


def _reference_layout(radii, area, gap, attempts, rng, *, outlines, restarts):
    for _ in range(restarts - 1):
        try:
            return _reference(radii, np.asarray(area) / 2, gap, attempts, rng, outlines=outlines)
        except CellError:
            continue
    return _reference(radii, np.asarray(area) / 2, gap, attempts, rng, outlines=outlines)


def _outcome(sampler, *args, **kwargs):
    """Poses, or the error's message when the layout jams."""
    try:
        return sampler(*args, **kwargs)
    except CellError as exc:
        return str(exc)


@pytest.mark.parametrize("design", ["paper_mixed", "trencadis"])
def test_layout_equals_the_candidate_by_candidate_rule(design: str) -> None:
    """Same poses, same generator state afterwards, on noisy outlines of real designs."""
    cfg = load_cell_config()
    shapes, _ = tile_shapes_from_design(Design.load(design))
    tiles = make_tiles(shapes, cfg.tiles, np.random.default_rng(0))
    area, gap = tuple(cfg.input_belt.tile_area), cfg.tiles.min_gap
    k = min(layout_capacity([t.outline for t in tiles], area, gap), cfg.tiles.batch_size)
    outlines = [t.outline for t in tiles[:k]]
    radii = np.array([t.radius for t in tiles[:k]])
    for seed in range(4):
        fast, slow = np.random.default_rng(seed), np.random.default_rng(seed)
        a = _outcome(
            sample_layout,
            radii,
            area,
            gap,
            cfg.tiles.placement_attempts,
            fast,
            outlines=outlines,
            restarts=cfg.tiles.placement_restarts,
        )
        b = _outcome(
            _reference_layout,
            radii,
            area,
            gap,
            cfg.tiles.placement_attempts,
            slow,
            outlines=outlines,
            restarts=cfg.tiles.placement_restarts,
        )
        assert isinstance(a, np.ndarray) or seed > 0  # the first seed lays every tile out
        assert type(a) is type(b)
        if isinstance(a, np.ndarray):
            assert np.array_equal(a, b)
        assert fast.random() == slow.random()
