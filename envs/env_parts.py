"""The parts of `MosaicAssembly-v0` made from one design's cell: `EnvParts` and `build_parts`.

The env builds them once at construction, and again at every reset when its design source is
procedural (`envs.design_source`); the IK solver (the arm alone) and the spaces are built once.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from envs.actions import (
    ActionAdapter,
    CartesianActions,
    DiscretePickPlaceActions,
    JointActions,
    PickPlaceActions,
)
from envs.cell.cell import Cell
from envs.cell.pick_place import PickPlaceExecutor
from envs.cell.tiles.shapes import design_mesh_size
from envs.env_config import EnvConfig, EnvConfigError
from envs.episode_setup import build_cell, design_cell_parts
from envs.indexing import IndexMaps
from envs.observations.spaces import Observer
from envs.task import MosaicTask
from envs.task_spec import Area, PickPlaceCodec, TaskSpec, build_task_spec, work_areas
from planners.config import PlannerConfig
from planners.ik import IKSolver

if TYPE_CHECKING:
    from qshape.design import Design


@dataclass(frozen=True)
class EnvParts:
    """Everything of the env that depends on the cell (see `MosaicAssemblyEnv` for each)."""

    cell: Cell
    task: MosaicTask
    observer: Observer
    index: IndexMaps
    pick_area: Area
    place_area: Area
    codec: PickPlaceCodec
    task_spec: TaskSpec
    executor: PickPlaceExecutor | None
    actions: ActionAdapter


def build_design_cell(cfg: EnvConfig, design: Design | None, seed: int) -> tuple[Design, Cell]:
    """The design (None: ``cfg.design``, loaded) and its cell built with ``seed``.

    Raises:
        CellError: The tiles do not fit (`envs.episode_setup.build_cell`).
    """
    design, shapes, slots = design_cell_parts(cfg, design)
    mesh = design_mesh_size(design)
    cell = build_cell(cfg.cell, shapes, slots, seed=seed, tries=cfg.layout_tries, mesh_size=mesh)
    return design, cell


def build_parts(
    cfg: EnvConfig,
    design: Design | None,
    seed: int,
    ik: IKSolver,
    pcfg: PlannerConfig,
    *,
    cell: Cell | None = None,
) -> EnvParts:
    """The cell of ``design`` (None: ``cfg.design``) built with ``seed``, and its parts.

    ``cell``: that cell built already (`build_design_cell` of the same arguments, in a design
    pool's worker: `envs.pool`); ``design`` must then be given.

    Raises:
        CellError: The tiles do not fit (`envs.episode_setup.build_cell`).
        EnvConfigError: An observation image larger than the render buffer.
    """
    if cell is None or design is None:
        design, cell = build_design_cell(cfg, design, seed)
    check_image_size(cfg, cell)
    task = MosaicTask(cell, cfg)
    pick, place = work_areas(cell, cfg)
    codec = PickPlaceCodec(pick, place, cfg.pick_yaw_entry)
    executor = None
    actions: ActionAdapter
    if cfg.action_mode == "joint":
        actions = JointActions(cell, cfg)
    elif cfg.action_mode == "cartesian":
        actions = CartesianActions(cell, cfg, ik, pick, place)
    else:
        executor = PickPlaceExecutor(cell, cfg, pcfg, ik, pick=pick, place=place)
        if cfg.action_mode == "pick_place":
            actions = PickPlaceActions(cell, cfg, executor, codec)
        else:
            actions = DiscretePickPlaceActions(cell, cfg, executor)
    return EnvParts(
        cell=cell,
        task=task,
        observer=Observer(cell, task, cfg),
        index=IndexMaps(cell, cfg),
        pick_area=pick,
        place_area=place,
        codec=codec,
        task_spec=build_task_spec(cell, cfg, design),
        executor=executor,
        actions=actions,
    )


def check_image_size(cfg: EnvConfig, cell: Cell) -> None:
    """Refuse an observation image larger than the model's offscreen render buffer.

    Raises:
        EnvConfigError: ``image_size`` beyond the buffer (names the allowed size).
    """
    if cfg.obs_mode in ("state", "objects"):
        return
    vis = cell.model.vis.global_
    h, w = cfg.image_size
    if h > vis.offheight or w > vis.offwidth:
        raise EnvConfigError(
            f"image_size {(h, w)} exceeds the offscreen render buffer "
            f"({vis.offheight}, {vis.offwidth}) px (height, width); allowed: up to that size"
        )


__all__ = ["EnvParts", "build_design_cell", "build_parts", "check_image_size"]
