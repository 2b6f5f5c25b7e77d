"""Programmatic composition of the cell with MjSpec: robot + belts + bin + mesh + cameras + tiles.

The robot comes from ``assets/irb140/irb140.xml``; everything else is added in code. Names are
resolved to ids once, into a frozen `SceneIds`.

World layout (see `LayoutConfig`): robot base at the origin; the input belt's centre line at
y = +belt_separation/2 and the output belt's at y = -belt_separation/2, both running along +x;
the working areas are centred at x = work_x.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass, replace

import mujoco
import numpy as np
import shapely
from shapely.geometry import Polygon

from envs.cell.config import CellConfig
from envs.cell.tiles.tile import PhysicalTile, SlotSpec
from envs.errors import CellError

# Contact bit masks: world/belts 1, tiles 2, arm 4 (the arm's classes set contype 4,
# conaffinity 1 in irb140.xml), support hulls 8. Tiles touch everything; the arm touches world
# and tiles. A tile made of several convex pieces touches the world (belts, mesh sheet, floor,
# bin) with one convex hull instead (`SUPPORT_CONTYPE`), its pieces only tiles and the arm.
WORLD_CONTYPE, WORLD_CONAFFINITY = 1, 1
TILE_CONTYPE, TILE_CONAFFINITY = 2, 7
PIECE_CONAFFINITY = TILE_CONAFFINITY & ~WORLD_CONTYPE
"""Pieces of a tile with a support hull: tiles and arm, not the world."""
SUPPORT_CONTYPE, SUPPORT_CONAFFINITY = 8, WORLD_CONTYPE
"""Support hull of a tile of several pieces: the world only."""
PARK_SPACING = 0.08
"""Grid spacing of parked (not yet fed) tiles on the floor far from the cell [m]."""
PARK_ORIGIN = np.array([-6.0, -1.0])
"""Corner of the parking grid, outside the rendered floor [m]."""
WAKE_FORCE = 1e-12
"""Negligible force [N] applied for one physics step to wake sleeping tiles (any applied force
wakes a sleeping tree in MuJoCo; changing qpos or surfacevel does not)."""
CONTACT_SOLREF = (0.004, 1.0)
"""Contact time constant [s] and damping ratio of tiles and belts: stiff (2x the default
timestep) so a tile crushed by the arm sinks at most a few mm into a belt (0.02 s: ~19 mm)."""
WELD_SOLREF = (0.004, 1.0)
"""Time constant [s] and damping ratio of the suction weld (stiff: 2x the default timestep)."""


@dataclass(frozen=True, eq=False)
class SceneIds:
    """Ids resolved once after compiling; index arrays for vectorised reads.

    Attributes:
        arm_qpos: qpos addresses of joints 1-6, shape (6,).
        arm_dof: dof addresses of joints 1-6, shape (6,).
        pos_actuators: Position servo actuator ids, shape (6,).
        vel_actuators: Velocity feed-forward actuator ids, shape (6,).
        tcp_site: Site at the pad face (z out of the pad).
        flange_site: Site at the flange (DH frame 6).
        pad_body: Body of the vacuum pad.
        weld: Equality id of the suction weld (inactive when nothing is held).
        tile_body: Body ids of the tiles' shown shapes, shape (n,): the tile's free body, or
            with variants the jointless child holding the shown variant (same frame; welds
            and forces go there, where the mass is).
        tile_qpos: First qpos address of each tile's free joint, shape (n,).
        tile_dof: First dof address of each tile's free joint, shape (n,).
        tile_geom_start: First geom id of each tile's shown variant, shape (n,).
        tile_geom_count: Number of geoms of each tile's shown variant, shape (n,).
        tile_visual: Visual geoms (ceramic body, glaze) of each tile's shown variant, shape
            (n, 2).
        variant_body: Body holding each variant's geoms, shape (variants, n) (the tile's own
            body with one variant).
        variant_geom_start: First geom id of each variant, shape (variants, n).
        variant_geom_count: Number of geoms of each variant, shape (variants, n).
        variant_visual: Visual geoms of every variant, shape (variants, n, 2).
        input_belt_geom: Geom carrying tiles on the input belt (surfacevel).
        mesh_geom: The mesh sheet on the output belt.
        input_camera: Camera id above the input belt.
        output_camera: Camera id above the output belt.
    """

    arm_qpos: np.ndarray
    arm_dof: np.ndarray
    pos_actuators: np.ndarray
    vel_actuators: np.ndarray
    tcp_site: int
    flange_site: int
    pad_body: int
    weld: int
    tile_body: np.ndarray
    tile_qpos: np.ndarray
    tile_dof: np.ndarray
    tile_geom_start: np.ndarray
    tile_geom_count: np.ndarray
    tile_visual: np.ndarray
    variant_body: np.ndarray
    variant_geom_start: np.ndarray
    variant_geom_count: np.ndarray
    variant_visual: np.ndarray
    input_belt_geom: int
    mesh_geom: int
    input_camera: int
    output_camera: int

    def with_variants(self, variant: np.ndarray) -> SceneIds:
        """These ids with tile i's geoms those of its variant ``variant[i]``, shape (n,)."""
        shown = (variant, np.arange(len(self.tile_body)))
        return replace(
            self,
            tile_body=self.variant_body[shown],
            tile_geom_start=self.variant_geom_start[shown],
            tile_geom_count=self.variant_geom_count[shown],
            tile_visual=self.variant_visual[shown],
        )

    @functools.cached_property
    def tile_qpos_index(self) -> np.ndarray:
        """Qpos indices of all tiles' free joints, shape (n, 7) (computed once, read-only)."""
        return _frozen(self.tile_qpos[:, None] + np.arange(7)[None, :])

    @functools.cached_property
    def tile_dof_index(self) -> np.ndarray:
        """Dof indices of all tiles' free joints, shape (n, 6) (computed once, read-only)."""
        return _frozen(self.tile_dof[:, None] + np.arange(6)[None, :])


