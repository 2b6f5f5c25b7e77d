"""Soak benchmark: thousands of episodes, no exception, flat memory, every tile accounted.

A seeded random policy (every ``adversarial_every``-th episode an adversarial one that repeats
its first action for ``adversarial_steps`` steps, piling tiles up and misplacing them) plays
``episodes`` episodes of `MosaicAssembly-v0` in a cheap mode (``configs/bench_soak.yaml``:
kinematic ``pick_place_discrete`` on state). After every step the tile accounting is checked
(the states of the real tiles sum to the tiles fed). Reported: episodes, steps, exceptions (by
type), accounting violations, episodes ended by success, by nothing placeable left and by the
step limit, and of those truncated, how many still had placeable tiles; the resident memory
(RSS) after the warm-up and at the end.

    python -m benchmarks.soak                     # ~10 min on one core; out/bench_soak.json
    python -m benchmarks.soak --episodes 200      # a shorter run

Not part of the default test run (it is a benchmark, not a test).
"""

from __future__ import annotations

import resource
import time
from collections import Counter
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

import gymnasium as gym

import envs  # noqa: F401 - registers the env
from apps.cli import CommandParser, run_cli, write_result
from configs import load_config
from envs import ENV_ID
from envs.cell.accounting import TILE_STATES

MB = 1024.0 * 1024.0


@dataclass(frozen=True)
class SoakConfig:
    """Settings of the soak benchmark (``configs/bench_soak.yaml``).

    Attributes:
        episodes: Episodes played.
        warmup_episodes: Episodes played before the memory baseline is taken.
        seed: Seed of the first episode (episode k: ``seed + k``) and of the policy.
        action_mode: Env action mode.
        obs_mode: Env observation mode.
        execution: Env execution of the pick_place modes.
        max_slots: First k slots of the design only (0: all).
        adversarial_every: Every k-th episode starts adversarially (0: never).
        adversarial_steps: Steps an adversarial episode repeats its first action for.
        rss_tolerance_mb: Allowed growth of the resident memory over the run [MB].
    """

    episodes: int = 2000
    warmup_episodes: int = 50
    seed: int = 0
    action_mode: str = "pick_place_discrete"
    obs_mode: str = "state"
    execution: str = "kinematic"
    max_slots: int = 0
    adversarial_every: int = 4
    adversarial_steps: int = 10
    rss_tolerance_mb: float = 5.0


def rss_mb() -> float:
    """Resident memory of this process now [MB] (Linux ``/proc``; peak RSS elsewhere)."""
    try:
        pages = int(Path("/proc/self/statm").read_text().split()[1])
        return pages * resource.getpagesize() / MB
    except OSError:
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def soak(cfg: SoakConfig) -> dict[str, Any]:
    """Play the episodes and return the figures (see the module docstring)."""
    env = gym.make(
        ENV_ID,
        action_mode=cfg.action_mode,
        obs_mode=cfg.obs_mode,
        execution=cfg.execution,
        max_slots=cfg.max_slots,
    )
    space = env.action_space
    space.seed(cfg.seed)
    exceptions: Counter[str] = Counter()
    ends: Counter[str] = Counter()
    steps = violations = truncated_placeable = 0
    rss_start = rss_peak = 0.0
    t0 = time.perf_counter()
    for k in range(cfg.episodes):
        if k == cfg.warmup_episodes:
            rss_start = rss_mb()
        try:
            _, info = env.reset(seed=cfg.seed + k)
            fixed = space.sample()
            adversarial = cfg.adversarial_every > 0 and k % cfg.adversarial_every == 0
            t = 0
            while True:
                action = fixed if adversarial and t < cfg.adversarial_steps else space.sample()
                t += 1
                _, _, terminated, truncated, info = env.step(action)
                steps += 1
                ev = info["evaluation"]
                if sum(ev[s] for s in TILE_STATES) != ev["fed"]:
                    violations += 1
                if terminated or truncated:
                    break
            if ev["success"]:
                ends["success"] += 1
            elif terminated:
                ends["nothing_placeable"] += 1
            else:
                ends["step_limit"] += 1
                truncated_placeable += int(ev["placeable"] > 0)
        except Exception as exc:  # noqa: BLE001 (counted and reported, the soak goes on)
            exceptions[f"{type(exc).__name__}: {exc}"[:200]] += 1
        if k >= cfg.warmup_episodes:
            rss_peak = max(rss_peak, rss_mb())
    env.close()
    rss_end = rss_mb()
    if cfg.episodes <= cfg.warmup_episodes:
        rss_start = rss_peak = rss_end
    return {
        "config": asdict(cfg),
        "episodes": cfg.episodes,
        "steps": steps,
        "exceptions": sum(exceptions.values()),
        "exception_kinds": dict(exceptions),
        "accounting_violations": violations,
        "ends": dict(ends),
        "truncated_with_placeable": truncated_placeable,
        "rss_start_mb": round(rss_start, 2),
        "rss_end_mb": round(rss_end, 2),
        "rss_peak_mb": round(rss_peak, 2),
        "rss_growth_mb": round(rss_end - rss_start, 2),
        "memory_flat": rss_end - rss_start <= cfg.rss_tolerance_mb,
        "wall_s": round(time.perf_counter() - t0, 1),
    }


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Command line: run the soak, print the figures, write the JSON."""
    ap = CommandParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", default="bench_soak", help="bundled name or YAML path")
    ap.add_argument("--episodes", type=int, help="episodes (default: config)")
    ap.add_argument("--out", type=Path, default=Path("out/bench_soak.json"))
    args = ap.parse_args(argv)
    cfg = load_config(SoakConfig, args.config)
    if args.episodes is not None:
        cfg = replace(cfg, episodes=args.episodes)
    out = soak(cfg)
    for key in (
        "episodes",
        "steps",
        "exceptions",
        "accounting_violations",
        "ends",
        "truncated_with_placeable",
        "rss_start_mb",
        "rss_end_mb",
        "rss_growth_mb",
        "memory_flat",
        "wall_s",
    ):
        print(f"{key}: {out[key]}")
    return write_result(args.out, out)


if __name__ == "__main__":
    run_cli(main)
