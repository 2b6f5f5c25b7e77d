"""The cell's fixed parts in the MuJoCo spec: floor and light, belts, reject bin, mesh, cameras.

`add_fixtures` adds them to a spec in one fixed order (the order sets the model's geom ids):
floor and light, the input belt with its rails and stand, the reject bin at its end, the
output belt with its stand and the mesh sheet, the slot marks on the sheet, the cameras.
"""

from __future__ import annotations

from collections.abc import Sequence

import mujoco
import numpy as np
import shapely
from shapely.geometry import Polygon

from envs.cell.config import CellConfig
from envs.cell.contacts import CONTACT_SOLREF, WORLD_CONAFFINITY, WORLD_CONTYPE
from envs.cell.geometry import CellGeometry
from envs.cell.tiles.tile import SlotSpec
from envs.errors import CellError
from spatial.rotations import quat_from_yaw
from spatial.units import MM_PER_M

BELT_FRICTION_TORSION_ROLL = (0.005, 0.0001)
"""Torsional and rolling friction of the belts and the mesh sheet (sliding: the tiles')."""


def extrusion(
    outline: np.ndarray, holes: Sequence[np.ndarray], z0: float, z1: float
) -> tuple[np.ndarray, np.ndarray]:
    """Closed triangle mesh of a polygon (with holes) extruded from z0 to z1.

    Returns:
        ``(vertices, faces)``: shapes (v, 3) [m] and (f, 3) vertex indices, outward normals.
    """
    rings = [np.asarray(outline, float), *[np.asarray(h, float) for h in holes]]
    pts2 = np.vstack(rings)
    n = len(pts2)
    verts = np.vstack(
        [np.column_stack([pts2, np.full(n, z0)]), np.column_stack([pts2, np.full(n, z1)])]
    )
    index = {(round(float(x), 12), round(float(y), 12)): i for i, (x, y) in enumerate(pts2)}
    faces = []
    for tri in shapely.constrained_delaunay_triangles(Polygon(rings[0], rings[1:])).geoms:
        ids = [
            index[(round(float(x), 12), round(float(y), 12))] for x, y in tri.exterior.coords[:3]
        ]
        a, b, c = pts2[ids]
        if (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) < 0:
            ids = ids[::-1]
        faces.append([ids[0] + n, ids[1] + n, ids[2] + n])  # top, counter-clockwise
        faces.append([ids[0], ids[2], ids[1]])  # bottom
    start = 0
    for ring in rings:
        m = len(ring)
        for k in range(m):
            i, j = start + k, start + (k + 1) % m
            faces.append([i, j, j + n])
            faces.append([i, j + n, i + n])
        start += m
    return verts, np.asarray(faces, dtype=int)


def _box(
    body: mujoco.MjsBody,
    name: str,
    pos: Sequence[float],
    size: Sequence[float],
    rgba: Sequence[float],
    *,
    collide: bool = True,
) -> mujoco.MjsGeom:
    g = body.add_geom()
    g.name = name
    g.type = mujoco.mjtGeom.mjGEOM_BOX
    g.pos = pos
    g.size = size
    g.rgba = rgba
    if collide:
        g.contype, g.conaffinity = WORLD_CONTYPE, WORLD_CONAFFINITY
        g.solref = list(CONTACT_SOLREF)
    else:
        g.contype, g.conaffinity = 0, 0
    return g


def add_fixtures(
    spec: mujoco.MjSpec, cfg: CellConfig, slots: Sequence[SlotSpec], geo: CellGeometry
) -> None:
    """Floor, light, belts, bin, mesh sheet with slot marks, cameras (in this order).

    The mesh sheet, the slot marks' bounds and the output camera's height are ``geo``'s
    (the design's mesh, `envs.cell.geometry.cell_geometry`).

    Raises:
        CellError: A slot extends beyond the mesh sheet.
    """
    _add_floor_and_light(spec, cfg)
    _add_input_belt(spec.worldbody, cfg, geo)
    _add_bin(spec.worldbody, cfg, geo)
    _add_output_belt(spec.worldbody, cfg, geo)
    _add_slot_marks(spec, cfg, geo, slots)
    _add_cameras(spec.worldbody, cfg, geo)


def _friction(cfg: CellConfig) -> list[float]:
    """Friction (sliding, torsional, rolling) of the belts and the mesh sheet."""
    return [cfg.tiles.friction, *BELT_FRICTION_TORSION_ROLL]