def _frozen(a: np.ndarray) -> np.ndarray:
    """``a`` made read-only (a cached index array must not change under its users)."""
    a.setflags(write=False)
    return a


@dataclass(frozen=True)
class CellGeometry:
    """Derived positions of the cell's parts [m] (all in the world frame).

    Attributes:
        input_centre: Centre of the input tile area on the belt top, shape (3,).
        output_centre: Centre of the mesh sheet's top, shape (3,).
        input_belt_end: x of the input belt's downstream end.
        input_belt_start: x of the input belt's upstream end.
        input_y: y of the input belt's centre line.
        belt_top: z of both belts' top faces.
        mesh_top: z of the mesh sheet's top face.
    """

    input_centre: np.ndarray
    output_centre: np.ndarray
    input_belt_end: float
    input_belt_start: float
    input_y: float
    belt_top: float
    mesh_top: float


def cell_geometry(cfg: CellConfig) -> CellGeometry:
    """Positions of the belts and working areas from the configuration."""
    lay = cfg.layout
    top = lay.belt_top_z
    y_in, y_out = lay.belt_separation / 2, -lay.belt_separation / 2
    end = lay.work_x + cfg.input_belt.end_offset
    mesh_top = top + cfg.output_belt.mesh_thickness
    return CellGeometry(
        input_centre=np.array([lay.work_x, y_in, top]),
        output_centre=np.array([lay.work_x, y_out, mesh_top]),
        input_belt_end=end,
        input_belt_start=end - cfg.input_belt.length,
        input_y=y_in,
        belt_top=top,
        mesh_top=mesh_top,
    )


def yaw_quat(yaw: np.ndarray | float) -> np.ndarray:
    """Quaternions (w, x, y, z) of rotations about z, shape (..., 4)."""
    yaw = np.asarray(yaw, dtype=float)
    q = np.zeros((*yaw.shape, 4))
    q[..., 0] = np.cos(yaw / 2)
    q[..., 3] = np.sin(yaw / 2)
    return q


