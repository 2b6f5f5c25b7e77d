"""Episode set-up's layout policy: the one place that decides what happens when tiles do not fit.

Random layouts of a crowded tile area fail now and then; a design may have more tiles than
the belt holds at once. Three decisions follow, all made here (the task's
`envs.task.MosaicTask.initialize_episode`, the env's construction and the programs call them):

- `build_cell`: a cell is built with the first seed from ``seed`` on whose layout fits (the
  seed also draws the tiles' manufacturing noise, so it is fixed at construction); only a
  failed random draw (`LayoutError`) is retried, a deterministic misfit (a tile larger than
  the area, more tile area than the belt holds) is raised at once.
- `retry_layout` with ``retry_on=CellError`` (`MosaicTask.initialize_episode`): at reset the
  tiles' variants are redrawn too, so any misfit of one draw may pass in the next.
- `with_feed_fallback`: a program that asked for every tile at once (``feed="all"``) gets the
  ``batch`` feed when they do not fit the belt together.

`design_cell_parts` turns an env configuration's design into the cell's tile shapes and slots.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, TypeVar

from envs.cell.cell import Cell
from envs.cell.config import CellConfig, FeedMode
from envs.cell.glazes import check_glazes
from envs.cell.tiles.shapes import tile_shapes_from_design
from envs.cell.tiles.tile import SlotSpec, TileShape
from envs.errors import CellError, LayoutError

if TYPE_CHECKING:
    from envs.env_config import EnvConfig
    from qshape.design import Design

T = TypeVar("T")

FALLBACK_FEED: FeedMode = "batch"
"""Feed a program falls back to when every tile at once does not fit (`with_feed_fallback`)."""


def retry_layout(
    draw: Callable[[int], T], tries: int, retry_on: type[CellError] = LayoutError
) -> T:
    """The first of ``draw(0)``, ..., ``draw(tries - 1)`` that does not raise ``retry_on``.

    Raises:
        CellError: The last draw's error when none fits; any other error of a draw at once;
            `LayoutError` when ``tries`` < 1.
    """
    for k in range(tries):
        try:
            return draw(k)
        except retry_on:
            if k == tries - 1:
                raise
    raise LayoutError(f"tries must be >= 1, got {tries}")


def build_cell(
    config: CellConfig | None,
    shapes: Sequence[TileShape] | None,
    slots: Sequence[SlotSpec] = (),
    seed: int = 0,
    tries: int = 20,
    *,
    mesh_size: Sequence[float] | None = None,
) -> Cell:
    """The cell built with the first seed from ``seed`` on whose layout fits the belt.

    The seed used is ``cell.layout_seed``; ``mesh_size`` is the design's mesh [m]
    (`envs.cell.tiles.shapes.design_mesh_size`; None: the cell's largest).

    Raises:
        LayoutError: No seed in ``[seed, seed + tries)`` fits.
        CellError: Any other bad input (raised at once), e.g. a `MeshSizeError`.
    """
    return retry_layout(
        lambda k: Cell(config, shapes, slots, seed=seed + k, mesh_size=mesh_size), tries
    )


def with_feed_fallback(make: Callable[[FeedMode], T], feed: FeedMode) -> tuple[T, FeedMode]:
    """``make(feed)``; with ``feed="all"`` whose tiles do not fit, ``make(FALLBACK_FEED)``.

    Returns:
        What ``make`` returned and the feed it was given.

    Raises:
        CellError: ``make``'s error with another feed, or with the fallback feed too.
    """
    try:
        return make(feed), feed
    except CellError:
        if feed != "all":
            raise
        return make(FALLBACK_FEED), FALLBACK_FEED


def design_cell_parts(
    config: EnvConfig, design: Design | None = None
) -> tuple[Design, tuple[TileShape, ...], tuple[SlotSpec, ...]]:
    """A design with its tile shapes and slots (the first ``max_slots`` when set).

    ``design`` None: the env's ``design`` (loaded); else that design (a procedural draw).
    A slot colour the cell cannot tell from its belt is warned about (`envs.cell.glazes`).
    """
    from qshape.design import Design  # noqa: PLC0415 - keep `import envs` light

    design = Design.load(config.design) if design is None else design
    check_glazes(design, config.cell, config.depth)
    shapes, slots = tile_shapes_from_design(design)
    if config.max_slots:
        shapes, slots = shapes[: config.max_slots], slots[: config.max_slots]
    return design, shapes, slots


__all__ = [
    "FALLBACK_FEED",
    "build_cell",
    "design_cell_parts",
    "retry_layout",
    "with_feed_fallback",
]
