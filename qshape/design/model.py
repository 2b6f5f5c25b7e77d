"""`Design`: a mosaic design (mesh, joint, slots) and its queries.

Reading and writing the file format live in `qshape.design.fileformat`, layout validation in
`qshape.design.checks`, designs from images in `qshape.design.from_image`; `Design`'s methods
are the public entry points to them.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from configs import CONFIG_DIR, ConfigError, parse_yaml, resolve_path
from configs.files import write_text
from qshape.design import checks, fileformat
from qshape.design.dxf_file import read_dxf, write_dxf
from qshape.design.from_image import design_mapping
from qshape.design.memo import BoundedMemo
from qshape.design.rules import DesignRules
from qshape.design.slot import Slot
from qshape.design.svg_file import read_svg, svg_text
from qshape.errors import DesignError
from qshape.theory.figure import Figure

DESIGN_SUBDIR = "designs"
"""Sub-folder of ``configs/`` holding the bundled designs."""
LOADED_DESIGNS = 64
"""Designs `Design.load` remembers (by file, text and rules; least recently used dropped
first): a design and its slots' outlines, a few hundred kB at most each."""
DRAWING_SUFFIXES = (".svg", ".dxf")
"""File suffixes `Design.load` reads as drawings (any other: the YAML design format)."""


