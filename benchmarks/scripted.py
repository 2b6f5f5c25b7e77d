"""Benchmark of the scripted cell: success, correctness and tiles/min over many seeds.

Run ``python -m benchmarks.scripted`` (``--seeds 0-4`` for a quick look, ``--workers 2``).
Every scenario of ``configs/bench_scripted.yaml`` (a design, a belt speed, a feed) plays one
episode of `MosaicAssembly-v0` per seed, driven by `agents.scripted.agent.ScriptedAgent` from
full-resolution camera images (calibrated cameras, dynamic execution). Prints one row per
scenario with its targets and writes ``out/bench_scripted.json``: per scenario the totals, the
worst episode's tiles/min, wall seconds per tile and every episode.
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import os
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

from agents.policies import parse_pairs
from apps.cli import CommandParser, UsageError, run_cli, write_result
from configs import ConfigError, load_config
from configs.checks import check_fields, checked
from envs import ENV_ID
from envs.cell.rendering import use_headless_rendering

OUT = Path("out/bench_scripted.json")
"""Default output file."""


STREAM_KEYS = ("belt_speed", "feed", "stream_period", "stream_initial", "stream_start")
"""The env keys a scenario's ``task`` gives it: the rung's belt and stream."""


@dataclass(frozen=True)
class Scenario:
    """One benchmark scenario.

    Attributes:
        name: Label of the table row.
        env: `EnvConfig` overrides (``design``, ``belt_speed``, ``feed``, ...).
        min_correct: Target: fraction of all tiles placed correctly over the seeds.
        min_tiles_per_min: Target: the worst episode's correct tiles per simulated minute
            (0: reported only).
        task: A ladder rung whose belt and stream (`STREAM_KEYS` of its env) the scenario
            plays, under ``env`` ("": none).
    """

    name: str
    env: dict[str, Any] = field(default_factory=dict)
    min_correct: float = 1.0
    min_tiles_per_min: float = 0.0
    task: str = ""

    def env_kwargs(self) -> dict[str, Any]:
        """The scenario's env overrides: its task's belt and stream, then ``env``.

        Raises:
            ConfigError: Unknown task (the message lists the ids).
        """
        if not self.task:
            return dict(self.env)
        from envs.tasks import get_task  # noqa: PLC0415 - the env stack, only when played

        rung = get_task(self.task).env
        return {**{k: rung[k] for k in STREAM_KEYS if k in rung}, **self.env}


@dataclass(frozen=True)
class ScriptedBenchConfig:
    """``configs/bench_scripted.yaml``.

    Attributes:
        seeds: First and one-past-last episode seed.
        image_size: Camera image (height, width) the agent sees [px].
        steps_per_slot: Episode step limit per slot.
        scenarios: The scenarios, in table order.
    """

    seeds: tuple[int, int] = (0, 20)
    image_size: tuple[int, int] = (492, 656)
    steps_per_slot: int = checked(2, ge=1)
    scenarios: tuple[Scenario, ...] = ()

    def __post_init__(self) -> None:
        """Raise `ConfigError` on bad values."""
        check_fields(self, ConfigError, prefix="bench_scripted: ")
        if self.seeds[1] <= self.seeds[0] or not self.scenarios:
            raise ConfigError(
                "bench_scripted: seeds must be [first, last) with last > first, and at least one "
                "scenario"
            )


@dataclass(frozen=True)
class Episode:
    """One scripted episode (see `play`)."""

    scenario: str
    seed: int
    slots: int
    correct: int
    misplaced: int
    dropped: int
    lost: int
    distractors_placed: int
    failed_actions: int
    steps: int
    sim_s: float
    tiles_per_min: float
    wall_s: float


_ENVS: dict[str, Any] = {}
"""Per worker process: the (env, agent) of the scenario it plays now."""


def play(job: tuple[Scenario, int, tuple[int, int], int]) -> Episode:
    """Play one episode of a scenario with the scripted agent (in a worker process)."""
    import gymnasium as gym  # noqa: PLC0415 - workers import the stack themselves

    from agents.scripted.agent import ScriptedAgent  # noqa: PLC0415

    scenario, seed, image_size, steps_per_slot = job
    if scenario.name not in _ENVS:
        close_envs()  # jobs come scenario by scenario: free the last one
        env = gym.make(
            ENV_ID,
            max_episode_steps=None,
            **{
                "action_mode": "pick_place",
                "image_size": image_size,
                "depth": True,  # the height picture (agents.scripted.height): every glaze seen
                **scenario.env_kwargs(),
            },
        )
        _ENVS[scenario.name] = (env, ScriptedAgent.from_env(env))
    env, agent = _ENVS[scenario.name]
    return run_episode(scenario.name, env, agent, seed, steps_per_slot)[0]


def run_episode(
    name: str,
    env: Any,
    agent: Any,
    seed: int,
    steps_per_slot: int,
    *,
    observer: Callable[[Any, dict[str, Any]], None] | None = None,
) -> tuple[Episode, dict[str, Any]]:
    """One episode of ``agent`` (a `ScriptedAgent`) in ``env``, up to the step limit.

    Args:
        name: Scenario label of the returned `Episode`.
        env: A ``pick_place`` `MosaicAssembly-v0` env.
        agent: The agent, built for ``env``.
        seed: Reset seed.
        steps_per_slot: Step limit per slot.
        observer: Called after every step with the observation and info.

    Returns:
        (the episode's figures, the last step's info).
    """
    t0 = time.perf_counter()
    obs, info = env.reset(seed=seed)
    agent.reset()
    limit = steps_per_slot * len(env.get_wrapper_attr("task_spec").slots)
    steps = failed = 0
    while steps < limit:
        action, _ = agent.predict(obs)
        obs, _, terminated, truncated, info = env.step(action)
        steps += 1
        failed += int(info["action_failed"])
        if observer is not None:
            observer(obs, info)
        if terminated or truncated:
            break
    e = info["evaluation"]
    episode = Episode(
        name,
        seed,
        int(e["slots"]),
        int(e["correct"]),
        int(e["misplaced"]),
        int(e["dropped"]),
        int(e["lost"]),
        int(e["distractors_placed"]),
        failed,
        steps,
        float(info["sim_time"]),
        float(info["tiles_per_min"]),
        time.perf_counter() - t0,
    )
    return episode, info


def close_envs() -> None:
    """Close this process's cached env (renderers freed)."""
    for env, _ in _ENVS.values():
        env.close()
    _ENVS.clear()


