"""Mosaic designs: the mesh, the joint and the slots (shape, colour, pose) a cell assembles.

A design lives in a YAML file (format in ``configs/designs/README.md``), is validated strictly on
load (duplicate or unknown keys, bad sizes, unknown shape kinds, degenerate or self-crossing
outlines, overlapping slots, slots outside the mesh) and gives each slot as a `qshape.Figure` in
mesh millimetres (x right, y up, origin at the mesh's lower-left corner).

One module per concept:

- `qshape.design.model`: `Design`, the design value and its queries;
- `qshape.design.slot`: `Slot`, one tile position and what derives from it (outline, symmetry);
- `qshape.design.paths`: `Loop` and `TilePath`, outlines of straight edges and arcs (bulges);
- `qshape.design.shapes`: the shape kinds of the file format compiled to a `TilePath`;
- `qshape.design.values`: checked numbers and colours of the file format;
- `qshape.design.fileformat`: reading and writing design files;
- `qshape.design.checks`: layout validation;
- `qshape.design.from_image`: a design from a design image;
- `qshape.design.rules`: `DesignRules`, sampling and validation parameters.
"""

from qshape.config_sections import load_section
from qshape.design.model import DESIGN_SUBDIR, Design, bundled_designs
from qshape.design.paths import Loop, TilePath
from qshape.design.rules import DesignRules
from qshape.design.slot import Slot
from qshape.design.values import color_hex
from qshape.errors import DesignError

__all__ = [
    "DESIGN_SUBDIR",
    "Design",
    "DesignError",
    "DesignRules",
    "Loop",
    "Slot",
    "TilePath",
    "bundled_designs",
    "color_hex",
    "load_section",
]