@dataclass(frozen=True)
class Design:
    """A mosaic design: a rectangular mesh, a joint width and the slots to fill.

    Attributes:
        name: Design name.
        mesh_size: (width, height) of the mesh, in [mm]; the origin is its lower-left corner,
            y up.
        joint: Joint (grout) width between neighbouring tiles, in [mm].
        slots: The slots, names unique.
        grout_color: RGB in [0, 1] of the joints and empty mesh (used for rendering).
        description: Free text.
        rules: Sampling and validation rules.
    """

    name: str
    mesh_size: tuple[float, float]
    joint: float
    slots: tuple[Slot, ...]
    grout_color: tuple[float, float, float] = (0.85, 0.83, 0.78)
    description: str = ""
    rules: DesignRules = field(default_factory=DesignRules, compare=False, repr=False)

    # ------------------------------------------------------------------ loading and saving

    @classmethod
    def load(cls, name_or_path: str | Path, rules: DesignRules | None = None) -> Design:
        """Load and validate a design: a bundled name (``"paper_mixed"``), a YAML, SVG or DXF path.

        SVG and DXF drawings are read by `qshape.design.svg_file` and `qshape.design.dxf_file`
        (format: ``configs/designs/README.md``); they may warn with
        `qshape.errors.DesignFileWarning` (skipped text, a default joint).

        Raises:
            DesignError: Missing or unreadable file, duplicate or unknown keys, bad values,
                degenerate or overlapping slots, slots outside the mesh; for drawings also an
                open path, no mesh or unknown units; the message names the slot or element.
        """
        suffix = Path(str(name_or_path)).suffix.lower()
        if suffix in DRAWING_SUFFIXES:
            if not Path(name_or_path).is_file():
                raise DesignError(f"{name_or_path}: no such design file")
            read = read_svg if suffix == ".svg" else read_dxf
            return cls.from_dict(read(name_or_path, rules), rules=rules, source=str(name_or_path))
        try:
            path = resolve_path(name_or_path, DESIGN_SUBDIR)
        except ConfigError as exc:
            raise DesignError(str(exc)) from exc
        try:
            text = path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as exc:
            raise DesignError(f"cannot read configuration {path}: {exc}") from exc
        source = str(name_or_path)
        key = (str(path.resolve()), text, rules, source)
        design, said = _LOADED.get(key, lambda: _load_recorded(cls, path, text, rules, source))
        for w in said:  # what loading it said, said again at every load (at the caller's line)
            warnings.warn(w.message, stacklevel=2)
        return design

    @classmethod
    def from_dict(
        cls, data: Mapping[str, Any], rules: DesignRules | None = None, source: str = "<dict>"
    ) -> Design:
        """Build and validate a design from its file mapping (see `load`).

        Raises:
            DesignError: As `load`.
        """
        if rules is not None and not isinstance(rules, DesignRules):
            raise DesignError(f"rules must be DesignRules or None, got {type(rules).__name__}")
        design = cls(**fileformat.read_fields(data, rules, source))
        design.validate(source)
        return design

    def to_dict(self) -> dict[str, Any]:
        """The design as a file mapping (inverse of `from_dict`)."""
        return fileformat.to_mapping(self)

    def save(self, path: str | Path, header: str = "") -> None:
        """Write the design as YAML (``header`` lines become leading comments)."""
        fileformat.save(self, path, header)

    def to_svg(self, path: str | Path | None = None) -> str:
        """The design as an SVG drawing (millimetres), written to ``path`` when given.

        `load` reads it back to the same slots (outlines within 0.01 mm).
        """
        text = svg_text(self)
        if path is not None:
            write_text(Path(path), text)
        return text

    def to_dxf(self, path: str | Path) -> None:
        """Write the design as a DXF drawing (millimetres, ``$INSUNITS`` 4) to ``path``.

        `load` reads it back to the same slots (outlines within 0.01 mm).
        """
        write_dxf(self, path)

    def validate(self, source: str = "") -> None:
        """Check every slot and the layout (see `qshape.design.checks.validate`).

        Raises:
            DesignError: Duplicate names, degenerate or self-crossing outlines, bad holes,
                slots outside the mesh, or slots closer than the joint allows.
        """
        checks.validate(self, source)

    # ------------------------------------------------------------------------- queries
    def figures(self) -> list[Figure]:
        """Every slot as a `qshape.Figure` in mesh millimetres, in slot order."""
        return [s.figure() for s in self.slots]

    def slot(self, name: str) -> Slot:
        """The slot called ``name``.

        Raises:
            DesignError: No such slot (the message lists the names).
        """
        for s in self.slots:
            if s.name == name:
                return s
        raise DesignError(
            f"design {self.name!r} has no slot {name!r}; slots: {[s.name for s in self.slots]}"
        )

    def with_slots(self, slots: Sequence[Slot]) -> Design:
        """Copy with other slots (validated)."""
        d = replace(self, slots=tuple(slots))
        d.validate()
        return d

    @classmethod
    def from_image(
        cls,
        image: str | Path | np.ndarray,
        mm_per_px: float,
        joint_mm: float,
        *,
        name: str = "from_image",
        params: Any = None,
        rules: DesignRules | None = None,
    ) -> Design:
        """Design from a design image (tiles on a joint colour), e.g. drawn in any editor.

        Tiles are found by `qshape.extract`; tiles touching the image border are left out.
        Each tile becomes a ``polygon`` slot (arcs as bulges) with the extracted colour. The
        mesh is the whole image.

        Args:
            image: RGB uint8 array (H, W, 3) or a path to an image file (PNG, JPEG, ...).
            mm_per_px: Scale, in [mm/px].
            joint_mm: Joint width of the design, in [mm].
            name: Design name.
            params: `qshape.vision.params.ExtractParams` (None: ``configs/vision.yaml``).
            rules: Validation rules.

        Raises:
            DesignError: Unreadable file, bad scale, no tiles, or an invalid resulting design.
            qshape.vision.params.ImageError: Malformed image.
        """
        data = design_mapping(image, mm_per_px, joint_mm, name=name, params=params, rules=rules)
        return cls.from_dict(data, rules=rules, source=f"design image {name!r}")


def bundled_designs() -> list[str]:
    """Names of the designs in ``configs/designs/``."""
    return sorted(p.stem for p in (CONFIG_DIR / DESIGN_SUBDIR).glob("*.yaml"))


_LOADED: BoundedMemo[tuple[Design, list[warnings.WarningMessage]]] = BoundedMemo(LOADED_DESIGNS)
"""`Design.load`'s designs with the warnings their loading gave: the same file text and rules
give the same (frozen) design, validated once; every env of a fixed design loads it."""


def _load_recorded(
    cls: type[Design], path: Path, text: str, rules: DesignRules | None, source: str
) -> tuple[Design, list[warnings.WarningMessage]]:
    """Parse and validate a design file's text; the design and the warnings it gave."""
    import yaml  # noqa: PLC0415 - its error type only

    try:
        data = parse_yaml(text)
    except yaml.YAMLError as exc:
        raise DesignError(f"cannot read configuration {path}: {exc}") from exc
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise DesignError(f"{path}: top level must be a mapping of keys, got {type(data).__name__}")
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        design = cls.from_dict(data, rules=rules, source=source)
    return design, list(said)


__all__ = ["DESIGN_SUBDIR", "LOADED_DESIGNS", "Design", "bundled_designs"]
