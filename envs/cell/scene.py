"""Programmatic composition of the cell with MjSpec: robot + belts + bin + mesh + cameras + tiles.

The robot comes from ``assets/irb140/irb140.xml``; the fixed parts are added by
`envs.cell.fixtures` (where they are: `envs.cell.geometry`; contact classes:
`envs.cell.contacts`), the tiles here. Names are resolved to ids once, into a frozen
`SceneIds`. `CellGeometry`, `cell_geometry` and `extrusion` are re-exported from their modules.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass, replace

import mujoco
import numpy as np
from shapely.geometry import Polygon

from envs.cell.config import CellConfig
from envs.cell.contacts import (
    CONTACT_SOLREF,
    PIECE_CONAFFINITY,
    SUPPORT_CONAFFINITY,
    SUPPORT_CONTYPE,
    TILE_CONAFFINITY,
    TILE_CONTYPE,
    WELD_SOLREF,
)
from envs.cell.fixtures import add_fixtures, extrusion
from envs.cell.geometry import CellGeometry, cell_geometry
from envs.cell.tiles.tile import PhysicalTile, SlotSpec
from envs.errors import CellError

PARK_SPACING = 0.08
"""Grid spacing of parked (not yet fed) tiles on the floor far from the cell [m]."""
PARK_ORIGIN = np.array([-6.0, -1.0])
"""Corner of the parking grid, outside the rendered floor [m]."""
WAKE_FORCE = 1e-12
"""Negligible force [N] applied for one physics step to wake sleeping tiles (any applied force
wakes a sleeping tree in MuJoCo; changing qpos or surfacevel does not)."""


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


def park_positions(n: int, thickness: float) -> np.ndarray:
    """Parking positions (on the floor, far away) of tiles not yet fed, shape (n, 3) [m]."""
    cols = max(1, int(np.ceil(np.sqrt(n))))
    k = np.arange(n)
    xy = PARK_ORIGIN + PARK_SPACING * np.stack([k % cols, k // cols], axis=1)
    return np.column_stack([xy, np.full(n, thickness / 2 + 1e-4)])


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
    geometry: CellGeometry | None = None,
) -> mujoco.MjSpec:
    """The whole cell as an editable MjSpec (tiles parked on the floor far away).

    Args:
        cfg: Cell configuration.
        tiles: Physical tiles (one free body each); empty for an arm + cell model. With
            ``variants`` V > 1: V variants of n tiles, variant-major (``v * n + i``), each in
            a child body of its tile's free body.
        slots: Slots of the mesh (visual marks).
        variants: Variants per tile in ``tiles``.
        geometry: Where the parts are, with the design's mesh (`cell_geometry`); None: the
            configuration's largest mesh.

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
    add_fixtures(spec, cfg, slots, geometry or cell_geometry(cfg))
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
    geometry: CellGeometry | None = None,
) -> tuple[mujoco.MjModel, SceneIds]:
    """Compile the cell and resolve its ids (all ``len(tiles)`` bodies; see `build_spec`).

    Raises:
        CellError: Bad slots or variants, or MuJoCo refused the composed model (message
            included).
    """
    spec = build_spec(cfg, tiles, slots, variants, geometry)
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
]