def park_positions(n: int, thickness: float) -> np.ndarray:
    """Parking positions (on the floor, far away) of tiles not yet fed, shape (n, 3) [m]."""
    cols = max(1, int(np.ceil(np.sqrt(n))))
    k = np.arange(n)
    xy = PARK_ORIGIN + PARK_SPACING * np.stack([k % cols, k // cols], axis=1)
    return np.column_stack([xy, np.full(n, thickness / 2 + 1e-4)])


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


def _add_environment(spec: mujoco.MjSpec, cfg: CellConfig, slots: Sequence[SlotSpec]) -> None:
    """Floor, light, belts, bin, mesh sheet with slot marks, cameras."""
    geo = cell_geometry(cfg)
    wb = spec.worldbody
    ib, ob, look = cfg.input_belt, cfg.output_belt, cfg.scenery
    top = geo.belt_top
    friction = [cfg.tiles.friction, 0.005, 0.0001]

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

    # Input belt (carries tiles through surfacevel) with its frame and the bin at the end.
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

    # Output belt with the mesh sheet and slot marks.
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
        [ob.mesh_size[0] / 2, ob.mesh_size[1] / 2, ob.mesh_thickness / 2],
        look.sheet_rgba,
    )
    sheet.friction = friction
    half = np.asarray(ob.mesh_size) / 2
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
                f"({ob.mesh_size[0] * 1000:.0f} x {ob.mesh_size[1] * 1000:.0f} mm, centred at 0)"
            )
        verts, faces = extrusion(outline, holes, 0.0, ob.slot_mark_height)
        mesh = spec.add_mesh(name=f"slot{k}_mark")
        mesh.uservert = verts.ravel().tolist()
        mesh.userface = faces.ravel().tolist()
        mesh.inertia = mujoco.mjtMeshInertia.mjMESH_INERTIA_SHELL
        g = wb.add_geom(name=f"slot{k}", type=mujoco.mjtGeom.mjGEOM_MESH, meshname=f"slot{k}_mark")
        g.pos = [oc[0] + x, oc[1] + y, geo.mesh_top]
        g.quat = yaw_quat(yaw)
        g.contype, g.conaffinity, g.group = 0, 0, 1
        col = look.slot_white + (1 - look.slot_white) * np.asarray(slot.shape.color)
        g.rgba = [*col, 1.0]

    # Cameras looking straight down; image right = +x, image up = +y.
    for name, centre, cam in (
        ("input_camera", geo.input_centre, cfg.input_camera),
        ("output_camera", geo.output_centre, cfg.output_camera),
    ):
        c = wb.add_camera(name=name)
        c.pos = [
            centre[0] + cam.offset[0],
            centre[1] + cam.offset[1],
            centre[2] + cam.height_above_belt,
        ]
        c.quat = [1, 0, 0, 0]
        c.fovy = cam.fovy_deg
    wb.add_camera(name="overview", pos=list(look.overview_pos), xyaxes=list(look.overview_xyaxes))


def _configure(spec: mujoco.MjSpec, cfg: CellConfig) -> None:
    ph = cfg.physics
    spec.option.timestep = ph.timestep
    spec.option.iterations = ph.iterations
    spec.option.ls_iterations = ph.ls_iterations
    spec.option.impratio = ph.impratio
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    if ph.sleep:
        spec.option.enableflags |= int(mujoco.mjtEnableBit.mjENBL_SLEEP)
        spec.option.sleep_tolerance = ph.sleep_tolerance
    spec.visual.quality.shadowsize = 0 if not cfg.render.shadows else 4096
    spec.visual.quality.offsamples = cfg.render.samples
    look = cfg.scenery  # exposure: ambient + diffuse scaled so a white face renders at it
    spec.visual.headlight.ambient = [look.headlight_ambient * look.light_scale] * 3
    spec.visual.headlight.diffuse = [look.headlight_diffuse * look.light_scale] * 3
    spec.visual.headlight.specular = [0.0, 0.0, 0.0]
    spec.visual.global_.offwidth = max(cfg.input_camera.width, cfg.output_camera.width, 1280)
    spec.visual.global_.offheight = max(cfg.input_camera.height, cfg.output_camera.height, 960)
    spec.stat.center = [0.3, 0.0, 0.3]
    spec.stat.extent = 1.5


def _robot_spec(cfg: CellConfig) -> mujoco.MjSpec:
    spec = mujoco.MjSpec.from_file(str(cfg.robot.model_path))
    for key in list(spec.keys):
        spec.delete(key)  # re-added with the full state in build_spec
    return spec


