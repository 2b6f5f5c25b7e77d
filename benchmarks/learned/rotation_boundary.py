"""How often the discrete rotation index sits on its 45 deg boundary, per decision rung.

With ``rotation_frame="tile"`` (the default, `envs.indexing`) rotation ``r`` of a
``pick_place_discrete`` action counts from the slot-aligned pose nearest to how the tile lies:
the index of the right turn depends on the tile's yaw relative to its slot, ``d``, rounded to
the nearest of ``rotation_bins`` steps. Where ``d`` lies near a bin boundary (45 deg for 4 bins)
a small change of the tile's yaw flips the right index, so a policy reading the yaw with a
little noise (or learning the boundary) errs there.

For each decision rung and its held-out seeds (1000-1019, designs as the protocol alternates
them) this resets the env and counts, over every (tile on the input belt, slot of its class)
pair, how many have ``d`` within ``margin_deg`` of a boundary. Two figures: over all pairs, and
over the pairs where the flip changes the right answer (the tile's symmetry does not make
every one of the ``rotation_bins`` turns equivalent: symmetry order not 0 and not a multiple
of the bins). Tiles are counted as they lie at reset (a stream feed's later tiles are not).

    python -m benchmarks.learned.rotation_boundary                 # out/rotation_boundary.json
    python -m benchmarks.learned.rotation_boundary --margin-deg 1
"""

from __future__ import annotations

import json
import math
import warnings
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import envs  # noqa: F401 - registers the ids
from apps.cli import CommandParser, run_cli
from configs.files import write_text
from envs.tasks import bundled_tasks

MARGIN_DEG = 2.0
"""Default distance from a bin boundary counted as on it [deg]."""
OUT = Path("out/rotation_boundary.json")
"""Default report path."""


def boundary_distances(env: gym.Env, bins: int) -> tuple[np.ndarray, np.ndarray]:
    """Per (input-belt tile, slot of its class) pair at the current state (privileged).

    Returns:
        Distance of the relative yaw to the nearest bin boundary [deg], shape (m,), and
        whether a flip there changes the right index (the tile's symmetry), shape (m,) bool.
    """
    u: Any = env.unwrapped
    cell, task = u.cell, u.task
    step = 2 * math.pi / bins
    tile_yaw = cell.tile_poses().yaw
    slot_yaw = cell.slot_poses_world()[:, 2]
    dist, matters = [], []
    for t in np.flatnonzero(cell.input_half()):
        sym = int(task.symmetry[t])
        for s in np.flatnonzero(task.slot_class == task.tile_class[t]):
            d = math.remainder(float(tile_yaw[t] - slot_yaw[s]), 2 * math.pi) / step
            dist.append(abs(abs(d - round(d)) - 0.5) * math.degrees(step))
            matters.append(sym != 0 and sym % bins != 0)
    return np.array(dist), np.array(matters, bool)


def measure(task_id: str, margin_deg: float) -> dict[str, Any]:
    """The boundary figures of one rung over its held-out seeds and designs."""
    task = bundled_tasks()[task_id]
    dist: list[np.ndarray] = []
    matters: list[np.ndarray] = []
    designs = task.designs("eval")
    for i, seed in enumerate(task.seeds):
        with warnings.catch_warnings():  # the -v0 ids' "out of date" notice
            warnings.simplefilter("ignore", DeprecationWarning)
            env = gym.make(task_id, **task.env_kwargs("eval", i % len(designs)))
        try:
            env.reset(seed=seed)
            d, m = boundary_distances(env, int(env.unwrapped.config.rotation_bins))  # type: ignore[attr-defined]
        finally:
            env.close()
        dist.append(d)
        matters.append(m)
    d, m = np.concatenate(dist), np.concatenate(matters)
    near = d < margin_deg
    return {
        "task": task_id,
        "seeds": f"{task.seeds[0]}-{task.seeds[-1]}",
        "designs": list(designs),
        "pairs": int(d.size),
        "near_boundary": int(near.sum()),
        "fraction": float(near.mean()) if d.size else 0.0,
        "pairs_where_it_matters": int(m.sum()),
        "near_where_it_matters": int((near & m).sum()),
        "fraction_where_it_matters": float((near & m).sum() / m.sum()) if m.any() else 0.0,
    }


def main(argv: list[str] | None = None) -> list[dict[str, Any]]:
    """Command line (see the module docstring); prints one row per rung."""
    p = CommandParser(description=__doc__.splitlines()[0])
    p.add_argument("--margin-deg", type=float, default=MARGIN_DEG, help="boundary margin [deg]")
    p.add_argument("--out", type=Path, default=OUT, help="JSON report")
    args = p.parse_args(argv)
    rows = []
    for task_id, task in bundled_tasks().items():
        if task.env.get("action_mode") != "pick_place_discrete":
            continue
        row = measure(task_id, args.margin_deg)
        rows.append(row)
        print(
            f"{task_id:26s} pairs {row['pairs']:4d}  within {args.margin_deg:g} deg: "
            f"{row['near_boundary']:3d} ({100 * row['fraction']:.1f} %)  where the tile's "
            f"symmetry makes it matter: {row['near_where_it_matters']:3d} of "
            f"{row['pairs_where_it_matters']:4d} ({100 * row['fraction_where_it_matters']:.1f} %)"
        )
    write_text(args.out, json.dumps({"margin_deg": args.margin_deg, "tasks": rows}, indent=2))
    return rows


if __name__ == "__main__":
    run_cli(main)
