"""Benchmark of ``objects_source="perception"`` against the privileged rows, ``MosaicDecision6-v0``.

Run ``python -m benchmarks.learned.objects_perception``. Two parts:

- cost: CPU ms per env step (kinematic ``pick_place_discrete``, driven by the privileged
  expert, resets not timed) with ``objects`` rows from each source, the sources alternated
  block by block (a shared machine's load falls on both alike);
- rows: over the held-out seeds 1000-1019, at reset and after every expert step, each tile's
  perceived row (cell order, `envs.observations.objects_perception.PerceivedTiles`) against its
  privileged row: missing (the tile is on the input belt, flag 1, but its row is masked), spurious
  (a perceived row for a tile not on the input belt), wrong (centroid > 2 mm, yaw > 3 deg
  modulo the shape's symmetry, or area > 5 %), and the error distributions: centroid [mm],
  yaw [deg] (modulo symmetry; continuous symmetry skipped), area [%], outline (each
  perceived point's distance to the built outline as it lies [mm]), colour (largest channel
  difference, in [0, 1] units). Once with the default cameras, once with the realistic
  camera of ``configs/bench_scripted.yaml`` (barrel lens, 10 ms exposure).

Writes ``out/bench_objects_perception.json``.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, cast

import gymnasium as gym
import numpy as np
from shapely.geometry import LinearRing, Point

import envs  # noqa: F401 - registers the ids
from apps.cli import CommandParser, run_cli
from benchmarks.learned.expert_step import timed_expert_step
from configs.files import write_text
from envs.mosaic_env import MosaicAssemblyEnv
from envs.observations.objects import OBJECT_FIELDS as F
from spatial.angles import symmetry_period
from spatial.units import MM_PER_M

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "out"
TASK = "MosaicDecision6-v0"
SOURCES = ("privileged", "perception")
SEEDS = range(1000, 1020)
TOLERANCE = {"centroid_mm": 2.0, "yaw_deg": 3.0, "area_pct": 5.0}
"""A perceived row is wrong past any of these (the tests' tolerances)."""
LENS = {"distortion": [-0.1, 0.08, 0.0, 0.0, 0.0]}
REALISTIC_CELL = {
    "input_camera": {**LENS, "exposure_time": 0.01},
    "output_camera": LENS,
    "tiles": {"variants": 8, "stream_period": 2.5, "stream_initial": 1},
}
"""The realistic camera of ``configs/bench_scripted.yaml`` (restating the env's tile changes)."""


def _expert_episode(env: gym.Env, seed: int, visit: Any = None) -> float:
    """Play one expert episode; CPU seconds of its steps. ``visit()`` after reset and steps."""
    u = cast(MosaicAssemblyEnv, env.unwrapped)
    env.reset(seed=seed)
    if visit is not None:
        visit()
    spent = 0.0
    for _ in range(len(u.cell.slots)):
        step = timed_expert_step(env)
        if step is None:
            break
        spent += step[0]
        if visit is not None:
            visit()
        if step[1]:
            break
    return spent


def cost(blocks: int, episodes: int) -> dict[str, Any]:
    """Median CPU ms per step of each source over alternated blocks."""
    made = {
        s: gym.make(TASK, obs_mode="objects", objects_source=s, disable_env_checker=True)
        for s in SOURCES
    }
    steps = len(cast(MosaicAssemblyEnv, made["privileged"].unwrapped).cell.slots)
    ms: dict[str, list[float]] = {s: [] for s in SOURCES}
    for b in range(blocks):
        for s in SOURCES if b % 2 == 0 else SOURCES[::-1]:
            spent = sum(_expert_episode(made[s], 100 * b + e) for e in range(episodes))
            ms[s].append(1e3 * spent / (episodes * steps))
    for e in made.values():
        e.close()
    out = {s: float(np.median(v)) for s, v in ms.items()}
    out["extra_ms"] = out["perception"] - out["privileged"]
    return out


def _angle_error_deg(a: float, b: float, symmetry: int) -> float | None:
    if symmetry == 0:
        return None
    period = symmetry_period(symmetry)
    d = (a - b) % period
    return float(np.degrees(min(d, period - d)))


def _compare(u: MosaicAssemblyEnv, acc: dict[str, list[float]], counts: dict[str, int]) -> None:
    """Privileged and perceived rows of the current state, cell order, into the tallies."""
    objects, perceived = u.observer.objects, u.observer.perceived
    assert objects is not None and perceived is not None
    priv, _ = objects.observe(np.random.default_rng(0), u.task.evaluate())
    per = perceived.observe(priv)
    poses = u.cell.tile_poses()
    for i, tile in enumerate(u.cell.tiles):
        on_belt, seen = priv[i, F["flag"]][0] > 0, per[i, F["valid"]][0] > 0
        counts["rows"] += int(on_belt)
        counts["missing"] += int(on_belt and not seen)
        counts["spurious"] += int(seen and not on_belt)
        if not seen:
            continue
        centroid = float(np.linalg.norm(per[i, F["xy"]] - priv[i, F["xy"]]) * MM_PER_M)
        yaw_p = float(np.arctan2(*per[i, F["yaw"]][::-1]))
        yaw_t = float(np.arctan2(*priv[i, F["yaw"]][::-1]))
        yaw = _angle_error_deg(yaw_p, yaw_t, tile.shape.symmetry)
        area = float(100 * abs(per[i, F["area"]][0] / priv[i, F["area"]][0] - 1))
        turn = np.array(
            [
                [np.cos(poses.yaw[i]), -np.sin(poses.yaw[i])],
                [np.sin(poses.yaw[i]), np.cos(poses.yaw[i])],
            ]
        )
        ring = LinearRing((tile.outline @ turn.T + poses.pos[i, :2]) * MM_PER_M)
        pts = per[i, F["points"]].reshape(-1, 2) + per[i, F["xy"]] * MM_PER_M
        outline = [ring.distance(Point(p)) for p in pts]
        acc["centroid_mm"].append(centroid)
        if yaw is not None:
            acc["yaw_deg"].append(yaw)
        acc["area_pct"].append(area)
        acc["outline_mean_mm"].append(float(np.mean(outline)))
        acc["outline_max_mm"].append(float(np.max(outline)))
        acc["color"].append(float(np.abs(per[i, F["rgb"]] - priv[i, F["rgb"]]).max()))
        wrong = centroid > TOLERANCE["centroid_mm"] or area > TOLERANCE["area_pct"]
        wrong = wrong or (yaw is not None and yaw > TOLERANCE["yaw_deg"])
        counts["wrong"] += int(wrong)
        counts["seen"] += 1


def rows(cell: dict[str, Any] | None) -> dict[str, Any]:
    """Missing / spurious / wrong counts and error distributions over `SEEDS`."""
    kw: dict[str, Any] = {"obs_mode": "objects", "objects_source": "perception"}
    if cell is not None:
        kw["cell"] = cell
    env = gym.make(TASK, disable_env_checker=True, **kw)
    u = cast(MosaicAssemblyEnv, env.unwrapped)
    acc: dict[str, list[float]] = {
        k: []
        for k in (
            "centroid_mm",
            "yaw_deg",
            "area_pct",
            "outline_mean_mm",
            "outline_max_mm",
            "color",
        )
    }
    counts = {"rows": 0, "missing": 0, "spurious": 0, "wrong": 0, "seen": 0}
    for seed in SEEDS:
        _expert_episode(env, seed, lambda: _compare(u, acc, counts))
    env.close()
    stats = {
        k: {"mean": float(np.mean(v)), "p95": float(np.percentile(v, 95)), "max": float(np.max(v))}
        for k, v in acc.items()
        if v
    }
    return {**counts, "errors": stats}


def main(argv: list[str] | None = None) -> None:
    """Print the figures and write ``out/bench_objects_perception.json``."""
    p = CommandParser(description=__doc__.splitlines()[0])
    p.add_argument("--blocks", type=int, default=4, help="alternated cost blocks per source")
    p.add_argument("--episodes", type=int, default=3, help="expert episodes per cost block")
    args = p.parse_args(argv)
    c = cost(args.blocks, args.episodes)
    print(f"{TASK}, CPU ms per env step (expert, median of {args.blocks} alternated blocks)")
    for s in SOURCES:
        print(f"  {s:10s} {c[s]:8.2f}")
    print(f"  perception - privileged: {c['extra_ms']:+.2f} ms/step")
    report: dict[str, Any] = {"task": TASK, "cost_ms_per_step": c, "tolerance": TOLERANCE}
    for name, cell in (("default camera", None), ("realistic camera", REALISTIC_CELL)):
        r = rows(cell)
        report[name] = r
        print(
            f"{name}, seeds {SEEDS.start}-{SEEDS.stop - 1}: {r['rows']} tile rows on the belt, "
            f"missing {r['missing']} ({100 * r['missing'] / max(r['rows'], 1):.2f} %), "
            f"spurious {r['spurious']}, wrong {r['wrong']} of {r['seen']} seen "
            f"({100 * r['wrong'] / max(r['seen'], 1):.2f} %)"
        )
        for k, v in r["errors"].items():
            print(f"  {k:16s} mean {v['mean']:7.3f}  p95 {v['p95']:7.3f}  max {v['max']:7.3f}")
    OUT.mkdir(exist_ok=True)
    write_text(OUT / "bench_objects_perception.json", json.dumps(report, indent=1))
    print(f"wrote {OUT / 'bench_objects_perception.json'}")


if __name__ == "__main__":
    run_cli(main)
