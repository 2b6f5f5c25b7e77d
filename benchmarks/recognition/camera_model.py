"""Benchmark of the rendered camera: colour fidelity, lens, motion blur, render cost.

Run ``python -m benchmarks.recognition.camera_model``. On the ``paper_mixed`` design laid out on
the input belt (glaze colour noise off, so every glaze is exactly its palette colour):

- colour fidelity: per palette colour, the median rendered colour inside each tile's glaze
  (segmentation render, eroded by a pixel) against the glaze colour, the worst channel error
  [%], and the white-balance gain perception fits on the picture (1: nothing to correct);
- render cost of the input camera, ideal vs through the lens vs with belt blur vs both, at the
  cameras' full size and at the observations' default size, measured side by side in one
  process (ms per frame; wall clock on a shared machine: compare ratios);
- the pictures ``out/camera_colour_chart.png`` (glaze | rendered swatch per colour),
  ``out/camera_lens.png`` (ideal | distorted) and ``out/camera_blur.png`` (still | moving belt).

Writes ``out/bench_camera.json``.
"""

from __future__ import annotations

import dataclasses
import json
import time
from pathlib import Path
from typing import Any

import cv2
import mujoco
import numpy as np

from agents.scripted.config import load_agents_config
from agents.scripted.perception import perceive_tiles
from agents.scripted.white_balance import color_gain
from apps.cli import CommandParser, run_cli
from benchmarks.design_cell import build_design_cell
from configs.files import write_image, write_text
from envs.cell.cell import Cell
from envs.cell.config import CellConfig, load_cell_config
from envs.task_spec import work_areas
from qshape.design import Design

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "out"
LENS = (-0.1, 0.08, 0.0, 0.0, 0.0)
"""The realistic scenario's lens (configs/bench_scripted.yaml)."""
EXPOSURE_TIME = 0.01
"""[s] The realistic scenario's shutter time."""
BELT_SPEED = 0.1
"""[m/s]"""
SIZES = ((492, 656), (72, 96))
"""Image sizes timed (height, width) [px]."""
SWATCH_PX = 48


def _cell_config(lens: tuple[float, ...], exposure_time: float) -> CellConfig:
    base = load_cell_config()
    cam = dataclasses.replace(base.input_camera, distortion=lens, exposure_time=exposure_time)
    tiles = dataclasses.replace(base.tiles, color_jitter=0.0)
    return dataclasses.replace(base, input_camera=cam, tiles=tiles)


GLAZE_MIN_PIXELS = 50
"""Fewest inner pixels of a tile whose rendered colour is measured (slivers are left out) [px]."""


def glaze_colours(cell: Cell) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(rendered, glaze) colours of every visible tile, (n, 3) each in [0, 1], and the image.

    The rendered colour is the median inside the tile's segmentation mask eroded by one pixel
    (edges blend with the belt), over tiles with at least `GLAZE_MIN_PIXELS` such pixels.
    """
    h, w = cell.cfg.input_camera.height, cell.cfg.input_camera.width
    image = cell.render("input_camera")
    r = mujoco.Renderer(cell.model, h, w)
    try:
        r.enable_segmentation_rendering()
        r.update_scene(cell.data, camera="input_camera")
        seg = r.render()[..., 0]
    finally:
        r.close()
    got, want = [], []
    kernel = np.ones((3, 3), np.uint8)
    for glaze in cell.ids.tile_visual[:, 1]:
        inner = cv2.erode((seg == glaze).astype(np.uint8), kernel).astype(bool)
        if inner.sum() >= GLAZE_MIN_PIXELS:
            got.append(np.median(image[inner], axis=0) / 255.0)
            want.append(cell.model.geom_rgba[glaze, :3].astype(float))
    return np.array(got), np.array(want), image


def colour_table(design: Design) -> dict[str, Any]:
    """Rendered vs glaze colour per palette colour, and perception's white-balance gain."""
    cell, _ = build_design_cell(design, _cell_config((0.0,) * 5, 0.0), seed=0)
    try:
        cell.step(100)
        got, want, image = glaze_colours(cell)
        per = perceive_tiles(
            image, cell.camera_model("input_camera"), work_areas(cell)[0].tile_top_z
        )
    finally:
        cell.close()
    palette = np.unique(np.round(want, 4), axis=0)
    rows = []
    for colour in palette:
        sel = np.all(np.abs(np.round(want, 4) - colour) < 1e-6, axis=1)
        rendered = got[sel].mean(axis=0)
        rows.append(
            {
                "glaze": colour.round(3).tolist(),
                "rendered": rendered.round(3).tolist(),
                "error_pct": (100 * (rendered - colour) / colour).round(1).tolist(),
                "max_abs_error_255": float(np.max(np.abs(rendered - colour)) * 255),
                "tiles": int(sel.sum()),
            }
        )
    measured = np.array([t.color for t in per.tiles])
    gain = color_gain(measured, palette, load_agents_config().perception)
    _colour_chart(rows)
    return {"colours": rows, "white_balance_gain": gain.round(3).tolist()}


