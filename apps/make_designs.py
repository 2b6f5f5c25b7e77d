"""Generate the bundled mosaic designs in ``configs/designs/`` (deterministic).

``python -m apps.make_designs`` rewrites ``square_grid``, ``paper_mixed``, ``hexagon`` and
``trencadis`` (the broken-tile pattern comes from a seeded Voronoi partition of the mesh: cells
shrunk by half a joint on each side, some with a notch pushed in to make them concave), and the
mural ``sunset`` in ``configs/murals/`` (1,000 square tesserae of 20 mm in six colours over
ten meshes). Each file is validated by loading it back.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from apps.cli import CommandParser, run_cli
from configs import CONFIG_DIR
from qshape.design import DESIGN_SUBDIR, Design, color_hex
from qshape.design.mural import MURAL_SUBDIR, Mural
from qshape.geometry import polygon_centroid

PALETTE = {
    "red": "#c0392b",
    "blue": "#2e6fd1",
    "yellow": "#e8c33a",
    "green": "#3f9e4d",
    "orange": "#e07b2a",
    "purple": "#8e4fb5",
    "teal": "#2aa39a",
    "pink": "#e86f9a",
    "brown": "#8b5a2b",
}
"""Tile colours: all far (> 0.25 RGB distance) from the grout and from the belt colours."""

GROUT = "#d9d4c7"
MESH_MM = 230.0
JOINT_MM = 2.0


@dataclass(frozen=True)
class TrencadisParams:
    """Broken-tile pattern generation.

    Attributes:
        seed: Random seed.
        grid: (columns, rows) of jittered Voronoi sites.
        margin_mm: Border of the mesh left empty, in [mm].
        site_jitter: Site jitter as a fraction of the grid cell.
        min_edge_mm: Vertices closer than this to the previous one are dropped, in [mm].
        concave_fraction: Fraction of the pieces given a notch (a concave vertex).
        notch_depth: Notch depth as a fraction of the distance from the edge midpoint to the
            piece centroid.
        min_area_mm2: Pieces smaller than this are dropped, in [mm^2].
        min_turn_deg: Vertices where the outline turns less than this are dropped (they would
            not read as corners), in [deg].
    """

    seed: int = 2026
    grid: tuple[int, int] = (7, 6)
    margin_mm: float = 6.0
    site_jitter: float = 0.35
    min_edge_mm: float = 8.0
    concave_fraction: float = 0.4
    notch_depth: float = 0.6
    min_area_mm2: float = 250.0
    min_turn_deg: float = 40.0


def _slot(  # noqa: PLR0917
    name: str, shape: dict[str, Any], color: str, x: float, y: float, angle: float = 0.0
) -> dict[str, Any]:
    return {
        "name": name,
        "shape": shape,
        "color": PALETTE.get(color, color),
        "pose": {"x": round(x, 3), "y": round(y, 3), "angle": round(angle, 3)},
    }


def _design(name: str, description: str, slots: list[dict[str, Any]]) -> dict[str, Any]:
    return {
        "name": name,
        "description": description,
        "mesh": {"width": MESH_MM, "height": MESH_MM},
        "joint": JOINT_MM,
        "grout_color": GROUT,
        "slots": slots,
    }


def square_grid() -> dict[str, Any]:
    """5 x 5 squares of 40 mm at a 2 mm joint in a three-colour pattern."""
    n, size = 5, 40.0
    pitch = size + JOINT_MM
    start = (MESH_MM - (n * size + (n - 1) * JOINT_MM)) / 2 + size / 2
    colors = ["blue", "yellow", "red"]
    slots = []
    for r in range(n):
        for c in range(n):
            ring = max(abs(r - n // 2), abs(c - n // 2))
            slots.append(
                _slot(
                    f"sq_r{r}c{c}",
                    {"kind": "square", "size": size},
                    colors[ring],
                    start + c * pitch,
                    start + r * pitch,
                )
            )
    return _design(
        "square_grid", "Classic grid: 5 x 5 squares of 40 mm, three colour rings.", slots
    )


def paper_mixed() -> dict[str, Any]:
    """The paper-like mixed set on a 4 x 4 layout (the cell's default design)."""
    pitch = MESH_MM / 4
    at = [pitch / 2 + pitch * i for i in range(4)]
    square = {"kind": "square", "size": 40.0}
    rect = {"kind": "rectangle", "width": 48.0, "height": 24.0}
    right = {"kind": "triangle_right", "width": 46.0, "height": 34.0}
    iso = {"kind": "triangle_isosceles", "base": 44.0, "height": 40.0}
    ell = {"kind": "polygon", "vertices": [[0, 0], [44, 0], [44, 20], [20, 20], [20, 44], [0, 44]]}
    holed = {
        "kind": "square",
        "size": 50.0,
        "holes": [{"kind": "square", "size": 18.0, "x": 11.0, "y": 11.0}],
    }
    slots = [
        _slot("square_red_1", square, "red", at[0], at[3]),
        _slot("square_blue", square, "blue", at[1], at[3], 90.0),
        _slot("rect_yellow", rect, "yellow", at[2], at[3]),
        _slot("circle_teal", {"kind": "circle", "radius": 21.0}, "teal", at[3], at[3]),
        _slot("right_orange", right, "orange", at[0], at[2], 0.0),
        _slot("iso_blue", iso, "blue", at[1], at[2], 180.0),
        _slot("ell_green", ell, "green", at[2], at[2], 0.0),
        _slot(
            "semicircle_yellow", {"kind": "semicircle", "radius": 24.0}, "yellow", at[3], at[2], 0.0
        ),
        _slot("holed_red", holed, "red", at[0], at[1], 0.0),
        _slot("rect_green", rect, "green", at[1], at[1], 45.0),
        _slot(
            "hexagon_purple",
            {"kind": "regular_polygon", "sides": 6, "radius": 23.0},
            "purple",
            at[2],
            at[1],
            30.0,
        ),
        _slot("right_teal", right, "teal", at[3], at[1], 90.0),
        _slot("square_red_2", square, "red", at[0], at[0], 90.0),
        _slot(
            "ring_orange",
            {"kind": "ring", "radius": 24.0, "inner_radius": 13.0},
            "orange",
            at[1],
            at[0],
        ),
        _slot("iso_red", iso, "red", at[2], at[0], 0.0),
        _slot("ell_orange", ell, "orange", at[3], at[0], 180.0),
    ]
    return _design(
        "paper_mixed",
        "Paper-like mixed set: squares, rectangles, right and isosceles triangles, L-shaped "
        "concave tiles, a circle, a semicircle, a square with an off-centre hole, a ring and a "
        "hexagon; repeated shapes in different colours. Default design of the cell.",
        slots,
    )


def hexagon() -> dict[str, Any]:
    """Honeycomb of regular hexagons (circumradius 18 mm) in three colours."""
    radius = 18.0
    across = math.sqrt(3.0) * radius
    dx = across + JOINT_MM
    dy = dx * math.sqrt(3.0) / 2.0
    colors = ["green", "yellow", "purple"]
    slots = []
    margin = 4.0
    row = 0
    y = margin + radius
    while y + radius <= MESH_MM - margin:
        x = margin + across / 2 + (dx / 2 if row % 2 else 0.0)
        col = 0
        while x + across / 2 <= MESH_MM - margin:
            color = colors[(col + (row % 2) + 2 * (row // 2)) % 3]
            slots.append(
                _slot(
                    f"hex_r{row}c{col}",
                    {"kind": "regular_polygon", "sides": 6, "radius": radius},
                    color,
                    x,
                    y,
                )
            )
            x += dx
            col += 1
        y += dy
        row += 1
    return _design("hexagon", "Honeycomb of hexagons (circumradius 18 mm), three colours.", slots)


def _clip(poly: np.ndarray, normal: np.ndarray, offset: float) -> np.ndarray:
    """Keep the part of a convex polygon where ``p . normal <= offset`` (Sutherland-Hodgman)."""
    if len(poly) == 0:
        return poly
    d = poly @ normal - offset
    out = []
    for i in range(len(poly)):
        j = (i + 1) % len(poly)
        if d[i] <= 0:
            out.append(poly[i])
        if (d[i] <= 0) != (d[j] <= 0):
            t = d[i] / (d[i] - d[j])
            out.append(poly[i] + t * (poly[j] - poly[i]))
    return np.array(out)


def trencadis(params: TrencadisParams | None = None) -> dict[str, Any]:
    """About 40 broken-tile pieces, convex and concave, separated by exactly one joint."""
    p = params or TrencadisParams()
    rng = np.random.default_rng(p.seed)
    cols, rows = p.grid
    inner = MESH_MM - 2 * p.margin_mm
    cw, ch = inner / cols, inner / rows
    gx, gy = np.meshgrid(np.arange(cols) + 0.5, np.arange(rows) + 0.5)
    sites = np.stack([gx.ravel() * cw, gy.ravel() * ch], axis=1) + p.margin_mm
    sites += (rng.random(sites.shape) - 0.5) * 2 * p.site_jitter * np.array([cw, ch])
    lo, hi = p.margin_mm, MESH_MM - p.margin_mm
    box = np.array([[lo, lo], [hi, lo], [hi, hi], [lo, hi]])
    names = list(PALETTE)
    slots: list[dict[str, Any]] = []
    half = JOINT_MM / 2
    for i, s in enumerate(sites):
        poly = box.copy()
        for j, t in enumerate(sites):
            if i == j:
                continue
            n = (t - s) / np.linalg.norm(t - s)
            poly = _clip(poly, n, float(n @ (s + t) / 2) - half)
        # Drop vertices too close to their predecessor (keeps the piece inside its cell).
        keep = [poly[0]]
        for v in poly[1:]:
            if np.linalg.norm(v - keep[-1]) >= p.min_edge_mm:
                keep.append(v)
        if len(keep) > 3 and np.linalg.norm(keep[0] - keep[-1]) < p.min_edge_mm:
            keep.pop()
        poly = np.array(keep)
        while len(poly) > 3:
            turn = _turns_deg(poly)
            k = int(np.argmin(turn))
            if turn[k] >= p.min_turn_deg:
                break
            poly = np.delete(poly, k, axis=0)
        if len(poly) < 3:
            continue
        area = 0.5 * abs(
            np.dot(poly[:, 0], np.roll(poly[:, 1], -1))
            - np.dot(np.roll(poly[:, 0], -1), poly[:, 1])
        )
        if area < p.min_area_mm2:
            continue
        centroid = poly.mean(axis=0)
        if rng.random() < p.concave_fraction:
            edges = np.roll(poly, -1, axis=0) - poly
            k = int(np.argmax(np.hypot(edges[:, 0], edges[:, 1])))
            mid = poly[k] + 0.5 * edges[k] + (rng.random() - 0.5) * 0.3 * edges[k]
            notch = mid + p.notch_depth * (centroid - mid)
            poly = np.insert(poly, k + 1, notch, axis=0)
        verts = [
            [round(float(x - centroid[0]), 3), round(float(y - centroid[1]), 3)] for x, y in poly
        ]
        color = PALETTE[names[int(rng.integers(len(names)))]]
        slots.append(
            _slot(
                f"piece_{len(slots):02d}", {"kind": "polygon", "vertices": verts}, color, 0.0, 0.0
            )
        )
        # The pose is the area centroid: the slot recentres its vertices on it, so the piece
        # lands exactly where the cell was.
        cx, cy = polygon_centroid(poly)
        slots[-1]["pose"] = {"x": round(float(cx), 3), "y": round(float(cy), 3), "angle": 0.0}
    return _design(
        "trencadis",
        f"Broken-tile pattern: {len(slots)} irregular pieces (seeded "
        f"Voronoi cells, some notched concave), generated by apps/make_designs.py.",
        slots,
    )


@dataclass(frozen=True)
class MuralParams:
    """The bundled mural: a sunset over the sea in square tesserae.

    Attributes:
        name: Mural name.
        tessera_mm: Side of a square tessera, in [mm] (real tesserae: 10-25 mm).
        joint_mm: Joint between tesserae, in [mm] (real joints: 2-3 mm); the mesh edges run
            along the middle of the joints, so joints are the same across meshes.
        tiles_per_mesh: (columns, rows) of tesserae on one mesh.
        meshes: (columns, rows) of meshes in the mural.
        horizon: Rows of tesserae below the horizon (the sea).
        sun: (column, row) of the sun's centre, in tesserae from the lower-left.
        sun_radius: Radius of the sun, in tesserae.
        wave_period: Columns per wave crest.
        wave_rows: Rows between wave lines in the sea.
    """

    name: str = "sunset"
    tessera_mm: float = 20.0
    joint_mm: float = 2.0
    tiles_per_mesh: tuple[int, int] = (10, 10)
    meshes: tuple[int, int] = (5, 2)
    horizon: int = 8
    sun: tuple[float, float] = (24.5, 9.0)
    sun_radius: float = 5.2
    wave_period: int = 8
    wave_rows: int = 3


def _sunset_color(p: MuralParams, col: int, row: int) -> str:
    """Palette name of the tessera at (column, row) of the sunset picture."""
    dx, dy = col - p.sun[0], row - p.sun[1]
    in_sun = math.hypot(dx, dy) <= p.sun_radius
    if row < p.horizon:
        phase = (col + 2 * (row // p.wave_rows)) % p.wave_period
        crest = row % p.wave_rows == 0 and phase < p.wave_period // 2
        if abs(dx) <= p.sun_radius * (0.3 + 0.1 * row) and row >= p.horizon - 3:
            return "yellow" if crest else "orange"  # the sun's reflection
        return "teal" if crest else "blue"
    if in_sun:
        return "yellow"
    height = row - p.horizon
    return ("orange", "pink", "purple", "purple")[min(height // 3, 3)]


def sunset(params: MuralParams | None = None) -> dict[str, Any]:
    """The mural-wide design of the sunset (split into meshes by `sunset_mural`)."""
    p = params or MuralParams()
    pitch = p.tessera_mm + p.joint_mm
    cols = p.tiles_per_mesh[0] * p.meshes[0]
    rows = p.tiles_per_mesh[1] * p.meshes[1]
    square = {"kind": "square", "size": p.tessera_mm}
    slots = [
        _slot(
            f"t_r{r:02d}c{c:02d}",
            square,
            _sunset_color(p, c, r),
            (c + 0.5) * pitch,
            (r + 0.5) * pitch,
        )
        for r in range(rows)
        for c in range(cols)
    ]
    return {
        "name": p.name,
        "description": (
            f"Sunset over the sea: {len(slots)} square tesserae of {p.tessera_mm:g} mm at a "
            f"{p.joint_mm:g} mm joint, six colours, on {p.meshes[0]} x {p.meshes[1]} meshes of "
            f"{p.tiles_per_mesh[0]} x {p.tiles_per_mesh[1]} tesserae."
        ),
        "mesh": {"width": cols * pitch, "height": rows * pitch},
        "joint": p.joint_mm,
        "grout_color": GROUT,
        "slots": slots,
    }


def sunset_mural(params: MuralParams | None = None) -> Mural:
    """The sunset cut into meshes of ``tiles_per_mesh`` tesserae (cuts along joints)."""
    p = params or MuralParams()
    pitch = p.tessera_mm + p.joint_mm
    design = Design.from_dict(sunset(p), source="sunset")
    size = (p.tiles_per_mesh[0] * pitch, p.tiles_per_mesh[1] * pitch)
    return Mural.split(design, size)


HEADER = """Mosaic design (format: configs/designs/README.md). Generated by
`python -m apps.make_designs`; edit the generator, not this file."""


MURAL_HEADER = """Mural (format: configs/designs/README.md, section Murals). Generated by
`python -m apps.make_designs`; edit the generator, not this file."""


def main(argv: list[str] | None = None) -> None:
    """Write and validate the bundled designs."""
    ap = CommandParser(description=__doc__)
    ap.add_argument("--out", type=Path, default=CONFIG_DIR / DESIGN_SUBDIR)
    ap.add_argument("--murals-out", type=Path, default=CONFIG_DIR / MURAL_SUBDIR)
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    for make in (square_grid, paper_mixed, hexagon, trencadis):
        data = make()
        design = Design.from_dict(data, source=make.__name__)
        path = args.out / f"{design.name}.yaml"
        design.save(path, HEADER)
        again = Design.load(path)
        convex = sum(_is_convex(s.local_path.outer.vertices) for s in again.slots)
        print(
            f"{path}: {len(again.slots)} slots ({convex} convex), colours "
            f"{sorted({color_hex(s.color) for s in again.slots})}"
        )
    args.murals_out.mkdir(parents=True, exist_ok=True)
    mural = sunset_mural()
    path = args.murals_out / f"{mural.name}.yaml"
    mural.save(path, MURAL_HEADER)
    loaded = Mural.load(path)
    colours = sorted({color_hex(s.color) for m in loaded.meshes for s in m.design.slots})
    print(
        f"{path}: {loaded.tiles} slots on {len(loaded.meshes)} meshes of "
        f"{loaded.meshes[0].design.mesh_size[0]:g} x {loaded.meshes[0].design.mesh_size[1]:g} mm, "
        f"colours {colours}"
    )


def _turns_deg(v: np.ndarray) -> np.ndarray:
    """Direction change of the outline at each vertex, in [deg] (0: straight through)."""
    a = v - np.roll(v, 1, axis=0)
    b = np.roll(v, -1, axis=0) - v
    cos = np.einsum("ij,ij->i", a, b) / (np.hypot(*a.T) * np.hypot(*b.T))
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


def _is_convex(v: np.ndarray) -> bool:
    e = np.roll(v, -1, axis=0) - v
    cross = e[:, 0] * np.roll(e[:, 1], -1) - e[:, 1] * np.roll(e[:, 0], -1)
    return bool(np.all(cross >= -1e-9))


if __name__ == "__main__":
    run_cli(main)
