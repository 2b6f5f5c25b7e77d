"""Murals: one mosaic design laid over several meshes, as factories ship it.

A mural is too large for one mesh sheet, so it is cut along joints into rectangular meshes;
each mesh is an ordinary `qshape.Design` (its own frame: lower-left corner at the origin) and
carries its placement in the mural (the mesh's lower-left corner in the mural frame, [mm]).
`Mural.split` cuts a mural-wide design into meshes; `Mural.load` reads the bundled format
(``configs/murals/<name>.yaml`` naming one design file per mesh; ``configs/designs/README.md``
documents it); `Mural.design` puts every mesh back into one mural-wide design.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import yaml

from configs import CONFIG_DIR, ConfigError, load_yaml, resolve_path
from configs.files import write_text
from qshape.design import Design, DesignError

MURAL_SUBDIR = "murals"
"""Sub-folder of ``configs/`` holding the bundled murals."""

_MURAL_KEYS = {"name", "description", "joint", "meshes"}
_MESH_KEYS = {"name", "design", "x", "y"}


class MuralError(DesignError):
    """A mural file or value is malformed; the message names the mesh and the problem."""


@dataclass(frozen=True)
class MuralMesh:
    """One mesh of a mural.

    Attributes:
        name: Unique name within the mural (``r<row>c<column>`` when made by `Mural.split`).
        design: The mesh's design, in the mesh's own frame (lower-left corner at the origin).
        x: Mural x of the mesh's lower-left corner, in [mm].
        y: Mural y of the mesh's lower-left corner, in [mm] (y up).
        source: The design file it was loaded from ("" when built in memory); what a cell
            loads to assemble this mesh.
    """

    name: str
    design: Design
    x: float
    y: float
    source: str = ""


@dataclass(frozen=True)
class Mural:
    """A mosaic design over several meshes.

    Attributes:
        name: Mural name.
        joint: Joint width between tiles, in [mm]; every mesh's design has this joint, and
            tiles on neighbouring meshes are at least this far apart too.
        meshes: The meshes, names unique, in assembly order.
        description: Free text.
    """

    name: str
    joint: float
    meshes: tuple[MuralMesh, ...]
    description: str = ""

    # ------------------------------------------------------------------------ building
    @classmethod
    def split(
        cls,
        design: Design,
        mesh_size: tuple[float, float],
        name: str | None = None,
        description: str = "",
    ) -> Mural:
        """Cut a mural-wide design into meshes of ``mesh_size`` on a grid from its origin.

        Each slot goes to the mesh holding its centroid and must lie wholly inside it (cuts
        run along joints). Meshes without slots are left out; each mesh design keeps the
        mural's joint and grout and takes the slots' names.

        Args:
            design: The whole mural as one design, in [mm].
            mesh_size: (width, height) of one mesh, in [mm].
            name: Mural name (default: the design's).
            description: Free text (default: the design's).

        Raises:
            MuralError: A non-positive mesh size, or a slot crossing a cut.
        """
        w, h = mesh_size
        if not (w > 0 and h > 0):
            raise MuralError(f"mesh size must be positive, got {mesh_size} mm")
        cells: dict[tuple[int, int], list[Any]] = {}
        for s in design.slots:
            col, row = math.floor(s.x / w), math.floor(s.y / h)
            cells.setdefault((row, col), []).append(s)
        meshes = []
        for (row, col), slots in sorted(cells.items()):
            x0, y0 = col * w, row * h
            moved = [replace(s, x=s.x - x0, y=s.y - y0) for s in slots]
            mesh_name = f"r{row}c{col}"
            try:
                mesh = Design(
                    name=f"{name or design.name}_{mesh_name}",
                    mesh_size=(w, h),
                    joint=design.joint,
                    slots=tuple(moved),
                    grout_color=design.grout_color,
                    description=f"mesh {mesh_name} of the mural {name or design.name}",
                    rules=design.rules,
                )
                mesh.validate()
            except DesignError as exc:
                raise MuralError(f"mesh {mesh_name} (cut at x {x0}, y {y0} mm): {exc}") from exc
            meshes.append(MuralMesh(mesh_name, mesh, x0, y0))
        mural = cls(
            name or design.name,
            design.joint,
            tuple(meshes),
            description or design.description,
        )
        mural.validate()
        return mural

    # ------------------------------------------------------------------ loading and saving
    @classmethod
    def load(cls, name_or_path: str | Path) -> Mural:
        """Load and validate a mural: a bundled name or a YAML path.

        Mesh design paths in the file are relative to the file's folder.

        Raises:
            MuralError: Missing or unreadable files, unknown or missing keys, bad values, a
                mesh design that does not load, meshes that overlap or differ in joint.
        """
        try:
            path = resolve_path(name_or_path, MURAL_SUBDIR)
            data = load_yaml(path)
        except ConfigError as exc:
            raise MuralError(str(exc)) from exc
        return cls.from_dict(data, path.parent, source=str(path))

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], folder: Path, source: str = "<dict>") -> Mural:
        """Build and validate a mural from its file mapping (see `load`).

        Args:
            data: The file mapping.
            folder: Folder the mesh design paths are relative to.
            source: Name used in error messages.

        Raises:
            MuralError: As `load`.
        """
        if not isinstance(data, Mapping):
            raise MuralError(f"{source}: a mural must be a mapping")
        unknown = sorted(set(data) - _MURAL_KEYS)
        if unknown:
            raise MuralError(f"{source}: unknown key(s) {unknown}; allowed: {sorted(_MURAL_KEYS)}")
        for key in ("name", "joint", "meshes"):
            if key not in data:
                raise MuralError(f"{source}: missing key {key!r}")
        raw = data["meshes"]
        if not isinstance(raw, list) or not raw:
            raise MuralError(f"{source}: meshes must be a non-empty list")
        meshes = []
        for i, m in enumerate(raw):
            if not isinstance(m, Mapping):
                raise MuralError(f"{source}: mesh {i} must be a mapping")
            where = f"{source}: mesh {m.get('name', i)!r}"
            bad = sorted(set(m) - _MESH_KEYS)
            missing = sorted(_MESH_KEYS - set(m))
            if bad or missing:
                raise MuralError(
                    f"{where}: unknown key(s) {bad}, missing key(s) {missing}; "
                    f"required: {sorted(_MESH_KEYS)}"
                )
            file = folder / str(m["design"])
            if not file.is_file():
                raise MuralError(f"{where}: design file {file} not found")
            try:
                design = Design.load(file)
            except DesignError as exc:
                raise MuralError(f"{where}: {exc}") from exc
            meshes.append(
                MuralMesh(
                    str(m["name"]),
                    design,
                    _number(m["x"], where),
                    _number(m["y"], where),
                    str(file),
                )
            )
        joint = _number(data["joint"], f"{source}: joint")
        if not joint > 0:
            raise MuralError(f"{source}: joint must be positive, got {joint}")
        mural = cls(str(data["name"]), joint, tuple(meshes), str(data.get("description", "")))
        mural.validate(source)
        return mural

    def save(self, path: str | Path, header: str = "") -> None:
        """Write the mural file and one design file per mesh in ``<stem>/`` beside it.

        ``header`` lines become leading comments of every file written.
        """
        path = Path(path)
        folder = path.parent / path.stem
        folder.mkdir(parents=True, exist_ok=True)
        for m in self.meshes:
            m.design.save(folder / f"{m.name}.yaml", header)
        data: dict[str, Any] = {"name": self.name}
        if self.description:
            data["description"] = self.description
        data["joint"] = self.joint
        data["meshes"] = [
            {"name": m.name, "design": f"{path.stem}/{m.name}.yaml", "x": m.x, "y": m.y}
            for m in self.meshes
        ]
        text = "".join(f"# {line}\n".replace("# \n", "#\n") for line in header.splitlines())
        text += yaml.safe_dump(data, sort_keys=False, default_flow_style=None, width=100)
        write_text(path, text)

    # ------------------------------------------------------------------------ queries
    @property
    def tiles(self) -> int:
        """Number of slots over all meshes."""
        return sum(len(m.design.slots) for m in self.meshes)

    @property
    def size(self) -> tuple[float, float]:
        """(width, height) of the bounding box of all meshes from the origin, in [mm]."""
        return (
            max(m.x + m.design.mesh_size[0] for m in self.meshes),
            max(m.y + m.design.mesh_size[1] for m in self.meshes),
        )

    def mesh(self, name: str) -> MuralMesh:
        """The mesh called ``name``.

        Raises:
            MuralError: No such mesh (the message lists the names).
        """
        for m in self.meshes:
            if m.name == name:
                return m
        raise MuralError(
            f"mural {self.name!r} has no mesh {name!r}; meshes: {[m.name for m in self.meshes]}"
        )

    def design(self) -> Design:
        """Every mesh's slots in the mural frame as one design (already valid: see `validate`).

        Slot names are ``<mesh>/<slot>``; the mesh of the design is the mural's bounding box.
        """
        slots = tuple(
            replace(s, name=f"{m.name}/{s.name}", x=s.x + m.x, y=s.y + m.y)
            for m in self.meshes
            for s in m.design.slots
        )
        first = self.meshes[0].design
        return Design(
            name=self.name,
            mesh_size=self.size,
            joint=self.joint,
            slots=slots,
            grout_color=first.grout_color,
            description=self.description,
            rules=first.rules,
        )

    def check_fits(self, width: float, height: float) -> None:
        """Check that every mesh fits a mesh area of ``width`` x ``height`` [mm] (a cell's).

        Raises:
            MuralError: A mesh is larger; the message names it.
        """
        for m in self.meshes:
            w, h = m.design.mesh_size
            if w > width or h > height:
                raise MuralError(
                    f"mural {self.name!r}: mesh {m.name!r} is {w} x {h} mm, larger than the "
                    f"{width} x {height} mm mesh area"
                )

    # ------------------------------------------------------------------------ validation
    def validate(self, source: str = "") -> None:
        """Check names, joints and layout.

        Each mesh design is valid on its own (checked when it is built or loaded); tiles of
        two meshes are a joint apart when meshes do not overlap and every tile keeps half the
        design rules' least gap (``min_gap_fraction`` x joint) from its mesh's edges, as cuts
        along the middle of joints do.

        Raises:
            MuralError: No meshes, duplicate mesh names, a mesh design with another joint,
                meshes whose rectangles overlap, or a tile closer to its mesh edge than half
                the least gap.
        """
        pre = f"{source}: " if source else f"mural {self.name!r}: "
        if not self.meshes:
            raise MuralError(f"{pre}no meshes")
        names = [m.name for m in self.meshes]
        dupes = sorted({n for n in names if names.count(n) > 1})
        if dupes:
            raise MuralError(f"{pre}duplicate mesh name(s) {dupes}")
        for m in self.meshes:
            if not math.isclose(m.design.joint, self.joint):
                raise MuralError(
                    f"{pre}mesh {m.name!r} has joint {m.design.joint} mm, the mural {self.joint} mm"
                )
        boxes = [
            (m.x, m.y, m.x + m.design.mesh_size[0], m.y + m.design.mesh_size[1])
            for m in self.meshes
        ]
        for i, a in enumerate(boxes):
            for j in range(i + 1, len(boxes)):
                b = boxes[j]
                if a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]:
                    raise MuralError(
                        f"{pre}meshes {names[i]!r} and {names[j]!r} overlap "
                        f"({a} and {b}, mm: x0, y0, x1, y1)"
                    )
        for m in self.meshes:
            half_gap = 0.5 * m.design.rules.min_gap_fraction * self.joint
            w, h = m.design.mesh_size
            for s in m.design.slots:
                pts = s.outline_mm()
                edge = min(
                    pts[:, 0].min(), pts[:, 1].min(), w - pts[:, 0].max(), h - pts[:, 1].max()
                )
                if edge < half_gap - 1e-9:
                    raise MuralError(
                        f"{pre}mesh {m.name!r}: slot {s.name!r} is {edge:.2f} mm from the mesh "
                        f"edge; at least {half_gap:.2f} mm (half the least joint) so tiles of "
                        f"neighbouring meshes stay a joint apart"
                    )


def _number(value: Any, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise MuralError(f"{where}: expected a finite number, got {value!r}")
    return float(value)


def bundled_murals() -> list[str]:
    """Names of the murals in ``configs/murals/``."""
    return sorted(p.stem for p in (CONFIG_DIR / MURAL_SUBDIR).glob("*.yaml"))


__all__ = ["MURAL_SUBDIR", "Mural", "MuralError", "MuralMesh", "bundled_murals"]