def _add_floor_and_light(spec: mujoco.MjSpec, cfg: CellConfig) -> None:
    """The checkered floor, the belts' matte material and the light from above."""
    wb, look = spec.worldbody, cfg.scenery
    spec.add_texture(
        name="floor_tex",
        type=mujoco.mjtTexture.mjTEXTURE_2D,
        builtin=mujoco.mjtBuiltin.mjBUILTIN_CHECKER,
        rgb1=list(look.floor_checker[0]),
        rgb2=list(look.floor_checker[1]),
        width=look.floor_texture_px,
        height=look.floor_texture_px,
    )
    repeat = look.floor_texture_repeat
    spec.add_material(
        name="floor_mat", textures=["", "floor_tex"], texrepeat=[repeat, repeat], texuniform=True
    )
    # Rubber belts are matte: MuJoCo's default material (specular 0.5) puts the headlight's
    # highlight in the middle of each camera image, which the perception's illumination model
    # (fitted to the belt) would read as brighter light there and so over-correct the tiles
    # near the image corners.
    spec.add_material(name="belt_mat", rgba=list(look.belt_rgba), specular=0.0, shininess=0.0)
    half_floor = look.floor_half_size
    floor = wb.add_geom(
        name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[half_floor, half_floor, 0.05]
    )
    floor.material = "floor_mat"
    floor.contype, floor.conaffinity = WORLD_CONTYPE, WORLD_CONAFFINITY
    floor.solref = list(CONTACT_SOLREF)
    wb.add_light(
        name="top_light",
        pos=list(look.light_pos),
        dir=[0, 0, -1],
        type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL,
        castshadow=False,
        diffuse=[look.light_diffuse * look.light_scale] * 3,
        specular=[look.light_specular] * 3,
    )


def _add_input_belt(wb: mujoco.MjsBody, cfg: CellConfig, geo: CellGeometry) -> None:
    """The input belt (it carries tiles through surfacevel), its rails and its stand."""
    ib, look, top, friction = cfg.input_belt, cfg.scenery, geo.belt_top, _friction(cfg)
    cx = geo.input_belt_end - ib.length / 2
    belt = _box(
        wb,
        "input_belt",
        [cx, geo.input_y, top - ib.thickness / 2],
        [ib.length / 2, ib.width / 2, ib.thickness / 2],
        look.belt_rgba,
    )
    belt.material = "belt_mat"
    belt.friction = friction
    belt.surfacevel = [ib.speed, 0.0, 0.0, 0.0, 0.0, 0.0]
    for side, sign in (("left", 1), ("right", -1)):
        _box(
            wb,
            f"input_rail_{side}",
            [cx, geo.input_y + sign * (ib.width / 2 + look.rail_gap), top],
            [ib.length / 2, look.rail_half_width, look.rail_height],
            look.frame_rgba,
        )
    leg = top - ib.thickness
    inset_x, inset_y = look.stand_inset
    _box(
        wb,
        "input_stand",
        [cx, geo.input_y, leg / 2],
        [ib.length / 2 - inset_x, ib.width / 2 - inset_y, leg / 2],
        look.frame_rgba,
        collide=False,
    )


def _add_bin(wb: mujoco.MjsBody, cfg: CellConfig, geo: CellGeometry) -> None:
    """The reject bin past the input belt's end, on its stand."""
    ib, look, top = cfg.input_belt, cfg.scenery, geo.belt_top
    bx0 = geo.input_belt_end + look.bin_gap
    bin_floor = top - ib.bin_depth
    bw = ib.width / 2 + look.bin_side_margin
    wall = look.bin_wall
    _box(
        wb,
        "bin_floor",
        [bx0 + ib.bin_length / 2, geo.input_y, bin_floor - wall],
        [ib.bin_length / 2, bw, wall],
        look.bin_floor_rgba,
    )
    _box(
        wb,
        "bin_far",
        [bx0 + ib.bin_length + wall, geo.input_y, bin_floor + ib.bin_depth / 2],
        [wall, bw, ib.bin_depth / 2],
        look.bin_wall_rgba,
    )
    for side, sign in (("left", 1), ("right", -1)):
        _box(
            wb,
            f"bin_{side}",
            [bx0 + ib.bin_length / 2, geo.input_y + sign * bw, bin_floor + ib.bin_depth / 2],
            [ib.bin_length / 2, wall, ib.bin_depth / 2],
            look.bin_wall_rgba,
        )
    _box(
        wb,
        "bin_stand",
        [bx0 + ib.bin_length / 2, geo.input_y, (bin_floor - 2 * wall) / 2],
        [
            ib.bin_length / 2 - look.bin_stand_inset,
            bw - look.bin_stand_inset,
            (bin_floor - 2 * wall) / 2,
        ],
        look.frame_rgba,
        collide=False,
    )


