"""Benchmark of the scripted cell on random designs nobody tuned for.

Run ``python -m benchmarks.random_designs`` (``--designs 0-9`` for a quick look, ``--level``
to pick levels). Each level of ``configs/bench_random_designs.yaml`` draws its designs from
`qshape.design.generator.DesignGenerator` (design ``i`` from ``numpy.random.default_rng(i)``),
writes each as a design file and plays one episode of `MosaicAssembly-v0` per design (reset
seed ``i``), driven by `agents.scripted.agent.ScriptedAgent` from full-resolution camera images
(`benchmarks.scripted.run_episode`). Levels differ in execution (kinematic for speed, a
dynamic sample) and camera (ideal, realistic).

Reported per level: tiles correct, mosaics complete, misplaced tiles, tiles left unrecognised,
and every slot not filled by the kind of failure (see `FAILURE_KINDS`), also per shape family
of the generator; for each kind the first failing picture is saved (the input camera with the
tiles concerned outlined, or the output camera for tiles misplaced). Prints a table and the run
time, writes ``out/bench_random_designs.json`` and the pictures in ``out/bench_random_designs/``.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import tempfile
import time
from collections import Counter
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from apps.cli import CommandParser, run_cli
from benchmarks.scripted import _seed_range, run_episode
from configs import ConfigError, load_config
from configs.checks import check_fields, checked
from configs.files import write_text
from envs import ENV_ID
from envs.cell.rendering import use_headless_rendering
from spatial.units import MM_PER_M

OUT = Path("out/bench_random_designs.json")
"""Default output file (pictures go to the folder of the same stem)."""
FAILURE_KINDS = (
    "misplaced",
    "dropped",
    "lost",
    "stranded",
    "unrecognised_shape",
    "unrecognised_colour",
    "outline_refused",
    "not_placed",
)
"""Why a slot stayed open: a tile put on the mesh wrong; dropped in transit; lost off the belt;
left beside the mesh; seen but matching no open slot's shape (``shape_absent``) or colour
(``color_absent``); an outline the perception could not make into a figure; anything else (not
seen, a failed pick, the step limit)."""


@dataclass(frozen=True)
class Level:
    """One level of the benchmark.

    Attributes:
        name: Label of the table row.
        designs: First and one-past-last design index.
        env: `EnvConfig` overrides (``execution``, ``feed``, ``cell``, ...).
        min_correct: Target: fraction of all tiles placed correctly.
        min_complete: Target: fraction of mosaics complete.
        max_misplaced: Target: tiles misplaced over the level.
        generator: `GeneratorConfig` fields changed for this level's designs (over the
            benchmark's ``generator_overrides``): e.g. the full range of glaze colours.
    """

    name: str
    designs: tuple[int, int] = (0, 200)
    env: dict[str, Any] = field(default_factory=dict)
    min_correct: float = 0.995
    min_complete: float = 0.98
    max_misplaced: int = 0
    generator: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class RandomDesignsBenchConfig:
    """``configs/bench_random_designs.yaml``.

    Attributes:
        generator: Generator parameters: bundled name or path (``design_generator``).
        generator_overrides: `GeneratorConfig` fields changed for the benchmark.
        image_size: Camera image (height, width) the agent sees [px].
        steps_per_slot: Episode step limit per slot.
        levels: The levels, in table order.
    """

    generator: str = "design_generator"
    generator_overrides: dict[str, Any] = field(default_factory=dict)
    image_size: tuple[int, int] = (492, 656)
    steps_per_slot: int = checked(2, ge=1)
    levels: tuple[Level, ...] = ()

    def __post_init__(self) -> None:
        """Raise `ConfigError` on bad values."""
        check_fields(self, ConfigError, prefix="bench_random_designs: ")
        if not self.levels:
            raise ConfigError("bench_random_designs: at least one level")
        for lv in self.levels:
            if lv.designs[1] <= lv.designs[0]:
                raise ConfigError(
                    f"level {lv.name!r}: designs must be [first, last) with last > first"
                )


Job = tuple[Level, int, RandomDesignsBenchConfig, str]
_CALIBRATIONS: dict[str, Any] = {}
"""Per worker process and level: the input camera's calibration."""


