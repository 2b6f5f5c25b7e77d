"""`Slot`: one tile position of a design (shape, colour, pose) and what derives from it."""

from __future__ import annotations

import functools
import hashlib
import json
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np
import yaml
from scipy.spatial import cKDTree

from qshape import geometry as geo
from qshape.design.memo import BoundedMemo
from qshape.design.paths import TilePath
from qshape.design.rules import DesignRules
from qshape.design.shapes import tile_path
from qshape.design.values import color_hex, plain, round_mm
from qshape.errors import DesignError
from qshape.geometry import FloatArray
from qshape.theory.figure import Figure

SYMMETRY_MEMO_SIZE = 4096
"""Shapes whose symmetry order is remembered (`SYMMETRY_MEMO`); an entry is a key (the
shape's canonical text, about 0.1-1 kB, and the rules) and an int: a few MB at most."""
SYMMETRY_MEMO: BoundedMemo[int] = BoundedMemo(SYMMETRY_MEMO_SIZE)
"""`Slot.symmetry` by (shape text, rules): the order depends on nothing else, and the same
shape is asked again by every slot of its class, every copy of a design and every check."""


_FIRST_PROBES = 32
"""Probes a symmetry test looks at before the others (most turns fail on them)."""
_REACH_MARGIN = 1e-6
"""Relative (and absolute, in [mm]) margin of the symmetry test's search radius over its
tolerance: every probe within the tolerance is found with its exact distance."""


@functools.lru_cache(maxsize=4096)
def _shape_text(shape_json: str) -> str:
    """The canonical text of a shape mapping (given as sorted JSON): its sorted YAML.

    A design of many copies of one shape (a mural) writes it once.
    """
    return yaml.safe_dump(json.loads(shape_json), sort_keys=True)


@dataclass(frozen=True)
class Slot:
    """One tile position of a design.

    Attributes:
        name: Unique name within the design.
        shape: The shape mapping as written in the design file (``kind``, its parameters and
            optional ``holes``); see ``configs/designs/README.md``.
        color: RGB in [0, 1].
        x: Mesh x of the tile's area centroid, in [mm].
        y: Mesh y of the tile's area centroid, in [mm] (y up).
        angle: Rotation of the shape about its centroid, in [deg], counter-clockwise.
        rules: Sampling and validation rules.
    """

    name: str
    shape: Mapping[str, Any]
    color: tuple[float, float, float]
    x: float
    y: float
    angle: float = 0.0
    rules: DesignRules = field(default_factory=DesignRules, compare=False, repr=False)

    @cached_property
    def local_path(self) -> TilePath:
        """Tile outline and holes in the tile frame: area centroid at the origin, angle 0, [mm].

        Raises:
            DesignError: Malformed shape.
        """
        path = tile_path(self.shape, f"slot {self.name!r}.shape")
        area, c = path.area_centroid(self.rules.outline_step_mm)
        if not area > 0.0:
            raise DesignError(f"slot {self.name!r}: zero or negative area (holes too large?)")
        return path.transformed(0.0, -c)

    @cached_property
    def path(self) -> TilePath:
        """Tile outline and holes placed on the mesh, [mm], y up."""
        return self.local_path.transformed(math.radians(self.angle), (self.x, self.y))

    def outline_mm(self) -> FloatArray:
        """Dense closed outline on the mesh, counter-clockwise, [mm], shape (m, 2)."""
        return self.path.outer.dense(self.rules.outline_step_mm)

    def holes_mm(self) -> list[FloatArray]:
        """Dense closed outline of each hole on the mesh, counter-clockwise, [mm]."""
        return [h.dense(self.rules.outline_step_mm) for h in self.path.holes]

    def figure(self) -> Figure:
        """The slot as a `qshape.Figure` in mesh millimetres (y up), with its colour.

        Made once per slot (a figure is read-only).
        """
        return self._figure

    @cached_property
    def _figure(self) -> Figure:
        return self.path.figure(self.color, self.rules.max_arc_deg)

    @property
    def centroid(self) -> FloatArray:
        """Area centroid on the mesh, [mm], shape (2,)."""
        return np.array([self.x, self.y])

    @cached_property
    def area(self) -> float:
        """Tile area with holes subtracted, in [mm^2]."""
        return self.local_path.area_centroid(self.rules.outline_step_mm)[0]

    @cached_property
    def shape_text(self) -> str:
        """The shape mapping's canonical text (YAML, sorted keys): equal for equal shapes."""
        return _shape_text(json.dumps(plain(self.shape), sort_keys=True))

    @cached_property
    def shape_key(self) -> str:
        """Identifier of the shape class: equal for slots whose shapes are equal (any pose)."""
        return hashlib.sha1(self.shape_text.encode()).hexdigest()[:12]

    @property
    def class_key(self) -> str:
        """Identifier of the shape-and-colour class."""
        return f"{self.shape_key}{color_hex(self.color)}"

    @cached_property
    def symmetry(self) -> int:
        """Rotational symmetry order of the shape (1: none, 4: square, 0: continuous).

        Remembered by shape and rules (`SYMMETRY_MEMO`).
        """
        return SYMMETRY_MEMO.get((self.shape_text, self.rules), self._symmetry)

    def _symmetry(self) -> int:
        rules = self.rules
        loops = (self.local_path.outer, *self.local_path.holes)
        samples = np.concatenate([lp.dense(rules.outline_step_mm / 4.0) for lp in loops])
        tree = cKDTree(samples)
        step = max(1, len(samples) // rules.symmetry_samples)
        probe = samples[::step]
        tol = rules.symmetry_tolerance * math.sqrt(self.area)

        # Only whether every probe lies within ``tol`` counts: probes farther than ``reach``
        # come back at inf (the search stops early), and a few probes first settle most turns
        # that are no symmetry. Same answer as the farthest probe's distance against ``tol``.
        reach = tol * (1.0 + _REACH_MARGIN) + _REACH_MARGIN
        first = probe[:_FIRST_PROBES]

        def invariant(angle: float) -> bool:
            for part in (first, probe):
                dist, _ = tree.query(geo.rotate(part, angle), distance_upper_bound=reach)
                if not np.max(dist) <= tol:
                    return False
            return True

        if invariant(1.0) and invariant(math.sqrt(2.0)):
            return 0
        for order in range(rules.max_symmetry_order, 1, -1):
            if invariant(2.0 * math.pi / order):
                return order
        return 1

    def to_dict(self) -> dict[str, Any]:
        """The slot as written in a design file."""
        return {
            "name": self.name,
            "shape": plain(self.shape),
            "color": color_hex(self.color),
            "pose": {"x": round_mm(self.x), "y": round_mm(self.y), "angle": round_mm(self.angle)},
        }


__all__ = ["SYMMETRY_MEMO", "SYMMETRY_MEMO_SIZE", "Slot"]
