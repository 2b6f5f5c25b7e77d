"""The paper's matching experiment (its Figs. 5-6), reproduced from a rendered image.

Run ``python -m apps.paper_experiment``: prints the table and writes
``out/paper_experiment.png`` (the tiles, their relevant points and numbers: Fig. 5c),
``out/paper_experiment_design_shape.png`` and ``..._design_shape_colour.png`` (the design with
the number of the tile that marked each object: Figs. 6a and 6b) and ``out/paper_experiment.json``.

Eight physical tiles (numbered 1-8 as in the paper's Fig. 5c) are drawn on a belt-coloured image
and recognised with `qshape.extract`; the design (Fig. 6) has 16 objects. The set reproduces
the
paper's findings:

* Shape only, the paper's loop (each tile in turn marks *every* still-unmarked design object of
  its shape, and a marked object is not compared again): tile 2 marks five objects, tile 3 three,
  tiles 5 and 7 one each; tiles 1 and 8 have the same shape in different colours and both design
  objects of that shape are marked 1, so tile 8 finds nothing (the paper's "mark-as-matched"
  effect); the same happens to tiles 4 and 6 (both objects marked 4).
* Shape and colour: tiles 2, 3, 4, 5, 6 and 8 are found; tile 2 only twice (two of its five
  same-shape objects share its colour); tiles 1 and 7 are not found (no object of their shape has
  their colour). (The paper's point 3 names "7 and 8"; with its point 1 listing 8 as found, 1 and
  7 is the consistent reading.)
* One tile per slot (what the cell does): the greedy loop in tile order and the optimal
  assignment. Tiles 4 and 6 differ in size within the joint tolerance: shape only, tile 4 fits
  both "rectangle" objects and tile 6 only the larger; greedy gives tile 4 the first one listed
  (the larger) and leaves tile 6 out, the optimal assignment places both. With colour the two
  objects have tile 4's and tile 6's colours, so both methods place both.
* Design objects of shapes no tile has (hexagon, semicircle) stay unmatched.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np

import qshape
from apps.cli import CommandParser, run_cli
from configs.files import write_image, write_text
from qshape.design import Design, Slot
from qshape.synthetic.render import RenderParams, fill_tiles, mm_to_px, render_design
from qshape.synthetic.synth import place_path
from qshape.theory.assign import feasible_pairs
from qshape.theory.tolerances import default_tolerances

ROOT = Path(__file__).resolve().parents[1]

PX_PER_MM = 3.0
"""Image scale of the tile picture [px/mm]."""
IMAGE_SIZE = (492, 656)
"""Picture (height, width) [px] (the paper's AVT Guppy F-033C)."""
BELT = (0.24, 0.26, 0.28)
"""Belt colour, RGB in [0, 1]."""
BLUR_SIGMA_PX = 0.7
"""Optical blur of the picture [px]."""

RED, GREEN, BLUE = "#c0392b", "#3f9e4d", "#2e6fd1"
YELLOW, PURPLE, TEAL = "#e8c33a", "#8e4fb5", "#2aa39a"
ORANGE, PINK, GREY = "#e07b2a", "#d6609a", "#8c8c8c"

SQUARE = {"kind": "square", "size": 30.0}
RECT_BIG = {"kind": "rectangle", "width": 40.0, "height": 20.0}
RECT_SMALL = {"kind": "rectangle", "width": 30.0, "height": 15.0}
RIGHT_TRI = {"kind": "triangle_right", "width": 40.0, "height": 28.0}
ELL = {"kind": "polygon", "vertices": [[0, 0], [36, 0], [36, 14], [14, 14], [14, 36], [0, 36]]}
OBTUSE_TRI = {"kind": "triangle_isosceles", "base": 44.0, "height": 16.0}
CIRCLE = {"kind": "circle", "radius": 15.0}
HEXAGON = {"kind": "regular_polygon", "sides": 6, "radius": 17.0}
SEMI = {"kind": "semicircle", "radius": 18.0}

# Physical tiles, numbered as in the paper's Fig. 5c: (shape, colour, centre [mm], angle [deg]).
TILES: tuple[tuple[dict[str, Any], str, tuple[float, float], float], ...] = (
    (SQUARE, RED, (35.0, 125.0), 20.0),  # 1: same shape as 8, a colour absent from the design
    (RIGHT_TRI, YELLOW, (90.0, 125.0), -35.0),  # 2: five objects of its shape, two of its colour
    (ELL, PURPLE, (150.0, 128.0), 60.0),  # 3: three objects
    ({"kind": "rectangle", "width": 35.0, "height": 17.5}, BLUE, (35.0, 70.0), 75.0),  # 4
    (OBTUSE_TRI, TEAL, (100.0, 65.0), 150.0),  # 5: one object
    (RECT_BIG, GREY, (160.0, 65.0), -20.0),  # 6: same shape as 4, larger, another colour
    (CIRCLE, ORANGE, (35.0, 22.0), 0.0),  # 7: one object of its shape, another colour
    (SQUARE, GREEN, (190.0, 20.0), -10.0),  # 8: same shape as 1
)
"""The eight tiles of the experiment."""

# Design objects (Fig. 6): name, shape, colour; laid out on a 5 x 4 grid.
DESIGN_OBJECTS: tuple[tuple[str, dict[str, Any], str], ...] = (
    ("square_a", SQUARE, GREEN),
    ("rect_big", RECT_BIG, GREY),
    ("tri_yellow_1", RIGHT_TRI, YELLOW),
    ("tri_red", RIGHT_TRI, RED),
    ("ell_1", ELL, PURPLE),
    ("rect_small", RECT_SMALL, BLUE),
    ("tri_blue", RIGHT_TRI, BLUE),
    ("square_b", SQUARE, GREEN),
    ("ell_2", ELL, PURPLE),
    ("tri_yellow_2", RIGHT_TRI, YELLOW),
    ("obtuse_teal", OBTUSE_TRI, TEAL),
    ("tri_orange", RIGHT_TRI, ORANGE),
    ("ell_3", ELL, PURPLE),
    ("circle_pink", CIRCLE, PINK),
    ("hexagon", HEXAGON, ORANGE),
    ("semicircle", SEMI, TEAL),
)
GRID_PITCH_MM = 55.0
"""Distance between design object centres [mm]."""
GRID_COLUMNS = 4


def paper_design() -> Design:
    """The experiment's design (16 objects on a 4 x 4 grid, 2 mm joint)."""
    slots = []
    for k, (name, shape, color) in enumerate(DESIGN_OBJECTS):
        row, col = divmod(k, GRID_COLUMNS)
        slots.append(
            {
                "name": name,
                "shape": shape,
                "color": color,
                "pose": {
                    "x": GRID_PITCH_MM * (col + 0.5),
                    "y": GRID_PITCH_MM * (GRID_COLUMNS - row - 0.5),
                    "angle": 0.0,
                },
            }
        )
    side = GRID_PITCH_MM * GRID_COLUMNS
    return Design.from_dict(
        {
            "name": "paper_experiment",
            "mesh": {"width": side, "height": side},
            "joint": 2.0,
            "slots": slots,
        }
    )


def render_tiles() -> np.ndarray:
    """The picture of the eight tiles, RGB uint8 of `IMAGE_SIZE`."""
    h, w = IMAGE_SIZE
    image = np.empty((h, w, 3), np.uint8)
    image[:] = [round(255 * c) for c in BELT]
    drawn, colors = [], []
    for k, (shape, color, (x, y), angle) in enumerate(TILES):
        slot = Slot(f"tile{k + 1}", shape, _rgb(color), 0.0, 0.0)
        centre_px = (x * PX_PER_MM, h - y * PX_PER_MM)
        path = place_path(slot.local_path, np.radians(angle), centre_px, PX_PER_MM)
        drawn.append((path.outer.dense(0.5), [hh.dense(0.5) for hh in path.holes]))
        colors.append(slot.color)
    fill_tiles(image, drawn, colors, RenderParams())
    return cv2.GaussianBlur(image, (0, 0), BLUR_SIGMA_PX)


def _rgb(hex_color: str) -> tuple[float, float, float]:
    v = hex_color.lstrip("#")
    return (int(v[0:2], 16) / 255.0, int(v[2:4], 16) / 255.0, int(v[4:6], 16) / 255.0)


@dataclass(frozen=True)
class ExperimentResult:
    """Outcome of the experiment.

    Attributes:
        tile_numbers: Paper number (1-8) of each extracted figure, in extraction order.
        marks_shape: Design object name -> tile number that marked it (paper's loop, shape only).
        marks_color: The same with colour.
        assign: Method and colour ("greedy/shape", ...) -> {tile number: object name}.
        design_names: Names of the design objects.
    """

    tile_numbers: tuple[int, ...]
    marks_shape: dict[str, int]
    marks_color: dict[str, int]
    assign: dict[str, dict[int, str]]
    design_names: tuple[str, ...]

    def marked_by(self, tile: int, use_color: bool) -> list[str]:
        """Objects marked by a tile number."""
        marks = self.marks_color if use_color else self.marks_shape
        return [name for name, t in marks.items() if t == tile]


def paper_loop(
    tiles: list[qshape.Description], slots: list[qshape.Description], use_color: bool
) -> dict[int, int]:
    """The paper's loop: each tile in order marks every unmarked object it matches.

    Returns:
        Slot index -> tile index (into ``tiles``).
    """
    t, s, _, _ = feasible_pairs(tiles, slots, default_tolerances(), use_color)
    matches: dict[int, list[int]] = {}
    for ti, si in sorted(zip(t.tolist(), s.tolist(), strict=True)):
        matches.setdefault(ti, []).append(si)
    marked: dict[int, int] = {}
    for ti in range(len(tiles)):
        for si in matches.get(ti, []):
            if si not in marked:
                marked[si] = ti
    return marked


def run_experiment() -> tuple[ExperimentResult, np.ndarray, list[qshape.Figure]]:
    """Render, extract, describe and match; returns the result, the image and the figures.

    Raises:
        qshape.QShapeError: Extraction found a different number of tiles than drawn.
    """
    design = paper_design()
    image = render_tiles()
    figs_px = qshape.extract(image)
    if len(figs_px) != len(TILES):
        raise qshape.QShapeError(f"extracted {len(figs_px)} tiles, drew {len(TILES)}")
    h = IMAGE_SIZE[0]
    numbers = []
    for f in figs_px:  # number each figure by the nearest drawn tile centre
        c = np.asarray(f.centroid)
        d = [
            np.hypot(c[0] - x * PX_PER_MM, c[1] - (h - y * PX_PER_MM)) for _, _, (x, y), _ in TILES
        ]
        numbers.append(int(np.argmin(d)) + 1)
    order = np.argsort(numbers)  # the paper's loop runs over tiles 1..8
    figs_mm = [
        qshape.Figure.from_polygon(
            np.asarray(figs_px[k].points) / PX_PER_MM,
            [
                qshape.Boundary.make(np.asarray(b.points) / PX_PER_MM, b.curve_mask, y_down=True)
                for b in figs_px[k].holes
            ],
            figs_px[k].color,
            curve_mask=figs_px[k].curve_mask,
            y_down=True,
        )
        for k in order
    ]
    nums = [numbers[k] for k in order]
    tdesc = qshape.describe_many(figs_mm)
    sdesc = qshape.describe_many(design.figures())
    names = tuple(s.name for s in design.slots)
    marks = {
        c: {names[si]: nums[ti] for si, ti in paper_loop(tdesc, sdesc, c).items()}
        for c in (False, True)
    }
    assigned: dict[str, dict[int, str]] = {}
    for method in ("greedy", "optimal"):
        for with_color in (False, True):
            res = qshape.assign(tdesc, sdesc, method=method, use_color=with_color)
            key = f"{method}/{'shape+colour' if with_color else 'shape'}"
            assigned[key] = {nums[a.tile]: names[a.slot] for a in res}
    result = ExperimentResult(tuple(nums), marks[False], marks[True], assigned, names)
    return result, image, figs_mm


SHORT_NAMES = {
    "square": "square",
    "rectangle": "rectangle",
    "triangle_right": "right tri.",
    "polygon": "L",
    "triangle_isosceles": "obtuse tri.",
    "circle": "circle",
}
"""Table names of the tiles' shape kinds."""


def table(r: ExperimentResult) -> str:
    """The experiment as a text table (one row per tile)."""
    cols = ("greedy/shape", "optimal/shape", "greedy/shape+colour", "optimal/shape+colour")
    rows = []
    for k, (shape, color, _, _) in enumerate(TILES):
        n = k + 1
        rows.append(
            [
                str(n),
                SHORT_NAMES.get(shape["kind"], shape["kind"]),
                color,
                ", ".join(r.marked_by(n, False)) or "-",
                ", ".join(r.marked_by(n, True)) or "-",
                *(r.assign[c].get(n, "-") for c in cols),
            ]
        )
    head = ["tile", "shape", "colour", "paper loop: shape", "paper loop: shape+colour", *cols]
    widths = [max(len(x[i]) for x in [head, *rows]) for i in range(len(head))]
    lines = ["  ".join(h.ljust(w) for h, w in zip(head, widths, strict=True))]
    lines.append("-" * len(lines[0]))
    lines += ["  ".join(c.ljust(w) for c, w in zip(x, widths, strict=True)) for x in rows]
    unmatched = [nm for nm in r.design_names if nm not in r.marks_shape]
    lines.append(f"design objects matched by no tile (shape only): {', '.join(unmatched)}")
    return "\n".join(lines)


DESIGN_PX_PER_MM = 2.5
"""Scale of the design pictures [px/mm]."""


def design_marks(design: Design, marks: dict[str, int]) -> np.ndarray:
    """The design (Fig. 6) with each marked object showing the number of its tile, RGB."""
    s = DESIGN_PX_PER_MM
    image = render_design(design, s, overlay=True)
    h_mm = design.mesh_size[1]
    for slot in design.slots:
        if slot.name in marks:
            c = mm_to_px(np.asarray([slot.centroid]), h_mm, s)[0]
            cv2.putText(image, str(marks[slot.name]), (int(c[0]) - 6, int(c[1]) + 8),
                        cv2.FONT_HERSHEY_SIMPLEX, 0.8, (255, 255, 255), 2, cv2.LINE_AA)  # fmt: skip
    return image


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Run the experiment, print the table, write the picture and JSON."""
    parser = CommandParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "out")
    args = parser.parse_args(argv)
    r, image, figs = run_experiment()
    print(table(r))
    args.out.mkdir(parents=True, exist_ok=True)
    shown = cv2.cvtColor(image, cv2.COLOR_RGB2BGR)
    for n, f in zip(r.tile_numbers, figs, strict=True):
        c = np.asarray(f.centroid) * PX_PER_MM  # figures are pixel coordinates / scale
        pts = np.round(np.asarray(f.points) * PX_PER_MM).astype(np.int32)
        cv2.polylines(shown, [pts], True, (255, 255, 255), 1, cv2.LINE_AA)
        for p in pts:
            cv2.circle(shown, (int(p[0]), int(p[1])), 3, (0, 0, 255), -1, cv2.LINE_AA)
        cv2.putText(shown, str(n), (int(c[0]) - 5, int(c[1]) + 5), cv2.FONT_HERSHEY_SIMPLEX,
                    0.6, (255, 255, 255), 2, cv2.LINE_AA)  # fmt: skip
    write_image(args.out / "paper_experiment.png", shown)
    design = paper_design()
    for suffix, marks in (("shape", r.marks_shape), ("shape_colour", r.marks_color)):
        write_image(
            args.out / f"paper_experiment_design_{suffix}.png",
            cv2.cvtColor(design_marks(design, marks), cv2.COLOR_RGB2BGR),
        )
    data = {
        "marks_shape": r.marks_shape,
        "marks_shape_colour": r.marks_color,
        "assign": {k: {str(t): s for t, s in v.items()} for k, v in r.assign.items()},
    }
    write_text((args.out / "paper_experiment.json"), json.dumps(data, indent=2))
    return data


if __name__ == "__main__":
    run_cli(main)