def _outline_picture(image: np.ndarray, outlines: list[np.ndarray], path: Path) -> None:
    """Save ``image`` with each pixel outline (m, 2) drawn in red."""
    from PIL import Image, ImageDraw  # noqa: PLC0415

    pic = Image.fromarray(np.asarray(image, dtype=np.uint8))
    draw = ImageDraw.Draw(pic)
    for pts in outlines:
        xy = [(float(x), float(y)) for x, y in np.asarray(pts)]
        draw.line([*xy, xy[0]], fill=(255, 40, 40), width=2)
    pic.save(path)


def open_slot_kinds(e: dict[str, Any], agent: Any) -> Counter[str]:
    """Every slot an episode left open, by the kind of failure (`FAILURE_KINDS`).

    ``e`` is the last ``info["evaluation"]``, ``agent`` the `ScriptedAgent` after the episode.
    """
    filled = np.asarray(e["slot_filled"], dtype=bool)
    kinds: Counter[str] = Counter()
    open_slots = int(np.count_nonzero(~filled))
    budget = open_slots

    def take(kind: str, n: int) -> None:
        nonlocal budget
        k = min(max(n, 0), budget)
        if k:
            kinds[kind] += k
            budget -= k

    take("misplaced", int(e["misplaced"]))
    take("dropped", int(e["dropped_tiles"]))
    take("lost", int(e["lost_tiles"]))
    take("stranded", int(e["stranded"]))
    reasons = Counter(u.reason for u in agent.unplaced)
    take("unrecognised_shape", reasons["shape_absent"])
    take("unrecognised_colour", reasons["color_absent"])
    per = agent.last_perception
    take("outline_refused", len(per.unrecognised) if per is not None else 0)
    take("not_placed", budget)
    return kinds


def play_design(job: Job) -> dict[str, Any]:
    """Draw design ``index``, play one episode of it, classify the open slots (worker)."""
    import gymnasium as gym  # noqa: PLC0415 - workers import the stack themselves

    from agents.scripted.agent import ScriptedAgent  # noqa: PLC0415
    from qshape.design.generator import DesignGenerator  # noqa: PLC0415
    from qshape.design.generator_config import GeneratorConfig  # noqa: PLC0415

    level, index, cfg, folder = job
    gen_cfg = GeneratorConfig.load(cfg.generator, **{**cfg.generator_overrides, **level.generator})
    design = DesignGenerator(gen_cfg).draw(np.random.default_rng(index), name=f"random_{index}")
    path = Path(folder) / f"random_{index}.yaml"
    design.save(path)
    env = gym.make(
        ENV_ID,
        max_episode_steps=None,
        **{
            "action_mode": "pick_place",
            "image_size": cfg.image_size,
            "depth": True,  # the height picture (agents.scripted.height): every glaze seen
            **level.env,
            "design": str(path),
        },
    )
    try:
        # The camera is the same for every design of a level: calibrated once per process.
        agent = ScriptedAgent.from_env(env, calibration=_CALIBRATIONS.get(level.name))
        _CALIBRATIONS[level.name] = agent.calibration
        last: dict[str, Any] = {}

        def observe(obs: Any, info: dict[str, Any]) -> None:
            del info
            last["obs"] = obs

        episode, info = run_episode(
            level.name, env, agent, index, cfg.steps_per_slot, observer=observe
        )
        slot_rows = slot_outcomes(design, env.get_wrapper_attr("task").placement())
    finally:
        env.close()
    e = info["evaluation"]
    filled = np.asarray(e["slot_filled"], dtype=bool)
    kinds = open_slot_kinds(e, agent)
    per = agent.last_perception
    families = Counter(
        s.name.split("_")[1] for s, ok in zip(design.slots, filled, strict=True) if not ok
    )
    unplaced_px = []
    if per is not None:
        bad = {u.tile for u in agent.unplaced if u.reason in ("shape_absent", "color_absent")}
        unplaced_px = [np.asarray(t.figure_px.outer.dense()) for t in per.tiles if t.index in bad]
    obs = last.get("obs", {})
    return {
        "level": level.name,
        "design": index,
        "slots": episode.slots,
        "correct": episode.correct,
        "complete": episode.correct == episode.slots,
        "misplaced": episode.misplaced,
        "unrecognised": kinds["unrecognised_shape"] + kinds["unrecognised_colour"],
        "failed_actions": episode.failed_actions,
        "steps": episode.steps,
        "wall_s": episode.wall_s,
        "failures": dict(kinds),
        "failed_families": dict(families),
        # For pictures only (dropped from the JSON).
        "_input": obs.get("input_camera"),
        "_output": obs.get("output_camera"),
        "_outlines": unplaced_px,
        "_slots": slot_rows,
    }