def _colour_chart(rows: list[dict[str, Any]]) -> None:
    chart = np.zeros((len(rows) * SWATCH_PX, 2 * SWATCH_PX, 3), np.uint8)
    for i, row in enumerate(rows):
        for j, key in enumerate(("glaze", "rendered")):
            rgb = np.clip(np.asarray(row[key]) * 255, 0, 255).astype(np.uint8)
            chart[i * SWATCH_PX : (i + 1) * SWATCH_PX, j * SWATCH_PX : (j + 1) * SWATCH_PX] = rgb
    write_image(OUT / "camera_colour_chart.png", chart[..., ::-1])


def render_cost(design: Design, repeats: int) -> dict[str, Any]:
    """Milliseconds per input-camera frame for each camera option, side by side in one process."""
    variants = {
        "ideal": ((0.0,) * 5, 0.0),
        "lens": (LENS, 0.0),
        "blur": ((0.0,) * 5, EXPOSURE_TIME),
        "lens+blur": (LENS, EXPOSURE_TIME),
    }
    cells = {}
    for name, (lens, exposure) in variants.items():
        cell, _ = build_design_cell(design, _cell_config(lens, exposure), seed=0)
        cell.belt_speed = BELT_SPEED
        cells[name] = cell
    out: dict[str, Any] = {}
    try:
        for h, w in SIZES:
            times: dict[str, list[float]] = {k: [] for k in cells}
            for cell in cells.values():
                cell.render("input_camera", h, w)  # renderer, lens maps, blur kernel
            for _ in range(repeats):  # interleaved: every option sees the same machine load
                for name, cell in cells.items():
                    t = time.perf_counter()
                    cell.render("input_camera", h, w)
                    times[name].append(time.perf_counter() - t)
            out[f"{h}x{w}"] = {k: 1e3 * float(np.median(v)) for k, v in times.items()}
        ideal = cells["ideal"].render("input_camera")
        lensed = cells["lens"].render("input_camera")
        blurred = cells["blur"].render("input_camera")
        write_image(OUT / "camera_lens.png", np.hstack([ideal, lensed])[..., ::-1])
        write_image(OUT / "camera_blur.png", np.hstack([ideal, blurred])[..., ::-1])
    finally:
        for cell in cells.values():
            cell.close()
    return out


def main(argv: list[str] | None = None) -> None:
    """Print the tables and write ``out/bench_camera.json``."""
    p = CommandParser(description=__doc__.splitlines()[0])
    p.add_argument("--design", default="paper_mixed")
    p.add_argument("--repeats", type=int, default=20, help="frames timed per option and size")
    args = p.parse_args(argv)
    OUT.mkdir(exist_ok=True)
    design = Design.load(args.design)
    colours = colour_table(design)
    print("glaze colour          rendered              error per channel [%]   max [1/255]")
    for row in colours["colours"]:
        print(
            f"{row['glaze']!s:22s}{row['rendered']!s:22s}{row['error_pct']!s:24s}"
            f"{row['max_abs_error_255']:.1f}"
        )
    print(f"white-balance gain fitted by perception: {colours['white_balance_gain']}")
    cost = render_cost(design, args.repeats)
    print("input camera render [ms/frame], median, options side by side:")
    for size, row in cost.items():
        print(f"  {size:8s} " + "  ".join(f"{k} {v:.1f}" for k, v in row.items()))
    result = {"colour": colours, "render_ms": cost, "lens": LENS, "exposure_time": EXPOSURE_TIME}
    write_text((OUT / "bench_camera.json"), json.dumps(result, indent=1))
    print(f"wrote {OUT / 'bench_camera.json'}")


if __name__ == "__main__":
    run_cli(main)