def tile_name(tile: int, variant: int = 0) -> str:
    """Name prefix of a tile's variant: ``tile3``, ``tile3v1``, ``tile3v2``...

    Its meshes and geoms carry the prefix; ``tile3`` also names the tile's free body and, with
    variants, ``{prefix}_shape`` the child body holding the variant's geoms.
    """
    return f"tile{tile}" if variant == 0 else f"tile{tile}v{variant}"


def _add_prism(
    spec: mujoco.MjSpec,
    body: mujoco.MjsBody,
    cfg: CellConfig,
    polygon: np.ndarray,
    *,
    names: tuple[str, str],
) -> mujoco.MjsGeom:
    """A hidden collision geom: convex ``polygon`` (k, 2) [m] extruded over the tile thickness.

    ``names``: the mesh's and the geom's.
    """
    t, m = cfg.tiles.thickness, len(polygon)
    bottom = np.column_stack([polygon, np.full(m, -t / 2)])
    verts = np.vstack([bottom, bottom + [0.0, 0.0, t]])
    mesh_name, geom_name = names
    mesh = spec.add_mesh(name=mesh_name)
    mesh.uservert = verts.ravel().tolist()
    g = body.add_geom(name=geom_name, type=mujoco.mjtGeom.mjGEOM_MESH, meshname=mesh_name)
    g.rgba = [*cfg.tiles.body_color, 1.0]
    g.friction = [cfg.tiles.friction, 0.005, 0.0001]
    g.condim = 4
    g.solref = list(CONTACT_SOLREF)
    g.group = 3  # collision, hidden; the visuals show the true (concave) shape
    return g