def summarise(scenario: Scenario, episodes: list[Episode]) -> dict[str, Any]:
    """Totals of one scenario and whether its targets are met."""
    tiles = sum(e.slots for e in episodes)
    correct = sum(e.correct for e in episodes)
    frac = correct / tiles if tiles else 0.0
    worst = min((e.tiles_per_min for e in episodes), default=0.0)
    sim = sum(e.sim_s for e in episodes)
    met = frac >= scenario.min_correct and worst >= scenario.min_tiles_per_min
    return {
        "scenario": scenario.name,
        "env": scenario.env_kwargs(),
        "episodes": len(episodes),
        "success_rate": sum(e.correct == e.slots for e in episodes) / max(len(episodes), 1),
        "tiles": tiles,
        "correct": correct,
        "correct_fraction": frac,
        "misplaced": sum(e.misplaced for e in episodes),
        "dropped": sum(e.dropped for e in episodes),
        "lost": sum(e.lost for e in episodes),
        "distractors_placed": sum(e.distractors_placed for e in episodes),
        "failed_actions": sum(e.failed_actions for e in episodes),
        "tiles_per_min": 60.0 * correct / sim if sim > 0 else 0.0,
        "tiles_per_min_worst": worst,
        "wall_s_per_tile": sum(e.wall_s for e in episodes) / max(correct, 1),
        "target_correct": scenario.min_correct,
        "target_tiles_per_min": scenario.min_tiles_per_min,
        "met": met,
        "per_episode": [asdict(e) for e in episodes],
    }