def _add_output_belt(wb: mujoco.MjsBody, cfg: CellConfig, geo: CellGeometry) -> None:
    """The output belt, its stand and the mesh sheet on it."""
    ob, look, top, friction = cfg.output_belt, cfg.scenery, geo.belt_top, _friction(cfg)
    leg = top - cfg.input_belt.thickness
    inset_x, inset_y = look.stand_inset
    oc = geo.output_centre
    obelt = _box(
        wb,
        "output_belt",
        [oc[0], oc[1], top - ob.thickness / 2],
        [ob.length / 2, ob.width / 2, ob.thickness / 2],
        look.belt_rgba,
    )
    obelt.material = "belt_mat"
    obelt.friction = friction
    _box(
        wb,
        "output_stand",
        [oc[0], oc[1], leg / 2],
        [ob.length / 2 - inset_x, ob.width / 2 - inset_y, leg / 2],
        look.frame_rgba,
        collide=False,
    )
    sheet = _box(
        wb,
        "mesh_sheet",
        [oc[0], oc[1], top + ob.mesh_thickness / 2],
        [geo.mesh_size[0] / 2, geo.mesh_size[1] / 2, ob.mesh_thickness / 2],
        look.sheet_rgba,
    )
    sheet.friction = friction


def _add_slot_marks(
    spec: mujoco.MjSpec, cfg: CellConfig, geo: CellGeometry, slots: Sequence[SlotSpec]
) -> None:
    """A thin coloured mark per slot on the mesh sheet (visual only)."""
    wb, ob, look, oc = spec.worldbody, cfg.output_belt, cfg.scenery, geo.output_centre
    half = geo.mesh_size / 2
    for k, slot in enumerate(slots):
        x, y, yaw = slot.pose
        c = slot.shape.polygon.centroid
        off = np.array([c.x, c.y])
        outline = slot.shape.outline - off
        holes = [h - off for h in slot.shape.holes]
        rot = np.array([[np.cos(yaw), -np.sin(yaw)], [np.sin(yaw), np.cos(yaw)]])
        world = outline @ rot.T + [x, y]
        if np.any(np.abs(world) > half + 1e-9):
            raise CellError(
                f"slot {k} ({slot.shape.name}) at pose {slot.pose} extends beyond the mesh "
                f"({geo.mesh_size[0] * MM_PER_M:.0f} x {geo.mesh_size[1] * MM_PER_M:.0f} mm, "
                "centred at 0)"
            )
        verts, faces = extrusion(outline, holes, 0.0, ob.slot_mark_height)
        mesh = spec.add_mesh(name=f"slot{k}_mark")
        mesh.uservert = verts.ravel().tolist()
        mesh.userface = faces.ravel().tolist()
        mesh.inertia = mujoco.mjtMeshInertia.mjMESH_INERTIA_SHELL
        g = wb.add_geom(name=f"slot{k}", type=mujoco.mjtGeom.mjGEOM_MESH, meshname=f"slot{k}_mark")
        g.pos = [oc[0] + x, oc[1] + y, geo.mesh_top]
        g.quat = quat_from_yaw(yaw)
        g.contype, g.conaffinity, g.group = 0, 0, 1
        col = look.slot_white + (1 - look.slot_white) * np.asarray(slot.shape.color)
        g.rgba = [*col, 1.0]


def _add_cameras(wb: mujoco.MjsBody, cfg: CellConfig, geo: CellGeometry) -> None:
    """The input and output cameras and the overview camera."""
    look = cfg.scenery
    # Cameras looking straight down; image right = +x, image up = +y.
    for name, centre, cam, height in (
        ("input_camera", geo.input_centre, cfg.input_camera, cfg.input_camera.height_above_belt),
        ("output_camera", geo.output_centre, cfg.output_camera, geo.output_camera_height),
    ):
        c = wb.add_camera(name=name)
        c.pos = [centre[0] + cam.offset[0], centre[1] + cam.offset[1], centre[2] + height]
        c.quat = [1, 0, 0, 0]
        c.fovy = cam.fovy_deg
    wb.add_camera(name="overview", pos=list(look.overview_pos), xyaxes=list(look.overview_xyaxes))


__all__ = ["add_fixtures", "extrusion"]
