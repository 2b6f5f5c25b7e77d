"""`envs.cell.layout`: contact layouts keep their guarantees, are seeded, and rarely jam."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from shapely.geometry import Polygon, box

from envs.cell.config import load_cell_config
from envs.cell.layout import GRID_STEP, Footprint, footprints, layout_capacity, sample_layout
from envs.cell.tiles.shapes import tile_shapes_from_design
from envs.cell.tiles.tile import make_tiles
from envs.errors import CellError
from qshape.design import Design

CFG = load_cell_config()
AREA = tuple(CFG.input_belt.tile_area)
GAP = CFG.tiles.min_gap
LAYOUT_SEEDS = 40
"""Layouts per design checked for the gap."""


def _design_tiles(design: str) -> tuple[list[np.ndarray], np.ndarray]:
    """Noisy outlines and radii of a design's tiles, as many as one layout holds (<= 16)."""
    shapes, _ = tile_shapes_from_design(Design.load(design))
    tiles = make_tiles(shapes, CFG.tiles, np.random.default_rng(0))
    k = min(layout_capacity([t.outline for t in tiles], AREA, GAP), CFG.tiles.batch_size)
    return [t.outline for t in tiles[:k]], np.array([t.radius for t in tiles[:k]])


def _polygons(outlines: list[np.ndarray], poses: np.ndarray) -> list[Polygon]:
    out = []
    for o, (x, y, yaw) in zip(outlines, poses, strict=True):
        c, s = np.cos(yaw), np.sin(yaw)
        out.append(Polygon(o @ np.array([[c, s], [-s, c]]) + [x, y]))
    return out


@pytest.mark.parametrize("design", ["paper_mixed", "trencadis"])
def test_layouts_keep_the_gap_inside_the_area(design: str) -> None:
    """Every pair of outlines at least the gap apart, every outline inside the area.

    Forty layouts per design (~2 s): a pair close enough to need the exact distance test shows
    up in a few of them (seeds 6, 9, 15, 16: a bounds pre-filter that ignored the gap let such
    pairs through; five seeds never met one).
    """
    outlines, radii = _design_tiles(design)
    area = box(-AREA[0] / 2, -AREA[1] / 2, AREA[0] / 2, AREA[1] / 2)
    for seed in range(LAYOUT_SEEDS):
        poses = sample_layout(
            radii,
            AREA,
            GAP,
            CFG.tiles.placement_attempts,
            np.random.default_rng(seed),
            outlines=outlines,
            restarts=CFG.tiles.placement_restarts,
        )
        polys = _polygons(outlines, poses)
        assert all(area.contains(p) for p in polys)
        for a in range(len(polys)):
            d = shapely.distance(polys[a], polys[a + 1 :])
            assert np.all(d >= GAP - 1e-12), (seed, a, d.min())


def test_layout_is_seeded() -> None:
    """Same seed: same poses and the same generator state afterwards; another seed differs."""
    outlines, radii = _design_tiles("paper_mixed")
    fps = footprints(outlines, GAP)
    runs = []
    for seed in (3, 3, 4):
        rng = np.random.default_rng(seed)
        poses = sample_layout(radii, AREA, GAP, 400, rng, outlines=fps, restarts=40)
        runs.append((poses, rng.random()))
    assert np.array_equal(runs[0][0], runs[1][0]) and runs[0][1] == runs[1][1]
    assert not np.array_equal(runs[0][0], runs[2][0])
    # Outlines or their footprints: the same layout.
    again = sample_layout(
        radii, AREA, GAP, 400, np.random.default_rng(3), outlines=outlines, restarts=40
    )
    assert np.array_equal(again, runs[0][0])


def test_sixteen_tile_design_rarely_jams() -> None:
    """One try lays the 16 tiles of paper_mixed out in almost every seed (uniform random
    placement jammed in about 3 of 4)."""
    outlines, radii = _design_tiles("paper_mixed")
    assert len(outlines) == 16
    fps = footprints(outlines, GAP)
    jams = 0
    for seed in range(40):
        try:
            sample_layout(radii, AREA, GAP, 400, np.random.default_rng(seed), outlines=fps)
        except CellError:
            jams += 1
    assert jams <= 4


def test_each_tile_lies_against_a_tile_or_the_edge() -> None:
    """Contact placement: every tile within a few grid cells of the gap from a tile placed
    before it or from the area's edge."""
    outlines, radii = _design_tiles("paper_mixed")
    poses = sample_layout(
        radii, AREA, GAP, 400, np.random.default_rng(1), outlines=outlines, restarts=40
    )
    polys = _polygons(outlines, poses)
    edge = box(-AREA[0] / 2, -AREA[1] / 2, AREA[0] / 2, AREA[1] / 2).exterior
    order = np.argsort(-radii)
    slack = []
    for k, i in enumerate(order):
        before = [polys[j] for j in order[:k]]
        near = min([edge.distance(polys[i]) + GAP / 2, *shapely.distance(polys[i], before)])
        slack.append(near - GAP)
    assert max(slack) < 3 * GRID_STEP
    assert min(slack) >= -1e-12


def test_footprint_of_a_rectangle() -> None:
    rect = np.array([[-0.02, -0.01], [0.02, -0.01], [0.02, 0.01], [-0.02, 0.01]])
    fp = Footprint.of(rect, GAP)
    assert fp.half_extent == pytest.approx(0.01)
    assert fp.inner == pytest.approx(0.01)
    assert fp.reach == pytest.approx(np.hypot(0.02, 0.01))
    assert fp.area == pytest.approx(Polygon(rect).buffer(GAP / 2).area, rel=0.02)
    assert Polygon(fp.grown).contains(Polygon(rect))


def test_footprints_must_match_the_gap() -> None:
    outlines, radii = _design_tiles("paper_mixed")
    fps = footprints(outlines, GAP / 2)
    with pytest.raises(CellError, match="gap"):
        sample_layout(radii, AREA, GAP, 400, np.random.default_rng(0), outlines=fps)


def test_too_many_tiles_are_refused_before_placing() -> None:
    outlines, radii = _design_tiles("paper_mixed")
    small = (AREA[0] / 2, AREA[1])
    with pytest.raises(CellError, match="tile area"):
        sample_layout(radii, small, GAP, 400, np.random.default_rng(0), outlines=outlines)