def slot_outcomes(design: Any, placement: Any) -> list[dict[str, Any]]:
    """Per slot of ``design``: name, family, filled, misplaced tile on it, that tile's errors.

    ``placement`` is the task's `envs.task.Placement` at the episode's end. ``misplaced_here``:
    a tile on the mesh that is not correct lies nearest this slot. Errors are those of the tile
    filling the slot, else of the misplaced tile nearest it: position [mm] and yaw modulo its
    symmetry [deg] (None: no tile on the slot).
    """
    correct = np.asarray(placement.correct, dtype=bool)
    wrong = np.asarray(placement.on_mesh, dtype=bool) & ~correct
    misplaced = {int(placement.slot[i]): int(i) for i in np.flatnonzero(wrong)}
    filling = {int(placement.slot[i]): int(i) for i in np.flatnonzero(correct)}
    rows = []
    for k, slot in enumerate(design.slots):
        tile = filling.get(k, misplaced.get(k))
        rows.append(
            {
                "name": slot.name,
                "family": slot.name.split("_")[1],
                "filled": k in filling,
                "misplaced_here": k in misplaced,
                "position_error_mm": None
                if tile is None
                else float(placement.position_error[tile]) * MM_PER_M,
                "yaw_error_deg": None
                if tile is None
                else float(np.degrees(placement.yaw_error[tile])),
            }
        )
    return rows


