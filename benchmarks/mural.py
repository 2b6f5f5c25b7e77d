"""Benchmark of a mural through the scripted cell, mesh by mesh, on a static belt.

Run ``python -m benchmarks.mural [--mural sunset] [--meshes r0c0,r1c2] [--seed 0] [--workers 2]``.
Each mesh of the mural (``configs/murals/``) is one episode of `MosaicAssembly-v0` with
``feed="batch"`` (a static belt, tiles indexed in batch by batch), driven by
`agents.scripted.agent.ScriptedAgent` from full-resolution camera images with dynamic execution, as
``benchmarks.scripted`` plays its scenarios (its `play` runs each episode). Before running, every
mesh is checked to fit the cell's mesh sheet. Prints one row per mesh and the mural's totals
(correct, misplaced, tiles per simulated minute, wall time) and writes ``out/bench_mural.json``.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import time
from pathlib import Path
from typing import Any

from apps.cli import CommandParser, run_cli, write_result
from benchmarks.scripted import Episode, Scenario, ScriptedBenchConfig, play, summarise, table
from configs import load_config
from envs.cell.rendering import use_headless_rendering
from qshape.design.mural import Mural, MuralError
from spatial.units import MM_PER_M

OUT = Path("out/bench_mural.json")
"""Default output file."""


def scenarios(mural: Mural, names: list[str] | None) -> list[Scenario]:
    """One scenario per selected mesh: its design file, fed in batches on a static belt.

    Raises:
        MuralError: An unknown mesh name (the message lists the names), or a mural built in
            memory (its meshes have no design files for the cell to load).
    """
    meshes = [mural.mesh(n) for n in names] if names else list(mural.meshes)
    out = []
    for m in meshes:
        if not m.source:
            raise MuralError(f"mesh {m.name!r} has no design file; save and load the mural first")
        out.append(
            Scenario(
                name=f"{mural.name} {m.name} ({len(m.design.slots)} tiles)",
                env={"design": m.source, "feed": "batch", "belt_speed": 0.0},
                min_correct=1.0,
            )
        )
    return out


def mesh_area_mm() -> tuple[float, float]:
    """The largest mesh sheet the cell takes, (width, height) in [mm] (``configs/cell.yaml``)."""
    from envs.cell.config import load_cell_config  # noqa: PLC0415 - keep the import light

    largest = load_cell_config().output_belt.max_mesh_size
    return largest[0] * MM_PER_M, largest[1] * MM_PER_M


def totals(rows: list[dict[str, Any]], episodes: list[Episode], wall_s: float) -> dict[str, Any]:
    """The mural's totals over its meshes."""
    tiles = sum(r["tiles"] for r in rows)
    correct = sum(r["correct"] for r in rows)
    sim = sum(e.sim_s for e in episodes)
    return {
        "meshes": len(rows),
        "tiles": tiles,
        "correct": correct,
        "correct_fraction": correct / tiles if tiles else 0.0,
        "misplaced": sum(r["misplaced"] for r in rows),
        "dropped": sum(r["dropped"] for r in rows),
        "lost": sum(r["lost"] for r in rows),
        "failed_actions": sum(r["failed_actions"] for r in rows),
        "sim_s": sim,
        "tiles_per_min": 60.0 * correct / sim if sim > 0 else 0.0,
        "tiles_per_min_worst_mesh": min((e.tiles_per_min for e in episodes), default=0.0),
        "episode_wall_s": sum(e.wall_s for e in episodes),
        "wall_s": wall_s,
        "wall_s_per_tile": sum(e.wall_s for e in episodes) / max(correct, 1),
    }


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Command line: run the selected meshes, print the table, write the JSON."""
    p = CommandParser(description=__doc__.splitlines()[0])
    p.add_argument("--mural", default="sunset", help="bundled mural name or YAML path")
    p.add_argument("--meshes", help="comma-separated mesh names (default: every mesh)")
    p.add_argument("--seed", type=int, default=0, help="episode seed of every mesh")
    p.add_argument("--config", default="bench_scripted", help="image size and step limit from")
    p.add_argument("--workers", type=int, default=min(2, os.cpu_count() or 1))
    p.add_argument("--out", type=Path, default=OUT)
    args = p.parse_args(argv)
    mural = Mural.load(args.mural)
    mural.check_fits(*mesh_area_mm())
    names = [n for n in (args.meshes or "").split(",") if n]
    chosen = scenarios(mural, names or None)
    cfg = load_config(ScriptedBenchConfig, args.config)
    jobs = [(s, args.seed, cfg.image_size, cfg.steps_per_slot) for s in chosen]
    t0 = time.perf_counter()
    use_headless_rendering()
    with mp.get_context("spawn").Pool(max(1, args.workers)) as pool:
        episodes = pool.map(play, jobs, chunksize=1)
    wall = time.perf_counter() - t0
    rows = [summarise(s, [e for e in episodes if e.scenario == s.name]) for s in chosen]
    total = totals(rows, episodes, wall)
    print(table(rows))
    print(
        f"mural {mural.name}: {total['meshes']} meshes, {total['correct']}/{total['tiles']} "
        f"correct, {total['misplaced']} misplaced, {total['tiles_per_min']:.2f} tiles/min "
        f"(simulated; worst mesh {total['tiles_per_min_worst_mesh']:.2f}), "
        f"{total['wall_s']:.0f} s wall ({total['wall_s_per_tile']:.2f} s/tile per worker)"
    )
    result = {
        "mural": mural.name,
        "mural_tiles": mural.tiles,
        "mural_meshes": len(mural.meshes),
        "seed": args.seed,
        "workers": args.workers,
        "image_size": list(cfg.image_size),
        "total": total,
        "meshes": rows,
    }
    return write_result(args.out, result)


if __name__ == "__main__":
    run_cli(main)
