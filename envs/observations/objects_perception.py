"""The ``objects`` tile rows from the input camera's picture (``objects_source="perception"``).

Per observation the input camera is rendered at ``objects_image_size`` and qshape's extraction
(`qshape.vision.extract.extract_detailed`, bundled ``configs/vision.yaml``) finds the whole
tiles in it. Each figure's outline (and holes) is cast through the published camera model
(`envs.cell.cameras.CameraModel.unproject_to_plane`, lens distortion removed) onto the plane
of the tiles' top faces, in world metres. A figure then gives one row as the privileged
source lays it out (`envs.observations.objects`): colour measured in the picture, area and hole
area of the figure on the plane, xy its area centroid, points resampled with the same start rule
(every point on the perceived outline), flag 1 (seen on the input belt), valid 1.

Yaw: the tile's yaw is a rotation of its body frame, which a picture does not show; the
design does (its tile shapes, known to the cell's operator). The perceived outline, centred,
is registered against each of the design's shape outlines (equal arc length samples, the best
cyclic shift and rotation by circular cross-correlation, `register`); the yaw is the
rotation of the best-fitting shape. A symmetric shape fits equally at each of its turns, so
the yaw is defined modulo the shape's symmetry, as the privileged yaw is compared.

Association: row ``i`` must hold the tile the ``pick_place_discrete`` action's index ``i``
names, which only the simulator knows. The env uses the privileged tile positions for that
decision and nothing else: figures and fed tiles are paired one to one by centroid distance
(`scipy.optimize.linear_sum_assignment`), and a pair counts only within ``objects_gate_mm``.
A tile no figure is paired with (occluded, off the picture or cut by its border, merged
with a touching tile, not yet fed, on the pad) gets a masked row: valid 0 and all zeros,
never a guess. A figure no tile is paired with is dropped.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment
from shapely.geometry import Polygon

from envs.cell.cell import Cell
from envs.env_config import EnvConfig, EnvConfigError
from envs.errors import CellError
from envs.observations.objects import as_xy, entity_geometry, oriented_points, resample_outline
from envs.task_spec import work_areas
from qshape.errors import QShapeError
from qshape.vision.extract import ExtractResult, extract_detailed
from qshape.vision.params import ExtractParams, ImageError
from spatial.units import MM_PER_M

REGISTER_SAMPLES = 256
"""Equal arc length samples per outline in the yaw registration."""


@dataclass(frozen=True)
class PerceivedFigure:
    """One whole figure of the picture on the belt plane.

    Attributes:
        outline: Outer outline, world (x, y) [m], shape (v, 2).
        holes: Hole outlines, world (x, y) [m].
        color: Measured RGB in [0, 1].
        centre: Area centroid (holes subtracted), world (x, y) [m], shape (2,).
    """

    outline: np.ndarray
    holes: tuple[np.ndarray, ...]
    color: tuple[float, float, float]
    centre: np.ndarray


def centred_samples(outline: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """An outline about ``centre`` at `REGISTER_SAMPLES` equal arc length points, complex [mm]."""
    xy = resample_outline(np.asarray(outline) - centre, REGISTER_SAMPLES) * MM_PER_M
    return xy[:, 0] + 1j * xy[:, 1]


def register(observed: np.ndarray, references: np.ndarray) -> tuple[int, float, float]:
    """The reference an observed outline fits best, the rotation and the RMS residual.

    Both are closed outlines about their centroids at the same number of equal arc length
    samples, counter-clockwise; for each reference and each cyclic shift ``s`` the best
    rotation of the reference onto the observed samples is the angle of
    ``c[s] = sum_k observed[k + s] conj(ref[k])`` (all shifts at once by FFT), and the
    residual ``sum |observed|^2 + sum |ref|^2 - 2 |c[s]|``.

    Args:
        observed: Shape (m,) complex [mm].
        references: Shape (r, m) complex [mm].

    Returns:
        (reference index, rotation [rad] taking the reference onto ``observed``, RMS residual
        per sample [mm]).
    """
    m = len(observed)
    corr = np.fft.ifft(np.fft.fft(observed)[None] * np.conj(np.fft.fft(references, axis=1)))
    power = np.sum(np.abs(observed) ** 2) + np.sum(np.abs(references) ** 2, axis=1)
    best = np.argmax(np.abs(corr), axis=1)
    peak = corr[np.arange(len(references)), best]
    residual = power - 2 * np.abs(peak)
    r = int(np.argmin(residual))
    return r, float(np.angle(peak[r])), float(np.sqrt(max(residual[r], 0.0) / m))


class PerceivedTiles:
    """Builds the ``objects`` tile rows of one cell from its input camera (cell order).

    Args:
        cell: The cell.
        config: Environment configuration (``objects_image_size``, ``objects_gate_mm``,
            ``objects_points``).
        fields: Field name -> column slice of a row (`envs.observations.objects.object_fields`).
        dim: Row length.

    Raises:
        EnvConfigError: ``objects_image_size`` outside qshape's accepted image sizes.
    """

    def __init__(self, cell: Cell, config: EnvConfig, fields: dict[str, slice], dim: int) -> None:
        self.cell = cell
        self.params = ExtractParams.load()
        h, w = config.objects_image_size
        lo, hi = self.params.min_size_px, self.params.max_size_px
        if not (lo <= h <= hi and lo <= w <= hi):
            raise EnvConfigError(
                f"objects_image_size {h} x {w} px is outside the extraction's accepted "
                f"{lo}..{hi} px per side"
            )
        self.size = (h, w)
        self.gate = config.objects_gate_mm / MM_PER_M
        self.points = config.objects_points
        self.fields = fields
        self.dim = dim
        self.plane_z = work_areas(cell, config)[0].tile_top_z
        self._shapes_seen: tuple[object, ...] | None = None
        self._references = np.zeros((0, REGISTER_SAMPLES), complex)
        self.last_figures: tuple[PerceivedFigure, ...] = ()
        self.last_picture: np.ndarray | None = None

    def figures(self, image: np.ndarray) -> tuple[PerceivedFigure, ...]:
        """The whole figures of an input camera picture on the belt plane.

        A picture the extraction refuses (uniform, dark) has none; a figure whose outline does
        not map to a valid polygon on the plane is dropped.
        """
        try:
            res: ExtractResult = extract_detailed(image, self.params)
        except ImageError:
            return ()
        h, w = image.shape[:2]
        camera = self.cell.camera_model("input_camera", h, w)
        out = []
        for fig in res.figures:
            try:
                outer = camera.unproject_to_plane(fig.outer.dense(), self.plane_z)[:, :2]
                holes = tuple(
                    camera.unproject_to_plane(b.dense(), self.plane_z)[:, :2] for b in fig.holes
                )
            except (CellError, QShapeError):
                continue
            poly = Polygon(outer, list(holes))
            if not poly.is_valid or poly.area <= 0:
                continue
            color = fig.color or (0.0, 0.0, 0.0)
            centre = np.array([poly.centroid.x, poly.centroid.y])
            out.append(PerceivedFigure(outer, holes, color, centre))
        return tuple(out)

    def observe(self, template: np.ndarray) -> np.ndarray:
        """Tile rows (rows_t, D) in the cell's order: perceived rows, masked rows of zeros.

        Args:
            template: Zero rows of the right shape (only its shape and dtype are used).
        """
        cell = self.cell
        if cell.slots is not self._shapes_seen:  # a reset drew another design
            self._start_episode()
        image = cell.render("input_camera", *self.size)
        figs = self.figures(image)
        self.last_picture, self.last_figures = image, figs
        tiles = np.zeros_like(template)
        pairs = self.associate(figs)
        if not pairs:
            return tiles
        rows = [i for i, _ in pairs]
        chosen = [figs[k] for _, k in pairs]
        self._fill(tiles, np.array(rows), chosen)
        return tiles

    def associate(self, figs: Sequence[PerceivedFigure]) -> list[tuple[int, int]]:
        """(tile index, figure index) pairs, one to one, centroids within the gate.

        Uses the simulator's tile positions (fed tiles only): the one privileged input, to
        decide which row a figure fills.
        """
        cell = self.cell
        fed = np.flatnonzero(cell.on_stage)
        if not len(figs) or not len(fed):
            return []
        xy = cell.tile_poses().pos[fed, :2]
        centres = np.array([f.centre for f in figs])
        dist = np.linalg.norm(xy[:, None] - centres[None], axis=2)
        far = dist > self.gate
        cost = np.where(far, self.gate * len(fed) * len(figs) + dist, dist)
        ti, fi = linear_sum_assignment(cost)
        return [(int(fed[t]), int(f)) for t, f in zip(ti, fi, strict=True) if not far[t, f]]

    def _fill(self, tiles: np.ndarray, rows: np.ndarray, figs: Sequence[PerceivedFigure]) -> None:
        f = self.fields
        geometry = entity_geometry(
            [g.outline for g in figs], [g.holes for g in figs], [g.color for g in figs], self.points
        )
        m = len(figs)
        pts = oriented_points(geometry, np.ones(m, complex), np.zeros(m), self.points)
        yaw = np.array([self._yaw(g) for g in figs])
        tiles[rows, f["rgb"]] = geometry.rgb
        tiles[rows, f["area"].start] = geometry.area
        tiles[rows, f["hole_area"].start] = geometry.hole_area
        tiles[rows, f["xy"]] = np.array([g.centre for g in figs])
        tiles[rows, f["yaw"]] = np.column_stack([np.cos(yaw), np.sin(yaw)])
        tiles[rows, f["flag"].start] = 1.0
        tiles[rows, f["valid"].start] = 1.0
        tiles[rows, f["points"]] = as_xy(pts)

    def _yaw(self, fig: PerceivedFigure) -> float:
        _, angle, _ = register(centred_samples(fig.outline, fig.centre), self._references)
        return angle

    def _start_episode(self) -> None:
        """The design's distinct shape outlines, about their area centroids (the references)."""
        cell = self.cell
        self._shapes_seen = cell.slots
        shapes = {s.shape.name: s.shape for s in cell.slots}
        refs = []
        for shape in shapes.values():
            poly = Polygon(shape.outline, list(shape.holes))
            refs.append(centred_samples(shape.outline, np.array(poly.centroid.coords[0])))
        self._references = np.array(refs).reshape(len(refs), REGISTER_SAMPLES)


__all__ = ["REGISTER_SAMPLES", "PerceivedFigure", "PerceivedTiles", "register"]