def table(rows: list[dict[str, Any]]) -> str:
    """The printed table."""
    head = (
        f"{'scenario':38s} {'eps':>4s} {'success':>8s} {'correct':>13s} {'mis':>4s} "
        f"{'drop':>4s} {'lost':>4s} {'fail':>4s} {'t/min':>6s} {'worst':>6s} "
        f"{'wall s/t':>8s}  target"
    )
    lines = [head, "-" * len(head)]
    for r in rows:
        target = f">= {r['target_correct']:.0%}"
        if r["target_tiles_per_min"]:
            target += f", >= {r['target_tiles_per_min']:g}/min"
        lines.append(
            f"{r['scenario']:38s} {r['episodes']:4d} {r['success_rate']:8.0%} "
            f"{r['correct']:5d}/{r['tiles']:<5d}{r['correct_fraction']:3.0%} "
            f"{r['misplaced']:4d} {r['dropped']:4d} {r['lost']:4d} {r['failed_actions']:4d} "
            f"{r['tiles_per_min']:6.2f} {r['tiles_per_min_worst']:6.2f} "
            f"{r['wall_s_per_tile']:8.2f}  {target}: {'met' if r['met'] else 'NOT MET'}"
        )
    return "\n".join(lines)


def design_scenario(design: str) -> Scenario:
    """The scenario of one design file: a static belt fed in batches, every tile right."""
    name = Path(design).name if Path(design).suffix else design
    return Scenario(
        f"{name}, static belt, batches",
        {"design": design, "feed": "batch"},
        min_correct=1.0,
        min_tiles_per_min=24.0,
    )


def _seed_range(text: str) -> tuple[int, int]:
    try:
        a, _, b = text.partition("-")
        lo, hi = int(a), int(b or a) + 1
    except ValueError as exc:
        raise argparse.ArgumentTypeError(f"seeds must be FIRST-LAST, got {text!r}") from exc
    if hi <= lo:
        raise argparse.ArgumentTypeError(f"seeds must be FIRST-LAST with LAST >= FIRST: {text!r}")
    return lo, hi


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Command line: run every scenario, print the table, write the JSON."""
    p = CommandParser(description=__doc__.splitlines()[0])
    p.add_argument("--config", default="bench_scripted", help="bundled name or YAML path")
    p.add_argument("--seeds", type=_seed_range, help="FIRST-LAST (default: config)")
    p.add_argument("--scenario", action="append", help="only these scenarios (by name prefix)")
    p.add_argument(
        "--design",
        action="append",
        help="instead of the config's scenarios: this design (name, .yaml, .svg or .dxf) on a "
        "static belt fed in batches, every tile right (repeatable)",
    )
    p.add_argument(
        "--env", nargs="*", default=[], metavar="KEY=VALUE", help="env (and cell) overrides"
    )
    p.add_argument("--workers", type=int, default=min(2, os.cpu_count() or 1))
    p.add_argument("--out", type=Path, default=OUT)
    args = p.parse_args(argv)
    cfg = load_config(ScriptedBenchConfig, args.config)
    if args.seeds:
        cfg = replace(cfg, seeds=args.seeds)
    if args.design:
        cfg = replace(cfg, scenarios=tuple(design_scenario(d) for d in args.design))
    scenarios = [
        replace(s, env={**s.env, **parse_pairs(args.env)})
        for s in cfg.scenarios
        if not args.scenario or any(s.name.startswith(x) for x in args.scenario)
    ]
    if not scenarios:
        raise UsageError(f"no scenario matches {args.scenario}")
    jobs = [
        (s, seed, cfg.image_size, cfg.steps_per_slot)
        for s in scenarios
        for seed in range(*cfg.seeds)
    ]
    t0 = time.perf_counter()
    use_headless_rendering()
    with mp.get_context("spawn").Pool(max(1, args.workers), maxtasksperchild=None) as pool:
        episodes = pool.map(play, jobs, chunksize=1)
    rows = [summarise(s, [e for e in episodes if e.scenario == s.name]) for s in scenarios]
    print(table(rows))
    result = {
        "seeds": list(cfg.seeds),
        "workers": args.workers,
        "wall_s": time.perf_counter() - t0,
        "scenarios": rows,
    }
    return write_result(args.out, result, f" ({result['wall_s']:.0f} s)")


if __name__ == "__main__":
    run_cli(main)