def summarise(level: Level, rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Totals of one level and whether its targets are met."""
    tiles = sum(r["slots"] for r in rows)
    correct = sum(r["correct"] for r in rows)
    complete = sum(r["complete"] for r in rows)
    failures: Counter[str] = Counter()
    families: Counter[str] = Counter()
    for r in rows:
        failures.update(r["failures"])
        families.update(r["failed_families"])
    frac = correct / tiles if tiles else 0.0
    done = complete / len(rows) if rows else 0.0
    misplaced = sum(r["misplaced"] for r in rows)
    return {
        "level": level.name,
        "env": level.env,
        "designs": len(rows),
        "tiles": tiles,
        "correct": correct,
        "correct_fraction": frac,
        "complete": complete,
        "complete_fraction": done,
        "misplaced": misplaced,
        "unrecognised": sum(r["unrecognised"] for r in rows),
        "failed_actions": sum(r["failed_actions"] for r in rows),
        "failures": {k: failures[k] for k in FAILURE_KINDS if failures[k]},
        "failed_families": dict(families.most_common()),
        "wall_s": sum(r["wall_s"] for r in rows),
        "targets": {
            "correct": level.min_correct,
            "complete": level.min_complete,
            "misplaced": level.max_misplaced,
        },
        "met": frac >= level.min_correct
        and done >= level.min_complete
        and misplaced <= level.max_misplaced,
        "per_design": [{k: v for k, v in r.items() if not k.startswith("_")} for r in rows],
    }


def save_pictures(
    rows: list[dict[str, Any]], folder: Path, saved: dict[str, str] | None = None
) -> dict[str, str]:
    """The first failing picture of every (level, failure kind) not in ``saved`` yet.

    Returns ``saved`` (a new mapping when None) with the files added: "level: kind" -> file.
    """
    folder.mkdir(parents=True, exist_ok=True)
    saved = {} if saved is None else saved
    for r in rows:
        for kind in r["failures"]:
            key = f"{r['level']}: {kind}"
            if key in saved:
                continue
            stem = "".join(c if c.isalnum() else "_" for c in key).strip("_")
            path = folder / f"{stem}_design{r['design']}.png"
            if kind == "misplaced" and r["_output"] is not None:
                _outline_picture(r["_output"], [], path)
            elif r["_input"] is not None:
                _outline_picture(r["_input"], r["_outlines"], path)
            else:
                continue
            saved[key] = str(path)
    return saved


def table(levels: list[dict[str, Any]]) -> str:
    """The printed table."""
    head = (
        f"{'level':36s} {'designs':>7s} {'tiles correct':>19s} {'complete':>14s} "
        f"{'mis':>4s} {'unrec':>5s}  targets"
    )
    lines = [head, "-" * len(head)]
    for r in levels:
        t = r["targets"]
        lines.append(
            f"{r['level']:36s} {r['designs']:7d} {r['correct']:6d}/{r['tiles']:<6d}"
            f"{r['correct_fraction']:6.1%} {r['complete']:4d}/{r['designs']:<4d}"
            f"{r['complete_fraction']:5.0%} {r['misplaced']:4d} {r['unrecognised']:5d}  "
            f">= {t['correct']:.1%}, >= {t['complete']:.0%}, <= {t['misplaced']} misplaced: "
            f"{'met' if r['met'] else 'NOT MET'}"
        )
        if r["failures"]:
            lines.append(f"{'':4s}open slots by kind: {r['failures']}")
            lines.append(f"{'':4s}open slots by family: {r['failed_families']}")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Command line: run every level, print the table and the time, write JSON and pictures."""
    p = CommandParser(description=__doc__.splitlines()[0])
    p.add_argument("--config", default="bench_random_designs", help="bundled name or YAML path")
    p.add_argument("--designs", type=_seed_range, help="FIRST-LAST design indices (all levels)")
    p.add_argument("--level", action="append", help="only these levels (by name prefix)")
    p.add_argument("--workers", type=int, default=1)
    p.add_argument("--out", type=Path, default=OUT)
    args = p.parse_args(argv)
    cfg = load_config(RandomDesignsBenchConfig, args.config)
    levels = [
        replace(lv, designs=args.designs) if args.designs else lv
        for lv in cfg.levels
        if not args.level or any(lv.name.startswith(x) for x in args.level)
    ]
    if not levels:
        raise SystemExit(f"error: no level matches {args.level}")
    t0 = time.perf_counter()
    use_headless_rendering()
    pictures: dict[str, str] = {}
    folder_out = args.out.with_suffix("")
    rows: list[dict[str, Any]] = []

    def keep(row: dict[str, Any]) -> None:
        save_pictures([row], folder_out, pictures)
        rows.append(r := {k: v for k, v in row.items() if not k.startswith("_")})
        print(
            f"{r['level']}: design {r['design']}: {r['correct']}/{r['slots']} "
            f"({r['wall_s']:.1f} s) {r['failures'] or ''}",
            flush=True,
        )
        # Written after every design: a run stopped early keeps what it played.
        _write(args, cfg, levels, rows, pictures, time.perf_counter() - t0, done=False)

    with tempfile.TemporaryDirectory(prefix="random_designs_") as folder:
        jobs: list[Job] = [(lv, i, cfg, folder) for lv in levels for i in range(*lv.designs)]
        # Interleaved across levels (by the share of each level played): a run stopped early
        # has played every level in proportion.
        jobs.sort(key=lambda j: (j[1] - j[0].designs[0]) / (j[0].designs[1] - j[0].designs[0]))
        if args.workers > 1:
            with mp.get_context("spawn").Pool(args.workers) as pool:
                for row in pool.imap(play_design, jobs, chunksize=1):
                    keep(row)
        else:
            for j in jobs:
                keep(play_design(j))
    result = _write(args, cfg, levels, rows, pictures, time.perf_counter() - t0, done=True)
    print(table(result["levels"]))
    print(
        f"wrote {args.out} and {len(pictures)} pictures; run time {result['wall_s']:.0f} s "
        f"({args.workers} worker)"
    )
    return result


def _write(  # noqa: PLR0913, PLR0917
    args: argparse.Namespace,
    cfg: RandomDesignsBenchConfig,
    levels: list[Level],
    rows: list[dict[str, Any]],
    pictures: dict[str, str],
    wall: float,
    done: bool,
) -> dict[str, Any]:
    summary = [
        summarise(lv, [r for r in rows if r["level"] == lv.name])
        for lv in levels
        if any(r["level"] == lv.name for r in rows)
    ]
    result = {
        "generator": cfg.generator,
        "generator_overrides": cfg.generator_overrides,
        "workers": args.workers,
        "complete_run": done,
        "wall_s": wall,
        "levels": summary,
        "pictures": pictures,
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    write_text(args.out, json.dumps(result, indent=2, default=float))
    return result


if __name__ == "__main__":
    run_cli(main)
