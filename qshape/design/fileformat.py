"""The design file format: reading a YAML mapping into design fields, writing one back.

The format is documented in ``configs/designs/README.md``. Reading is strict: unknown keys,
missing keys and values of the wrong type raise `DesignError` naming the slot and the key.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import yaml

from qshape.design.fields import DesignFields
from qshape.design.rules import DesignRules
from qshape.design.slot import Slot
from qshape.design.values import color_hex, number, parse_color, plain, round_mm
from qshape.errors import DesignError

DESIGN_KEYS = {"name", "description", "mesh", "joint", "grout_color", "slots"}
SLOT_KEYS = {"name", "shape", "color", "pose"}
POSE_KEYS = {"x", "y", "angle"}
DEFAULT_GROUT = "#d9d4c7"
"""Joint colour of a design file without ``grout_color``."""


def read_fields(
    data: Mapping[str, Any], rules: DesignRules | None = None, source: str = "<dict>"
) -> dict[str, Any]:
    """The `Design` fields of a design file mapping (not yet validated as a layout).

    Raises:
        DesignError: Not a mapping, unknown or missing keys, values of the wrong type.
    """
    rules = rules or DesignRules()
    if not isinstance(data, Mapping):
        raise DesignError(f"{source}: a design must be a mapping")
    unknown = sorted(set(data) - DESIGN_KEYS)
    if unknown:
        raise DesignError(f"{source}: unknown key(s) {unknown}; allowed: {sorted(DESIGN_KEYS)}")
    for key in ("name", "mesh", "joint", "slots"):
        if key not in data:
            raise DesignError(f"{source}: missing key {key!r}")
    mesh = data["mesh"]
    if not isinstance(mesh, Mapping) or set(mesh) != {"width", "height"}:
        raise DesignError(f"{source}: mesh must be a mapping with exactly width and height")
    size = (
        number(mesh["width"], f"{source}: mesh.width"),
        number(mesh["height"], f"{source}: mesh.height"),
    )
    joint = number(data["joint"], f"{source}: joint")
    raw = data["slots"]
    if not isinstance(raw, list) or not raw:
        raise DesignError(f"{source}: slots must be a non-empty list")
    slots = []
    for i, s in enumerate(raw):
        where = f"{source}: slot {i}"
        if not isinstance(s, Mapping):
            raise DesignError(f"{where}: must be a mapping")
        name = str(s.get("name", f"slot_{i}"))
        where = f"{source}: slot {name!r}"
        bad = sorted(set(s) - SLOT_KEYS)
        if bad:
            raise DesignError(f"{where}: unknown key(s) {bad}; allowed: {sorted(SLOT_KEYS)}")
        for key in ("shape", "color", "pose"):
            if key not in s:
                raise DesignError(f"{where}: missing key {key!r}")
        pose = s["pose"]
        if not isinstance(pose, Mapping) or sorted(set(pose) - POSE_KEYS):
            raise DesignError(f"{where}: pose must be a mapping of {sorted(POSE_KEYS)}")
        if "x" not in pose or "y" not in pose:
            raise DesignError(f"{where}: pose needs x and y")
        slots.append(
            Slot(
                name=name,
                shape=plain(s["shape"]) if isinstance(s["shape"], Mapping) else s["shape"],
                color=parse_color(s["color"], f"{where}.color"),
                x=number(pose["x"], f"{where}.pose.x", False),
                y=number(pose["y"], f"{where}.pose.y", False),
                angle=number(pose.get("angle", 0.0), f"{where}.pose.angle", False),
                rules=rules,
            )
        )
    return {
        "name": str(data["name"]),
        "mesh_size": size,
        "joint": joint,
        "slots": tuple(slots),
        "grout_color": parse_color(
            data.get("grout_color", DEFAULT_GROUT), f"{source}: grout_color"
        ),
        "description": str(data.get("description", "")),
        "rules": rules,
    }


def to_mapping(design: DesignFields) -> dict[str, Any]:
    """The design as a file mapping (inverse of `read_fields`)."""
    out: dict[str, Any] = {"name": design.name}
    if design.description:
        out["description"] = design.description
    out["mesh"] = {"width": round_mm(design.mesh_size[0]), "height": round_mm(design.mesh_size[1])}
    out["joint"] = round_mm(design.joint)
    out["grout_color"] = color_hex(design.grout_color)
    out["slots"] = [s.to_dict() for s in design.slots]
    return out


def save(design: DesignFields, path: str | Path, header: str = "") -> None:
    """Write the design as YAML (``header`` lines become leading comments)."""
    text = "".join(f"# {line}\n".replace("# \n", "#\n") for line in header.splitlines())
    text += yaml.safe_dump(to_mapping(design), sort_keys=False, default_flow_style=None, width=100)
    Path(path).write_text(text, encoding="utf-8")


__all__ = ["DESIGN_KEYS", "POSE_KEYS", "SLOT_KEYS", "read_fields", "save", "to_mapping"]