def _add_tiles(
    spec: mujoco.MjSpec, cfg: CellConfig, tiles: Sequence[PhysicalTile], variants: int
) -> None:
    """One free body per tile (``tiles`` variant-major); with variants, a child body each.

    With ``variants`` V > 1 the free body ``tile{i}`` has no geoms of its own: each variant's
    geoms sit in a jointless child body ``{tile_name(i, v)}_shape`` (one tree, no extra degrees
    of freedom); a cell zeroes the mass and contact bits of the variants it does not show.
    """
    t = cfg.tiles.thickness
    n = len(tiles) // variants
    park = park_positions(n, t)
    bodies = []
    for i in range(n):
        body = spec.worldbody.add_body(name=tile_name(i), pos=park[i])
        body.add_freejoint(name=f"{tile_name(i)}_joint")
        bodies.append(body)
    for j, tile in enumerate(tiles):
        name = tile_name(j % n, j // n)
        body = bodies[j % n] if variants == 1 else bodies[j % n].add_body(name=f"{name}_shape")
        pieces = len(tile.pieces)
        for k, piece in enumerate(tile.pieces):
            g = _add_prism(spec, body, cfg, piece, names=(f"{name}_piece{k}", f"{name}_geom{k}"))
            g.density = cfg.tiles.density
            g.contype = TILE_CONTYPE
            g.conaffinity = TILE_CONAFFINITY if pieces == 1 else PIECE_CONAFFINITY
        if pieces > 1:
            # A flat tile on a flat support touches it over its outline's convex hull: one hull
            # gives that support with a few contacts where the pieces gave a few each (a holed
            # square: 4 instead of ~150). Massless; the pieces carry the mass.
            hull = np.asarray(Polygon(tile.outline).convex_hull.exterior.coords)[:-1]
            g = _add_prism(spec, body, cfg, hull, names=(f"{name}_hull", f"{name}_support"))
            g.density = 0.0
            g.contype, g.conaffinity = SUPPORT_CONTYPE, SUPPORT_CONAFFINITY
        # Visuals: the ceramic body and the coloured glaze on the top face (massless).
        glaze = cfg.tiles.glaze_thickness
        for part, z0, z1, rgba in (
            ("body", -t / 2, t / 2 - glaze, [*cfg.tiles.body_color, 1.0]),
            ("glaze", t / 2 - glaze, t / 2 + 1e-5, [*tile.color, 1.0]),
        ):
            verts, faces = extrusion(tile.outline, tile.holes, z0, z1)
            mesh = spec.add_mesh(name=f"{name}_{part}")
            mesh.uservert = verts.ravel().tolist()
            mesh.userface = faces.ravel().tolist()
            g = body.add_geom(
                name=f"{name}_{part}", type=mujoco.mjtGeom.mjGEOM_MESH, meshname=f"{name}_{part}"
            )
            g.contype = g.conaffinity = 0
            g.density = 0.0
            g.group = 2
            g.rgba = rgba


def build_spec(
    cfg: CellConfig,
    tiles: Sequence[PhysicalTile] = (),
    slots: Sequence[SlotSpec] = (),
    variants: int = 1,
) -> mujoco.MjSpec:
    """The whole cell as an editable MjSpec (tiles parked on the floor far away).

    Args:
        cfg: Cell configuration.
        tiles: Physical tiles (one free body each); empty for an arm + cell model. With
            ``variants`` V > 1: V variants of n tiles, variant-major (``v * n + i``), each in
            a child body of its tile's free body.
        slots: Slots of the mesh (visual marks).
        variants: Variants per tile in ``tiles``.

    Raises:
        CellError: A slot outside the mesh, or ``tiles`` not a multiple of ``variants``.
    """
    if variants < 1 or len(tiles) % variants:
        raise CellError(
            f"{len(tiles)} tiles cannot be {variants} variants of each tile; allowed: "
            "variants >= 1 dividing the number of tiles"
        )
    spec = _robot_spec(cfg)
    _configure(spec, cfg)
    _add_environment(spec, cfg, slots)
    if tiles:
        _add_tiles(spec, cfg, tiles, variants)
        eq = spec.add_equality(name="suction_weld", type=mujoco.mjtEq.mjEQ_WELD)
        eq.objtype = mujoco.mjtObj.mjOBJ_BODY
        eq.name1, eq.name2 = "vacuum_pad", "tile0"
        eq.active = False
        eq.solref = list(WELD_SOLREF)
    return spec


def resolve_ids(model: mujoco.MjModel, n_tiles: int, variants: int = 1) -> SceneIds:
    """Resolve every name the cell uses to ids, once.

    Args:
        model: The compiled cell.
        n_tiles: Tiles per variant.
        variants: Variants per tile; the tile arrays describe variant 0.
    """

    def nid(kind: mujoco.mjtObj, name: str) -> int:
        i = mujoco.mj_name2id(model, kind, name)
        if i < 0:
            raise CellError(f"model has no {kind.name} named {name!r}")
        return int(i)

    joints = [nid(mujoco.mjtObj.mjOBJ_JOINT, f"joint{k}") for k in range(1, 7)]
    names = [tile_name(i) for i in range(n_tiles)]
    bodies = np.array([nid(mujoco.mjtObj.mjOBJ_BODY, b) for b in names], int)
    tjoints = [nid(mujoco.mjtObj.mjOBJ_JOINT, f"{b}_joint") for b in names]
    parts = ("body", "glaze")
    visual = np.array(
        [
            [nid(mujoco.mjtObj.mjOBJ_GEOM, f"{tile_name(i, v)}_{part}") for part in parts]
            for v in range(variants)
            for i in range(n_tiles)
        ],
        int,
    ).reshape(variants, n_tiles, 2)
    if variants == 1:
        shape_bodies = bodies.reshape(1, -1)
    else:
        shape_bodies = np.array(
            [
                [nid(mujoco.mjtObj.mjOBJ_BODY, f"{tile_name(i, v)}_shape") for i in range(n_tiles)]
                for v in range(variants)
            ],
            int,
        ).reshape(variants, n_tiles)
    return SceneIds(
        arm_qpos=model.jnt_qposadr[joints].copy(),
        arm_dof=model.jnt_dofadr[joints].copy(),
        pos_actuators=np.array([nid(mujoco.mjtObj.mjOBJ_ACTUATOR, f"pos{k}") for k in range(1, 7)]),
        vel_actuators=np.array([nid(mujoco.mjtObj.mjOBJ_ACTUATOR, f"vel{k}") for k in range(1, 7)]),
        tcp_site=nid(mujoco.mjtObj.mjOBJ_SITE, "tcp"),
        flange_site=nid(mujoco.mjtObj.mjOBJ_SITE, "flange"),
        pad_body=nid(mujoco.mjtObj.mjOBJ_BODY, "vacuum_pad"),
        weld=nid(mujoco.mjtObj.mjOBJ_EQUALITY, "suction_weld") if n_tiles else -1,
        tile_body=shape_bodies[0].copy(),
        tile_qpos=model.jnt_qposadr[tjoints].copy() if names else np.zeros(0, int),
        tile_dof=model.jnt_dofadr[tjoints].copy() if names else np.zeros(0, int),
        tile_geom_start=model.body_geomadr[shape_bodies[0]].copy(),
        tile_geom_count=model.body_geomnum[shape_bodies[0]].copy(),
        tile_visual=visual[0],
        variant_body=shape_bodies,
        variant_geom_start=model.body_geomadr[shape_bodies].copy(),
        variant_geom_count=model.body_geomnum[shape_bodies].copy(),
        variant_visual=visual,
        input_belt_geom=nid(mujoco.mjtObj.mjOBJ_GEOM, "input_belt"),
        mesh_geom=nid(mujoco.mjtObj.mjOBJ_GEOM, "mesh_sheet"),
        input_camera=nid(mujoco.mjtObj.mjOBJ_CAMERA, "input_camera"),
        output_camera=nid(mujoco.mjtObj.mjOBJ_CAMERA, "output_camera"),
    )


def build_scene(
    cfg: CellConfig,
    tiles: Sequence[PhysicalTile] = (),
    slots: Sequence[SlotSpec] = (),
    variants: int = 1,
) -> tuple[mujoco.MjModel, SceneIds]:
    """Compile the cell and resolve its ids (all ``len(tiles)`` bodies; see `build_spec`).

    Raises:
        CellError: Bad slots or variants, or MuJoCo refused the composed model (message
            included).
    """
    spec = build_spec(cfg, tiles, slots, variants)
    try:
        model = spec.compile()
    except ValueError as exc:
        raise CellError(f"MuJoCo could not compile the cell: {exc}") from exc
    ids = resolve_ids(model, len(tiles) // variants, variants)
    if variants > 1:
        set_tile_rotation_lengths(model, ids)
    return model, ids


def set_tile_rotation_lengths(model: mujoco.MjModel, ids: SceneIds) -> None:
    """Rotational dof lengths of tiles whose geoms sit in variant child bodies.

    MuJoCo scales a rotational velocity by its dof's length before comparing it with the
    sleep tolerance. For a free body without geoms of its own the compiler measures that
    length to the world origin (about 6 m from the parking spots) instead of the tile's size,
    so a tile had to be ~200 times stiller to fall asleep, and piles of tiles stayed awake
    (3x the physics cost per step). Here each length becomes the farthest corner of the
    tile's collision geoms' boxes from its free body, the tile's size as for a one-variant
    tile. `mujoco.mj_setConst` recomputes the lengths: call this again after it.
    """
    corner = np.abs(model.geom_pos + model.geom_aabb[:, :3]) + model.geom_aabb[:, 3:]
    reach = np.linalg.norm(corner, axis=1)  # child bodies sit at their tile body's origin
    start, count = ids.variant_geom_start, ids.variant_geom_count
    for i in range(start.shape[1]):
        spans = zip(start[:, i], count[:, i], strict=True)
        mine = np.concatenate([np.arange(a, a + k) for a, k in spans])
        model.dof_length[ids.tile_dof_index[i, 3:]] = float(reach[mine].max())


def build_arm_model(cfg: CellConfig | None = None, with_cell: bool = True) -> mujoco.MjModel:
    """Arm + pad model without tiles, for IK and collision queries.

    Args:
        cfg: Cell configuration (defaults when None).
        with_cell: Include belts, bin and mesh sheet (static geoms) as obstacles.

    Returns:
        A model whose qpos is exactly the six arm joints.
    """
    cfg = cfg or CellConfig()
    if not with_cell:
        spec = _robot_spec(cfg)
        _configure(spec, cfg)
        return spec.compile()
    return build_scene(cfg)[0]


__all__ = [
    "CellGeometry",
    "SceneIds",
    "build_arm_model",
    "build_scene",
    "build_spec",
    "cell_geometry",
    "extrusion",
    "park_positions",
    "resolve_ids",
    "set_tile_rotation_lengths",
    "tile_name",
    "yaw_quat",
]
